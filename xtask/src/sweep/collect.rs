//! `cargo xtask sweep collect DIR`: every finished task's `summary.json` with its parameters into
//! `DIR/sweep.csv` (header: `task`, the varied parameters, then every figure key in key order; one
//! row per finished task, in task order), `DIR/sweep-status.json` (counts, failed and missing
//! tasks, the timing keys), the plots of each figure against each varied parameter
//! (`DIR/plots/`, [`super::plots`]) and the report `DIR/report/index.html`, which shows the sweep.
//!
//! For a benchmark's sweep, the CSV tables every point wrote under the same name
//! (`accuracy_vs_time.csv`, `pc_stretch.csv` …) are also concatenated in task order into
//! `DIR/<name>.csv`: the table `bench <crate> --sweep <knob>` writes in one process.
//!
//! Cells: numbers as `summary.json` writes them (shortest text that reads back to the same f64),
//! `NaN` for a non-finite figure (`null` in JSON), `true`/`false`, text as is, empty when a task
//! has no such figure.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

use serde_json::Value;

use super::plan::{Plan, Source};
use super::task::{state, TaskState};
use crate::error::{io_err, Error, Result};
use crate::out::{write_atomic, Cell, CsvWriter, Summary};

/// The table of a sweep folder.
pub const SWEEP_CSV: &str = "sweep.csv";
/// The status of a collected sweep.
pub const STATUS_JSON: &str = "sweep-status.json";

/// One finished task's row.
#[derive(Clone, Debug)]
pub struct Row {
    /// Task id.
    pub id: String,
    /// Its parameter values (RON text).
    pub values: Vec<String>,
    /// Its figures.
    pub figures: BTreeMap<String, Value>,
}

/// What `collect` found.
#[derive(Clone, Debug, Default)]
pub struct Collected {
    /// Finished tasks' rows, in task order.
    pub rows: Vec<Row>,
    /// Failed tasks (ids).
    pub failed: Vec<String>,
    /// Tasks not run yet or killed while running (ids).
    pub missing: Vec<String>,
    /// Every figure key of any row, sorted.
    pub keys: Vec<String>,
    /// The keys any task marked as timing (`timing.json`).
    pub timing: Vec<String>,
}

/// A figure as CSV text.
pub fn cell_text(v: Option<&Value>) -> String {
    match v {
        None => String::new(),
        Some(Value::Null) => "NaN".into(),
        Some(Value::Number(n)) => n.to_string(),
        Some(Value::Bool(b)) => b.to_string(),
        Some(Value::String(s)) => s.clone(),
        Some(other) => other.to_string(),
    }
}

/// Reads every task of `plan`.
pub fn gather(plan: &Plan) -> Result<Collected> {
    let mut c = Collected::default();
    let mut keys = BTreeSet::new();
    let mut timing = BTreeSet::new();
    for t in &plan.tasks {
        match state(&t.dir) {
            TaskState::Finished => {
                let s = Summary::read(&t.dir.join("summary.json"))?;
                let figures: BTreeMap<String, Value> = s.iter().map(|(k, v)| (k.clone(), v.clone())).collect();
                keys.extend(figures.keys().cloned());
                let tj = t.dir.join(crate::record::TIMING_JSON);
                if let Ok(text) = std::fs::read_to_string(&tj) {
                    let list: Vec<String> =
                        serde_json::from_str(&text).map_err(|e| Error::Run(format!("{}: {e}", tj.display())))?;
                    timing.extend(list);
                }
                c.rows.push(Row { id: t.id.clone(), values: t.values.clone(), figures });
            }
            TaskState::Failed => c.failed.push(t.id.clone()),
            TaskState::Partial | TaskState::Missing => c.missing.push(t.id.clone()),
        }
    }
    c.keys = keys.into_iter().collect();
    c.timing = timing.into_iter().collect();
    Ok(c)
}

/// Writes `sweep.csv`.
pub fn write_csv(path: &Path, plan: &Plan, c: &Collected) -> Result<()> {
    let mut header: Vec<&str> = vec!["task"];
    header.extend(plan.parameters.iter().map(String::as_str));
    header.extend(c.keys.iter().map(String::as_str));
    let mut w = CsvWriter::create(path, &header)?;
    for r in &c.rows {
        let mut cells = vec![Cell::Text(r.id.clone())];
        cells.extend(r.values.iter().map(|v| Cell::Text(v.clone())));
        cells.extend(c.keys.iter().map(|k| Cell::Text(cell_text(r.figures.get(k)))));
        w.row(&cells)?;
    }
    Ok(())
}

/// Concatenates the top-level CSV tables of the finished bench points (same name, same header)
/// into `dir/<name>.csv`, in task order. Returns the files written.
pub fn merge_bench_tables(dir: &Path, plan: &Plan, c: &Collected) -> Result<Vec<PathBuf>> {
    let finished: Vec<&super::plan::PlanTask> =
        plan.tasks.iter().filter(|t| c.rows.iter().any(|r| r.id == t.id)).collect();
    let mut names = BTreeSet::new();
    for t in &finished {
        for e in std::fs::read_dir(&t.dir).map_err(io_err(&t.dir))?.flatten() {
            let n = e.file_name().to_string_lossy().into_owned();
            if n.ends_with(".csv") && e.path().is_file() {
                names.insert(n);
            }
        }
    }
    let mut written = Vec::new();
    for name in names {
        let mut header: Option<String> = None;
        let mut body = String::new();
        for t in &finished {
            let p = t.dir.join(&name);
            let Ok(text) = std::fs::read_to_string(&p) else { continue };
            let mut lines = text.lines();
            let h = lines.next().unwrap_or_default().to_string();
            match &header {
                None => header = Some(h),
                Some(h0) if *h0 != h => {
                    return Err(Error::Run(format!(
                        "{}: its header differs from the other points' {name}",
                        p.display()
                    )))
                }
                Some(_) => {}
            }
            for l in lines {
                body.push_str(l);
                body.push('\n');
            }
        }
        let out = dir.join(&name);
        write_atomic(&out, format!("{}\n{body}", header.unwrap_or_default()).as_bytes())?;
        written.push(out);
    }
    Ok(written)
}

/// `sweep collect DIR`: the CSV, the status, the plots and the report. Succeeds whatever the
/// tasks' status (failed and missing tasks are listed).
pub fn collect(dir: &Path) -> Result<Collected> {
    let dir = crate::paths::absolute(dir);
    let plan = Plan::read(&dir)?;
    let c = gather(&plan)?;
    let csv = dir.join(SWEEP_CSV);
    write_csv(&csv, &plan, &c)?;
    let tables =
        if matches!(plan.source, Source::Bench { .. }) { merge_bench_tables(&dir, &plan, &c)? } else { Vec::new() };
    let status = serde_json::json!({
        "name": plan.name(),
        "tasks": plan.tasks.len(),
        "finished": c.rows.len(),
        "failed": c.failed,
        "missing": c.missing,
        "parameters": plan.parameters,
        "figures": c.keys.len(),
        "timing": c.timing,
        "tables": tables.iter().filter_map(|p| p.file_name()).map(|n| n.to_string_lossy().into_owned()).collect::<Vec<_>>(),
    });
    let text = serde_json::to_string_pretty(&status).map_err(|e| Error::Run(e.to_string()))?;
    write_atomic(&dir.join(STATUS_JSON), (text + "\n").as_bytes())?;
    let plots = super::plots::write(&dir, &plan, &c)?;
    say!(
        "sweep {}: {} of {} tasks finished, {} failed, {} missing; {} rows × {} figures in {}; {} plots",
        plan.name(),
        c.rows.len(),
        plan.tasks.len(),
        c.failed.len(),
        c.missing.len(),
        c.rows.len(),
        c.keys.len(),
        csv.display(),
        plots
    );
    for t in &tables {
        say!("  merged bench table: {}", t.display());
    }
    if !c.failed.is_empty() {
        say!("  failed: {}", c.failed.join(", "));
    }
    if !c.missing.is_empty() {
        say!("  missing: {}", c.missing.join(", "));
    }
    crate::report::rebuild(&dir)?;
    Ok(c)
}

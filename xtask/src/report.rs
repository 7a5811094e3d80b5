//! `cargo xtask repro`: runs every built-in scene and every benchmark, then the report;
//! `cargo xtask report [OUT_DIR]`: the report alone, rebuilt from whatever runs are in a folder.
//!
//! A run is a folder holding `summary.json` (finished) or `FAILED` (failed), at any depth. The
//! report is `OUT_DIR/report/index.html` (per run: description, mode, headline figures beside
//! the paper's targets with pass/fail from `checks.json`, the notes of `report.md`, plots, the
//! preview strip and animation, links to every raw file) and the same content in Markdown,
//! `index.md`. `repro` also writes `report/summary.json`: its wall time and every run's status.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::time::Instant;

use serde_json::json;

use crate::checks::{self, CheckRow};
use crate::error::{io_err, Error, Result};
use crate::out::{ensure_dir, write_atomic, Summary};
use crate::registry;
use crate::run::{run_bench, run_scene_with, DirPolicy, Outcome, RunOptions, FAILED, RUN_JSON};
use crate::scene::Mode;

/// Runs everything and writes the report. A failing scene does not stop the others; the command
/// fails at the end if any did, after the report (which lists the failures) is written.
/// Benchmarks run their quick sweeps unless `mode` is `Full`.
pub fn repro(mode: Mode, out_root: PathBuf) -> Result<()> {
    let scenes = registry::builtin_scenes()?;
    let benches = registry::benches();
    let total = scenes.len() + benches.len();
    let t0 = Instant::now();
    say!("repro ({}): {} scenes and {} benchmarks → {}", mode.name(), scenes.len(), benches.len(), out_root.display());
    let mut outcomes = Vec::new();
    let mut k = 0;
    let opts = |dir: PathBuf, m: Mode, label: String| RunOptions {
        mode: m,
        out_dir: dir,
        policy: DirPolicy::Owned,
        overrides: Vec::new(),
        previews: true,
        label,
    };
    for s in &scenes {
        k += 1;
        let dir = out_root.join(&s.id);
        let t = Instant::now();
        let r = run_scene_with(&s.id, &s.file, &opts(dir.clone(), mode, format!("[{k}/{total}] {}", s.id)));
        let o = Outcome { id: s.id.clone(), wall_s: t.elapsed().as_secs_f64(), error: r.err().map(|e| e.to_string()) };
        say!("{}", status_line(&o, mode));
        outcomes.push(o);
    }
    // Benchmarks: the quick sweeps by default, the full sweeps with --full.
    let bench_mode = if mode == Mode::Full { Mode::Full } else { Mode::Quick };
    for b in &benches {
        k += 1;
        let id = format!("bench/{}", b.crate_name);
        let dir = out_root.join("bench").join(b.crate_name);
        let t = Instant::now();
        let r = run_bench(b.crate_name, None, None, &opts(dir.clone(), bench_mode, format!("[{k}/{total}] {id}")));
        let o = Outcome { id, wall_s: t.elapsed().as_secs_f64(), error: r.err().map(|e| e.to_string()) };
        say!("{}", status_line(&o, bench_mode));
        outcomes.push(o);
    }
    let wall_s = t0.elapsed().as_secs_f64();
    let report_dir = out_root.join("report");
    ensure_dir(&report_dir)?;
    write_repro_summary(&report_dir, mode, bench_mode, wall_s, &outcomes)?;
    let runs = collect_runs(&out_root)?;
    let md = write_markdown(&report_dir, &runs, Some(wall_s))?;
    let html = crate::html::write(&report_dir, &out_root, &runs, Some(wall_s))?;
    say!("report: {} ({})", html.display(), md.display());
    let failed: Vec<&str> = outcomes.iter().filter(|o| o.error.is_some()).map(|o| o.id.as_str()).collect();
    say!("repro: {} runs in {}, {} failed", outcomes.len(), crate::ui::human_secs(wall_s), failed.len());
    if failed.is_empty() {
        Ok(())
    } else {
        Err(Error::Run(format!("{} of {} runs failed: {}", failed.len(), outcomes.len(), failed.join(", "))))
    }
}

/// `report/summary.json` of a repro: its wall time and every run's status.
fn write_repro_summary(
    report_dir: &Path,
    mode: Mode,
    bench_mode: Mode,
    wall_s: f64,
    outcomes: &[Outcome],
) -> Result<()> {
    let runs: Vec<_> = outcomes
        .iter()
        .map(|o| {
            json!({
                "id": o.id,
                "status": if o.error.is_some() { "failed" } else { "ok" },
                "wall_s": o.wall_s,
                "mode": if o.id.starts_with("bench/") { bench_mode.name() } else { mode.name() },
            })
        })
        .collect();
    let v = json!({
        "wall_s": wall_s,
        "mode": mode.name(),
        "bench_mode": bench_mode.name(),
        "runs_total": outcomes.len(),
        "runs_failed": outcomes.iter().filter(|o| o.error.is_some()).count(),
        "runs": runs,
    });
    let text = serde_json::to_string_pretty(&v).map_err(|e| Error::Run(e.to_string()))?;
    write_atomic(&report_dir.join("summary.json"), (text + "\n").as_bytes())
}

/// `cargo xtask report OUT_DIR`: the HTML and Markdown report of the runs in `out_root`. Failed
/// runs are listed as failed; the command succeeds whatever the runs' status.
pub fn rebuild(out_root: &Path) -> Result<()> {
    if !out_root.is_dir() {
        return Err(Error::Usage(format!("{}: no such folder", out_root.display())));
    }
    let runs = collect_runs(out_root)?;
    let report_dir = out_root.join("report");
    ensure_dir(&report_dir)?;
    let wall = repro_wall(&report_dir);
    let md = write_markdown(&report_dir, &runs, wall)?;
    let html = crate::html::write(&report_dir, out_root, &runs, wall)?;
    let failed = runs.iter().filter(|r| r.failed.is_some()).count();
    say!("report: {} ({}); {} runs, {} failed", html.display(), md.display(), runs.len(), failed);
    Ok(())
}

fn repro_wall(report_dir: &Path) -> Option<f64> {
    let text = std::fs::read_to_string(report_dir.join("summary.json")).ok()?;
    serde_json::from_str::<serde_json::Value>(&text).ok()?.get("wall_s")?.as_f64()
}

fn status_line(o: &Outcome, mode: Mode) -> String {
    match &o.error {
        None => format!("ok     {:40} {:8.2} s  ({})", o.id, o.wall_s, mode.name()),
        Some(e) => format!("FAILED {:40} {:8.2} s  {e}", o.id, o.wall_s),
    }
}

/// One run found in an output folder.
#[derive(Clone, Debug)]
pub struct RunInfo {
    /// Its folder relative to the output root, with `/` (`shells/drape`, `bench/tracks`).
    pub id: String,
    /// Its folder.
    pub dir: PathBuf,
    /// One line from `run.json` or the built-in scene list (empty when unknown).
    pub description: String,
    /// `quick`, `default`, `full` (from `summary.json` or `run.json`).
    pub mode: String,
    /// Its figures (finished runs).
    pub summary: Option<Summary>,
    /// Its paper checks (`checks.json`).
    pub checks: Vec<CheckRow>,
    /// The error, for a failed run (`FAILED`'s first line and the rest).
    pub failed: Option<String>,
}

impl RunInfo {
    /// Wall time of the run (s), when finished.
    pub fn wall_s(&self) -> Option<f64> {
        self.summary.as_ref().and_then(|s| s.get("wall_s"))
    }
}

fn read_run(root: &Path, dir: &Path, described: &[(String, String)]) -> Result<RunInfo> {
    let id = dir
        .strip_prefix(root)
        .map(|r| r.components().map(|c| c.as_os_str().to_string_lossy()).collect::<Vec<_>>().join("/"))
        .unwrap_or_else(|_| dir.display().to_string());
    let meta: Option<serde_json::Value> =
        std::fs::read_to_string(dir.join(RUN_JSON)).ok().and_then(|t| serde_json::from_str(&t).ok());
    let meta_str = |k: &str| meta.as_ref().and_then(|m| m.get(k)).and_then(|v| v.as_str()).map(str::to_string);
    let failed = if dir.join(FAILED).is_file() {
        Some(std::fs::read_to_string(dir.join(FAILED)).map_err(io_err(dir.join(FAILED)))?.trim_end().to_string())
    } else {
        None
    };
    let summary = if failed.is_none() && dir.join("summary.json").is_file() {
        Some(Summary::read(&dir.join("summary.json"))?)
    } else {
        None
    };
    let mode = summary
        .as_ref()
        .and_then(|s| s.value("mode").and_then(|v| v.as_str()).map(str::to_string))
        .or_else(|| meta_str("mode"))
        .or_else(|| failed.as_ref().and_then(|f| f.lines().find_map(|l| l.strip_prefix("mode: ").map(str::to_string))))
        .unwrap_or_default();
    let description = meta_str("description")
        .or_else(|| described.iter().find(|(i, _)| id.ends_with(i.as_str())).map(|(_, d)| d.clone()))
        .unwrap_or_default();
    Ok(RunInfo {
        checks: checks::read(dir).unwrap_or_default(),
        id,
        dir: dir.to_path_buf(),
        description,
        mode,
        summary,
        failed,
    })
}

/// Every run under `root` (folders with `summary.json` or `FAILED`, at any depth; a run's own
/// subfolders are not searched; `root/report` is skipped), sorted by id.
pub fn collect_runs(root: &Path) -> Result<Vec<RunInfo>> {
    // Descriptions of the built-in scenes and benches, for runs without run.json.
    let mut described: Vec<(String, String)> =
        registry::builtin_scenes().unwrap_or_default().into_iter().map(|s| (s.id, s.description)).collect();
    described
        .extend(registry::benches().iter().map(|b| (format!("bench/{}", b.crate_name), b.description.to_string())));
    let mut runs = Vec::new();
    let mut stack = vec![root.to_path_buf()];
    while let Some(d) = stack.pop() {
        if d != root && (d.join("summary.json").is_file() || d.join(FAILED).is_file()) {
            runs.push(read_run(root, &d, &described)?);
            continue;
        }
        let Ok(rd) = std::fs::read_dir(&d) else { continue };
        for e in rd.flatten() {
            let p = e.path();
            if p.is_dir() && !(d == root && e.file_name() == "report") {
                stack.push(p);
            }
        }
    }
    runs.sort_by(|a, b| a.id.cmp(&b.id));
    Ok(runs)
}

/// Path of `target` relative to `base` (both under the same output root), with `/` separators.
pub fn relative(base: &Path, target: &Path) -> String {
    let b: Vec<_> = base.components().collect();
    let t: Vec<_> = target.components().collect();
    let common = b.iter().zip(&t).take_while(|(x, y)| x == y).count();
    let mut parts: Vec<String> = vec!["..".to_string(); b.len() - common];
    parts.extend(t[common..].iter().map(|c| c.as_os_str().to_string_lossy().into_owned()));
    parts.join("/")
}

/// The images of a run folder to show: the preview strip and animation first, then every other
/// PNG (plots, renders) in name order.
pub fn images(dir: &Path) -> Vec<PathBuf> {
    let mut v: Vec<PathBuf> = std::fs::read_dir(dir)
        .map(|rd| {
            rd.flatten()
                .map(|e| e.path())
                .filter(|p| p.is_file() && p.extension().is_some_and(|x| x == "png" || x == "apng"))
                .collect()
        })
        .unwrap_or_default();
    v.sort_by_key(|p| {
        let n = p.file_name().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
        (n != "preview.png", n != "preview.apng", n)
    });
    v
}

/// Writes `report_dir/index.md`.
pub fn write_markdown(report_dir: &Path, runs: &[RunInfo], wall_s: Option<f64>) -> Result<PathBuf> {
    let mut md = String::new();
    let _ = writeln!(md, "# Reproduction report\n");
    let failed = runs.iter().filter(|r| r.failed.is_some()).count();
    let _ = writeln!(
        md,
        "{} runs, {} failed{}. Each figure comes from the run listed with it, in the mode shown.\n",
        runs.len(),
        failed,
        wall_s.map(|w| format!("; repro wall time {:.1} s", w)).unwrap_or_default()
    );
    let _ = writeln!(md, "| run | status | mode | wall time (s) | checks |\n|---|---|---|---|---|");
    for r in runs {
        let status = if r.failed.is_some() { "**failed**" } else { "ok" };
        let pass = r.checks.iter().filter(|c| c.pass).count();
        let checks = if r.checks.is_empty() { String::new() } else { format!("{pass}/{} pass", r.checks.len()) };
        let wall = r.wall_s().map(|w| format!("{w:.2}")).unwrap_or_default();
        let _ = writeln!(md, "| [{}](#{}) | {status} | {} | {wall} | {checks} |", r.id, anchor(&r.id), r.mode);
    }
    if let Some(root) = report_dir.parent() {
        crate::sweep::report::markdown(&mut md, report_dir, root);
    }
    for r in runs {
        let _ = writeln!(md, "\n## {}\n\n{}\n\nMode `{}`.\n", r.id, r.description, r.mode);
        if let Some(e) = &r.failed {
            let _ = writeln!(md, "**Failed:** `{}`\n", e.lines().next().unwrap_or(""));
        }
        if !r.checks.is_empty() {
            let _ = writeln!(md, "| figure | ours | target | | source |\n|---|---|---|---|---|");
            for c in &r.checks {
                let _ = writeln!(
                    md,
                    "| `{}` | {} | {} | {} | {} |",
                    c.key,
                    checks::format_number(c.value),
                    c.target,
                    if c.pass { "pass" } else { "**FAIL**" },
                    c.source
                );
            }
            md.push('\n');
        }
        let notes = r.dir.join("report.md");
        if notes.is_file() {
            let text = std::fs::read_to_string(&notes).map_err(io_err(&notes))?;
            let _ = writeln!(md, "{}\n", text.trim_end());
        }
        if let Some(s) = &r.summary {
            let _ = writeln!(md, "<details><summary>summary.json</summary>\n\n| key | value |\n|---|---|");
            for (k, v) in s.iter() {
                let _ = writeln!(md, "| `{k}` | {} |", checks::format_value(v));
            }
            let _ = writeln!(md, "\n</details>\n");
        }
        for img in images(&r.dir) {
            let name = img.file_name().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
            let _ = writeln!(md, "![{name}]({})\n", relative(report_dir, &img));
        }
    }
    crate::out::ensure_dir(report_dir)?;
    let path = report_dir.join("index.md");
    std::fs::write(&path, md).map_err(io_err(&path))?;
    Ok(path)
}

/// The Markdown/HTML anchor of a run id.
pub fn anchor(id: &str) -> String {
    id.to_lowercase().chars().map(|c| if c.is_alphanumeric() || c == '-' { c } else { '-' }).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn relative_paths_between_output_dirs() {
        assert_eq!(relative(Path::new("/o/report"), Path::new("/o/geom-core/x/a.png")), "../geom-core/x/a.png");
        assert_eq!(relative(Path::new("/o/report"), Path::new("/o/report/a.png")), "a.png");
    }

    #[test]
    fn runs_are_collected_at_any_depth_with_failures() {
        let root = std::env::temp_dir().join(format!("xtask-report-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&root);
        let ok_dir = root.join("c/ok");
        let mut s = Summary::new();
        s.set("err_rel", 2.5e-13).set_str("mode", "quick");
        s.write(&ok_dir).unwrap();
        std::fs::write(ok_dir.join("report.md"), "| paper | ours |\n|---|---|\n| 1 | 2 |\n").unwrap();
        let deep = root.join("sweep/tasks/7");
        std::fs::create_dir_all(&deep).unwrap();
        std::fs::write(deep.join(FAILED), "boom\n\nrun: x\nmode: default\n").unwrap();
        std::fs::create_dir_all(root.join("c/empty/frames")).unwrap();
        let runs = collect_runs(&root).unwrap();
        let ids: Vec<&str> = runs.iter().map(|r| r.id.as_str()).collect();
        assert_eq!(ids, ["c/ok", "sweep/tasks/7"]);
        assert_eq!(runs[1].mode, "default");
        let md = std::fs::read_to_string(write_markdown(&root.join("report"), &runs, None).unwrap()).unwrap();
        assert!(md.contains("**Failed:** `boom`"), "{md}");
        assert!(md.contains("| paper | ours |"));
        assert!(md.contains("`err_rel` | 2.5000e-13"));
        rebuild(&root).unwrap();
        let html = std::fs::read_to_string(root.join("report/index.html")).unwrap();
        assert!(html.contains("failed") && html.contains("c/ok"));
        std::fs::remove_dir_all(&root).unwrap();
    }
}

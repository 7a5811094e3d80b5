//! `cargo xtask repro`: runs every built-in scene and every benchmark, then assembles one report,
//! `out/report/index.md`, with each scene's own notes (`report.md`, where the paper's tables stand
//! beside ours), its `summary.json` figures and its plots and images.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::time::Instant;

use indicatif::{ProgressBar, ProgressStyle};

use crate::error::{io_err, Error, Result};
use crate::out::{ensure_dir, Summary};
use crate::registry;
use crate::run::{run_bench, run_scene, Outcome};
use crate::scene::Mode;

/// Runs everything and writes the report. A failing scene does not stop the others; the command
/// fails at the end if any did, after the report (which lists the failures) is written.
pub fn repro(mode: Mode, out_root: PathBuf) -> Result<()> {
    let scenes = registry::builtin_scenes()?;
    let benches = registry::benches();
    let total = (scenes.len() + benches.len()) as u64;
    let bar = ProgressBar::new(total);
    bar.set_style(
        ProgressStyle::with_template("{elapsed_precise} [{bar:30}] {pos}/{len} {msg}")
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    let t0 = Instant::now();
    let mut outcomes = Vec::new();
    for s in &scenes {
        bar.set_message(s.id.clone());
        let dir = out_root.join(&s.id);
        let t = Instant::now();
        let r = run_scene(&s.id, &s.file, mode, &dir);
        let o = Outcome {
            id: s.id.clone(),
            description: s.description.clone(),
            out_dir: dir,
            wall_s: t.elapsed().as_secs_f64(),
            error: r.err().map(|e| e.to_string()),
        };
        bar.suspend(|| println!("{}", status_line(&o)));
        outcomes.push(o);
        bar.inc(1);
    }
    for b in &benches {
        let id = format!("bench/{}", b.crate_name);
        bar.set_message(id.clone());
        let dir = out_root.join("bench").join(b.crate_name);
        let t = Instant::now();
        let r = run_bench(b.crate_name, mode == Mode::Quick, None, &dir);
        let o = Outcome {
            id,
            description: b.description.to_string(),
            out_dir: dir,
            wall_s: t.elapsed().as_secs_f64(),
            error: r.err().map(|e| e.to_string()),
        };
        bar.suspend(|| println!("{}", status_line(&o)));
        outcomes.push(o);
        bar.inc(1);
    }
    bar.finish_and_clear();
    let report_dir = out_root.join("report");
    let path = write_report(&report_dir, &outcomes, mode, t0.elapsed().as_secs_f64())?;
    println!("report: {}", path.display());
    let failed: Vec<&str> = outcomes.iter().filter(|o| o.error.is_some()).map(|o| o.id.as_str()).collect();
    if failed.is_empty() {
        Ok(())
    } else {
        Err(Error::Run(format!("{} of {} runs failed: {}", failed.len(), outcomes.len(), failed.join(", "))))
    }
}

fn status_line(o: &Outcome) -> String {
    match &o.error {
        None => format!("ok     {:40} {:8.2} s", o.id, o.wall_s),
        Some(e) => format!("FAILED {:40} {:8.2} s  {e}", o.id, o.wall_s),
    }
}

/// Path of `target` relative to `base` (both under the same output root), with `/` separators.
fn relative(base: &Path, target: &Path) -> String {
    let b: Vec<_> = base.components().collect();
    let t: Vec<_> = target.components().collect();
    let common = b.iter().zip(&t).take_while(|(x, y)| x == y).count();
    let mut parts: Vec<String> = vec!["..".to_string(); b.len() - common];
    parts.extend(t[common..].iter().map(|c| c.as_os_str().to_string_lossy().into_owned()));
    parts.join("/")
}

fn format_value(v: &serde_json::Value) -> String {
    match v {
        serde_json::Value::Number(n) => match n.as_f64() {
            Some(x) if n.is_f64() && x != 0.0 && (x.abs() < 1e-3 || x.abs() >= 1e6) => format!("{x:.4e}"),
            Some(x) if n.is_f64() => format!("{x:.6}").trim_end_matches('0').trim_end_matches('.').to_string(),
            _ => n.to_string(),
        },
        serde_json::Value::String(s) => s.clone(),
        serde_json::Value::Null => "null (non-finite)".into(),
        other => other.to_string(),
    }
}

/// Writes `report_dir/index.md` from the outcomes and the files each run left in its directory.
pub fn write_report(report_dir: &Path, outcomes: &[Outcome], mode: Mode, total_s: f64) -> Result<PathBuf> {
    ensure_dir(report_dir)?;
    let mut md = String::new();
    let _ = writeln!(md, "# Reproduction report\n");
    let _ = writeln!(
        md,
        "Mode `{}`; {} runs in {:.1} s. Every figure below comes from the run that wrote this report \
         (`cargo xtask repro{}`).\n",
        mode.name(),
        outcomes.len(),
        total_s,
        match mode {
            Mode::Quick => " --quick",
            Mode::Default => "",
            Mode::Full => " --full",
        }
    );
    let _ = writeln!(md, "| run | status | wall time (s) |\n|---|---|---|");
    for o in outcomes {
        let status = if o.error.is_some() { "**failed**" } else { "ok" };
        let _ = writeln!(md, "| [{}](#{}) | {} | {:.2} |", o.id, anchor(&o.id), status, o.wall_s);
    }
    for o in outcomes {
        let _ = writeln!(md, "\n## {}\n\n{}\n", o.id, o.description);
        if let Some(e) = &o.error {
            let _ = writeln!(md, "**Failed:** `{e}`\n");
        }
        let notes = o.out_dir.join("report.md");
        if notes.is_file() {
            let text = std::fs::read_to_string(&notes).map_err(io_err(&notes))?;
            let _ = writeln!(md, "{}\n", text.trim_end());
        }
        let summary = o.out_dir.join("summary.json");
        if summary.is_file() {
            let s = Summary::read(&summary)?;
            let _ = writeln!(md, "<details><summary>summary.json</summary>\n\n| key | value |\n|---|---|");
            for (k, v) in s.iter() {
                let _ = writeln!(md, "| `{k}` | {} |", format_value(v));
            }
            let _ = writeln!(md, "\n</details>\n");
        }
        for png in pngs(&o.out_dir)? {
            let name = png.file_name().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
            let _ = writeln!(md, "![{name}]({})\n", relative(report_dir, &png));
        }
    }
    let path = report_dir.join("index.md");
    std::fs::write(&path, md).map_err(io_err(&path))?;
    Ok(path)
}

fn anchor(id: &str) -> String {
    id.to_lowercase()
        .chars()
        .filter(|c| c.is_alphanumeric() || *c == '-' || *c == ' ')
        .collect::<String>()
        .replace(' ', "-")
}

fn pngs(dir: &Path) -> Result<Vec<PathBuf>> {
    if !dir.is_dir() {
        return Ok(Vec::new());
    }
    let mut v: Vec<PathBuf> = std::fs::read_dir(dir)
        .map_err(io_err(dir))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "png"))
        .collect();
    v.sort();
    Ok(v)
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
    fn report_lists_failures_notes_and_figures() {
        let root = std::env::temp_dir().join(format!("xtask-report-{}", std::process::id()));
        let ok_dir = root.join("c/ok");
        let mut s = Summary::new();
        s.set("err_rel", 2.5e-13);
        s.write(&ok_dir).unwrap();
        std::fs::write(ok_dir.join("report.md"), "| paper | ours |\n|---|---|\n| 1 | 2 |\n").unwrap();
        let outcomes = vec![
            Outcome { id: "c/ok".into(), description: "works".into(), out_dir: ok_dir, wall_s: 0.5, error: None },
            Outcome {
                id: "c/bad".into(),
                description: "breaks".into(),
                out_dir: root.join("c/bad"),
                wall_s: 0.1,
                error: Some("boom".into()),
            },
        ];
        let path = write_report(&root.join("report"), &outcomes, Mode::Quick, 0.6).unwrap();
        let md = std::fs::read_to_string(path).unwrap();
        assert!(md.contains("**Failed:** `boom`"));
        assert!(md.contains("| paper | ours |"));
        assert!(md.contains("`err_rel` | 2.5000e-13"));
        std::fs::remove_dir_all(&root).unwrap();
    }
}

//! Running one scene or one benchmark: output directory, timing, `summary.json`.

use std::path::{Path, PathBuf};
use std::time::Instant;

use crate::error::{Error, Result};
use crate::out::{ensure_dir, Summary};
use crate::registry::{self, BenchCtx, RunCtx};
use crate::scene::{self, Mode};

/// The outcome of one scene or benchmark, for the report.
#[derive(Clone, Debug)]
pub struct Outcome {
    /// `<crate>/<scene>` or `bench/<crate>`.
    pub id: String,
    /// One-line description.
    pub description: String,
    /// Where its files are.
    pub out_dir: PathBuf,
    /// Wall time (s).
    pub wall_s: f64,
    /// The error, if it failed.
    pub error: Option<String>,
}

/// Runs a scene file with its runner into `out_dir`; writes `summary.json` (with `wall_s` and
/// `mode` added) and returns it.
pub fn run_scene(scene_id: &str, file: &Path, mode: Mode, out_dir: &Path) -> Result<Summary> {
    let header = scene::load_header(file)?;
    let runners = registry::runners();
    let runner = runners.iter().find(|r| r.method == header.method).ok_or_else(|| {
        let known: Vec<&str> = runners.iter().map(|r| r.method).collect();
        scene::invalid(file, format!("{scene_id}: unknown method '{}'; known: {}", header.method, known.join(", ")))
    })?;
    ensure_dir(out_dir)?;
    let ctx = RunCtx { scene_file: file.to_path_buf(), mode, out_dir: out_dir.to_path_buf() };
    let t0 = Instant::now();
    let mut summary = (runner.run)(&ctx)?;
    summary.set("wall_s", t0.elapsed().as_secs_f64());
    summary.set_str("mode", mode.name());
    summary.write(out_dir)?;
    Ok(summary)
}

/// Runs the benchmark of `crate_name` into `out_dir`; writes `summary.json`. `sweep` selects one
/// of the bench's sweeps (`--sweep <knob>`, or `all`); an unknown knob is a usage error naming the
/// known ones.
pub fn run_bench(crate_name: &str, quick: bool, sweep: Option<&str>, out_dir: &Path) -> Result<Summary> {
    let benches = registry::benches();
    let bench = benches.iter().find(|b| b.crate_name == crate_name).ok_or_else(|| {
        let known: Vec<&str> = benches.iter().map(|b| b.crate_name).collect();
        Error::Usage(format!("no benchmark for '{crate_name}'; known: {}", known.join(", ")))
    })?;
    if let Some(k) = sweep {
        if bench.sweeps.is_empty() {
            return Err(Error::Usage(format!("the '{crate_name}' benchmark has one fixed sweep; drop --sweep {k}")));
        }
        if k != "all" && !bench.sweeps.contains(&k) {
            return Err(Error::Usage(format!(
                "no sweep '{k}' in the '{crate_name}' benchmark; known: {}, all",
                bench.sweeps.join(", ")
            )));
        }
    }
    ensure_dir(out_dir)?;
    let t0 = Instant::now();
    let ctx = BenchCtx { quick, out_dir: out_dir.to_path_buf(), sweep: sweep.map(str::to_string) };
    let mut summary = (bench.run)(&ctx)?;
    summary.set("wall_s", t0.elapsed().as_secs_f64());
    summary.set_str("mode", if quick { "quick" } else { "default" });
    summary.write(out_dir)?;
    Ok(summary)
}

/// Prints a summary as aligned `key = value` lines.
pub fn print_summary(s: &Summary) {
    let width = s.iter().map(|(k, _)| k.len()).max().unwrap_or(0);
    for (k, v) in s.iter() {
        println!("  {k:width$} = {v}");
    }
}

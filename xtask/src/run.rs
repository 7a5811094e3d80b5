//! Running one scene or one benchmark: the output folder (refused when it holds someone's files,
//! cleared when it is ours or `--force` says so), progress, timing, the generic outputs every
//! run that writes mesh frames gets (previews, USD), `FAILED` when the run fails, and
//! `summary.json` written last and atomically — so a run folder with `summary.json` and no
//! `FAILED` is a finished run.

use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::{Path, PathBuf};
use std::time::Instant;

use crate::error::{io_err, Error, Result};
use crate::out::{ensure_dir, write_atomic, Summary};
use crate::registry::{self, BenchCtx, RunCtx};
use crate::scene::{self, Mode, Override};
use crate::ui::{self, RunProgress};

/// The outcome of one scene or benchmark, for the report.
#[derive(Clone, Debug)]
pub struct Outcome {
    /// `<crate>/<scene>` or `bench/<crate>`.
    pub id: String,
    /// Wall time (s).
    pub wall_s: f64,
    /// The error, if it failed.
    pub error: Option<String>,
}

/// Who owns an output folder that already holds files.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DirPolicy {
    /// The default folder (`out/<crate>/<scene>`): the tool's own, cleared before the run.
    Owned,
    /// A folder given with `--out`: refused when not empty, unless `force` (then cleared).
    Explicit {
        /// `--force`.
        force: bool,
    },
}

/// Options of one run.
#[derive(Clone, Debug)]
pub struct RunOptions {
    /// Run size.
    pub mode: Mode,
    /// The run folder.
    pub out_dir: PathBuf,
    /// What to do when it holds files.
    pub policy: DirPolicy,
    /// `--set` overrides of the scene's parameters.
    pub overrides: Vec<Override>,
    /// Render previews and write USD for mesh sequences (on unless `--no-preview`).
    pub previews: bool,
    /// Label of the progress display (the id, or `[k/n] id` in `repro`).
    pub label: String,
}

/// What a finished run left.
#[derive(Clone, Debug)]
pub struct RunResult {
    /// The figures written to `summary.json`.
    pub summary: Summary,
    /// Wall time of the runner (s).
    pub wall_s: f64,
    /// Wall time of previews and USD export (s).
    pub extras_s: f64,
    /// Files in the run folder.
    pub files: usize,
    /// Their total size (bytes).
    pub bytes: u64,
}

/// The name of the file a failed run leaves in its folder (with the error inside).
pub const FAILED: &str = "FAILED";

/// The metadata file a run leaves beside its outputs (id, description, scene file, mode,
/// overrides), so that a report can be rebuilt from the folder.
pub const RUN_JSON: &str = "run.json";

/// Writes `dir/run.json`.
pub fn write_run_json(
    dir: &Path,
    id: &str,
    description: &str,
    scene_file: Option<&Path>,
    o: &RunOptions,
) -> Result<()> {
    let v = serde_json::json!({
        "id": id,
        "description": description,
        "scene_file": scene_file.map(|p| p.display().to_string()),
        "mode": o.mode.name(),
        "overrides": o.overrides.iter().map(|v| v.to_string()).collect::<Vec<_>>(),
    });
    let text = serde_json::to_string_pretty(&v).map_err(|e| Error::Run(e.to_string()))?;
    write_atomic(&dir.join(RUN_JSON), (text + "\n").as_bytes())
}

/// True when `dir` holds nothing (or does not exist).
fn is_empty_dir(dir: &Path) -> bool {
    std::fs::read_dir(dir).map(|mut r| r.next().is_none()).unwrap_or(true)
}

/// Refuses to clear a folder that holds the current directory, a checkout or a home folder —
/// what a mistyped `--out . --force` would otherwise delete.
fn check_clearable(dir: &Path) -> Result<()> {
    let canon = dir.canonicalize().map_err(io_err(dir))?;
    let cwd = std::env::current_dir().ok().and_then(|c| c.canonicalize().ok());
    let home = std::env::var_os("HOME").map(PathBuf::from).and_then(|h| h.canonicalize().ok());
    let data = crate::paths::find_data_root().and_then(|d| d.canonicalize().ok());
    let why = if canon.parent().is_none() {
        Some("it is the file system root")
    } else if cwd.as_ref().is_some_and(|c| c.starts_with(&canon)) {
        Some("it holds the current directory")
    } else if home.as_ref().is_some_and(|h| h.starts_with(&canon)) {
        Some("it holds the home folder")
    } else if data.as_ref().is_some_and(|d| d.starts_with(&canon)) {
        Some("it holds the toolkit's scenes and assets")
    } else if canon.join("Cargo.toml").exists() || canon.join(".git").exists() {
        Some("it is a project folder (Cargo.toml or .git)")
    } else {
        None
    };
    match why {
        Some(w) => Err(Error::Usage(format!("refusing to clear {}: {w}", dir.display()))),
        None => Ok(()),
    }
}

/// Removes everything inside `dir` (the folder itself stays).
fn clear_dir(dir: &Path) -> Result<()> {
    check_clearable(dir)?;
    for e in std::fs::read_dir(dir).map_err(io_err(dir))? {
        let p = e.map_err(io_err(dir))?.path();
        let r = if p.is_dir() && !p.is_symlink() { std::fs::remove_dir_all(&p) } else { std::fs::remove_file(&p) };
        r.map_err(io_err(&p))?;
    }
    Ok(())
}

/// Makes `dir` an empty run folder according to `policy`.
pub fn prepare_dir(dir: &Path, policy: DirPolicy) -> Result<()> {
    if dir.exists() && !dir.is_dir() {
        return Err(Error::Usage(format!("{} exists and is not a folder", dir.display())));
    }
    if !is_empty_dir(dir) {
        match policy {
            DirPolicy::Explicit { force: false } => {
                return Err(Error::Usage(format!(
                    "{} is not empty: pass --force to clear it first, or choose another --out",
                    dir.display()
                )))
            }
            DirPolicy::Explicit { force: true } | DirPolicy::Owned => clear_dir(dir)?,
        }
    }
    ensure_dir(dir)
}

/// Writes `dir/FAILED` with the error (and removes a `summary.json` a previous step may have
/// left, so the folder never reads as finished).
pub fn write_failed(dir: &Path, what: &str, mode: &str, wall_s: f64, e: &Error) {
    if !dir.is_dir() {
        return;
    }
    let _ = std::fs::remove_file(dir.join("summary.json"));
    let text = format!("{e}\n\nrun: {what}\nmode: {mode}\nwall_s: {wall_s:.3}\n");
    if let Err(w) = write_atomic(&dir.join(FAILED), text.as_bytes()) {
        tell!("warning: could not write {}: {w}", dir.join(FAILED).display());
    }
}

/// The message of a caught panic.
fn panic_message(p: &(dyn std::any::Any + Send)) -> String {
    if let Some(s) = p.downcast_ref::<&str>() {
        (*s).to_string()
    } else if let Some(s) = p.downcast_ref::<String>() {
        s.clone()
    } else {
        "(no message)".into()
    }
}

/// Calls `f`, turning a panic into an error (the run is reported failed, with `FAILED`).
fn guarded<T>(what: &str, f: impl FnOnce() -> Result<T>) -> Result<T> {
    match catch_unwind(AssertUnwindSafe(f)) {
        Ok(r) => r,
        Err(p) => Err(Error::Run(format!("{what} panicked: {}", panic_message(p.as_ref())))),
    }
}

/// Files and bytes under `dir`.
pub fn count_files(dir: &Path) -> (usize, u64) {
    let mut n = 0;
    let mut bytes = 0;
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        let Ok(rd) = std::fs::read_dir(&d) else { continue };
        for e in rd.flatten() {
            let Ok(md) = e.metadata() else { continue };
            if md.is_dir() {
                stack.push(e.path());
            } else {
                n += 1;
                bytes += md.len();
            }
        }
    }
    (n, bytes)
}

/// After the runner: previews and USD of every mesh sequence the run wrote (old-style runners
/// included: this reads the frames from disk), timed into `preview_s`.
fn generic_outputs(dir: &Path, summary: &mut Summary, enabled: bool) -> Result<f64> {
    if !enabled {
        return Ok(0.0);
    }
    let t = Instant::now();
    let n = crate::preview::render_run(dir)?;
    let dt = t.elapsed().as_secs_f64();
    if n > 0 {
        summary.set("preview_s", dt);
    }
    Ok(dt)
}

/// Runs a scene file with its runner into `o.out_dir`; writes `summary.json` (with `wall_s` and
/// `mode` added, last and atomically) and returns it. A failure leaves `FAILED` in the folder.
pub fn run_scene_with(scene_id: &str, file: &Path, o: &RunOptions) -> Result<RunResult> {
    prepare_dir(&o.out_dir, o.policy)?;
    scene::set_overrides(Some(file), o.overrides.clone());
    let progress = RunProgress::start(&o.label);
    let t0 = Instant::now();
    let result = (|| {
        if !o.overrides.is_empty() {
            // Paths that do not exist are refused before any work.
            scene::read_scene_text(file)?;
        }
        let description = scene::load_header(file).map(|h| h.description).unwrap_or_default();
        write_run_json(&o.out_dir, scene_id, &description, Some(file), o)?;
        let runner = registry::runner_for(file)?;
        let ctx = RunCtx::new(file, o.mode, &o.out_dir);
        let mut summary = crate::paths::with_scene_base(file, || guarded(scene_id, || (runner.run)(&ctx)))
            .map_err(|e| scene::locate(file, e))?;
        let wall_s = t0.elapsed().as_secs_f64();
        summary.set("wall_s", wall_s);
        summary.set_str("mode", o.mode.name());
        progress.message("previews");
        let extras_s = guarded("preview", || generic_outputs(&o.out_dir, &mut summary, o.previews))?;
        summary.write(&o.out_dir)?;
        Ok((summary, wall_s, extras_s))
    })();
    progress.finish();
    scene::set_overrides(None, Vec::new());
    match result {
        Ok((summary, wall_s, extras_s)) => {
            let (files, bytes) = count_files(&o.out_dir);
            Ok(RunResult { summary, wall_s, extras_s, files, bytes })
        }
        Err(e) => {
            write_failed(&o.out_dir, scene_id, o.mode.name(), t0.elapsed().as_secs_f64(), &e);
            Err(e)
        }
    }
}

/// Runs the benchmark of `crate_name` into `o.out_dir`; writes `summary.json`. `sweep` selects one
/// of the bench's sweeps (`--sweep <knob>`, or `all`); an unknown knob is a usage error naming the
/// known ones. `--set` overrides apply to every scene file the bench reads; a bench that reads
/// none refuses them.
///
/// `point` (`--point I`) runs only the `I`-th point of a splittable sweep
/// ([`crate::bench_points::points`]); it needs `sweep` (not `all`).
pub fn run_bench(crate_name: &str, sweep: Option<&str>, point: Option<usize>, o: &RunOptions) -> Result<RunResult> {
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
    if let Some(i) = point {
        let k = sweep.filter(|k| *k != "all").ok_or_else(|| {
            Error::Usage(format!("--point {i} needs --sweep <knob> (one of: {})", bench.sweeps.join(", ")))
        })?;
        let n = crate::bench_points::points(crate_name, k, o.mode == Mode::Quick)
            .ok_or_else(|| {
                Error::Usage(format!(
                    "the '{k}' sweep of the '{crate_name}' benchmark does not split into points; run it whole"
                ))
            })?
            .len();
        if i >= n {
            return Err(Error::Usage(format!(
                "--point {i}: the '{k}' sweep of '{crate_name}' has {n} points (0 … {})",
                n - 1
            )));
        }
    }
    prepare_dir(&o.out_dir, o.policy)?;
    scene::set_overrides(None, o.overrides.clone());
    let progress = RunProgress::start(&o.label);
    let t0 = Instant::now();
    let ctx = BenchCtx {
        quick: o.mode == Mode::Quick,
        full: o.mode == Mode::Full,
        out_dir: o.out_dir.to_path_buf(),
        sweep: sweep.map(str::to_string),
        point,
    };
    let id = format!("bench/{crate_name}");
    let result = (|| {
        write_run_json(&o.out_dir, &id, bench.description, None, o)?;
        let mut summary = guarded(&id, || (bench.run)(&ctx))?;
        if !o.overrides.is_empty() && scene::overrides_applied() == 0 {
            return Err(Error::Usage(format!(
                "the '{crate_name}' benchmark reads no scene file, so {} had nothing to change",
                o.overrides.iter().map(|v| v.to_string()).collect::<Vec<_>>().join(" ")
            )));
        }
        let wall_s = t0.elapsed().as_secs_f64();
        summary.set("wall_s", wall_s);
        summary.set_str("mode", o.mode.name());
        let extras_s = guarded("preview", || generic_outputs(&o.out_dir, &mut summary, o.previews))?;
        summary.write(&o.out_dir)?;
        Ok((summary, wall_s, extras_s))
    })();
    progress.finish();
    scene::set_overrides(None, Vec::new());
    match result {
        Ok((summary, wall_s, extras_s)) => {
            let (files, bytes) = count_files(&o.out_dir);
            Ok(RunResult { summary, wall_s, extras_s, files, bytes })
        }
        Err(e) => {
            write_failed(&o.out_dir, &id, o.mode.name(), t0.elapsed().as_secs_f64(), &e);
            Err(e)
        }
    }
}

/// Prints a summary as aligned `key = value` lines.
pub fn print_summary(s: &Summary) {
    let width = s.iter().map(|(k, _)| k.len()).max().unwrap_or(0);
    for (k, v) in s.iter() {
        say!("  {k:width$} = {}", crate::checks::format_value(v));
    }
}

/// The closing lines of a run: wall time, files written, the headline figures with pass/fail
/// against the paper's targets (`checks.json`), or every figure with `verbose`.
pub fn print_closing(id: &str, mode: Mode, dir: &Path, r: &RunResult, verbose: bool) {
    let checks = crate::checks::read(dir).unwrap_or_default();
    let failed = checks.iter().filter(|c| !c.pass).count();
    let verdict = if checks.is_empty() {
        String::new()
    } else if failed == 0 {
        format!("; checks: all {} pass", checks.len())
    } else {
        format!("; checks: {failed} of {} FAIL", checks.len())
    };
    let extras = if r.extras_s > 0.0 { format!(" (+{} previews)", ui::human_secs(r.extras_s)) } else { String::new() };
    say!(
        "done {id} ({}) in {}{extras}: {} files, {} in {}{verdict}",
        mode.name(),
        ui::human_secs(r.wall_s),
        r.files,
        ui::human_bytes(r.bytes),
        dir.display()
    );
    if dir.join("preview.png").is_file() {
        say!("  preview: {}", dir.join("preview.png").display());
    }
    if verbose {
        print_summary(&r.summary);
        return;
    }
    if !checks.is_empty() {
        let w = checks.iter().map(|c| c.key.len()).max().unwrap_or(0);
        for c in &checks {
            say!(
                "  {:w$}  {:>12}  target {:<14} {}  {}",
                c.key,
                crate::checks::format_number(c.value),
                c.target,
                if c.pass { "pass" } else { "FAIL" },
                c.source
            );
        }
    } else {
        // Without paper checks: the first figures that are not timings or run settings.
        let timing = |k: &str| {
            ["_s", "_ms", "_us", "_hz"].iter().any(|u| k.ends_with(u))
                || ["_s_", "s_per_", "_per_s", "speedup", "threads", "profile", "mode"].iter().any(|t| k.contains(t))
        };
        let shown: Vec<_> = r.summary.iter().filter(|(k, _)| !timing(k)).take(8).collect();
        let w = shown.iter().map(|(k, _)| k.len()).max().unwrap_or(0);
        for (k, v) in &shown {
            say!("  {k:w$} = {}", crate::checks::format_value(v));
        }
    }
    let n = r.summary.iter().count();
    say!("  {n} figures in {} (--verbose prints all)", dir.join("summary.json").display());
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tmp(name: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("xtask-run-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        d
    }

    #[test]
    fn explicit_out_is_refused_when_not_empty_and_cleared_with_force() {
        let d = tmp("force");
        prepare_dir(&d, DirPolicy::Explicit { force: false }).unwrap();
        std::fs::write(d.join("stale.obj"), "x").unwrap();
        std::fs::create_dir_all(d.join("frames")).unwrap();
        std::fs::write(d.join("frames/0000.obj"), "x").unwrap();
        let e = prepare_dir(&d, DirPolicy::Explicit { force: false }).unwrap_err();
        assert!(e.to_string().contains("--force"), "{e}");
        assert!(d.join("stale.obj").exists(), "nothing deleted without --force");
        prepare_dir(&d, DirPolicy::Explicit { force: true }).unwrap();
        assert!(is_empty_dir(&d));
        std::fs::write(d.join("stale.obj"), "x").unwrap();
        prepare_dir(&d, DirPolicy::Owned).unwrap();
        assert!(is_empty_dir(&d));
        std::fs::remove_dir_all(&d).unwrap();
    }

    #[test]
    fn force_never_clears_the_current_directory_or_a_project() {
        let e = prepare_dir(Path::new("."), DirPolicy::Explicit { force: true }).unwrap_err();
        assert!(e.to_string().contains("refusing"), "{e}");
        let d = tmp("project");
        std::fs::create_dir_all(&d).unwrap();
        std::fs::write(d.join("Cargo.toml"), "[package]").unwrap();
        let e = prepare_dir(&d, DirPolicy::Explicit { force: true }).unwrap_err();
        assert!(e.to_string().contains("project folder"), "{e}");
        assert!(d.join("Cargo.toml").exists());
        std::fs::remove_dir_all(&d).unwrap();
    }

    #[test]
    fn failed_marker_replaces_a_summary() {
        let d = tmp("failed");
        std::fs::create_dir_all(&d).unwrap();
        Summary::new().write(&d).unwrap();
        write_failed(&d, "c/s", "quick", 1.0, &Error::Run("boom".into()));
        assert!(!d.join("summary.json").exists());
        let text = std::fs::read_to_string(d.join(FAILED)).unwrap();
        assert!(text.starts_with("boom\n"), "{text}");
        let leftovers: Vec<_> = std::fs::read_dir(&d).unwrap().flatten().map(|e| e.file_name()).collect();
        assert_eq!(leftovers.len(), 1, "no temporary file left: {leftovers:?}");
        std::fs::remove_dir_all(&d).unwrap();
    }

    #[test]
    fn panics_become_errors() {
        let prev = std::panic::take_hook();
        std::panic::set_hook(Box::new(|_| {}));
        let r: Result<()> = guarded("x", || panic!("kaboom"));
        std::panic::set_hook(prev);
        assert!(r.unwrap_err().to_string().contains("kaboom"));
    }
}

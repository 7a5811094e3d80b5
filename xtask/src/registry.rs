//! What `cargo xtask` knows: the scene runners and benchmarks each crate registers, and the
//! built-in scene files under `scenes/<crate>/<scene>.ron`.
//!
//! A crate joins by adding a module under `scenes/` (its runners) and/or a benchmark, and one line
//! in [`runners`] / [`benches`]. Built-in scenes are discovered from the scene directory, so adding
//! a scene of an existing runner is adding a file.

use std::path::{Path, PathBuf};

use crate::error::{io_err, Error, Result};
use crate::out::Summary;
use crate::scene::{self, Mode};

/// What a runner is given.
#[derive(Clone, Debug)]
pub struct RunCtx {
    /// The scene file.
    pub scene_file: PathBuf,
    /// Run size.
    pub mode: Mode,
    /// Where every output goes (created before the runner is called).
    pub out_dir: PathBuf,
}

impl RunCtx {
    /// A context for running `scene_file` at `mode` into `out_dir`.
    pub fn new(scene_file: &Path, mode: Mode, out_dir: &Path) -> Self {
        Self { scene_file: scene_file.to_path_buf(), mode, out_dir: out_dir.to_path_buf() }
    }

    /// A path written in the scene file, resolved against the scene file's folder (absolute paths
    /// stay as they are): `Obj(path: "mygrid.obj")` in `/home/u/shot.ron` is
    /// `/home/u/mygrid.obj`, wherever the command runs from. Built-in scenes reach the shipped
    /// assets as `../../assets/…`.
    pub fn resolve(&self, path: impl AsRef<Path>) -> PathBuf {
        crate::paths::resolve_in(&self.scene_file, path.as_ref())
    }
}

/// A scene runner: reads its parameters from the scene file, computes, writes outputs into
/// `out_dir`, and returns the figures of `summary.json`.
pub struct Runner {
    /// The `method` a scene file names to use this runner.
    pub method: &'static str,
    /// The entry point.
    pub run: fn(&RunCtx) -> Result<Summary>,
}

/// What a benchmark is given.
#[derive(Clone, Debug)]
pub struct BenchCtx {
    /// Reduced sweep (smoke test; `repro` runs it by default).
    pub quick: bool,
    /// Paper-scale sweep (`--full`); a bench with one scale treats it as the default.
    #[allow(dead_code)] // read by the benches as they gain full sweeps (issue 22, item 6)
    pub full: bool,
    /// `out/bench/<crate>/` (created before the benchmark is called).
    pub out_dir: PathBuf,
    /// `--sweep <knob>`: run only this sweep (one of the bench's [`Bench::sweeps`], or `all`);
    /// `None` runs the bench's default set.
    pub sweep: Option<String>,
    /// `--point I` (with `--sweep <knob>`): run only the `I`-th point of that sweep
    /// ([`crate::bench_points`]); `None` runs every point.
    pub point: Option<usize>,
}

/// An accuracy-versus-time benchmark of one crate.
pub struct Bench {
    /// The crate name, as in `cargo xtask bench <crate>`.
    pub crate_name: &'static str,
    /// One line saying what it sweeps.
    pub description: &'static str,
    /// The entry point: writes CSV and PNG into `out_dir` and returns the summary figures.
    pub run: fn(&BenchCtx) -> Result<Summary>,
    /// The sweeps `--sweep <knob>` can select (empty: the bench has one fixed sweep).
    pub sweeps: &'static [&'static str],
}

/// Every scene runner of every crate.
pub fn runners() -> Vec<Runner> {
    let mut v = Vec::new();
    crate::crates::geom_core::register(&mut v);
    crate::crates::barnet::register(&mut v);
    crate::crates::shells::register(&mut v);
    crate::crates::tracks::register(&mut v);
    crate::crates::curve_skin::register(&mut v);
    crate::crates::rigging::register(&mut v);
    crate::crates::motion_graph::register(&mut v);
    crate::crates::perf_control::register(&mut v);
    crate::crates::flip_tet::register(&mut v);
    crate::crates::wrinkles::register(&mut v);
    crate::crates::cloth_fit::register(&mut v);
    crate::pipeline::register(&mut v);
    v
}

/// Every benchmark of every crate.
pub fn benches() -> Vec<Bench> {
    vec![
        Bench {
            crate_name: "geom-core",
            description: "sparse solvers: direct factorisation, refactorisation and IC(0)-PCG on Laplacian + mass systems",
            run: crate::bench_geom_core::run,
            sweeps: &[],
        },
        Bench {
            crate_name: "barnet",
            description: "bar-net: membrane resolution vs shape error and time per frame; Catmull-Clark level vs error and arm frame time",
            run: crate::bench_barnet::run,
            sweeps: &[],
        },
        Bench {
            crate_name: "curve-skin",
            description: "curve skinning: frame-table size, LBS influence count and method cost against accuracy",
            run: crate::bench_curve_skin::run,
            sweeps: &[],
        },
        Bench {
            crate_name: "rigging",
            description: "automatic rigging: tau, packing cap and refinement iterations vs embedding success, joint error and time",
            run: crate::bench_rigging::run,
            sweeps: &[],
        },
        Bench {
            crate_name: "shells",
            description: "substeps × Newton iterations × Hessian mode on drape and wind-flag: error vs ms/frame",
            run: crate::bench_shells::run,
            sweeps: &[],
        },
        Bench {
            crate_name: "tracks",
            description: "tracks: 16 … 1024 clustered regions on the Xavier clip, deviation and wavelength vs time per frame",
            run: crate::bench_tracks::run,
            sweeps: &[],
        },
        Bench {
            crate_name: "motion-graph",
            description: "motion graphs: search budget vs constraint error (hierarchy on/off), graph density, database size, smoothing window",
            run: crate::bench_motion_graph::run,
            sweeps: &[],
        },
        Bench {
            crate_name: "perf-control",
            description: "perf-control: beam width, working rate, database size, stretch limit and k vs DP time and walk tracking error",
            run: crate::bench_perf_control::run,
            sweeps: crate::bench_perf_control::SWEEPS,
        },
        Bench {
            crate_name: "flip-tet",
            description: "flip-tet: resolution, adaptivity levels, solver tolerance and boundary order vs dam-break front error, rest speed and time",
            run: crate::bench_flip_tet::run,
            sweeps: crate::bench_flip_tet::SWEEPS,
        },
        Bench {
            crate_name: "wrinkles",
            description: "wrinkles: quadrature tolerance, gradient bins, mode, smoothing and subdivision level vs coefficient/h/area error and time",
            run: crate::bench_wrinkles::run,
            sweeps: &[],
        },
        Bench {
            crate_name: "cloth-fit",
            description: "cloth-fit: annealing budget, coarse search, mesh and image resolution, dt vs parameter error and wall time; evaluation cost by stage; anytime curve",
            run: crate::bench_cloth_fit::run,
            sweeps: crate::bench_cloth_fit::SWEEPS,
        },
    ]
}

/// A built-in scene file.
#[derive(Clone, Debug)]
pub struct BuiltinScene {
    /// `<crate>/<scene>` (the file's directory and stem).
    pub id: String,
    /// The scene file.
    pub file: PathBuf,
    /// Its runner.
    pub method: String,
    /// Its one-line description.
    pub description: String,
}

/// Every built-in scene under `scenes/` (found at run time, [`crate::paths::scenes_dir`]),
/// sorted by id.
pub fn builtin_scenes() -> Result<Vec<BuiltinScene>> {
    builtin_scenes_in(&crate::paths::scenes_dir()?)
}

/// Every scene file under `dir/<crate>/*.ron`, sorted by id.
pub fn builtin_scenes_in(dir: &Path) -> Result<Vec<BuiltinScene>> {
    let mut out = Vec::new();
    if !dir.exists() {
        return Ok(out);
    }
    let mut crates: Vec<PathBuf> =
        std::fs::read_dir(dir).map_err(io_err(dir))?.filter_map(|e| e.ok().map(|e| e.path())).collect();
    crates.sort();
    for c in crates.into_iter().filter(|p| p.is_dir()) {
        let crate_name = c.file_name().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
        let mut files: Vec<PathBuf> = std::fs::read_dir(&c)
            .map_err(io_err(&c))?
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| p.extension().is_some_and(|x| x == "ron"))
            .collect();
        files.sort();
        for f in files {
            let stem = f.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
            let h = scene::load_header(&f)?;
            out.push(BuiltinScene {
                id: format!("{crate_name}/{stem}"),
                file: f,
                method: h.method,
                description: h.description,
            });
        }
    }
    Ok(out)
}

/// Resolves a `run` target: a built-in `<crate>/<scene>` or a path to a `.ron` file. Returns the
/// scene id (a user file gets `<crate>/<file stem>`, the crate taken from its runner) and the file.
pub fn resolve_target(target: &str) -> Result<(String, PathBuf)> {
    let as_path = Path::new(target);
    if target.ends_with(".ron") || as_path.is_file() {
        let abs = crate::paths::absolute(as_path);
        let h = scene::load_header(&abs)?;
        let crate_name = h.method.split('/').next().unwrap_or("scene").to_string();
        let stem = as_path.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_else(|| "scene".into());
        return Ok((format!("{crate_name}/{stem}"), abs));
    }
    let scenes = builtin_scenes()?;
    match scenes.iter().find(|s| s.id == target) {
        Some(s) => Ok((s.id.clone(), s.file.clone())),
        None => {
            let close: Vec<&str> = scenes
                .iter()
                .filter(|s| s.id.split('/').next() == target.split('/').next())
                .map(|s| s.id.as_str())
                .collect();
            Err(Error::Usage(format!(
                "no built-in scene '{target}' and no such .ron file{}; `cargo xtask list` shows every scene",
                if close.is_empty() { String::new() } else { format!(" (this crate has: {})", close.join(", ")) }
            )))
        }
    }
}

/// The runner a scene file names, or an error at the line of its `method` naming the known ones.
pub fn runner_for(file: &Path) -> Result<Runner> {
    let header = scene::load_header(file)?;
    let mut runners = runners();
    match runners.iter().position(|r| r.method == header.method) {
        Some(i) => Ok(runners.swap_remove(i)),
        None => {
            let known: Vec<&str> = runners.iter().map(|r| r.method).collect();
            let text = std::fs::read_to_string(file).map_err(io_err(file))?;
            Err(scene::at_field(
                file,
                &text,
                "method",
                format!("unknown method '{}'; known: {}", header.method, known.join(", ")),
            ))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_builtin_scene_has_a_runner_and_description() {
        let names: Vec<&str> = runners().iter().map(|r| r.method).collect();
        for s in builtin_scenes().unwrap() {
            assert!(names.contains(&s.method.as_str()), "{}: no runner '{}'", s.id, s.method);
            assert!(!s.description.is_empty(), "{}: empty description", s.id);
        }
    }

    #[test]
    fn unknown_target_is_a_clear_error() {
        let e = resolve_target("geom-core/no-such-scene").unwrap_err();
        assert!(e.to_string().contains("no built-in scene"), "{e}");
    }
}

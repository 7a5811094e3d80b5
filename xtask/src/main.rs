//! `cargo xtask …`: the toolkit's command line (ARCHITECTURE.md): list and run scenes, run the
//! accuracy-versus-time benchmarks, inspect mesh and motion files, print a method's parameters,
//! reproduce every paper experiment into one report, and rebuild the report from existing runs.

#[macro_use]
mod ui;

mod bench_barnet;
mod bench_cloth_fit;
mod bench_curve_skin;
mod bench_flip_tet;
mod bench_geom_core;
mod bench_motion_graph;
mod bench_perf_control;
mod bench_rigging;
mod bench_shells;
mod bench_tracks;
mod bench_wrinkles;
mod checks;
mod cmd_retarget;
mod cmd_rig;
mod crates;
mod error;
mod html;
mod inspect;
mod out;
mod params;
mod paths;
mod plot;
mod preview;
mod record;
mod registry;
mod report;
mod ronpath;
mod run;
mod scene;
mod scene_items;

use std::path::PathBuf;
use std::process::ExitCode;

use clap::{Parser, Subcommand};

use crate::run::{DirPolicy, RunOptions};
use crate::scene::{Mode, Override};

#[derive(Parser)]
#[command(name = "cargo xtask", about = "Scenes, benchmarks, file inspection and the reproduction report")]
struct Cli {
    /// Use the built-in scenes of DIR (its parent holds assets/) instead of the ones found beside
    /// the binary or above the current directory.
    #[arg(long, global = true, value_name = "DIR")]
    scenes: Option<PathBuf>,
    #[command(subcommand)]
    cmd: Cmd,
}

#[derive(Subcommand)]
enum Cmd {
    /// Every built-in scene as <crate>/<scene> with a one-line description, and the benchmarks.
    List,
    /// Runs one scene: a built-in <crate>/<scene> or a .ron scene file.
    Run {
        /// <crate>/<scene> or path/to/scene.ron
        target: String,
        /// Reduced version for smoke tests (well under a minute).
        #[arg(long, conflicts_with = "full")]
        quick: bool,
        /// Paper-scale version.
        #[arg(long)]
        full: bool,
        /// Write exactly this scene's files (summary.json included) into DIR; refused when DIR is
        /// not empty, unless --force.
        #[arg(long, value_name = "DIR")]
        out: Option<PathBuf>,
        /// Clear a non-empty --out folder first.
        #[arg(long)]
        force: bool,
        /// Override a parameter: a path inside the scene's params block and a RON value, e.g.
        /// --set shell.material.density=0.2 (repeatable).
        #[arg(long = "set", value_name = "PATH=VALUE")]
        set: Vec<String>,
        /// Print every figure of summary.json at the end.
        #[arg(long, short)]
        verbose: bool,
        /// Skip the previews (preview.png, preview.apng) and USD files of mesh sequences.
        #[arg(long)]
        no_preview: bool,
    },
    /// Runs a crate's accuracy-versus-time sweep into out/bench/<crate>/.
    Bench {
        /// The crate, e.g. geom-core.
        krate: String,
        /// Reduced sweep.
        #[arg(long, conflicts_with = "full")]
        quick: bool,
        /// Paper-scale sweep.
        #[arg(long)]
        full: bool,
        /// Output directory (default out/bench/<crate>); refused when not empty, unless --force.
        #[arg(long, value_name = "DIR")]
        out: Option<PathBuf>,
        /// Clear a non-empty --out folder first.
        #[arg(long)]
        force: bool,
        /// Run only this sweep of the bench (flip-tet: resolution, levels, tol, bc, solver, remesh,
        /// cfl, pic, surface; or all).
        #[arg(long, value_name = "KNOB")]
        sweep: Option<String>,
        /// Override a parameter of the scene files the bench reads (PATH=VALUE, repeatable).
        #[arg(long = "set", value_name = "PATH=VALUE")]
        set: Vec<String>,
        /// Print every figure of summary.json at the end.
        #[arg(long, short)]
        verbose: bool,
    },
    /// Prints what a mesh (OBJ/PLY/OFF) or motion (BVH) file holds, or why it cannot be read.
    Inspect {
        /// The file.
        file: PathBuf,
    },
    /// Prints an annotated template of a method's parameters (units, defaults, the built-in
    /// scenes that use it), e.g. `params shells/drape`; `params` alone lists the methods.
    Params {
        /// A method (<crate>/<runner>) or a crate.
        method: Option<String>,
    },
    /// Rigs a character mesh: rig.json (joints and weights in the mesh's own axes and units),
    /// the rigged character as character.glb and preview.png, into out/rig/<mesh name>/.
    Rig {
        /// The mesh (OBJ, PLY, OFF or GLB).
        mesh: PathBuf,
        /// Skeleton template: human, quadruped or a template .ron file.
        #[arg(long, default_value = "human")]
        skeleton: String,
        /// The mesh's up axis (x, -y, +z, …); detected when not given.
        #[arg(long, value_name = "AXIS", allow_hyphen_values = true)]
        up: Option<String>,
        /// The axis the character faces; detected when not given.
        #[arg(long, value_name = "AXIS", allow_hyphen_values = true)]
        front: Option<String>,
        /// Length unit of the mesh for the glTF file (m, cm, mm, in; auto: from the height).
        #[arg(long, default_value = "auto")]
        units: String,
        /// Output directory.
        #[arg(long, value_name = "DIR")]
        out: Option<PathBuf>,
    },
    /// Plays a BVH clip on a rig of `rig`: retargeted.bvh, animated.glb, skinned OBJ frames.
    Retarget {
        /// The BVH clip.
        clip: PathBuf,
        /// rig.json written by `cargo xtask rig`.
        #[arg(long)]
        rig: PathBuf,
        /// Length unit of the rig (m, cm, mm, in; auto: from its height).
        #[arg(long, default_value = "auto")]
        units: String,
        /// Skinning of the OBJ frames (lbs or dqs).
        #[arg(long, default_value = "dqs")]
        skinning: String,
        /// Write every n-th skinned frame as OBJ (0: none).
        #[arg(long, default_value_t = 10)]
        every: usize,
        /// Output directory.
        #[arg(long, value_name = "DIR")]
        out: Option<PathBuf>,
    },
    /// Every built-in scene and benchmark, then the report out/report/index.html (and index.md).
    Repro {
        /// Smoke run of a few minutes.
        #[arg(long, conflicts_with = "full")]
        quick: bool,
        /// Paper scale (scenes and the benchmarks' full sweeps).
        #[arg(long)]
        full: bool,
        /// Output root (default out/).
        #[arg(long, value_name = "DIR")]
        out: Option<PathBuf>,
    },
    /// (Re)renders preview.png, preview.apng and the .usda files of existing run folders from the
    /// frames and scene.json they hold; prints the time each took.
    Preview {
        /// Run folders.
        #[arg(required = true)]
        dirs: Vec<PathBuf>,
    },
    /// Builds OUT_DIR/report/index.html (and index.md) from the runs found in OUT_DIR at any
    /// depth (folders with summary.json or FAILED).
    Report {
        /// The folder to collect (default out/).
        out_dir: Option<PathBuf>,
    },
}

fn mode(quick: bool, full: bool) -> Mode {
    if quick {
        Mode::Quick
    } else if full {
        Mode::Full
    } else {
        Mode::Default
    }
}

fn overrides(set: &[String]) -> error::Result<Vec<Override>> {
    set.iter().map(|s| Override::parse(s)).collect()
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    if let Some(dir) = &cli.scenes {
        paths::set_scenes_override(dir);
    }
    let result = match cli.cmd {
        Cmd::List => list(),
        Cmd::Run { target, quick, full, out, force, set, verbose, no_preview } => {
            overrides(&set).and_then(|ovs| run_one(&target, mode(quick, full), out, force, ovs, verbose, !no_preview))
        }
        Cmd::Bench { krate, quick, full, out, force, sweep, set, verbose } => {
            overrides(&set).and_then(|ovs| bench_one(&krate, mode(quick, full), out, force, sweep, ovs, verbose))
        }
        Cmd::Inspect { file } => inspect::inspect(&file),
        Cmd::Params { method } => params::print(method.as_deref()),
        Cmd::Rig { mesh, skeleton, up, front, units, out } => {
            let out = out.unwrap_or_else(|| out::default_out_root().join("rig").join(stem(&mesh)));
            cmd_rig::run(&cmd_rig::RigArgs { mesh, skeleton, up, front, units, out })
        }
        Cmd::Retarget { clip, rig, units, skinning, every, out } => {
            let out = out.unwrap_or_else(|| out::default_out_root().join("retarget").join(stem(&clip)));
            cmd_retarget::run(&cmd_retarget::RetargetArgs { clip, rig, units, skinning, every, out })
        }
        Cmd::Repro { quick, full, out } => report::repro(mode(quick, full), out.unwrap_or_else(out::default_out_root)),
        Cmd::Preview { dirs } => previews(&dirs),
        Cmd::Report { out_dir } => report::rebuild(&out_dir.unwrap_or_else(out::default_out_root)),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            tell!("error: {e}");
            ExitCode::FAILURE
        }
    }
}

fn list() -> error::Result<()> {
    let scenes = registry::builtin_scenes()?;
    let width = scenes.iter().map(|s| s.id.len()).max().unwrap_or(0);
    say!("scenes (cargo xtask run <id> [--quick | --full]):");
    for s in &scenes {
        say!("  {:width$}  {}  [{}]", s.id, s.description, s.method);
    }
    say!("benchmarks (cargo xtask bench <crate> [--quick | --full]):");
    for b in registry::benches() {
        say!("  {:width$}  {}", b.crate_name, b.description);
    }
    Ok(())
}

fn previews(dirs: &[PathBuf]) -> error::Result<()> {
    for d in dirs {
        let t = std::time::Instant::now();
        let n = preview::render_run(d)?;
        say!("preview {}: {n} sequences in {:.3} s", d.display(), t.elapsed().as_secs_f64());
    }
    Ok(())
}

fn policy(explicit: bool, force: bool) -> DirPolicy {
    if explicit {
        DirPolicy::Explicit { force }
    } else {
        DirPolicy::Owned
    }
}

fn run_one(
    target: &str,
    mode: Mode,
    out: Option<PathBuf>,
    force: bool,
    overrides: Vec<Override>,
    verbose: bool,
    previews: bool,
) -> error::Result<()> {
    let (id, file) = registry::resolve_target(target)?;
    let explicit = out.is_some();
    let dir = out.unwrap_or_else(|| out::default_out_root().join(&id));
    say!("run {id} ({}) → {}", mode.name(), dir.display());
    say!("  scene file: {}", file.display());
    for o in &overrides {
        say!("  {o}");
    }
    let opts = RunOptions {
        mode,
        out_dir: dir.clone(),
        policy: policy(explicit, force),
        overrides,
        previews,
        label: id.clone(),
    };
    match run::run_scene_with(&id, &file, &opts) {
        Ok(r) => {
            run::print_closing(&id, mode, &dir, &r, verbose);
            Ok(())
        }
        Err(e) => {
            if dir.join(run::FAILED).is_file() {
                say!("FAILED {id} ({}): see {}", mode.name(), dir.join(run::FAILED).display());
            }
            Err(e)
        }
    }
}

fn bench_one(
    krate: &str,
    mode: Mode,
    out: Option<PathBuf>,
    force: bool,
    sweep: Option<String>,
    overrides: Vec<Override>,
    verbose: bool,
) -> error::Result<()> {
    let explicit = out.is_some();
    let dir = out.unwrap_or_else(|| out::default_out_root().join("bench").join(krate));
    let id = format!("bench/{krate}");
    say!("bench {krate} ({}) → {}", mode.name(), dir.display());
    let opts = RunOptions {
        mode,
        out_dir: dir.clone(),
        policy: policy(explicit, force),
        overrides,
        previews: true,
        label: id.clone(),
    };
    let r = run::run_bench(krate, sweep.as_deref(), &opts)?;
    run::print_closing(&id, mode, &dir, &r, verbose);
    Ok(())
}

/// The file name without extension (for default output folders).
fn stem(p: &std::path::Path) -> String {
    p.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_else(|| "input".into())
}

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
mod bench_points;
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
mod pipeline;
mod plot;
mod preview;
mod record;
mod registry;
mod report;
mod ronpath;
mod run;
mod scene;
mod scene_items;
mod sweep;

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
        /// With --out: succeed at once when DIR holds a finished run (summary.json, no FAILED);
        /// otherwise clear DIR and run (what a sweep's task lines use).
        #[arg(long, requires = "out", conflicts_with = "force")]
        resume: bool,
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
        /// Run only the I-th point (from 0) of the --sweep (the sweeps whose points are
        /// independent: flip-tet resolution, levels, tol, bc, remesh, cfl; perf-control rate,
        /// stretch, k).
        #[arg(long, value_name = "I", requires = "sweep")]
        point: Option<usize>,
        /// With --out: succeed at once when DIR holds a finished run; otherwise clear it and run.
        #[arg(long, requires = "out", conflicts_with = "force")]
        resume: bool,
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
    /// Plans a sweep: DIR/tasks.txt (one self-contained command per task), DIR/sweep.ron (task →
    /// parameters) and DIR/sweep.openjd.yaml, from a sweep file or a benchmark's sweep.
    Plan {
        /// A sweep file (.ron: scene, mode, vary).
        #[arg(required_unless_present = "bench", conflicts_with = "bench")]
        file: Option<PathBuf>,
        /// Plan the points of this crate's benchmark sweep instead (with --sweep).
        #[arg(long, value_name = "CRATE", requires = "sweep")]
        bench: Option<String>,
        /// The benchmark's sweep (e.g. resolution).
        #[arg(long, value_name = "KNOB", requires = "bench")]
        sweep: Option<String>,
        /// Bench points at quick size.
        #[arg(long, conflicts_with = "full", requires = "bench")]
        quick: bool,
        /// Bench points at full size.
        #[arg(long, requires = "bench")]
        full: bool,
        /// The sweep folder.
        #[arg(long, value_name = "DIR")]
        out: PathBuf,
        /// Replace another sweep planned in DIR (its tasks/ are removed).
        #[arg(long)]
        force: bool,
    },
    /// Runs, submits or collects a planned sweep.
    Sweep {
        #[command(subcommand)]
        cmd: SweepCmd,
    },
    /// Builds OUT_DIR/report/index.html (and index.md) from the runs found in OUT_DIR at any
    /// depth (folders with summary.json or FAILED).
    Report {
        /// The folder to collect (default out/).
        out_dir: Option<PathBuf>,
    },
}

#[derive(Subcommand)]
enum SweepCmd {
    /// Runs the unfinished tasks of DIR/tasks.txt on this machine, N at a time.
    Run {
        /// DIR/tasks.txt of `plan`.
        tasks: PathBuf,
        /// Concurrent processes.
        #[arg(short = 'j', long, default_value_t = 1)]
        jobs: usize,
    },
    /// Writes DIR/sweep.sbatch (a job array of the unfinished tasks) and submits it with a
    /// dependent job that collects the results.
    Slurm {
        /// DIR/tasks.txt of `plan`.
        tasks: PathBuf,
        /// Slurm partition.
        #[arg(long)]
        partition: Option<String>,
        /// Time limit per task (Slurm syntax, e.g. 0:30:00).
        #[arg(long)]
        time: Option<String>,
        /// Memory per task (Slurm syntax, e.g. 4G).
        #[arg(long)]
        mem: Option<String>,
        /// At most K tasks at once (the array's %K).
        #[arg(long, value_name = "K")]
        throttle: Option<usize>,
        /// Write sweep.sbatch but do not submit.
        #[arg(long)]
        no_submit: bool,
    },
    /// Merges every finished task's summary.json with its parameters into DIR/sweep.csv, plots
    /// each figure against each parameter, and rebuilds DIR/report/index.html.
    Collect {
        /// The sweep folder.
        dir: PathBuf,
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
        Cmd::Run { target, quick, full, out, force, resume, set, verbose, no_preview } => {
            if resumed(resume, out.as_deref()) {
                Ok(())
            } else {
                overrides(&set).and_then(|ovs| {
                    run_one(&target, mode(quick, full), out, force || resume, ovs, verbose, !no_preview)
                })
            }
        }
        Cmd::Bench { krate, quick, full, out, force, sweep, point, resume, set, verbose } => {
            if resumed(resume, out.as_deref()) {
                Ok(())
            } else {
                overrides(&set).and_then(|ovs| {
                    let b = BenchArgs { mode: mode(quick, full), out, force: force || resume, sweep, point };
                    bench_one(&krate, b, ovs, verbose)
                })
            }
        }
        Cmd::Plan { file, bench, sweep, quick, full, out, force } => {
            plan(file.as_deref(), bench.as_deref(), sweep.as_deref(), mode(quick, full), &out, force)
        }
        Cmd::Sweep { cmd } => match cmd {
            SweepCmd::Run { tasks, jobs } => sweep::local::run(&tasks, jobs),
            SweepCmd::Slurm { tasks, partition, time, mem, throttle, no_submit } => {
                let o = sweep::slurm::SlurmOpts { partition, time, mem, throttle };
                sweep::slurm::submit(&tasks, &o, !no_submit)
            }
            SweepCmd::Collect { dir } => sweep::collect::collect(&dir).map(|_| ()),
        },
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

/// `--resume`: true (and says so) when `out` holds a finished run, which is then left as it is.
fn resumed(resume: bool, out: Option<&std::path::Path>) -> bool {
    match out {
        Some(dir) if resume && sweep::task::state(dir) == sweep::task::TaskState::Finished => {
            say!("finished already, skipped: {}", dir.display());
            true
        }
        _ => false,
    }
}

/// `plan`: a sweep file or a bench sweep into `out`.
fn plan(
    file: Option<&std::path::Path>,
    bench: Option<&str>,
    knob: Option<&str>,
    mode: Mode,
    out: &std::path::Path,
    force: bool,
) -> error::Result<()> {
    let dir = paths::absolute(out);
    let p = match (file, bench, knob) {
        (Some(f), _, _) => sweep::plan::Plan::from_file(&sweep::file::load(f)?, &dir),
        (None, Some(b), Some(k)) => sweep::plan::Plan::from_bench(b, k, mode, &dir)?,
        _ => return Err(error::Error::Usage("plan needs a sweep file, or --bench <crate> --sweep <knob>".into())),
    };
    let lines = sweep::plan::write(&p, &dir, force)?;
    let finished = p.tasks.iter().filter(|t| sweep::task::state(&t.dir) == sweep::task::TaskState::Finished).count();
    say!(
        "plan {}: {} tasks over {} ({} mode) → {}",
        p.name(),
        lines.len(),
        p.parameters.join(" × "),
        p.mode,
        dir.display()
    );
    say!("  {}", dir.join(sweep::plan::TASKS_TXT).display());
    say!("  {}", dir.join(sweep::plan::SWEEP_RON).display());
    say!("  {}", dir.join(sweep::openjd::FILE).display());
    if finished > 0 {
        say!("  {finished} tasks already finished (kept)");
    }
    if let Some(first) = lines.first() {
        say!("first task: {first}");
    }
    Ok(())
}

/// The arguments of `bench` besides the crate and overrides.
struct BenchArgs {
    mode: Mode,
    out: Option<PathBuf>,
    force: bool,
    sweep: Option<String>,
    point: Option<usize>,
}

fn bench_one(krate: &str, a: BenchArgs, overrides: Vec<Override>, verbose: bool) -> error::Result<()> {
    let BenchArgs { mode, out, force, sweep, point } = a;
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
    let r = run::run_bench(krate, sweep.as_deref(), point, &opts)?;
    run::print_closing(&id, mode, &dir, &r, verbose);
    Ok(())
}

/// The file name without extension (for default output folders).
fn stem(p: &std::path::Path) -> String {
    p.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_else(|| "input".into())
}

//! `cargo xtask …`: the toolkit's command line (ARCHITECTURE.md): list and run scenes, run the
//! accuracy-versus-time benchmarks, inspect mesh and motion files, and reproduce every paper
//! experiment into one report.

mod bench_barnet;
mod bench_curve_skin;
mod bench_flip_tet;
mod bench_geom_core;
mod bench_motion_graph;
mod bench_perf_control;
mod bench_rigging;
mod bench_shells;
mod bench_tracks;
mod bench_wrinkles;
mod crates;
mod error;
mod inspect;
mod out;
mod plot;
mod record;
mod registry;
mod report;
mod run;
mod scene;
mod scenes;

use std::path::PathBuf;
use std::process::ExitCode;

use clap::{Parser, Subcommand};

use crate::scene::Mode;

#[derive(Parser)]
#[command(name = "cargo xtask", about = "Scenes, benchmarks, file inspection and the reproduction report")]
struct Cli {
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
        /// Write exactly this scene's files (summary.json included) into DIR.
        #[arg(long, value_name = "DIR")]
        out: Option<PathBuf>,
    },
    /// Runs a crate's accuracy-versus-time sweep into out/bench/<crate>/.
    Bench {
        /// The crate, e.g. geom-core.
        krate: String,
        /// Reduced sweep.
        #[arg(long)]
        quick: bool,
        /// Output directory (default out/bench/<crate>).
        #[arg(long, value_name = "DIR")]
        out: Option<PathBuf>,
        /// Run only this sweep of the bench (flip-tet: resolution, levels, tol, bc, solver, remesh,
        /// cfl, pic, surface; or all).
        #[arg(long, value_name = "KNOB")]
        sweep: Option<String>,
    },
    /// Prints what a mesh (OBJ/PLY/OFF) or motion (BVH) file holds, or why it cannot be read.
    Inspect {
        /// The file.
        file: PathBuf,
    },
    /// Every built-in scene and benchmark, then the report out/report/index.md.
    Repro {
        /// Smoke run of a few minutes.
        #[arg(long, conflicts_with = "full")]
        quick: bool,
        /// Paper scale.
        #[arg(long)]
        full: bool,
        /// Output root (default out/).
        #[arg(long, value_name = "DIR")]
        out: Option<PathBuf>,
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

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.cmd {
        Cmd::List => list(),
        Cmd::Run { target, quick, full, out } => run_one(&target, mode(quick, full), out),
        Cmd::Bench { krate, quick, out, sweep } => {
            let dir = out.unwrap_or_else(|| out::default_out_root().join("bench").join(&krate));
            run::run_bench(&krate, quick, sweep.as_deref(), &dir).map(|s| {
                println!("bench {krate}: {}", dir.display());
                run::print_summary(&s);
            })
        }
        Cmd::Inspect { file } => inspect::inspect(&file),
        Cmd::Repro { quick, full, out } => report::repro(mode(quick, full), out.unwrap_or_else(out::default_out_root)),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}

fn list() -> error::Result<()> {
    let scenes = registry::builtin_scenes()?;
    let width = scenes.iter().map(|s| s.id.len()).max().unwrap_or(0);
    println!("scenes (cargo xtask run <id> [--quick | --full]):");
    for s in &scenes {
        println!("  {:width$}  {}  [{}]", s.id, s.description, s.method);
    }
    println!("benchmarks (cargo xtask bench <crate> [--quick]):");
    for b in registry::benches() {
        println!("  {:width$}  {}", b.crate_name, b.description);
    }
    Ok(())
}

fn run_one(target: &str, mode: Mode, out: Option<PathBuf>) -> error::Result<()> {
    let (id, file) = registry::resolve_target(target)?;
    let dir = out.unwrap_or_else(|| out::default_out_root().join(&id));
    let s = run::run_scene(&id, &file, mode, &dir)?;
    println!("{id} ({}): {}", mode.name(), dir.display());
    run::print_summary(&s);
    Ok(())
}

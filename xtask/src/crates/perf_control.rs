//! perf-control's adapter: one runner per experiment of `perf_control::experiments` (PC-1 walk,
//! PC-2 walk timing, PC-3 mouse paths, PC-4 dance, PC-5 dance timing, PC-6 real data and its cross-clip variant), each
//! loading the scene's `params` block and calling the experiment with a file recorder (tables
//! `metrics.csv`, `timing.csv`, `segments.csv`, `target_points.csv`, `dances.csv`,
//! `confusion.csv`, `streaming.csv`, plots `topview.png`, `time_vs_length.png`, `labels.png`,
//! `held_hand.png`, `setup.csv`, `target.bvh`).

use perf_control::experiments::{dance, dance_timing, mouse_paths, real_data, walk, walk_timing};

use crate::error::{Error, Result};
use crate::out::{workspace_root, Summary};
use crate::record::run_experiment;
use crate::registry::{RunCtx, Runner};

impl From<perf_control::PcError> for Error {
    fn from(e: perf_control::PcError) -> Self {
        Error::Run(format!("perf-control: {e}"))
    }
}

/// Adds perf-control's runners.
pub fn register(v: &mut Vec<Runner>) {
    v.push(Runner { method: "perf-control/walk", run: |ctx| run_experiment(ctx, walk::run) });
    v.push(Runner { method: "perf-control/walk-timing", run: |ctx| run_experiment(ctx, walk_timing::run) });
    v.push(Runner { method: "perf-control/mouse-paths", run: |ctx| run_experiment(ctx, mouse_paths::run) });
    v.push(Runner { method: "perf-control/real-data", run: run_real });
    v.push(Runner { method: "perf-control/real-data-cross-clip", run: run_real });
    v.push(Runner { method: "perf-control/dance", run: |ctx| run_experiment(ctx, dance::run) });
    v.push(Runner { method: "perf-control/dance-timing", run: |ctx| run_experiment(ctx, dance_timing::run) });
}

/// PC-6 (both scenes): the BVH paths of the scene file are relative to its folder (`workspace_root()` is the
/// running scene's folder, `crate::paths::relative_base`).
fn run_real(ctx: &RunCtx) -> Result<Summary> {
    run_experiment(ctx, |p: &real_data::Params, size, rec| {
        let mut p = p.clone();
        p.resolve_paths(&workspace_root());
        real_data::run(&p, size, rec)
    })
}

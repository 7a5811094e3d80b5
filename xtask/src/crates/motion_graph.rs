//! motion-graph's adapter: the scenes `scenes/motion-graph/*.ron` name the runner
//! `motion-graph/search`, which loads the `params` block, resolves the BVH paths against the
//! workspace root and calls [`motion_graph::experiments::search::run`] with a file recorder
//! (tables `metrics.csv`, `cuts.csv`, `anytime.csv`, plot `trajectory.png`, `motion.bvh`,
//! `problem_<k>.bvh`, optional stick-figure frames).

use motion_graph::experiments::search::{run, Params};

use crate::error::{Error, Result};
use crate::out::Summary;
use crate::record::run_experiment;
use crate::registry::{RunCtx, Runner};

impl From<motion_graph::Error> for Error {
    fn from(e: motion_graph::Error) -> Self {
        Error::Run(format!("motion-graph: {e}"))
    }
}

/// Adds motion-graph's runner.
pub fn register(v: &mut Vec<Runner>) {
    v.push(Runner { method: "motion-graph/search", run: run_search });
}

/// Runs a motion-graph scene.
fn run_search(ctx: &RunCtx) -> Result<Summary> {
    run_experiment(ctx, |p: &Params, size, rec| {
        let mut p = p.clone();
        p.resolve_paths(&ctx.resolve("."));
        run(&p, size, rec)
    })
}

//! curve-skin's scenes (spec §6) over `curve_skin::experiments`: `curve-skin/arm`
//! (`elbow-bend`, `candy-wrapper`), `curve-skin/humanoid`, `curve-skin/walk`, `curve-skin/perf`.

use curve_skin::experiments::{arm, humanoid, perf, walk};
use curve_skin::SkinError;

use super::run_scene;
use crate::error::{Error, Result};
use crate::out::Summary;
use crate::registry::{RunCtx, Runner};

impl From<SkinError> for Error {
    fn from(e: SkinError) -> Self {
        match e {
            SkinError::Core(c) => Error::Core(c),
            other => Error::Run(format!("curve-skin: {other}")),
        }
    }
}

/// The message of a bad-parameter error (reported against the scene file).
fn param(e: &SkinError) -> Option<&str> {
    match e {
        SkinError::Param(m) => Some(m),
        _ => None,
    }
}

fn run_arm(ctx: &RunCtx) -> Result<Summary> {
    run_scene(ctx, arm::run, param)
}

fn run_humanoid(ctx: &RunCtx) -> Result<Summary> {
    run_scene(ctx, humanoid::run, param)
}

fn run_walk(ctx: &RunCtx) -> Result<Summary> {
    run_scene(ctx, walk::run, param)
}

fn run_perf(ctx: &RunCtx) -> Result<Summary> {
    run_scene(ctx, perf::run, param)
}

/// Adds curve-skin's runners.
pub fn register(v: &mut Vec<Runner>) {
    v.push(Runner { method: "curve-skin/arm", run: run_arm });
    v.push(Runner { method: "curve-skin/humanoid", run: run_humanoid });
    v.push(Runner { method: "curve-skin/walk", run: run_walk });
    v.push(Runner { method: "curve-skin/perf", run: run_perf });
}

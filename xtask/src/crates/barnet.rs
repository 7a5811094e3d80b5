//! barnet's scenes (spec §6) over `barnet::experiments`: `barnet/arm-muscle`,
//! `barnet/elbow-volume`, `barnet/stiffness`, `barnet/topology`, `barnet/scaling`,
//! `barnet/nonlinear-vs-fdm`.

use barnet::experiments::{arm_muscle, elbow_volume, nonlinear_vs_fdm, scaling, stiffness, topology};
use barnet::BarNetError;

use super::run_scene;
use crate::error::{Error, Result};
use crate::out::Summary;
use crate::registry::{RunCtx, Runner};

impl From<BarNetError> for Error {
    fn from(e: BarNetError) -> Self {
        match e {
            BarNetError::Core(c) => Error::Core(c),
            other => Error::Run(other.to_string()),
        }
    }
}

/// The message of a bad-parameter error (reported against the scene file).
fn param(e: &BarNetError) -> Option<&str> {
    match e {
        BarNetError::InvalidParameter(m) => Some(m),
        _ => None,
    }
}

fn run_arm_muscle(ctx: &RunCtx) -> Result<Summary> {
    run_scene(ctx, arm_muscle::run, param)
}

fn run_elbow_volume(ctx: &RunCtx) -> Result<Summary> {
    run_scene(ctx, elbow_volume::run, param)
}

fn run_stiffness(ctx: &RunCtx) -> Result<Summary> {
    run_scene(ctx, stiffness::run, param)
}

fn run_topology(ctx: &RunCtx) -> Result<Summary> {
    run_scene(ctx, topology::run, param)
}

fn run_scaling(ctx: &RunCtx) -> Result<Summary> {
    run_scene(ctx, scaling::run, param)
}

fn run_nonlinear_vs_fdm(ctx: &RunCtx) -> Result<Summary> {
    run_scene(ctx, nonlinear_vs_fdm::run, param)
}

/// Adds barnet's runners.
pub fn register(v: &mut Vec<Runner>) {
    v.push(Runner { method: "barnet/arm-muscle", run: run_arm_muscle });
    v.push(Runner { method: "barnet/elbow-volume", run: run_elbow_volume });
    v.push(Runner { method: "barnet/stiffness", run: run_stiffness });
    v.push(Runner { method: "barnet/topology", run: run_topology });
    v.push(Runner { method: "barnet/scaling", run: run_scaling });
    v.push(Runner { method: "barnet/nonlinear-vs-fdm", run: run_nonlinear_vs_fdm });
}

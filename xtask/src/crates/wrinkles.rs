//! wrinkles' scenes (spec §6) over `wrinkles::experiments`: `wrinkles/uniaxial` (W1),
//! `wrinkles/four-stage` (W2), `wrinkles/sleeve` (W3), `wrinkles/vs-fine` (W4), `wrinkles/precompute-cost` (W5),
//! `wrinkles/realtime-small` (W6).

use wrinkles::experiments::{four_stage, precompute_cost, realtime_small, sleeve, uniaxial, vs_fine};
use wrinkles::WrinkleError;

use super::run_scene;
use crate::error::{Error, Result};
use crate::out::Summary;
use crate::registry::{RunCtx, Runner};

impl From<WrinkleError> for Error {
    fn from(e: WrinkleError) -> Self {
        match e {
            WrinkleError::Core(c) => Error::Core(c),
            other => Error::Run(format!("wrinkles: {other}")),
        }
    }
}

/// The message of a bad-parameter error (reported against the scene file).
fn param(e: &WrinkleError) -> Option<&str> {
    match e {
        WrinkleError::InvalidOption(m) => Some(m),
        _ => None,
    }
}

fn run_uniaxial(ctx: &RunCtx) -> Result<Summary> {
    run_scene(ctx, uniaxial::run, param)
}

fn run_four_stage(ctx: &RunCtx) -> Result<Summary> {
    run_scene(ctx, four_stage::run, param)
}

fn run_sleeve(ctx: &RunCtx) -> Result<Summary> {
    run_scene(ctx, sleeve::run, param)
}

fn run_vs_fine(ctx: &RunCtx) -> Result<Summary> {
    run_scene(ctx, vs_fine::run, param)
}

fn run_realtime(ctx: &RunCtx) -> Result<Summary> {
    run_scene(ctx, realtime_small::run, param)
}

fn run_precompute_cost(ctx: &RunCtx) -> Result<Summary> {
    run_scene(ctx, precompute_cost::run, param)
}

/// Adds wrinkles' runners.
pub fn register(v: &mut Vec<Runner>) {
    v.push(Runner { method: "wrinkles/uniaxial", run: run_uniaxial });
    v.push(Runner { method: "wrinkles/four-stage", run: run_four_stage });
    v.push(Runner { method: "wrinkles/sleeve", run: run_sleeve });
    v.push(Runner { method: "wrinkles/vs-fine", run: run_vs_fine });
    v.push(Runner { method: "wrinkles/realtime-small", run: run_realtime });
    v.push(Runner { method: "wrinkles/precompute-cost", run: run_precompute_cost });
}

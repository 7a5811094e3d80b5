//! Per-crate adapters: each registers its scene runners, which load a scene's parameters, call
//! the crate's experiment with a file-writing recorder (`record::run_experiment`) and return the
//! figures of `summary.json`; and each turns its crate's error type into [`crate::error::Error`].

use ::geom_core::experiment::{Report, Size};
use ::geom_core::record::Recorder;
use serde::de::DeserializeOwned;

use crate::error::{Error, Result};
use crate::out::Summary;
use crate::record::run_experiment;
use crate::registry::RunCtx;
use crate::scene;

pub mod barnet;
pub mod cloth_fit;
pub mod curve_skin;
pub mod flip_tet;
pub mod geom_core;
pub mod motion_graph;
pub mod perf_control;
pub mod rigging;
pub mod shells;
pub mod tracks;
pub mod wrinkles;

/// An experiment of a method crate: `run(&Params, Size, &mut dyn Recorder)`.
pub type Experiment<P, E> = fn(&P, Size, &mut dyn Recorder) -> std::result::Result<Report, E>;

/// Runs `f` on the scene of `ctx` through [`run_experiment`]; an error that `param` recognises
/// as a bad parameter (its message) names the scene file, every other converts with `From`.
pub fn run_scene<P, E>(ctx: &RunCtx, f: Experiment<P, E>, param: fn(&E) -> Option<&str>) -> Result<Summary>
where
    P: DeserializeOwned,
    Error: From<E>,
{
    run_experiment::<P, Error>(ctx, |p, s, r| {
        f(p, s, r).map_err(|e| match param(&e) {
            Some(msg) => scene::invalid(&ctx.scene_file, msg),
            None => Error::from(e),
        })
    })
}

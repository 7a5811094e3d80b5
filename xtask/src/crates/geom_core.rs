//! geom-core's own scenes over `geom_core::experiments`: `geom-core/render`,
//! `geom-core/subdivision`, `geom-core/mocap`. Mesh and clip paths in the scene files are
//! relative to the scene file's folder (`out::workspace_root()` while a scene runs, as
//! `RunCtx::resolve`). (geom-core's error type is xtask's `Error::Core`.)

use geom_core::experiment::{Report, Size};
use geom_core::experiments::{mocap, render, subdivision};
use geom_core::record::Recorder;

use super::run_scene;
use crate::error::Result;
use crate::out::{workspace_root, Summary};
use crate::registry::{RunCtx, Runner};

/// The message of a bad-parameter error (reported against the scene file).
fn param(e: &geom_core::Error) -> Option<&str> {
    match e {
        geom_core::Error::InvalidParameter(m) => Some(m),
        _ => None,
    }
}

fn render_here(p: &render::Params, s: Size, r: &mut dyn Recorder) -> geom_core::Result<Report> {
    render::run(&render::Params { root: workspace_root(), ..p.clone() }, s, r)
}

fn subdivision_here(p: &subdivision::Params, s: Size, r: &mut dyn Recorder) -> geom_core::Result<Report> {
    subdivision::run(&subdivision::Params { root: workspace_root(), ..p.clone() }, s, r)
}

fn mocap_here(p: &mocap::Params, s: Size, r: &mut dyn Recorder) -> geom_core::Result<Report> {
    mocap::run(&mocap::Params { root: workspace_root(), ..p.clone() }, s, r)
}

fn run_render(ctx: &RunCtx) -> Result<Summary> {
    run_scene(ctx, render_here, param)
}

fn run_subdivision(ctx: &RunCtx) -> Result<Summary> {
    run_scene(ctx, subdivision_here, param)
}

fn run_mocap(ctx: &RunCtx) -> Result<Summary> {
    run_scene(ctx, mocap_here, param)
}

/// Adds geom-core's runners.
pub fn register(v: &mut Vec<Runner>) {
    v.push(Runner { method: "geom-core/render", run: run_render });
    v.push(Runner { method: "geom-core/subdivision", run: run_subdivision });
    v.push(Runner { method: "geom-core/mocap", run: run_mocap });
}

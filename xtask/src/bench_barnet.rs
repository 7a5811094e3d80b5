//! `cargo xtask bench barnet`: accuracy versus time of the bar-net (spec §9).
//!
//! 1. Net resolution: the analytic membrane (spec 7.1 c) at N = 8 … 287 (quick: … 71): shape
//!    error against the exact solution, equilibrium residual, factorisation time and time per
//!    frame (constant q: one right-hand side and three back-substitutions).
//! 2. Fine-mesh resolution on the arm: Catmull–Clark levels 0–3, whole-frame time (LBS, bar-net
//!    and subdivision) against the distance of the level-L vertices to their level-4 positions
//!    (coarse vertices keep their indices across levels, so this is the vertex-wise convergence
//!    to the limit surface).
//!
//! Writes `accuracy_vs_time.csv`, `fine_levels.csv`, `accuracy_vs_time.png`, `fine_levels.png`.

use std::time::Instant;

use barnet::analytic;
use barnet::deformer::{BarNetDeformer, DeformerConfig, Drivers, FineSpec, FrameOutput};
use barnet::metrics::max_distance;
use barnet::presets::{biceps_arm, biceps_bulge};
use barnet::subdiv::{self, Scheme};
use barnet::{FdmOptions, FdmSolver};
use geom_core::math::Iso3;
use geom_core::stats::{median, nan_max};

use crate::error::Result;
use crate::out::{CsvWriter, Summary};
use crate::plot::{LinePlot, Series};
use crate::registry::BenchCtx;

/// The paper's biceps arm with its bulge channel, skinned at Catmull–Clark level `levels`.
fn arm_config(levels: u32) -> DeformerConfig {
    DeformerConfig {
        loads: vec![biceps_bulge()],
        fine: FineSpec::Subdivision { scheme: Scheme::CatmullClark, levels },
        ..biceps_arm()
    }
}

/// Runs the sweep; see the module docs.
pub fn run(ctx: &BenchCtx) -> Result<Summary> {
    let mut s = Summary::new();
    // 1. Net resolution.
    let ns: &[usize] = if ctx.quick { &[8, 17, 35, 71] } else { &[8, 17, 35, 71, 143, 287] };
    let mut csv = CsvWriter::create(
        &ctx.out_dir.join("accuracy_vs_time.csv"),
        &["N", "free_nodes", "shape_err", "residual", "factor_s", "frame_s"],
    )?;
    let (mut pts, mut fpts) = (Vec::new(), Vec::new());
    let mut max_res: f64 = 0.0;
    for &n in ns {
        let c = analytic::membrane(n, 1.0);
        let (loads, fixed) = c.split();
        let t0 = Instant::now();
        let solver = FdmSolver::new(&c.net, &FdmOptions::default())?;
        let tf = t0.elapsed().as_secs_f64();
        let mut x = Vec::new();
        let mut times = Vec::new();
        let mut res = 0.0;
        for _ in 0..5 {
            let t = Instant::now();
            res = solver.solve_into(&loads, &fixed, &mut x)?.rel_residual;
            times.push(t.elapsed().as_secs_f64());
        }
        let tsol = median(&times);
        let err = analytic::max_abs_err(&x, c.exact.as_ref().expect("membrane has an exact solution"), 2);
        max_res = nan_max(max_res, res);
        pts.push((tsol, err));
        fpts.push((tf, err));
        csv.row(&[n.into(), loads.len().into(), err.into(), res.into(), tf.into(), tsol.into()])?;
    }
    s.set("membrane_max_equilibrium_residual", max_res);
    if let Some(&(t, e)) = pts.last() {
        s.set("membrane_finest_shape_err", e);
        s.set("membrane_finest_frame_s", t);
    }
    LinePlot::new("Membrane net: shape error vs time", "time (s)", "max nodal error vs exact")
        .log(true, true)
        .with(Series::new("per frame (back-substitution)", pts))
        .with(Series::new("factorisation", fpts))
        .write_png(&ctx.out_dir.join("accuracy_vs_time.png"))?;
    // 2. Fine-mesh resolution on the arm.
    let arm = barnet::arm::Arm::new(&Default::default())?;
    let max_level = if ctx.quick { 3 } else { 4 };
    let (reference, _) = subdiv::catmull_clark(&arm.mesh, max_level)?;
    let mut csv =
        CsvWriter::create(&ctx.out_dir.join("fine_levels.csv"), &["level", "fine_vertices", "geom_err_m", "frame_s"])?;
    let mut lpts = Vec::new();
    for level in 0..max_level {
        let (fine, _) = subdiv::catmull_clark(&arm.mesh, level)?;
        // Coarse vertices keep their indices across levels: compare the common prefix.
        let err = max_distance(&fine.positions, &reference.positions);
        let mut d = BarNetDeformer::new(&arm_config(level))?;
        let pose = d.arm_pose(1.5, &Iso3::identity())?;
        let drv = Drivers { joint_angles: vec![0.0, 1.5, 0.0], time: 0.0 };
        let mut out = FrameOutput::default();
        let mut times = Vec::new();
        for _ in 0..21 {
            d.deform(&pose, &drv, &mut out)?;
            times.push(out.timings.total);
        }
        let t = median(&times);
        lpts.push((t, err));
        csv.row(&[(level as usize).into(), fine.positions.len().into(), err.into(), t.into()])?;
        if level == 2 {
            s.set("arm_frame_s_level2", t);
        }
    }
    LinePlot::new(
        "Arm: fine-mesh geometric error vs time per frame",
        "time per frame (s)",
        "distance to level-max vertices (m)",
    )
    .log(true, true)
    .with(Series::new("Catmull-Clark levels 0..", lpts))
    .write_png(&ctx.out_dir.join("fine_levels.png"))?;
    s.set_str("timing_profile", if cfg!(debug_assertions) { "dev" } else { "release" });
    Ok(s)
}

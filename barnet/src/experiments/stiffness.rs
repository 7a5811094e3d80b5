//! Animated stiffness (spec §6.3, §3.6): the biceps bar group's force density follows its
//! stiffness channel (1 → 0.25 → 1 over the run) under constant loads, which costs a numeric
//! refactorisation per frame; compared with the same deformer at constant q.
//!
//! Outputs: table `metrics` (case, frame, bulge, residual, refactorised, stage times), plots
//! `bulge` and `time`, fine-mesh frames `frames/NNNN.obj` of the animated case. Figures:
//! `bulge_max_m_animated_q`, `bulge_max_m_constant_q` (m), `refactorizations`,
//! `max_equilibrium_residual`, and the timings `s_per_frame_animated_q`,
//! `s_per_frame_constant_q` (s), `refactor_time_ratio` with `timing_profile`.
//!
//! ```no_run
//! use barnet::deformer::{DriverSpec, GroupSpec, NodeSet, StiffnessSpec};
//! use barnet::experiments::stiffness::{run, Params};
//! use geom_core::experiment::{BySize, Size};
//! use geom_core::record::NullRecorder;
//! let mut deformer = barnet::presets::biceps_arm();
//! deformer.groups.push(GroupSpec { id: 1, nodes: NodeSet::Named("biceps".into()) });
//! deformer.stiffness.push(StiffnessSpec {
//!     group: 1,
//!     driver: DriverSpec::Time,
//!     curve: vec![(0.0, 1.0), (0.5, 0.25), (1.0, 1.0)],
//! });
//! let mut bulge = barnet::presets::biceps_bulge();
//! bulge.driver = DriverSpec::Constant;
//! deformer.loads.push(bulge);
//! let p = Params { deformer, elbow_deg: 90.0, frames: BySize::Same(5), obj_every: 10, timing_reps: 1 };
//! let r = run(&p, Size::Quick, &mut NullRecorder::default()).unwrap();
//! assert!(r.get_f64("bulge_max_m_animated_q") > r.get_f64("bulge_max_m_constant_q"));
//! ```

use geom_core::experiment::{BySize, Report, Size, Target};
use geom_core::math::Iso3;
use geom_core::record::{Recorder, Series};
use geom_core::stats::{self, nan_max};
use serde::Deserialize;

use crate::deformer::{BarNetDeformer, DeformerConfig, Drivers, FrameOutput};
use crate::error::Result;
use crate::metrics::bulge;

use super::{check_residual, fine_frame, median_timings, profile};

/// The scene's `params` block.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Params {
    /// Deformer with a stiffness channel (driver `Time`, t ∈ [0, 1] over the run).
    pub deformer: DeformerConfig,
    /// Elbow angle held during the run (degrees).
    pub elbow_deg: f64,
    /// Frames (at least 2).
    pub frames: BySize<usize>,
    /// Frame stride of the OBJ output.
    pub obj_every: usize,
    /// Timing repetitions per frame (the frame time is the one with the median total).
    pub timing_reps: usize,
}

fn series(plot: &str, label: &str, y: &str, log_y: bool, points: Vec<(f64, f64)>) -> Series {
    Series { plot: plot.into(), label: label.into(), axes: ("t".into(), y.into()), log: (false, log_y), points }
}

/// Runs both cases; see the module docs.
pub fn run(p: &Params, size: Size, rec: &mut dyn Recorder) -> Result<Report> {
    let n = p.frames.get(size).max(2);
    rec.table(
        "metrics",
        &["case", "frame", "t", "bulge_m", "residual", "refactored", "t_stiffness_s", "t_solve_s", "t_total_s"],
    )?;
    let mut s = Report::default();
    let mut max_res: f64 = 0.0;
    for (ci, case) in ["animated_q", "constant_q"].into_iter().enumerate() {
        let mut cfg = p.deformer.clone();
        if case == "constant_q" {
            cfg.stiffness.clear();
        }
        let mut d = BarNetDeformer::new(&cfg)?;
        let faces = d.fine.faces().clone();
        let a = p.elbow_deg.to_radians();
        let pose = d.arm_pose(a, &Iso3::identity())?;
        let x_max = d.arm.spec.upper_len - 2.0 * cfg.ramp_half_width;
        let mut out = FrameOutput::default();
        let mut lbs_fine = Vec::new();
        let (mut bp, mut tp, mut totals) = (Vec::new(), Vec::new(), Vec::new());
        let mut refactors = 0usize;
        for f in 0..n {
            rec.progress((ci * n + f) as u64, 2 * n as u64);
            let t = f as f64 / (n - 1) as f64;
            let mut times = Vec::new();
            for r in 0..p.timing_reps.max(1) {
                // Alternate the driver so that every repetition refactorises when q is animated.
                let tt = if r % 2 == 1 && case == "animated_q" { (t + 0.5 / n as f64).min(1.0) } else { t };
                d.deform(&pose, &Drivers { joint_angles: vec![0.0, a, 0.0], time: tt }, &mut out)?;
                refactors += out.refactored as usize;
                times.push(out.timings);
            }
            d.deform(&pose, &Drivers { joint_angles: vec![0.0, a, 0.0], time: t }, &mut out)?;
            let tm = median_timings(&mut times);
            check_residual("stiffness", out.residual, 1e-12)?;
            max_res = nan_max(max_res, out.residual);
            d.fine.eval(&out.lbs, &mut lbs_fine);
            let b = bulge(&out.fine, &lbs_fine, x_max);
            bp.push((t, b * 1000.0));
            tp.push((t, tm.total * 1e6));
            totals.push(tm.total);
            rec.row(
                "metrics",
                &[
                    case.into(),
                    f.into(),
                    t.into(),
                    b.into(),
                    out.residual.into(),
                    (out.refactored as usize).into(),
                    tm.stiffness.into(),
                    tm.solve.into(),
                    tm.total.into(),
                ],
            )?;
            if case == "animated_q" && (f % p.obj_every.max(1) == 0 || f + 1 == n) {
                fine_frame(rec, "frames", f, &out.fine, &faces)?;
            }
        }
        s.timing(&format!("s_per_frame_{case}"), stats::mean(&totals));
        s.num(&format!("bulge_max_m_{case}"), bp.iter().map(|x| x.1).fold(0.0, nan_max) / 1000.0);
        if case == "animated_q" {
            s.count("refactorizations", refactors as u64);
        }
        rec.series(&series("bulge", case, "bulge height (mm)", false, bp))?;
        rec.series(&series("time", case, "time per frame (us)", true, tp))?;
    }
    s.num("max_equilibrium_residual", max_res);
    s.timing("refactor_time_ratio", s.get_f64("s_per_frame_animated_q") / s.get_f64("s_per_frame_constant_q"));
    s.text("timing_profile", profile());
    s.check("max_equilibrium_residual", Target::AtMost(1e-12), "spec §7.3 e: every frame in equilibrium");
    Ok(s)
}

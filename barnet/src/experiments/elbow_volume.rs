//! The paper's elbow example (spec §6.2): radial loads on the elbow ring whose magnitude is
//! fitted per frame by secant iterations (spec §3.8) so that the capped fine mesh keeps its rest
//! volume; LBS and DQS of the same control mesh for reference.
//!
//! Outputs: table `metrics` (per frame: relative volume change of LBS, DQS and the bar-net,
//! fitted magnitude, residual, times), plots `volume` and `fitted_magnitude`, fine-mesh frames
//! `frames/NNNN.obj` every `obj_every` frames. Figures: `volume_loss_lbs_max_rel`,
//! `volume_loss_dqs_max_rel`, `volume_err_barnet_max_rel`, `fitted_magnitude_max`,
//! `max_equilibrium_residual`, `free_nodes`, `frames`, `curve_skin_reference`, and the timings
//! `s_per_frame`, `s_per_frame_with_fit` (s).
//!
//! ```no_run
//! use barnet::deformer::{DirLocal, DriverSpec, LoadSpec, NodeSet};
//! use barnet::experiments::elbow_volume::{run, Params};
//! use barnet::experiments::Sweep;
//! use geom_core::experiment::{BySize, Size};
//! use geom_core::record::NullRecorder;
//! let mut deformer = barnet::presets::biceps_arm();
//! deformer.free = NodeSet::Named("elbow_24".into());
//! deformer.loads.push(LoadSpec {
//!     name: "elbow_volume".into(),
//!     nodes: NodeSet::Named("elbow_ring".into()),
//!     dir_local: DirLocal::Radial,
//!     driver: DriverSpec::JointAngle { joint: "elbow".into() },
//!     curve: vec![(0.0, 0.0), (2.4, 1.0)],
//!     scale: 0.02,
//! });
//! let sweep = Sweep { from_deg: 0.0, to_deg: 140.0, frames: BySize::Same(8) };
//! let p = Params { deformer, sweep, obj_every: 10, secant_iters: 3 };
//! let r = run(&p, Size::Quick, &mut NullRecorder::default()).unwrap();
//! assert!(r.get_f64("volume_err_barnet_max_rel") < 1e-4);
//! ```

use std::time::Instant;

use geom_core::experiment::{Report, Size, Target};
use geom_core::math::{Iso3, Pt3};
use geom_core::record::{Recorder, Series};
use geom_core::stats::{self, nan_max};
use serde::Deserialize;

use crate::deformer::{BarNetDeformer, DeformerConfig, Drivers, FrameOutput};
use crate::error::{BarNetError, Result};
use crate::volume::CappedVolume;

use super::{check_residual, fine_frame, Sweep};

/// The scene's `params` block.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Params {
    /// Deformer with the elbow net; its first load channel's magnitude is fitted per frame.
    pub deformer: DeformerConfig,
    /// The elbow sweep.
    pub sweep: Sweep,
    /// Frame stride of the OBJ output.
    pub obj_every: usize,
    /// Secant iterations per frame (spec §3.8: 2–3).
    pub secant_iters: usize,
}

fn series(plot: &str, label: &str, y: &str, points: Vec<(f64, f64)>) -> Series {
    Series {
        plot: plot.into(),
        label: label.into(),
        axes: ("elbow flexion (deg)".into(), y.into()),
        log: (false, false),
        points,
    }
}

/// Runs the sweep; see the module docs.
pub fn run(p: &Params, size: Size, rec: &mut dyn Recorder) -> Result<Report> {
    let angles = p.sweep.angles(size);
    let mut d = BarNetDeformer::new(&p.deformer)?;
    if d.loads.is_empty() {
        return Err(BarNetError::InvalidParameter("elbow-volume: the deformer needs a load channel to fit".into()));
    }
    let n_ch = d.loads.len();
    let faces = d.fine.faces().clone();
    let cv = CappedVolume::for_faces(&faces)?;
    let mut out = FrameOutput::default();
    let rest_pose = d.arm_pose(0.0, &Iso3::identity())?;
    d.deform_with(&rest_pose, &Drivers { joint_angles: vec![0.0; 3], time: 0.0 }, Some(&vec![0.0; n_ch]), &mut out)?;
    let v_rest = cv.volume(&out.fine);
    rec.table(
        "metrics",
        &[
            "frame",
            "elbow_deg",
            "volume_lbs_rel",
            "volume_dqs_rel",
            "volume_barnet_rel",
            "fitted_magnitude",
            "residual",
            "t_frame_s",
            "t_fit_s",
        ],
    )?;
    let (mut max_res, mut loss_lbs, mut loss_dqs, mut err_bn, mut fmax): (f64, f64, f64, f64, f64) =
        (0.0, 0.0, 0.0, 0.0, 0.0);
    let (mut s_lbs, mut s_dqs, mut s_bn, mut s_f) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    let (mut frame_times, mut fit_times) = (Vec::new(), Vec::new());
    let mut f_prev = 0.0;
    let mut dqs_ctrl = vec![Pt3::origin(); d.control_rest().positions.len()];
    let mut tmp = Vec::new();
    for (fi, &a) in angles.iter().enumerate() {
        rec.progress(fi as u64, angles.len() as u64);
        let pose = d.arm_pose(a, &Iso3::identity())?;
        let drv = Drivers { joint_angles: vec![0.0, a, 0.0], time: fi as f64 };
        let t0 = Instant::now();
        let vol = |d: &mut BarNetDeformer, f: f64, out: &mut FrameOutput| -> Result<f64> {
            let mut m = vec![0.0; n_ch];
            m[0] = f;
            d.deform_with(&pose, &drv, Some(&m), out)?;
            Ok(cv.volume(&out.fine) - v_rest)
        };
        // Secant on f (volume is nearly linear in f: positions are linear in the loads).
        let (mut f0, mut f1) = (f_prev, f_prev + 0.25);
        let (mut g0, mut g1) = (vol(&mut d, f0, &mut out)?, vol(&mut d, f1, &mut out)?);
        for _ in 0..p.secant_iters {
            if g1 == g0 || (g1.abs() <= 1e-12 * v_rest) {
                break;
            }
            let f2 = f1 - g1 * (f1 - f0) / (g1 - g0);
            (f0, g0, f1) = (f1, g1, f2);
            g1 = vol(&mut d, f1, &mut out)?;
        }
        fit_times.push(t0.elapsed().as_secs_f64());
        let t1 = Instant::now();
        vol(&mut d, f1, &mut out)?;
        frame_times.push(t1.elapsed().as_secs_f64());
        f_prev = f1;
        check_residual("elbow-volume", out.residual, 1e-12)?;
        max_res = nan_max(max_res, out.residual);
        d.fine.eval(&out.lbs, &mut tmp);
        let v_l = cv.volume(&tmp) / v_rest - 1.0;
        d.weights.dqs(&d.control_rest().positions, &pose, &mut dqs_ctrl);
        d.fine.eval(&dqs_ctrl, &mut tmp);
        let v_d = cv.volume(&tmp) / v_rest - 1.0;
        let v_b = cv.volume(&out.fine) / v_rest - 1.0;
        loss_lbs = nan_max(loss_lbs, -v_l);
        loss_dqs = nan_max(loss_dqs, -v_d);
        err_bn = nan_max(err_bn, v_b.abs());
        fmax = nan_max(fmax, f1.abs());
        let deg = a.to_degrees();
        s_lbs.push((deg, v_l * 100.0));
        s_dqs.push((deg, v_d * 100.0));
        s_bn.push((deg, v_b * 100.0));
        s_f.push((deg, f1));
        rec.row(
            "metrics",
            &[
                fi.into(),
                deg.into(),
                v_l.into(),
                v_d.into(),
                v_b.into(),
                f1.into(),
                out.residual.into(),
                frame_times[fi].into(),
                fit_times[fi].into(),
            ],
        )?;
        if fi % p.obj_every.max(1) == 0 || fi + 1 == angles.len() {
            fine_frame(rec, "frames", fi, &out.fine, &faces)?;
        }
    }
    let y = "volume change (%)";
    rec.series(&series("volume", "LBS", y, s_lbs))?;
    rec.series(&series("volume", "DQS", y, s_dqs))?;
    rec.series(&series("volume", "LBS + bar-net (fitted loads)", y, s_bn))?;
    rec.series(&series("fitted_magnitude", "fitted", "magnitude (x scale)", s_f))?;
    let mut s = Report::default();
    s.num("max_equilibrium_residual", max_res);
    s.num("volume_loss_lbs_max_rel", loss_lbs);
    s.num("volume_loss_dqs_max_rel", loss_dqs);
    s.num("volume_err_barnet_max_rel", err_bn);
    s.num("fitted_magnitude_max", fmax);
    s.timing("s_per_frame", stats::mean(&frame_times));
    s.timing("s_per_frame_with_fit", stats::mean(&fit_times));
    s.count("free_nodes", d.solver.free_nodes().len() as u64);
    s.count("frames", angles.len() as u64);
    s.text("curve_skin_reference", "not run: barnet must not depend on curve-skin this session");
    s.check("max_equilibrium_residual", Target::AtMost(1e-12), "spec §7.3 e: every frame in equilibrium");
    let src = "spec §3.8: loads fitted to the rest volume (ours: within 0.01 %)";
    s.check("volume_err_barnet_max_rel", Target::AtMost(1e-4), src);
    Ok(s)
}

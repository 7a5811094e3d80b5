//! The paper's Figure 3 (spec §6.1): biceps/triceps bar-nets on the procedural arm (12 free
//! nodes), an elbow sweep, force-density variants (paper: lower q, bigger bulge) and the
//! Catmull–Clark level-2 skin of 2816 faces.
//!
//! Outputs: table `metrics` (per q and frame: bulge, volumes, residual, stage times), plots
//! `bulge` and `volume`, fine-mesh frames `frames/NNNN.obj` and control frames
//! `control/NNNN.obj` of the first q every `obj_every` frames, a note with the paper's figures.
//! Figures: `bulge_height_m_q<q>` (m), `lower_q_bigger_bulge` (1 if the peak bulge grows
//! strictly as q decreases), `max_equilibrium_residual`, `fine_faces`, `fine_vertices`,
//! `control_vertices`, `free_nodes`, `frames`, `solver_path`, and the timings `s_per_frame`,
//! `s_per_frame_max`, `s_per_frame_barnet` (s) with `timing_profile`.
//!
//! ```no_run
//! use barnet::experiments::arm_muscle::{run, Params};
//! use barnet::experiments::Sweep;
//! use geom_core::experiment::{BySize, Size};
//! use geom_core::record::NullRecorder;
//! let mut deformer = barnet::presets::biceps_arm();
//! deformer.loads.push(barnet::presets::biceps_bulge());
//! let p = Params {
//!     deformer,
//!     q_variants: vec![1.0, 0.5],
//!     sweep: Sweep { from_deg: 0.0, to_deg: 140.0, frames: BySize::Same(8) },
//!     obj_every: 10,
//!     timing_reps: 1,
//! };
//! let r = run(&p, Size::Quick, &mut NullRecorder::default()).unwrap();
//! assert_eq!(r.get_f64("lower_q_bigger_bulge"), 1.0);
//! ```

use geom_core::experiment::{Report, Size, Target};
use geom_core::math::Iso3;
use geom_core::record::{Recorder, Series};
use geom_core::stats::{self, nan_max};
use serde::Deserialize;

use crate::deformer::{BarNetDeformer, DeformerConfig, Drivers, FrameOutput};
use crate::error::Result;
use crate::metrics::bulge;
use crate::volume::CappedVolume;

use super::{check_residual, control_frame, fine_frame, median_timings, profile, Sweep};

/// The scene's `params` block.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Params {
    /// The arm deformer (its `q` is replaced by each variant).
    pub deformer: DeformerConfig,
    /// Force-density variants; the first is the main run (frames, timings).
    pub q_variants: Vec<f64>,
    /// The elbow sweep.
    pub sweep: Sweep,
    /// Frame stride of the OBJ output.
    pub obj_every: usize,
    /// Timing repetitions per frame (the frame time is the one with the median total).
    pub timing_reps: usize,
}

fn series(plot: &str, label: String, y: &str, points: Vec<(f64, f64)>) -> Series {
    Series { plot: plot.into(), label, axes: ("elbow flexion (deg)".into(), y.into()), log: (false, false), points }
}

/// Runs the sweep for every q; see the module docs.
pub fn run(p: &Params, size: Size, rec: &mut dyn Recorder) -> Result<Report> {
    let angles = p.sweep.angles(size);
    rec.table(
        "metrics",
        &[
            "q",
            "frame",
            "elbow_deg",
            "bulge_m",
            "volume_m3",
            "volume_lbs_m3",
            "residual",
            "t_lbs_s",
            "t_loads_s",
            "t_solve_s",
            "t_fine_s",
            "t_total_s",
        ],
    )?;
    let mut s = Report::default();
    let mut max_res: f64 = 0.0;
    let (mut main_times, mut main_barnet_times) = (Vec::new(), Vec::new());
    let mut peak_bulges = Vec::new();
    for (vi, &q) in p.q_variants.iter().enumerate() {
        let mut cfg = p.deformer.clone();
        cfg.q = q;
        let mut d = BarNetDeformer::new(&cfg)?;
        let faces = d.fine.faces().clone();
        let cv = CappedVolume::for_faces(&faces)?;
        let x_max = d.arm.spec.upper_len - 2.0 * cfg.ramp_half_width;
        let mut out = FrameOutput::default();
        let mut lbs_fine = Vec::new();
        let (mut bpts, mut vpts, mut vlbs) = (Vec::new(), Vec::new(), Vec::new());
        for (f, &a) in angles.iter().enumerate() {
            rec.progress((vi * angles.len() + f) as u64, (p.q_variants.len() * angles.len()) as u64);
            let pose = d.arm_pose(a, &Iso3::identity())?;
            let drivers = Drivers { joint_angles: vec![0.0, a, 0.0], time: f as f64 };
            let mut times = Vec::new();
            for _ in 0..p.timing_reps.max(1) {
                d.deform(&pose, &drivers, &mut out)?;
                times.push(out.timings);
            }
            let t = median_timings(&mut times);
            check_residual("arm-muscle", out.residual, 1e-12)?;
            max_res = nan_max(max_res, out.residual);
            d.fine.eval(&out.lbs, &mut lbs_fine);
            let b = bulge(&out.fine, &lbs_fine, x_max);
            let (vol, vol_l) = (cv.volume(&out.fine), cv.volume(&lbs_fine));
            bpts.push((a.to_degrees(), b * 1000.0));
            vpts.push((a.to_degrees(), vol * 1e6));
            vlbs.push((a.to_degrees(), vol_l * 1e6));
            rec.row(
                "metrics",
                &[
                    q.into(),
                    f.into(),
                    a.to_degrees().into(),
                    b.into(),
                    vol.into(),
                    vol_l.into(),
                    out.residual.into(),
                    t.lbs.into(),
                    t.loads.into(),
                    t.solve.into(),
                    t.fine.into(),
                    t.total.into(),
                ],
            )?;
            if vi == 0 {
                main_times.push(t.total);
                main_barnet_times.push(t.loads + t.solve + t.stiffness);
                if f % p.obj_every.max(1) == 0 || f + 1 == angles.len() {
                    fine_frame(rec, "frames", f, &out.fine, &faces)?;
                    control_frame(rec, "control", f, &out.control, &d.control_rest().faces)?;
                }
            }
        }
        let peak = bpts.iter().map(|p| p.1).fold(0.0, nan_max) / 1000.0;
        peak_bulges.push((q, peak));
        s.num(&format!("bulge_height_m_q{q}"), peak);
        rec.series(&series("bulge", format!("bar-net, q = {q}"), "bulge height (mm)", bpts))?;
        if vi == 0 {
            rec.series(&series("volume", "LBS".into(), "volume (cm^3)", vlbs))?;
            rec.series(&series("volume", format!("bar-net, q = {q}"), "volume (cm^3)", vpts))?;
            s.count("fine_faces", faces.len() as u64);
            s.count("fine_vertices", out.fine.len() as u64);
            s.count("control_vertices", out.control.len() as u64);
            s.count("free_nodes", d.solver.free_nodes().len() as u64);
            s.text("solver_path", &format!("{:?}", d.solver.path()));
        }
    }
    s.num("max_equilibrium_residual", max_res);
    s.timing("s_per_frame", stats::mean(&main_times));
    s.timing("s_per_frame_max", stats::max(&main_times));
    s.timing("s_per_frame_barnet", stats::mean(&main_barnet_times));
    let tp = if cfg!(debug_assertions) { "dev (debug assertions, opt-level 1)" } else { "release" };
    s.text("timing_profile", tp);
    s.count("frames", angles.len() as u64);
    peak_bulges.sort_by(|a, b| a.0.total_cmp(&b.0));
    let monotone = peak_bulges.windows(2).all(|w| w[0].1 > w[1].1);
    s.count("lower_q_bigger_bulge", monotone as u64);
    s.check("max_equilibrium_residual", Target::AtMost(1e-12), "spec §7.3 e: every frame in equilibrium");
    s.check("lower_q_bigger_bulge", Target::Equals(1.0), "paper Fig. 3 d: lower q, bigger bulge");
    rec.note(&format!(
        "### barnet/arm-muscle\n\n| item | paper | ours |\n|---|---|---|\n| fine faces | 2816 | {} |\n| fine vertices | 2891 | {} (open tube, spec §12.7) |\n| free nodes | 12 | {} |\n| lower q ⇒ bigger bulge | yes (Fig. 3d) | {} |\n| time per frame | not reported | {:.3e} s ({}) |\n| max equilibrium residual | — | {:.2e} |",
        s.get_f64("fine_faces"),
        s.get_f64("fine_vertices"),
        s.get_f64("free_nodes"),
        if monotone { "yes" } else { "no" },
        s.get_f64("s_per_frame"),
        profile(),
        max_res
    ))?;
    Ok(s)
}

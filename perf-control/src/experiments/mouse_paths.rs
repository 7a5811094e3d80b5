//! PC-3 (spec §6): random performed mouse paths (30 s, 0.8–1.8 m/s) and one too-fast stroke
//! (6 m/s) drive the walk database through the Frenet-frame path control (spec §3.12). Figures:
//! pelvis-to-path RMS and max, heading RMS, D per frame; for the stroke the achieved, requested
//! and intrinsic speeds against the database's fastest step.
//!
//! Outputs: table `metrics` (one row per path), plot `topview` (first path).
//!
//! ```no_run
//! use geom_core::experiment::Size;
//! use geom_core::record::NullRecorder;
//! use perf_control::experiments::mouse_paths::{run, Params};
//! let text = std::fs::read_to_string("scenes/perf-control/mouse-paths.ron").unwrap();
//! #[derive(serde::Deserialize)]
//! struct Scene { params: Params }
//! let s: Scene = ron::from_str(&text).unwrap();
//! let r = run(&s.params, Size::Quick, &mut NullRecorder::default()).unwrap();
//! println!("worst path RMS {} m", r.get_f64("path_rms_m_worst"));
//! ```

use geom_core::experiment::{BySize, Report, Size, Target};
use geom_core::record::Recorder;
use geom_core::stats::{max, mean};
use serde::Deserialize;

use crate::data::walk::HIP_WIDTH;
use crate::data::{mouse_path, straight_stroke};
use crate::dp::DpParams;
use crate::error::Result;
use crate::eval::{fastest_step_speed, intrinsic_speed, path_following};
use crate::experiments::common::topview;
use crate::output::target_motion;
use crate::pipeline::drive;
use crate::presets::{walk_database, WalkDbParams};
use crate::{hips_control, path_control, tracking_error};

/// Parameters of PC-3 (the RON `params` block of `perf-control/mouse-paths`).
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Params {
    /// The walk database.
    pub database: WalkDbParams,
    /// DP parameters.
    pub dp: DpParams,
    /// Seeds of the paths.
    pub seeds: Vec<u64>,
    /// Paths used (a prefix of `seeds`).
    pub count: BySize<usize>,
    /// Path length (s).
    pub secs: f64,
    /// Speed range of the paths (m/s).
    pub speed: (f64, f64),
    /// Tangent smoothing window of the path control (samples).
    pub smooth: usize,
    /// Speed of the too-fast stroke (m/s).
    pub fast_speed: f64,
    /// Length of the stroke (s).
    pub fast_secs: f64,
}

/// Runs PC-3: see the module documentation.
pub fn run(p: &Params, size: Size, rec: &mut dyn Recorder) -> Result<Report> {
    let w = walk_database(&p.database, p.dp.stretch_limit_s, size)?;
    let u = p.database.factor;
    let native = p.database.native_hz;
    let fastest = fastest_step_speed(&w.fine, native);
    let n = p.count.get(size).min(p.seeds.len());
    rec.table(
        "metrics",
        &[
            "path",
            "path_rms_m",
            "path_max_m",
            "mid_rms_m",
            "heading_rms_deg",
            "requested_speed",
            "achieved_speed",
            "intrinsic_speed",
            "D_per_frame",
            "dp_s",
        ],
    )?;
    let mut feasible = Vec::new();
    let mut fast_row = [f64::NAN; 5];
    let cases: Vec<(String, Vec<[f64; 2]>)> = p.seeds[..n]
        .iter()
        .map(|&s| (format!("seed{s}"), mouse_path(s, p.secs, native, p.speed)))
        .chain(std::iter::once(("fast".to_string(), straight_stroke(p.fast_secs, native, p.fast_speed))))
        .collect();
    for (ci, (name, path)) in cases.iter().enumerate() {
        rec.progress(ci as u64, cases.len() as u64);
        let x_fine = path_control(path, native, HIP_WIDTH, p.smooth);
        let d = drive(&w.db, &w.fine, &x_fine, u, &p.dp)?;
        let achieved = hips_control(&d.motion, HIP_WIDTH);
        let tr = tracking_error(&x_fine, &achieved);
        let pf = path_following(&d.motion, path, native);
        let dpf = d.fine.d_total / x_fine.len() as f64;
        let raw = target_motion(&w.fine, &d.fine, false)?;
        let intrinsic = intrinsic_speed(&raw, &d.fine, native);
        rec.row(
            "metrics",
            &[
                name.as_str().into(),
                pf.rms_m.into(),
                pf.max_m.into(),
                tr.rms_m.into(),
                tr.heading_rms_deg.into(),
                pf.requested_speed.into(),
                pf.achieved_speed.into(),
                intrinsic.into(),
                dpf.into(),
                d.dp_s.into(),
            ],
        )?;
        if name == "fast" {
            fast_row = [pf.rms_m, pf.achieved_speed, pf.requested_speed, dpf, intrinsic];
        } else {
            feasible.push((pf.rms_m, pf.max_m, tr.heading_rms_deg, dpf));
        }
        if ci == 0 {
            topview(rec, &x_fine, &achieved)?;
        }
    }
    rec.progress(cases.len() as u64, cases.len() as u64);
    let col = |i: usize| -> Vec<f64> { feasible.iter().map(|r| [r.0, r.1, r.2, r.3][i]).collect() };
    let mut r = Report::default();
    r.count("paths", feasible.len() as u64);
    r.count("db_instances", w.db.instances.len() as u64);
    r.num("path_rms_m_mean", mean(&col(0)));
    r.num("path_rms_m_worst", max(&col(0)));
    r.num("path_max_m", max(&col(1)));
    r.num("heading_rms_deg_mean", mean(&col(2)));
    r.num("d_per_frame_mean", mean(&col(3)));
    r.num("fast_path_rms_m", fast_row[0]);
    r.num("fast_achieved_speed_m_s", fast_row[1]);
    r.num("fast_requested_speed_m_s", fast_row[2]);
    r.num("fast_d_per_frame", fast_row[3]);
    r.num("fast_intrinsic_speed_m_s", fast_row[4]);
    r.num("db_fastest_step_speed_m_s", fastest);
    r.check("path_rms_m_worst", Target::AtMost(0.15), "PC-3 (spec §6): path RMS of feasible paths");
    r.check("fast_achieved_speed_m_s", Target::Above(0.0), "PC-3 (spec §6): the too-fast stroke finishes");
    Ok(r)
}

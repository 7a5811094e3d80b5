//! PC-6 (spec §6): real capture. CMU 01_03 and the first half of 01_01 (resampled to 30 Hz,
//! contacts detected, a segment boundary at every detected foot plant) form the database; the
//! hips control of the second half of 01_01 drives it. Tracking only (the clips are mostly jumps
//! and climbing): the point is that a second skeleton and a detected segmentation run end to end.
//!
//! Outputs: table `segments`, plot `topview`, file `target.bvh`.
//!
//! ```no_run
//! use geom_core::experiment::Size;
//! use geom_core::record::NullRecorder;
//! use perf_control::experiments::real_data::{run, Params};
//! let text = std::fs::read_to_string("scenes/perf-control/real-data.ron").unwrap();
//! #[derive(serde::Deserialize)]
//! struct Scene { params: Params }
//! let mut s: Scene = ron::from_str(&text).unwrap();
//! s.params.resolve_paths(std::path::Path::new("."));
//! let r = run(&s.params, Size::Quick, &mut NullRecorder::default()).unwrap();
//! println!("midpoint RMS {} m", r.get_f64("mid_rms_m"));
//! ```

use std::path::Path;

use geom_core::anim::bvh;
use geom_core::anim::{ContactParams, Motion};
use geom_core::experiment::{Report, Size};
use geom_core::record::Recorder;
use serde::Deserialize;

use crate::data::take_from_walk;
use crate::data::walk::HIP_WIDTH;
use crate::dp::DpParams;
use crate::error::{PcError, Result};
use crate::experiments::common::{record_segments, topview};
use crate::pipeline::drive;
use crate::presets::PreparedDb;
use crate::{hips_control, tracking_error};

/// Parameters of PC-6 (the RON `params` block of `perf-control/real-data`).
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Params {
    /// BVH of the training clip (a relative path is resolved by [`Params::resolve_paths`]).
    pub train: String,
    /// BVH of the clip cut in half: first half trains, second half is the input.
    pub split: String,
    /// Rate everything is resampled to (Hz).
    pub rate_hz: f64,
    /// Downsampling factor of the DP.
    pub factor: usize,
    /// DP parameters.
    pub dp: DpParams,
}

impl Params {
    /// Resolves relative BVH paths against `root` (the scene file's folder: the built-in scene
    /// names `../../assets/mocap/…`).
    pub fn resolve_paths(&mut self, root: &Path) {
        for p in [&mut self.train, &mut self.split] {
            if Path::new(p.as_str()).is_relative() {
                *p = root.join(p.as_str()).to_string_lossy().into_owned();
            }
        }
    }
}

/// Reads a BVH clip, resamples it to `rate_hz` and detects its foot contacts.
pub fn load_clip(path: &str, rate_hz: f64) -> Result<Motion> {
    let at = |e: geom_core::Error| PcError::BadParameter { name: "bvh", msg: format!("{path}: {e}") };
    let m = bvh::read_file(path, &bvh::BvhOptions::default()).map_err(at)?;
    let mut m = m.resample(1.0 / rate_hz).map_err(at)?;
    m.detect_contacts(&ContactParams::default());
    Ok(m)
}

/// Runs PC-6: see the module documentation.
pub fn run(p: &Params, _size: Size, rec: &mut dyn Recorder) -> Result<Report> {
    if p.factor == 0 || !p.rate_hz.is_finite() || p.rate_hz <= 0.0 {
        return Err(PcError::BadParameter { name: "factor, rate_hz", msg: "must be positive".into() });
    }
    let a = load_clip(&p.train, p.rate_hz)?;
    let b = load_clip(&p.split, p.rate_hz)?;
    let half = b.len() / 2;
    let (b1, b2) = (b.slice(0, half), b.slice(half, b.len()));
    let takes = vec![take_from_walk(a), take_from_walk(b1)];
    let segs: usize = takes.iter().map(|t| t.boundaries.len() - 1).sum();
    let w = PreparedDb::unclustered(takes, p.rate_hz / p.factor as f64, p.rate_hz)?;
    let x_fine = hips_control(&b2, HIP_WIDTH);
    let d = drive(&w.db, &w.fine, &x_fine, p.factor, &p.dp)?;
    let achieved = hips_control(&d.motion, HIP_WIDTH);
    let tr = tracking_error(&x_fine, &achieved);
    topview(rec, &x_fine, &achieved)?;
    record_segments(rec, &w.db, &d.coarse, &d.fine)?;
    if rec.keeps_outputs() {
        rec.file("target.bvh", bvh::write(&d.motion, &Default::default()).as_bytes())?;
    }
    let mut r = Report::default();
    r.count("segments_detected", segs as u64);
    r.count("db_instances", w.before as u64);
    r.count("input_frames", x_fine.len() as u64);
    r.count("chosen_segments", d.fine.segments.len() as u64);
    r.num("mid_rms_m", tr.rms_m);
    r.num("mid_max_m", tr.max_m);
    r.num("heading_rms_deg", tr.heading_rms_deg);
    r.num("d_per_frame", d.fine.d_total / x_fine.len() as f64);
    r.timing("dp_s", d.dp_s);
    r.timing("refine_s", d.refine_s);
    Ok(r)
}

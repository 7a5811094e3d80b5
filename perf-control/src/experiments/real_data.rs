//! PC-6 (spec §6): real capture. Two scenes share this experiment:
//! - `perf-control/real-data` (the spec's split): CMU 01_03 and the first half of 01_01 form the
//!   database, the hips control of the second half of 01_01 drives it;
//! - `perf-control/real-data-cross-clip` (issue 27): a database built from one clip (01_01)
//!   drives the other clip's motion (01_03), so no input frame has a near copy in the database.
//!
//! Every clip is resampled to 30 Hz, its contacts detected, and its capture set-up frames (the
//! converter's T-pose at frame 0 and any settling) dropped by the rule of
//! [`crate::data::capture`] *before* it is cut into halves; a segment boundary is placed at every
//! detected foot plant ([`take_from_walk`]). Figures: tracking (midpoint RMS and max, heading
//! RMS), the gait figures of PC-1 against the input clip's own detected contacts (stride
//! frequency ratio, phase agreement: same feet on the ground in the same frame), the output's foot
//! skate beside the input's, and per clip the frames the set-up rule dropped. No quality target:
//! the clips are mostly jumps and climbing, with few plants; the point is that a second skeleton
//! (CMU) and a detected segmentation run end to end.
//!
//! Outputs: tables `segments`, `setup` (per clip: frames, frames dropped, pose distance of
//! frame 0 and the clip's median pose distance), plot `topview`, file `target.bvh`.
//!
//! ```no_run
//! use geom_core::experiment::Size;
//! use geom_core::record::NullRecorder;
//! use perf_control::experiments::real_data::{run, Params};
//! let text = std::fs::read_to_string("scenes/perf-control/real-data.ron").unwrap();
//! #[derive(serde::Deserialize)]
//! struct Scene { params: Params }
//! let mut s: Scene = ron::from_str(&text).unwrap();
//! s.params.resolve_paths(std::path::Path::new("scenes/perf-control"));
//! let r = run(&s.params, Size::Quick, &mut NullRecorder::default()).unwrap();
//! println!("midpoint RMS {} m", r.get_f64("mid_rms_m"));
//! ```

use std::collections::BTreeMap;
use std::path::Path;

use geom_core::anim::bvh;
use geom_core::anim::metrics::foot_skate;
use geom_core::anim::{ContactParams, Motion};
use geom_core::experiment::{Report, Size};
use geom_core::record::{Cell, Recorder};
use geom_core::stats::median;
use serde::Deserialize;

use crate::data::capture::{trim_setup, SetupRule};
use crate::data::take_from_walk;
use crate::data::walk::HIP_WIDTH;
use crate::dp::DpParams;
use crate::error::{PcError, Result};
use crate::eval::{phase_agreement, step_frequency};
use crate::experiments::common::{record_segments, topview};
use crate::pipeline::drive;
use crate::presets::PreparedDb;
use crate::{hips_control, tracking_error};

/// Which part of a clip (after its set-up frames are dropped).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize)]
pub enum Part {
    /// The whole clip.
    #[default]
    Whole,
    /// Frames `[0, n/2)`.
    FirstHalf,
    /// Frames `[n/2, n)`.
    SecondHalf,
}

/// A BVH clip, or part of it.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Clip {
    /// BVH file (a relative path is resolved by [`Params::resolve_paths`]).
    pub path: String,
    /// Which part.
    #[serde(default)]
    pub part: Part,
}

/// Parameters of PC-6 (the RON `params` block of `perf-control/real-data` and
/// `perf-control/real-data-cross-clip`).
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Params {
    /// Clips (or halves) forming the database, one take each.
    pub database: Vec<Clip>,
    /// The clip (or half) whose hips control is the input.
    pub input: Clip,
    /// Rate everything is resampled to (Hz).
    pub rate_hz: f64,
    /// Downsampling factor of the DP.
    pub factor: usize,
    /// The capture set-up rule ([`crate::data::capture`]).
    pub setup: SetupRule,
    /// DP parameters.
    pub dp: DpParams,
}

impl Params {
    /// Resolves relative BVH paths against `root` (the scene file's folder: the built-in scenes
    /// name `../../assets/mocap/…`).
    pub fn resolve_paths(&mut self, root: &Path) {
        for c in self.database.iter_mut().chain(std::iter::once(&mut self.input)) {
            if Path::new(c.path.as_str()).is_relative() {
                c.path = root.join(c.path.as_str()).to_string_lossy().into_owned();
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

/// A loaded clip without its set-up frames, and the set-up figures.
struct Loaded {
    motion: Motion,
    frames: usize,
    dropped: usize,
    frame0_dist_m: f64,
    median_dist_m: f64,
}

fn part(m: &Motion, p: Part) -> Motion {
    let half = m.len() / 2;
    match p {
        Part::Whole => m.clone(),
        Part::FirstHalf => m.slice(0, half),
        Part::SecondHalf => m.slice(half, m.len()),
    }
}

/// The file stem of a clip's path (`01_01`), used in figure keys.
fn stem(path: &str) -> String {
    Path::new(path).file_stem().map_or_else(|| path.to_string(), |s| s.to_string_lossy().into_owned())
}

/// Runs PC-6: see the module documentation.
pub fn run(p: &Params, _size: Size, rec: &mut dyn Recorder) -> Result<Report> {
    if p.factor == 0 || !p.rate_hz.is_finite() || p.rate_hz <= 0.0 {
        return Err(PcError::BadParameter { name: "factor, rate_hz", msg: "must be positive".into() });
    }
    if p.database.is_empty() {
        return Err(PcError::EmptyDatabase("the scene lists no database clip".into()));
    }
    // Each file once, trimmed before it is cut (BTreeMap: a fixed order for the table).
    let mut clips: BTreeMap<String, Loaded> = BTreeMap::new();
    for c in p.database.iter().chain(std::iter::once(&p.input)) {
        if clips.contains_key(&c.path) {
            continue;
        }
        let m = load_clip(&c.path, p.rate_hz)?;
        let frames = m.len();
        let (motion, s) = trim_setup(m, &p.setup)
            .map_err(|e| PcError::BadParameter { name: "setup", msg: format!("{}: {e}", c.path) })?;
        let loaded = Loaded {
            motion,
            frames,
            dropped: s.first,
            frame0_dist_m: s.pose_dist_m[0],
            median_dist_m: median(&s.pose_dist_m),
        };
        clips.insert(c.path.clone(), loaded);
    }
    let takes: Vec<_> = p.database.iter().map(|c| take_from_walk(part(&clips[&c.path].motion, c.part))).collect();
    let segs: usize = takes.iter().map(|t| t.boundaries.len() - 1).sum();
    let w = PreparedDb::unclustered(takes, p.rate_hz / p.factor as f64, p.rate_hz)?;
    let truth = part(&clips[&p.input.path].motion, p.input.part);
    let x_fine = hips_control(&truth, HIP_WIDTH);
    let d = drive(&w.db, &w.fine, &x_fine, p.factor, &p.dp)?;
    let achieved = hips_control(&d.motion, HIP_WIDTH);
    let tr = tracking_error(&x_fine, &achieved);
    topview(rec, &x_fine, &achieved)?;
    record_segments(rec, &w.db, &d.coarse, &d.fine)?;
    rec.table("setup", &["clip", "frames", "dropped", "frame0_pose_dist_m", "median_pose_dist_m"])?;
    let mut r = Report::default();
    for (path, c) in &clips {
        let name = stem(path);
        rec.row(
            "setup",
            &[
                Cell::Text(name.clone()),
                c.frames.into(),
                c.dropped.into(),
                c.frame0_dist_m.into(),
                c.median_dist_m.into(),
            ],
        )?;
        r.count(&format!("setup_dropped_frames_{name}"), c.dropped as u64);
        r.num(&format!("setup_frame0_pose_dist_m_{name}"), c.frame0_dist_m);
    }
    if rec.keeps_outputs() {
        rec.file("target.bvh", bvh::write(&d.motion, &Default::default()).as_bytes())?;
    }
    r.count("segments_detected", segs as u64);
    r.count("db_instances", w.before as u64);
    r.count("input_frames", x_fine.len() as u64);
    r.count("chosen_segments", d.fine.segments.len() as u64);
    r.num("mid_rms_m", tr.rms_m);
    r.num("mid_max_m", tr.max_m);
    r.num("heading_rms_deg", tr.heading_rms_deg);
    r.num("d_per_frame", d.fine.d_total / x_fine.len() as f64);
    r.num("stride_ratio", step_frequency(&d.motion) / step_frequency(&truth));
    r.num("phase_agreement", phase_agreement(&d.motion, &truth));
    r.num("skate_cm_s", foot_skate(&d.motion, &d.motion.labels).rate_cm_s);
    r.num("input_skate_cm_s", foot_skate(&truth, &truth.labels).rate_cm_s);
    r.timing("dp_s", d.dp_s);
    r.timing("refine_s", d.refine_s);
    Ok(r)
}

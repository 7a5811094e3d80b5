//! Motion capture end to end: BVH clips through the reader, forward kinematics over the frames,
//! and a write/read round trip compared joint by joint.
//!
//! Outputs: plots `root_top_view` (root trajectory, x against z) and `head_height`. Figures per
//! clip (`<clip>` = the file stem): `<clip>_joints`, `<clip>_frames`, `<clip>_frame_rate_hz`,
//! `<clip>_duration_s`, `<clip>_height_range_m`, `<clip>_roundtrip_max_err_m` (largest joint
//! position difference after the round trip, on up to 200 evenly spaced frames), and the
//! timings `<clip>_parse_s`, `<clip>_fk_us_per_frame`.
//!
//! ```no_run
//! use geom_core::experiment::Size;
//! use geom_core::experiments::mocap::{run, Params};
//! use geom_core::record::NullRecorder;
//! let p = Params { clips: vec!["assets/mocap/01_01.bvh".into()], quick_frames: 300, root: ".".into() };
//! let r = run(&p, Size::Quick, &mut NullRecorder::default()).unwrap();
//! assert!(r.get_f64("01_01_roundtrip_max_err_m") < 1e-6);
//! ```

use std::path::PathBuf;
use std::time::Instant;

use serde::{Deserialize, Serialize};

use crate::anim::{bvh, JointRole};
use crate::error::{Error, Result};
use crate::experiment::{Report, Size, Target};
use crate::math::Pt3;
use crate::record::{Recorder, Series};
use crate::stats::{nan_max, nan_min};

/// The scene's `params` block.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Params {
    /// BVH files, relative to `root`.
    pub clips: Vec<PathBuf>,
    /// Frames run through forward kinematics in the quick and tiny runs (all frames otherwise).
    pub quick_frames: usize,
    /// Folder the clips are read from (not part of the scene file: the caller sets it).
    #[serde(skip)]
    pub root: PathBuf,
}

fn series(plot: &str, label: &str, axes: (&str, &str), points: Vec<(f64, f64)>) -> Series {
    Series { plot: plot.into(), label: label.into(), axes: (axes.0.into(), axes.1.into()), log: (false, false), points }
}

/// Runs every clip; see the module docs.
pub fn run(p: &Params, size: Size, rec: &mut dyn Recorder) -> Result<Report> {
    let mut s = Report::default();
    for (ci, path) in p.clips.iter().enumerate() {
        rec.progress(ci as u64, p.clips.len() as u64);
        let full = p.root.join(path);
        let name = path.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
        let text = std::fs::read_to_string(&full)
            .map_err(|e| Error::Io(std::io::Error::new(e.kind(), format!("{}: {e}", full.display()))))?;
        let t0 = Instant::now();
        let m = bvh::read(&text, &bvh::BvhOptions::default())?;
        let parse_s = t0.elapsed().as_secs_f64();
        let nj = m.skeleton.joints.len();
        let frames = match size {
            Size::Tiny | Size::Quick => m.len().min(p.quick_frames),
            _ => m.len(),
        };
        let mut pos = vec![Pt3::origin(); nj];
        let t1 = Instant::now();
        let (mut min_y, mut max_y) = (f64::INFINITY, f64::NEG_INFINITY);
        let head = m.skeleton.role(JointRole::Head);
        let (mut head_curve, mut root_curve) = (Vec::new(), Vec::new());
        for f in 0..frames {
            m.joint_positions(f, &mut pos);
            for q in &pos {
                min_y = nan_min(min_y, q.y);
                max_y = nan_max(max_y, q.y);
            }
            if let Some(hj) = head {
                head_curve.push((f as f64 * m.frame_time, pos[hj as usize].y));
            }
            root_curve.push((pos[0].x, pos[0].z));
        }
        let fk_s = t1.elapsed().as_secs_f64();
        // Write, read back, compare joint positions.
        let back = bvh::read(&bvh::write(&m, &bvh::BvhWriteOptions::default()), &bvh::BvhOptions::default())?;
        if back.len() != m.len() {
            return Err(Error::DimensionMismatch { what: "BVH round trip frames", expected: m.len(), got: back.len() });
        }
        let mut pos2 = vec![Pt3::origin(); nj];
        let mut rt_err = 0.0f64;
        for f in (0..frames).step_by((frames / 200).max(1)) {
            m.joint_positions(f, &mut pos);
            back.joint_positions(f, &mut pos2);
            for (a, b) in pos.iter().zip(&pos2) {
                rt_err = nan_max(rt_err, (a - b).norm());
            }
        }
        s.count(&format!("{name}_joints"), nj as u64);
        s.count(&format!("{name}_frames"), m.len() as u64);
        s.num(&format!("{name}_frame_rate_hz"), 1.0 / m.frame_time);
        s.num(&format!("{name}_duration_s"), m.duration());
        s.timing(&format!("{name}_parse_s"), parse_s);
        s.timing(&format!("{name}_fk_us_per_frame"), 1e6 * fk_s / frames.max(1) as f64);
        s.num(&format!("{name}_height_range_m"), max_y - min_y);
        s.num(&format!("{name}_roundtrip_max_err_m"), rt_err);
        s.check(&format!("{name}_roundtrip_max_err_m"), Target::AtMost(1e-6), "BVH write/read keeps the motion");
        rec.series(&series("root_top_view", &name, ("x (m)", "z (m)"), root_curve))?;
        rec.series(&series("head_height", &name, ("time (s)", "height (m)"), head_curve))?;
    }
    Ok(s)
}

//! Figures of a path-driven walk (spec §3.14 "Tracking error (walk, mouse)", PC-3): the output
//! pelvis against the requested path point at the same time, the requested and achieved speeds,
//! the speed of the motion itself with the seam jumps excluded, and the database's fastest step.

use geom_core::anim::Motion;
use geom_core::stats::max;

use crate::db::MappingDb;
use crate::dp::Interpretation;

/// Output pelvis floor point against the requested path point at the same frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PathFollowing {
    /// RMS distance (m).
    pub rms_m: f64,
    /// Largest distance (m).
    pub max_m: f64,
    /// Requested mean speed: path length over the common duration (m/s).
    pub requested_speed: f64,
    /// Achieved mean speed of the output root over the same duration (m/s).
    pub achieved_speed: f64,
}

/// Compares the output `m` (root = pelvis) with the path `(x, z)` sampled at `rate_hz`, over
/// their common frames.
pub fn path_following(m: &Motion, path: &[[f64; 2]], rate_hz: f64) -> PathFollowing {
    let nf = path.len().min(m.len());
    let errs: Vec<f64> = (0..nf).map(|f| (m.root_pos[f].x - path[f][0]).hypot(m.root_pos[f].z - path[f][1])).collect();
    let rms_m = (errs.iter().map(|e| e * e).sum::<f64>() / nf as f64).sqrt();
    let len_path: f64 = path.windows(2).map(|q| (q[1][0] - q[0][0]).hypot(q[1][1] - q[0][1])).sum();
    let len_out: f64 = m.root_pos.windows(2).map(|q| (q[1].x - q[0].x).hypot(q[1].z - q[0].z)).sum();
    let dur = (nf.max(2) - 1) as f64 / rate_hz;
    PathFollowing { rms_m, max_m: max(&errs), requested_speed: len_path / dur, achieved_speed: len_out / dur }
}

/// Speed of the motion itself (m/s): the horizontal root path of the raw output (no seam offsets)
/// per second, the frames that start a segment excluded so the alignment jumps between segments
/// do not count as walking.
pub fn intrinsic_speed(raw: &Motion, it: &Interpretation, rate_hz: f64) -> f64 {
    let seam_frames: Vec<usize> = it.segments.iter().filter(|c| c.start > 0).map(|c| c.start as usize).collect();
    let (mut dist, mut steps) = (0.0, 0usize);
    for f in 1..raw.len() {
        if !seam_frames.contains(&f) {
            let q = raw.root_pos[f] - raw.root_pos[f - 1];
            dist += q.x.hypot(q.z);
            steps += 1;
        }
    }
    dist / (steps.max(1) as f64 / rate_hz)
}

/// The database's fastest step: the largest mean horizontal root speed of an instance's source
/// slice (m/s), from the takes' motions at `native_hz`; NaN when a take has no motion.
pub fn fastest_step_speed(db: &MappingDb, native_hz: f64) -> f64 {
    let speeds: Vec<f64> = db
        .instances
        .iter()
        .map(|i| {
            let (t, a, b) = i.source;
            db.takes[t as usize].source.as_ref().map_or(f64::NAN, |m| {
                let d = m.root_pos[b] - m.root_pos[a];
                d.x.hypot(d.z) / ((b - a) as f64 / native_hz)
            })
        })
        .collect();
    max(&speeds)
}

/// Seam frames of an interpretation: the start frames of every segment after the first that
/// lie inside the input.
pub fn seam_frames(it: &Interpretation) -> Vec<usize> {
    it.segments.iter().skip(1).map(|s| s.start).filter(|&s| s > 0).map(|s| s as usize).collect()
}

//! Evaluation metrics (spec §3.14): control tracking, gait frequency and phase, seam jumps;
//! [`path`] the path-following figures of PC-3; [`dance`] the dance semantics of PC-4.

pub mod dance;
pub mod path;

pub use path::{fastest_step_speed, intrinsic_speed, path_following, seam_frames, PathFollowing};

use crate::track::PointTrack;
use geom_core::anim::{FrameLabels, Motion};
use geom_core::math::wrap_angle;
use geom_core::stats::{median, nan_max};
use serde::{Deserialize, Serialize};

/// Tracking error of a 2-point floor control (`[left, right]`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct TrackingStats {
    /// Frames compared.
    pub frames: usize,
    /// RMS distance of the midpoints (m).
    pub rms_m: f64,
    /// Largest midpoint distance (m).
    pub max_m: f64,
    /// RMS difference of the heading of `left − right` (deg).
    pub heading_rms_deg: f64,
}

/// Compares two 2-point controls frame by frame over their common length.
pub fn tracking_error(requested: &PointTrack, achieved: &PointTrack) -> TrackingStats {
    let n = requested.len().min(achieved.len());
    if n == 0 || requested.n_points < 2 || achieved.n_points < 2 {
        return TrackingStats::default();
    }
    let (mut s2, mut mx, mut h2) = (0.0, 0.0f64, 0.0);
    for f in 0..n {
        let (a, b) = (requested.frame(f), achieved.frame(f));
        let ma = (a[0] + a[1]) * 0.5;
        let mb = (b[0] + b[1]) * 0.5;
        let d = ((ma.x - mb.x).powi(2) + (ma.z - mb.z).powi(2)).sqrt();
        s2 += d * d;
        mx = nan_max(mx, d);
        let ea = a[0] - a[1];
        let eb = b[0] - b[1];
        let dh = wrap_angle(ea.x.atan2(ea.z) - eb.x.atan2(eb.z));
        h2 += dh * dh;
    }
    TrackingStats {
        frames: n,
        rms_m: (s2 / n as f64).sqrt(),
        max_m: mx,
        heading_rms_deg: (h2 / n as f64).sqrt().to_degrees(),
    }
}

/// Per-frame stance state: bit 0 left foot, bit 1 right foot on the ground (ankle or toe
/// contact).
pub fn stance_states(labels: &FrameLabels) -> Vec<u8> {
    labels
        .contacts
        .iter()
        .map(|&c| {
            let l = c & (FrameLabels::L_ANKLE | FrameLabels::L_TOE) != 0;
            let r = c & (FrameLabels::R_ANKLE | FrameLabels::R_TOE) != 0;
            l as u8 | (r as u8) << 1
        })
        .collect()
}

/// Foot plants: frames where a foot's contact starts, with the foot (0 left, 1 right).
pub fn plants(labels: &FrameLabels) -> Vec<(usize, u8)> {
    let st = stance_states(labels);
    let mut out = Vec::new();
    for f in 1..st.len() {
        for foot in 0..2u8 {
            let bit = 1 << foot;
            if st[f] & bit != 0 && st[f - 1] & bit == 0 {
                out.push((f, foot));
            }
        }
    }
    out
}

/// Step frequency of a clip (plants per second).
pub fn step_frequency(m: &Motion) -> f64 {
    let d = m.duration();
    if d <= 0.0 {
        return 0.0;
    }
    plants(&m.labels).len() as f64 / d
}

/// Phase agreement (spec §3.14): fraction of the common frames whose stance state (which feet
/// are on the ground) is the same in both clips.
pub fn phase_agreement(a: &Motion, b: &Motion) -> f64 {
    let (sa, sb) = (stance_states(&a.labels), stance_states(&b.labels));
    let n = sa.len().min(sb.len());
    if n == 0 {
        return 0.0;
    }
    sa.iter().zip(&sb).take(n).filter(|(x, y)| x == y).count() as f64 / n as f64
}

/// Largest point jump `max_p ‖x_{f} − x_{f−1}‖` (m) at each of the given frames, and the median
/// frame-to-frame jump elsewhere (a seam-quality indicator for point output; NaN when there is no
/// other frame). A NaN coordinate makes the jumps NaN.
pub fn seam_jumps(t: &PointTrack, seams: &[usize]) -> (Vec<f64>, f64) {
    let jump = |f: usize| -> f64 {
        let (a, b) = (t.frame(f - 1), t.frame(f));
        a.iter().zip(b).map(|(p, q)| (p - q).norm()).fold(0.0, nan_max)
    };
    let js: Vec<f64> = seams.iter().filter(|&&f| f >= 1 && f < t.len()).map(|&f| jump(f)).collect();
    let others: Vec<f64> = (1..t.len()).filter(|f| !seams.contains(f)).map(jump).collect();
    (js, median(&others))
}

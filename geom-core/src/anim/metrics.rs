//! Motion quality metrics (motion-graph.md §3.12): foot skate over contact frames, splice
//! discontinuities (velocity and acceleration jumps of world joint positions) and their
//! within-clip reference distribution, and a stick-figure mesh for viewing a frame.
//!
//! Definitions (Δt = frame time, `x_j(f)` world position of joint `j` at frame `f`):
//! - velocity jump at frame `b`: `J_v = max_j ‖x_j(b+1) − 2x_j(b) + x_j(b−1)‖ / Δt` (m/s);
//! - acceleration jump: `J_a = max_j ‖x_j(b+2) − 3x_j(b+1) + 3x_j(b) − x_j(b−1)‖ / Δt²` (m/s²);
//! - foot skate: over every frame where a foot point carries a contact flag in that frame and the
//!   previous one, the horizontal displacement of the point.

use super::motion::{FrameLabels, Motion};
use super::skeleton::JointRole;
use crate::error::Result;
use crate::math::{Pt3, Vec3};
use crate::mesh::TriMesh;

/// Foot-skate statistics (both feet, ankle and toe points summed).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SkateStats {
    /// Total horizontal sliding of contact points per second of motion (cm/s); 0 for clips of
    /// one frame.
    pub rate_cm_s: f64,
    /// Mean sliding per contact point-frame (mm).
    pub mean_mm: f64,
    /// Largest sliding speed of a contact point (cm/s).
    pub max_speed_cm_s: f64,
    /// Number of (point, frame) pairs in contact on two consecutive frames.
    pub contact_frames: usize,
    /// Total sliding (m).
    pub slide_m: f64,
}

/// Foot skate of `m` with contact flags `contacts` (usually `m.labels`, or the flags carried from
/// the source frames of an assembled motion). Frames beyond `contacts.contacts` count as no
/// contact. Feet without the ankle/toe roles are skipped.
pub fn foot_skate(m: &Motion, contacts: &FrameLabels) -> SkateStats {
    let s = &m.skeleton;
    let pts = [
        (FrameLabels::L_ANKLE, s.role(JointRole::LeftAnkle)),
        (FrameLabels::L_TOE, s.role(JointRole::LeftToe)),
        (FrameLabels::R_ANKLE, s.role(JointRole::RightAnkle)),
        (FrameLabels::R_TOE, s.role(JointRole::RightToe)),
    ];
    let flag = |f: usize| contacts.contacts.get(f).copied().unwrap_or(0);
    let nj = m.n_joints();
    let mut prev = vec![Pt3::origin(); nj];
    let mut cur = vec![Pt3::origin(); nj];
    let mut st = SkateStats::default();
    for f in 0..m.len() {
        m.joint_positions(f, &mut cur);
        if f > 0 {
            for (bit, j) in pts {
                let Some(j) = j else { continue };
                if flag(f) & bit != 0 && flag(f - 1) & bit != 0 {
                    let d = cur[j as usize] - prev[j as usize];
                    let h = d.x.hypot(d.z);
                    st.slide_m += h;
                    st.contact_frames += 1;
                    st.max_speed_cm_s = st.max_speed_cm_s.max(100.0 * h / m.frame_time);
                }
            }
        }
        std::mem::swap(&mut prev, &mut cur);
    }
    if st.contact_frames > 0 {
        st.mean_mm = 1000.0 * st.slide_m / st.contact_frames as f64;
    }
    let dur = m.duration();
    if dur > 0.0 {
        st.rate_cm_s = 100.0 * st.slide_m / dur;
    }
    st
}

/// Velocity and acceleration jump at one frame.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct JumpStats {
    /// The frame `b` (first frame of the new piece at a splice).
    pub frame: usize,
    /// `J_v` (m/s); 0 when `b − 1` or `b + 1` is outside the clip.
    pub jv: f64,
    /// `J_a` (m/s²); 0 when `b − 1` or `b + 2` is outside the clip.
    pub ja: f64,
}

/// World joint positions of every frame.
pub fn world_positions(m: &Motion) -> Vec<Vec<Pt3>> {
    let nj = m.n_joints();
    (0..m.len())
        .map(|f| {
            let mut p = vec![Pt3::origin(); nj];
            m.joint_positions(f, &mut p);
            p
        })
        .collect()
}

fn jumps_at(x: &[Vec<Pt3>], b: usize, dt: f64) -> JumpStats {
    let n = x.len();
    let mut js = JumpStats { frame: b, jv: 0.0, ja: 0.0 };
    if b >= 1 && b + 1 < n {
        for ((p1, p0), pm) in x[b + 1].iter().zip(&x[b]).zip(&x[b - 1]) {
            let v = p1.coords - 2.0 * p0.coords + pm.coords;
            js.jv = js.jv.max(v.norm() / dt);
        }
    }
    if b >= 1 && b + 2 < n {
        for (((p2, p1), p0), pm) in x[b + 2].iter().zip(&x[b + 1]).zip(&x[b]).zip(&x[b - 1]) {
            let a = p2.coords - 3.0 * p1.coords + 3.0 * p0.coords - pm.coords;
            js.ja = js.ja.max(a.norm() / (dt * dt));
        }
    }
    js
}

/// `J_v`, `J_a` at each of `frames` (motion-graph.md §3.12).
pub fn splice_discontinuity(m: &Motion, frames: &[usize]) -> Vec<JumpStats> {
    let x = world_positions(m);
    frames.iter().map(|&b| jumps_at(&x, b, m.frame_time)).collect()
}

/// The 50th, 95th and 99th percentiles of a sample.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Percentiles {
    /// Median.
    pub p50: f64,
    /// 95th percentile.
    pub p95: f64,
    /// 99th percentile.
    pub p99: f64,
}

/// Percentile `q ∈ [0, 100]` of `xs` by linear interpolation between order statistics: the one
/// copy in [`crate::stats::percentile`]. NaN for an empty sample or one holding a NaN, so a
/// figure computed from a failed (or missing) run never reads as 0 (issue 21; this function used
/// to drop NaNs and return 0 for an empty sample).
pub fn percentile(xs: &[f64], q: f64) -> f64 {
    crate::stats::percentile(xs, q)
}

impl Percentiles {
    /// Percentiles of a sample.
    pub fn of(xs: &[f64]) -> Percentiles {
        Percentiles { p50: percentile(xs, 50.0), p95: percentile(xs, 95.0), p99: percentile(xs, 99.0) }
    }
}

/// The within-clip reference distribution of splice statistics.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct JumpDistribution {
    /// Percentiles of `J_v` over every interior frame (m/s).
    pub jv: Percentiles,
    /// Percentiles of `J_a` over every frame with `b − 1 ≥ 0`, `b + 2 < len` (m/s²).
    pub ja: Percentiles,
    /// Number of frames measured.
    pub samples: usize,
}

/// `J_v` and `J_a` at every frame of every clip (the natural frame-to-frame changes a splice is
/// compared with, motion-graph.md §3.12).
pub fn within_clip_jump_distribution(clips: &[Motion]) -> JumpDistribution {
    let mut jv = Vec::new();
    let mut ja = Vec::new();
    for m in clips {
        let x = world_positions(m);
        for b in 1..m.len().saturating_sub(2) {
            let s = jumps_at(&x, b, m.frame_time);
            jv.push(s.jv);
            ja.push(s.ja);
        }
    }
    JumpDistribution { jv: Percentiles::of(&jv), ja: Percentiles::of(&ja), samples: jv.len() }
}

/// A stick figure of frame `frame`: one square-section box of half-width `radius` (m) per bone
/// (joint to parent; bones shorter than 1e-6 m are skipped), as one closed triangle mesh
/// (12 triangles per bone, outward orientation). Errors if `frame` is out of range or a position
/// is not finite.
pub fn stick_figure(m: &Motion, frame: usize, radius: f64) -> Result<TriMesh> {
    if frame >= m.len() {
        return Err(crate::error::Error::InvalidParameter(format!(
            "stick_figure: frame {frame} of a {}-frame motion",
            m.len()
        )));
    }
    let r = if radius.is_finite() && radius > 0.0 { radius } else { 0.02 };
    let mut p = vec![Pt3::origin(); m.n_joints()];
    m.joint_positions(frame, &mut p);
    let mut pos = Vec::new();
    let mut faces = Vec::new();
    const CUBE: [[u32; 3]; 12] = [
        [0, 4, 6],
        [0, 6, 2],
        [1, 3, 7],
        [1, 7, 5],
        [0, 1, 5],
        [0, 5, 4],
        [2, 6, 7],
        [2, 7, 3],
        [0, 2, 3],
        [0, 3, 1],
        [4, 5, 7],
        [4, 7, 6],
    ];
    for (j, joint) in m.skeleton.joints.iter().enumerate() {
        let Some(par) = joint.parent else { continue };
        let (a, b) = (p[par as usize], p[j]);
        let axis = b - a;
        let len = axis.norm();
        if len.is_nan() || len <= 1e-6 {
            continue;
        }
        let ax = axis / len;
        let helper = if ax.x.abs() < 0.9 { Vec3::x() } else { Vec3::y() };
        let u = ax.cross(&helper).normalize();
        let v = ax.cross(&u);
        let base = pos.len() as u32;
        for i in 0..8u32 {
            let (x, y, z) = (i & 1, (i >> 1) & 1, (i >> 2) & 1);
            let end = if x == 1 { b } else { a };
            let sy = if y == 1 { r } else { -r };
            let sz = if z == 1 { r } else { -r };
            pos.push(end + u * sy + v * sz);
        }
        faces.extend(CUBE.iter().map(|t| [t[0] + base, t[1] + base, t[2] + base]));
    }
    TriMesh::new(pos, faces)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Issue 21: an empty sample or a NaN in it gives NaN, never 0 (a failed run must not read as
    /// a perfect one); ordinary samples interpolate as before.
    #[test]
    fn percentile_of_empty_or_nan_samples_is_nan() {
        assert!(percentile(&[], 90.0).is_nan());
        assert!(percentile(&[0.1, f64::NAN, 0.3], 50.0).is_nan());
        assert_eq!(percentile(&[0.0, 10.0], 90.0), 9.0);
        let p = Percentiles::of(&[]);
        assert!(p.p50.is_nan() && p.p95.is_nan() && p.p99.is_nan());
    }
}

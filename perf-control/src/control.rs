//! Control signals (spec §3.12): the hips projected to the floor with normalized width, a Frenet
//! frame along a 2-D path (mouse), and end-effector point sets. Both floor controls produce the
//! same 2-point format `[left, right]`, so a path can drive the walk database.

use crate::track::PointTrack;
use geom_core::anim::{JointRole, Motion};
use geom_core::math::{Pt3, Vec3};

/// Speed (m/s) below which the path tangent is frozen (spec §3.12).
pub const STOP_SPEED: f64 = 0.05;

fn role_positions(m: &Motion, roles: &[JointRole]) -> PointTrack {
    let idx: Vec<usize> = roles.iter().map(|r| m.skeleton.role(*r).map_or(0, |j| j as usize)).collect();
    let mut buf = vec![Pt3::origin(); m.n_joints()];
    let mut data = Vec::with_capacity(m.len() * roles.len());
    for f in 0..m.len() {
        m.joint_positions(f, &mut buf);
        data.extend(idx.iter().map(|&j| buf[j].coords));
    }
    PointTrack::new(1.0 / m.frame_time, roles.len(), data)
}

/// Hips control: left and right hip joints projected onto the floor (y = 0), replaced by
/// `m ± (h/2)e` with midpoint `m` and unit direction `e = (L − R)/|L − R|` (the previous frame's
/// `e`, or +X, when the hips coincide in plan view). Points `[left, right]`. A skeleton without
/// hip roles uses the root joint for both (then `e` = +X).
pub fn hips_control(m: &Motion, hip_width: f64) -> PointTrack {
    let hips = role_positions(m, &[JointRole::LeftHip, JointRole::RightHip]);
    let mut e_prev = Vec3::x();
    let mut data = Vec::with_capacity(hips.data.len());
    for f in 0..hips.len() {
        let (l, r) = (hips.data[2 * f], hips.data[2 * f + 1]);
        let mid = Vec3::new(0.5 * (l.x + r.x), 0.0, 0.5 * (l.z + r.z));
        let d = Vec3::new(l.x - r.x, 0.0, l.z - r.z);
        let n = d.norm();
        let e = if n > 1e-9 { d / n } else { e_prev };
        e_prev = e;
        data.push(mid + e * (0.5 * hip_width));
        data.push(mid - e * (0.5 * hip_width));
    }
    PointTrack::new(hips.rate_hz, 2, data)
}

/// Path control: samples `p_k` (x, z) at `rate_hz`; tangent = central difference (one-sided at
/// the ends) averaged over a centred window of `smooth` samples; below [`STOP_SPEED`] the
/// previous tangent is kept (the first valid one before it, +Z if the path never moves); normal
/// `n = up × t̂`; points `p ± (h/2) n` (left first).
pub fn path_control(path_xz: &[[f64; 2]], rate_hz: f64, hip_width: f64, smooth: usize) -> PointTrack {
    let n = path_xz.len();
    let p = |k: usize| Vec3::new(path_xz[k][0], 0.0, path_xz[k][1]);
    let raw: Vec<Vec3> = (0..n)
        .map(|k| {
            if n < 2 {
                Vec3::zeros()
            } else if k == 0 {
                (p(1) - p(0)) * rate_hz
            } else if k == n - 1 {
                (p(n - 1) - p(n - 2)) * rate_hz
            } else {
                (p(k + 1) - p(k - 1)) * (0.5 * rate_hz)
            }
        })
        .collect();
    let w = smooth.max(1);
    let lo = (w - 1) / 2;
    let hi = w / 2;
    let vel: Vec<Vec3> = (0..n)
        .map(|k| {
            let a = k.saturating_sub(lo);
            let b = (k + hi).min(n.saturating_sub(1));
            raw[a..=b].iter().sum::<Vec3>() / (b - a + 1) as f64
        })
        .collect();
    let first = vel.iter().find(|v| v.norm() >= STOP_SPEED).map_or(Vec3::z(), |v| v.normalize());
    let mut t_prev = first;
    let mut data = Vec::with_capacity(2 * n);
    for (k, v) in vel.iter().enumerate() {
        let s = v.norm();
        let t = if s >= STOP_SPEED { v / s } else { t_prev };
        t_prev = t;
        let nrm = Vec3::new(t.z, 0.0, -t.x); // up × t
        data.push(p(k) + nrm * (0.5 * hip_width));
        data.push(p(k) - nrm * (0.5 * hip_width));
    }
    PointTrack::new(rate_hz, 2, data)
}

/// End effectors `[LeftHand, RightHand, LeftAnkle, RightAnkle]` in world coordinates (spec §3.1).
pub fn end_effectors(m: &Motion) -> PointTrack {
    role_positions(m, &[JointRole::LeftHand, JointRole::RightHand, JointRole::LeftAnkle, JointRole::RightAnkle])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    #[allow(clippy::needless_range_loop)] // k indexes the path and the control alike
    fn path_control_straight_line_and_stop() {
        // Straight line along direction (3, 4)/5 at 1.5 m/s, 30 Hz, then a stop.
        let dir = [0.6, 0.8];
        let mut path: Vec<[f64; 2]> =
            (0..60).map(|k| [1.0 + dir[0] * 0.05 * k as f64, -2.0 + dir[1] * 0.05 * k as f64]).collect();
        let last = path[59];
        path.extend(std::iter::repeat_n(last, 30));
        let h = 0.2;
        let c = path_control(&path, 30.0, h, 5);
        let nrm = Vec3::new(dir[1], 0.0, -dir[0]);
        for k in 0..55 {
            let p = Vec3::new(path[k][0], 0.0, path[k][1]);
            assert!((c.frame(k)[0] - (p + nrm * 0.1)).norm() <= 1e-12, "frame {k}");
            assert!((c.frame(k)[1] - (p - nrm * 0.1)).norm() <= 1e-12);
        }
        // The stop keeps the last tangent: still ±h/2 along the same normal, no NaN.
        for k in 60..90 {
            let sep = c.frame(k)[0] - c.frame(k)[1];
            assert!(sep.iter().all(|v| v.is_finite()));
            assert!((sep - nrm * h).norm() <= 1e-12);
        }
    }
}

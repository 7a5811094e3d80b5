//! Rotations: quaternion log/exp maps, shortest-arc slerp, hemisphere fixing, and the six
//! Tait–Bryan Euler orders with the BVH meaning (motion-graph.md §2.2).
//!
//! Conventions:
//! - [`quat_log`] returns the **rotation vector** `θ·n̂` (axis times angle, radians, `θ ∈ [0, π]`,
//!   shortest arc), and [`quat_exp`] is its inverse; `exp(log(q)) = ±q`. (This is twice the
//!   "pure quaternion" logarithm; the factor is chosen so that the vector is an angle in radians.)
//! - Euler angles: for the order `a1 a2 a3` the rotation is `R = R_a1(θ1)·R_a2(θ2)·R_a3(θ3)`
//!   (intrinsic rotations applied to column vectors), exactly how BVH `CHANNELS … Zrotation
//!   Yrotation Xrotation` reads: `Rz·Ry·Rx`.

use super::{Mat3, UnitQuat, Vec3};
use nalgebra as na;
use serde::{Deserialize, Serialize};

/// Rotation vector (axis · angle, radians) of `q` along the shortest arc: the angle is in `[0, π]`
/// (the sign of `q` is chosen with `w ≥ 0`). Accurate for tiny angles (uses `atan2`).
pub fn quat_log(q: &UnitQuat) -> Vec3 {
    let (w, v) = if q.w < 0.0 { (-q.w, -q.imag()) } else { (q.w, q.imag()) };
    let s = v.norm();
    if s == 0.0 {
        return Vec3::zeros();
    }
    // half angle = atan2(s, w); the rotation angle is twice that.
    v * (2.0 * s.atan2(w) / s)
}

/// Unit quaternion rotating by `|v|` radians about `v / |v|` (inverse of [`quat_log`]).
pub fn quat_exp(v: &Vec3) -> UnitQuat {
    let theta = v.norm();
    let half = 0.5 * theta;
    // sin(θ/2)/θ, with its series for tiny θ (relative error < 1e-20 below 1e-5).
    let k = if theta < 1e-5 { 0.5 - theta * theta / 48.0 } else { half.sin() / theta };
    UnitQuat::new_normalize(na::Quaternion::new(half.cos(), v.x * k, v.y * k, v.z * k))
}

/// Spherical linear interpolation from `a` (`t = 0`) to `b` (`t = 1`) along the shortest arc
/// (`b` is negated first if `a·b < 0`). Computed as `a·exp(t·log(a⁻¹b))`, so it is accurate for
/// nearly equal inputs and never divides by `sin θ`. `t` outside `[0, 1]` extrapolates.
pub fn slerp(a: &UnitQuat, b: &UnitQuat, t: f64) -> UnitQuat {
    let rel = a.inverse() * b;
    a * quat_exp(&(quat_log(&rel) * t))
}

/// Flips the sign of `q` (same rotation) if needed so that `q·prev ≥ 0` (4-D dot product): keeps
/// a quaternion sequence on one hemisphere, so that averaging, differencing and smoothing in
/// quaternion space behave (motion-graph.md §8, "quaternion sign flips").
pub fn fix_hemisphere(prev: &UnitQuat, q: &mut UnitQuat) {
    if prev.coords.dot(&q.coords) < 0.0 {
        *q = UnitQuat::new_unchecked(-q.into_inner());
    }
}

/// The six Tait–Bryan rotation orders. `XYZ` means `R = Rx(θ1)·Ry(θ2)·Rz(θ3)`; the angle array
/// passed to [`euler_to_quat`] lists the angles in the same order as the axes in the name.
#[allow(clippy::upper_case_acronyms)]
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
pub enum RotOrder {
    /// `Rx·Ry·Rz`.
    XYZ,
    /// `Rx·Rz·Ry`.
    XZY,
    /// `Ry·Rx·Rz`.
    YXZ,
    /// `Ry·Rz·Rx`.
    YZX,
    /// `Rz·Rx·Ry`.
    ZXY,
    /// `Rz·Ry·Rx` (the CMU BVH order).
    ZYX,
}

impl RotOrder {
    /// All six orders.
    pub const ALL: [RotOrder; 6] =
        [RotOrder::XYZ, RotOrder::XZY, RotOrder::YXZ, RotOrder::YZX, RotOrder::ZXY, RotOrder::ZYX];

    /// The axes (0 = x, 1 = y, 2 = z) in application order `a1, a2, a3`.
    pub fn axes(self) -> [usize; 3] {
        match self {
            RotOrder::XYZ => [0, 1, 2],
            RotOrder::XZY => [0, 2, 1],
            RotOrder::YXZ => [1, 0, 2],
            RotOrder::YZX => [1, 2, 0],
            RotOrder::ZXY => [2, 0, 1],
            RotOrder::ZYX => [2, 1, 0],
        }
    }

    /// The order with the given axes, or `None` if they are not a permutation of `{0, 1, 2}`.
    pub fn from_axes(axes: [usize; 3]) -> Option<RotOrder> {
        RotOrder::ALL.into_iter().find(|o| o.axes() == axes)
    }

    /// Name as written in this enum (`"ZYX"` …).
    pub fn name(self) -> &'static str {
        match self {
            RotOrder::XYZ => "XYZ",
            RotOrder::XZY => "XZY",
            RotOrder::YXZ => "YXZ",
            RotOrder::YZX => "YZX",
            RotOrder::ZXY => "ZXY",
            RotOrder::ZYX => "ZYX",
        }
    }
}

/// Rotation by `angle` radians about coordinate axis `axis` (0 = x, 1 = y, 2 = z).
pub fn axis_quat(axis: usize, angle: f64) -> UnitQuat {
    let (s, c) = (0.5 * angle).sin_cos();
    let mut v = Vec3::zeros();
    v[axis] = s;
    UnitQuat::new_unchecked(na::Quaternion::new(c, v.x, v.y, v.z))
}

/// Quaternion of `R = R_a1(θ1)·R_a2(θ2)·R_a3(θ3)` for the order's axes `a1 a2 a3`; angles in
/// radians, listed in the order of the axes.
pub fn euler_to_quat(order: RotOrder, rad: [f64; 3]) -> UnitQuat {
    let [a1, a2, a3] = order.axes();
    axis_quat(a1, rad[0]) * axis_quat(a2, rad[1]) * axis_quat(a3, rad[2])
}

/// Angles `[θ1, θ2, θ3]` (radians) with `euler_to_quat(order, θ) = ±q`.
///
/// Ranges: `θ1, θ3 ∈ (−π, π]`, `θ2 ∈ [−π/2, π/2]`. At gimbal lock (`cos θ2` below 1e-12, the
/// middle angle at ±90°) the third angle is set to 0 and the remaining rotation is put into the
/// first (motion-graph.md §2.2). Away from gimbal lock the third angle is computed from the
/// residual rotation `(R_a1(θ1)·R_a2(θ2))ᵀ·R`, so the recomposition stays accurate (≈ 1e-15) even
/// close to the lock, where `θ1` and `θ3` individually are ill-conditioned.
pub fn quat_to_euler(order: RotOrder, q: &UnitQuat) -> [f64; 3] {
    let r: Mat3 = q.to_rotation_matrix().into_inner();
    let [i, j, k] = order.axes();
    // Parity of the permutation (i, j, k): +1 for cyclic orders (XYZ, YZX, ZXY), −1 otherwise.
    let eps = if (j + 3 - i) % 3 == 1 { 1.0 } else { -1.0 };
    // R[i][k] = ε·sin θ2, R[i][i] = cos θ2·cos θ3, R[i][j] = −ε·cos θ2·sin θ3.
    let cos2 = r[(i, i)].hypot(r[(i, j)]);
    let theta2 = (eps * r[(i, k)]).atan2(cos2);
    let r2t = axis_quat(j, theta2).to_rotation_matrix().into_inner().transpose();
    if cos2 < 1e-12 {
        // Gimbal lock: R = R_i(θ1)·R_j(θ2) with θ3 = 0, so R_i(θ1) = R·R_j(θ2)ᵀ.
        let m = r * r2t;
        let theta1 = angle_about(&m, i);
        return [theta1, theta2, 0.0];
    }
    // R[j][k] = −ε·sin θ1·cos θ2, R[k][k] = cos θ1·cos θ2.
    let theta1 = (-eps * r[(j, k)]).atan2(r[(k, k)]);
    let r1t = axis_quat(i, theta1).to_rotation_matrix().into_inner().transpose();
    let n = r2t * r1t * r;
    let theta3 = angle_about(&n, k);
    [theta1, theta2, theta3]
}

/// The angle of a rotation matrix that is (numerically) a rotation about coordinate axis `a`.
fn angle_about(m: &Mat3, a: usize) -> f64 {
    let (a1, a2) = ((a + 1) % 3, (a + 2) % 3);
    // R_a(θ)[a2][a1] = sin θ, R_a(θ)[a1][a1] = cos θ (cyclic a → a1 → a2).
    let s = 0.5 * (m[(a2, a1)] - m[(a1, a2)]);
    let c = 0.5 * (m[(a1, a1)] + m[(a2, a2)]);
    s.atan2(c)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rot_x(a: f64) -> Mat3 {
        let (s, c) = a.sin_cos();
        Mat3::new(1.0, 0.0, 0.0, 0.0, c, -s, 0.0, s, c)
    }
    fn rot_y(a: f64) -> Mat3 {
        let (s, c) = a.sin_cos();
        Mat3::new(c, 0.0, s, 0.0, 1.0, 0.0, -s, 0.0, c)
    }
    fn rot_z(a: f64) -> Mat3 {
        let (s, c) = a.sin_cos();
        Mat3::new(c, -s, 0.0, s, c, 0.0, 0.0, 0.0, 1.0)
    }
    fn rot(axis: usize, a: f64) -> Mat3 {
        [rot_x, rot_y, rot_z][axis](a)
    }

    #[test]
    fn axis_quat_matches_explicit_matrices() {
        for axis in 0..3 {
            for &a in &[0.3, -1.2, 2.9] {
                let m = axis_quat(axis, a).to_rotation_matrix().into_inner();
                assert!((m - rot(axis, a)).norm() < 1e-15);
            }
        }
    }

    #[test]
    fn log_exp_round_trip_and_shortest_arc() {
        let v = Vec3::new(0.3, -0.4, 1.1);
        let q = quat_exp(&v);
        assert!((quat_log(&q) - v).norm() < 1e-14);
        // The negated quaternion is the same rotation: same log.
        let qn = UnitQuat::new_unchecked(-q.into_inner());
        assert!((quat_log(&qn) - v).norm() < 1e-14);
        // Tiny angles keep full relative accuracy.
        let t = Vec3::new(1e-12, -2e-12, 3e-12);
        assert!((quat_log(&quat_exp(&t)) - t).norm() < 1e-26);
        // Angles above π come back as the shorter equivalent rotation.
        let big = Vec3::new(0.0, 0.0, 4.0);
        let l = quat_log(&quat_exp(&big));
        assert!((l - Vec3::new(0.0, 0.0, 4.0 - 2.0 * std::f64::consts::PI)).norm() < 1e-13);
        assert_eq!(quat_log(&UnitQuat::identity()), Vec3::zeros());
    }

    #[test]
    fn slerp_endpoints_midpoint_and_shortest_arc() {
        let a = euler_to_quat(RotOrder::ZYX, [0.1, 0.2, 0.3]);
        let b = euler_to_quat(RotOrder::ZYX, [0.5, -0.4, 1.0]);
        assert!(slerp(&a, &b, 0.0).angle_to(&a) < 1e-14);
        assert!(slerp(&a, &b, 1.0).angle_to(&b) < 1e-14);
        let m = slerp(&a, &b, 0.5);
        assert!((m.angle_to(&a) - m.angle_to(&b)).abs() < 1e-14);
        // Shortest arc: interpolating towards −b gives the same rotations.
        let bn = UnitQuat::new_unchecked(-b.into_inner());
        for &t in &[0.25, 0.5, 0.75] {
            assert!(slerp(&a, &bn, t).angle_to(&slerp(&a, &b, t)) < 1e-14);
        }
        // Constant angular velocity about z: slerp is exact.
        let q0 = axis_quat(2, 0.0);
        let q1 = axis_quat(2, 1.0);
        assert!(slerp(&q0, &q1, 0.3).angle_to(&axis_quat(2, 0.3)) < 1e-15);
    }

    #[test]
    fn fix_hemisphere_flips_only_when_needed() {
        let p = axis_quat(0, 0.2);
        let mut q = UnitQuat::new_unchecked(-axis_quat(0, 0.3).into_inner());
        fix_hemisphere(&p, &mut q);
        assert!(p.coords.dot(&q.coords) > 0.0);
        assert!((q.coords - axis_quat(0, 0.3).coords).norm() < 1e-16);
        let mut r = axis_quat(1, 0.1);
        let before = r;
        fix_hemisphere(&p, &mut r);
        assert_eq!(r, before);
    }

    #[test]
    fn euler_order_axes_are_permutations() {
        for o in RotOrder::ALL {
            assert_eq!(RotOrder::from_axes(o.axes()), Some(o));
        }
        assert_eq!(RotOrder::from_axes([0, 0, 1]), None);
    }

    #[test]
    fn euler_to_quat_is_the_listed_product() {
        for o in RotOrder::ALL {
            let [a1, a2, a3] = o.axes();
            let ang = [0.7, -0.3, 1.9];
            let m = euler_to_quat(o, ang).to_rotation_matrix().into_inner();
            let want = rot(a1, ang[0]) * rot(a2, ang[1]) * rot(a3, ang[2]);
            assert!((m - want).norm() < 1e-14, "{o:?}");
        }
    }

    #[test]
    fn gimbal_lock_puts_everything_in_the_first_angle() {
        for o in RotOrder::ALL {
            for &mid in &[std::f64::consts::FRAC_PI_2, -std::f64::consts::FRAC_PI_2] {
                let q = euler_to_quat(o, [0.4, mid, -0.9]);
                let e = quat_to_euler(o, &q);
                assert_eq!(e[2], 0.0, "{o:?}");
                assert!(euler_to_quat(o, e).angle_to(&q) < 1e-10, "{o:?}");
            }
        }
    }
}

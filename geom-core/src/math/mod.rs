//! Small-vector math: nalgebra aliases, the [`AsPt3`] point abstraction, rotations and Euler
//! orders, planar (ground) transforms, small symmetric eigenproblems, 1-D curves and cubic roots.

use nalgebra as na;

pub mod curve;
pub mod eig;
pub mod planar;
pub mod poly;
pub mod rot;

pub use curve::{catmull_rom, Curve1D, Lerp};
pub use eig::{sym_eig2, sym_eig3};
pub use planar::{heading, wrap_angle, Planar};
pub use rot::{axis_quat, euler_to_quat, fix_hemisphere, quat_exp, quat_log, quat_to_euler, slerp, RotOrder};

/// 2-vector (f64).
pub type Vec2 = na::Vector2<f64>;
/// 3-vector (f64): displacements, velocities, forces, normals.
pub type Vec3 = na::Vector3<f64>;
/// 2-D point (f64), e.g. a UV coordinate in metres of material space.
pub type Pt2 = na::Point2<f64>;
/// 3-D point (f64): positions.
pub type Pt3 = na::Point3<f64>;
/// 2×2 matrix (f64).
pub type Mat2 = na::Matrix2<f64>;
/// 3×3 matrix (f64).
pub type Mat3 = na::Matrix3<f64>;
/// 3×4 matrix (f64), e.g. a camera projection `P = K [R | t]`.
pub type Mat34 = na::Matrix3x4<f64>;
/// Unit quaternion (f64) for rotations.
pub type UnitQuat = na::UnitQuaternion<f64>;
/// Rigid transform (rotation + translation, f64).
pub type Iso3 = na::Isometry3<f64>;

/// Anything that can be read as a 3-D point: lets geometry functions run on `Pt3`, `Vec3`,
/// `[f64; 3]` and `[f32; 3]` data without copying.
pub trait AsPt3: Sync {
    /// The point as f64 coordinates.
    fn pt3(&self) -> Pt3;
}

impl AsPt3 for Pt3 {
    #[inline]
    fn pt3(&self) -> Pt3 {
        *self
    }
}
impl AsPt3 for Vec3 {
    #[inline]
    fn pt3(&self) -> Pt3 {
        Pt3::from(*self)
    }
}
impl AsPt3 for [f64; 3] {
    #[inline]
    fn pt3(&self) -> Pt3 {
        Pt3::new(self[0], self[1], self[2])
    }
}
impl AsPt3 for [f32; 3] {
    #[inline]
    fn pt3(&self) -> Pt3 {
        Pt3::new(self[0] as f64, self[1] as f64, self[2] as f64)
    }
}

/// Hermite smoothstep: 0 below `e0`, 1 above `e1`, `3t² − 2t³` between.
pub fn smoothstep(e0: f64, e1: f64, x: f64) -> f64 {
    if e1 == e0 {
        return if x < e0 { 0.0 } else { 1.0 };
    }
    let t = ((x - e0) / (e1 - e0)).clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

//! Exact conversions between nalgebra (our types) and glam (parry's types). Every function
//! copies the `f64` components, so round trips are bitwise exact.

use crate::math::{Iso3, Pt3, Vec3};

pub use parry3d_f64::math::{Pose as DPose3, Rotation as DQuat, Vector as DVec3};

/// A point as parry's vector type.
#[inline]
pub fn pt(p: &Pt3) -> DVec3 {
    DVec3::new(p.x, p.y, p.z)
}

/// A parry vector as a point.
#[inline]
pub fn to_pt(v: DVec3) -> Pt3 {
    Pt3::new(v.x, v.y, v.z)
}

/// A vector as parry's vector type.
#[inline]
pub fn vec(v: &Vec3) -> DVec3 {
    DVec3::new(v.x, v.y, v.z)
}

/// A parry vector as a vector.
#[inline]
pub fn to_vec(v: DVec3) -> Vec3 {
    Vec3::new(v.x, v.y, v.z)
}

/// A rigid transform as a parry pose (the quaternion's components are copied, not
/// renormalised).
#[inline]
pub fn pose(iso: &Iso3) -> DPose3 {
    let q = iso.rotation.quaternion();
    let t = &iso.translation.vector;
    DPose3::from_parts(DVec3::new(t.x, t.y, t.z), DQuat::from_xyzw(q.i, q.j, q.k, q.w))
}

/// A parry pose as a rigid transform (the quaternion's components are copied, not
/// renormalised).
#[inline]
pub fn to_iso(p: &DPose3) -> Iso3 {
    let (q, t) = (p.rotation, p.translation);
    Iso3::from_parts(
        nalgebra::Translation3::new(t.x, t.y, t.z),
        nalgebra::UnitQuaternion::new_unchecked(nalgebra::Quaternion::new(q.w, q.x, q.y, q.z)),
    )
}

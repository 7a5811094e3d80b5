//! [`Planar`]: a rigid transform of the ground plane (rotation about +Y, then translation in xz),
//! used for a character's torso frame and for placing motion clips (motion-graph.md §2.1, §3.1).
//!
//! Convention: +Y is up; a character faces +Z with its left on +X. Rotation about +Y by `yaw`
//! maps `(x, z) → (x cos yaw + z sin yaw, −x sin yaw + z cos yaw)` (equivalently, with the complex
//! number `u = z + i·x`, it multiplies `u` by `e^{i·yaw}`). The heading of a forward vector `f` is
//! `yaw = atan2(f.x, f.z)`, so yaw 0 faces +Z and yaw π/2 faces +X.

use super::{Iso3, UnitQuat, Vec3};
use nalgebra as na;
use serde::{Deserialize, Serialize};
use std::f64::consts::{PI, TAU};

/// Ground-plane rigid transform: `p ↦ R_y(yaw)·p + (x, 0, z)`. Angles in radians, lengths in
/// metres. `yaw` is not wrapped by [`compose`](Planar::compose) (so sequences stay continuous);
/// use [`wrap_angle`] where a canonical value is needed.
#[derive(Clone, Copy, Debug, PartialEq, Default, Serialize, Deserialize)]
pub struct Planar {
    /// Translation along x (m).
    pub x: f64,
    /// Translation along z (m).
    pub z: f64,
    /// Rotation about +Y (rad).
    pub yaw: f64,
}

/// Wraps an angle (rad) into `(−π, π]`.
pub fn wrap_angle(a: f64) -> f64 {
    let w = a - TAU * ((a + PI) / TAU).floor();
    // `w` is in [−π, π); map −π to π.
    if w <= -PI {
        w + TAU
    } else {
        w
    }
}

/// Heading (yaw, rad) of a direction: `atan2(d.x, d.z)`; 0 for +Z, π/2 for +X.
pub fn heading(d: &Vec3) -> f64 {
    d.x.atan2(d.z)
}

impl Planar {
    /// A transform from its parts.
    pub fn new(x: f64, z: f64, yaw: f64) -> Self {
        Self { x, z, yaw }
    }

    /// The identity transform.
    pub fn identity() -> Self {
        Self { x: 0.0, z: 0.0, yaw: 0.0 }
    }

    /// `self ∘ b`: apply `b` first, then `self`.
    pub fn compose(&self, b: &Planar) -> Planar {
        let t = self.apply_dir(Vec3::new(b.x, 0.0, b.z));
        Planar { x: self.x + t.x, z: self.z + t.z, yaw: self.yaw + b.yaw }
    }

    /// The inverse transform (`self.compose(&self.inverse())` is the identity).
    pub fn inverse(&self) -> Planar {
        let inv = Planar { x: 0.0, z: 0.0, yaw: -self.yaw };
        let t = inv.apply_dir(Vec3::new(self.x, 0.0, self.z));
        Planar { x: -t.x, z: -t.z, yaw: -self.yaw }
    }

    /// Transforms a point: rotate about +Y, then translate by `(x, 0, z)` (y unchanged).
    pub fn apply_point(&self, p: Vec3) -> Vec3 {
        let d = self.apply_dir(p);
        Vec3::new(d.x + self.x, d.y, d.z + self.z)
    }

    /// Transforms a direction (rotation only).
    pub fn apply_dir(&self, d: Vec3) -> Vec3 {
        let (s, c) = self.yaw.sin_cos();
        Vec3::new(c * d.x + s * d.z, d.y, -s * d.x + c * d.z)
    }

    /// The same transform as a 3-D isometry.
    pub fn to_iso3(&self) -> Iso3 {
        Iso3::from_parts(
            na::Translation3::new(self.x, 0.0, self.z),
            UnitQuat::from_axis_angle(&Vec3::y_axis(), self.yaw),
        )
    }

    /// Projects a 3-D isometry onto the ground plane: translation `(t.x, t.z)`, yaw = heading of
    /// the rotated +Z axis; if that axis is (nearly) vertical (its xz part shorter than 1e-9), the
    /// heading of the rotated +X axis minus π/2 is used instead. Result yaw in `(−π, π]`.
    pub fn from_iso3(iso: &Iso3) -> Planar {
        let f = iso.rotation * Vec3::z();
        let yaw = if f.x.hypot(f.z) > 1e-9 {
            heading(&f)
        } else {
            let l = iso.rotation * Vec3::x();
            wrap_angle(heading(&l) - 0.5 * PI)
        };
        Planar { x: iso.translation.x, z: iso.translation.z, yaw }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: Vec3, b: Vec3) -> bool {
        (a - b).norm() < 1e-13
    }

    #[test]
    fn rotation_convention_and_heading() {
        let p = Planar::new(0.0, 0.0, 0.5 * PI);
        // yaw π/2 turns the +Z facing direction to +X.
        assert!(close(p.apply_dir(Vec3::z()), Vec3::x()));
        assert!((heading(&p.apply_dir(Vec3::z())) - 0.5 * PI).abs() < 1e-15);
        // Matches the complex-number form u = z + i x multiplied by e^{i yaw}.
        let q = Planar::new(0.0, 0.0, 0.7);
        let d = Vec3::new(0.3, 2.0, -1.1);
        let u = na::Complex::new(d.z, d.x) * na::Complex::from_polar(1.0, 0.7);
        let r = q.apply_dir(d);
        assert!((r.z - u.re).abs() < 1e-15 && (r.x - u.im).abs() < 1e-15 && r.y == 2.0);
    }

    #[test]
    fn compose_inverse_and_iso_agree() {
        let a = Planar::new(1.0, -2.0, 0.4);
        let b = Planar::new(-0.5, 3.0, -2.2);
        let p = Vec3::new(0.2, 1.5, -0.7);
        assert!(close(a.compose(&b).apply_point(p), a.apply_point(b.apply_point(p))));
        let id = a.compose(&a.inverse());
        assert!(close(id.apply_point(p), p));
        assert!(close(a.inverse().compose(&a).apply_point(p), p));
        let iso = a.to_iso3();
        assert!(close((iso * na::Point3::from(p)).coords, a.apply_point(p)));
        let back = Planar::from_iso3(&iso);
        assert!((back.x - a.x).abs() < 1e-15 && (back.z - a.z).abs() < 1e-15);
        assert!((back.yaw - a.yaw).abs() < 1e-15);
        assert_eq!(Planar::identity().apply_point(p), p);
    }

    #[test]
    fn from_iso3_handles_a_vertical_forward_axis() {
        // Lying on the back: forward +Z rotated to +Y, heading comes from the x axis.
        let rot =
            UnitQuat::from_axis_angle(&Vec3::y_axis(), 0.3) * UnitQuat::from_axis_angle(&Vec3::x_axis(), -0.5 * PI);
        let p = Planar::from_iso3(&Iso3::from_parts(na::Translation3::new(1.0, 2.0, 3.0), rot));
        assert!((p.yaw - 0.3).abs() < 1e-12, "{}", p.yaw);
        assert_eq!((p.x, p.z), (1.0, 3.0));
    }

    #[test]
    fn wrap_angle_range() {
        for k in -5..=5 {
            for &a in &[-3.0, -1.0, 0.0, 2.5, PI] {
                let w = wrap_angle(a + TAU * k as f64);
                assert!(w > -PI && w <= PI);
                assert!((wrap_angle(w - a)).abs() < 1e-12);
            }
        }
        assert_eq!(wrap_angle(-PI), PI);
    }
}

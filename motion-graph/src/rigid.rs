//! [`Rigid2`]: a ground-plane rigid transform with its rotation stored as `(cos, sin)`, so that
//! composing placements during the search (§3.5, §3.6) needs no trigonometry.
//!
//! Same convention as [`Planar`] (rotation about +Y by `yaw` maps `(x, z)` to
//! `(x cos + z sin, −x sin + z cos)`, then translation); `yaw` is carried along unwrapped (sum of
//! the composed yaws, as [`Planar::compose`] does) so heading errors match the `Planar`
//! evaluation.

use geom_core::math::{Planar, Vec3};

/// Planar rigid transform `p ↦ R_y(yaw) p + (x, 0, z)` with `c = cos yaw`, `s = sin yaw`.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct Rigid2 {
    /// `cos yaw`.
    pub c: f64,
    /// `sin yaw`.
    pub s: f64,
    /// Translation along x (m).
    pub x: f64,
    /// Translation along z (m).
    pub z: f64,
    /// Yaw (rad, unwrapped).
    pub yaw: f64,
}

impl From<Planar> for Rigid2 {
    fn from(p: Planar) -> Self {
        let (s, c) = p.yaw.sin_cos();
        Rigid2 { c, s, x: p.x, z: p.z, yaw: p.yaw }
    }
}

impl From<Rigid2> for Planar {
    fn from(r: Rigid2) -> Self {
        Planar { x: r.x, z: r.z, yaw: r.yaw }
    }
}

impl Rigid2 {
    /// `self ∘ b`: apply `b` first, then `self`.
    #[inline]
    pub fn compose(&self, b: &Rigid2) -> Rigid2 {
        Rigid2 {
            c: self.c * b.c - self.s * b.s,
            s: self.s * b.c + self.c * b.s,
            x: self.x + self.c * b.x + self.s * b.z,
            z: self.z - self.s * b.x + self.c * b.z,
            yaw: self.yaw + b.yaw,
        }
    }

    /// The inverse transform.
    #[inline]
    pub fn inverse(&self) -> Rigid2 {
        Rigid2 {
            c: self.c,
            s: -self.s,
            x: -(self.c * self.x - self.s * self.z),
            z: -(self.s * self.x + self.c * self.z),
            yaw: -self.yaw,
        }
    }

    /// The translation of `self ∘ b` (position of `b`'s origin in `self`'s target frame).
    #[inline]
    pub fn apply_xz(&self, x: f64, z: f64) -> (f64, f64) {
        (self.x + self.c * x + self.s * z, self.z - self.s * x + self.c * z)
    }

    /// Transforms a point (y unchanged).
    #[inline]
    pub fn apply_point(&self, p: Vec3) -> Vec3 {
        let (x, z) = self.apply_xz(p.x, p.z);
        Vec3::new(x, p.y, z)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Composition, inverse and point maps agree with `Planar` (same formulas up to rounding:
    /// 1e-12 on values of order 10).
    #[test]
    fn matches_planar() {
        let a = Planar::new(1.5, -2.0, 0.7);
        let b = Planar::new(-0.3, 4.0, -2.9);
        let (ra, rb) = (Rigid2::from(a), Rigid2::from(b));
        let c = Rigid2::from(a.compose(&b));
        let rc = ra.compose(&rb);
        for (u, v) in [(c.c, rc.c), (c.s, rc.s), (c.x, rc.x), (c.z, rc.z), (c.yaw, rc.yaw)] {
            assert!((u - v).abs() < 1e-12, "{u} vs {v}");
        }
        let i = Rigid2::from(a.inverse());
        let ri = ra.inverse();
        for (u, v) in [(i.c, ri.c), (i.s, ri.s), (i.x, ri.x), (i.z, ri.z), (i.yaw, ri.yaw)] {
            assert!((u - v).abs() < 1e-12, "{u} vs {v}");
        }
        let p = Vec3::new(0.4, 1.1, -3.0);
        assert!((a.apply_point(p) - ra.apply_point(p)).norm() < 1e-12);
        let id = ra.compose(&ra.inverse());
        assert!((id.c - 1.0).abs() < 1e-15 && id.s.abs() < 1e-15 && id.x.abs() < 1e-12 && id.z.abs() < 1e-12);
    }
}

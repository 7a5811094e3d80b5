//! Pinhole cameras beyond geom-core's [`Camera`]: the K[R|t] decomposition, Brown–Conrady lens
//! distortion and the perturbed camera of the noise model (spec §3.3, §3.4).
//!
//! The camera model is geom-core's (OpenCV conventions: pixel centres at integers, (0, 0) the
//! centre of the top-left pixel, y down, depth w = (PX̃)₂ > 0 in front).

use geom_core::math::{Mat3, Pt2, Pt3, Vec3};
use geom_core::raster::Camera;
use geom_core::rng::Rng;
use nalgebra::{Rotation3, Unit};
use serde::{Deserialize, Serialize};

/// `P = K [R | t]` → `(K, R, t)` by an RQ decomposition of the left 3×3 block `M = K R`,
/// with K upper triangular with a positive diagonal (spec T1). `R` has det +1 for every
/// physical camera (det M > 0); a mirrored camera gives det R = −1.
pub fn decompose(c: &Camera) -> (Mat3, Mat3, Vec3) {
    let m: Mat3 = c.p.fixed_view::<3, 3>(0, 0).into_owned();
    let r = c.view_rotation();
    let mut k = m * r.transpose();
    // Exact zeros below the diagonal (they are rounding residue of the Gram–Schmidt).
    k[(1, 0)] = 0.0;
    k[(2, 0)] = 0.0;
    k[(2, 1)] = 0.0;
    let t = k.try_inverse().map(|ki| ki * c.p.column(3)).unwrap_or_else(Vec3::zeros);
    (k, r, t)
}

/// The same camera rotated by `rot_deg` about a random axis through its centre and moved by
/// `shift_m` in a random direction (the calibration error of the noise model, spec §3.3).
pub fn perturbed(c: &Camera, rot_deg: f64, shift_m: f64, rng: &mut Rng) -> Camera {
    let (k, r, t) = decompose(c);
    let center = -(r.transpose() * t);
    let axis = Unit::new_normalize(rng.unit_vec3());
    let dr = Rotation3::from_axis_angle(&axis, rot_deg.to_radians());
    let r2 = r * dr.matrix();
    let c2 = center + shift_m * rng.unit_vec3();
    Camera::from_krt(&k, &r2, &(-(r2 * c2)), c.width, c.height)
}

/// Brown–Conrady lens distortion on normalised image coordinates (x, y) = K⁻¹(u, v, 1):
/// x_d = x(1 + k1 r² + k2 r⁴) + 2p1 xy + p2(r² + 2x²), y_d = y(1 + k1 r² + k2 r⁴) +
/// p1(r² + 2y²) + 2p2 xy.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Distortion {
    /// Radial k1.
    pub k1: f64,
    /// Radial k2.
    pub k2: f64,
    /// Tangential p1.
    pub p1: f64,
    /// Tangential p2.
    pub p2: f64,
}

impl Distortion {
    /// Distorts normalised coordinates.
    pub fn distort(&self, x: f64, y: f64) -> (f64, f64) {
        let r2 = x * x + y * y;
        let radial = 1.0 + self.k1 * r2 + self.k2 * r2 * r2;
        (
            x * radial + 2.0 * self.p1 * x * y + self.p2 * (r2 + 2.0 * x * x),
            y * radial + self.p1 * (r2 + 2.0 * y * y) + 2.0 * self.p2 * x * y,
        )
    }

    /// Inverse of [`Distortion::distort`] by fixed-point iteration (20 iterations; exact for
    /// zero coefficients, converges for the mild distortions of real lenses).
    pub fn undistort(&self, xd: f64, yd: f64) -> (f64, f64) {
        let (mut x, mut y) = (xd, yd);
        for _ in 0..20 {
            let (dx, dy) = self.distort(x, y);
            x += xd - dx;
            y += yd - dy;
        }
        (x, y)
    }

    /// Pixel of the distorted (real) image that shows what the ideal pinhole `k` maps to pixel
    /// `p` (used to resample footage into the distortion-free camera).
    pub fn distorted_pixel(&self, k: &Mat3, p: Pt2) -> Pt2 {
        let (fx, fy, cx, cy, s) = (k[(0, 0)], k[(1, 1)], k[(0, 2)], k[(1, 2)], k[(0, 1)]);
        let y = (p.y - cy) / fy;
        let x = (p.x - cx - s * y) / fx;
        let (xd, yd) = self.distort(x, y);
        Pt2::new(fx * xd + s * yd + cx, fy * yd + cy)
    }
}

/// The world point at depth `w` behind pixel `p` of camera `c` (`None` for an affine camera).
pub fn backproject(c: &Camera, p: Pt2, w: f64) -> Option<Pt3> {
    let m: Mat3 = c.p.fixed_view::<3, 3>(0, 0).into_owned();
    let mi = m.try_inverse()?;
    let h = Vec3::new(p.x * w, p.y * w, w) - c.p.column(3);
    Some(Pt3::from(mi * h))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Spec T1: look_at → project against hand-computed pixels; decompose ∘ from_krt = id.
    #[test]
    fn look_at_projects_and_decomposes() {
        let c =
            Camera::look_at(&Pt3::new(0.0, -1.2, 0.0), &Pt3::new(0.0, 0.0, 0.0), &Vec3::z(), 60.0, 320, 240).unwrap();
        // f = 120 / tan 30°; a point 0.1 m right and 0.05 m up at depth 1.2 m.
        let f = 120.0 / 30f64.to_radians().tan();
        let (px, w) = c.project(&Pt3::new(0.1, 0.0, 0.05)).unwrap();
        assert!((w - 1.2).abs() < 1e-12);
        assert!((px.x - (159.5 + f * 0.1 / 1.2)).abs() < 1e-12);
        assert!((px.y - (119.5 - f * 0.05 / 1.2)).abs() < 1e-12);
        let (k, r, t) = decompose(&c);
        assert!((r.determinant() - 1.0).abs() < 1e-12);
        let c2 = Camera::from_krt(&k, &r, &t, 320, 240);
        assert!((c2.p - c.p).norm() <= 1e-12 * c.p.norm());
        let mut rng = Rng::new(5);
        for _ in 0..20 {
            let kk = Mat3::new(
                rng.range(300.0, 900.0),
                rng.range(-2.0, 2.0),
                rng.range(100.0, 300.0),
                0.0,
                rng.range(300.0, 900.0),
                rng.range(100.0, 300.0),
                0.0,
                0.0,
                1.0,
            );
            let rr = Rotation3::from_axis_angle(&Unit::new_normalize(rng.unit_vec3()), rng.range(-3.0, 3.0));
            let tt = Vec3::new(rng.normal(), rng.normal(), rng.normal());
            let cam = Camera::from_krt(&kk, rr.matrix(), &tt, 640, 480);
            let (k2, r2, t2) = decompose(&cam);
            assert!((k2 - kk).norm() <= 1e-12 * kk.norm(), "{k2} vs {kk}");
            assert!((r2 - rr.matrix()).norm() <= 1e-12);
            assert!((t2 - tt).norm() <= 1e-12 * tt.norm().max(1.0));
        }
    }

    #[test]
    fn distortion_round_trips_and_backprojection_inverts_projection() {
        let d = Distortion { k1: -0.2, k2: 0.05, p1: 0.001, p2: -0.002 };
        for &(x, y) in &[(0.1, -0.2), (0.3, 0.25), (0.0, 0.0)] {
            let (xd, yd) = d.distort(x, y);
            let (xu, yu) = d.undistort(xd, yd);
            assert!((xu - x).abs() < 1e-12 && (yu - y).abs() < 1e-12);
        }
        let c = Camera::look_at(&Pt3::new(0.3, -1.0, 0.2), &Pt3::origin(), &Vec3::z(), 40.0, 200, 100).unwrap();
        let x = Pt3::new(0.05, 0.1, -0.1);
        let (p, w) = c.project(&x).unwrap();
        assert!((backproject(&c, p, w).unwrap() - x).norm() < 1e-12);
    }
}

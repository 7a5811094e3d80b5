//! [`Camera`]: a pinhole projection matrix with an image size.

use crate::error::{Error, Result};
use crate::math::{Mat3, Mat34, Pt2, Pt3, Vec3};

/// A pinhole camera: the 3×4 projection `P = K [R | t]` and the image size in pixels.
///
/// A world point `X` maps to pixel `((PX̃)₀/(PX̃)₂, (PX̃)₁/(PX̃)₂)` with `X̃ = (X, 1)`; pixel
/// `(0, 0)` is the centre of the top-left pixel, `y` points down. Its depth is `w = (PX̃)₂`,
/// positive in front of the camera (for `K₃₃ = 1` and a rotation `R`, `w` is the distance along
/// the optical axis in metres).
#[derive(Clone, Debug, PartialEq)]
pub struct Camera {
    /// Projection matrix `P = K [R | t]`.
    pub p: Mat34,
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
}

impl Camera {
    /// A camera at `eye` looking at `target`, with `up` giving the upward image direction,
    /// vertical field of view `fov_y_deg` (degrees, in `(0, 180)`), square pixels and the
    /// principal point at the image centre `((w − 1)/2, (h − 1)/2)`.
    ///
    /// The camera frame is OpenCV's: x right, y down, z forward; `K = [[f, 0, cx], [0, f, cy],
    /// [0, 0, 1]]` with `f = (h/2) / tan(fov_y/2)`.
    ///
    /// Errors (`InvalidParameter`): zero image size, a field of view outside `(0, 180)`,
    /// `eye == target`, `up` parallel to the viewing direction, or non-finite input.
    pub fn look_at(eye: &Pt3, target: &Pt3, up: &Vec3, fov_y_deg: f64, width: u32, height: u32) -> Result<Self> {
        if width == 0 || height == 0 {
            return Err(Error::InvalidParameter(format!("Camera::look_at: image size {width}×{height}")));
        }
        if !(fov_y_deg > 0.0 && fov_y_deg < 180.0) {
            return Err(Error::InvalidParameter(format!("Camera::look_at: fov_y_deg = {fov_y_deg} outside (0, 180)")));
        }
        let fwd = target - eye;
        if !(fwd.norm() > 0.0 && fwd.norm().is_finite()) {
            return Err(Error::InvalidParameter("Camera::look_at: eye and target coincide or are not finite".into()));
        }
        let f = fwd.normalize();
        let right = f.cross(up);
        // sin(angle(up, forward)) must not vanish; 1e-12 is far below any meaningful up vector.
        if right.norm() <= 1e-12 * up.norm() || !right.norm().is_finite() || !up.norm().is_finite() {
            return Err(Error::InvalidParameter("Camera::look_at: up is parallel to the viewing direction".into()));
        }
        let r1 = right.normalize();
        let r2 = f.cross(&r1);
        let r = Mat3::from_rows(&[r1.transpose(), r2.transpose(), f.transpose()]);
        let focal = 0.5 * height as f64 / (0.5 * fov_y_deg.to_radians()).tan();
        let k =
            Mat3::new(focal, 0.0, 0.5 * (width as f64 - 1.0), 0.0, focal, 0.5 * (height as f64 - 1.0), 0.0, 0.0, 1.0);
        let t = -(r * eye.coords);
        Ok(Self::from_krt(&k, &r, &t, width, height))
    }

    /// `P = K [R | t]` from intrinsics `k`, world-to-camera rotation `r` and translation `t`
    /// (a world point `X` has camera coordinates `R X + t`).
    pub fn from_krt(k: &Mat3, r: &Mat3, t: &Vec3, width: u32, height: u32) -> Self {
        let mut rt = Mat34::zeros();
        rt.fixed_view_mut::<3, 3>(0, 0).copy_from(r);
        rt.set_column(3, t);
        Self { p: k * rt, width, height }
    }

    /// Homogeneous image point `P X̃ = (u w, v w, w)`.
    #[inline]
    pub fn homogeneous(&self, x: &Pt3) -> Vec3 {
        self.p.fixed_view::<3, 3>(0, 0) * x.coords + self.p.column(3)
    }

    /// Pixel coordinates and depth `w` of `x`, or `None` if `x` is not in front of the camera
    /// (`w ≤ 0` or not finite). The pixel may lie outside the image.
    pub fn project(&self, x: &Pt3) -> Option<(Pt2, f64)> {
        let h = self.homogeneous(x);
        (h.z > 0.0 && h.z.is_finite()).then(|| (Pt2::new(h.x / h.z, h.y / h.z), h.z))
    }

    /// The camera centre `C = −M⁻¹ p₄` (`M` the left 3×3 block of `P`), `None` if `M` is
    /// singular (an affine camera).
    pub fn center(&self) -> Option<Pt3> {
        let m: Mat3 = self.p.fixed_view::<3, 3>(0, 0).into_owned();
        m.try_inverse().map(|mi| Pt3::from(-(mi * self.p.column(3))))
    }

    /// The world-to-camera rotation `R` of the RQ decomposition `M = K R` (`K` upper triangular
    /// with a positive diagonal), by Gram–Schmidt on the rows of `M` from the bottom: rows are the
    /// camera's right, down and forward axes in world coordinates.
    pub fn view_rotation(&self) -> Mat3 {
        let m: Mat3 = self.p.fixed_view::<3, 3>(0, 0).into_owned();
        let (m1, m2, m3) = (m.row(0).transpose(), m.row(1).transpose(), m.row(2).transpose());
        let r3 = m3.normalize();
        let r2 = (m2 - r3 * m2.dot(&r3)).normalize();
        let r1 = (m1 - r3 * m1.dot(&r3) - r2 * m1.dot(&r2)).normalize();
        Mat3::from_rows(&[r1.transpose(), r2.transpose(), r3.transpose()])
    }

    /// `+1` or `−1`: the sign of `det M`. A triangle `(a, b, c)` faces the camera (its normal
    /// `(b − a) × (c − a)` points towards the centre) iff `det[Pa, Pb, Pc] · sign < 0`.
    pub(crate) fn handedness(&self) -> f64 {
        let m: Mat3 = self.p.fixed_view::<3, 3>(0, 0).into_owned();
        if m.determinant() < 0.0 {
            -1.0
        } else {
            1.0
        }
    }

    /// `true` if triangle `(a, b, c)` shows its front (normal `(b − a) × (c − a)`) to the camera.
    /// Uses `det[Pa, Pb, Pc] = det M · (a − C) · n`, valid even for corners behind the camera.
    pub fn is_front_facing(&self, a: &Pt3, b: &Pt3, c: &Pt3) -> bool {
        let h = Mat3::from_columns(&[self.homogeneous(a), self.homogeneous(b), self.homogeneous(c)]);
        h.determinant() * self.handedness() < 0.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cam() -> Camera {
        Camera::look_at(&Pt3::new(0.0, 0.0, 5.0), &Pt3::origin(), &Vec3::y(), 90.0, 101, 51).expect("valid camera")
    }

    #[test]
    fn look_at_projects_target_to_the_principal_point() {
        let c = cam();
        let (px, w) = c.project(&Pt3::origin()).expect("in front");
        assert!((px - Pt2::new(50.0, 25.0)).norm() < 1e-12);
        assert!((w - 5.0).abs() < 1e-12);
        // +x world is right, +y world is up (smaller pixel y).
        let (pr, _) = c.project(&Pt3::new(1.0, 0.0, 0.0)).expect("in front");
        let (pu, _) = c.project(&Pt3::new(0.0, 1.0, 0.0)).expect("in front");
        assert!(pr.x > 50.0 && (pr.y - 25.0).abs() < 1e-12);
        assert!(pu.y < 25.0);
        // fov 90°: a point at height w·tan(45°) = w sits h/2 pixels above the centre.
        let (pe, _) = c.project(&Pt3::new(0.0, 5.0, 0.0)).expect("in front");
        assert!((pe.y - (25.0 - 25.5)).abs() < 1e-12);
        assert!(c.project(&Pt3::new(0.0, 0.0, 6.0)).is_none());
        assert!((c.center().expect("finite camera") - Pt3::new(0.0, 0.0, 5.0)).norm() < 1e-12);
    }

    #[test]
    fn rotation_and_facing() {
        let c = cam();
        let r = c.view_rotation();
        assert!((r.row(2).transpose() - Vec3::new(0.0, 0.0, -1.0)).norm() < 1e-12);
        assert!((r.row(1).transpose() - Vec3::new(0.0, -1.0, 0.0)).norm() < 1e-12);
        let (a, b, d) = (Pt3::new(0.0, 0.0, 0.0), Pt3::new(1.0, 0.0, 0.0), Pt3::new(0.0, 1.0, 0.0));
        assert!(c.is_front_facing(&a, &b, &d));
        assert!(!c.is_front_facing(&a, &d, &b));
    }

    #[test]
    fn invalid_parameters_are_errors() {
        let e = Pt3::new(0.0, 0.0, 5.0);
        assert!(Camera::look_at(&e, &e, &Vec3::y(), 60.0, 10, 10).is_err());
        assert!(Camera::look_at(&e, &Pt3::origin(), &Vec3::z(), 60.0, 10, 10).is_err());
        assert!(Camera::look_at(&e, &Pt3::origin(), &Vec3::y(), 180.0, 10, 10).is_err());
        assert!(Camera::look_at(&e, &Pt3::origin(), &Vec3::y(), 60.0, 0, 10).is_err());
    }
}

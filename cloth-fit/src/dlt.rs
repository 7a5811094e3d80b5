//! Camera calibration from marker correspondences by the normalised direct linear transform
//! (spec §3.4 step 4; Hartley & Zisserman, *Multiple View Geometry*, alg. 7.1). The paper
//! computed the camera and projector matrices "using a calibration grid comprising of several
//! motion capture markers" (Bhat et al. 2003 §5).

use geom_core::math::{Mat3, Mat34, Pt2, Pt3};
use geom_core::raster::Camera;
use nalgebra::{DMatrix, Matrix4};

use crate::error::{FitError, Result};

/// Solves the 3×4 projection `P` from `n ≥ 6` non-coplanar world points and their pixels
/// (OpenCV pixel convention) and returns the camera (scaled so that the third row of `M` is a
/// unit vector: w is the depth in metres) with the RMS reprojection error in pixels.
///
/// Errors: [`FitError::DegenerateCalibration`] for fewer than 6 points, different list
/// lengths, non-finite input, or (nearly) coplanar points (smallest singular value of the
/// centred cloud below 1e-3 × the largest).
pub fn calibrate_dlt(world: &[Pt3], image: &[Pt2], width: u32, height: u32) -> Result<(Camera, f64)> {
    let n = world.len();
    let deg = |m: String| Err(FitError::DegenerateCalibration(m));
    if n != image.len() {
        return deg(format!("{n} world points but {} image points", image.len()));
    }
    if n < 6 {
        return deg(format!("{n} markers; the DLT needs at least 6 non-coplanar ones"));
    }
    if world.iter().any(|p| p.iter().any(|c| !c.is_finite())) || image.iter().any(|p| p.iter().any(|c| !c.is_finite()))
    {
        return deg("non-finite marker coordinates".into());
    }
    // Coplanarity: singular values of the centred 3-D cloud.
    let c3 = world.iter().fold(nalgebra::Vector3::zeros(), |a, p| a + p.coords) / n as f64;
    let mut cov = Mat3::zeros();
    for p in world {
        let d = p.coords - c3;
        cov += d * d.transpose();
    }
    let ev = cov.symmetric_eigenvalues();
    let (smin, smax) = (ev.min().max(0.0).sqrt(), ev.max().max(0.0).sqrt());
    if !(smin >= 1e-3 * smax) || smax == 0.0 {
        return deg(format!(
            "markers are (nearly) coplanar: smallest/largest singular value of the centred cloud {:.3e}",
            if smax > 0.0 { smin / smax } else { 0.0 }
        ));
    }
    // Hartley normalisation.
    let c2 = image.iter().fold(nalgebra::Vector2::zeros(), |a, p| a + p.coords) / n as f64;
    let d2 = image.iter().map(|p| (p.coords - c2).norm()).sum::<f64>() / n as f64;
    let d3 = world.iter().map(|p| (p.coords - c3).norm()).sum::<f64>() / n as f64;
    if !(d2 > 0.0) {
        return deg("all image points coincide".into());
    }
    let (s2, s3) = (2f64.sqrt() / d2, 3f64.sqrt() / d3);
    let t2 = Mat3::new(s2, 0.0, -s2 * c2.x, 0.0, s2, -s2 * c2.y, 0.0, 0.0, 1.0);
    let t3 =
        Matrix4::new(s3, 0.0, 0.0, -s3 * c3.x, 0.0, s3, 0.0, -s3 * c3.y, 0.0, 0.0, s3, -s3 * c3.z, 0.0, 0.0, 0.0, 1.0);
    let mut a = DMatrix::<f64>::zeros(2 * n, 12);
    for (k, (x, u)) in world.iter().zip(image).enumerate() {
        let xw = (x.coords - c3) * s3;
        let xh = [xw.x, xw.y, xw.z, 1.0];
        let (un, vn) = ((u.x - c2.x) * s2, (u.y - c2.y) * s2);
        for j in 0..4 {
            a[(2 * k, j)] = xh[j];
            a[(2 * k, 8 + j)] = -un * xh[j];
            a[(2 * k + 1, 4 + j)] = xh[j];
            a[(2 * k + 1, 8 + j)] = -vn * xh[j];
        }
    }
    // Right singular vector of the smallest singular value (of AᵀA's eigenproblem for the
    // square case too; A is 2n × 12 with 2n ≥ 12).
    let svd = a.svd(false, true);
    let vt = svd.v_t.ok_or_else(|| FitError::DegenerateCalibration("SVD did not converge".into()))?;
    let (imin, _) =
        svd.singular_values
            .iter()
            .enumerate()
            .fold((0, f64::INFINITY), |(bi, bv), (i, &v)| if v < bv { (i, v) } else { (bi, bv) });
    let h = vt.row(imin);
    let pn = Mat34::from_row_slice(&h.iter().copied().collect::<Vec<f64>>());
    let t2i = t2.try_inverse().expect("a scaling with s > 0 is invertible");
    let mut p: Mat34 = t2i * pn * t3;
    // Scale: unit third row of M, sign so that the markers are in front (w > 0).
    let m3 = p.fixed_view::<1, 3>(2, 0).norm();
    if !(m3 > 0.0) || !m3.is_finite() {
        return deg("the solved projection is affine or degenerate".into());
    }
    p /= m3;
    let cam0 = Camera { p, width, height };
    let wsum: f64 = world.iter().map(|x| cam0.homogeneous(x).z).sum();
    if wsum < 0.0 {
        p = -p;
    }
    let cam = Camera { p, width, height };
    let mut se = 0.0;
    for (x, u) in world.iter().zip(image) {
        let hx = cam.homogeneous(x);
        if !(hx.z > 0.0) {
            return deg("a marker lies behind the solved camera".into());
        }
        let px = Pt2::new(hx.x / hx.z, hx.y / hx.z);
        se += (px - u).norm_squared();
    }
    Ok((cam, (se / n as f64).sqrt()))
}

#[cfg(test)]
mod tests {
    use super::*;
    use geom_core::math::Vec3;
    use geom_core::rng::Rng;

    fn camera() -> Camera {
        Camera::look_at(&Pt3::new(0.1, -1.2, 0.05), &Pt3::new(0.0, 0.0, -0.2), &Vec3::z(), 33.4, 320, 240).unwrap()
    }

    /// Spec T2.
    #[test]
    fn dlt_recovers_the_camera() {
        let c = camera();
        let mut rng = Rng::new(2);
        let world: Vec<Pt3> =
            (0..20).map(|_| Pt3::new(rng.range(-0.3, 0.3), rng.range(-0.2, 0.2), rng.range(-0.5, 0.1))).collect();
        let image: Vec<Pt2> = world.iter().map(|x| c.project(x).unwrap().0).collect();
        let (est, rms) = calibrate_dlt(&world, &image, 320, 240).unwrap();
        assert!(rms < 1e-8, "rms {rms}");
        assert!((est.p - c.p).norm() <= 1e-8 * c.p.norm(), "{} vs {}", est.p, c.p);
        // 0.5 px noise.
        let noisy: Vec<Pt2> =
            image.iter().map(|p| p + nalgebra::Vector2::new(rng.normal(), rng.normal()) * 0.5).collect();
        let (_, rms) = calibrate_dlt(&world, &noisy, 320, 240).unwrap();
        assert!(rms <= 1.5 * 0.5, "rms {rms}");
        // Coplanar and too few markers.
        let flat: Vec<Pt3> = (0..6).map(|i| Pt3::new(0.1 * i as f64, 0.05 * (i * i) as f64, 0.0)).collect();
        let fi: Vec<Pt2> = flat.iter().map(|x| c.project(x).unwrap().0).collect();
        assert!(matches!(calibrate_dlt(&flat, &fi, 320, 240), Err(FitError::DegenerateCalibration(_))));
        assert!(matches!(calibrate_dlt(&world[..5], &image[..5], 320, 240), Err(FitError::DegenerateCalibration(_))));
    }
}

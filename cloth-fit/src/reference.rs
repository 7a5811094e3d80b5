//! Analytic references the figures and tests are compared with: gratings of known
//! orientation (spec T6), the stripe period predicted by the two homographies of a plane
//! (T5), and the variability of a quadratic error (T14).

use geom_core::image::ImageF32;

use crate::rig::Rig;

/// A cosine grating of `period` px whose stripes run along the screen direction `phi` (rad,
/// counter-clockwise with y up on screen, i.e. along (cos φ, −sin φ) in pixel coordinates):
/// I = 0.5 + 0.4 cos(2π d/period), d the distance across the stripes. The angle map of it is φ.
pub fn grating(width: u32, height: u32, period: f64, phi: f64) -> ImageF32 {
    let (s, c) = phi.sin_cos();
    let mut img = ImageF32::new(width, height, 0.0);
    for y in 0..height {
        for x in 0..width {
            let d = s * x as f64 + c * y as f64;
            img.set(x, y, (0.5 + 0.4 * (std::f64::consts::TAU * d / period).cos()) as f32);
        }
    }
    img
}

/// The variability of E(p) = E0(1 + c(p/p0 − 1)²) for a relative error change `target`
/// (spec T14): sqrt(target/c).
pub fn quadratic_variability(c: f64, target: f64) -> f64 {
    (target / c).sqrt()
}

/// The stripe period (px) in the camera image at the point where the projector's optical axis
/// meets the plane perpendicular to that axis at distance `d` (m) from the projector, by the
/// camera→plane→projector homography (spec T5). `None` when the rig cannot see the point.
pub fn stripe_period_on_projector_plane(rig: &Rig, d: f64) -> Option<f64> {
    let cp = rig.projector.camera.center()?;
    let axis = rig.projector.camera.view_rotation().row(2).transpose();
    rig.stripe_period_at(&(cp + d * axis), &axis)
}

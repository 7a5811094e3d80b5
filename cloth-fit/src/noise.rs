//! The degradation that turns a clean synthetic render into "real" footage (spec §3.3
//! `NoiseModel`, §3.11 mismatched condition): per-frame gain, Gaussian blur, additive Gaussian
//! noise, 8-bit quantisation, and a camera calibration error (the truth is rendered by a camera
//! rotated and shifted from the nominal one that the fit uses). All randomness comes from one
//! seeded generator, one independent stream per frame.

use geom_core::image::{gaussian_blur, Border, ImageF32};
use geom_core::raster::Camera;
use geom_core::rng::Rng;
use serde::{Deserialize, Serialize};

use crate::camera::perturbed;
use crate::error::{FitError, Result};

/// Noise and calibration-error model.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct NoiseModel {
    /// Additive Gaussian noise σ (intensity units, [0, 1] scale).
    pub sigma: f64,
    /// Per-frame gain 1 + σ_g ξ.
    pub gain_sigma: f64,
    /// Gaussian blur σ_b (px).
    pub blur_px: f64,
    /// Quantise to 8 bits.
    pub quantize_8bit: bool,
    /// Rotation of the truth camera about a random axis (degrees).
    pub camera_rot_deg: f64,
    /// Shift of the truth camera centre in a random direction (m).
    pub camera_shift_m: f64,
    /// Seed.
    pub seed: u64,
}

impl Default for NoiseModel {
    /// The mismatched condition of spec §3.11: σ = 0.02, gain 0.02, blur 0.5 px, 8-bit,
    /// camera error 0.2° and 2 mm, seed 11.
    fn default() -> Self {
        Self {
            sigma: 0.02,
            gain_sigma: 0.02,
            blur_px: 0.5,
            quantize_8bit: true,
            camera_rot_deg: 0.2,
            camera_shift_m: 0.002,
            seed: 11,
        }
    }
}

impl NoiseModel {
    /// Checks the values.
    pub fn validate(&self) -> Result<()> {
        let v = [self.sigma, self.gain_sigma, self.blur_px, self.camera_rot_deg, self.camera_shift_m];
        if v.iter().any(|x| !x.is_finite() || *x < 0.0) {
            return Err(FitError::BadParameter(format!("noise model values must be finite and ≥ 0, got {self:?}")));
        }
        Ok(())
    }

    /// The truth camera: `nominal` with the calibration error applied (the same for every frame
    /// of a sequence; stream `u64::MAX` of the seed).
    pub fn truth_camera(&self, nominal: &Camera) -> Camera {
        if self.camera_rot_deg == 0.0 && self.camera_shift_m == 0.0 {
            return nominal.clone();
        }
        let mut rng = Rng::stream(self.seed, u64::MAX);
        perturbed(nominal, self.camera_rot_deg, self.camera_shift_m, &mut rng)
    }
}

/// Degrades frame `frame` of a clean render (spec §2 `degrade`): gain, blur, noise, 8 bits.
pub fn degrade(img: &ImageF32, n: &NoiseModel, frame: usize) -> ImageF32 {
    let mut rng = Rng::stream(n.seed, frame as u64);
    let gain = 1.0 + n.gain_sigma * rng.normal();
    let mut out = img.clone();
    for v in out.data.iter_mut() {
        *v = (*v as f64 * gain) as f32;
    }
    if n.blur_px > 0.0 {
        out = gaussian_blur(&out, n.blur_px, Border::Clamp);
    }
    for v in out.data.iter_mut() {
        let mut x = *v as f64 + n.sigma * rng.normal();
        if n.quantize_8bit {
            x = (x * 255.0).round().clamp(0.0, 255.0) / 255.0;
        }
        *v = x as f32;
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Spec T16: on a flat image the residual has mean 0 and standard deviation σ after 8-bit
    /// quantisation (within 5 %).
    #[test]
    fn noise_statistics() {
        let clean = ImageF32::new(256, 256, 0.5);
        let n = NoiseModel { gain_sigma: 0.0, blur_px: 0.0, ..NoiseModel::default() };
        let d = degrade(&clean, &n, 3);
        let r: Vec<f64> = d.data.iter().map(|&v| v as f64 - 0.5).collect();
        let m = r.iter().sum::<f64>() / r.len() as f64;
        let sd = (r.iter().map(|x| (x - m) * (x - m)).sum::<f64>() / r.len() as f64).sqrt();
        assert!(m.abs() <= 0.05 * n.sigma, "mean {m}");
        assert!((sd - n.sigma).abs() <= 0.05 * n.sigma, "sd {sd}");
        // Deterministic per (seed, frame), different across frames.
        assert_eq!(degrade(&clean, &n, 3), d);
        assert_ne!(degrade(&clean, &n, 4), d);
    }
}

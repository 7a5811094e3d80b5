//! The capture rig: camera, structured-light projector, frame rate and gravity direction (spec
//! §2 `Rig`, §3.3, §3.4 calibration file, §4.3).
//!
//! The paper projects "a structured light pattern of horizontal stripes onto the fabric" to
//! normalise lighting and reflectance (Bhat et al. 2003 §4). The projector is a second pinhole;
//! its baseline to the camera must be perpendicular to the stripes (projector above or below
//! the camera for horizontal stripes), otherwise the stripes carry no shape information.

use std::path::Path;

use geom_core::math::{Mat34, Pt2, Pt3, Vec3};
use geom_core::raster::Camera;
use serde::{Deserialize, Serialize};

use crate::camera::{backproject, Distortion};
use crate::dlt::calibrate_dlt;
use crate::error::{FitError, Result};

/// Stripe intensity profile across one projector period.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub enum StripeProfile {
    /// s = ½ + ½ cos(2π y_p/Λ_p).
    #[default]
    Cosine,
    /// s = ½ + ½ tanh(κ cos(2π y_p/Λ_p))/tanh κ, a softened square wave.
    Square {
        /// Softness κ (> 0; large = sharp).
        softness: f64,
    },
}

/// The stripe projector.
#[derive(Clone, Debug, PartialEq)]
pub struct Projector {
    /// Its pinhole model (rows y_p of its image are the stripe phase).
    pub camera: Camera,
    /// Stripe period Λ_p in projector pixels.
    pub stripe_period_px: f64,
    /// Stripe profile.
    pub profile: StripeProfile,
}

impl Projector {
    /// Stripe intensity s(X) ∈ [0, 1] at world point `x` (0 behind the projector).
    pub fn stripe(&self, x: &Pt3) -> f64 {
        let h = self.camera.homogeneous(x);
        if !(h.z > 0.0) {
            return 0.0;
        }
        let c = (std::f64::consts::TAU * (h.y / h.z) / self.stripe_period_px).cos();
        match self.profile {
            StripeProfile::Cosine => 0.5 + 0.5 * c,
            StripeProfile::Square { softness } => 0.5 + 0.5 * (softness * c).tanh() / softness.tanh(),
        }
    }
}

/// Camera, projector and timing of a capture.
#[derive(Clone, Debug, PartialEq)]
pub struct Rig {
    /// The (distortion-free) camera that renders simulations and that footage is resampled to.
    pub camera: Camera,
    /// Lens distortion of the real camera (footage is undistorted once at load).
    pub distortion: Option<Distortion>,
    /// The stripe projector.
    pub projector: Projector,
    /// Frame rate (frames/s).
    pub fps: f64,
    /// Unit up vector; gravity is −9.81·world_up (m/s²).
    pub world_up: Vec3,
    /// Time of frame 0 on the corner tracks' clock (s).
    pub time_offset_s: f64,
}

/// Findings of the rig check at setup.
#[derive(Clone, Debug, PartialEq)]
pub struct RigCheck {
    /// Predicted stripe period in the camera image at the swatch (px).
    pub stripe_period_img_px: f64,
    /// Warnings (e.g. the projector baseline parallel to the stripes).
    pub warnings: Vec<String>,
}

/// Smallest image stripe period accepted without `allow_fine_stripes` (px, spec §8).
pub const MIN_STRIPE_PERIOD_PX: f64 = 5.0;

impl Rig {
    /// Gravity (m/s²).
    pub fn gravity(&self) -> Vec3 {
        -9.81 * self.world_up
    }

    /// Stripe period in the camera image (px) at the surface point `x` with unit normal `n`:
    /// the plane through `x` maps camera pixels to projector pixels (a homography through the
    /// plane); the period is Λ_p / |∇_u y_p| there (spec §4.3, T5).
    pub fn stripe_period_at(&self, x: &Pt3, n: &Vec3) -> Option<f64> {
        let (u0, _) = self.camera.project(x)?;
        let cc = self.camera.center()?;
        let hit = |u: Pt2| -> Option<f64> {
            // Ray from the camera centre through pixel u, intersected with the plane.
            let far = backproject(&self.camera, u, 1.0)?;
            let d = far - cc;
            let denom = d.dot(n);
            if denom.abs() < 1e-15 {
                return None;
            }
            let s = (x - cc).dot(n) / denom;
            let p = cc + s * d;
            let (pp, _) = self.projector.camera.project(&p)?;
            Some(pp.y)
        };
        let e = 0.5;
        let gx = (hit(u0 + nalgebra::Vector2::new(e, 0.0))? - hit(u0 - nalgebra::Vector2::new(e, 0.0))?) / (2.0 * e);
        let gy = (hit(u0 + nalgebra::Vector2::new(0.0, e))? - hit(u0 - nalgebra::Vector2::new(0.0, e))?) / (2.0 * e);
        let g = (gx * gx + gy * gy).sqrt();
        (g > 0.0).then(|| self.projector.stripe_period_px / g)
    }

    /// The setup check of spec §8 at the swatch point `x` with normal `n`: the stripe period in
    /// the image must be ≥ 5 px (else [`FitError::StripesUnderResolved`] unless `allow_fine`),
    /// and a projector baseline parallel to the stripes gives a warning.
    pub fn check(&self, x: &Pt3, n: &Vec3, allow_fine: bool) -> Result<RigCheck> {
        let period = self
            .stripe_period_at(x, n)
            .ok_or_else(|| FitError::BadParameter("the swatch is not visible to both camera and projector".into()))?;
        if period < MIN_STRIPE_PERIOD_PX && !allow_fine {
            return Err(FitError::StripesUnderResolved { period_px: period, min_px: MIN_STRIPE_PERIOD_PX });
        }
        let mut warnings = Vec::new();
        if let (Some(cc), Some(cp)) = (self.camera.center(), self.projector.camera.center()) {
            let base = cp - cc;
            // Stripes run along the projector's image x axis (its rows).
            let stripe_dir = self.projector.camera.view_rotation().row(0).transpose();
            let cos = base.normalize().dot(&stripe_dir).abs();
            if base.norm() == 0.0 || cos > 0.95 {
                warnings.push(format!(
                    "projector baseline is (nearly) parallel to the stripes (|cos| = {cos:.3}): stripes carry no shape information"
                ));
            }
        }
        Ok(RigCheck { stripe_period_img_px: period, warnings })
    }
}

/// A camera in a scene or calibration file.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum CameraSpec {
    /// A camera at `eye` looking at `target` (square pixels, centred principal point).
    LookAt {
        /// Centre (m).
        eye: Pt3,
        /// Look-at point (m).
        target: Pt3,
        /// Up direction of the image.
        up: Vec3,
        /// Vertical field of view (degrees).
        fov_y_deg: f64,
        /// Image width (px).
        width: u32,
        /// Image height (px).
        height: u32,
    },
    /// A 3×4 projection matrix, rows first.
    Matrix {
        /// P, row-major.
        p: [[f64; 4]; 3],
        /// Image width (px).
        width: u32,
        /// Image height (px).
        height: u32,
        /// Optional lens distortion.
        #[serde(default)]
        distortion: Option<Distortion>,
    },
    /// Marker correspondences solved by the DLT ([`calibrate_dlt`]).
    Markers {
        /// World positions (m).
        world: Vec<Pt3>,
        /// Pixel positions (OpenCV convention).
        image: Vec<Pt2>,
        /// Image width (px).
        width: u32,
        /// Image height (px).
        height: u32,
        /// Optional lens distortion (applied to the marker pixels' undistortion first).
        #[serde(default)]
        distortion: Option<Distortion>,
    },
}

impl CameraSpec {
    /// Builds the camera; returns it with its distortion and the DLT's RMS reprojection error
    /// (0 for analytic cameras).
    pub fn build(&self) -> Result<(Camera, Option<Distortion>, f64)> {
        match self {
            CameraSpec::LookAt { eye, target, up, fov_y_deg, width, height } => {
                Ok((Camera::look_at(eye, target, up, *fov_y_deg, *width, *height)?, None, 0.0))
            }
            CameraSpec::Matrix { p, width, height, distortion } => {
                if *width == 0 || *height == 0 || p.iter().flatten().any(|v| !v.is_finite()) {
                    return Err(FitError::BadParameter("camera matrix: zero size or non-finite entries".into()));
                }
                let m = Mat34::from_fn(|r, c| p[r][c]);
                Ok((Camera { p: m, width: *width, height: *height }, *distortion, 0.0))
            }
            CameraSpec::Markers { world, image, width, height, distortion } => {
                let (cam, rms) = calibrate_dlt(world, image, *width, *height)?;
                Ok((cam, *distortion, rms))
            }
        }
    }

    /// The spec of an existing camera as a matrix.
    pub fn from_camera(c: &Camera, distortion: Option<Distortion>) -> Self {
        let p = [0, 1, 2].map(|r| [0, 1, 2, 3].map(|k| c.p[(r, k)]));
        CameraSpec::Matrix { p, width: c.width, height: c.height, distortion }
    }
}

/// The projector in a scene or calibration file.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ProjectorSpec {
    /// Its pinhole model.
    pub camera: CameraSpec,
    /// Stripe period Λ_p (projector pixels).
    pub stripe_period_px: f64,
    /// Stripe profile.
    #[serde(default)]
    pub profile: StripeProfile,
}

/// A rig in a scene file, or the calibration file `rig.ron` of real footage (spec §3.4).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RigSpec {
    /// The camera.
    pub camera: CameraSpec,
    /// The projector.
    pub projector: ProjectorSpec,
    /// Frames per second.
    pub fps: f64,
    /// Up direction (gravity = −9.81·world_up).
    pub world_up: Vec3,
    /// Time of frame 0 on the corner tracks' clock (s).
    #[serde(default)]
    pub time_offset_s: f64,
}

/// A built rig with the calibration residuals of its DLT solves.
#[derive(Clone, Debug, PartialEq)]
pub struct BuiltRig {
    /// The rig.
    pub rig: Rig,
    /// RMS reprojection error of the camera's DLT (px; 0 if analytic).
    pub camera_rms_px: f64,
    /// RMS reprojection error of the projector's DLT (px; 0 if analytic).
    pub projector_rms_px: f64,
}

impl RigSpec {
    /// Builds the rig (running the DLT for `Markers` cameras). Errors: invalid fps, up vector,
    /// stripe period or profile; calibration errors.
    pub fn build(&self) -> Result<BuiltRig> {
        if !(self.fps > 0.0 && self.fps.is_finite()) {
            return Err(FitError::BadParameter(format!("fps must be > 0, got {}", self.fps)));
        }
        let up = self
            .world_up
            .try_normalize(1e-12)
            .ok_or_else(|| FitError::BadParameter("world_up must be a non-zero finite vector".into()))?;
        if !(self.projector.stripe_period_px > 0.0 && self.projector.stripe_period_px.is_finite()) {
            return Err(FitError::BadParameter(format!(
                "stripe_period_px must be > 0, got {}",
                self.projector.stripe_period_px
            )));
        }
        if let StripeProfile::Square { softness } = self.projector.profile {
            if !(softness > 0.0 && softness.is_finite()) {
                return Err(FitError::BadParameter(format!("square stripe softness must be > 0, got {softness}")));
            }
        }
        if !self.time_offset_s.is_finite() {
            return Err(FitError::BadParameter("time_offset_s is not finite".into()));
        }
        let (camera, distortion, camera_rms_px) = self.camera.build()?;
        let (pcam, _, projector_rms_px) = self.projector.camera.build()?;
        Ok(BuiltRig {
            rig: Rig {
                camera,
                distortion,
                projector: Projector {
                    camera: pcam,
                    stripe_period_px: self.projector.stripe_period_px,
                    profile: self.projector.profile,
                },
                fps: self.fps,
                world_up: up,
                time_offset_s: self.time_offset_s,
            },
            camera_rms_px,
            projector_rms_px,
        })
    }
}

/// Reads a calibration file (RON [`RigSpec`]) and builds the rig (spec §3.4 `load_rig`).
/// Errors name the file (and the line and column for syntax errors).
pub fn load_rig(path: &Path) -> Result<BuiltRig> {
    let text =
        std::fs::read_to_string(path).map_err(|e| FitError::Io { path: path.to_path_buf(), msg: e.to_string() })?;
    let spec: RigSpec = ron::Options::default()
        .with_default_extension(ron::extensions::Extensions::IMPLICIT_SOME)
        .from_str(&text)
        .map_err(|e| FitError::Parse {
            path: path.to_path_buf(),
            line: e.span.start.line,
            col: e.span.start.col,
            msg: e.code.to_string(),
        })?;
    spec.build().map_err(|e| match e {
        FitError::BadParameter(m) => FitError::BadParameter(format!("{}: {m}", path.display())),
        FitError::DegenerateCalibration(m) => FitError::DegenerateCalibration(format!("{}: {m}", path.display())),
        other => other,
    })
}

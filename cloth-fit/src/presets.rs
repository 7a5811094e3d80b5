//! The paper's fabrics and calibration setups, as synthetic truths (spec §4.1, §4.3, §4.6,
//! §4.7; all values ours: the seed has no fitted values, ranges or rig dimensions).
//!
//! Bhat et al. (2003, §5) used linen, fleece, satin and knit; a static test with two corner
//! separations, a waving test with two trials, and 150-frame validation sequences driven by a
//! robot arm along a sinusoid.

use geom_core::math::{Pt3, Vec3};
use serde::{Deserialize, Serialize};

use crate::forward::{Integrator, SimOptions};
use crate::params::{DragParams, FabricParams, ParamId, ParamRange, Scale};
use crate::rig::{CameraSpec, ProjectorSpec, RigSpec, StripeProfile};
use crate::setup::{Experiment, ExperimentKind, SettleProtocol, Swatch};
use crate::trajectory::CornerMotion;

/// The four synthetic fabrics (spec §4.6; bending lengths 1.3–3.1 cm).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
pub enum FabricPreset {
    /// Stiff woven linen.
    Linen,
    /// Soft, heavy fleece.
    Fleece,
    /// Light, flowing satin.
    Satin,
    /// Stretchy knit.
    Knit,
}

impl FabricPreset {
    /// All four, in the paper's order.
    pub const ALL: [FabricPreset; 4] =
        [FabricPreset::Linen, FabricPreset::Fleece, FabricPreset::Satin, FabricPreset::Knit];

    /// Lower-case name (summary-key suffix).
    pub fn name(self) -> &'static str {
        match self {
            FabricPreset::Linen => "linen",
            FabricPreset::Fleece => "fleece",
            FabricPreset::Satin => "satin",
            FabricPreset::Knit => "knit",
        }
    }

    /// Areal density ρ (kg/m²).
    pub fn areal_density(self) -> f64 {
        match self {
            FabricPreset::Linen => 0.17,
            FabricPreset::Fleece => 0.25,
            FabricPreset::Satin => 0.10,
            FabricPreset::Knit => 0.22,
        }
    }

    /// The true parameters (spec §4.6).
    pub fn params(self) -> FabricParams {
        let (stretch, shear, bend, bs, bsh, bb, k_n, k_t, k_f) = match self {
            FabricPreset::Linen => (1500.0, 150.0, 5e-5, 2e-3, 2e-3, 1e-2, 1.0, 0.05, 1.0),
            FabricPreset::Fleece => (400.0, 40.0, 2e-5, 5e-3, 5e-3, 2e-2, 1.5, 0.10, 2.0),
            FabricPreset::Satin => (800.0, 30.0, 2e-6, 1e-3, 1e-3, 5e-3, 0.6, 0.02, 0.5),
            FabricPreset::Knit => (60.0, 12.0, 1e-5, 1e-2, 1e-2, 2e-2, 1.2, 0.08, 3.0),
        };
        FabricParams {
            stretch,
            shear,
            bend,
            stretch_damp: bs,
            shear_damp: bsh,
            bend_damp: bb,
            drag: DragParams { k_n, k_t, k_f },
        }
    }

    /// The 0.5 m × 0.5 m swatch of this fabric.
    pub fn swatch(self) -> Swatch {
        Swatch { width: 0.5, height: 0.5, areal_density: self.areal_density() }
    }
}

/// The search ranges of spec §4.1.
pub fn default_ranges() -> Vec<ParamRange> {
    let r = |id, lo, hi, scale| ParamRange { id, lo, hi, scale };
    vec![
        r(ParamId::Stretch, 10.0, 5000.0, Scale::Log),
        r(ParamId::Shear, 1.0, 500.0, Scale::Log),
        r(ParamId::Bend, 1e-7, 3e-4, Scale::Log),
        r(ParamId::StretchDamp, 1e-5, 1e-1, Scale::Log),
        r(ParamId::ShearDamp, 1e-5, 1e-1, Scale::Log),
        r(ParamId::BendDamp, 1e-5, 1e-1, Scale::Log),
        r(ParamId::DragN, 0.0, 4.0, Scale::Linear),
        r(ParamId::DragT, 0.0, 0.5, Scale::Linear),
        r(ParamId::DragF, 0.0, 10.0, Scale::Linear),
    ]
}

/// Drag at the midpoint of its range: the paper fixed the drag "to the mid point of their range
/// of values" in the static test.
pub fn drag_midpoint() -> DragParams {
    DragParams { k_n: 2.0, k_t: 0.25, k_f: 5.0 }
}

/// Static trial `k` (0 or 1: separations 0.40 m and 0.30 m) with `frames` frames.
pub fn static_trial(f: FabricPreset, k: usize, frames: usize) -> Experiment {
    let separation = if k == 0 { 0.40 } else { 0.30 };
    Experiment {
        kind: ExperimentKind::Static { separation },
        swatch: f.swatch(),
        frames,
        settle: SettleProtocol::default(),
    }
}

/// Waving trial `k` (spec §4.7): trial 0 at 0.40 m, amplitude (0.08, 0.12, 0) m at 1 Hz; trial 1
/// at 0.35 m, (0.06, 0.15, 0) m at 1.25 Hz; 90° between x and y, 0.25 s ramp.
pub fn waving_trial(f: FabricPreset, k: usize, frames: usize) -> Experiment {
    let (separation, amplitude, freq_hz) =
        if k == 0 { (0.40, Vec3::new(0.08, 0.12, 0.0), 1.0) } else { (0.35, Vec3::new(0.06, 0.15, 0.0), 1.25) };
    Experiment {
        kind: ExperimentKind::Waving {
            separation,
            moving: CornerMotion::Sinusoid { amplitude, freq_hz, phase_deg: 90.0, ramp_s: 0.25 },
        },
        swatch: f.swatch(),
        frames,
        settle: SettleProtocol::default(),
    }
}

/// The held-out "robot" sequence (spec §4.7): separation 0.40 m, out-of-plane sinusoid of
/// 0.18 m at 0.8 Hz.
pub fn validation_trial(f: FabricPreset, frames: usize) -> Experiment {
    Experiment {
        kind: ExperimentKind::Waving {
            separation: 0.40,
            moving: CornerMotion::Sinusoid {
                amplitude: Vec3::new(0.0, 0.18, 0.0),
                freq_hz: 0.8,
                phase_deg: 0.0,
                ramp_s: 0.25,
            },
        },
        swatch: f.swatch(),
        frames,
        settle: SettleProtocol::default(),
    }
}

/// Image period of the stripes the default rig is designed for (px, spec §4.2).
pub const STRIPE_PERIOD_IMG_PX: f64 = 8.0;

/// The rig of spec §4.3 at image size `width × height`: camera 1.2 m in front of the swatch
/// (vertical FOV 33.4°), projector 0.35 m above it (1024 × 768, FOV 40°). The projector's
/// stripe period is Λ_p = 21 px at 320 × 240 and scales with 320/width, so that the stripes
/// stay ≈ 8 px in every image size.
pub fn rig_spec(width: u32, height: u32) -> RigSpec {
    let target = Pt3::new(0.0, 0.0, -0.2);
    RigSpec {
        camera: CameraSpec::LookAt {
            eye: Pt3::new(0.0, -1.2, 0.0),
            target,
            up: Vec3::z(),
            fov_y_deg: 33.4,
            width,
            height,
        },
        projector: ProjectorSpec {
            camera: CameraSpec::LookAt {
                eye: Pt3::new(0.0, -1.1, 0.35),
                target,
                up: Vec3::z(),
                fov_y_deg: 40.0,
                width: 1024,
                height: 768,
            },
            stripe_period_px: 21.0 * 320.0 / width as f64,
            profile: StripeProfile::Cosine,
        },
        fps: 30.0,
        world_up: Vec3::z(),
        time_offset_s: 0.0,
    }
}

/// The fitting model of spec §4.5: res 12, dt = 1/240 s, backward Euler.
pub fn fit_model() -> SimOptions {
    SimOptions {
        res: 12,
        dt: 1.0 / 240.0,
        integrator: Integrator::BackwardEuler,
        collisions: Default::default(),
        render_subdivision: 0,
        implicit_drag: false,
    }
}

/// The mismatched truth model of spec §3.11: res 24, dt = 1/480 s, BDF2.
pub fn truth_model() -> SimOptions {
    SimOptions { res: 24, dt: 1.0 / 480.0, integrator: Integrator::Bdf2, ..fit_model() }
}

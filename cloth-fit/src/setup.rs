//! The calibration experiments (Bhat et al. 2003 §5: "a static test and a waving test" on a
//! small swatch; spec §2 `Experiment`, §3.2 boundary conditions and settle protocol, §4.7).
//!
//! A swatch of `width × height` metres hangs from its two top corners in a vertical plane. In
//! the static test both corners are held at a given separation; in the waving test one corner
//! is moved back and forth; a tracked experiment (real footage) moves both corners along
//! measured paths. Every experiment starts with the same deterministic settle protocol, so that
//! the initial conditions are identical for the truth and the fit (the paper "carefully
//! controlled" them).

use geom_core::math::{Pt3, Vec3};
use serde::{Deserialize, Serialize};

use crate::error::{FitError, Result};
use crate::trajectory::{CornerMotion, Trajectory};

/// The fabric sample (measured, never fitted: the paper measured mass and dimensions).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Swatch {
    /// Width along the top edge (m).
    pub width: f64,
    /// Height (m).
    pub height: f64,
    /// Areal density ρ (kg/m²).
    pub areal_density: f64,
}

/// What the corners do.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum ExperimentKind {
    /// Both top corners held at `separation` (m) apart (paper: static test).
    Static {
        /// Corner distance (m).
        separation: f64,
    },
    /// Corner 0 fixed, corner 1 follows `moving` from its settled position (paper: waving
    /// test).
    Waving {
        /// Corner distance while settling (m).
        separation: f64,
        /// Motion of corner 1 from t = 0 (the first frame).
        moving: CornerMotion,
    },
    /// Both corners follow measured paths (real footage, spec §3.4).
    Tracked {
        /// Paths of corner 0 and corner 1 in world coordinates.
        corners: [Trajectory; 2],
        /// Time of frame 0 on the paths' clock (s): the calibration's `time_offset_s`.
        start_s: f64,
    },
}

/// The deterministic settle protocol (spec §3.2, ours).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SettleProtocol {
    /// Symmetry-breaking out-of-plane bulge toward the camera (m), a half-sine in u and v.
    pub bulge_m: f64,
    /// Time over which the corners move from full width to their targets (s), smoothstep.
    pub move_s: f64,
    /// Settling time with the extra mass damping (s).
    pub settle_s: f64,
    /// Longest settling time (s); beyond it the result is flagged `NotSettled`.
    pub max_s: f64,
    /// Extra mass-proportional damping α_settle while settling (1/s).
    pub alpha: f64,
    /// Kinetic energy per unit mass below which the sheet counts as settled (m²/s²).
    pub ke_per_mass: f64,
    /// Quasi-static relaxation after the settle (ours): this many backward-Euler steps of
    /// `relax_dt`, which converge to the static equilibrium (a fixed point that does not depend
    /// on damping or drag), so the settled shape is a function of the stiffnesses alone.
    pub relax_steps: usize,
    /// Step of the relaxation (s).
    pub relax_dt: f64,
    /// Rayleigh β of every term while settling and relaxing (s), in place of the fabric's own
    /// damping; drag is at the middle of its range while settling. The hanging swatch has more
    /// than one equilibrium (its folds can buckle either way), and with the fabric's own
    /// damping the branch reached depended on damping: linen at 160 × 120 jumped between two
    /// shapes 72 silhouette pixels apart for ±5 % of one β (`static_landscape` example). With
    /// a fixed settle damping the settled shape is a function of the stiffnesses alone.
    pub damping: f64,
    /// Quasi-static continuation (ours; 0 = the dynamic settle of spec §3.2): the corners move
    /// to their targets in this many backward-Euler steps of `move_s / quasi_static_steps`,
    /// every step starting from rest (velocities reset to zero), i.e. a sequence of
    /// mass-regularised equilibrium solves that follows one equilibrium branch continuously;
    /// the relaxation steps then also start from rest and stop once no vertex moves more than
    /// `relax_tol_m`. The dynamic settle's swinging and its 2.5 s of small steps are skipped:
    /// the settled shape is a continuous function of the stiffnesses between the branch's
    /// bifurcation points, and it costs tens of solves instead of hundreds.
    pub quasi_static_steps: usize,
    /// Convergence tolerance of the quasi-static relaxation (m): the largest vertex move of
    /// one relaxation step below which it stops (only with `quasi_static_steps > 0`).
    pub relax_tol_m: f64,
}

impl Default for SettleProtocol {
    /// 10 mm bulge (2 mm left fleece's bend unidentifiable at 160 × 120: ±20 % of bend
    /// changed E by 0.001, one fold pixel; 10 mm gives a graded response, `static_landscape`),
    /// 0.5 s corner move, settle damping β = 1e-3 s (the log-centre of its range), α = 5 s⁻¹;
    /// the dynamic settle of spec §3.2: 2.5 s (max 4 s) at the model's dt down to 1e-8 m²/s²,
    /// then 40 relaxation steps of 1 s. The quasi-static continuation (`quasi_static_steps` = 5,
    /// `relax_tol_m` = 1e-7 m) is an option, not the default: it is 6–15× cheaper and smooths
    /// the landscape (`static_landscape` at 160 × 120: linen's E ≤ 1 for ±20 % of bend), but it
    /// does so by making the static image nearly blind to bend — spec T19 fails with it (+20 %
    /// bend changes E by 0.001 at 96 × 72, `tests/tests/cloth_fit_forward.rs`) — and its drape
    /// depends on the mesh resolution (T20: 1.36 cm between res 12 and 24, against ≤ 1 cm).
    fn default() -> Self {
        Self {
            bulge_m: 0.01,
            move_s: 0.5,
            settle_s: 2.5,
            max_s: 4.0,
            alpha: 5.0,
            ke_per_mass: 1e-8,
            relax_steps: 40,
            relax_dt: 1.0,
            damping: 1e-3,
            quasi_static_steps: 0,
            relax_tol_m: 1e-7,
        }
    }
}

/// One calibration experiment (one trial).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Experiment {
    /// Corner conditions.
    pub kind: ExperimentKind,
    /// The swatch.
    pub swatch: Swatch,
    /// Number of frames compared (the paper: the first 50 frames; static: 5).
    pub frames: usize,
    /// Settle protocol.
    #[serde(default)]
    pub settle: SettleProtocol,
}

impl Experiment {
    /// Checks every value before any simulation.
    pub fn validate(&self) -> Result<()> {
        let s = &self.swatch;
        if !(s.width > 0.0
            && s.height > 0.0
            && s.areal_density > 0.0
            && s.width.is_finite()
            && s.height.is_finite()
            && s.areal_density.is_finite())
        {
            return Err(FitError::BadParameter(format!(
                "swatch: width, height and areal density must be finite and > 0, got {s:?}"
            )));
        }
        if self.frames == 0 {
            return Err(FitError::BadParameter("experiment: frames must be ≥ 1".into()));
        }
        let p = &self.settle;
        let ok = p.bulge_m.is_finite()
            && p.move_s >= 0.0
            && p.settle_s >= p.move_s
            && p.max_s >= p.settle_s
            && p.alpha >= 0.0
            && p.ke_per_mass >= 0.0
            && p.max_s.is_finite()
            && p.relax_dt > 0.0
            && p.relax_dt.is_finite()
            && p.relax_steps <= 1000
            && p.damping >= 0.0
            && p.damping.is_finite()
            && p.quasi_static_steps <= 10_000
            && p.relax_tol_m >= 0.0
            && p.relax_tol_m.is_finite();
        if !ok {
            return Err(FitError::BadParameter(format!("settle protocol out of range: {p:?}")));
        }
        match &self.kind {
            ExperimentKind::Static { separation } | ExperimentKind::Waving { separation, .. } => {
                if !(*separation > 0.0 && *separation <= s.width) {
                    return Err(FitError::BadParameter(format!(
                        "corner separation {separation} m must be in (0, width = {}]",
                        s.width
                    )));
                }
            }
            ExperimentKind::Tracked { corners, start_s } => {
                for c in corners {
                    c.validate()?;
                }
                if !start_s.is_finite() {
                    return Err(FitError::BadParameter("tracked experiment: start time not finite".into()));
                }
            }
        }
        if let ExperimentKind::Waving { moving, .. } = &self.kind {
            moving.validate()?;
        }
        Ok(())
    }

    /// Positions of the two top corners at frame 0 (m). Static and waving experiments place
    /// them at (∓separation/2, 0, 0): the swatch hangs in the plane y = 0 with its top edge on
    /// the x axis.
    pub fn corner_targets(&self) -> [Pt3; 2] {
        match &self.kind {
            ExperimentKind::Static { separation } | ExperimentKind::Waving { separation, .. } => {
                [Pt3::new(-0.5 * separation, 0.0, 0.0), Pt3::new(0.5 * separation, 0.0, 0.0)]
            }
            ExperimentKind::Tracked { corners, start_s } => [corners[0].at(*start_s), corners[1].at(*start_s)],
        }
    }

    /// Position of corner `i` at time `t` ≥ 0 after frame 0 (s).
    pub fn corner_at(&self, i: usize, t: f64) -> Pt3 {
        let target = self.corner_targets()[i];
        match &self.kind {
            ExperimentKind::Static { .. } => target,
            ExperimentKind::Waving { moving, .. } => {
                if i == 1 {
                    target + moving.at(t)
                } else {
                    target
                }
            }
            ExperimentKind::Tracked { corners, start_s } => corners[i].at(start_s + t),
        }
    }

    /// True when the corners move after frame 0 (waving and tracked experiments).
    pub fn is_dynamic(&self) -> bool {
        !matches!(self.kind, ExperimentKind::Static { .. })
    }

    /// The rest frame of the swatch: `(top-edge midpoint, unit horizontal axis from corner 0 to
    /// corner 1, unit up)`, the vertical plane through the two frame-0 corners. Errors when the
    /// corners coincide in the horizontal plane.
    pub fn swatch_frame(&self, world_up: &Vec3) -> Result<(Pt3, Vec3, Vec3)> {
        let up = world_up
            .try_normalize(1e-12)
            .ok_or_else(|| FitError::BadParameter("world_up must be a non-zero vector".into()))?;
        let [c0, c1] = self.corner_targets();
        let d = c1 - c0;
        let horiz = d - up * d.dot(&up);
        let e_u = horiz
            .try_normalize(1e-9)
            .ok_or_else(|| FitError::BadParameter("the two top corners are vertically aligned or coincide".into()))?;
        let top = Pt3::from((c0.coords + c1.coords) * 0.5);
        let mid = top + up * ((c0 - top).dot(&up));
        Ok((mid, e_u, up))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sw() -> Swatch {
        Swatch { width: 0.5, height: 0.5, areal_density: 0.17 }
    }

    #[test]
    fn corners_and_validation() {
        let e = Experiment {
            kind: ExperimentKind::Waving {
                separation: 0.4,
                moving: CornerMotion::Sinusoid {
                    amplitude: Vec3::new(0.08, 0.12, 0.0),
                    freq_hz: 1.0,
                    phase_deg: 90.0,
                    ramp_s: 0.25,
                },
            },
            swatch: sw(),
            frames: 50,
            settle: SettleProtocol::default(),
        };
        e.validate().unwrap();
        assert_eq!(e.corner_targets()[1], Pt3::new(0.2, 0.0, 0.0));
        assert_eq!(e.corner_at(0, 1.0), Pt3::new(-0.2, 0.0, 0.0));
        assert!(e.corner_at(1, 1.0) != Pt3::new(0.2, 0.0, 0.0));
        let (m, eu, up) = e.swatch_frame(&Vec3::z()).unwrap();
        assert_eq!((m, eu, up), (Pt3::origin(), Vec3::x(), Vec3::z()));
        let mut bad = e.clone();
        bad.kind = ExperimentKind::Static { separation: 0.6 };
        assert!(bad.validate().is_err());
        let mut bad = e.clone();
        bad.frames = 0;
        assert!(bad.validate().is_err());
    }
}

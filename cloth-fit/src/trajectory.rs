//! Prescribed corner paths (spec §2 `Trajectory`, `CornerMotion`; §3.2 boundary conditions).
//!
//! The paper measured the two top corners with a Vicon system and drove the validation runs
//! with a robot arm along a sinusoid (Bhat et al. 2003 §5); here the corners follow either a
//! fixed point, a ramped sinusoid, or samples interpolated by Catmull–Rom in time.

use geom_core::math::{catmull_rom, smoothstep, Pt3, Vec3};
use serde::{Deserialize, Serialize};

use crate::error::{FitError, Result};

/// A corner's absolute path in world coordinates (m), as a function of time (s).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum Trajectory {
    /// Stays at one point.
    Fixed(Pt3),
    /// `start + ramp(t) · motion(t)` with the motion of [`CornerMotion::Sinusoid`].
    Sinusoid {
        /// Position at t = 0 (m).
        start: Pt3,
        /// Amplitude per axis (m).
        amplitude: Vec3,
        /// Frequency (Hz).
        freq_hz: f64,
        /// Phase of the y and z components relative to x (degrees).
        phase_deg: f64,
        /// Smoothstep amplitude ramp (s).
        ramp_s: f64,
    },
    /// Samples `(t, position)` sorted by time; Catmull–Rom between them, the end values held
    /// outside.
    Samples(Vec<(f64, Pt3)>),
}

impl Trajectory {
    /// Position at time `t` (s).
    pub fn at(&self, t: f64) -> Pt3 {
        match self {
            Trajectory::Fixed(p) => *p,
            Trajectory::Sinusoid { start, amplitude, freq_hz, phase_deg, ramp_s } => {
                start + sinusoid(*amplitude, *freq_hz, *phase_deg, *ramp_s, t)
            }
            Trajectory::Samples(s) => catmull_rom(s, t),
        }
    }

    /// Time range covered by samples (`None` for analytic paths).
    pub fn sample_range(&self) -> Option<(f64, f64)> {
        match self {
            Trajectory::Samples(s) => Some((s.first()?.0, s.last()?.0)),
            _ => None,
        }
    }

    /// Checks finiteness and sample order.
    pub fn validate(&self) -> Result<()> {
        let bad = |m: String| Err(FitError::BadParameter(m));
        match self {
            Trajectory::Fixed(p) => {
                if p.iter().any(|c| !c.is_finite()) {
                    return bad("fixed corner position is not finite".into());
                }
            }
            Trajectory::Sinusoid { start, amplitude, freq_hz, phase_deg, ramp_s } => {
                if start.iter().chain(amplitude.iter()).any(|c| !c.is_finite())
                    || !freq_hz.is_finite()
                    || !phase_deg.is_finite()
                    || !(*ramp_s >= 0.0)
                {
                    return bad("sinusoid corner path: non-finite values or negative ramp".into());
                }
            }
            Trajectory::Samples(s) => {
                if s.is_empty() {
                    return bad("corner path without samples".into());
                }
                for (i, (t, p)) in s.iter().enumerate() {
                    if !t.is_finite() || p.iter().any(|c| !c.is_finite()) {
                        return bad(format!("corner sample {i} is not finite"));
                    }
                    if i > 0 && *t <= s[i - 1].0 {
                        return bad(format!("corner sample {i}: time {t} not after {}", s[i - 1].0));
                    }
                }
            }
        }
        Ok(())
    }
}

/// Motion of the moving corner relative to its settled position (spec §2 `CornerMotion`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum CornerMotion {
    /// d(t) = s(t/ramp) · (A_x sin ωt, A_y sin(ωt + φ), A_z sin(ωt + φ)), ω = 2π f, s the
    /// smoothstep, so that position and velocity start at zero and the acceleration is finite.
    Sinusoid {
        /// Amplitude per axis (m).
        amplitude: Vec3,
        /// Frequency (Hz).
        freq_hz: f64,
        /// Phase of the y and z components relative to x (degrees).
        phase_deg: f64,
        /// Amplitude ramp (s).
        ramp_s: f64,
    },
    /// Displacement samples `(t, d)` (Catmull–Rom, end values held).
    Samples(Vec<(f64, Vec3)>),
}

impl CornerMotion {
    /// Displacement at `t` ≥ 0 (s) from the settled position (m).
    pub fn at(&self, t: f64) -> Vec3 {
        match self {
            CornerMotion::Sinusoid { amplitude, freq_hz, phase_deg, ramp_s } => {
                sinusoid(*amplitude, *freq_hz, *phase_deg, *ramp_s, t)
            }
            CornerMotion::Samples(s) => {
                if s.is_empty() {
                    Vec3::zeros()
                } else {
                    catmull_rom(s, t)
                }
            }
        }
    }

    /// Checks finiteness.
    pub fn validate(&self) -> Result<()> {
        match self {
            CornerMotion::Sinusoid { amplitude, freq_hz, phase_deg, ramp_s } => {
                if amplitude.iter().any(|c| !c.is_finite())
                    || !freq_hz.is_finite()
                    || !phase_deg.is_finite()
                    || !(*ramp_s >= 0.0)
                {
                    return Err(FitError::BadParameter("corner motion: non-finite values or negative ramp".into()));
                }
            }
            CornerMotion::Samples(s) => {
                for (i, (t, d)) in s.iter().enumerate() {
                    if !t.is_finite() || d.iter().any(|c| !c.is_finite()) || (i > 0 && *t <= s[i - 1].0) {
                        return Err(FitError::BadParameter(format!("corner motion sample {i} invalid")));
                    }
                }
            }
        }
        Ok(())
    }
}

fn sinusoid(a: Vec3, f: f64, phase_deg: f64, ramp: f64, t: f64) -> Vec3 {
    if t <= 0.0 {
        return Vec3::zeros();
    }
    let w = std::f64::consts::TAU * f;
    let ph = phase_deg.to_radians();
    let r = if ramp > 0.0 { smoothstep(0.0, ramp, t) } else { 1.0 };
    r * Vec3::new(a.x * (w * t).sin(), a.y * (w * t + ph).sin(), a.z * (w * t + ph).sin())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sinusoid_starts_at_rest_and_samples_hold_their_ends() {
        let m = CornerMotion::Sinusoid {
            amplitude: Vec3::new(0.08, 0.12, 0.0),
            freq_hz: 1.0,
            phase_deg: 90.0,
            ramp_s: 0.25,
        };
        assert_eq!(m.at(0.0), Vec3::zeros());
        // Velocity at 0⁺ is ~0 thanks to the smoothstep ramp (the y term starts at cos 0 = 1).
        let h = 1e-6;
        assert!(m.at(h).norm() / h < 1e-4);
        // After the ramp the plain sinusoid.
        let t = 0.6;
        let w = std::f64::consts::TAU;
        assert!((m.at(t) - Vec3::new(0.08 * (w * t).sin(), 0.12 * (w * t).cos(), 0.0)).norm() < 1e-15);
        let s = Trajectory::Samples(vec![(0.0, Pt3::new(0.0, 0.0, 0.0)), (1.0, Pt3::new(1.0, 0.0, 0.0))]);
        assert_eq!(s.at(-1.0), Pt3::origin());
        assert_eq!(s.at(5.0), Pt3::new(1.0, 0.0, 0.0));
        assert!((s.at(0.5).x - 0.5).abs() < 1e-15);
        assert!(Trajectory::Samples(vec![(1.0, Pt3::origin()), (0.5, Pt3::origin())]).validate().is_err());
    }
}

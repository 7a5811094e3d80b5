//! Prescribed rigid motion over time: [`KinematicPath`], shared by moving obstacles and pinned
//! vertex sets (shells, tracks) and by flip-tet's moving obstacles.
//!
//! A path maps the rest placement of a rigid set to its placement at time t: a point p₀ is at
//! `path.transform(t) * p₀`. Paths compose, start late, or follow keyframes, so a scene can
//! twist, pull or carry cloth and spin, slide or lift obstacles.
//!
//! ```
//! use geom_core::kinematic::KinematicPath;
//! use geom_core::math::{Pt3, Vec3};
//! // One turn per second about +y through the origin, starting at t = 1 s.
//! let spin: KinematicPath = ron::from_str(
//!     "After(start: 1.0, path: Rotate(center: (0, 0, 0), axis: (0, 1, 0), omega: 6.283185307179586))",
//! ).unwrap();
//! spin.validate().unwrap();
//! let p = Pt3::new(1.0, 0.0, 0.0);
//! assert_eq!(spin.point_at(0.5, &p), p);
//! let q = spin.point_at(1.25, &p); // a quarter turn
//! assert!((q - Pt3::new(0.0, 0.0, -1.0)).norm() < 1e-12);
//! ```

use nalgebra::{Translation3, Unit};
use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};
use crate::math::{Iso3, Pt3, UnitQuat, Vec3};

/// One keyframe of a [`KinematicPath::Keyframes`] path.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Keyframe {
    /// Time (s).
    pub t: f64,
    /// Translation of the rest placement (m).
    #[serde(default = "zero")]
    pub translation: Vec3,
    /// Rotation about the path's pivot as a rotation vector: axis × angle, in **degrees**.
    #[serde(default = "zero")]
    pub rotation_deg: Vec3,
}

fn zero() -> Vec3 {
    Vec3::zeros()
}

/// Rigid motion of a set of points over time.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum KinematicPath {
    /// Constant velocity (m/s) from t = 0.
    Translate {
        /// Velocity (m/s).
        velocity: Vec3,
    },
    /// Constant angular velocity about an axis through a centre, from t = 0.
    Rotate {
        /// Point on the axis (m).
        center: Pt3,
        /// Axis (normalised on use; right-hand rule).
        axis: Vec3,
        /// Angular speed (rad/s).
        omega: f64,
    },
    /// At rest until `start` (s), then `path` with its clock starting at zero.
    After {
        /// Start time (s).
        start: f64,
        /// The motion after the start.
        path: Box<KinematicPath>,
    },
    /// Several motions applied in order: the placement at t is `Tₙ(t) ⋯ T₁(t)`.
    Compose(Vec<KinematicPath>),
    /// Keyframes: translation interpolated linearly, rotation (about `pivot`) by spherical
    /// interpolation, held before the first and after the last key. Between two keys the
    /// rotation takes the short way, so a turn of more than 180° needs intermediate keys.
    Keyframes {
        /// Centre of the keyed rotations, in the rest placement (m).
        pivot: Pt3,
        /// Keys, in increasing time.
        keys: Vec<Keyframe>,
    },
}

fn rot_vec_deg(v: &Vec3) -> UnitQuat {
    UnitQuat::from_scaled_axis(v * std::f64::consts::PI / 180.0)
}

impl KinematicPath {
    /// Checks every number is finite, axes are non-zero and keys are in increasing time; the
    /// message names the offending part.
    pub fn validate(&self) -> Result<()> {
        let bad = |m: String| Err(Error::InvalidParameter(format!("kinematic path: {m}")));
        match self {
            KinematicPath::Translate { velocity } => {
                if velocity.iter().any(|x| !x.is_finite()) {
                    return bad(format!("Translate velocity must be finite, got {velocity:?}"));
                }
            }
            KinematicPath::Rotate { center, axis, omega } => {
                if center.iter().chain(axis.iter()).any(|x| !x.is_finite()) || !omega.is_finite() {
                    return bad("Rotate centre, axis and omega must be finite".into());
                }
                if axis.norm().partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) {
                    return bad("Rotate axis must be non-zero".into());
                }
            }
            KinematicPath::After { start, path } => {
                if !start.is_finite() {
                    return bad(format!("After start must be finite, got {start}"));
                }
                path.validate()?;
            }
            KinematicPath::Compose(paths) => {
                for p in paths {
                    p.validate()?;
                }
            }
            KinematicPath::Keyframes { pivot, keys } => {
                if keys.is_empty() {
                    return bad("Keyframes needs at least one key".into());
                }
                if pivot.iter().any(|x| !x.is_finite()) {
                    return bad("Keyframes pivot must be finite".into());
                }
                for (i, k) in keys.iter().enumerate() {
                    if !k.t.is_finite() || k.translation.iter().chain(k.rotation_deg.iter()).any(|x| !x.is_finite()) {
                        return bad(format!("key {i} has a non-finite value"));
                    }
                    if i > 0 && k.t.partial_cmp(&keys[i - 1].t) != Some(std::cmp::Ordering::Greater) {
                        return bad(format!("key {i}: times must increase ({} after {})", k.t, keys[i - 1].t));
                    }
                }
            }
        }
        Ok(())
    }

    /// The rigid transform at time t (s).
    pub fn transform(&self, t: f64) -> Iso3 {
        match self {
            KinematicPath::Translate { velocity } => Iso3::translation(velocity.x * t, velocity.y * t, velocity.z * t),
            KinematicPath::Rotate { center, axis, omega } => {
                let r = UnitQuat::from_axis_angle(&Unit::new_normalize(*axis), omega * t);
                about(center, r, Vec3::zeros())
            }
            KinematicPath::After { start, path } => {
                if t <= *start {
                    Iso3::identity()
                } else {
                    path.transform(t - start)
                }
            }
            KinematicPath::Compose(paths) => paths.iter().fold(Iso3::identity(), |acc, p| p.transform(t) * acc),
            KinematicPath::Keyframes { pivot, keys } => {
                let first = &keys[0];
                let last = &keys[keys.len() - 1];
                let (tr, r) = if t <= first.t {
                    (first.translation, rot_vec_deg(&first.rotation_deg))
                } else if t >= last.t {
                    (last.translation, rot_vec_deg(&last.rotation_deg))
                } else {
                    let j = keys.partition_point(|k| k.t <= t);
                    let (a, b) = (&keys[j - 1], &keys[j]);
                    let s = (t - a.t) / (b.t - a.t);
                    let ra = rot_vec_deg(&a.rotation_deg);
                    let rb = rot_vec_deg(&b.rotation_deg);
                    (a.translation + s * (b.translation - a.translation), crate::math::slerp(&ra, &rb, s))
                };
                about(pivot, r, tr)
            }
        }
    }

    /// Where the rest point `p` is at time t (s).
    pub fn point_at(&self, t: f64, p: &Pt3) -> Pt3 {
        self.transform(t) * p
    }

    /// Velocity (m/s) at time t of the point whose rest position is `p`, by a central difference
    /// over ±1 µs (exact for the constant-velocity paths up to rounding; one-sided at a keyframe).
    pub fn velocity_at(&self, t: f64, p: &Pt3) -> Vec3 {
        let dt = 1e-6;
        (self.point_at(t + dt, p) - self.point_at(t - dt, p)) / (2.0 * dt)
    }

    /// True when the path never moves anything (no velocity, no rotation, no keyed change).
    pub fn is_static(&self) -> bool {
        match self {
            KinematicPath::Translate { velocity } => velocity.norm() == 0.0,
            KinematicPath::Rotate { omega, .. } => *omega == 0.0,
            KinematicPath::After { path, .. } => path.is_static(),
            KinematicPath::Compose(p) => p.iter().all(KinematicPath::is_static),
            KinematicPath::Keyframes { keys, .. } => {
                keys.iter().all(|k| k.translation == keys[0].translation && k.rotation_deg == keys[0].rotation_deg)
            }
        }
    }
}

/// Rotation `r` about the point `c`, then translation `tr`: x ↦ c + r(x − c) + tr.
fn about(c: &Pt3, r: UnitQuat, tr: Vec3) -> Iso3 {
    let cv = c.coords;
    Iso3::from_parts(Translation3::from(cv - r * cv + tr), r)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn translate_and_rotate() {
        let p = KinematicPath::Translate { velocity: Vec3::new(1.0, 2.0, 3.0) };
        assert_eq!(p.point_at(2.0, &Pt3::origin()), Pt3::new(2.0, 4.0, 6.0));
        assert!((p.velocity_at(0.3, &Pt3::origin()) - Vec3::new(1.0, 2.0, 3.0)).norm() < 1e-8);
        let r = KinematicPath::Rotate {
            center: Pt3::new(1.0, 0.0, 0.0),
            axis: Vec3::new(0.0, 0.0, 2.0),
            omega: std::f64::consts::PI,
        };
        let q = r.point_at(1.0, &Pt3::new(2.0, 0.0, 0.0));
        assert!((q - Pt3::new(0.0, 0.0, 0.0)).norm() < 1e-12);
    }

    #[test]
    fn compose_screws_a_ring() {
        // One full turn about y over 4 s while moving 0.1 m along +y: a screw.
        let tau = std::f64::consts::TAU;
        let s = KinematicPath::Compose(vec![
            KinematicPath::Rotate { center: Pt3::origin(), axis: Vec3::y(), omega: tau / 4.0 },
            KinematicPath::Translate { velocity: Vec3::new(0.0, 0.025, 0.0) },
        ]);
        let q = s.point_at(2.0, &Pt3::new(0.1, 0.0, 0.0));
        assert!((q - Pt3::new(-0.1, 0.05, 0.0)).norm() < 1e-12, "{q}");
        let q = s.point_at(4.0, &Pt3::new(0.1, 0.0, 0.0));
        assert!((q - Pt3::new(0.1, 0.1, 0.0)).norm() < 1e-12, "{q}");
    }

    #[test]
    fn keyframes_interpolate_and_hold() {
        let k = KinematicPath::Keyframes {
            pivot: Pt3::origin(),
            keys: vec![
                Keyframe { t: 1.0, translation: Vec3::zeros(), rotation_deg: Vec3::zeros() },
                Keyframe { t: 3.0, translation: Vec3::new(0.0, 1.0, 0.0), rotation_deg: Vec3::new(0.0, 0.0, 90.0) },
            ],
        };
        k.validate().unwrap();
        let p = Pt3::new(1.0, 0.0, 0.0);
        assert_eq!(k.point_at(0.0, &p), p);
        let mid = k.point_at(2.0, &p);
        let h = std::f64::consts::FRAC_1_SQRT_2;
        assert!((mid - Pt3::new(h, 0.5 + h, 0.0)).norm() < 1e-12, "{mid}");
        assert!((k.point_at(9.0, &p) - Pt3::new(0.0, 2.0, 0.0)).norm() < 1e-12);
        assert!(!k.is_static());
    }

    #[test]
    fn bad_paths_are_refused_with_a_reason() {
        let nan = KinematicPath::Translate { velocity: Vec3::new(f64::NAN, 0.0, 0.0) };
        assert!(nan.validate().unwrap_err().to_string().contains("finite"));
        let axis = KinematicPath::Rotate { center: Pt3::origin(), axis: Vec3::zeros(), omega: 1.0 };
        assert!(axis.validate().unwrap_err().to_string().contains("axis"));
        let order = KinematicPath::Keyframes {
            pivot: Pt3::origin(),
            keys: vec![
                Keyframe { t: 1.0, translation: Vec3::zeros(), rotation_deg: Vec3::zeros() },
                Keyframe { t: 1.0, translation: Vec3::zeros(), rotation_deg: Vec3::zeros() },
            ],
        };
        assert!(order.validate().unwrap_err().to_string().contains("increase"));
        let nested = KinematicPath::After { start: 0.0, path: Box::new(nan) };
        assert!(nested.validate().is_err());
    }
}

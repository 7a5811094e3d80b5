//! Visibility sizing (spec §3.12 `V(x, y)`): a pinhole camera frustum, optionally key-framed or
//! orbiting, expanded by a margin.

use geom_core::math::{Pt3, Vec3};
use serde::{Deserialize, Serialize};

/// One camera key frame: `(t, position, look_at)` in s and m.
pub type Keyframe = (f64, (f64, f64, f64), (f64, f64, f64));

/// Where the camera is at time `t` (spec §3.12: position, look-at, optional key-framed path).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub enum CameraPath {
    /// A fixed camera.
    Fixed {
        /// Eye position (m).
        position: (f64, f64, f64),
        /// Point looked at (m).
        look_at: (f64, f64, f64),
    },
    /// A camera circling `center` in the horizontal plane at `height` above it, looking at `center`;
    /// angle `2π (t / period) + phase` measured from +x towards +z.
    Orbit {
        /// Orbit centre, also the look-at point (m).
        center: (f64, f64, f64),
        /// Orbit radius (m).
        radius: f64,
        /// Eye height above the centre (m).
        height: f64,
        /// Time for one turn (s).
        period: f64,
        /// Angle at `t = 0` (rad).
        phase: f64,
    },
    /// Linear interpolation between key frames `(t, position, look_at)`, sorted by time; held
    /// constant before the first and after the last.
    Keyframes(Vec<Keyframe>),
}

/// Visibility metric parameters (spec §4 `sizing.visibility`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct VisibilityParams {
    /// Camera placement over time.
    pub path: CameraPath,
    /// Vertical field of view (degrees, in (0, 180)).
    pub fov_y_deg: f64,
    /// Width / height of the image.
    #[serde(default = "default_aspect")]
    pub aspect: f64,
    /// Near clipping distance (m).
    #[serde(default = "default_near")]
    pub near: f64,
    /// Far clipping distance (m).
    #[serde(default = "default_far")]
    pub far: f64,
    /// Frustum margin in units of `r_max` (spec: 2).
    #[serde(default = "default_margin")]
    pub margin_r_max: f64,
}

fn default_aspect() -> f64 {
    16.0 / 9.0
}
fn default_near() -> f64 {
    0.01
}
fn default_far() -> f64 {
    1e3
}
fn default_margin() -> f64 {
    2.0
}

fn p3(v: (f64, f64, f64)) -> Pt3 {
    Pt3::new(v.0, v.1, v.2)
}

impl VisibilityParams {
    /// Checks the ranges; the error names the field.
    pub fn validate(&self) -> geom_core::Result<()> {
        let bad = |w: &str| Err(geom_core::Error::InvalidParameter(format!("sizing.visibility.{w}")));
        if !(self.fov_y_deg > 0.0 && self.fov_y_deg < 180.0) {
            return bad("fov_y_deg must be in (0, 180)");
        }
        if !(self.aspect > 0.0 && self.aspect.is_finite()) {
            return bad("aspect must be finite and > 0");
        }
        if !(self.near >= 0.0 && self.far > self.near) {
            return bad("near/far must satisfy 0 <= near < far");
        }
        if !(self.margin_r_max >= 0.0 && self.margin_r_max.is_finite()) {
            return bad("margin_r_max must be finite and >= 0");
        }
        match &self.path {
            CameraPath::Orbit { radius, period, .. } if !(*radius > 0.0 && *period > 0.0) => {
                bad("path: orbit radius and period must be > 0")
            }
            CameraPath::Keyframes(k)
                if k.is_empty()
                    || k.windows(2).any(|w| w[1].0.partial_cmp(&w[0].0) != Some(std::cmp::Ordering::Greater)) =>
            {
                bad("path: keyframes must be non-empty with increasing times")
            }
            _ => Ok(()),
        }
    }

    /// Eye and look-at point at time `t` (s).
    pub fn pose(&self, t: f64) -> (Pt3, Pt3) {
        match &self.path {
            CameraPath::Fixed { position, look_at } => (p3(*position), p3(*look_at)),
            CameraPath::Orbit { center, radius, height, period, phase } => {
                let a = std::f64::consts::TAU * t / period + phase;
                let c = p3(*center);
                (c + Vec3::new(radius * a.cos(), *height, radius * a.sin()), c)
            }
            CameraPath::Keyframes(k) => {
                let first = &k[0];
                let last = &k[k.len() - 1];
                if t <= first.0 {
                    return (p3(first.1), p3(first.2));
                }
                if t >= last.0 {
                    return (p3(last.1), p3(last.2));
                }
                let i = k.partition_point(|f| f.0 <= t) - 1;
                let (a, b) = (&k[i], &k[i + 1]);
                let s = (t - a.0) / (b.0 - a.0);
                let lerp = |u: (f64, f64, f64), v: (f64, f64, f64)| p3(u) + (p3(v) - p3(u)) * s;
                (lerp(a.1, b.1), lerp(a.2, b.2))
            }
        }
    }

    /// The frustum at time `t`.
    pub fn frustum(&self, t: f64) -> Frustum {
        let (eye, target) = self.pose(t);
        Frustum::new(eye, target, self.fov_y_deg, self.aspect, self.near, self.far)
    }
}

/// A view frustum in camera coordinates (x right, y up, z forward).
#[derive(Clone, Copy, Debug)]
pub struct Frustum {
    eye: Pt3,
    right: Vec3,
    up: Vec3,
    fwd: Vec3,
    tan_x: f64,
    tan_y: f64,
    near: f64,
    far: f64,
}

impl Frustum {
    /// Frustum of a camera at `eye` looking at `target` (world up = +y; when looking straight up
    /// or down, +z is used instead).
    pub fn new(eye: Pt3, target: Pt3, fov_y_deg: f64, aspect: f64, near: f64, far: f64) -> Self {
        let fwd = (target - eye).try_normalize(0.0).unwrap_or(Vec3::new(0.0, 0.0, -1.0));
        let world_up = if fwd.cross(&Vec3::y()).norm() > 1e-9 { Vec3::y() } else { Vec3::z() };
        let right = fwd.cross(&world_up).normalize();
        let up = right.cross(&fwd);
        let tan_y = (0.5 * fov_y_deg.to_radians()).tan();
        Self { eye, right, up, fwd, tan_x: tan_y * aspect, tan_y, near, far }
    }

    /// Whether `x` lies in the frustum with every bounding plane pushed out by `margin` (m): the
    /// intersection of the offset half-spaces, a slight superset of the Minkowski sum with a ball.
    pub fn contains(&self, x: &Pt3, margin: f64) -> bool {
        let d = x - self.eye;
        let (cx, cy, cz) = (d.dot(&self.right), d.dot(&self.up), d.dot(&self.fwd));
        if cz < self.near - margin || cz > self.far + margin {
            return false;
        }
        // Side plane |cx| = cz tan: its unit normal has z-component sin, x-component cos, so a
        // pushed-out plane reads |cx| ≤ cz tan + margin / cos.
        let sec_x = (1.0 + self.tan_x * self.tan_x).sqrt();
        let sec_y = (1.0 + self.tan_y * self.tan_y).sqrt();
        cx.abs() <= cz * self.tan_x + margin * sec_x && cy.abs() <= cz * self.tan_y + margin * sec_y
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frustum_membership_and_margin() {
        let f = Frustum::new(Pt3::new(0.0, 0.0, 5.0), Pt3::origin(), 60.0, 1.0, 0.1, 100.0);
        assert!(f.contains(&Pt3::origin(), 0.0));
        assert!(!f.contains(&Pt3::new(0.0, 0.0, 6.0), 0.0)); // behind the eye
                                                             // At distance 5, the half-height is 5 tan 30° = 2.887.
        assert!(f.contains(&Pt3::new(0.0, 2.8, 0.0), 0.0));
        assert!(!f.contains(&Pt3::new(0.0, 3.0, 0.0), 0.0));
        // Distance from (0, 3, 0) to the top plane is (3 − 2.887) cos 30° = 0.0977.
        assert!(f.contains(&Pt3::new(0.0, 3.0, 0.0), 0.1));
        assert!(!f.contains(&Pt3::new(0.0, 3.0, 0.0), 0.09));
    }

    #[test]
    fn orbit_and_keyframes() {
        let v = VisibilityParams {
            path: CameraPath::Orbit { center: (1.0, 0.0, 1.0), radius: 2.5, height: 1.0, period: 2.0, phase: 0.0 },
            fov_y_deg: 50.0,
            aspect: 1.0,
            near: 0.01,
            far: 100.0,
            margin_r_max: 2.0,
        };
        v.validate().expect("valid");
        let (e, t) = v.pose(0.5); // quarter turn: +z side
        assert!((e - Pt3::new(1.0, 1.0, 3.5)).norm() < 1e-12 && (t - Pt3::new(1.0, 0.0, 1.0)).norm() < 1e-15);
        let k = VisibilityParams {
            path: CameraPath::Keyframes(vec![
                (0.0, (0.0, 0.0, 0.0), (1.0, 0.0, 0.0)),
                (1.0, (2.0, 0.0, 0.0), (3.0, 0.0, 0.0)),
            ]),
            ..v.clone()
        };
        let (e, _) = k.pose(0.25);
        assert!((e.x - 0.5).abs() < 1e-15);
        assert_eq!(k.pose(7.0).0, Pt3::new(2.0, 0.0, 0.0));
        let bad = VisibilityParams { fov_y_deg: 190.0, ..v };
        assert!(bad.validate().is_err());
    }
}

//! Muscle action lines (spec §3.4.8; paper: "each action line is deformed by a curve skeleton,
//! and the action line in turn deforms the muscle").
//!
//! An [`ActionLine`] is a polyline of rest control points. They are bound exactly like skin
//! vertices (same candidates, weights and local coordinates, against the skin's rest curve
//! frames) and deformed with the same posed frames, so the line bends around the joint without
//! being animated by hand. Its length ratio (posed / rest) drives an optional [`MuscleBulge`]:
//! a volume-preserving muscle of rest radius `a` shortened to the ratio `λ` thickens to `a/√λ`,
//! so skin vertices within a capsule of radius `influence` around the rest line are pushed away
//! from the posed line by `a·(1/√λ − 1)·f`, with the fall-off `f` = smoothstep across the capsule
//! times the belly profile `sin(π·u)` (u = normalised rest arc length, 0 at the tendons).

use geom_core::math::{smoothstep, AsPt3, Pt3, Vec3};
use geom_core::query::closest_point_segment;

use super::skin::CurveSkin;
use crate::error::{Result, SkinError};

/// A muscle action line: rest control points (m), at least two, consecutive ones distinct.
#[derive(Clone, Debug, PartialEq)]
pub struct ActionLine {
    /// Rest control points, in order along the muscle (origin → insertion).
    pub control_points: Vec<Pt3>,
}

impl ActionLine {
    /// Validates the control points. Errors: fewer than two points, a non-finite coordinate, or
    /// a zero-length segment.
    pub fn new(control_points: Vec<Pt3>) -> Result<ActionLine> {
        if control_points.len() < 2 {
            return Err(SkinError::Param(format!(
                "action line needs at least 2 control points, got {}",
                control_points.len()
            )));
        }
        if let Some(i) = control_points.iter().position(|p| !p.coords.iter().all(|c| c.is_finite())) {
            return Err(SkinError::Param(format!("action line control point {i} is not finite")));
        }
        if let Some(i) = control_points.windows(2).position(|w| (w[1] - w[0]).norm() <= 1e-12) {
            return Err(SkinError::Param(format!("action line segment {i} has zero length")));
        }
        Ok(ActionLine { control_points })
    }

    /// Rest length of the polyline (m).
    pub fn rest_length(&self) -> f64 {
        polyline_length(&self.control_points)
    }

    /// The control points deformed by the skin's current (last `prepare`) curve frames, exact
    /// `f64` path; `out` is resized to the number of control points.
    pub fn deform(&self, skin: &CurveSkin, out: &mut Vec<Pt3>) {
        out.clear();
        out.extend(self.control_points.iter().map(|x| skin.map_point(x)));
    }

    /// Posed length / rest length of a deformed copy of this line.
    pub fn length_ratio(&self, posed: &[Pt3]) -> f64 {
        polyline_length(posed) / self.rest_length()
    }
}

/// Length of a polyline (m).
pub fn polyline_length(p: &[Pt3]) -> f64 {
    p.windows(2).map(|w| (w[1] - w[0]).norm()).sum()
}

/// One skin vertex inside a muscle's capsule.
#[derive(Clone, Copy, Debug, PartialEq)]
struct BulgeEntry {
    vertex: u32,
    segment: u32,
    t: f64,
    falloff: f64,
}

/// The optional bulge of skin vertices around an action line (module docs).
#[derive(Clone, Debug, PartialEq)]
pub struct MuscleBulge {
    /// Rest muscle radius `a` (m).
    pub radius: f64,
    /// Capsule radius of influence around the rest line (m).
    pub influence: f64,
    entries: Vec<BulgeEntry>,
}

impl MuscleBulge {
    /// Finds the skin vertices within `influence` of the rest line and their fall-off. Errors:
    /// non-positive or non-finite `radius` / `influence`.
    pub fn new<P: AsPt3>(line: &ActionLine, rest: &[P], radius: f64, influence: f64) -> Result<MuscleBulge> {
        if !(radius > 0.0 && radius.is_finite() && influence > 0.0 && influence.is_finite()) {
            return Err(SkinError::Param(format!(
                "muscle radius and influence must be positive and finite, got {radius} and {influence}"
            )));
        }
        let cp = &line.control_points;
        let total = line.rest_length();
        let mut start = Vec::with_capacity(cp.len());
        let mut acc = 0.0;
        for w in cp.windows(2) {
            start.push(acc);
            acc += (w[1] - w[0]).norm();
        }
        let mut entries = Vec::new();
        for (v, x) in rest.iter().enumerate() {
            let x = x.pt3();
            let mut best = (f64::INFINITY, 0usize, 0.0);
            for (s, w) in cp.windows(2).enumerate() {
                let (t, p) = closest_point_segment(&x, &w[0], &w[1]);
                let d = (p - x).norm();
                if d < best.0 {
                    best = (d, s, t);
                }
            }
            let (d, s, t) = best;
            if d >= influence {
                continue;
            }
            let u = (start[s] + t * (cp[s + 1] - cp[s]).norm()) / total;
            let falloff = smoothstep(0.0, 1.0, 1.0 - d / influence) * (std::f64::consts::PI * u).sin();
            if falloff > 0.0 {
                entries.push(BulgeEntry { vertex: v as u32, segment: s as u32, t, falloff });
            }
        }
        Ok(MuscleBulge { radius, influence, entries })
    }

    /// Number of skin vertices the bulge can move.
    pub fn len(&self) -> usize {
        self.entries.len()
    }

    /// True when no vertex lies within the capsule.
    pub fn is_empty(&self) -> bool {
        self.entries.is_empty()
    }

    /// Displacement magnitude at unit fall-off for the length ratio `λ`: `a·(1/√λ − 1)` (m;
    /// negative when the muscle is stretched).
    pub fn thickening(&self, length_ratio: f64) -> f64 {
        self.radius * (1.0 / length_ratio.max(1e-6).sqrt() - 1.0)
    }

    /// Pushes the deformed skin `positions` away from the posed line `line_posed` (same control
    /// point count as the rest line) by `thickening(λ)·falloff`. A vertex lying on the posed line
    /// is not moved (no direction).
    pub fn apply(&self, line_posed: &[Pt3], length_ratio: f64, positions: &mut [[f32; 3]]) {
        let amount = self.thickening(length_ratio);
        for e in &self.entries {
            let (s, v) = (e.segment as usize, e.vertex as usize);
            let p = line_posed[s] + (line_posed[s + 1] - line_posed[s]) * e.t;
            let x = positions[v];
            let dir = Vec3::new(x[0] as f64, x[1] as f64, x[2] as f64) - p.coords;
            let n = dir.norm();
            if n <= 1e-12 {
                continue;
            }
            let dx = dir * (amount * e.falloff / n);
            positions[v] = [x[0] + dx.x as f32, x[1] + dx.y as f32, x[2] + dx.z as f32];
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn action_line_rejects_bad_input() {
        assert!(ActionLine::new(vec![Pt3::origin()]).is_err());
        assert!(ActionLine::new(vec![Pt3::origin(), Pt3::origin()]).is_err());
        assert!(ActionLine::new(vec![Pt3::origin(), Pt3::new(f64::NAN, 0.0, 0.0)]).is_err());
        let l = ActionLine::new(vec![Pt3::origin(), Pt3::new(3.0, 0.0, 0.0), Pt3::new(3.0, 4.0, 0.0)]).unwrap();
        assert_eq!(l.rest_length(), 7.0);
        assert!(MuscleBulge::new(&l, &[Pt3::origin()], 0.0, 1.0).is_err());
    }

    #[test]
    fn bulge_thickens_a_shortened_muscle_only_inside_its_capsule() {
        let l = ActionLine::new(vec![Pt3::origin(), Pt3::new(1.0, 0.0, 0.0)]).unwrap();
        let rest = [Pt3::new(0.5, 0.1, 0.0), Pt3::new(0.5, 0.3, 0.0), Pt3::new(0.0, 0.1, 0.0)];
        let b = MuscleBulge::new(&l, &rest, 0.05, 0.2).unwrap();
        // Vertex 1 is outside the capsule; vertex 2 sits at a tendon end (sin(π·0) = 0).
        assert_eq!(b.len(), 1);
        // Volume preservation: λ = 0.64 ⇒ radius ×1.25.
        assert!((b.thickening(0.64) - 0.0125).abs() < 1e-15);
        let mut pos: Vec<[f32; 3]> = rest.iter().map(|p| [p.x as f32, p.y as f32, p.z as f32]).collect();
        b.apply(&l.control_points, 0.64, &mut pos);
        // Vertex 0: at the belly (u = ½), d = 0.1 ⇒ falloff = smoothstep(0.5) = 0.5, moved +y.
        assert!((pos[0][1] as f64 - (0.1 + 0.0125 * 0.5)).abs() < 1e-7);
        assert_eq!(pos[1], [0.5, 0.3, 0.0]);
        assert_eq!(pos[2], [0.0, 0.1, 0.0]);
    }
}

//! Orientation of a character mesh: which of its axes is up and which way it faces.
//!
//! The templates are authored upright (+Y up), facing +Z, with the character's left on +X
//! (spec §2). A mesh exported Z-up, facing −Z or +X is turned into that frame by one of the 24
//! axis-aligned rotations ([`Orientation`]: a signed permutation of the coordinates, so turning
//! there and back is exact). [`detect_orientation`] finds it from the shape: the template is
//! embedded in the sphere graph of the mesh seen in each of the 24 frames (one distance field,
//! the graph's vertices permuted), each search within a small expansion budget, and the frame
//! with the lowest penalty wins (ties go to the earlier frame of [`Orientation::all`], which
//! starts with the identity).

use std::fmt;
use std::str::FromStr;

use geom_core::math::{Pt3, Vec3};
use serde::{Deserialize, Serialize};

use crate::embed::{candidates, Problem, SearchBudget};
use crate::error::{Result, RigError};
use crate::graph::EmbedGraph;
use crate::options::RigOptions;
use crate::template::SkeletonTemplate;

/// A signed coordinate axis.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum Axis {
    /// +X
    PosX,
    /// −X
    NegX,
    /// +Y
    PosY,
    /// −Y
    NegY,
    /// +Z
    PosZ,
    /// −Z
    NegZ,
}

impl Axis {
    /// All six, in the order +X, −X, +Y, −Y, +Z, −Z.
    pub const ALL: [Axis; 6] = [Axis::PosX, Axis::NegX, Axis::PosY, Axis::NegY, Axis::PosZ, Axis::NegZ];

    /// The coordinate index (0, 1, 2) and the sign (±1).
    pub fn index_sign(self) -> (usize, f64) {
        match self {
            Axis::PosX => (0, 1.0),
            Axis::NegX => (0, -1.0),
            Axis::PosY => (1, 1.0),
            Axis::NegY => (1, -1.0),
            Axis::PosZ => (2, 1.0),
            Axis::NegZ => (2, -1.0),
        }
    }

    /// The unit vector.
    pub fn vector(self) -> Vec3 {
        let (i, s) = self.index_sign();
        let mut v = Vec3::zeros();
        v[i] = s;
        v
    }

    /// `+x`, `-y`, …
    pub fn name(self) -> &'static str {
        ["+x", "-x", "+y", "-y", "+z", "-z"][Axis::ALL.iter().position(|a| *a == self).expect("listed")]
    }
}

impl fmt::Display for Axis {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for Axis {
    type Err = RigError;

    /// `x`, `+x`, `-x`, `X`, … (no sign = positive).
    fn from_str(s: &str) -> Result<Axis> {
        let t = s.trim().to_ascii_lowercase();
        let (neg, a) = match t.strip_prefix('-') {
            Some(r) => (true, r),
            None => (false, t.strip_prefix('+').unwrap_or(&t)),
        };
        let axis = match (a, neg) {
            ("x", false) => Axis::PosX,
            ("x", true) => Axis::NegX,
            ("y", false) => Axis::PosY,
            ("y", true) => Axis::NegY,
            ("z", false) => Axis::PosZ,
            ("z", true) => Axis::NegZ,
            _ => {
                return Err(RigError::InvalidParameter(format!("axis '{s}': expected x, y or z with an optional sign")))
            }
        };
        Ok(axis)
    }
}

/// Which input axis is up and which one the character faces. The canonical frame is up = +Y,
/// front = +Z (left = up × front = +X).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub struct Orientation {
    /// The input axis pointing up.
    pub up: Axis,
    /// The input axis the character faces.
    pub front: Axis,
}

impl Default for Orientation {
    fn default() -> Self {
        Orientation { up: Axis::PosY, front: Axis::PosZ }
    }
}

impl fmt::Display for Orientation {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "up {}, front {}", self.up, self.front)
    }
}

impl Orientation {
    /// Checks that up and front are different coordinate axes.
    pub fn new(up: Axis, front: Axis) -> Result<Orientation> {
        if up.index_sign().0 == front.index_sign().0 {
            return Err(RigError::InvalidParameter(format!("up {up} and front {front} must be different axes")));
        }
        Ok(Orientation { up, front })
    }

    /// The 24 orientations: up in the order +Y, +Z, −Z, +X, −X, −Y (the usual exports first), and
    /// for each the fronts in the order of [`Axis::ALL`] with +Z, −Z, −Y first when possible. The
    /// identity (up +Y, front +Z) is first.
    pub fn all() -> Vec<Orientation> {
        let ups = [Axis::PosY, Axis::PosZ, Axis::NegZ, Axis::PosX, Axis::NegX, Axis::NegY];
        let fronts = [Axis::PosZ, Axis::NegZ, Axis::NegY, Axis::PosY, Axis::PosX, Axis::NegX];
        let mut v = Vec::with_capacity(24);
        for up in ups {
            for front in fronts {
                if let Ok(o) = Orientation::new(up, front) {
                    v.push(o);
                }
            }
        }
        v
    }

    /// The input axis on the character's left (`up × front`).
    pub fn left(&self) -> Vec3 {
        self.up.vector().cross(&self.front.vector())
    }

    /// A vector of the input frame in the canonical frame: `(v·left, v·up, v·front)`. Exact (a
    /// signed permutation).
    pub fn to_canonical(&self, v: &Vec3) -> Vec3 {
        Vec3::new(v.dot(&self.left()), v.dot(&self.up.vector()), v.dot(&self.front.vector()))
    }

    /// A vector of the canonical frame in the input frame (inverse of [`Self::to_canonical`]).
    pub fn from_canonical(&self, v: &Vec3) -> Vec3 {
        self.left() * v.x + self.up.vector() * v.y + self.front.vector() * v.z
    }

    /// [`Self::to_canonical`] of a point.
    pub fn point_to_canonical(&self, p: &Pt3) -> Pt3 {
        Pt3::from(self.to_canonical(&p.coords))
    }

    /// [`Self::from_canonical`] of a point.
    pub fn point_from_canonical(&self, p: &Pt3) -> Pt3 {
        Pt3::from(self.from_canonical(&p.coords))
    }
}

/// What [`detect_orientation`] found.
#[derive(Clone, Debug, PartialEq)]
pub struct OrientationReport {
    /// The orientation with the lowest penalty.
    pub orientation: Orientation,
    /// Every orientation tried with the penalty of its best embedding (`∞` when none passed).
    pub penalties: Vec<(Orientation, f64)>,
    /// Partial embeddings expanded over all orientations.
    pub expanded: usize,
}

/// The graph `g` (normalized coordinates, the unit cube) seen in orientation `o`: vertices
/// turned about the cube's centre, everything else unchanged (distances are invariant).
pub fn rotated_graph(g: &EmbedGraph, o: &Orientation) -> EmbedGraph {
    let c = Vec3::repeat(0.5);
    let mut r = g.clone();
    for p in &mut r.verts {
        *p = Pt3::from(o.to_canonical(&(p.coords - c)) + c);
    }
    r
}

/// Finds the orientation of a character from its sphere graph (normalized coordinates of the
/// input mesh): the template is embedded in the graph seen in each `allowed` orientation (e.g.
/// [`Orientation::all`]) with at most `budget` expansions each, and the lowest penalty wins (the
/// earlier orientation on a tie). `NoEmbedding` when no orientation admits an embedding.
pub fn detect_orientation(
    g: &EmbedGraph,
    sk: &SkeletonTemplate,
    o: &RigOptions,
    budget: &SearchBudget,
    allowed: &[Orientation],
) -> Result<OrientationReport> {
    let rs = sk.reduced();
    let mut penalties = Vec::with_capacity(allowed.len());
    let mut expanded = 0;
    let mut best: Option<(Orientation, f64)> = None;
    for &or in allowed {
        let gr = rotated_graph(g, &or);
        let cand = candidates(&gr, sk, &rs, &[], o, &|p| *p, 1.0)?;
        let pr = Problem::new(&gr, sk, &rs, &cand, o);
        let (res, n) = match crate::embed::search(&pr, 1, budget) {
            Ok(v) => (v[0].penalty, v[0].expanded),
            Err(RigError::NoEmbedding { expanded, .. }) => (f64::INFINITY, expanded),
            Err(e) => return Err(e),
        };
        expanded += n;
        penalties.push((or, res));
        if res < best.map_or(f64::INFINITY, |b| b.1) {
            best = Some((or, res));
        }
    }
    match best {
        Some((orientation, _)) => Ok(OrientationReport { orientation, penalties, expanded }),
        None => Err(RigError::NoEmbedding { best_partial: None, expanded }),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn axes_parse_and_orientations_are_proper_rotations() {
        assert_eq!("z".parse::<Axis>().unwrap(), Axis::PosZ);
        assert_eq!("-Y".parse::<Axis>().unwrap(), Axis::NegY);
        assert!("w".parse::<Axis>().is_err());
        assert!(Orientation::new(Axis::PosY, Axis::NegY).is_err());
        let all = Orientation::all();
        assert_eq!(all.len(), 24);
        assert_eq!(all[0], Orientation::default());
        let v = Vec3::new(0.3, -1.7, 2.9);
        for o in &all {
            // Exact round trip, determinant +1, up → +Y, front → +Z.
            assert_eq!(o.from_canonical(&o.to_canonical(&v)), v);
            assert_eq!(o.to_canonical(&o.up.vector()), Vec3::y());
            assert_eq!(o.to_canonical(&o.front.vector()), Vec3::z());
            let m = nalgebra::Matrix3::from_columns(&[
                o.to_canonical(&Vec3::x()),
                o.to_canonical(&Vec3::y()),
                o.to_canonical(&Vec3::z()),
            ]);
            assert_eq!(m.determinant(), 1.0);
        }
        let distinct: std::collections::HashSet<_> = all.iter().collect();
        assert_eq!(distinct.len(), 24);
    }
}

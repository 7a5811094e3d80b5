//! Rigid obstacles as contact geometry: every obstacle is a half-space or a set of "core"
//! primitives (points, segments, triangles) thickened by a radius ξ — a sphere is one point with
//! ξ = r, a capsule two points and a segment with ξ = r, a closed mesh its vertices, edges and
//! triangles with ξ = 0. Cloth–obstacle contact is then the same point–triangle and edge–edge
//! geometry as self-contact (cloth vertex × obstacle triangle, cloth edge × obstacle edge, cloth
//! triangle × obstacle point), with the obstacle's points fixed during a step.

use geom_core::math::{Iso3, Pt3, Vec3};
use geom_core::spatial::{Aabb, AabbTree};

use crate::effects::{Obstacle, ObstacleShape};

/// An obstacle placed at the end of a step.
pub(crate) enum Placed {
    /// The solid half-space {n̂·x ≤ offset}.
    Half {
        /// Outward unit normal.
        normal: Vec3,
        /// n̂·x on the surface (m).
        offset: f64,
    },
    /// Core primitives thickened by `xi`.
    Core(Box<Core>),
}

/// Core primitives of a rounded or mesh obstacle, in world coordinates at the step's end.
pub(crate) struct Core {
    /// Thickness added to the core (m): the sphere's or capsule's radius, 0 for meshes.
    pub xi: f64,
    /// Points (sphere centre, capsule ends, mesh vertices).
    pub points: Vec<Pt3>,
    /// Segments as point index pairs (capsule axis, mesh edges).
    pub edges: Vec<[u32; 2]>,
    /// Triangles as point index triples (mesh faces).
    pub tris: Vec<[u32; 3]>,
    /// Trees over the points, edges and triangles (boxes grown by ξ; a deforming mesh's boxes
    /// cover the step's start and end positions).
    pub trees: [AabbTree; 3],
    /// A deforming mesh's point displacements over the step (m; `points` − `disp` are the
    /// step-start positions); empty for rigid obstacles, whose points are fixed in a step.
    pub disp: Vec<Vec3>,
}

impl Core {
    fn new(xi: f64, points: Vec<Pt3>, edges: Vec<[u32; 2]>, tris: Vec<[u32; 3]>) -> Self {
        let pb: Vec<Aabb> = points.iter().map(|p| Aabb::from_points(&[*p]).grow(xi)).collect();
        let eb: Vec<Aabb> = edges.iter().map(|e| pb[e[0] as usize].union(&pb[e[1] as usize])).collect();
        let tb: Vec<Aabb> =
            tris.iter().map(|t| pb[t[0] as usize].union(&pb[t[1] as usize]).union(&pb[t[2] as usize])).collect();
        let trees = [AabbTree::build(&pb), AabbTree::build(&eb), AabbTree::build(&tb)];
        Self { xi, points, edges, tris, trees, disp: Vec::new() }
    }

    /// A deforming mesh moving from `start` to `end` over the step (module `deforming`): the
    /// contact geometry is `end`, the trees' boxes cover both.
    pub(crate) fn moving(start: &[Pt3], end: Vec<Pt3>, edges: Vec<[u32; 2]>, tris: Vec<[u32; 3]>) -> Self {
        let pb: Vec<Aabb> = start.iter().zip(&end).map(|(a, b)| Aabb::from_points(&[*a, *b])).collect();
        let eb: Vec<Aabb> = edges.iter().map(|e| pb[e[0] as usize].union(&pb[e[1] as usize])).collect();
        let tb: Vec<Aabb> =
            tris.iter().map(|t| pb[t[0] as usize].union(&pb[t[1] as usize]).union(&pb[t[2] as usize])).collect();
        let trees = [AabbTree::build(&pb), AabbTree::build(&eb), AabbTree::build(&tb)];
        let disp = start.iter().zip(&end).map(|(a, b)| b - a).collect();
        Self { xi: 0.0, points: end, edges, tris, trees, disp }
    }

    /// The displacement over the step of the obstacle point at `p` (one of `points`), found
    /// among the vertices `ids` of a contact's obstacle feature; zero for rigid obstacles.
    pub(crate) fn shift_of(&self, ids: &[u32], p: &Pt3) -> Vec3 {
        ids.iter()
            .find(|&&i| self.points.get(i as usize) == Some(p))
            .and_then(|&i| self.disp.get(i as usize).copied())
            .unwrap_or_else(Vec3::zeros)
    }
}

/// Unique undirected edges (a < b, sorted) of a triangle list.
pub(crate) fn mesh_edges(tris: &[[u32; 3]]) -> Vec<[u32; 2]> {
    let mut e: Vec<[u32; 2]> =
        tris.iter().flat_map(|t| (0..3).map(move |k| [t[k].min(t[(k + 1) % 3]), t[k].max(t[(k + 1) % 3])])).collect();
    e.sort_unstable();
    e.dedup();
    e
}

/// The rigid placement of an obstacle at time t (identity for static ones).
pub(crate) fn pose(o: &Obstacle, t: f64) -> Iso3 {
    o.motion.as_ref().map(|m| m.transform(t)).unwrap_or_else(Iso3::identity)
}

/// Places `o` at pose `iso`. `edges` are the mesh's edges (precomputed; empty otherwise).
pub(crate) fn place(o: &Obstacle, iso: &Iso3, edges: &[[u32; 2]]) -> Placed {
    match &o.shape {
        ObstacleShape::Plane { normal, offset } => {
            // The placed plane: n' = R n̂, offset' = n'·(pose · (offset n̂)).
            let n = normal.normalize();
            let nw = iso.rotation * n;
            let p = iso * Pt3::from(*offset * n);
            Placed::Half { normal: nw, offset: nw.dot(&p.coords) }
        }
        ObstacleShape::Sphere { center, radius } => {
            Placed::Core(Box::new(Core::new(*radius, vec![iso * center], vec![], vec![])))
        }
        ObstacleShape::Capsule { a, b, radius } => {
            Placed::Core(Box::new(Core::new(*radius, vec![iso * a, iso * b], vec![[0, 1]], vec![])))
        }
        ObstacleShape::Mesh { verts, tris } => Placed::Core(Box::new(Core::new(
            0.0,
            verts.iter().map(|p| iso * p).collect(),
            edges.to_vec(),
            tris.clone(),
        ))),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use geom_core::kinematic::KinematicPath;

    #[test]
    fn placed_plane_follows_its_motion() {
        let o = Obstacle {
            shape: ObstacleShape::Plane { normal: Vec3::new(0.0, 2.0, 0.0), offset: 0.5 },
            friction: 0.5,
            motion: Some(KinematicPath::Translate { velocity: Vec3::new(0.0, 1.0, 0.0) }),
        };
        match place(&o, &pose(&o, 2.0), &[]) {
            Placed::Half { normal, offset } => {
                assert!((normal - Vec3::y()).norm() < 1e-15);
                assert!((offset - 2.5).abs() < 1e-12);
            }
            Placed::Core(_) => panic!("a plane is a half-space"),
        }
    }

    #[test]
    fn mesh_edges_are_unique_and_sorted() {
        let e = mesh_edges(&[[0, 1, 2], [2, 1, 3]]);
        assert_eq!(e, vec![[0, 1], [0, 2], [1, 2], [1, 3], [2, 3]]);
    }
}

//! Marching tetrahedra: the zero level set of a piecewise-linear field on a tetrahedral grid.
//!
//! Within a tetrahedron the field is the linear interpolant of its four node values, so the
//! level set is exactly one triangle (one node on its own side) or one planar quad split into two
//! triangles (two nodes on each side). Surface vertices live on grid edges and are shared through
//! an edge-keyed map, so tetrahedra that share a face produce matching triangle edges: the result
//! is watertight whenever the tetrahedral grid is conforming and the surface stays inside it.

use std::collections::HashMap;

use crate::error::{Error, Result};
use crate::math::Pt3;
use crate::mesh::TriMesh;

/// Replaces values too close to zero so that no surface vertex coincides with a grid node (which
/// would create zero-area triangles): `|v| < snap` becomes `±snap` keeping its sign, an exact `0`
/// becomes `+snap` (outside).
pub(crate) fn snap_value(v: f64, snap: f64) -> f64 {
    if v == 0.0 {
        snap
    } else if v.abs() < snap {
        snap.copysign(v)
    } else {
        v
    }
}

/// Accumulates the triangles of many tetrahedra with shared edge vertices.
pub(crate) struct Marcher {
    map: HashMap<(u64, u64), u32>,
    pub(crate) positions: Vec<Pt3>,
    pub(crate) faces: Vec<[u32; 3]>,
}

impl Marcher {
    pub(crate) fn new() -> Self {
        Self { map: HashMap::new(), positions: Vec::new(), faces: Vec::new() }
    }

    /// The surface vertex on the edge between nodes `a` and `b` (keys `ka`, `kb`).
    fn vertex(&mut self, ka: u64, kb: u64, pa: &Pt3, pb: &Pt3, va: f64, vb: f64) -> u32 {
        // Interpolate from the smaller key so that both tetrahedra sharing the edge get the
        // bit-identical point.
        let (key, (pa, pb, va, vb)) = if ka < kb { ((ka, kb), (pa, pb, va, vb)) } else { ((kb, ka), (pb, pa, vb, va)) };
        let positions = &mut self.positions;
        *self.map.entry(key).or_insert_with(|| {
            let t = va / (va - vb);
            positions.push(pa + (pb - pa) * t);
            (positions.len() - 1) as u32
        })
    }

    /// Emits triangle `(a, b, c)`, reversed if its normal does not point along `out`.
    fn tri(&mut self, t: [u32; 3], out: &crate::math::Vec3) {
        let [a, b, c] = t.map(|i| self.positions[i as usize]);
        let n = (b - a).cross(&(c - a));
        if n.dot(out) < 0.0 {
            self.faces.push([t[0], t[2], t[1]]);
        } else {
            self.faces.push(t);
        }
    }

    /// Marches one tetrahedron: node keys, positions and already-snapped values (never 0).
    pub(crate) fn tet(&mut self, k: [u64; 4], p: [Pt3; 4], v: [f64; 4]) {
        let inside: Vec<usize> = (0..4).filter(|&i| v[i] < 0.0).collect();
        let outside: Vec<usize> = (0..4).filter(|&i| v[i] >= 0.0).collect();
        if inside.is_empty() || outside.is_empty() {
            return;
        }
        let centroid = |s: &[usize]| s.iter().fold(Pt3::origin().coords, |acc, &i| acc + p[i].coords) / s.len() as f64;
        let out = centroid(&outside) - centroid(&inside);
        let mut e = |i: usize, j: usize| self.vertex(k[i], k[j], &p[i], &p[j], v[i], v[j]);
        match (inside.len(), outside.len()) {
            (1, 3) | (3, 1) => {
                let (a, rest) = if inside.len() == 1 { (inside[0], outside) } else { (outside[0], inside) };
                let t = [e(a, rest[0]), e(a, rest[1]), e(a, rest[2])];
                self.tri(t, &out);
            }
            _ => {
                let (a, b, c, d) = (inside[0], inside[1], outside[0], outside[1]);
                let (ac, ad, bd, bc) = (e(a, c), e(a, d), e(b, d), e(b, c));
                self.tri([ac, ad, bd], &out);
                self.tri([ac, bd, bc], &out);
            }
        }
    }

    /// The finished mesh (validated by [`TriMesh::new`]).
    pub(crate) fn finish(self) -> Result<TriMesh> {
        if self.faces.is_empty() {
            return Err(Error::InvalidParameter("marching tetrahedra: the field has no zero crossing".into()));
        }
        TriMesh::new(self.positions, self.faces)
    }
}

/// Triangulates the zero level set of the piecewise-linear field `values` (one per node) on the
/// tetrahedral grid `(nodes, tets)`.
///
/// `{value < 0}` is inside; triangles face outward; vertices on the same grid edge are shared, so
/// a conforming grid whose boundary nodes are all outside gives a closed, oriented 2-manifold.
/// Values with `|v| < snap` become `±snap` keeping their sign, an exact `0` becomes `+snap`.
///
/// Departure from GEOM-CORE.md §3.11: returns `Result` (an empty level set, or a non-manifold
/// result from a non-conforming grid, is an error, never a panic).
pub fn marching_tets(nodes: &[Pt3], tets: &[[u32; 4]], values: &[f64], snap: f64) -> Result<TriMesh> {
    if values.len() != nodes.len() {
        return Err(Error::DimensionMismatch {
            what: "marching_tets values",
            expected: nodes.len(),
            got: values.len(),
        });
    }
    let mut m = Marcher::new();
    for (ti, t) in tets.iter().enumerate() {
        if let Some(&bad) = t.iter().find(|&&i| i as usize >= nodes.len()) {
            return Err(Error::IndexOutOfRange { face: ti as u32, vertex: bad });
        }
        let v = t.map(|i| snap_value(values[i as usize], snap));
        if v.iter().any(|x| !x.is_finite()) {
            return Err(Error::NonFinite("marching_tets values"));
        }
        m.tet(t.map(|i| i as u64), t.map(|i| nodes[i as usize]), v);
    }
    m.finish()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn single_tet_cases_face_outward() {
        let nodes =
            [Pt3::new(0.0, 0.0, 0.0), Pt3::new(1.0, 0.0, 0.0), Pt3::new(0.0, 1.0, 0.0), Pt3::new(0.0, 0.0, 1.0)];
        // The field x + y + z − 0.5 (one node inside): gradient (1, 1, 1), normals must have a
        // positive sum.
        let v: Vec<f64> = nodes.iter().map(|p| p.x + p.y + p.z - 0.5).collect();
        let m = marching_tets(&nodes, &[[0, 1, 2, 3]], &v, 1e-9).expect("one crossing");
        let [a, b, c] = m.faces[0].map(|i| m.positions[i as usize]);
        assert!((b - a).cross(&(c - a)).sum() > 0.0);
        // Three inside, node 3 outside: the normal points towards node 3.
        let m = marching_tets(&nodes, &[[0, 1, 2, 3]], &[-1.0, -1.0, -1.0, 1.0], 1e-9).expect("one crossing");
        let [a, b, c] = m.faces[0].map(|i| m.positions[i as usize]);
        assert!((b - a).cross(&(c - a)).z > 0.0);
        // Two inside, two outside: a quad (two triangles).
        let v = [-1.0, -1.0, 1.0, 1.0];
        let m = marching_tets(&nodes, &[[0, 1, 2, 3]], &v, 1e-9).expect("quad");
        assert_eq!(m.faces.len(), 2);
        assert_eq!(m.positions.len(), 4);
        assert!(matches!(marching_tets(&nodes, &[[0, 1, 2, 3]], &[1.0; 4], 1e-9), Err(Error::InvalidParameter(_))));
        assert!(matches!(marching_tets(&nodes, &[[0, 1, 2, 9]], &v, 1e-9), Err(Error::IndexOutOfRange { .. })));
    }

    #[test]
    fn snapping_keeps_signs() {
        assert_eq!(snap_value(0.0, 0.1), 0.1);
        assert_eq!(snap_value(-0.01, 0.1), -0.1);
        assert_eq!(snap_value(0.01, 0.1), 0.1);
        assert_eq!(snap_value(-3.0, 0.1), -3.0);
    }
}

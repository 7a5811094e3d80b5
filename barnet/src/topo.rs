//! [`PolyTopo`]: edge-level connectivity of a polygon mesh (any face sizes), as needed by the
//! bar-net (bars = edges), the Catmull–Clark operator (edge and face points) and the capped
//! volume (boundary loops).
//!
//! Edges, edge faces and vertex faces come from `geom_core::mesh::PolyMesh`, boundary loops
//! from `geom_core::mesh::Topology` on the fan triangulation; this type adds the face → edge
//! and vertex → edge maps the bar-net and Catmull–Clark need.

use crate::error::{BarNetError, Result};
use geom_core::graph::Ragged;
use geom_core::mesh::{PolyMesh, Topology};

/// Edge connectivity of a polygon mesh.
#[derive(Clone, Debug)]
pub struct PolyTopo {
    /// Number of vertices.
    pub n_vertices: usize,
    /// Unique undirected edges `[a, b]` with `a < b`, sorted.
    pub edges: Vec<[u32; 2]>,
    /// Faces incident to each edge (one on the boundary, two inside, more if non-manifold).
    pub edge_faces: Ragged<u32>,
    /// Per face, per corner `i`: the edge joining corner `i` and corner `i + 1`.
    pub face_edges: Ragged<u32>,
    /// Edges incident to each vertex.
    pub vertex_edges: Ragged<u32>,
    /// Faces incident to each vertex.
    pub vertex_faces: Ragged<u32>,
}

impl PolyTopo {
    /// Builds the connectivity. Errors: a face with fewer than 3 corners or an out-of-range
    /// index (`InvalidParameter` / `NodeOutOfRange`), or a face repeating a vertex. Edges, edge
    /// faces and vertex faces are geom-core's (`PolyMesh::edges`, `edge_faces`, `vertex_faces`).
    pub fn new(m: &PolyMesh) -> Result<Self> {
        let n = m.positions.len();
        for (f, row) in m.faces.rows().enumerate() {
            if row.len() < 3 {
                return Err(BarNetError::InvalidParameter(format!("face {f} has {} corners (< 3)", row.len())));
            }
            for (i, &a) in row.iter().enumerate() {
                let b = row[(i + 1) % row.len()];
                for v in [a, b] {
                    if v as usize >= n {
                        return Err(BarNetError::NodeOutOfRange { bar: usize::MAX, node: v, n_nodes: n });
                    }
                }
                if a == b {
                    return Err(BarNetError::InvalidParameter(format!("face {f} repeats vertex {a}")));
                }
            }
        }
        let edges = m.edges();
        let edge_faces = m.edge_faces();
        let mut face_edges = Ragged::new();
        let mut row_e = Vec::new();
        for row in m.faces.rows() {
            row_e.clear();
            for (i, &a) in row.iter().enumerate() {
                let b = row[(i + 1) % row.len()];
                // Every face edge is in `edges` (geom-core lists them all, sorted).
                let e = edges.binary_search(&[a.min(b), a.max(b)]).expect("face edge listed") as u32;
                row_e.push(e);
            }
            face_edges.push_row(&row_e);
        }
        let mut ve = Vec::with_capacity(2 * edges.len());
        for (i, e) in edges.iter().enumerate() {
            ve.push((e[0], i as u32));
            ve.push((e[1], i as u32));
        }
        let vertex_edges = Ragged::from_pairs(n, &ve);
        let vertex_faces = m.vertex_faces();
        Ok(Self { n_vertices: n, edges, edge_faces, face_edges, vertex_edges, vertex_faces })
    }

    /// True when edge `e` has exactly one incident face.
    pub fn is_boundary_edge(&self, e: usize) -> bool {
        self.edge_faces.row(e).len() == 1
    }

    /// The fan triangulation of `m` and its geom-core [`Topology`] (manifold, consistently
    /// oriented). Errors: those of `Topology::new` (non-manifold edge or vertex, inconsistent
    /// orientation).
    pub fn triangle_topology(m: &PolyMesh) -> Result<(Vec<[u32; 3]>, Topology)> {
        let mut tris = Vec::with_capacity(m.faces.items.len());
        for row in m.faces.rows() {
            for i in 1..row.len().saturating_sub(1) {
                tris.push([row[0], row[i], row[i + 1]]);
            }
        }
        let t = Topology::new(m.positions.len(), &tris)?;
        Ok((tris, t))
    }

    /// Boundary loops as vertex sequences following the faces' orientation (each directed
    /// boundary edge `a → b` as it appears in its face): geom-core's `Topology::boundary_loops`
    /// of the fan triangulation (whose extra diagonals are interior). Errors: see
    /// [`Self::triangle_topology`].
    pub fn try_boundary_loops(m: &PolyMesh) -> Result<Vec<Vec<u32>>> {
        Ok(Self::triangle_topology(m)?.1.boundary_loops())
    }

    /// [`Self::try_boundary_loops`] for meshes known to be manifold and consistently oriented;
    /// returns no loop for a mesh geom-core's topology rejects (use `try_boundary_loops` to get
    /// the error).
    pub fn boundary_loops(&self, m: &PolyMesh) -> Vec<Vec<u32>> {
        Self::try_boundary_loops(m).unwrap_or_default()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use geom_core::math::Pt3;

    fn square_with_two_quads() -> PolyMesh {
        // 0-1-2 / 3-4-5 grid, two quads.
        let positions = (0..6).map(|i| Pt3::new((i % 3) as f64, (i / 3) as f64, 0.0)).collect();
        PolyMesh { positions, faces: Ragged::from_rows([vec![0u32, 1, 4, 3], vec![1, 2, 5, 4]]), uv: None }
    }

    #[test]
    fn counts_edges_and_boundary() {
        let m = square_with_two_quads();
        let t = PolyTopo::new(&m).unwrap();
        assert_eq!(t.edges.len(), 7);
        let interior: Vec<_> = (0..7).filter(|&e| !t.is_boundary_edge(e)).collect();
        assert_eq!(interior.len(), 1);
        assert_eq!(t.edges[interior[0]], [1, 4]);
        let loops = t.boundary_loops(&m);
        assert_eq!(loops.len(), 1);
        assert_eq!(loops[0], vec![0, 1, 2, 5, 4, 3]);
    }

    #[test]
    fn bad_faces_are_errors() {
        let mut m = square_with_two_quads();
        m.faces = Ragged::from_rows([vec![0u32, 1]]);
        assert!(PolyTopo::new(&m).is_err());
        m.faces = Ragged::from_rows([vec![0u32, 1, 9]]);
        assert!(matches!(PolyTopo::new(&m), Err(BarNetError::NodeOutOfRange { node: 9, .. })));
    }
}

//! [`PolyTopo`]: edge-level connectivity of a polygon mesh (any face sizes), as needed by the
//! bar-net (bars = edges), the Catmull–Clark operator (edge and face points) and the capped
//! volume (boundary loops).
//!
//! Should move to geom-core (`PolyMesh::edges`, `edge_faces`, boundary loops are listed in
//! GEOM-CORE.md §3.4 but were not available when this crate was written).

use crate::error::{BarNetError, Result};
use geom_core::graph::Ragged;
use geom_core::mesh::PolyMesh;
use std::collections::HashMap;

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
    /// index (`InvalidParameter` / `NodeOutOfRange`), or a face repeating a vertex.
    pub fn new(m: &PolyMesh) -> Result<Self> {
        let n = m.positions.len();
        let mut key: HashMap<(u32, u32), u32> = HashMap::new();
        let mut edges: Vec<[u32; 2]> = Vec::new();
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
                let k = (a.min(b), a.max(b));
                if let std::collections::hash_map::Entry::Vacant(e) = key.entry(k) {
                    e.insert(0);
                    edges.push([k.0, k.1]);
                }
            }
        }
        edges.sort_unstable();
        for (i, e) in edges.iter().enumerate() {
            key.insert((e[0], e[1]), i as u32);
        }
        let mut ef_pairs = Vec::new();
        let mut face_edges = Ragged::new();
        let mut row_e = Vec::new();
        for (f, row) in m.faces.rows().enumerate() {
            row_e.clear();
            for (i, &a) in row.iter().enumerate() {
                let b = row[(i + 1) % row.len()];
                let e = key[&(a.min(b), a.max(b))];
                row_e.push(e);
                ef_pairs.push((e, f as u32));
            }
            face_edges.push_row(&row_e);
        }
        let edge_faces = Ragged::from_pairs(edges.len(), &ef_pairs);
        let mut ve = Vec::with_capacity(2 * edges.len());
        for (i, e) in edges.iter().enumerate() {
            ve.push((e[0], i as u32));
            ve.push((e[1], i as u32));
        }
        let vertex_edges = Ragged::from_pairs(n, &ve);
        let mut vf = Vec::new();
        for (f, row) in m.faces.rows().enumerate() {
            for &v in row {
                vf.push((v, f as u32));
            }
        }
        let vertex_faces = Ragged::from_pairs(n, &vf);
        Ok(Self { n_vertices: n, edges, edge_faces, face_edges, vertex_edges, vertex_faces })
    }

    /// True when edge `e` has exactly one incident face.
    pub fn is_boundary_edge(&self, e: usize) -> bool {
        self.edge_faces.row(e).len() == 1
    }

    /// Boundary loops as vertex sequences following the faces' orientation (each directed
    /// boundary edge `a → b` as it appears in its face). Non-manifold boundary vertices (more
    /// than two boundary edges) end a chain; open chains are returned as they are.
    pub fn boundary_loops(&self, m: &PolyMesh) -> Vec<Vec<u32>> {
        let mut next: HashMap<u32, u32> = HashMap::new();
        for (e, _) in self.edges.iter().enumerate() {
            if !self.is_boundary_edge(e) {
                continue;
            }
            let f = self.edge_faces.row(e)[0] as usize;
            let row = m.faces.row(f);
            let fe = self.face_edges.row(f);
            let i = fe.iter().position(|&x| x as usize == e).expect("edge belongs to its face (built together)");
            next.insert(row[i], row[(i + 1) % row.len()]);
        }
        let mut starts: Vec<u32> = next.keys().copied().collect();
        starts.sort_unstable();
        let mut used = std::collections::HashSet::new();
        let mut loops = Vec::new();
        for s in starts {
            if used.contains(&s) {
                continue;
            }
            let mut lp = vec![s];
            used.insert(s);
            let mut v = s;
            while let Some(&w) = next.get(&v) {
                if w == s || used.contains(&w) {
                    break;
                }
                used.insert(w);
                lp.push(w);
                v = w;
            }
            loops.push(lp);
        }
        loops
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

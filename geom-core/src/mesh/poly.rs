//! [`PolyMesh`]: a plain polygon mesh (faces of any size), as read from OBJ/OFF files or built as
//! control meshes; triangulate it to get a [`super::TriMesh`].

use super::{TriMesh, Uv};
use crate::error::{Error, Result};
use crate::graph::Ragged;
use crate::math::{Pt2, Pt3};

/// A polygon mesh: positions and faces of three or more vertices each, with optional per-vertex
/// texture coordinates. No validation beyond what the constructor's caller did.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PolyMesh {
    /// Vertex positions (m).
    pub positions: Vec<Pt3>,
    /// One row of vertex indices per face, counter-clockwise seen from the front.
    pub faces: Ragged<u32>,
    /// Optional per-vertex texture coordinates (metres of material space).
    pub uv: Option<Vec<Pt2>>,
}

impl PolyMesh {
    /// Undirected edges `[a, b]` with `a < b`, sorted and unique (consecutive vertices of each
    /// face, including the closing edge).
    pub fn edges(&self) -> Vec<[u32; 2]> {
        let mut e: Vec<[u32; 2]> = self.directed_edges().map(|(a, b, _)| if a < b { [a, b] } else { [b, a] }).collect();
        e.sort_unstable();
        e.dedup();
        e
    }

    /// Faces of each edge of [`Self::edges`] (same order), ascending: one face on the boundary,
    /// two in the interior, more at non-manifold edges.
    pub fn edge_faces(&self) -> Ragged<u32> {
        let edges = self.edges();
        let mut pairs: Vec<(u32, u32)> = self
            .directed_edges()
            .map(|(a, b, f)| {
                let key = if a < b { [a, b] } else { [b, a] };
                // Every directed edge's key is in `edges` by construction.
                (edges.binary_search(&key).expect("edge listed") as u32, f)
            })
            .collect();
        pairs.sort_unstable();
        pairs.dedup();
        Ragged::from_pairs(edges.len(), &pairs)
    }

    /// Faces around each vertex, ascending (unordered fan). Out-of-range indices are skipped.
    pub fn vertex_faces(&self) -> Ragged<u32> {
        let n = self.positions.len();
        let mut pairs: Vec<(u32, u32)> = Vec::with_capacity(self.faces.items.len());
        for (f, row) in self.faces.rows().enumerate() {
            for &v in row {
                if (v as usize) < n {
                    pairs.push((v, f as u32));
                }
            }
        }
        pairs.sort_unstable();
        pairs.dedup();
        Ragged::from_pairs(n, &pairs)
    }

    /// Triangulates every polygon `[v0, v1, …, vk]` as the fan `(v0, vi, vi+1)` and validates the
    /// result with [`TriMesh::new`]. Returns the mesh (per-vertex UVs carried over) and, per
    /// triangle, the index of its polygon. Errors: [`Error::InvalidParameter`] for a polygon with
    /// fewer than three vertices or a UV list of the wrong length, and every [`TriMesh::new`]
    /// error (indices refer to the triangulated faces; map them back with the returned list).
    pub fn triangulate_fan(&self) -> Result<(TriMesh, Vec<u32>)> {
        let mut tris = Vec::with_capacity(self.faces.items.len());
        let mut parent = Vec::with_capacity(self.faces.items.len());
        for (f, row) in self.faces.rows().enumerate() {
            if row.len() < 3 {
                return Err(Error::InvalidParameter(format!(
                    "polygon {f} has {} vertices (at least 3 needed)",
                    row.len()
                )));
            }
            for i in 1..row.len() - 1 {
                tris.push([row[0], row[i], row[i + 1]]);
                parent.push(f as u32);
            }
        }
        let mut m = TriMesh::new(self.positions.clone(), tris)?;
        if let Some(uv) = &self.uv {
            m = m.with_uv(Uv::PerVertex(uv.clone()))?;
        }
        Ok((m, parent))
    }

    fn directed_edges(&self) -> impl Iterator<Item = (u32, u32, u32)> + '_ {
        self.faces.rows().enumerate().flat_map(|(f, row)| {
            (0..row.len()).filter_map(move |k| {
                let (a, b) = (row[k], row[(k + 1) % row.len()]);
                (a != b).then_some((a, b, f as u32))
            })
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn two_quads() -> PolyMesh {
        let positions = (0..6).map(|i| Pt3::new((i % 3) as f64, (i / 3) as f64, 0.0)).collect();
        PolyMesh { positions, faces: Ragged::from_rows([vec![0u32, 1, 4, 3], vec![1, 2, 5, 4]]), uv: None }
    }

    #[test]
    fn poly_edges_and_incidence() {
        let m = two_quads();
        assert_eq!(m.edges(), vec![[0, 1], [0, 3], [1, 2], [1, 4], [2, 5], [3, 4], [4, 5]]);
        let ef = m.edge_faces();
        assert_eq!(ef.row(3), &[0, 1]); // the shared edge 1–4
        assert_eq!(ef.row(0), &[0]);
        let vf = m.vertex_faces();
        assert_eq!(vf.row(4), &[0, 1]);
        assert_eq!(vf.row(5), &[1]);
    }

    #[test]
    fn fan_triangulation_maps_back() {
        let m = two_quads();
        let (t, parent) = m.triangulate_fan().expect("two planar quads triangulate to a valid mesh");
        assert_eq!(t.faces, vec![[0, 1, 4], [0, 4, 3], [1, 2, 5], [1, 5, 4]]);
        assert_eq!(parent, vec![0, 0, 1, 1]);
        let bad = PolyMesh { faces: Ragged::from_rows([vec![0u32, 1]]), ..m };
        assert!(matches!(bad.triangulate_fan(), Err(Error::InvalidParameter(_))));
    }
}

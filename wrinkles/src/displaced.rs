//! Conforming regular refinement of a coarse triangle mesh (spec §3.13): every triangle split
//! into `L²` sub-triangles, lattice vertices shared along coarse edges, so the displaced surface
//! is watertight. Vertex count `V + E(L−1) + T(L−1)(L−2)/2`.

use geom_core::math::{Pt2, Pt3};
use geom_core::mesh::{TriMesh, Uv};

use crate::error::Result;

/// The refinement's combinatorics: per coarse face, the global index of each lattice point
/// `(i, j)` (barycentric `((L−i−j)/L, i/L, j/L)`), and the refined faces.
#[derive(Clone, Debug)]
pub struct Refinement {
    /// Level L ≥ 1.
    pub level: u32,
    /// Number of refined vertices.
    pub n_vertices: usize,
    /// `lattice[f][idx(i, j)]`: global vertex of lattice point (i, j) of face f.
    pub lattice: Vec<Vec<u32>>,
    /// Refined faces with their coarse face and the lattice points of their corners.
    pub faces: Vec<[u32; 3]>,
    /// Coarse face of each refined face.
    pub parent: Vec<u32>,
    /// Per refined face, the barycentric coordinates of its corners in the coarse face.
    pub corner_bary: Vec<[[f64; 3]; 3]>,
}

/// Index of lattice point (i, j), i + j ≤ L, in row-major triangular order.
pub fn lattice_index(level: u32, i: u32, j: u32) -> usize {
    // Row j holds L − j + 1 points; rows before it hold j(L+1) − j(j−1)/2.
    let (l, i, j) = (level as usize, i as usize, j as usize);
    j * (l + 1) - j * j.saturating_sub(1) / 2 + i
}

fn bary(level: u32, i: u32, j: u32) -> [f64; 3] {
    let l = level as f64;
    [(level - i - j) as f64 / l, i as f64 / l, j as f64 / l]
}

impl Refinement {
    /// Builds the refinement of `faces` over `n_coarse` vertices with unique `edges` (sorted
    /// `[a, b]`, `a < b`, as in [`crate::WrinkleRig::edges`]).
    pub fn new(n_coarse: usize, faces: &[[u32; 3]], edges: &[[u32; 2]], level: u32) -> Self {
        let l = level.max(1);
        let per_edge = (l - 1) as usize;
        let per_face = ((l as usize - 1) * (l as usize).saturating_sub(2)) / 2;
        let base_face = n_coarse + edges.len() * per_edge;
        let n_vertices = base_face + faces.len() * per_face;
        let n_lat = ((l + 1) * (l + 2) / 2) as usize;
        let edge_id =
            |a: u32, b: u32| edges.binary_search(&[a.min(b), a.max(b)]).expect("edge list built from these faces");
        let mut lattice = Vec::with_capacity(faces.len());
        for (f, t) in faces.iter().enumerate() {
            let mut lat = vec![0u32; n_lat];
            let mut interior = 0usize;
            for j in 0..=l {
                for i in 0..=(l - j) {
                    let k = l - i - j;
                    let idx = lattice_index(l, i, j);
                    // Which coarse element holds the point: corner, edge, or interior.
                    let g = match (k == 0, i == 0, j == 0) {
                        (_, true, true) => t[0] as usize,
                        (true, _, true) => t[1] as usize,
                        (true, true, _) => t[2] as usize,
                        (_, _, true) => edge_point(edge_id(t[0], t[1]), t[0], t[1], i, n_coarse, per_edge, l),
                        (true, _, _) => edge_point(edge_id(t[1], t[2]), t[1], t[2], j, n_coarse, per_edge, l),
                        (_, true, _) => edge_point(edge_id(t[2], t[0]), t[2], t[0], k, n_coarse, per_edge, l),
                        _ => {
                            interior += 1;
                            base_face + f * per_face + interior - 1
                        }
                    };
                    lat[idx] = g as u32;
                }
            }
            lattice.push(lat);
        }
        let mut out_faces = Vec::with_capacity(faces.len() * (l * l) as usize);
        let mut parent = Vec::with_capacity(out_faces.capacity());
        let mut corner_bary = Vec::with_capacity(out_faces.capacity());
        for (f, lat) in lattice.iter().enumerate() {
            for j in 0..l {
                for i in 0..(l - j) {
                    let c = [(i, j), (i + 1, j), (i, j + 1)];
                    out_faces.push(c.map(|(a, b)| lat[lattice_index(l, a, b)]));
                    corner_bary.push(c.map(|(a, b)| bary(l, a, b)));
                    parent.push(f as u32);
                    if i + j + 1 < l {
                        let c = [(i + 1, j), (i + 1, j + 1), (i, j + 1)];
                        out_faces.push(c.map(|(a, b)| lat[lattice_index(l, a, b)]));
                        corner_bary.push(c.map(|(a, b)| bary(l, a, b)));
                        parent.push(f as u32);
                    }
                }
            }
        }
        Self { level: l, n_vertices, lattice, faces: out_faces, parent, corner_bary }
    }
}

/// Global index of the point `s` steps (1 ≤ s < L) from `from` towards `to` on edge `e`.
fn edge_point(e: usize, from: u32, to: u32, s: u32, n_coarse: usize, per_edge: usize, l: u32) -> usize {
    let s_from_min = if from < to { s } else { l - s };
    n_coarse + e * per_edge + (s_from_min - 1) as usize
}

/// A displaced refined surface: positions, faces, per-corner UVs.
#[derive(Clone, Debug)]
pub struct DisplacedMesh {
    /// Vertex positions (m).
    pub positions: Vec<Pt3>,
    /// Triangles.
    pub faces: Vec<[u32; 3]>,
    /// Per-corner UVs (seams allowed).
    pub uv: Uv,
}

impl DisplacedMesh {
    /// As a validated geom-core mesh (fails if displacement made faces degenerate).
    pub fn into_trimesh(self) -> Result<TriMesh> {
        Ok(TriMesh::new(self.positions, self.faces)?.with_uv(self.uv)?)
    }

    /// Total surface area (m²).
    pub fn area(&self) -> f64 {
        self.faces
            .iter()
            .map(|t| {
                let p = |k: usize| self.positions[t[k] as usize];
                0.5 * (p(1) - p(0)).cross(&(p(2) - p(0))).norm()
            })
            .sum()
    }
}

/// Per-corner UVs of the refined faces from the coarse UVs.
pub fn refined_uv(r: &Refinement, coarse_uv: impl Fn(usize, usize) -> Pt2) -> Uv {
    Uv::PerCorner(
        r.corner_bary
            .iter()
            .zip(&r.parent)
            .map(|(cb, &f)| {
                cb.map(|b| {
                    let f = f as usize;
                    Pt2::from(
                        coarse_uv(f, 0).coords * b[0] + coarse_uv(f, 1).coords * b[1] + coarse_uv(f, 2).coords * b[2],
                    )
                })
            })
            .collect(),
    )
}

//! Subdivision surfaces as sparse operators (spec §3.4.4 `Subdivision`): the fine mesh is
//! `fine = S · control` with `S` (n_fine × n_control) built once from the topology, exact for
//! the subdivision surface of the chosen level.
//!
//! - [`catmull_clark`]: Catmull and Clark (1978) on any polygon mesh; every level yields quads.
//!   Interior rules: face point = face centroid; edge point = (a + b + F₁ + F₂)/4; vertex point
//!   = (F̄ + 2R̄ + (k − 3)V)/k (F̄ mean of adjacent face points, R̄ mean of edge midpoints,
//!   k valence). Boundary (crease) rules: edge point = midpoint, vertex = (a + 6V + b)/8 over
//!   its two boundary neighbours; a boundary vertex with a single face (a corner) or more than
//!   two boundary edges stays where it is.
//! - [`loop_subdivision`]: Loop (1987) on triangle meshes; edge point = 3/8 (a + b) + 1/8 (c + d),
//!   vertex = (1 − kβ) V + β Σ neighbours with Loop's β(k); the same boundary rules.
//!
//! Fine vertex numbering: the coarse vertices keep their indices, then one vertex per edge (in
//! [`PolyTopo`] edge order), then (Catmull–Clark) one per face.
//! Catmull–Clark operator rows and its face construction live here, not in geom-core
//! (GEOM-CORE.md §6: one user).

use crate::error::{BarNetError, Result};
use crate::topo::PolyTopo;
use geom_core::graph::Ragged;
use geom_core::linalg::{Csr, Triplets};
use geom_core::math::Pt3;
use geom_core::mesh::PolyMesh;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// Subdivision scheme of the fine surface.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum Scheme {
    /// Catmull–Clark (any polygons).
    CatmullClark,
    /// Loop (triangles only).
    Loop,
}

/// Subdivides `m` `levels` times with `scheme`; returns the fine mesh (positions = `S · m`)
/// and the operator `S`. Level 0 returns `m` and the identity.
pub fn subdivide(m: &PolyMesh, scheme: Scheme, levels: u32) -> Result<(PolyMesh, Csr)> {
    let mut mesh = m.clone();
    let mut s = Csr::identity(m.positions.len());
    for _ in 0..levels {
        let (faces, s1) = match scheme {
            Scheme::CatmullClark => catmull_clark_level(&mesh)?,
            Scheme::Loop => loop_level(&mesh)?,
        };
        let mut p = vec![Pt3::origin(); s1.nrows];
        apply(&s1, &mesh.positions, &mut p);
        s = s1.matmul(&s);
        mesh = PolyMesh { positions: p, faces, uv: None };
    }
    Ok((mesh, s))
}

/// Catmull–Clark subdivision, `levels` times (see [`subdivide`]).
pub fn catmull_clark(m: &PolyMesh, levels: u32) -> Result<(PolyMesh, Csr)> {
    subdivide(m, Scheme::CatmullClark, levels)
}

/// Loop subdivision, `levels` times (see [`subdivide`]). Errors: a non-triangle face.
pub fn loop_subdivision(m: &PolyMesh, levels: u32) -> Result<(PolyMesh, Csr)> {
    subdivide(m, Scheme::Loop, levels)
}

/// Row `i` of `S · p`, accumulated in f64 in the row's column order.
fn row_times(s: &Csr, p: &[Pt3], i: usize) -> [f64; 3] {
    let (c, w) = s.row(i);
    let mut acc = [0.0f64; 3];
    for (&j, &wj) in c.iter().zip(w) {
        let q = &p[j as usize];
        acc[0] += wj * q.x;
        acc[1] += wj * q.y;
        acc[2] += wj * q.z;
    }
    acc
}

/// `out = S · p` (f64).
pub fn apply(s: &Csr, p: &[Pt3], out: &mut [Pt3]) {
    for (i, o) in out.iter_mut().enumerate().take(s.nrows) {
        let acc = row_times(s, p, i);
        *o = Pt3::new(acc[0], acc[1], acc[2]);
    }
}

/// `out = S · p` in `f32` (the fine-mesh output format), accumulated in f64; rows in parallel
/// when `parallel` (bitwise identical to serial: each row is computed by one thread in order).
pub fn apply_f32(s: &Csr, p: &[Pt3], out: &mut [[f32; 3]], parallel: bool) {
    let row = |i: usize| -> [f32; 3] {
        let acc = row_times(s, p, i);
        [acc[0] as f32, acc[1] as f32, acc[2] as f32]
    };
    if parallel {
        out.par_iter_mut().enumerate().for_each(|(i, o)| *o = row(i));
    } else {
        for (i, o) in out.iter_mut().enumerate() {
            *o = row(i);
        }
    }
}

/// Boundary classification of a vertex: its boundary-edge neighbours and face count.
fn boundary_neighbours(t: &PolyTopo, v: usize) -> Vec<u32> {
    t.vertex_edges
        .row(v)
        .iter()
        .filter(|&&e| t.is_boundary_edge(e as usize))
        .map(|&e| {
            let [a, b] = t.edges[e as usize];
            if a as usize == v {
                b
            } else {
                a
            }
        })
        .collect()
}

/// Pushes the boundary/corner vertex rule; returns false when `v` is interior.
fn push_boundary_vertex(tr: &mut Triplets, t: &PolyTopo, v: usize) -> bool {
    let bn = boundary_neighbours(t, v);
    if bn.is_empty() {
        return false;
    }
    if bn.len() == 2 && t.vertex_faces.row(v).len() > 1 {
        tr.push(v as u32, bn[0], 0.125);
        tr.push(v as u32, v as u32, 0.75);
        tr.push(v as u32, bn[1], 0.125);
    } else {
        tr.push(v as u32, v as u32, 1.0);
    }
    true
}

/// One Catmull–Clark level: new faces and the operator.
fn catmull_clark_level(m: &PolyMesh) -> Result<(Ragged<u32>, Csr)> {
    let t = PolyTopo::new(m)?;
    let (nv, ne, nf) = (m.positions.len(), t.edges.len(), m.faces.len());
    let n1 = nv + ne + nf;
    let mut tr = Triplets::with_capacity(n1, nv, 16 * n1);
    // Vertex points.
    for v in 0..nv {
        if push_boundary_vertex(&mut tr, &t, v) {
            continue;
        }
        let faces = t.vertex_faces.row(v);
        let edges = t.vertex_edges.row(v);
        let k = edges.len();
        if k == 0 {
            tr.push(v as u32, v as u32, 1.0);
            continue;
        }
        let kf = k as f64;
        // F̄ / k: each adjacent face point is the mean of its face.
        for &f in faces {
            let row = m.faces.row(f as usize);
            let w = 1.0 / (faces.len() as f64 * row.len() as f64 * kf);
            for &u in row {
                tr.push(v as u32, u, w);
            }
        }
        // 2 R̄ / k: edge midpoints.
        for &e in edges {
            let [a, b] = t.edges[e as usize];
            let w = 2.0 / (kf * kf) * 0.5;
            tr.push(v as u32, a, w);
            tr.push(v as u32, b, w);
        }
        tr.push(v as u32, v as u32, (kf - 3.0) / kf);
    }
    // Edge points.
    for (e, &[a, b]) in t.edges.iter().enumerate() {
        let r = (nv + e) as u32;
        let faces = t.edge_faces.row(e);
        if faces.len() == 2 {
            tr.push(r, a, 0.25);
            tr.push(r, b, 0.25);
            for &f in faces {
                let row = m.faces.row(f as usize);
                let w = 0.25 / row.len() as f64;
                for &u in row {
                    tr.push(r, u, w);
                }
            }
        } else {
            tr.push(r, a, 0.5);
            tr.push(r, b, 0.5);
        }
    }
    // Face points.
    for f in 0..nf {
        let row = m.faces.row(f);
        let w = 1.0 / row.len() as f64;
        for &u in row {
            tr.push((nv + ne + f) as u32, u, w);
        }
    }
    let mut faces = Ragged::new();
    for f in 0..nf {
        let row = m.faces.row(f);
        let fe = t.face_edges.row(f);
        let k = row.len();
        let fp = (nv + ne + f) as u32;
        for i in 0..k {
            let e_next = nv as u32 + fe[i];
            let e_prev = nv as u32 + fe[(i + k - 1) % k];
            faces.push_row(&[row[i], e_next, fp, e_prev]);
        }
    }
    Ok((faces, Csr::from_triplets(&tr)))
}

/// Loop's β for an interior vertex of valence `k`.
fn loop_beta(k: usize) -> f64 {
    let kf = k as f64;
    let c = 0.375 + 0.25 * (2.0 * std::f64::consts::PI / kf).cos();
    (0.625 - c * c) / kf
}

/// One Loop level: new faces and the operator.
fn loop_level(m: &PolyMesh) -> Result<(Ragged<u32>, Csr)> {
    if let Some(f) = m.faces.rows().position(|r| r.len() != 3) {
        return Err(BarNetError::InvalidParameter(format!(
            "Loop subdivision needs triangles; face {f} has {} corners",
            m.faces.row(f).len()
        )));
    }
    let t = PolyTopo::new(m)?;
    let (nv, ne) = (m.positions.len(), t.edges.len());
    let n1 = nv + ne;
    let mut tr = Triplets::with_capacity(n1, nv, 8 * n1);
    for v in 0..nv {
        if push_boundary_vertex(&mut tr, &t, v) {
            continue;
        }
        let edges = t.vertex_edges.row(v);
        let k = edges.len();
        let beta = loop_beta(k.max(1));
        for &e in edges {
            let [a, b] = t.edges[e as usize];
            tr.push(v as u32, if a as usize == v { b } else { a }, beta);
        }
        tr.push(v as u32, v as u32, 1.0 - k as f64 * beta);
    }
    for (e, &[a, b]) in t.edges.iter().enumerate() {
        let r = (nv + e) as u32;
        let faces = t.edge_faces.row(e);
        if faces.len() == 2 {
            tr.push(r, a, 0.375);
            tr.push(r, b, 0.375);
            for &f in faces {
                let opp = m.faces.row(f as usize).iter().copied().find(|&u| u != a && u != b);
                let opp = opp.expect("a triangle has a vertex off each of its edges");
                tr.push(r, opp, 0.125);
            }
        } else {
            tr.push(r, a, 0.5);
            tr.push(r, b, 0.5);
        }
    }
    let mut faces = Ragged::new();
    for f in 0..m.faces.len() {
        let v = m.faces.row(f);
        let fe = t.face_edges.row(f);
        let e: Vec<u32> = fe.iter().map(|&x| nv as u32 + x).collect();
        // e[i] joins corner i and i+1.
        faces.push_row(&[v[0], e[0], e[2]]);
        faces.push_row(&[v[1], e[1], e[0]]);
        faces.push_row(&[v[2], e[2], e[1]]);
        faces.push_row(&[e[0], e[1], e[2]]);
    }
    Ok((faces, Csr::from_triplets(&tr)))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::arm::open_tube;

    fn row_sums(s: &Csr) -> f64 {
        (0..s.nrows).map(|i| (s.row(i).1.iter().sum::<f64>() - 1.0).abs()).fold(0.0, f64::max)
    }

    /// Spec 7.3 c: rows sum to 1; affine functions reproduced; 2816 faces / 2848 vertices.
    #[test]
    fn catmull_clark_arm_counts_and_affine() {
        let m = open_tube(8, 22, 0.045, 0.57).unwrap();
        let (fine, s) = catmull_clark(&m, 2).unwrap();
        assert_eq!(fine.faces.len(), 2816);
        assert_eq!(fine.positions.len(), 2848);
        assert!(row_sums(&s) < 1e-14, "row sums off by {}", row_sums(&s));
        // An affine map A x + b of the control points maps the fine points the same way.
        let a = geom_core::math::Mat3::new(1.0, 0.2, -0.3, 0.1, 0.9, 0.4, -0.2, 0.5, 1.1);
        let b = geom_core::math::Vec3::new(0.3, -0.7, 2.0);
        let ctrl: Vec<Pt3> = m.positions.iter().map(|p| Pt3::from(a * p.coords + b)).collect();
        let mut f = vec![Pt3::origin(); s.nrows];
        apply(&s, &ctrl, &mut f);
        let err =
            f.iter().zip(&fine.positions).map(|(x, p)| (x.coords - (a * p.coords + b)).norm()).fold(0.0, f64::max);
        assert!(err < 1e-12, "affine reproduction error {err}");
    }

    /// A regular interior quad grid is reproduced on a plane and stays planar; Loop rows too.
    #[test]
    fn loop_rows_sum_to_one() {
        let tri = PolyMesh {
            positions: vec![
                Pt3::new(0.0, 0.0, 0.0),
                Pt3::new(1.0, 0.0, 0.0),
                Pt3::new(0.0, 1.0, 0.0),
                Pt3::new(1.0, 1.0, 0.3),
            ],
            faces: Ragged::from_rows([vec![0u32, 1, 2], vec![1, 3, 2]]),
            uv: None,
        };
        let (fine, s) = loop_subdivision(&tri, 2).unwrap();
        assert_eq!(fine.faces.len(), 32);
        assert!(row_sums(&s) < 1e-14);
        let quad = PolyMesh { faces: Ragged::from_rows([vec![0u32, 1, 3, 2]]), ..tri.clone() };
        assert!(loop_subdivision(&quad, 1).is_err());
    }

    #[test]
    fn parallel_apply_is_bitwise_serial() {
        let m = open_tube(8, 22, 0.045, 0.57).unwrap();
        let (_, s) = catmull_clark(&m, 2).unwrap();
        let mut a = vec![[0f32; 3]; s.nrows];
        let mut b = a.clone();
        apply_f32(&s, &m.positions, &mut a, false);
        apply_f32(&s, &m.positions, &mut b, true);
        assert_eq!(a, b);
    }
}

//! Linear (midpoint) subdivision with its prolongation operator P (GEOM-CORE.md §3.4; SH, TR).
//!
//! Each level splits every triangle `(a, b, c)` into four through the edge midpoints; coarse
//! vertices keep their indices and the midpoint of edge `e` (in [`super::Topology::edges`]
//! order) gets index `n + e`. Face `f` becomes faces `4f..4f+4`: `(a, m_ab, m_ca)`,
//! `(m_ab, b, m_bc)`, `(m_ca, m_bc, c)`, `(m_ab, m_bc, m_ca)`, all with the parent's orientation.

use std::sync::Arc;

use super::{HalfEdgeId, Topology, TriMesh, Uv};
use crate::linalg::Csr;
use crate::math::{Pt2, Pt3};

/// Subdivides `levels` times by midpoint quadrisection. Returns the fine mesh and the
/// prolongation `P = P_L ⋯ P_1` (n_fine × n_coarse, dyadic weights, rows sum to 1) with
/// `fine.positions = P · coarse.positions` exactly: the fine positions are computed as that
/// product (column order ascending, per coordinate), so they are bitwise equal to applying `P`
/// with [`Csr::mul_vec`]. Per-vertex UVs are prolongated by `P` too; per-corner UVs are
/// interpolated per face (seams preserved). `levels = 0` returns a copy and the identity.
pub fn subdivide_linear(m: &TriMesh, levels: u32) -> (TriMesh, Csr) {
    let n0 = m.positions.len();
    // P so far (starts as the identity); each level appends one merged row per edge.
    let mut pm = Csr::identity(n0);
    let mut faces = m.faces.clone();
    let mut topo: Arc<Topology> = Arc::clone(m.topology_arc());
    let mut corner_uv: Option<Vec<[Pt2; 3]>> = match &m.uv {
        Some(Uv::PerCorner(c)) => Some(c.clone()),
        _ => None,
    };
    for _ in 0..levels {
        let n = pm.nrows as u32;
        for &[a, b] in topo.edges() {
            push_half_sum(&mut pm, a as usize, b as usize);
        }
        let mut fine = Vec::with_capacity(4 * faces.len());
        for (f, t) in faces.iter().enumerate() {
            // Half-edge 3f + k runs from corner k to corner k + 1 (Topology layout).
            let mid = |k: u32| n + topo.edge(HalfEdgeId(3 * f as u32 + k)).0;
            let (mab, mbc, mca) = (mid(0), mid(1), mid(2));
            let [a, b, c] = *t;
            fine.push([a, mab, mca]);
            fine.push([mab, b, mbc]);
            fine.push([mca, mbc, c]);
            fine.push([mab, mbc, mca]);
        }
        if let Some(cu) = corner_uv.as_mut() {
            let mut next = Vec::with_capacity(4 * cu.len());
            for u in cu.iter() {
                let h = |p: Pt2, q: Pt2| Pt2::from((p.coords + q.coords) * 0.5);
                let (uab, ubc, uca) = (h(u[0], u[1]), h(u[1], u[2]), h(u[2], u[0]));
                next.push([u[0], uab, uca]);
                next.push([uab, u[1], ubc]);
                next.push([uca, ubc, u[2]]);
                next.push([uab, ubc, uca]);
            }
            *cu = next;
        }
        faces = fine;
        // Midpoint subdivision of a manifold, consistently oriented mesh is again one: every
        // coarse edge splits into two edges with the parents' twins, every new interior edge
        // is shared by a corner triangle and the centre triangle in opposite directions.
        topo = Arc::new(Topology::new(pm.nrows, &faces).expect("subdivision preserves manifoldness"));
    }
    let p = pm;
    let positions = prolongate(&p, &m.positions);
    let uv = match &m.uv {
        None => None,
        Some(Uv::PerVertex(u)) => {
            let u3: Vec<Pt3> = u.iter().map(|q| Pt3::new(q.x, q.y, 0.0)).collect();
            Some(Uv::PerVertex(prolongate(&p, &u3).iter().map(|q| Pt2::new(q.x, q.y)).collect()))
        }
        Some(Uv::PerCorner(_)) => corner_uv.map(Uv::PerCorner),
    };
    (TriMesh::from_parts(positions, faces, uv, topo), p)
}

/// Appends the row `(row_a + row_b) / 2` to `m` (rows have ascending columns; the result too).
/// Exact: P's weights are dyadic, so halving and adding them does not round.
fn push_half_sum(m: &mut Csr, a: usize, b: usize) {
    let (mut i, ie) = (m.row_ptr[a], m.row_ptr[a + 1]);
    let (mut j, je) = (m.row_ptr[b], m.row_ptr[b + 1]);
    while i < ie || j < je {
        let ca = if i < ie { m.col[i] } else { u32::MAX };
        let cb = if j < je { m.col[j] } else { u32::MAX };
        let (c, v) = if ca == cb {
            let v = 0.5 * m.val[i] + 0.5 * m.val[j];
            i += 1;
            j += 1;
            (ca, v)
        } else if ca < cb {
            i += 1;
            (ca, 0.5 * m.val[i - 1])
        } else {
            j += 1;
            (cb, 0.5 * m.val[j - 1])
        };
        m.col.push(c);
        m.val.push(v);
    }
    m.row_ptr.push(m.col.len());
    m.nrows += 1;
}

/// `P · x` per coordinate with [`Csr::mul_vec`] (so callers get bitwise the same numbers).
fn prolongate(p: &Csr, x: &[Pt3]) -> Vec<Pt3> {
    let mut out = vec![Pt3::origin(); p.nrows];
    let mut src = vec![0.0; p.ncols];
    let mut dst = vec![0.0; p.nrows];
    for d in 0..3 {
        for (s, q) in src.iter_mut().zip(x) {
            *s = q[d];
        }
        p.mul_vec(&src, &mut dst);
        for (o, v) in out.iter_mut().zip(&dst) {
            o[d] = *v;
        }
    }
    out
}

//! Discrete operators on triangle meshes as [`Csr`] matrices or lumped vectors: the cotan
//! stiffness (Laplacian) matrix, barycentric / Voronoi (Meyer et al. 2003 mixed) lumped masses,
//! the consistent P1 mass matrix and the mean-curvature normal.
//!
//! Sign convention (GEOM-CORE.md §5 item 13): the cotan matrix is positive semi-definite,
//! `L_ij = −½(cot α_ij + cot β_ij)`, `L_ii = −Σ_{j≠i} L_ij`, so `xᵀLx = ½∫|∇x|²` for P1 `x`.

use super::geometry::tri;
use crate::linalg::{Csr, Triplets};
use crate::math::{AsPt3, Pt3, Vec3};

/// Floor on `sin` in `cot = cos / max(sin, 1e-12)` (GEOM-CORE.md §3.4): keeps cotangents of
/// (nearly) degenerate corners finite.
pub const COT_SIN_FLOOR: f64 = 1e-12;

/// Cotangent of the corner at `o` between edges to `p` and `q`, scale-invariant
/// (`cos / max(sin, 1e-12)` with normalised edge vectors); 0 for a zero-length edge.
#[inline]
pub(crate) fn corner_cot(o: &Pt3, p: &Pt3, q: &Pt3) -> f64 {
    let e1 = p - o;
    let e2 = q - o;
    let l = e1.norm() * e2.norm();
    if !(l.is_finite() && l > 0.0) {
        return 0.0;
    }
    let cos = e1.dot(&e2) / l;
    let sin = e1.cross(&e2).norm() / l;
    cos / sin.max(COT_SIN_FLOOR)
}

/// The three corner cotangents of a triangle: entry `k` belongs to corner `k`, i.e. to the
/// opposite edge `(k+1, k+2)`.
#[inline]
pub(crate) fn tri_cots(x: &[Pt3; 3]) -> [f64; 3] {
    [corner_cot(&x[0], &x[1], &x[2]), corner_cot(&x[1], &x[2], &x[0]), corner_cot(&x[2], &x[0], &x[1])]
}

/// Cotan stiffness matrix (n × n, n = `p.len()`), the PSD Laplacian of P1 finite elements:
/// `L_ij = −½(cot α_ij + cot β_ij)` over the (one or two) corners opposite edge `ij`,
/// `L_ii = −Σ_{j≠i} L_ij` computed from the assembled row (so `L·1 = 0` to round-off).
/// `cot = cos / max(sin, 1e-12)`; `clamp = Some(c)` limits every corner cotangent to `[−c, c]`
/// (e.g. to tame slivers). Every vertex has a stored diagonal entry (zero for isolated vertices).
pub fn cotan_stiffness<P: AsPt3>(faces: &[[u32; 3]], p: &[P], clamp: Option<f64>) -> Csr {
    let n = p.len();
    let mut t = Triplets::with_capacity(n, n, 6 * faces.len() + n);
    for i in 0..n as u32 {
        t.push(i, i, 0.0);
    }
    for f in faces {
        let x = tri(p, f);
        let c = tri_cots(&x);
        for k in 0..3 {
            let mut ck = c[k];
            if let Some(m) = clamp {
                ck = ck.clamp(-m, m);
            }
            let (i, j) = (f[(k + 1) % 3], f[(k + 2) % 3]);
            t.push(i, j, -0.5 * ck);
            t.push(j, i, -0.5 * ck);
        }
    }
    let mut l = Csr::from_triplets(&t);
    set_diagonal_to_negative_row_sum(&mut l);
    l
}

/// Sets every stored diagonal entry to minus the sum of the row's off-diagonal entries.
fn set_diagonal_to_negative_row_sum(l: &mut Csr) {
    for i in 0..l.nrows {
        let r = l.row_ptr[i]..l.row_ptr[i + 1];
        let mut s = 0.0;
        let mut d = None;
        for k in r {
            if l.col[k] as usize == i {
                d = Some(k);
            } else {
                s += l.val[k];
            }
        }
        if let Some(k) = d {
            l.val[k] = -s;
        }
    }
}

/// Lumped barycentric mass: each vertex gets a third of the area of its faces (m²).
pub fn mass_barycentric<P: AsPt3>(faces: &[[u32; 3]], p: &[P]) -> Vec<f64> {
    let mut m = vec![0.0; p.len()];
    for f in faces {
        let a = 0.5 * super::geometry::area_vector(&tri(p, f)).norm() / 3.0;
        for &v in f {
            m[v as usize] += a;
        }
    }
    m
}

/// Lumped Voronoi mass, Meyer et al. 2003 "mixed" area (their Fig. 4): in a non-obtuse triangle
/// vertex `i` gets its Voronoi region `⅛(|e_ij|² cot γ_k + |e_ik|² cot γ_j)`; in an obtuse
/// triangle the obtuse corner gets A/2 and the others A/4. Every triangle distributes exactly
/// its area, so the total equals the total surface area (and [`mass_barycentric`]'s sum).
pub fn mass_voronoi<P: AsPt3>(faces: &[[u32; 3]], p: &[P]) -> Vec<f64> {
    let mut m = vec![0.0; p.len()];
    for f in faces {
        let x = tri(p, f);
        let area = 0.5 * super::geometry::area_vector(&x).norm();
        // Edge opposite corner k and its squared length.
        let l2 = [(x[1] - x[2]).norm_squared(), (x[2] - x[0]).norm_squared(), (x[0] - x[1]).norm_squared()];
        // Corner k is obtuse when its opposite edge is longer than the other two in Pythagoras.
        let obtuse = (0..3).find(|&k| l2[k] > l2[(k + 1) % 3] + l2[(k + 2) % 3]);
        match obtuse {
            Some(o) => {
                for k in 0..3 {
                    m[f[k] as usize] += if k == o { 0.5 * area } else { 0.25 * area };
                }
            }
            None => {
                let c = tri_cots(&x);
                for k in 0..3 {
                    let (j, l) = ((k + 1) % 3, (k + 2) % 3);
                    // Edge k–j is opposite corner l, edge k–l is opposite corner j.
                    m[f[k] as usize] += 0.125 * (l2[l] * c[l] + l2[j] * c[j]);
                }
            }
        }
    }
    m
}

/// Consistent P1 mass matrix (n × n): `M_ij = Σ_T (A_T/12)(1 + δ_ij)` over triangles containing
/// both `i` and `j`. Rows sum to the barycentric lumped mass; `1ᵀM1` is the total area.
pub fn mass_p1<P: AsPt3>(faces: &[[u32; 3]], p: &[P]) -> Csr {
    let n = p.len();
    let mut t = Triplets::with_capacity(n, n, 9 * faces.len());
    for f in faces {
        let a = 0.5 * super::geometry::area_vector(&tri(p, f)).norm();
        for (ki, &i) in f.iter().enumerate() {
            for (kj, &j) in f.iter().enumerate() {
                t.push(i, j, if ki == kj { a / 6.0 } else { a / 12.0 });
            }
        }
    }
    Csr::from_triplets(&t)
}

/// Mean-curvature normal `−M_vor⁻¹ L x = 2H n` at each vertex (m⁻¹), FT's convention: the
/// discrete Laplace–Beltrami of the position. On a sphere of radius R it points to the centre
/// with length 2/R. Zero for vertices with zero Voronoi mass.
pub fn mean_curvature_normal<P: AsPt3>(faces: &[[u32; 3]], p: &[P]) -> Vec<Vec3> {
    let l = cotan_stiffness(faces, p, None);
    let m = mass_voronoi(faces, p);
    (0..p.len())
        .map(|i| {
            let (c, v) = l.row(i);
            let xi = p[i].pt3();
            // Σ_j L_ij x_j = Σ_{j≠i} L_ij (x_j − x_i) since the row sums to zero: better
            // conditioned far from the origin.
            let lx = c.iter().zip(v).fold(Vec3::zeros(), |s, (&j, &w)| s + w * (p[j as usize].pt3() - xi));
            if m[i] > 0.0 {
                -lx / m[i]
            } else {
                Vec3::zeros()
            }
        })
        .collect()
}

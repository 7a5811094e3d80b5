//! Regular-grid polygonizer: samples a field on a cubic grid, splits every cube into the six
//! tetrahedra of the Kuhn (Freudenthal) subdivision along the main diagonal, and marches them.
//! Every cube uses the same split, so the face diagonals of neighbouring cubes agree and the
//! tetrahedral grid is conforming: the mesh is watertight (see [`super::marching_tets`]).

use rayon::prelude::*;

use super::marching::{snap_value, Marcher};
use crate::error::{Error, Result};
use crate::math::{Pt3, Vec3};
use crate::mesh::TriMesh;
use crate::spatial::Aabb;

/// Grid for [`polygonize`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PolygonizeOptions {
    /// Region sampled. The solid `{f < 0}` must lie strictly inside it (every grid node on the
    /// boundary must be outside, else the surface would be cut open).
    pub bounds: Aabb,
    /// Grid spacing (length units of the field).
    pub h: f64,
}

/// The six Kuhn tetrahedra of a unit cube, corners numbered by bits (x = 1, y = 2, z = 4): one per
/// permutation of the axes, each the path 0 → e_a → e_a + e_b → 7.
const KUHN: [[usize; 4]; 6] = [[0, 1, 3, 7], [0, 1, 5, 7], [0, 2, 3, 7], [0, 2, 6, 7], [0, 4, 5, 7], [0, 4, 6, 7]];

/// Meshes the zero level set of `f` (negative inside) on a grid of spacing `o.h` covering
/// `o.bounds`: Kuhn 6-tetrahedron split and marching tetrahedra with snap `1e-3·h`.
///
/// The field is sampled in parallel by z-slabs (each value written once, so the result is
/// bitwise independent of the thread count); marching is serial in a fixed order.
/// Errors: `InvalidParameter` for a bad spacing or bounds, for a grid above 2³¹ nodes, when a
/// boundary node is inside (the surface would be open) or when nothing is inside;
/// `NonFinite` if the field returns a non-finite value.
pub fn polygonize(f: &(dyn Fn(&Pt3) -> f64 + Sync), o: &PolygonizeOptions) -> Result<TriMesh> {
    let h = o.h;
    if !(h > 0.0 && h.is_finite()) || o.bounds.is_empty() {
        return Err(Error::InvalidParameter(format!("polygonize: spacing {h} or empty bounds")));
    }
    let size = o.bounds.size();
    let n: [usize; 3] = std::array::from_fn(|a| (size[a] / h).ceil() as usize + 1);
    let total = n[0] as f64 * n[1] as f64 * n[2] as f64;
    if total > 2f64.powi(31) {
        return Err(Error::InvalidParameter(format!("polygonize: grid of {total} nodes is too large (h = {h})")));
    }
    let min = o.bounds.min;
    let node =
        |i: usize, j: usize, k: usize| Pt3::new(min.x + i as f64 * h, min.y + j as f64 * h, min.z + k as f64 * h);
    let slab = n[0] * n[1];
    let snap = 1e-3 * h;
    let mut values = vec![0.0; slab * n[2]];
    values.par_chunks_mut(slab).enumerate().for_each(|(k, s)| {
        for j in 0..n[1] {
            for i in 0..n[0] {
                s[i + n[0] * j] = snap_value(f(&node(i, j, k)), snap);
            }
        }
    });
    if values.iter().any(|v| !v.is_finite()) {
        return Err(Error::NonFinite("polygonize field"));
    }
    let id = |i: usize, j: usize, k: usize| i + n[0] * (j + n[1] * k);
    for k in 0..n[2] {
        for j in 0..n[1] {
            for i in 0..n[0] {
                let boundary = i == 0 || j == 0 || k == 0 || i + 1 == n[0] || j + 1 == n[1] || k + 1 == n[2];
                if boundary && values[id(i, j, k)] < 0.0 {
                    let p = node(i, j, k);
                    return Err(Error::InvalidParameter(format!(
                        "polygonize: the solid reaches the bounds at ({}, {}, {})",
                        p.x, p.y, p.z
                    )));
                }
            }
        }
    }
    let mut m = Marcher::new();
    for k in 0..n[2] - 1 {
        for j in 0..n[1] - 1 {
            for i in 0..n[0] - 1 {
                let corner = |c: usize| id(i + (c & 1), j + ((c >> 1) & 1), k + ((c >> 2) & 1));
                let cid: [usize; 8] = std::array::from_fn(corner);
                let cv = cid.map(|c| values[c]);
                let neg = cv.iter().filter(|v| **v < 0.0).count();
                if neg == 0 || neg == 8 {
                    continue;
                }
                let cp: [Pt3; 8] = std::array::from_fn(|c| node(i + (c & 1), j + ((c >> 1) & 1), k + ((c >> 2) & 1)));
                for t in KUHN {
                    m.tet(t.map(|c| cid[c] as u64), t.map(|c| cp[c]), t.map(|c| cv[c]));
                }
            }
        }
    }
    m.finish()
}

/// Meshes `f` at the grid spacing whose vertex count is within `tol·target_vertices` of
/// `target_vertices` (vertex count ∝ h⁻², so the spacing is updated by `h ← h·sqrt(n/target)`;
/// at most 12 trials, the closest one is returned). Returns the mesh and the spacing used.
pub fn polygonize_to_count(
    f: &(dyn Fn(&Pt3) -> f64 + Sync),
    bounds: Aabb,
    target_vertices: usize,
    tol: f64,
) -> Result<(TriMesh, f64)> {
    if target_vertices < 4 || tol.is_nan() || tol <= 0.0 {
        return Err(Error::InvalidParameter(format!(
            "polygonize_to_count: target {target_vertices} vertices, tolerance {tol}"
        )));
    }
    let mut h = bounds.diag() / 60.0;
    let mut best: Option<(TriMesh, f64)> = None;
    for _ in 0..12 {
        // Pad by two cells so the boundary nodes are outside.
        let b = Aabb::new(bounds.min - Vec3::repeat(2.0 * h), bounds.max + Vec3::repeat(2.0 * h));
        let m = polygonize(f, &PolygonizeOptions { bounds: b, h })?;
        let nv = m.n_vertices() as f64;
        let err = (nv - target_vertices as f64).abs();
        let better = best.as_ref().is_none_or(|(bm, _)| err < (bm.n_vertices() as f64 - target_vertices as f64).abs());
        let done = err <= tol * target_vertices as f64;
        let next = h * (nv / target_vertices as f64).sqrt();
        if better {
            best = Some((m, h));
        }
        if done {
            break;
        }
        h = next;
    }
    // The loop ran at least once and stores its first result.
    Ok(best.expect("at least one trial"))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn grid_must_enclose_the_solid() {
        let f = |p: &Pt3| p.coords.norm() - 1.0;
        let o = PolygonizeOptions { bounds: Aabb::new(Pt3::new(-0.5, -2.0, -2.0), Pt3::new(2.0, 2.0, 2.0)), h: 0.25 };
        assert!(matches!(polygonize(&f, &o), Err(Error::InvalidParameter(_))));
        let o = PolygonizeOptions { h: -1.0, ..o };
        assert!(matches!(polygonize(&f, &o), Err(Error::InvalidParameter(_))));
    }
}

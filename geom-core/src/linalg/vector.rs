//! Dense vector helpers for the solvers: the deterministic [`dot`] product, vector norms and
//! zero-copy flat views of point and vector arrays (GEOM-CORE.md §1 "Layout").
//!
//! Determinism: every reduction here sums fixed [`DOT_CHUNK`]-entry chunks, each chunk in index
//! order, and then the chunk sums in chunk order. The chunking does not depend on the number of
//! threads, so the result is bitwise identical for any Rayon pool size (and to the serial loop).

use crate::math::{Pt3, Vec3};
use rayon::prelude::*;

/// Entries per chunk of a deterministic reduction (and the minimum work per Rayon task of the
/// element-wise vector updates).
pub const DOT_CHUNK: usize = 4096;

/// Sum of `a[i] b[i]` over one chunk with four interleaved partial sums (a fixed order, so the
/// result is reproducible while the loop still pipelines).
#[inline]
fn chunk_dot(a: &[f64], b: &[f64]) -> f64 {
    let mut s = [0.0f64; 4];
    let mut ca = a.chunks_exact(4);
    let mut cb = b.chunks_exact(4);
    for (x, y) in (&mut ca).zip(&mut cb) {
        s[0] += x[0] * y[0];
        s[1] += x[1] * y[1];
        s[2] += x[2] * y[2];
        s[3] += x[3] * y[3];
    }
    for (k, (x, y)) in ca.remainder().iter().zip(cb.remainder()).enumerate() {
        s[k] += x * y;
    }
    (s[0] + s[1]) + (s[2] + s[3])
}

/// Deterministic dot product `Σ a[i] b[i]`: fixed 4096-entry chunks, summed in order (parallel
/// over chunks for long vectors). Bitwise identical for any thread count.
///
/// # Panics
/// If the lengths differ (a programming error, not a data error).
pub fn dot(a: &[f64], b: &[f64]) -> f64 {
    assert_eq!(a.len(), b.len(), "linalg::dot: lengths differ");
    if a.len() <= DOT_CHUNK {
        return chunk_dot(a, b);
    }
    let partial: Vec<f64> =
        a.par_chunks(DOT_CHUNK).zip(b.par_chunks(DOT_CHUNK)).map(|(x, y)| chunk_dot(x, y)).collect();
    partial.iter().fold(0.0, |s, &p| s + p)
}

/// Euclidean norm `√(a·a)` through the deterministic [`dot`].
pub fn norm2(a: &[f64]) -> f64 {
    dot(a, a).sqrt()
}

/// True when every entry is finite (no NaN, no ±∞).
pub fn all_finite(a: &[f64]) -> bool {
    a.iter().all(|v| v.is_finite())
}

/// `y ← y + alpha x`, element-wise in parallel (each entry is independent, so the result does
/// not depend on the thread count).
pub(crate) fn axpy(alpha: f64, x: &[f64], y: &mut [f64]) {
    debug_assert_eq!(x.len(), y.len());
    y.par_iter_mut().with_min_len(DOT_CHUNK).zip(x.par_iter()).for_each(|(yi, xi)| *yi += alpha * xi);
}

/// `p ← z + beta p`, element-wise in parallel.
pub(crate) fn xpby(z: &[f64], beta: f64, p: &mut [f64]) {
    debug_assert_eq!(z.len(), p.len());
    p.par_iter_mut().with_min_len(DOT_CHUNK).zip(z.par_iter()).for_each(|(pi, zi)| *pi = zi + beta * *pi);
}

/// Positions as a flat `[x0, y0, z0, x1, …]` slice, without copying (nalgebra's `bytemuck`
/// support: `Point3<f64>` is three packed `f64`).
pub fn flat(p: &[Pt3]) -> &[f64] {
    bytemuck::cast_slice(p)
}

/// Mutable flat view of positions; see [`flat`].
pub fn flat_mut(p: &mut [Pt3]) -> &mut [f64] {
    bytemuck::cast_slice_mut(p)
}

/// Vectors (displacements, velocities, forces) as a flat `[x0, y0, z0, x1, …]` slice.
pub fn flat_vec(v: &[Vec3]) -> &[f64] {
    bytemuck::cast_slice(v)
}

/// Mutable flat view of vectors; see [`flat_vec`].
pub fn flat_vec_mut(v: &mut [Vec3]) -> &mut [f64] {
    bytemuck::cast_slice_mut(v)
}

/// A flat `[x0, y0, z0, …]` slice seen as points, without copying.
///
/// # Panics
/// If `x.len()` is not a multiple of 3.
pub fn as_pt3(x: &[f64]) -> &[Pt3] {
    assert!(x.len().is_multiple_of(3), "linalg::as_pt3: length {} is not a multiple of 3", x.len());
    bytemuck::cast_slice(x)
}

/// Mutable version of [`as_pt3`].
///
/// # Panics
/// If `x.len()` is not a multiple of 3.
pub fn as_pt3_mut(x: &mut [f64]) -> &mut [Pt3] {
    assert!(x.len().is_multiple_of(3), "linalg::as_pt3_mut: length {} is not a multiple of 3", x.len());
    bytemuck::cast_slice_mut(x)
}

/// A flat `[x0, y0, z0, …]` slice seen as vectors, without copying.
///
/// # Panics
/// If `x.len()` is not a multiple of 3.
pub fn as_vec3(x: &[f64]) -> &[Vec3] {
    assert!(x.len().is_multiple_of(3), "linalg::as_vec3: length {} is not a multiple of 3", x.len());
    bytemuck::cast_slice(x)
}

/// Mutable version of [`as_vec3`].
///
/// # Panics
/// If `x.len()` is not a multiple of 3.
pub fn as_vec3_mut(x: &mut [f64]) -> &mut [Vec3] {
    assert!(x.len().is_multiple_of(3), "linalg::as_vec3_mut: length {} is not a multiple of 3", x.len());
    bytemuck::cast_slice_mut(x)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dot_matches_naive_sum_closely() {
        // 10 000 entries cross several chunks; compare against a compensated (Kahan) sum.
        let a: Vec<f64> = (0..10_000).map(|i| ((i * 37 % 101) as f64 - 50.0) * 0.01).collect();
        let b: Vec<f64> = (0..10_000).map(|i| ((i * 13 % 97) as f64 - 48.0) * 0.02).collect();
        let (mut s, mut c) = (0.0f64, 0.0f64);
        for (x, y) in a.iter().zip(&b) {
            let t = x * y - c;
            let u = s + t;
            c = (u - s) - t;
            s = u;
        }
        // Relative error of a recursive sum of 10⁴ terms is ≤ ~n·ε·Σ|aᵢbᵢ|/|Σaᵢbᵢ|; 1e-12 is ample.
        let sabs: f64 = a.iter().zip(&b).map(|(x, y)| (x * y).abs()).sum();
        assert!((dot(&a, &b) - s).abs() <= 1e-12 * sabs);
    }

    #[test]
    fn flat_views_round_trip() {
        let mut p = vec![Pt3::new(1.0, 2.0, 3.0), Pt3::new(4.0, 5.0, 6.0)];
        assert_eq!(flat(&p), &[1.0, 2.0, 3.0, 4.0, 5.0, 6.0]);
        flat_mut(&mut p)[4] = 7.0;
        assert_eq!(p[1].y, 7.0);
        let v = [Vec3::new(0.5, -1.0, 2.0)];
        assert_eq!(flat_vec(&v), &[0.5, -1.0, 2.0]);
        let x = [1.0, 2.0, 3.0, 4.0, 5.0, 6.0];
        assert_eq!(as_pt3(&x)[1], Pt3::new(4.0, 5.0, 6.0));
        assert_eq!(as_vec3(&x)[0], Vec3::new(1.0, 2.0, 3.0));
    }

    #[test]
    #[should_panic(expected = "multiple of 3")]
    fn as_pt3_rejects_ragged_length() {
        let _ = as_pt3(&[1.0, 2.0]);
    }
}

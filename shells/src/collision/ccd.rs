//! Continuous collision detection for linearly moving primitives (shells.md §3.9 step 2):
//! the coplanarity cubic ((x₂−x₁)(t) × (x₃−x₁)(t))·(x₄−x₁)(t) = 0 on t ∈ [0, 1], roots by
//! `geom_core::math::poly::cubic_roots_unit`, then the true distance at each root.

use geom_core::math::{Pt3, Vec3};
use geom_core::query::{closest_point_triangle, closest_points_segments};

pub use geom_core::math::poly::cubic_roots_unit;

/// Coefficients (c₀, c₁, c₂, c₃) of the coplanarity polynomial of four points moving linearly
/// from `x` by `d` over t ∈ [0, 1].
pub fn coplanarity_cubic(x: &[Pt3; 4], d: &[Vec3; 4]) -> [f64; 4] {
    let a = x[1] - x[0];
    let b = x[2] - x[0];
    let c = x[3] - x[0];
    let da = d[1] - d[0];
    let db = d[2] - d[0];
    let dc = d[3] - d[0];
    let axb = a.cross(&b);
    let mixed = da.cross(&b) + a.cross(&db);
    let dadb = da.cross(&db);
    [axb.dot(&c), mixed.dot(&c) + axb.dot(&dc), dadb.dot(&c) + mixed.dot(&dc), dadb.dot(&dc)]
}

fn at(x: &[Pt3; 4], d: &[Vec3; 4], t: f64) -> [Pt3; 4] {
    std::array::from_fn(|i| x[i] + t * d[i])
}

/// Candidate times: the cubic's roots in [0, 1], or the sample times {0, ¼, ½, ¾, 1} when the
/// motion is coplanar throughout (all coefficients negligible). Returns the times and their
/// count (no allocation: this runs for every broad-phase candidate pair).
fn candidate_times(x: &[Pt3; 4], d: &[Vec3; 4]) -> ([f64; 5], usize) {
    let mut out = [0.0; 5];
    let c = coplanarity_cubic(x, d);
    // Largest of |x_i − x_0| and |d_i| (squared norms, one square root: the same value).
    let scale = x.iter().zip(d).fold(0.0f64, |m, (p, v)| m.max((p - x[0]).norm_squared()).max(v.norm_squared())).sqrt();
    let tol = 1e-14 * scale.powi(3).max(f64::MIN_POSITIVE);
    if c.iter().all(|v| v.abs() <= tol) {
        out = [0.0, 0.25, 0.5, 0.75, 1.0];
        return (out, 5);
    }
    // Bernstein coefficients on [0, 1]: the cubic lies in their convex hull there, so when all
    // four are beyond ±tol with one sign it has no root in [0, 1] (the common case of a broad-
    // phase candidate that never becomes coplanar), and the root finder is skipped.
    let b = [c[0], c[0] + c[1] / 3.0, c[0] + (2.0 * c[1] + c[2]) / 3.0, c[0] + c[1] + c[2] + c[3]];
    if b.iter().all(|&x| x > tol) || b.iter().all(|&x| x < -tol) {
        return (out, 0);
    }
    let mut r = [0.0; 3];
    let k = cubic_roots_unit(c, &mut r);
    out[..k].copy_from_slice(&r[..k]);
    (out, k)
}

/// First time t ∈ [0, 1] at which vertex p (moving by dp) comes within `delta` of the triangle
/// t (moving by dt): `Some((t, barycentrics))`.
pub fn vertex_triangle(p: &Pt3, dp: &Vec3, tri: &[Pt3; 3], dt: &[Vec3; 3], delta: f64) -> Option<(f64, [f64; 3])> {
    let x = [tri[0], tri[1], tri[2], *p];
    let d = [dt[0], dt[1], dt[2], *dp];
    let (times, k) = candidate_times(&x, &d);
    for &t in &times[..k] {
        let y = at(&x, &d, t);
        let (c, w) = closest_point_triangle(&y[3], &[y[0], y[1], y[2]]);
        if (y[3] - c).norm() <= delta {
            return Some((t, w));
        }
    }
    None
}

/// First time t ∈ [0, 1] at which edges a0–a1 and b0–b1 come within `delta`:
/// `Some((t, s_a, s_b))` with the segment parameters of the closest points.
pub fn edge_edge(a: &[Pt3; 2], da: &[Vec3; 2], b: &[Pt3; 2], db: &[Vec3; 2], delta: f64) -> Option<(f64, f64, f64)> {
    let x = [a[0], a[1], b[0], b[1]];
    let d = [da[0], da[1], db[0], db[1]];
    let (times, k) = candidate_times(&x, &d);
    for &t in &times[..k] {
        let y = at(&x, &d, t);
        let (s, u, p, q) = closest_points_segments(&y[0], &y[1], &y[2], &y[3]);
        if (p - q).norm() <= delta {
            return Some((t, s, u));
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kernels::testutil::TestRng;

    /// §7 test 15 is geom-core's (`cubic_roots_unit`); here a few shells-specific cubics.
    #[test]
    fn cubic_roots() {
        let mut r = [0.0; 3];
        // (t − 0.2)(t − 0.5)(t − 0.9)
        let n = cubic_roots_unit([-0.09, 0.73, -1.6, 1.0], &mut r);
        assert_eq!(n, 3);
        for (a, b) in r.iter().zip([0.2, 0.5, 0.9]) {
            assert!((a - b).abs() < 1e-10);
        }
        // Double root at 0.5: (t − 0.5)²(t + 1).
        let n = cubic_roots_unit([0.25, 0.0 - 0.75, 0.0, 1.0], &mut r);
        assert!(n >= 1 && r[..n].iter().any(|x| (x - 0.5).abs() < 1e-6));
        // Linear root at exactly 0 and quadratic with no root.
        assert_eq!(cubic_roots_unit([0.0, 1.0, 0.0, 0.0], &mut r), 1);
        assert_eq!(r[0], 0.0);
        assert_eq!(cubic_roots_unit([1.0, 0.0, 1.0, 0.0], &mut r), 0);
    }

    /// The Bernstein pre-test only skips cubics without a root in [0, 1]: on random cubics
    /// (and ones with planted roots) the candidate times equal those of the root finder alone.
    #[test]
    fn bernstein_skip_is_exact() {
        let mut rng = TestRng::new(5);
        let mut skipped = 0;
        for k in 0..20_000 {
            let c = if k % 2 == 0 {
                [rng.range(-1.0, 1.0), rng.range(-1.0, 1.0), rng.range(-1.0, 1.0), rng.range(-1.0, 1.0)]
            } else {
                // (t − r₀)(t − r₁)(t − r₂)·s with roots scattered around [0, 1].
                let (a, b, d, s) =
                    (rng.range(-0.5, 1.5), rng.range(-0.5, 1.5), rng.range(-0.5, 1.5), rng.range(-2.0, 2.0));
                [-s * a * b * d, s * (a * b + a * d + b * d), -s * (a + b + d), s]
            };
            let b = [c[0], c[0] + c[1] / 3.0, c[0] + (2.0 * c[1] + c[2]) / 3.0, c[0] + c[1] + c[2] + c[3]];
            if b.iter().all(|&x| x > 1e-14) || b.iter().all(|&x| x < -1e-14) {
                skipped += 1;
                let mut r = [0.0; 3];
                assert_eq!(cubic_roots_unit(c, &mut r), 0, "skipped a cubic with a root in [0, 1]: {c:?}");
            }
        }
        assert!(skipped > 2000, "the pre-test must skip often: {skipped}");
    }

    /// §7 test 16: a vertex crossing a triangle at t* = 0.37; an edge–edge crossing; grazing
    /// parallel edges; random motions vs brute-force sampling.
    #[test]
    fn ccd_cases() {
        let tri = [Pt3::new(0.0, 0.0, 0.0), Pt3::new(1.0, 0.0, 0.0), Pt3::new(0.0, 1.0, 0.0)];
        let z = [Vec3::zeros(); 3];
        let p = Pt3::new(0.2, 0.2, 0.37);
        let (t, w) = vertex_triangle(&p, &Vec3::new(0.0, 0.0, -1.0), &tri, &z, 1e-9).unwrap();
        assert!((t - 0.37).abs() < 1e-8, "{t}");
        assert!((w[1] - 0.2).abs() < 1e-8);
        // Miss: passes beside the triangle.
        assert!(vertex_triangle(&Pt3::new(0.8, 0.8, 0.5), &Vec3::new(0.0, 0.0, -1.0), &tri, &z, 1e-9).is_none());
        // Edge–edge crossing at t = 0.5.
        let a = [Pt3::new(0.0, 0.0, 0.5), Pt3::new(1.0, 0.0, 0.5)];
        let b = [Pt3::new(0.5, -1.0, 0.0), Pt3::new(0.5, 1.0, 0.0)];
        let (t, s, u) =
            edge_edge(&a, &[Vec3::new(0.0, 0.0, -1.0); 2], &b, &[Vec3::zeros(); 2], 1e-9).expect("edges cross");
        assert!((t - 0.5).abs() < 1e-8 && (s - 0.5).abs() < 1e-8 && (u - 0.5).abs() < 1e-8);
        // Grazing parallel edges sliding over each other at distance 1e-3 (no hit at δ = 1e-6).
        let a = [Pt3::new(0.0, 0.0, 1e-3), Pt3::new(1.0, 0.0, 1e-3)];
        let b = [Pt3::new(0.0, 0.0, 0.0), Pt3::new(1.0, 0.0, 0.0)];
        assert!(edge_edge(&a, &[Vec3::new(0.5, 0.0, 0.0); 2], &b, &[Vec3::zeros(); 2], 1e-6).is_none());
        // Random motions: every crossing that brute-force sampling sees with clearance is found.
        let mut r = TestRng::new(9);
        let mut crossings = 0;
        for _ in 0..20_000 {
            let rp = |r: &mut TestRng| Pt3::new(r.range(-1.0, 1.0), r.range(-1.0, 1.0), r.range(-1.0, 1.0));
            let rv = |r: &mut TestRng| Vec3::new(r.range(-1.0, 1.0), r.range(-1.0, 1.0), r.range(-1.0, 1.0));
            let tri = [rp(&mut r), rp(&mut r), rp(&mut r)];
            let dt = [rv(&mut r), rv(&mut r), rv(&mut r)];
            let p = rp(&mut r);
            let dp = rv(&mut r);
            // Signed side of p relative to the triangle plane, sampled.
            let side = |t: f64| {
                let y: [Pt3; 3] = std::array::from_fn(|i| tri[i] + t * dt[i]);
                let q = p + t * dp;
                let n = (y[1] - y[0]).cross(&(y[2] - y[0]));
                let (c, w) = closest_point_triangle(&q, &y);
                let inside = w.iter().all(|&x| x > 1e-4) && (q - c).norm() < 0.5;
                (n.dot(&(q - y[0])), inside, n.norm())
            };
            let mut prev = side(0.0);
            let mut sampled_hit = false;
            let steps = 2000;
            for k in 1..=steps {
                let cur = side(k as f64 / steps as f64);
                if prev.0.signum() != cur.0.signum() && cur.1 && prev.1 && cur.2 > 1e-2 && prev.2 > 1e-2 {
                    sampled_hit = true;
                }
                prev = cur;
            }
            if sampled_hit {
                crossings += 1;
                assert!(vertex_triangle(&p, &dp, &tri, &dt, 1e-6).is_some(), "missed a crossing");
            }
        }
        assert!(crossings > 50, "too few crossings sampled: {crossings}");
    }
}

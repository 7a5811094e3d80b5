//! Continuous collision detection for linearly moving primitives (shells.md §3.9 step 2):
//! the coplanarity cubic ((x₂−x₁)(t) × (x₃−x₁)(t))·(x₄−x₁)(t) = 0 on t ∈ [0, 1], roots by
//! `geom_core::math::poly::cubic_roots_unit`, then the true distance at each root. Exact
//! pre-tests skip pairs that provably stay more than 2δ apart (a separating coordinate axis at
//! both ends of the step; a Bernstein sign test; the closest-point direction as a separating
//! axis before root finding), which leaves every result unchanged.

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

/// Which points of `x` form the first primitive (the rest form the second): the triangle of a
/// vertex–triangle pair (3) or the first edge of an edge–edge pair (2).
#[derive(Clone, Copy)]
enum Split {
    VertexTriangle = 3,
    EdgeEdge = 2,
}

/// True when a plane separates the two primitives by more than `gap` throughout t ∈ [0, 1]:
/// for the unit axis `n`, min over the second primitive's points of x(t)·n minus max over the
/// first's exceeds `gap` at t = 0 and at t = 1. Each x_i(t)·n is linear in t, so that
/// difference (a minimum of linear functions minus a maximum of them) is concave in t and
/// exceeds `gap` on all of [0, 1] when it does at both ends; the primitives' convex hulls are
/// then more than `gap` apart at every t.
fn separated_along(x: &[Pt3; 4], d: &[Vec3; 4], split: Split, n: &Vec3, gap: f64) -> bool {
    let k = split as usize;
    [0.0, 1.0].iter().all(|&t| {
        let s = |i: usize| (x[i].coords + t * d[i]).dot(n);
        let hi_a = (0..k).map(s).fold(f64::NEG_INFINITY, f64::max);
        let lo_b = (k..4).map(s).fold(f64::INFINITY, f64::min);
        lo_b - hi_a > gap
    })
}

/// True when one coordinate axis separates the primitives by more than `gap` at t = 0 and at
/// t = 1 (the same axis and side at both times), hence throughout the step (see
/// [`separated_along`]). Swept boxes of primitives that move together overlap although the
/// primitives never approach; this cheap test drops most of them before the cubic is formed.
fn separated_on_axes(x: &[Pt3; 4], d: &[Vec3; 4], split: Split, gap: f64) -> bool {
    let k = split as usize;
    let y: [Pt3; 4] = std::array::from_fn(|i| x[i] + d[i]);
    (0..3).any(|c| {
        let range = |p: &[Pt3; 4], r: std::ops::Range<usize>| {
            p[r].iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), q| (lo.min(q[c]), hi.max(q[c])))
        };
        let (a0, b0, a1, b1) = (range(x, 0..k), range(x, k..4), range(&y, 0..k), range(&y, k..4));
        (b0.0 - a0.1 > gap && b1.0 - a1.1 > gap) || (a0.0 - b0.1 > gap && a1.0 - b1.1 > gap)
    })
}

/// Conservative no-contact test used before root finding: the direction between the closest
/// points at t = 0, then at t = 1, tried as a separating axis (see [`separated_along`]) with
/// gap 2δ. When it holds, every point of one primitive stays more than 2δ from the other over
/// the whole step, so no root of the cubic can be a hit (distance ≤ δ): skipping the roots
/// leaves the result unchanged (`ccd::tests::separation_skip_is_exact`). This removes most of
/// the root finding for nearly coplanar neighbours of one flat cloth layer, whose cubics have
/// roots but whose primitives stay a cell apart.
fn separated(x: &[Pt3; 4], d: &[Vec3; 4], split: Split, delta: f64) -> bool {
    let gap = 2.0 * delta;
    [0.0, 1.0].iter().any(|&t| {
        let y = at(x, d, t);
        let axis = match split {
            Split::VertexTriangle => y[3] - closest_point_triangle(&y[3], &[y[0], y[1], y[2]]).0,
            Split::EdgeEdge => {
                let (_, _, pa, pb) = closest_points_segments(&y[0], &y[1], &y[2], &y[3]);
                pb - pa
            }
        };
        let len = axis.norm();
        len > gap && separated_along(x, d, split, &(axis / len), gap)
    })
}

/// Candidate times: the cubic's roots in [0, 1], or the sample times {0, ¼, ½, ¾, 1} when the
/// motion is coplanar throughout (all coefficients negligible). Returns the times and their
/// count (no allocation: this runs for every broad-phase candidate pair). With `prefilter`
/// (δ, split), cubics with roots are first checked by [`separated`]; a separated pair gets no
/// candidate time.
fn candidate_times(x: &[Pt3; 4], d: &[Vec3; 4], prefilter: Option<(f64, Split)>) -> ([f64; 5], usize) {
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
    if let Some((delta, split)) = prefilter {
        if separated(x, d, split, delta) {
            return (out, 0);
        }
    }
    let mut r = [0.0; 3];
    let k = cubic_roots_unit(c, &mut r);
    out[..k].copy_from_slice(&r[..k]);
    (out, k)
}

/// First time t ∈ [0, 1] at which vertex p (moving by dp) comes within `delta` of the triangle
/// t (moving by dt): `Some((t, barycentrics))`.
pub fn vertex_triangle(p: &Pt3, dp: &Vec3, tri: &[Pt3; 3], dt: &[Vec3; 3], delta: f64) -> Option<(f64, [f64; 3])> {
    vertex_triangle_impl(p, dp, tri, dt, delta, true)
}

fn vertex_triangle_impl(
    p: &Pt3,
    dp: &Vec3,
    tri: &[Pt3; 3],
    dt: &[Vec3; 3],
    delta: f64,
    prefilter: bool,
) -> Option<(f64, [f64; 3])> {
    let x = [tri[0], tri[1], tri[2], *p];
    let d = [dt[0], dt[1], dt[2], *dp];
    if prefilter && separated_on_axes(&x, &d, Split::VertexTriangle, 2.0 * delta) {
        return None;
    }
    let (times, k) = candidate_times(&x, &d, prefilter.then_some((delta, Split::VertexTriangle)));
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
    edge_edge_impl(a, da, b, db, delta, true)
}

fn edge_edge_impl(
    a: &[Pt3; 2],
    da: &[Vec3; 2],
    b: &[Pt3; 2],
    db: &[Vec3; 2],
    delta: f64,
    prefilter: bool,
) -> Option<(f64, f64, f64)> {
    let x = [a[0], a[1], b[0], b[1]];
    let d = [da[0], da[1], db[0], db[1]];
    if prefilter && separated_on_axes(&x, &d, Split::EdgeEdge, 2.0 * delta) {
        return None;
    }
    let (times, k) = candidate_times(&x, &d, prefilter.then_some((delta, Split::EdgeEdge)));
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

    /// The separating-axis pre-tests (coordinate axes, closest-point directions) only skip
    /// pairs without a hit: on random near-coplanar motions (flat-layer neighbours, sliding and
    /// crossing pairs, contacts within δ) the results with and without them are identical, bit
    /// for bit, while most pairs are skipped.
    #[test]
    fn separation_skip_is_exact() {
        let mut r = TestRng::new(17);
        let (mut hits, mut skipped) = (0, 0);
        let delta = 1e-3;
        for k in 0..40_000 {
            // Points near the plane z = 0 (every other case exactly in it), small motions.
            let flat = if k % 2 == 0 { 0.0 } else { 0.02 };
            let rp = |r: &mut TestRng| Pt3::new(r.range(-1.0, 1.0), r.range(-1.0, 1.0), flat * r.range(-1.0, 1.0));
            let scale = [0.01, 0.1, 1.0][k % 3];
            let rv = |r: &mut TestRng| scale * Vec3::new(r.range(-1.0, 1.0), r.range(-1.0, 1.0), r.range(-1.0, 1.0));
            let tri = [rp(&mut r), rp(&mut r), rp(&mut r)];
            let dt = [rv(&mut r), rv(&mut r), rv(&mut r)];
            let (p, dp) = (rp(&mut r), rv(&mut r));
            let a = vertex_triangle_impl(&p, &dp, &tri, &dt, delta, true);
            let b = vertex_triangle_impl(&p, &dp, &tri, &dt, delta, false);
            assert_eq!(
                a.map(|(t, w)| (t.to_bits(), w.map(f64::to_bits))),
                b.map(|(t, w)| (t.to_bits(), w.map(f64::to_bits)))
            );
            let (ea, eb) = ([rp(&mut r), rp(&mut r)], [rp(&mut r), rp(&mut r)]);
            let (da, db) = ([rv(&mut r), rv(&mut r)], [rv(&mut r), rv(&mut r)]);
            let c = edge_edge_impl(&ea, &da, &eb, &db, delta, true);
            let d = edge_edge_impl(&ea, &da, &eb, &db, delta, false);
            let bits = |x: Option<(f64, f64, f64)>| x.map(|(t, s, u)| [t, s, u].map(f64::to_bits));
            assert_eq!(bits(c), bits(d));
            hits += a.is_some() as u32 + c.is_some() as u32;
            let x = [tri[0], tri[1], tri[2], p];
            let dx = [dt[0], dt[1], dt[2], dp];
            skipped += (separated_on_axes(&x, &dx, Split::VertexTriangle, 2.0 * delta)
                || separated(&x, &dx, Split::VertexTriangle, delta)) as u32;
        }
        assert!(hits > 1000, "the test must see hits: {hits}");
        assert!(skipped > 10_000, "the pre-tests must skip often: {skipped}");
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

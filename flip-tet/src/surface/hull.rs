//! Exact distance to the convex hull of three balls (spec §3.11.2).
//!
//! The convex hull of the balls `B(x_k, r_k)` is the union of the balls with linearly interpolated
//! centres and radii over the triangle, `H = ∪_{λ∈Δ} B(Σλ_k x_k, Σλ_k r_k)`, so outside `H` the
//! distance is `min_{λ∈Δ} f(λ)` with the convex `f(λ) = |q − x(λ)| − r(λ)`. The minimiser is either
//! the interior stationary point (a planar facet tangent to all three spheres: the paper's system
//! `n·x_k + d = r_k`, `|n| = 1`) or lies on an edge (a round cone, which also covers the spheres).

use geom_core::iso::sdf::round_cone;
use geom_core::math::{Pt3, Vec3};

/// Relative threshold below which the three centres count as collinear (squared-area test).
const COLLINEAR_REL: f64 = 1e-20;

/// Signed distance from `q` to the convex hull of the three balls `(centers[k], radii[k])` (m).
///
/// Exact outside the hull; inside it returns the union-of-balls value `min_λ f(λ)` of the interior
/// stationary point or of the edges (negative), which is what the level set needs (spec §3.11.2).
/// Degenerate triplets (collinear or coincident centres, nested balls) skip the planar facets and
/// fall back to the round cones and spheres, so the value stays continuous (spec §8 H-HULL-DEGEN).
pub fn hull_distance(q: &Pt3, centers: &[Pt3; 3], radii: &[f64; 3]) -> f64 {
    let [a, b, c] = centers;
    let [ra, rb, rc] = *radii;
    let mut d = round_cone(q, a, b, ra, rb).min(round_cone(q, b, c, rb, rc)).min(round_cone(q, c, a, rc, ra));
    if let Some(f) = facet_distance(q, centers, radii) {
        d = d.min(f);
    }
    d
}

/// The smallest valid planar-facet candidate of the triplet hull, if any (spec §3.11.2 "Planes").
///
/// Solves `u·(x_k − x_1) = −(r_k − r_1)` (k = 2, 3) for the in-plane minimum-norm `u₀`, then
/// `u = u₀ ± √(1 − |u₀|²) ê`. A candidate `f = u·q − (u·x_1 + r_1)` is valid when the foot `q − f u`
/// has non-negative barycentrics in the tangent triangle `T_k = x_k + r_k u` and `f + r(λ) > 0`.
pub fn facet_distance(q: &Pt3, centers: &[Pt3; 3], radii: &[f64; 3]) -> Option<f64> {
    let x1 = centers[0];
    let e1 = centers[1] - x1;
    let e2 = centers[2] - x1;
    let n = e1.cross(&e2);
    let n2 = n.norm_squared();
    if n2.is_nan() || n2 <= COLLINEAR_REL * e1.norm_squared() * e2.norm_squared() || n2 == 0.0 {
        return None;
    }
    // Gram system for u₀ = α e1 + β e2 (minimum norm: u₀ in the triangle's plane).
    let (g11, g12, g22) = (e1.dot(&e1), e1.dot(&e2), e2.dot(&e2));
    let (b1, b2) = (-(radii[1] - radii[0]), -(radii[2] - radii[0]));
    let det = g11 * g22 - g12 * g12;
    let alpha = (b1 * g22 - b2 * g12) / det;
    let beta = (g11 * b2 - g12 * b1) / det;
    let u0 = e1 * alpha + e2 * beta;
    let s2 = 1.0 - u0.norm_squared();
    if s2.is_nan() || s2 < 0.0 {
        return None;
    }
    let en = n / n2.sqrt();
    let mut best: Option<f64> = None;
    for sign in [1.0, -1.0] {
        let u = u0 + en * (sign * s2.sqrt());
        let h = u.dot(&x1.coords) + radii[0];
        let f = u.dot(&q.coords) - h;
        let t = [0, 1, 2].map(|k| centers[k] + u * radii[k]);
        let foot = q - u * f;
        let Some(lam) = barycentric(&foot, &t) else { continue };
        if lam.iter().any(|&l| l < 0.0) {
            continue;
        }
        let r_lam = lam[0] * radii[0] + lam[1] * radii[1] + lam[2] * radii[2];
        if f + r_lam > 0.0 {
            best = Some(best.map_or(f, |b: f64| b.min(f)));
        }
    }
    best
}

/// Barycentric coordinates of `p` (assumed in the plane of `t`) in triangle `t`; `None` when the
/// triangle is degenerate.
fn barycentric(p: &Pt3, t: &[Pt3; 3]) -> Option<[f64; 3]> {
    let n: Vec3 = (t[1] - t[0]).cross(&(t[2] - t[0]));
    let n2 = n.norm_squared();
    if n2.is_nan() || n2 <= 0.0 {
        return None;
    }
    let l0 = (t[1] - p).cross(&(t[2] - p)).dot(&n) / n2;
    let l1 = (t[2] - p).cross(&(t[0] - p)).dot(&n) / n2;
    Some([l0, l1, 1.0 - l0 - l1])
}

/// Distance from `q` to the round cone (convex hull) of two balls: re-export of geom-core's exact
/// closed form, used for connected pairs (spec §3.11.2 "Round cone").
pub fn pair_distance(q: &Pt3, a: &Pt3, b: &Pt3, ra: f64, rb: f64) -> f64 {
    round_cone(q, a, b, ra, rb)
}

#[cfg(test)]
mod tests {
    use super::*;
    use geom_core::rng::Rng;

    /// Brute-force minimum of the convex `f(λ) = |q − x(λ)| − r(λ)` over the triangle: a grid
    /// followed by repeated local refinement around the best sample.
    fn brute(q: &Pt3, c: &[Pt3; 3], r: &[f64; 3]) -> f64 {
        let f = |l1: f64, l2: f64| {
            let l1 = l1.clamp(0.0, 1.0);
            let l2 = l2.clamp(0.0, 1.0 - l1);
            let l0 = 1.0 - l1 - l2;
            let x = c[0].coords * l0 + c[1].coords * l1 + c[2].coords * l2;
            (q.coords - x).norm() - (l0 * r[0] + l1 * r[1] + l2 * r[2])
        };
        let n = 60;
        let (mut b1, mut b2, mut bv) = (0.0, 0.0, f64::INFINITY);
        for i in 0..=n {
            for j in 0..=(n - i) {
                let (l1, l2) = (i as f64 / n as f64, j as f64 / n as f64);
                let v = f(l1, l2);
                if v < bv {
                    (b1, b2, bv) = (l1, l2, v);
                }
            }
        }
        let mut step = 1.0 / n as f64;
        for _ in 0..60 {
            let mut moved = false;
            for (d1, d2) in [(1.0, 0.0), (-1.0, 0.0), (0.0, 1.0), (0.0, -1.0), (1.0, -1.0), (-1.0, 1.0)] {
                let (l1, l2) = (b1 + d1 * step, b2 + d2 * step);
                if l1 < 0.0 || l2 < 0.0 || l1 + l2 > 1.0 {
                    continue;
                }
                let v = f(l1, l2);
                if v < bv {
                    (b1, b2, bv) = (l1, l2, v);
                    moved = true;
                }
            }
            if !moved {
                step *= 0.5;
            }
        }
        bv
    }

    #[test]
    fn matches_brute_force_on_random_triplets() {
        let mut rng = Rng::new(5);
        let mut checked = 0;
        for _ in 0..400 {
            let c = [0, 1, 2].map(|_| Pt3::new(rng.range(-1.0, 1.0), rng.range(-1.0, 1.0), rng.range(-1.0, 1.0)));
            let r = [0, 1, 2].map(|_| rng.range(0.05, 0.6));
            let q = Pt3::new(rng.range(-3.0, 3.0), rng.range(-3.0, 3.0), rng.range(-3.0, 3.0));
            let bf = brute(&q, &c, &r);
            if bf <= 0.0 {
                continue; // outside-only property (spec T-HULL-BRUTE)
            }
            let size = (c[1] - c[0]).norm().max((c[2] - c[0]).norm()) + r.iter().fold(0.0f64, |a, &b| a.max(b));
            let d = hull_distance(&q, &c, &r);
            // Tolerance 1e-7 × triplet size (spec T-HULL-BRUTE); the refinement reaches ~1e-12.
            assert!((d - bf).abs() <= 1e-7 * size, "closed form {d} vs brute {bf}");
            checked += 1;
        }
        assert!(checked > 200, "too few outside samples: {checked}");
    }

    #[test]
    fn sphere_and_cone_cases_exact() {
        // Nested balls: the large one dominates (distance to the large sphere).
        let c = [Pt3::origin(), Pt3::new(0.1, 0.0, 0.0), Pt3::new(0.0, 0.1, 0.0)];
        let r = [1.0, 0.2, 0.2];
        let q = Pt3::new(0.0, 0.0, 3.0);
        assert!((hull_distance(&q, &c, &r) - 2.0).abs() <= 1e-14);
        // Equal radii, collinear centres: capsule distance.
        let c = [Pt3::origin(), Pt3::new(1.0, 0.0, 0.0), Pt3::new(2.0, 0.0, 0.0)];
        let q = Pt3::new(1.3, 2.0, 0.0);
        assert!((hull_distance(&q, &c, &[0.5; 3]) - 1.5).abs() <= 1e-14);
        // Beyond an end cap: distance to the end sphere.
        let q = Pt3::new(4.0, 0.0, 0.0);
        assert!((hull_distance(&q, &c, &[0.5; 3]) - 1.5).abs() <= 1e-14);
        // Coincident centres (H-COINCIDENT): the largest sphere, no NaN.
        let c = [Pt3::origin(); 3];
        let d = hull_distance(&Pt3::new(0.0, 2.0, 0.0), &c, &[0.3, 0.5, 0.1]);
        assert!((d - 1.5).abs() <= 1e-14);
    }

    #[test]
    fn equal_radii_plane_case() {
        // Equal radii in the plane z = 0: the hull is a slab |z| ≤ r over the triangle.
        let c = [Pt3::origin(), Pt3::new(1.0, 0.0, 0.0), Pt3::new(0.0, 1.0, 0.0)];
        let q = Pt3::new(0.2, 0.3, 1.7);
        assert!((hull_distance(&q, &c, &[0.25; 3]) - 1.45).abs() <= 1e-14);
        let q = Pt3::new(0.2, 0.3, -0.75);
        assert!((hull_distance(&q, &c, &[0.25; 3]) - 0.5).abs() <= 1e-14);
    }

    #[test]
    fn mixed_radii_tangent_to_plane_give_plane() {
        // Spheres of radii r, 2r, 4r tangent to y = H from below (spec T-SURF-FLAT).
        let (r, h) = (0.01, 0.3);
        let rad = [r, 2.0 * r, 4.0 * r];
        let c = [Pt3::new(0.0, h - rad[0], 0.0), Pt3::new(0.09, h - rad[1], 0.01), Pt3::new(0.03, h - rad[2], 0.1)];
        for (x, y, z) in [(0.04, h + 0.01, 0.04), (0.05, h + 0.2, 0.03), (0.03, h + 1e-6, 0.05)] {
            let d = hull_distance(&Pt3::new(x, y, z), &c, &rad);
            assert!((d - (y - h)).abs() <= 1e-12, "{d} vs {}", y - h);
        }
    }

    #[test]
    fn continuous_across_degeneracy() {
        // Nearly collinear centres: the value approaches the collinear (capsule) value.
        let q = Pt3::new(0.7, 0.9, 0.2);
        let c0 = [Pt3::origin(), Pt3::new(1.0, 0.0, 0.0), Pt3::new(2.0, 0.0, 0.0)];
        let d0 = hull_distance(&q, &c0, &[0.3, 0.2, 0.4]);
        let c1 = [Pt3::origin(), Pt3::new(1.0, 1e-7, 0.0), Pt3::new(2.0, 0.0, 0.0)];
        let d1 = hull_distance(&q, &c1, &[0.3, 0.2, 0.4]);
        assert!((d0 - d1).abs() <= 1e-6, "{d0} vs {d1}");
    }
}

//! Triangle quadrature (spec §3.12): the 7-point degree-5 rule (Dunavant 1985), adaptive 4-way
//! midpoint subdivision to a per-area tolerance, and a uniform-subdivision reference rule.
//!
//! Points are barycentric triples `[λ0, λ1, λ2]` of the triangle being integrated; weights are
//! absolute (they sum to the triangle's area). Per GEOM-CORE.md §6 the rules live in this crate.

/// Number of points of [`DEGREE5`].
pub const N_RULE: usize = 7;

/// The 7-point degree-5 rule on the reference triangle: `(barycentric point, weight)`, weights
/// summing to 1 (multiply by the area). Exact closed forms: `a = (6 ∓ √15)/21`,
/// `w = (155 ∓ √15)/1200`, centroid weight 9/40.
pub fn degree5() -> [([f64; 3], f64); N_RULE] {
    let s15 = 15f64.sqrt();
    let a1 = (6.0 - s15) / 21.0;
    let b1 = 1.0 - 2.0 * a1;
    let w1 = (155.0 - s15) / 1200.0;
    let a2 = (6.0 + s15) / 21.0;
    let b2 = 1.0 - 2.0 * a2;
    let w2 = (155.0 + s15) / 1200.0;
    let c = 1.0 / 3.0;
    [
        ([c, c, c], 9.0 / 40.0),
        ([b1, a1, a1], w1),
        ([a1, b1, a1], w1),
        ([a1, a1, b1], w1),
        ([b2, a2, a2], w2),
        ([a2, b2, a2], w2),
        ([a2, a2, b2], w2),
    ]
}

/// One quadrature point kept for later use: barycentric position in the coarse triangle and its
/// absolute weight (m²).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct QuadPoint {
    /// Barycentric coordinates in the whole (coarse) triangle.
    pub bary: [f64; 3],
    /// Absolute weight (m²).
    pub weight: f64,
}

/// Result of [`adaptive`].
#[derive(Clone, Debug)]
pub struct Adaptive {
    /// Integral of every component of the integrand.
    pub integral: Vec<f64>,
    /// Sum of `‖I_parent − I_children‖∞` over accepted nodes: the reported error estimate.
    pub error: f64,
    /// Some node reached `max_depth` without meeting the tolerance.
    pub unconverged: bool,
    /// The accepted leaves' points (28 per accepted node: 4 children × 7 points).
    pub points: Vec<QuadPoint>,
}

type Tri = [[f64; 3]; 3];

fn lerp_bary(t: &Tri, b: &[f64; 3]) -> [f64; 3] {
    let mut o = [0.0; 3];
    for (k, c) in t.iter().enumerate() {
        for d in 0..3 {
            o[d] += b[k] * c[d];
        }
    }
    o
}

fn mid(a: &[f64; 3], b: &[f64; 3]) -> [f64; 3] {
    [0.5 * (a[0] + b[0]), 0.5 * (a[1] + b[1]), 0.5 * (a[2] + b[2])]
}

fn children(t: &Tri) -> [Tri; 4] {
    let (m01, m12, m20) = (mid(&t[0], &t[1]), mid(&t[1], &t[2]), mid(&t[2], &t[0]));
    [[t[0], m01, m20], [m01, t[1], m12], [m20, m12, t[2]], [m12, m20, m01]]
}

/// Degree-5 rule on sub-triangle `t` (barycentric corners) of area `area`; accumulates into `out`
/// and optionally records the points.
fn rule_on(
    t: &Tri,
    area: f64,
    dim: usize,
    f: &mut dyn FnMut([f64; 3], &mut [f64]),
    out: &mut [f64],
    buf: &mut [f64],
    rec: Option<&mut Vec<QuadPoint>>,
) {
    out[..dim].iter_mut().for_each(|v| *v = 0.0);
    let mut rec = rec;
    for (b, w) in degree5() {
        let p = lerp_bary(t, &b);
        f(p, buf);
        let wa = w * area;
        for d in 0..dim {
            out[d] += wa * buf[d];
        }
        if let Some(r) = rec.as_deref_mut() {
            r.push(QuadPoint { bary: p, weight: wa });
        }
    }
}

/// Adaptive quadrature of the `dim`-component integrand `f(bary, out)` over a triangle of area
/// `area` (spec §3.12 step 2). A node is accepted when `‖I_parent − ΣI_children‖∞ ≤
/// tolerance·area(node)` or its children are at depth `max_depth`; its children's 28 points then
/// become leaves. The integral is the sum of the accepted children's values.
pub fn adaptive(
    area: f64,
    dim: usize,
    f: &mut dyn FnMut([f64; 3], &mut [f64]),
    tolerance: f64,
    max_depth: u32,
) -> Adaptive {
    let mut res = Adaptive { integral: vec![0.0; dim], error: 0.0, unconverged: false, points: Vec::new() };
    let mut buf = vec![0.0; dim];
    let root: Tri = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    let mut parent = vec![0.0; dim];
    rule_on(&root, area, dim, f, &mut parent, &mut buf, None);
    // Stack of (triangle, its depth, its already computed integral).
    let mut stack: Vec<(Tri, u32, Vec<f64>)> = vec![(root, 0, parent)];
    let mut kids_val = vec![vec![0.0; dim]; 4];
    let mut sum = vec![0.0; dim];
    let mut kid_pts: Vec<QuadPoint> = Vec::with_capacity(4 * N_RULE);
    while let Some((t, depth, val)) = stack.pop() {
        let child_area = area / 4f64.powi(depth as i32 + 1);
        let ch = children(&t);
        sum.iter_mut().for_each(|v| *v = 0.0);
        kid_pts.clear();
        for (k, c) in ch.iter().enumerate() {
            rule_on(c, child_area, dim, f, &mut kids_val[k], &mut buf, Some(&mut kid_pts));
            for (s, v) in sum.iter_mut().zip(&kids_val[k]) {
                *s += v;
            }
        }
        let diff = val.iter().zip(&sum).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
        let node_area = 4.0 * child_area;
        let converged = diff <= tolerance * node_area;
        if converged || depth + 1 >= max_depth {
            if !converged {
                res.unconverged = true;
            }
            res.error += diff;
            for (r, s) in res.integral.iter_mut().zip(&sum) {
                *r += s;
            }
            res.points.extend_from_slice(&kid_pts);
        } else {
            for (k, c) in ch.iter().enumerate() {
                stack.push((*c, depth + 1, kids_val[k].clone()));
            }
        }
    }
    res
}

/// Reference rule: the degree-5 rule on each of the `4^level` sub-triangles of the uniform
/// midpoint subdivision (error `O(4^{-3·level})` for smooth integrands).
pub fn uniform(area: f64, dim: usize, f: &mut dyn FnMut([f64; 3], &mut [f64]), level: u32) -> Vec<f64> {
    let mut tris: Vec<Tri> = vec![[[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]];
    for _ in 0..level {
        tris = tris.iter().flat_map(children).collect();
    }
    let a = area / tris.len() as f64;
    let mut total = vec![0.0; dim];
    let mut part = vec![0.0; dim];
    let mut buf = vec![0.0; dim];
    for t in &tris {
        rule_on(t, a, dim, f, &mut part, &mut buf, None);
        for d in 0..dim {
            total[d] += part[d];
        }
    }
    total
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Exact integral of λ0^i λ1^j λ2^k over the unit-area triangle: 2·i! j! k! / (i+j+k+2)!.
    fn exact_monomial(i: u32, j: u32, k: u32) -> f64 {
        let fact = |n: u32| (1..=n).map(|x| x as f64).product::<f64>();
        2.0 * fact(i) * fact(j) * fact(k) / fact(i + j + k + 2)
    }

    #[test]
    fn degree5_rule_is_exact_to_degree_5() {
        // Every monomial of total degree ≤ 5 to round-off (1e-14 absolute on O(1e-3) values).
        for i in 0..=5u32 {
            for j in 0..=(5 - i) {
                for k in 0..=(5 - i - j) {
                    let r: f64 = degree5()
                        .iter()
                        .map(|(b, w)| w * b[0].powi(i as i32) * b[1].powi(j as i32) * b[2].powi(k as i32))
                        .sum();
                    assert!((r - exact_monomial(i, j, k)).abs() < 1e-15, "{i}{j}{k}");
                }
            }
        }
        // and not exact at degree 6 (the test can fail).
        let r: f64 = degree5().iter().map(|(b, w)| w * b[0].powi(6)).sum();
        assert!((r - exact_monomial(6, 0, 0)).abs() > 1e-6);
    }

    #[test]
    fn adaptive_meets_tolerance_on_oscillatory_integrand() {
        let mut f = |b: [f64; 3], o: &mut [f64]| o[0] = (20.0 * b[1]).sin() * (9.0 * b[2]).cos();
        let reference = uniform(1.0, 1, &mut f, 6)[0];
        for tol in [1e-3, 1e-5] {
            let r = adaptive(1.0, 1, &mut f, tol, 10);
            assert!(!r.unconverged);
            assert!((r.integral[0] - reference).abs() <= 3.0 * tol, "tol {tol}");
            let w: f64 = r.points.iter().map(|p| p.weight).sum();
            assert!((w - 1.0).abs() < 1e-13);
        }
    }
}

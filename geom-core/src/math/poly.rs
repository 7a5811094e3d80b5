//! Real roots of low-degree polynomials on the unit interval, for continuous collision detection
//! (shells.md §3.9 step 2, test 15): [`cubic_roots_unit`].

/// Tolerance on `|f|` (after normalising the coefficients to max-magnitude 1) below which an
/// endpoint `t ∈ {0, 1}` or a critical point of `f` counts as a root. It is ~1000× the rounding
/// error of evaluating a normalised cubic on `[0, 1]`, so exact roots there are never lost to
/// rounding, and tangential (double) roots are reported even when rounding lifts them off zero.
pub const ROOT_EPS: f64 = 1e-12;

/// Roots closer than this are reported once (the best-evaluated one is kept).
const MERGE_TOL: f64 = 1e-7;

/// Roots of `c0 + c1·t + c2·t² + c3·t³` in `[0, 1]`, written ascending into `out`; returns their
/// count (≤ 3).
///
/// Method (shells.md §3.9): normalise the coefficients by the largest magnitude; find the
/// critical points (real roots of the derivative, a quadratic solved in the cancellation-free
/// form, which degenerates to the linear case when the cubic coefficient vanishes, so a
/// negligible or zero `c3` — a quadratic, a line — needs no separate path); split `[0, 1]` at the
/// critical points into pieces on which `f` is monotone; bisect (≤ 60 steps, to the last bit)
/// every piece whose ends have strictly opposite signs. In addition, an endpoint `t ∈ {0, 1}` or
/// a critical point where `|f| ≤ ROOT_EPS` is a root: this catches roots exactly at 0 or 1 and
/// double roots (a tangency has no sign change) whether rounding puts the numerical minimum just
/// above or just below zero. Candidates closer than 1e-7 are merged, keeping the one with the
/// smallest `|f|` (for a double root that is the critical point itself, accurate to ~1e-16).
///
/// Guarantees: every sign change of `f` on `[0, 1]` yields a root within the bisection
/// resolution; every double root yields a root. A root reported from the `ROOT_EPS` rule may be a
/// near-miss (`f` touches ±1e-12 without crossing): for CCD that is the conservative choice,
/// the caller checks the distance at the reported time.
///
/// Degenerate input: all coefficients zero (`f ≡ 0`, coplanar motion in CCD) or any non-finite
/// coefficient returns 0 roots; the caller must handle `f ≡ 0` itself (shells.md samples the
/// distance). In the (near-degenerate) event of more than three merged candidates, near-misses
/// (no sign change) are dropped first, so certain roots are never lost.
pub fn cubic_roots_unit(c: [f64; 4], out: &mut [f64; 3]) -> usize {
    if c.iter().any(|x| !x.is_finite()) {
        return 0;
    }
    let scale = c.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    if scale == 0.0 {
        return 0;
    }
    let c = [c[0] / scale, c[1] / scale, c[2] / scale, c[3] / scale];
    let f = |t: f64| ((c[3] * t + c[2]) * t + c[1]) * t + c[0];

    // Split points: 0, critical points in (0, 1) ascending, 1.
    let mut pts = [0.0f64; 4];
    let mut np = 1;
    let mut crit = [0.0f64; 2];
    let nc = quadratic_roots(3.0 * c[3], 2.0 * c[2], c[1], &mut crit);
    for &r in &crit[..nc] {
        if r > 0.0 && r < 1.0 && r > pts[np - 1] {
            pts[np] = r;
            np += 1;
        }
    }
    pts[np] = 1.0;
    np += 1;
    let vals: [f64; 4] = std::array::from_fn(|i| if i < np { f(pts[i]) } else { 0.0 });

    // Candidates (t, |f(t)|, from bisection).
    let mut cand = [(0.0f64, 0.0f64, false); 7];
    let mut nk = 0;
    for i in 0..np {
        if vals[i].abs() <= ROOT_EPS {
            cand[nk] = (pts[i], vals[i].abs(), false);
            nk += 1;
        }
    }
    for i in 0..np - 1 {
        let (fa, fb) = (vals[i], vals[i + 1]);
        if (fa < 0.0 && fb > 0.0) || (fa > 0.0 && fb < 0.0) {
            let t = bisect(&f, pts[i], pts[i + 1], fa);
            cand[nk] = (t, f(t).abs(), true);
            nk += 1;
        }
    }
    let cand = &mut cand[..nk];
    cand.sort_by(|a, b| a.0.total_cmp(&b.0));

    // Merge clusters; keep the best-evaluated member of each (earliest on ties) and remember
    // whether the cluster contains a certain root (a sign change).
    let mut merged = [(0.0f64, false); 7];
    let mut nm = 0;
    let mut i = 0;
    while i < cand.len() {
        let start = cand[i].0;
        let mut best = cand[i];
        let mut certain = cand[i].2;
        let mut j = i + 1;
        while j < cand.len() && cand[j].0 - start <= MERGE_TOL {
            if cand[j].1 < best.1 {
                best = cand[j];
            }
            certain |= cand[j].2;
            j += 1;
        }
        merged[nm] = (best.0.clamp(0.0, 1.0), certain);
        nm += 1;
        i = j;
    }
    // More than three: drop near-miss clusters (no sign change) from the latest on. At most three
    // pieces have a sign change, so the certain roots always fit.
    let mut keep = [true; 7];
    let mut excess = nm.saturating_sub(3);
    for k in (0..nm).rev() {
        if excess == 0 {
            break;
        }
        if !merged[k].1 {
            keep[k] = false;
            excess -= 1;
        }
    }
    let mut n = 0;
    for k in 0..nm {
        if keep[k] && n < 3 {
            out[n] = merged[k].0;
            n += 1;
        }
    }
    n
}

/// Real roots of `a·t² + b·t + c` (ascending) in the cancellation-free form
/// `q = −(b + sign(b)·√disc)/2`, roots `q/a`, `c/q`; linear when `a = 0`. Returns the count;
/// 0 when there is no real root or the polynomial is constant.
pub fn quadratic_roots(a: f64, b: f64, c: f64, out: &mut [f64; 2]) -> usize {
    if a == 0.0 {
        if b == 0.0 {
            return 0;
        }
        out[0] = -c / b;
        return 1;
    }
    let disc = b * b - 4.0 * a * c;
    if disc < 0.0 {
        return 0;
    }
    let sq = disc.sqrt();
    let q = -0.5 * (b + if b >= 0.0 { sq } else { -sq });
    if q == 0.0 {
        // b = 0 and c = 0: double root at 0.
        out[0] = 0.0;
        out[1] = 0.0;
        return 2;
    }
    let (r1, r2) = (q / a, c / q);
    out[0] = r1.min(r2);
    out[1] = r1.max(r2);
    2
}

/// Bisection on `[lo, hi]` where `f(lo) = f_lo` and `f(hi)` have opposite signs; ≤ 60 halvings
/// or until the interval cannot shrink further in floating point.
fn bisect(f: &impl Fn(f64) -> f64, mut lo: f64, mut hi: f64, mut f_lo: f64) -> f64 {
    for _ in 0..60 {
        let mid = 0.5 * (lo + hi);
        if mid <= lo || mid >= hi {
            break;
        }
        let fm = f(mid);
        if fm == 0.0 {
            return mid;
        }
        if (fm < 0.0) == (f_lo < 0.0) {
            lo = mid;
            f_lo = fm;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Rng;

    fn roots(c: [f64; 4]) -> Vec<f64> {
        let mut out = [0.0; 3];
        let n = cubic_roots_unit(c, &mut out);
        out[..n].to_vec()
    }

    /// Coefficients of k·(t − r0)(t − r1)(t − r2).
    fn from_roots(k: f64, r: [f64; 3]) -> [f64; 4] {
        let [a, b, c] = r;
        [-k * a * b * c, k * (a * b + b * c + a * c), -k * (a + b + c), k]
    }

    fn assert_found(found: &[f64], want: &[f64], tol: f64) {
        for w in want {
            assert!(found.iter().any(|f| (f - w).abs() <= tol), "root {w} missing in {found:?}");
        }
    }

    #[test]
    fn three_simple_roots() {
        let r = roots(from_roots(1.0, [0.2, 0.5, 0.9]));
        assert_eq!(r.len(), 3);
        assert_found(&r, &[0.2, 0.5, 0.9], 1e-12);
        assert!(r[0] < r[1] && r[1] < r[2]);
    }

    #[test]
    fn double_root_at_half() {
        // (t − 0.5)²(t − 2) = t³ − 3t² + 2.25t − 0.5: exact coefficients.
        let r = roots([-0.5, 2.25, -3.0, 1.0]);
        assert_eq!(r.len(), 1, "{r:?}");
        assert!((r[0] - 0.5).abs() < 1e-10, "{r:?}");
        // Both signs of the leading factor, and a double root with a simple one.
        let r = roots([0.5, -2.25, 3.0, -1.0]);
        assert_eq!(r.len(), 1);
        assert!((r[0] - 0.5).abs() < 1e-10);
        let r = roots(from_roots(1.0, [0.3, 0.3, 0.8]));
        assert_eq!(r.len(), 2, "{r:?}");
        assert!((r[0] - 0.3).abs() < 1e-8 && (r[1] - 0.8).abs() < 1e-12, "{r:?}");
    }

    #[test]
    fn roots_at_exactly_zero_and_one() {
        let r = roots(from_roots(1.0, [0.0, 1.0, 3.0]));
        assert_eq!(r, vec![0.0, 1.0]);
        // f(t) = t: a root exactly at 0 only.
        assert_eq!(roots([0.0, 1.0, 0.0, 0.0]), vec![0.0]);
        // f(t) = 1 − t: exactly at 1.
        assert_eq!(roots([1.0, -1.0, 0.0, 0.0]), vec![1.0]);
    }

    #[test]
    fn degenerate_quadratic_linear_constant() {
        // Quadratic (t − 0.25)(t − 0.75).
        let r = roots([0.1875, -1.0, 1.0, 0.0]);
        assert_found(&r, &[0.25, 0.75], 1e-12);
        assert_eq!(r.len(), 2);
        // Linear 2t − 1.
        assert_eq!(roots([-1.0, 2.0, 0.0, 0.0]), vec![0.5]);
        // Constant non-zero, identically zero, non-finite: no roots.
        assert!(roots([3.0, 0.0, 0.0, 0.0]).is_empty());
        assert!(roots([0.0; 4]).is_empty());
        assert!(roots([f64::NAN, 1.0, 0.0, 0.0]).is_empty());
        // Near-degenerate leading coefficient: a tiny cubic term on a quadratic.
        let r = roots([0.1875, -1.0, 1.0, 1e-17]);
        assert_found(&r, &[0.25, 0.75], 1e-12);
        assert_eq!(r.len(), 2);
        let r = roots([-0.3, 1.0, 1e-30, -1e-300]);
        assert_eq!(r.len(), 1);
        assert!((r[0] - 0.3).abs() < 1e-15);
    }

    #[test]
    fn no_root_in_the_interval() {
        assert!(roots(from_roots(1.0, [-0.5, 1.5, 2.0])).is_empty());
        assert!(roots([1.0, 0.0, 1.0, 0.0]).is_empty()); // 1 + t²
        assert!(roots(from_roots(1.0, [-2.0, -1.0, 1.5])).is_empty());
    }

    #[test]
    fn huge_and_tiny_scales() {
        for &k in &[1e-200, 1e-20, 1.0, 1e20, 1e200] {
            let r = roots(from_roots(k, [0.1, 0.4, 0.7]));
            assert_found(&r, &[0.1, 0.4, 0.7], 1e-12);
            assert_eq!(r.len(), 3);
        }
    }

    #[test]
    fn triple_root() {
        // (t − 0.5)³ = t³ − 1.5t² + 0.75t − 0.125 (exact).
        let r = roots([-0.125, 0.75, -1.5, 1.0]);
        assert!(!r.is_empty());
        // Triple roots are conditioned like ε^{1/3}: 1e-12^{1/3} = 1e-4.
        assert_found(&r, &[0.5], 1e-4);
    }

    /// Random cubics with known roots (some inside [0,1], some outside, clustered and double):
    /// every root in [0,1] separated from the others is found accurately; clustered ones are
    /// found within the conditioning bound.
    #[test]
    fn random_cubics_never_miss_a_root() {
        let mut rng = Rng::new(2024);
        for case in 0..20000 {
            let mut r = [rng.range(-0.5, 1.5), rng.range(-0.5, 1.5), rng.range(-0.5, 1.5)];
            match case % 5 {
                0 => r[1] = r[0],                          // exact double root
                1 => r[1] = r[0] + rng.range(-1e-6, 1e-6), // close pair
                _ => {}
            }
            let k = if rng.f64() < 0.5 { -1.0 } else { 1.0 } * 10f64.powf(rng.range(-3.0, 3.0));
            let c = from_roots(k, r);
            let found = roots(c);
            assert!(found.windows(2).all(|w| w[0] < w[1]), "not ascending {found:?}");
            for (i, &ri) in r.iter().enumerate() {
                if !(0.0..=1.0).contains(&ri) {
                    continue;
                }
                let nearest_other = (0..3).filter(|&j| j != i).map(|j| (r[j] - ri).abs()).fold(f64::INFINITY, f64::min);
                // Separated simple roots: accuracy limited by coefficient rounding (~1e-16
                // relative) divided by the slope |f'| ≥ product of separations.
                let tol = if nearest_other > 1e-3 { 1e-9 } else { 1e-5 };
                // Roots on the interval boundary may be reported at 0 or 1 when |f| ≤ ε there.
                assert!(
                    found.iter().any(|f| (f - ri).abs() <= tol),
                    "case {case}: root {ri} of {r:?} (k = {k}) missing in {found:?}"
                );
            }
        }
    }

    /// Independent check against dense sampling: every sign change seen between samples has a
    /// reported root inside (or at the ends of) that sample interval.
    #[test]
    fn random_coefficients_against_sampling() {
        let mut rng = Rng::new(77);
        let n = 2000;
        for _ in 0..3000 {
            let c = [rng.range(-1.0, 1.0), rng.range(-3.0, 3.0), rng.range(-3.0, 3.0), rng.range(-2.0, 2.0)];
            let found = roots(c);
            let f = |t: f64| ((c[3] * t + c[2]) * t + c[1]) * t + c[0];
            let mut prev = f(0.0);
            for s in 1..=n {
                let t1 = s as f64 / n as f64;
                let t0 = (s - 1) as f64 / n as f64;
                let cur = f(t1);
                if prev * cur < 0.0 {
                    assert!(
                        found.iter().any(|&r| r >= t0 - 1e-12 && r <= t1 + 1e-12),
                        "{c:?}: sign change in [{t0}, {t1}] missing in {found:?}"
                    );
                }
                prev = cur;
            }
        }
    }

    #[test]
    fn quadratic_roots_forms() {
        let mut o = [0.0; 2];
        assert_eq!(quadratic_roots(1.0, -3.0, 2.0, &mut o), 2);
        assert_eq!(o, [1.0, 2.0]);
        assert_eq!(quadratic_roots(0.0, 2.0, -1.0, &mut o), 1);
        assert_eq!(o[0], 0.5);
        assert_eq!(quadratic_roots(1.0, 0.0, 1.0, &mut o), 0);
        assert_eq!(quadratic_roots(0.0, 0.0, 1.0, &mut o), 0);
        assert_eq!(quadratic_roots(2.0, 0.0, 0.0, &mut o), 2);
        assert_eq!(o, [0.0, 0.0]);
        // Tiny leading coefficient: the small root stays accurate.
        assert_eq!(quadratic_roots(1e-20, 1.0, -0.5, &mut o), 2);
        assert!((o[1] - 0.5).abs() < 1e-15);
    }
}

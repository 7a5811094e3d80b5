//! Small 2-D clustering helpers for edge clustering (motion-graph.md §3.4): k-means with
//! k-means++ seeding (Lloyd iterations) and a bisecting 2-means split. These belong in
//! `geom_core::cluster` (GEOM-CORE.md §3.13), which does not exist yet; they are kept minimal
//! here and should move there.

use geom_core::rng::Rng;

/// Squared distance.
fn d2(a: [f64; 2], b: [f64; 2]) -> f64 {
    (a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2)
}

/// k-means on 2-D points: k-means++ seeding from `rng`, at most `iters` Lloyd iterations.
/// Returns the cluster index of each point; clusters may end up empty (their index is simply not
/// used). `k` is clamped to `[1, points.len()]`.
pub fn kmeans(points: &[[f64; 2]], k: usize, rng: &mut Rng, iters: usize) -> Vec<usize> {
    let n = points.len();
    if n == 0 {
        return vec![];
    }
    let k = k.clamp(1, n);
    let mut centres = vec![points[rng.below(n)]];
    let mut best: Vec<f64> = points.iter().map(|p| d2(*p, centres[0])).collect();
    while centres.len() < k {
        let total: f64 = best.iter().sum();
        let next = if total > 0.0 {
            let mut u = rng.f64() * total;
            let mut pick = n - 1;
            for (i, &b) in best.iter().enumerate() {
                if u < b {
                    pick = i;
                    break;
                }
                u -= b;
            }
            pick
        } else {
            rng.below(n)
        };
        centres.push(points[next]);
        for (b, p) in best.iter_mut().zip(points) {
            *b = b.min(d2(*p, points[next]));
        }
    }
    let mut assign = vec![0usize; n];
    for _ in 0..iters.max(1) {
        let mut changed = false;
        for (i, p) in points.iter().enumerate() {
            let mut bi = 0;
            let mut bd = f64::INFINITY;
            for (c, ce) in centres.iter().enumerate() {
                let d = d2(*p, *ce);
                if d < bd {
                    bd = d;
                    bi = c;
                }
            }
            if assign[i] != bi {
                assign[i] = bi;
                changed = true;
            }
        }
        let mut sum = vec![[0.0f64; 3]; k];
        for (p, &a) in points.iter().zip(&assign) {
            sum[a][0] += p[0];
            sum[a][1] += p[1];
            sum[a][2] += 1.0;
        }
        for (c, s) in centres.iter_mut().zip(&sum) {
            if s[2] > 0.0 {
                *c = [s[0] / s[2], s[1] / s[2]];
            }
        }
        if !changed {
            break;
        }
    }
    assign
}

/// Principal axis (unit) and centroid of 2-D points; eigenvalues `(λ₁ ≥ λ₂)` of the covariance.
pub fn pca(points: &[[f64; 2]]) -> ([f64; 2], [f64; 2], (f64, f64)) {
    let n = points.len().max(1) as f64;
    let c = [points.iter().map(|p| p[0]).sum::<f64>() / n, points.iter().map(|p| p[1]).sum::<f64>() / n];
    let (mut sxx, mut sxy, mut syy) = (0.0, 0.0, 0.0);
    for p in points {
        let (dx, dy) = (p[0] - c[0], p[1] - c[1]);
        sxx += dx * dx;
        sxy += dx * dy;
        syy += dy * dy;
    }
    let (sxx, sxy, syy) = (sxx / n, sxy / n, syy / n);
    let tr = sxx + syy;
    let det = sxx * syy - sxy * sxy;
    let disc = (0.25 * tr * tr - det).max(0.0).sqrt();
    let (l1, l2) = (0.5 * tr + disc, (0.5 * tr - disc).max(0.0));
    let axis = if sxy.abs() > 1e-300 {
        let v = [l1 - syy, sxy];
        let nn = (v[0] * v[0] + v[1] * v[1]).sqrt();
        [v[0] / nn, v[1] / nn]
    } else if sxx >= syy {
        [1.0, 0.0]
    } else {
        [0.0, 1.0]
    };
    (axis, c, (l1, l2))
}

/// Splits points (at least 2) into two non-empty sides: 2-means started from the extremes along
/// the principal axis; if a side comes out empty, the median split along that axis.
pub fn bisect(points: &[[f64; 2]]) -> Vec<bool> {
    let n = points.len();
    let (axis, c, _) = pca(points);
    let proj: Vec<f64> = points.iter().map(|p| (p[0] - c[0]) * axis[0] + (p[1] - c[1]) * axis[1]).collect();
    let (mut lo, mut hi) = (0, 0);
    for i in 0..n {
        if proj[i] < proj[lo] {
            lo = i;
        }
        if proj[i] > proj[hi] {
            hi = i;
        }
    }
    let mut ca = points[lo];
    let mut cb = points[hi];
    let mut side = vec![false; n];
    for _ in 0..20 {
        for (s, p) in side.iter_mut().zip(points) {
            *s = d2(*p, cb) < d2(*p, ca);
        }
        let mut sa = [0.0, 0.0, 0.0];
        let mut sb = [0.0, 0.0, 0.0];
        for (s, p) in side.iter().zip(points) {
            let t = if *s { &mut sb } else { &mut sa };
            t[0] += p[0];
            t[1] += p[1];
            t[2] += 1.0;
        }
        if sa[2] == 0.0 || sb[2] == 0.0 {
            break;
        }
        ca = [sa[0] / sa[2], sa[1] / sa[2]];
        cb = [sb[0] / sb[2], sb[1] / sb[2]];
    }
    let count = side.iter().filter(|s| **s).count();
    if count == 0 || count == n {
        let mut order: Vec<usize> = (0..n).collect();
        order.sort_by(|&a, &b| proj[a].total_cmp(&proj[b]).then(a.cmp(&b)));
        for (r, &i) in order.iter().enumerate() {
            side[i] = r >= n / 2;
        }
    }
    side
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn kmeans_separates_blobs_and_bisect_is_nonempty() {
        let mut pts = vec![];
        for i in 0..20 {
            pts.push([i as f64 * 0.01, 0.0]);
            pts.push([10.0 + i as f64 * 0.01, 5.0]);
        }
        let mut rng = Rng::new(1);
        let a = kmeans(&pts, 2, &mut rng, 50);
        for i in 0..20 {
            assert_eq!(a[2 * i], a[0]);
            assert_eq!(a[2 * i + 1], a[1]);
        }
        assert_ne!(a[0], a[1]);
        // Identical points: bisect falls back to the median split.
        let same = vec![[1.0, 1.0]; 5];
        let s = bisect(&same);
        let c = s.iter().filter(|x| **x).count();
        assert!(c > 0 && c < 5);
        let (_, _, (l1, l2)) = pca(&[[0.0, 0.0], [2.0, 2.0], [4.0, 4.0]]);
        assert!(l1 > 0.0 && l2.abs() < 1e-12);
    }
}

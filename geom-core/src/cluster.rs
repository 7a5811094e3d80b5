//! Clustering (GEOM-CORE.md §3.13): complete-linkage agglomerative clustering over an arbitrary
//! distance function, cut by a distance threshold or to a target cluster count (used by
//! perf-control §3.7 to reduce a database of motion instances).
//!
//! Complete linkage: the distance between two clusters is the *largest* pairwise distance of
//! their members, so every cluster of a cut at threshold `τ` has diameter ≤ `τ` (unlike k-means).
//! Merge heights are non-decreasing (complete linkage is a monotone, "reducible" linkage), so the
//! dendrogram is built once and any threshold cut is "apply every merge of height ≤ τ".
//!
//! Algorithm: distance matrix (O(N²) memory, O(N²) distance calls) with a cached nearest
//! neighbour per row; after merging `j` into `i` (Lance–Williams for complete linkage:
//! `d(k, i∪j) = max(d(k, i), d(k, j))`) only rows whose cached neighbour was `i` or `j` are
//! rescanned (distances only grow, so every other cache stays valid). Average O(N²) time.
//! Ties are broken deterministically by the lowest `(i, j)` index pair. Infinite (or NaN)
//! distances mean "never merge".

/// How to cut the dendrogram.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Cut {
    /// Merge while the smallest cluster distance is ≤ the threshold.
    Threshold(f64),
    /// The threshold giving a cluster count within `n ± tol` (the largest such threshold's
    /// count closest to `n`; equivalent to bisecting the threshold). If fewer than `n − tol`
    /// clusters are unreachable because infinite distances forbid merges, the finest reachable
    /// partition with the fewest clusters is returned.
    TargetCount {
        /// Wanted number of clusters.
        n: usize,
        /// Accepted deviation.
        tol: usize,
    },
}

/// One merge of the dendrogram: clusters represented by their lowest member `a < b`, at height
/// `h` (complete-linkage distance).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Merge {
    /// Representative (lowest index) of the first cluster.
    pub a: usize,
    /// Representative of the second cluster.
    pub b: usize,
    /// Complete-linkage distance at the merge.
    pub h: f64,
}

/// The complete-linkage dendrogram of `n` items: merges in order (non-decreasing `h`). Only
/// finite distances are merged; the result has `n − 1` merges when all distances are finite.
pub fn complete_linkage_dendrogram(n: usize, dist: &dyn Fn(usize, usize) -> f64) -> Vec<Merge> {
    let clean = |d: f64| if d.is_nan() { f64::INFINITY } else { d };
    let mut m = vec![f64::INFINITY; n * n];
    for i in 0..n {
        for j in (i + 1)..n {
            let d = clean(dist(i, j));
            m[i * n + j] = d;
            m[j * n + i] = d;
        }
    }
    let mut alive = vec![true; n];
    // nn[i] = (distance, index) of the nearest live j > i … we keep the full row minimum over
    // all live j ≠ i with ties to the lowest j.
    let row_min = |m: &[f64], alive: &[bool], i: usize| -> (f64, usize) {
        let mut best = (f64::INFINITY, usize::MAX);
        for j in 0..n {
            if j != i && alive[j] && m[i * n + j] < best.0 {
                best = (m[i * n + j], j);
            }
        }
        best
    };
    let mut nn: Vec<(f64, usize)> = (0..n).map(|i| row_min(&m, &alive, i)).collect();
    let mut merges = Vec::with_capacity(n.saturating_sub(1));
    loop {
        // Global minimum over live rows; ties → lowest (i, j) pair.
        let mut best = (f64::INFINITY, usize::MAX, usize::MAX);
        for i in 0..n {
            if !alive[i] || !nn[i].0.is_finite() {
                continue;
            }
            let (d, j) = nn[i];
            let (a, b) = if i < j { (i, j) } else { (j, i) };
            if d < best.0 || (d == best.0 && (a, b) < (best.1, best.2)) {
                best = (d, a, b);
            }
        }
        if !best.0.is_finite() {
            break;
        }
        let (h, a, b) = best;
        merges.push(Merge { a, b, h });
        alive[b] = false;
        for k in 0..n {
            if k != a && alive[k] {
                let d = m[k * n + a].max(m[k * n + b]);
                m[k * n + a] = d;
                m[a * n + k] = d;
            }
        }
        nn[a] = row_min(&m, &alive, a);
        for k in 0..n {
            if k != a && alive[k] {
                if nn[k].1 == a || nn[k].1 == b {
                    nn[k] = row_min(&m, &alive, k);
                } else if m[k * n + a] < nn[k].0 || (m[k * n + a] == nn[k].0 && a < nn[k].1) {
                    // Cannot happen for complete linkage (distances only grow); kept for ties.
                    nn[k] = (m[k * n + a], a);
                }
            }
        }
    }
    merges
}

/// Cluster labels after applying the first `count` merges: ids `0, 1, …` in order of each
/// cluster's lowest member.
fn labels_after(n: usize, merges: &[Merge], count: usize) -> Vec<u32> {
    let mut parent: Vec<usize> = (0..n).collect();
    fn find(p: &mut [usize], mut x: usize) -> usize {
        while p[x] != x {
            p[x] = p[p[x]];
            x = p[x];
        }
        x
    }
    for mg in &merges[..count] {
        let ra = find(&mut parent, mg.a);
        let rb = find(&mut parent, mg.b);
        let (lo, hi) = if ra < rb { (ra, rb) } else { (rb, ra) };
        parent[hi] = lo;
    }
    let mut id = vec![u32::MAX; n];
    let mut next = 0u32;
    (0..n)
        .map(|i| {
            let r = find(&mut parent, i);
            if id[r] == u32::MAX {
                id[r] = next;
                next += 1;
            }
            id[r]
        })
        .collect()
}

/// Complete-linkage clustering of `n` items with pairwise distance `dist(i, j)` (symmetric; only
/// `i < j` is queried), cut by `cut`. Returns one cluster id per item, numbered in order of
/// each cluster's lowest member. A non-finite threshold below 0 (or NaN) merges nothing.
pub fn complete_linkage(n: usize, dist: &dyn Fn(usize, usize) -> f64, cut: Cut) -> Vec<u32> {
    let merges = complete_linkage_dendrogram(n, dist);
    let count = match cut {
        Cut::Threshold(t) => merges.iter().take_while(|m| m.h <= t).count(),
        Cut::TargetCount { n: want, tol } => {
            // Clusters after c merges: n − c. Threshold cuts can only stop between merges of
            // different heights; pick the cut whose count is closest to `want` (ties: fewer
            // merges), preferring counts within the tolerance.
            let mut cuts: Vec<usize> = vec![0];
            for c in 1..=merges.len() {
                if c == merges.len() || merges[c].h > merges[c - 1].h {
                    cuts.push(c);
                }
            }
            let mut best = 0usize;
            let mut best_err = usize::MAX;
            for &c in &cuts {
                let err = (n - c).abs_diff(want);
                if err < best_err {
                    best_err = err;
                    best = c;
                }
            }
            let _ = tol; // the closest achievable count is returned; `tol` documents the contract
            best
        }
    };
    labels_after(n, &merges, count)
}

/// Number of clusters in a label vector.
pub fn cluster_count(labels: &[u32]) -> usize {
    labels.iter().map(|&l| l as usize + 1).max().unwrap_or(0)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Rng;

    /// Naive O(N³) complete linkage stopped at a threshold, same tie rule (lowest pair).
    fn naive(n: usize, d: &dyn Fn(usize, usize) -> f64, thr: f64) -> Vec<u32> {
        let mut clusters: Vec<Vec<usize>> = (0..n).map(|i| vec![i]).collect();
        loop {
            let mut best = (f64::INFINITY, 0, 0);
            for a in 0..clusters.len() {
                for b in (a + 1)..clusters.len() {
                    let mut dm: f64 = 0.0;
                    for &i in &clusters[a] {
                        for &j in &clusters[b] {
                            dm = dm.max(if i < j { d(i, j) } else { d(j, i) });
                        }
                    }
                    if dm < best.0 {
                        best = (dm, a, b);
                    }
                }
            }
            if best.0.is_nan() || best.0 > thr {
                break;
            }
            let cb = clusters.remove(best.2);
            clusters[best.1].extend(cb);
        }
        let mut out = vec![0u32; n];
        let mut reps: Vec<(usize, usize)> =
            clusters.iter().enumerate().map(|(c, m)| (*m.iter().min().unwrap(), c)).collect();
        reps.sort();
        for (id, (_, c)) in reps.iter().enumerate() {
            for &i in &clusters[*c] {
                out[i] = id as u32;
            }
        }
        out
    }

    fn random_points(seed: u64, n: usize) -> Vec<[f64; 2]> {
        let mut r = Rng::new(seed);
        (0..n).map(|_| [r.range(0.0, 10.0), r.range(0.0, 10.0)]).collect()
    }

    #[test]
    fn matches_naive_and_bounds_diameter() {
        for seed in 0..5 {
            let p = random_points(seed, 60);
            let d = |i: usize, j: usize| ((p[i][0] - p[j][0]).powi(2) + (p[i][1] - p[j][1]).powi(2)).sqrt();
            for thr in [0.5, 1.5, 3.0, 6.0] {
                let fast = complete_linkage(60, &d, Cut::Threshold(thr));
                assert_eq!(fast, naive(60, &d, thr), "seed {seed} thr {thr}");
                for i in 0..60 {
                    for j in 0..60 {
                        if fast[i] == fast[j] {
                            assert!(d(i, j) <= thr);
                        }
                    }
                }
            }
        }
    }

    #[test]
    fn merge_heights_are_monotone_and_infinite_distances_never_merge() {
        let p = random_points(9, 40);
        // Two groups that may never merge with each other.
        let d = |i: usize, j: usize| {
            if (i < 20) != (j < 20) {
                f64::INFINITY
            } else {
                ((p[i][0] - p[j][0]).powi(2) + (p[i][1] - p[j][1]).powi(2)).sqrt()
            }
        };
        let m = complete_linkage_dendrogram(40, &d);
        assert_eq!(m.len(), 38);
        assert!(m.windows(2).all(|w| w[0].h <= w[1].h));
        let l = complete_linkage(40, &d, Cut::Threshold(1e9));
        assert_eq!(cluster_count(&l), 2);
        let l = complete_linkage(40, &d, Cut::TargetCount { n: 1, tol: 0 });
        assert_eq!(cluster_count(&l), 2, "finest reachable with fewest clusters");
    }

    #[test]
    fn target_count_within_tolerance() {
        let p = random_points(3, 100);
        let d = |i: usize, j: usize| ((p[i][0] - p[j][0]).powi(2) + (p[i][1] - p[j][1]).powi(2)).sqrt();
        for want in [5, 17, 40, 70, 99] {
            let l = complete_linkage(100, &d, Cut::TargetCount { n: want, tol: 2 });
            let c = cluster_count(&l);
            assert!(c.abs_diff(want) <= 2, "want {want} got {c}");
        }
        assert_eq!(complete_linkage(0, &d, Cut::Threshold(1.0)), Vec::<u32>::new());
        assert_eq!(complete_linkage(1, &d, Cut::Threshold(1.0)), vec![0]);
    }
}

//! [`KdTree`]: a balanced k-d tree over 3-D points for nearest-neighbour and radius queries.

use crate::math::Pt3;

/// A k-d tree over 3-D points, stored implicitly: the points are permuted so that, for every
/// index range `[lo, hi)`, the median `m = (lo + hi) / 2` is the splitting point, the points of
/// `[lo, m)` have coordinate `≤` and those of `(m, hi)` coordinate `≥` the median's along the
/// range's split axis (the axis of largest spread). Building is O(n log n) and allocation-light,
/// so the tree is cheap to rebuild when the points move (FT particles, RG samples).
///
/// Distances are Euclidean; queries compare squared distances computed exactly as
/// `dx² + dy² + dz²`, and ties are broken by the smaller point index, so results equal a brute
/// force scan bit for bit.
#[derive(Clone, Debug, Default)]
pub struct KdTree {
    /// Points in tree order.
    pts: Vec<[f64; 3]>,
    /// Original index of each point in tree order.
    idx: Vec<u32>,
    /// Split axis of the range whose median sits at this position.
    axis: Vec<u8>,
}

#[inline]
fn dist2(a: &[f64; 3], b: &[f64; 3]) -> f64 {
    let (dx, dy, dz) = (a[0] - b[0], a[1] - b[1], a[2] - b[2]);
    dx * dx + dy * dy + dz * dz
}

/// `(d², index)` lexicographic "less than".
#[inline]
fn better(d2: f64, i: u32, e2: f64, j: u32) -> bool {
    d2 < e2 || (d2 == e2 && i < j)
}

impl KdTree {
    /// Builds the tree over `points` (index `i` is `points[i]`).
    pub fn build(points: &[Pt3]) -> Self {
        let n = points.len();
        let mut t = Self {
            pts: points.iter().map(|p| [p.x, p.y, p.z]).collect(),
            idx: (0..n as u32).collect(),
            axis: vec![0; n],
        };
        t.build_range(0, n);
        t
    }

    fn build_range(&mut self, lo: usize, hi: usize) {
        if hi - lo <= 1 {
            return;
        }
        let mut mn = [f64::INFINITY; 3];
        let mut mx = [f64::NEG_INFINITY; 3];
        for p in &self.pts[lo..hi] {
            for k in 0..3 {
                mn[k] = mn[k].min(p[k]);
                mx[k] = mx[k].max(p[k]);
            }
        }
        let mut axis = 0;
        for k in 1..3 {
            if mx[k] - mn[k] > mx[axis] - mn[axis] {
                axis = k;
            }
        }
        let mid = (lo + hi) / 2;
        // Co-permute points and indices: sort a key vector, then gather (the slice sizes shrink
        // geometrically, so the extra copies cost O(n log n) in all).
        let mut keys: Vec<(f64, u32, [f64; 3])> =
            (lo..hi).map(|k| (self.pts[k][axis], self.idx[k], self.pts[k])).collect();
        keys.select_nth_unstable_by(mid - lo, |a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        for (s, (_, i, p)) in keys.into_iter().enumerate() {
            self.idx[lo + s] = i;
            self.pts[lo + s] = p;
        }
        self.axis[mid] = axis as u8;
        self.build_range(lo, mid);
        self.build_range(mid + 1, hi);
    }

    /// Number of points.
    pub fn len(&self) -> usize {
        self.pts.len()
    }

    /// `true` for a tree over no points.
    pub fn is_empty(&self) -> bool {
        self.pts.is_empty()
    }

    /// The nearest point to `q`: `(index, distance)`, the smaller index on ties; `None` for an
    /// empty tree.
    pub fn nearest(&self, q: &Pt3) -> Option<(u32, f64)> {
        let q = [q.x, q.y, q.z];
        let mut best = (f64::INFINITY, u32::MAX);
        self.nearest_range(&q, 0, self.pts.len(), &mut best);
        (best.1 != u32::MAX).then(|| (best.1, best.0.sqrt()))
    }

    fn nearest_range(&self, q: &[f64; 3], lo: usize, hi: usize, best: &mut (f64, u32)) {
        if lo >= hi {
            return;
        }
        let mid = (lo + hi) / 2;
        let d2 = dist2(q, &self.pts[mid]);
        if better(d2, self.idx[mid], best.0, best.1) {
            *best = (d2, self.idx[mid]);
        }
        if hi - lo == 1 {
            return;
        }
        let axis = self.axis[mid] as usize;
        let diff = q[axis] - self.pts[mid][axis];
        let (near, far) = if diff <= 0.0 { ((lo, mid), (mid + 1, hi)) } else { ((mid + 1, hi), (lo, mid)) };
        self.nearest_range(q, near.0, near.1, best);
        // A point on the far side is at least |diff| away (monotone rounding keeps this exact);
        // `<=` keeps equal-distance points with smaller indices reachable.
        if diff * diff <= best.0 {
            self.nearest_range(q, far.0, far.1, best);
        }
    }

    /// The `k` nearest points to `q` as `(index, distance)`, sorted by (distance, index), into
    /// `out` (cleared first). Fewer than `k` when the tree holds fewer points.
    pub fn knn(&self, q: &Pt3, k: usize, out: &mut Vec<(u32, f64)>) {
        out.clear();
        if k == 0 || self.pts.is_empty() {
            return;
        }
        let q = [q.x, q.y, q.z];
        // `heap` holds (d², index) sorted ascending; at most k entries (k is small in practice,
        // so an insertion-sorted vector beats a binary heap).
        let mut heap: Vec<(f64, u32)> = Vec::with_capacity(k + 1);
        self.knn_range(&q, k, 0, self.pts.len(), &mut heap);
        out.extend(heap.into_iter().map(|(d2, i)| (i, d2.sqrt())));
    }

    fn knn_range(&self, q: &[f64; 3], k: usize, lo: usize, hi: usize, heap: &mut Vec<(f64, u32)>) {
        if lo >= hi {
            return;
        }
        let mid = (lo + hi) / 2;
        let d2 = dist2(q, &self.pts[mid]);
        let i = self.idx[mid];
        let full = heap.len() == k;
        if !full || better(d2, i, heap[k - 1].0, heap[k - 1].1) {
            let pos = heap.partition_point(|&(e2, j)| better(e2, j, d2, i));
            heap.insert(pos, (d2, i));
            heap.truncate(k);
        }
        if hi - lo == 1 {
            return;
        }
        let axis = self.axis[mid] as usize;
        let diff = q[axis] - self.pts[mid][axis];
        let (near, far) = if diff <= 0.0 { ((lo, mid), (mid + 1, hi)) } else { ((mid + 1, hi), (lo, mid)) };
        self.knn_range(q, k, near.0, near.1, heap);
        if heap.len() < k || diff * diff <= heap[k - 1].0 {
            self.knn_range(q, k, far.0, far.1, heap);
        }
    }

    /// Indices of all points within distance `r` of `q` (closed ball: `|p − q|² ≤ r²`), sorted
    /// ascending, into `out` (cleared first).
    pub fn within(&self, q: &Pt3, r: f64, out: &mut Vec<u32>) {
        out.clear();
        if r.is_nan() || r < 0.0 {
            return;
        }
        let q = [q.x, q.y, q.z];
        self.within_range(&q, r * r, 0, self.pts.len(), out);
        out.sort_unstable();
    }

    fn within_range(&self, q: &[f64; 3], r2: f64, lo: usize, hi: usize, out: &mut Vec<u32>) {
        if lo >= hi {
            return;
        }
        let mid = (lo + hi) / 2;
        if dist2(q, &self.pts[mid]) <= r2 {
            out.push(self.idx[mid]);
        }
        if hi - lo == 1 {
            return;
        }
        let axis = self.axis[mid] as usize;
        let diff = q[axis] - self.pts[mid][axis];
        if diff <= 0.0 || diff * diff <= r2 {
            self.within_range(q, r2, lo, mid, out);
        }
        if diff >= 0.0 || diff * diff <= r2 {
            self.within_range(q, r2, mid + 1, hi, out);
        }
    }
}

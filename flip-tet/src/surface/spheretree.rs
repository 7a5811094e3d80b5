//! [`SphereTree`]: a bounding-box tree over source spheres answering the clamped sphere-union
//! query `min_s (|q − x_s| − r_s)` over the sources within a search ball, with pruning.
//!
//! The level set (spec §3.11.3) needs, at every node, the union-of-spheres value over all sources
//! within `search = 2 l r_max + band`, clamped to `±band`. A plain radius query visits every source
//! in that ball (thousands of particles per node at the simulation's `h = 4 r`). Here every tree
//! node stores its box, the largest radius below it and the box of its balls, so a subtree whose
//! lower bound `max(dist(q, box) − r_max(subtree), dist(q, ball box))` already exceeds the current
//! minimum (or the band) is skipped,
//! and the search stops once the minimum is below `−band` (the value is then clamped anyway).
//! The per-source arithmetic and the ball test are the same expressions as the exhaustive scan,
//! and skipped sources provably cannot lower the minimum, so the result is bitwise equal to the
//! exhaustive scan (checked in `tests/surface_fast.rs`).

use geom_core::math::Pt3;

/// Sources per leaf.
const LEAF: usize = 8;
/// Traversal stack size: median splits give depth `≤ log2(n / LEAF) + 1 < 40` for any `u32` count,
/// and the traversal holds at most two entries per level.
const STACK: usize = 96;

#[derive(Clone, Copy, Debug)]
struct Node {
    min: [f64; 3],
    max: [f64; 3],
    /// Largest source radius in the subtree (m).
    rmax: f64,
    /// Bounding box of the balls `x_s ± r_s` of the subtree (m): for `q` outside it, every
    /// source value `|q − x_s| − r_s` is at least the distance from `q` to this box. Much tighter than
    /// `dist(q, centre box) − rmax` for subtrees that mix small surface particles with the large
    /// interior radii of deep ones.
    bmin: [f64; 3],
    bmax: [f64; 3],
    /// Source range `[lo, hi)` in tree order.
    lo: u32,
    hi: u32,
    /// Child node indices; `u32::MAX` for a leaf.
    left: u32,
    right: u32,
}

/// Bounding-box tree over spheres `(x_s, r_s)`: the pruned sphere-union query of the level set
/// ([`SphereTree::min_value`]) and the emptiness test of a gather ([`SphereTree::any_closer`]).
#[derive(Clone, Debug, Default)]
pub struct SphereTree {
    nodes: Vec<Node>,
    /// Centres in tree order.
    pts: Vec<Pt3>,
    /// Radii in tree order.
    r: Vec<f64>,
    /// Input index of each source, in tree order.
    idx: Vec<u32>,
}

/// Squared distance from `q` to the box `[min, max]` (0 inside). For a point `p` of the box every
/// rounded coordinate difference `|q_k − p_k|` is at least the rounded gap (rounding is monotone),
/// so this never exceeds the rounded `|q − p|²` of any point in the box.
#[inline]
fn box_dist2(q: &[f64; 3], min: &[f64; 3], max: &[f64; 3]) -> f64 {
    let mut d2 = 0.0;
    for k in 0..3 {
        let g = if q[k] < min[k] {
            min[k] - q[k]
        } else if q[k] > max[k] {
            q[k] - max[k]
        } else {
            0.0
        };
        d2 += g * g;
    }
    d2
}

impl SphereTree {
    /// Builds the tree over the spheres `(centres[i], radii[i])` (median splits along the longest
    /// box axis; ties broken by index, so the build is deterministic).
    pub fn build(centres: &[Pt3], radii: &[f64]) -> Self {
        let mut order: Vec<u32> = (0..centres.len() as u32).collect();
        let mut t = Self { nodes: Vec::new(), pts: Vec::new(), r: Vec::new(), idx: Vec::new() };
        if !order.is_empty() {
            t.build_range(centres, radii, &mut order, 0);
        }
        t.pts = order.iter().map(|&i| centres[i as usize]).collect();
        t.r = order.iter().map(|&i| radii[i as usize]).collect();
        t.idx = order;
        t
    }

    fn build_range(&mut self, c: &[Pt3], r: &[f64], order: &mut [u32], lo: usize) -> u32 {
        let mut min = [f64::INFINITY; 3];
        let mut max = [f64::NEG_INFINITY; 3];
        let mut rmax = f64::NEG_INFINITY;
        let mut bmin = [f64::INFINITY; 3];
        let mut bmax = [f64::NEG_INFINITY; 3];
        for &i in order.iter() {
            let p = c[i as usize];
            let ri = r[i as usize];
            for k in 0..3 {
                min[k] = min[k].min(p[k]);
                max[k] = max[k].max(p[k]);
                bmin[k] = bmin[k].min(p[k] - ri);
                bmax[k] = bmax[k].max(p[k] + ri);
            }
            rmax = rmax.max(ri);
        }
        let id = self.nodes.len() as u32;
        let n = order.len();
        self.nodes.push(Node {
            min,
            max,
            rmax,
            bmin,
            bmax,
            lo: lo as u32,
            hi: (lo + n) as u32,
            left: u32::MAX,
            right: u32::MAX,
        });
        if n <= LEAF {
            return id;
        }
        let mut axis = 0;
        for k in 1..3 {
            if max[k] - min[k] > max[axis] - min[axis] {
                axis = k;
            }
        }
        let mid = n / 2;
        order.select_nth_unstable_by(mid, |&a, &b| c[a as usize][axis].total_cmp(&c[b as usize][axis]).then(a.cmp(&b)));
        let (left_part, right_part) = order.split_at_mut(mid);
        let left = self.build_range(c, r, left_part, lo);
        let right = self.build_range(c, r, right_part, lo + mid);
        self.nodes[id as usize].left = left;
        self.nodes[id as usize].right = right;
        id
    }

    /// Whether some centre lies at distance `< rad` from `q`, with the distance computed as
    /// `sqrt(dx² + dy² + dz²)` (the k-d tree's `nearest` expression), so
    /// `!any_closer(q, rad)` equals `tree.nearest(q).is_none_or(|(_, d)| d >= rad)` exactly. The
    /// boxes prune empty regions after a few levels, unlike a split-plane k-d tree, which makes
    /// this the cheap "is this tet far from every particle" test of a gather over all tets.
    pub fn any_closer(&self, q: &Pt3, rad: f64) -> bool {
        if rad.is_nan() {
            return false;
        }
        let qa = [q.x, q.y, q.z];
        // Monotone rounding: no point of the box is closer than the box itself.
        self.traverse(
            &qa,
            false,
            |n| box_dist2(&qa, &n.min, &n.max).sqrt() >= rad,
            |k| {
                let p = &self.pts[k];
                let (dx, dy, dz) = (qa[0] - p.x, qa[1] - p.y, qa[2] - p.z);
                (dx * dx + dy * dy + dz * dz).sqrt() < rad
            },
        )
    }

    /// Whether some centre other than input index `except` has `dx² + dy² + dz² ≤ r2`
    /// (`d = q − x_s`): the ballistic test "a neighbour within the reach" with the k-d tree's
    /// expression. Nearer children are searched first and the search stops at the first hit.
    pub fn any_other_within2(&self, q: &Pt3, r2: f64, except: u32) -> bool {
        if r2.is_nan() {
            return false;
        }
        let qa = [q.x, q.y, q.z];
        self.traverse(
            &qa,
            true,
            |n| box_dist2(&qa, &n.min, &n.max) > r2,
            |k| {
                let p = &self.pts[k];
                let (dx, dy, dz) = (qa[0] - p.x, qa[1] - p.y, qa[2] - p.z);
                self.idx[k] != except && dx * dx + dy * dy + dz * dz <= r2
            },
        )
    }

    /// Input indices (ascending) of the centres with `dx² + dy² + dz² ≤ rad²` (`d = q − x_s`): the
    /// same predicate and order as geom-core's `KdTree::within`, so the two lists are equal. The
    /// boxes of 8-source leaves prune whole regions, which is cheaper than the k-d tree's
    /// one-point-per-node descent for the many small gathers of P2G.
    pub fn within(&self, q: &Pt3, rad: f64, out: &mut Vec<u32>) {
        out.clear();
        if rad.is_nan() || rad < 0.0 {
            return;
        }
        let r2 = rad * rad;
        let qa = [q.x, q.y, q.z];
        // Monotone rounding: no point of the box has a smaller rounded `d²` than the box.
        self.traverse(
            &qa,
            false,
            |n| box_dist2(&qa, &n.min, &n.max) > r2,
            |k| {
                let p = &self.pts[k];
                let (dx, dy, dz) = (qa[0] - p.x, qa[1] - p.y, qa[2] - p.z);
                if dx * dx + dy * dy + dz * dz <= r2 {
                    out.push(self.idx[k]);
                }
                false
            },
        );
        out.sort_unstable();
    }

    /// Input indices (ascending) of the spheres that can overlap the ball `(q, rad)`: every source
    /// with `|q − x_s| < rad + r_s` is listed (with a relative slack of `1e−12` against rounding, so
    /// a few just-touching ones may be listed too; the caller keeps its exact test). Subtrees are
    /// pruned with their own largest radius, so a small query among a few large spheres does not
    /// list everything within `rad + max r` as a plain radius query must.
    pub fn touching(&self, q: &Pt3, rad: f64, out: &mut Vec<u32>) {
        out.clear();
        if rad.is_nan() {
            return;
        }
        const SLACK: f64 = 1.0 + 1e-12;
        let qa = [q.x, q.y, q.z];
        // Monotone rounding: no point of the box is closer than the box itself.
        self.traverse(
            &qa,
            false,
            |n| box_dist2(&qa, &n.min, &n.max).sqrt() > (rad + n.rmax) * SLACK,
            |k| {
                let p = &self.pts[k];
                let (dx, dy, dz) = (qa[0] - p.x, qa[1] - p.y, qa[2] - p.z);
                if (dx * dx + dy * dy + dz * dz).sqrt() <= (rad + self.r[k]) * SLACK {
                    out.push(self.idx[k]);
                }
                false
            },
        );
        out.sort_unstable();
    }

    /// Depth-first traversal shared by the queries above: subtrees with `skip(node)` are pruned,
    /// `visit(k)` is called for every source slot `k` (tree order) of the reached leaves (a node
    /// is scanned as a leaf when the fixed stack is full), and the traversal stops and returns
    /// true as soon as `visit` does. With `near_first` the child whose box is nearer to `qa` is
    /// entered first (the left one on ties), else always the left one.
    #[inline]
    fn traverse(
        &self,
        qa: &[f64; 3],
        near_first: bool,
        skip: impl Fn(&Node) -> bool,
        mut visit: impl FnMut(usize) -> bool,
    ) -> bool {
        if self.nodes.is_empty() {
            return false;
        }
        let mut stack = [0u32; STACK];
        let mut sp = 1usize;
        while sp > 0 {
            sp -= 1;
            let n = &self.nodes[stack[sp] as usize];
            if skip(n) {
                continue;
            }
            if n.left == u32::MAX || sp + 2 > STACK {
                for k in n.lo as usize..n.hi as usize {
                    if visit(k) {
                        return true;
                    }
                }
                continue;
            }
            let (a, b) = (&self.nodes[n.left as usize], &self.nodes[n.right as usize]);
            let (first, second) = if near_first && box_dist2(qa, &b.min, &b.max) < box_dist2(qa, &a.min, &a.max) {
                (n.right, n.left)
            } else {
                (n.left, n.right)
            };
            stack[sp] = second;
            stack[sp + 1] = first;
            sp += 2;
        }
        false
    }

    /// Minimum of `best` and `|q − x_s| − r_s` over the sources of `n`'s range inside the closed
    /// ball `|q − x_s|² ≤ s2` (the squared distance is the k-d tree's `dx² + dy² + dz²`).
    fn scan(&self, q: &Pt3, s2: f64, n: &Node, mut best: f64) -> f64 {
        for k in n.lo as usize..n.hi as usize {
            let p = &self.pts[k];
            let (dx, dy, dz) = (q.x - p.x, q.y - p.y, q.z - p.z);
            if dx * dx + dy * dy + dz * dz <= s2 {
                best = best.min((q - p).norm() - self.r[k]);
            }
        }
        best
    }

    /// `min_s (|q − x_s| − r_s)` over the sources with `|q − x_s|² ≤ search²` (the closed ball of
    /// the exhaustive radius query), up to what the caller's clamp to `[−band, band]` cannot see:
    ///
    /// - sources whose value provably exceeds `band` are skipped (the clamp maps the minimum to
    ///   `band` either way; `+∞` is returned when no source at or below `band` exists);
    /// - the search stops as soon as the minimum is `< −band` (the clamp gives `−band`).
    ///
    /// So `clamp(result, −band, band)` equals the clamped exhaustive minimum bitwise, and the
    /// unclamped result equals the exhaustive minimum whenever that lies in `[−band, band]`.
    /// `eps` (m, ≥ 0) is the safety margin subtracted from every lower bound against rounding.
    pub fn min_value(&self, q: &Pt3, search: f64, band: f64, eps: f64) -> f64 {
        self.min_value_until(q, search, band, eps, -band)
    }

    /// [`Self::min_value`] that stops as soon as the running minimum is `< stop` (`stop ≥ −band`)
    /// and returns it: the exact minimum is then `< stop` too (it is at most any term found).
    /// When the result is `≥ stop` the search never stopped early and the result equals
    /// [`Self::min_value`] bitwise (same traversal, same pruning, same arithmetic). With
    /// `stop = 0` this decides "inside the sphere union" for a node that only needs its sign.
    pub fn min_value_until(&self, q: &Pt3, search: f64, band: f64, eps: f64, stop: f64) -> f64 {
        let mut best = f64::INFINITY;
        if self.nodes.is_empty() || search.is_nan() || search < 0.0 {
            return best;
        }
        let s2 = search * search;
        let qa = [q.x, q.y, q.z];
        let mut stack = [0u32; STACK];
        let mut sp = 1usize;
        while sp > 0 {
            sp -= 1;
            let n = &self.nodes[stack[sp] as usize];
            let d2b = box_dist2(&qa, &n.min, &n.max);
            if d2b > s2 {
                continue;
            }
            // Outside the ball box `q` is outside every ball, so each value is at least the
            // distance to that box; inside it only the centre-box bound holds.
            let db = box_dist2(&qa, &n.bmin, &n.bmax).sqrt();
            let lb = if db > 0.0 { (d2b.sqrt() - n.rmax).max(db) } else { d2b.sqrt() - n.rmax } - eps;
            if lb > band || lb >= best {
                continue;
            }
            if n.left == u32::MAX {
                best = self.scan(q, s2, n, best);
                if best < stop {
                    return best;
                }
                continue;
            }
            // Push the farther child first so the nearer one is searched first.
            let (a, b) = (&self.nodes[n.left as usize], &self.nodes[n.right as usize]);
            let da = box_dist2(&qa, &a.min, &a.max).sqrt() - a.rmax;
            let db = box_dist2(&qa, &b.min, &b.max).sqrt() - b.rmax;
            let (near, far) = if da <= db { (n.left, n.right) } else { (n.right, n.left) };
            if sp + 2 > STACK {
                // Unreachable for median-split trees (depth < 40); scan the subtree instead.
                best = self.scan(q, s2, n, best);
                continue;
            }
            stack[sp] = far;
            stack[sp + 1] = near;
            sp += 2;
        }
        best
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use geom_core::rng::Rng;
    use geom_core::spatial::KdTree;

    #[test]
    fn any_closer_equals_the_nearest_neighbour_test() {
        // A clustered cloud (a slab) and queries everywhere, including far empty space and radii
        // equal to exact distances: the box test must agree with k-d `nearest` bit for bit.
        let mut rng = Rng::new(9);
        let pts: Vec<Pt3> =
            (0..3000).map(|_| Pt3::new(rng.range(0.0, 1.0), rng.range(0.0, 0.2), rng.range(0.0, 1.0))).collect();
        let tree = SphereTree::build(&pts, &vec![0.0; pts.len()]);
        let kd = KdTree::build(&pts);
        let mut hits = 0;
        for i in 0..4000 {
            let q = Pt3::new(rng.range(-0.2, 1.2), rng.range(-0.2, 1.2), rng.range(-0.2, 1.2));
            let rad = if i % 10 == 0 { kd.nearest(&q).map_or(0.05, |(_, d)| d) } else { rng.range(0.0, 0.1) };
            let want = !kd.nearest(&q).is_none_or(|(_, d)| d >= rad);
            assert_eq!(tree.any_closer(&q, rad), want, "q = {q:?}, rad = {rad}");
            hits += usize::from(want);
        }
        assert!(hits > 200 && hits < 3800, "{hits}");
        // `within` lists exactly what the k-d tree lists, in the same order.
        let (mut a, mut b) = (Vec::new(), Vec::new());
        for i in 0..500 {
            let q = Pt3::new(rng.range(-0.2, 1.2), rng.range(-0.2, 0.4), rng.range(-0.2, 1.2));
            let rad = if i % 10 == 0 { kd.nearest(&q).map_or(0.05, |(_, d)| d) } else { rng.range(0.0, 0.08) };
            tree.within(&q, rad, &mut a);
            kd.within(&q, rad, &mut b);
            assert_eq!(a, b, "q = {q:?}, rad = {rad}");
        }
        // `touching` lists exactly the overlapping spheres (plus only near-ties), ascending.
        let radii: Vec<f64> = (0..pts.len()).map(|i| if i % 7 == 0 { 0.08 } else { 0.01 }).collect();
        let st = SphereTree::build(&pts, &radii);
        let mut out = Vec::new();
        let mut listed = 0;
        for _ in 0..500 {
            let q = Pt3::new(rng.range(-0.1, 1.1), rng.range(-0.1, 0.3), rng.range(-0.1, 1.1));
            let rad = rng.range(0.0, 0.02);
            st.touching(&q, rad, &mut out);
            assert!(out.windows(2).all(|w| w[0] < w[1]));
            for (i, p) in pts.iter().enumerate() {
                let d = (p - q).norm();
                let listed_i = out.binary_search(&(i as u32)).is_ok();
                if d < rad + radii[i] {
                    assert!(listed_i, "missing {i}");
                } else if listed_i {
                    assert!(d <= (rad + radii[i]) * (1.0 + 1e-11), "extra {i}");
                }
            }
            listed += out.len();
        }
        assert!(listed > 500, "{listed}");
        assert!(!SphereTree::build(&[], &[]).any_closer(&Pt3::origin(), 1.0));
    }
}

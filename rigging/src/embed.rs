//! Discrete embedding (rigging spec §3.6–3.9): candidates per reduced joint, the nine basis
//! penalties, the best-first branch-and-bound (A*) search over partial embeddings, the k best
//! embeddings (training data), and the reinsertion of degree-2 joints along graph paths.

use std::cmp::Ordering;
use std::collections::{BinaryHeap, HashMap};

use geom_core::math::{Pt3, Vec3};

use crate::error::{Result, RigError};
use crate::graph::EmbedGraph;
use crate::options::RigOptions;
use crate::template::{ReducedSkeleton, SkeletonTemplate};

/// A user hint (paper §3.2: constraints on reduced joints).
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub enum Hint {
    /// The joint must be embedded at one of these graph vertices.
    AtGraphVertices {
        /// Template joint name.
        joint: String,
        /// Allowed graph vertices.
        verts: Vec<u32>,
    },
    /// The joint must be embedded within `radius` of `point` (both in ORIGINAL mesh units).
    Near {
        /// Template joint name.
        joint: String,
        /// Point (original coordinates).
        point: [f64; 3],
        /// Radius (original units).
        radius: f64,
    },
}

/// The result of the discrete search.
#[derive(Clone, Debug, PartialEq)]
pub struct DiscreteEmbedding {
    /// Graph vertex per reduced joint.
    pub verts: Vec<u32>,
    /// Total weighted penalty f = Γ · features.
    pub penalty: f64,
    /// Unweighted basis penalties summed over joints (b1 … b9).
    pub features: [f64; 9],
    /// Whether the search was exact (the queue cap was never hit).
    pub certified_optimal: bool,
    /// Partial embeddings expanded.
    pub expanded: usize,
    /// Largest queue size.
    pub max_queue: usize,
}

/// Candidate graph vertices per reduced joint (spec §3.6), hints applied. `to_norm` maps
/// original coordinates to normalized ones (hint points) and `scale` original lengths.
pub fn candidates(
    g: &EmbedGraph,
    sk: &SkeletonTemplate,
    rs: &ReducedSkeleton,
    hints: &[Hint],
    o: &RigOptions,
    to_norm: &dyn Fn(&Pt3) -> Pt3,
    scale: f64,
) -> Result<Vec<Vec<u32>>> {
    let n = g.len() as u32;
    let ext = extremities(g);
    let mut order: Vec<u32> = (0..n).collect();
    order.sort_by(|&a, &b| g.radius[b as usize].total_cmp(&g.radius[a as usize]).then(a.cmp(&b)));
    let mut cand: Vec<Vec<u32>> = (0..rs.len())
        .map(|i| {
            if rs.fat[i] {
                let mut c: Vec<u32> = order.iter().take(o.fat_candidates).copied().collect();
                c.sort_unstable();
                c
            } else if rs.is_leaf(i) {
                (0..n).filter(|&v| ext[v as usize]).collect()
            } else {
                (0..n).collect()
            }
        })
        .collect();
    for h in hints {
        let name = match h {
            Hint::AtGraphVertices { joint, .. } | Hint::Near { joint, .. } => joint,
        };
        let full =
            sk.find(name).ok_or_else(|| RigError::InvalidParameter(format!("hint names unknown joint '{name}'")))?;
        let r = rs
            .full_index
            .iter()
            .position(|&f| f == full)
            .ok_or_else(|| RigError::InvalidParameter(format!("hint joint '{name}' is not a reduced joint")))?;
        cand[r] = match h {
            Hint::AtGraphVertices { verts, .. } => {
                if let Some(bad) = verts.iter().find(|&&v| v >= n) {
                    return Err(RigError::InvalidParameter(format!("hint vertex {bad} ≥ graph size {n}")));
                }
                verts.clone()
            }
            Hint::Near { point, radius, .. } => {
                let c = to_norm(&Pt3::from(*point));
                let rr = radius * scale;
                (0..n).filter(|&v| (g.verts[v as usize] - c).norm() <= rr).collect()
            }
        };
    }
    Ok(cand)
}

/// Extremity vertices (spec §3.6): v is one if for some neighbour e₁ no neighbour e₂ with
/// r(v) ≤ 2 r(e₂) continues straight on (dot(unit(e₂ − v), unit(v − e₁)) > 0.8).
pub fn extremities(g: &EmbedGraph) -> Vec<bool> {
    (0..g.len())
        .map(|v| {
            let pv = g.verts[v];
            g.adj[v].iter().any(|&e1| {
                let d1 = (pv - g.verts[e1 as usize]).normalize();
                !g.adj[v].iter().any(|&e2| {
                    g.radius[v] <= 2.0 * g.radius[e2 as usize] && (g.verts[e2 as usize] - pv).normalize().dot(&d1) > 0.8
                })
            })
        })
        .collect()
}

fn unit(v: Vec3) -> Option<Vec3> {
    let n = v.norm();
    if n > 1e-12 {
        Some(v / n)
    } else {
        None
    }
}

/// ramp(x; a → A, b → B): linear interpolation, clamped outside [a, b].
fn ramp(x: f64, a: f64, va: f64, b: f64, vb: f64) -> f64 {
    let t = ((x - a) / (b - a)).clamp(0.0, 1.0);
    va + (vb - va) * t
}

/// The search problem: graph, reduced skeleton, candidates and precomputed template data.
pub struct Problem<'a> {
    g: &'a EmbedGraph,
    rs: &'a ReducedSkeleton,
    cand: &'a [Vec<u32>],
    o: &'a RigOptions,
    /// Scaled reduced rest positions.
    given: Vec<Pt3>,
    /// Per reduced joint: scaled given vectors of the chain's bones.
    sub_given: Vec<Vec<Vec3>>,
    miny: f64,
    memo: std::cell::RefCell<HashMap<(usize, u32), f64>>,
}

impl<'a> Problem<'a> {
    /// Prepares the search.
    pub fn new(
        g: &'a EmbedGraph,
        sk: &SkeletonTemplate,
        rs: &'a ReducedSkeleton,
        cand: &'a [Vec<u32>],
        o: &'a RigOptions,
    ) -> Self {
        let s = o.skeleton_scale;
        let rest = sk.rest();
        let given = rs.rest.iter().map(|p| Pt3::from(p.coords * s)).collect();
        let sub_given = rs
            .chain
            .iter()
            .map(|c| {
                c.iter()
                    .map(|&f| (rest[f] - rest[sk.joints[f].parent.expect("chain joint has a parent")]) * s)
                    .collect()
            })
            .collect();
        let miny = g.verts.iter().map(|p| p.y).fold(f64::INFINITY, f64::min);
        Problem { g, rs, cand, o, given, sub_given, miny, memo: Default::default() }
    }

    /// Local basis penalties of joint `i` at `v` with its parent at `vp` (b1, b2 parent part,
    /// b5, b6, b7, b8); `None` if rejected outright.
    fn local(&self, i: usize, v: u32, vp: u32) -> Option<[f64; 9]> {
        let g = self.g;
        let mut b = [0.0; 9];
        let p = self.rs.parent[i].expect("non-root");
        let dg = g.d(v, vp);
        let rho = self.o.play_factor * (g.radius[v as usize] + g.radius[vp as usize]);
        let l = self.rs.chain_len[i] * self.o.skeleton_scale;
        // b1 short bones.
        if !dg.is_finite() || dg + rho < l / 2.0 {
            return None;
        }
        b[0] = ramp(l / (dg + rho), 0.5, 0.0, 2.0, 3.0).powi(3);
        let pv = g.verts[v as usize];
        let pp = g.verts[vp as usize];
        // b2, parent part.
        if v != vp {
            if let (Some(e), Some(gv)) = (unit(pv - pp), unit(self.given[i] - self.given[p])) {
                let c = e.dot(&gv);
                if c < 0.0 {
                    return None;
                }
                b[1] += 0.5 * ((4.0 * (1.0 - c)).powi(2) - 0.1).max(0.0);
            }
        }
        // b5 feet.
        if self.rs.foot[i] {
            b[4] = pv.y - self.miny;
        }
        // b6 zero-length chains.
        if v == vp {
            b[5] = 1.0;
        }
        // b7 bone orientation along the chain.
        if v != vp {
            let subs = &self.sub_given[i];
            let mut add = |e: Vec3, gg: Vec3| {
                if let (Some(e), Some(gu)) = (unit(e), unit(gg)) {
                    let c = e.dot(&gu);
                    let t = (1.0 - c) * ramp(c, -0.5, 6.0, 0.0, 1.0);
                    b[6] += 50.0 * gg.norm_squared() * t * t;
                }
            };
            if subs.len() == 1 {
                add(pv - pp, subs[0]);
            } else {
                let pts = split_path(g, vp, v, &self.rs.chain_frac[i]);
                for (k, gg) in subs.iter().enumerate() {
                    add(pts[k + 1] - pts[k], *gg);
                }
            }
        }
        // b8 leaf not at an extremity.
        if self.rs.is_leaf(i) && v != vp {
            if let Some(dir) = unit(pv - pp) {
                let bad = g.adj[v as usize].iter().any(|&o| {
                    let po = g.verts[o as usize];
                    g.radius[v as usize] <= 2.0 * g.radius[o as usize]
                        && unit(po - pp).is_some_and(|u| u.dot(&dir) > 0.95)
                        && unit(po - pv).is_some_and(|u| u.dot(&dir) > 0.8)
                });
                if bad {
                    b[7] = 1.0;
                }
            }
        }
        self.check(b)
    }

    fn check(&self, b: [f64; 9]) -> Option<[f64; 9]> {
        for k in 0..9 {
            if !(self.o.gamma[k] * b[k] <= self.o.reject_bound) {
                return None;
            }
        }
        Some(b)
    }

    fn weighted(&self, b: &[f64; 9]) -> f64 {
        (0..9).map(|k| self.o.gamma[k] * b[k]).sum()
    }

    /// Minimum weighted local penalty of joint `i` over its candidates with the parent at `vp`
    /// (memoized; `∞` if every candidate is rejected). A lower bound on joint i's increment.
    fn min_local(&self, i: usize, vp: u32) -> f64 {
        if let Some(&m) = self.memo.borrow().get(&(i, vp)) {
            return m;
        }
        let m = self.cand[i]
            .iter()
            .filter_map(|&v| self.local(i, v, vp).map(|b| self.weighted(&b)))
            .fold(f64::INFINITY, f64::min);
        self.memo.borrow_mut().insert((i, vp), m);
        m
    }

    /// Vertices used by the chains of the partial embedding `pv` (joints 0..pv.len()).
    fn used(&self, pv: &[u32]) -> Vec<bool> {
        let mut u = vec![false; self.g.len()];
        u[pv[0] as usize] = true;
        for i in 1..pv.len() {
            let p = self.rs.parent[i].expect("non-root");
            let path = self.g.path(pv[i], pv[p]);
            for &x in &path[..path.len().saturating_sub(1)] {
                u[x as usize] = true;
            }
            u[pv[i] as usize] = true;
        }
        u
    }

    /// All nine basis penalties of adding joint `i = pv.len()` at `v` (local and dependent
    /// terms); `None` if rejected.
    pub fn increment(&self, pv: &[u32], used: &[bool], v: u32) -> Option<[f64; 9]> {
        let i = pv.len();
        let g = self.g;
        let rs = self.rs;
        if i == 0 {
            return Some([0.0; 9]);
        }
        let p = rs.parent[i].expect("non-root");
        let vp = pv[p];
        let mut b = self.local(i, v, vp)?;
        let pvv = g.verts[v as usize];
        // b2 siblings.
        for k in 1..i {
            if rs.parent[k] == Some(p) && pv[k] != v {
                if let (Some(e), Some(gv)) = (unit(pvv - g.verts[pv[k] as usize]), unit(self.given[i] - self.given[k]))
                {
                    let c = e.dot(&gv);
                    if c < -0.5 {
                        return None;
                    }
                    b[1] += 0.5 * ((2.0 * (1.0 - c)).powi(2) - 0.5).max(0.0);
                }
            }
        }
        // b3 symmetric lengths.
        if let Some(s) = rs.symmetric_to[i].filter(|&s| s < i) {
            let ps = rs.parent[s].expect("non-root");
            let a = g.d(v, vp);
            let a2 = g.d(pv[s], pv[ps]);
            let rho = self.o.play_factor * (g.radius[v as usize] + g.radius[vp as usize]);
            let rho2 = self.o.play_factor * (g.radius[pv[s] as usize] + g.radius[pv[ps] as usize]);
            let n = if a > 0.0 && a2 > 0.0 { (a / a2).max(a2 / a).min(2.0) } else { 2.0 };
            let m = (a2 / (a + rho)).max(a / (a2 + rho2));
            b[2] = ((0.2 * n + 0.8 * m).powi(3) - 1.2).max(0.0);
        }
        // b4 chains sharing vertices.
        let path = g.path(v, vp);
        let mut added = false;
        for (j, &u) in path[..path.len().saturating_sub(1)].iter().enumerate() {
            if used[u as usize] {
                if g.radius[u as usize] < 0.02 {
                    return None;
                }
                b[3] += 0.5 / ((j + 1) * (j + 1)) as f64;
                added = true;
            }
        }
        if added {
            b[3] += 0.5;
        }
        // b9 far along chains but close in the graph.
        for k in 0..i {
            if k == p {
                continue;
            }
            let a = rs.lca(i, k);
            let va = if a == i { v } else { pv[a] };
            let t = g.d(v, va) + g.d(va, pv[k]);
            let gg = g.d(v, pv[k]);
            let s = g.radius[v as usize] + g.radius[pv[k] as usize];
            if (t + s) / (gg + s) > 2.0 {
                b[8] += 1.0;
            }
        }
        self.check(b)
    }

    /// Lower bound on the completion cost of partial `pv`: Σ over unembedded joints whose
    /// parent is embedded of their minimum local penalty.
    fn completion_bound(&self, pv: &[u32]) -> f64 {
        (pv.len()..self.rs.len())
            .filter_map(|j| {
                let p = self.rs.parent[j].expect("non-root");
                (p < pv.len()).then(|| self.min_local(j, pv[p]))
            })
            .sum()
    }
}

/// Points along the graph path `vp → v` at the cumulative fractions `frac` of its length
/// (first = vp, last = v).
pub fn split_path(g: &EmbedGraph, vp: u32, v: u32, frac: &[f64]) -> Vec<Pt3> {
    let path = g.path(vp, v);
    let pts: Vec<Pt3> = path.iter().map(|&x| g.verts[x as usize]).collect();
    let mut cum = vec![0.0];
    for w in pts.windows(2) {
        cum.push(cum.last().expect("non-empty") + (w[1] - w[0]).norm());
    }
    let total = *cum.last().expect("non-empty");
    let mut out = vec![g.verts[vp as usize]];
    let mut acc = 0.0;
    for f in frac {
        acc += f;
        let target = acc.min(1.0) * total;
        let k = cum.iter().position(|&c| c >= target).unwrap_or(cum.len() - 1);
        let p = if k == 0 || total == 0.0 {
            pts[k.min(pts.len() - 1)]
        } else {
            let t = (target - cum[k - 1]) / (cum[k] - cum[k - 1]).max(1e-300);
            pts[k - 1] + (pts[k] - pts[k - 1]) * t
        };
        out.push(p);
    }
    if let Some(l) = out.last_mut() {
        *l = g.verts[v as usize];
    }
    out
}

struct Entry {
    lb: f64,
    g: f64,
    feat: [f64; 9],
    verts: Vec<u32>,
}
impl PartialEq for Entry {
    fn eq(&self, o: &Self) -> bool {
        self.cmp(o) == Ordering::Equal
    }
}
impl Eq for Entry {}
impl PartialOrd for Entry {
    fn partial_cmp(&self, o: &Self) -> Option<Ordering> {
        Some(self.cmp(o))
    }
}
impl Ord for Entry {
    // Max-heap on the reverse: smallest bound first, deeper first, then lexicographic.
    fn cmp(&self, o: &Self) -> Ordering {
        o.lb.total_cmp(&self.lb).then(self.verts.len().cmp(&o.verts.len())).then(o.verts.cmp(&self.verts))
    }
}

/// Limits of the discrete search (issue 23: the search must return in bounded time).
///
/// When a limit is hit before `k` complete embeddings were popped, the search completes the
/// most promising partial embeddings depth first (cheapest increment first, with backtracking)
/// and returns the best complete embedding found, flagged `certified_optimal = false`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SearchBudget {
    /// Partial embeddings expanded by the best-first search at most (deterministic).
    pub max_expansions: usize,
    /// Wall-clock limit of the best-first search (s); `None` = none. A time limit makes the
    /// result depend on the machine when it is hit; the expansion limit does not.
    pub max_seconds: Option<f64>,
    /// Node visits of the depth-first completion after a limit was hit.
    pub completion_visits: usize,
}

impl SearchBudget {
    /// The budget of a rig's options (`max_expansions`, `max_search_seconds`).
    pub fn of(o: &RigOptions) -> Self {
        SearchBudget {
            max_expansions: o.max_expansions,
            max_seconds: o.max_search_seconds,
            completion_visits: (o.max_expansions / 4).max(1000),
        }
    }
}

/// The `k` best complete embeddings in non-decreasing penalty order (the first is optimal when
/// `certified_optimal`), within the budget of the options ([`search`]). Best-first branch and
/// bound (spec §3.8).
pub fn k_best_embeddings(pr: &Problem, k: usize) -> Result<Vec<DiscreteEmbedding>> {
    search(pr, k, &SearchBudget::of(pr.o))
}

/// Best-first branch and bound (spec §3.8) for the `k` best embeddings, within `budget`. Every
/// returned embedding records the expansions spent. If the budget stops the search first, the
/// embeddings found so far are returned, or, if none, the best completion of the open partial
/// embeddings (`certified_optimal = false`); `NoEmbedding` when nothing passes the bound.
pub fn search(pr: &Problem, k: usize, budget: &SearchBudget) -> Result<Vec<DiscreteEmbedding>> {
    let t0 = std::time::Instant::now();
    let rs = pr.rs;
    let r = rs.len();
    let mut heap = BinaryHeap::new();
    heap.push(Entry { lb: 0.0, g: 0.0, feat: [0.0; 9], verts: Vec::new() });
    let mut out = Vec::new();
    let mut expanded = 0usize;
    let mut maxq = 1usize;
    let mut certified = true;
    let mut stopped = false;
    let mut deepest: Vec<u32> = Vec::new();
    while let Some(e) = heap.pop() {
        if e.verts.len() == r {
            out.push(DiscreteEmbedding {
                verts: e.verts,
                penalty: e.g,
                features: e.feat,
                certified_optimal: certified,
                expanded,
                max_queue: maxq,
            });
            if out.len() >= k {
                break;
            }
            continue;
        }
        if expanded >= budget.max_expansions || budget.max_seconds.is_some_and(|s| t0.elapsed().as_secs_f64() > s) {
            heap.push(e);
            stopped = true;
            break;
        }
        expanded += 1;
        if e.verts.len() > deepest.len() {
            deepest = e.verts.clone();
        }
        for child in expand(pr, &e) {
            heap.push(child);
        }
        maxq = maxq.max(heap.len());
        if heap.len() > pr.o.max_queue {
            // Bounded memory: keep the best half; optimality is no longer certified.
            certified = false;
            let mut v = heap.into_sorted_vec();
            v.reverse();
            v.truncate(pr.o.max_queue / 2);
            heap = v.into_iter().collect();
        }
    }
    if stopped && out.is_empty() {
        // Complete the most promising open partials depth first; keep the cheapest result.
        let mut visits = 0usize;
        let mut best: Option<Entry> = None;
        while let Some(e) = heap.pop() {
            if visits >= budget.completion_visits {
                break;
            }
            if best.as_ref().is_some_and(|b| b.g <= e.lb) {
                break;
            }
            if let Some(c) = complete(pr, e, &mut visits, budget.completion_visits) {
                if best.as_ref().is_none_or(|b| c.g < b.g) {
                    best = Some(c);
                }
            }
        }
        if let Some(b) = best {
            out.push(DiscreteEmbedding {
                verts: b.verts,
                penalty: b.g,
                features: b.feat,
                certified_optimal: false,
                expanded,
                max_queue: maxq,
            });
        }
    }
    if out.is_empty() {
        return Err(RigError::NoEmbedding {
            best_partial: if deepest.is_empty() { None } else { Some(deepest) },
            expanded,
        });
    }
    Ok(out)
}

/// The children of a partial embedding that pass the rejection rules (spec §3.7–3.8).
fn expand(pr: &Problem, e: &Entry) -> Vec<Entry> {
    let i = e.verts.len();
    let used = if i > 0 { pr.used(&e.verts) } else { vec![false; pr.g.len()] };
    let mut out = Vec::new();
    for &v in &pr.cand[i] {
        let Some(b) = pr.increment(&e.verts, &used, v) else { continue };
        let g = e.g + pr.weighted(&b);
        if g > pr.o.reject_bound {
            continue;
        }
        let mut verts = e.verts.clone();
        verts.push(v);
        let lb = g + pr.completion_bound(&verts);
        if !(lb <= pr.o.reject_bound) {
            continue;
        }
        let mut feat = e.feat;
        for q in 0..9 {
            feat[q] += b[q];
        }
        out.push(Entry { lb, g, feat, verts });
    }
    out
}

/// Depth-first completion of `e`, children in increasing bound order, until a complete
/// embedding is found or `max_visits` nodes were visited in all.
fn complete(pr: &Problem, e: Entry, visits: &mut usize, max_visits: usize) -> Option<Entry> {
    if e.verts.len() == pr.rs.len() {
        return Some(e);
    }
    if *visits >= max_visits {
        return None;
    }
    *visits += 1;
    let mut children = expand(pr, &e);
    children.sort_by(|a, b| a.lb.total_cmp(&b.lb).then(a.verts.cmp(&b.verts)));
    for c in children {
        if let Some(done) = complete(pr, c, visits, max_visits) {
            return Some(done);
        }
        if *visits >= max_visits {
            break;
        }
    }
    None
}

/// The optimal discrete embedding (spec §3.8).
pub fn discrete_embed(pr: &Problem) -> Result<DiscreteEmbedding> {
    let mut v = k_best_embeddings(pr, 1)?;
    Ok(v.remove(0))
}

/// Basis penalties (b1 … b9) of a complete embedding, summed in joint order (for learning).
pub fn basis_penalties(pr: &Problem, verts: &[u32]) -> Option<[f64; 9]> {
    let mut f = [0.0; 9];
    for i in 1..verts.len() {
        let used = pr.used(&verts[..i]);
        let b = pr.increment(&verts[..i], &used, verts[i])?;
        for q in 0..9 {
            f[q] += b[q];
        }
    }
    Some(f)
}

/// Reinserts the degree-2 joints (spec §3.9): every full joint of chain i is placed on the
/// graph path from its reduced parent at the cumulative given-length fraction. Normalized
/// coordinates, full-skeleton order.
pub fn reinsert_joints(g: &EmbedGraph, sk: &SkeletonTemplate, rs: &ReducedSkeleton, verts: &[u32]) -> Vec<Pt3> {
    let mut q = vec![Pt3::origin(); sk.len()];
    q[rs.full_index[0]] = g.verts[verts[0] as usize];
    for i in 1..rs.len() {
        let p = rs.parent[i].expect("non-root");
        let pts = split_path(g, verts[p], verts[i], &rs.chain_frac[i]);
        for (k, &f) in rs.chain[i].iter().enumerate() {
            q[f] = pts[k + 1];
        }
    }
    q
}

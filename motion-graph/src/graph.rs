//! Edges, the threshold τ and the hierarchy of graphs (motion-graph.md §3.3, §3.4).
//!
//! Edge convention: `(s, i) → (t, j)` means "frame `t_j` may be played right after `s_i`"; it
//! exists when `C(s_{i+1}, t_j) < τ`, `i + 1 < len(s)`, `(t, j) ≠ (s, i + 1)` and, within one clip,
//! `|i + 1 − j| ≥ min_self_gap`. `cost = C/τ ∈ [0, 1)`. The natural successor is implicit.

use crate::db::Database;
use crate::error::{Error, Result};
use crate::features::{FeatureTable, JointWeights};
use crate::kmeans::{bisect, kmeans, pca};
use crate::rigid::Rigid2;
use geom_core::graph::UnionFind;
use geom_core::rng::{splitmix64, Rng};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use std::collections::{BTreeMap, HashMap};

/// A database frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
pub struct FrameRef {
    /// Clip index.
    pub clip: u32,
    /// Frame within the clip.
    pub frame: u32,
}

/// Index into [`MotionGraph::edges`].
pub type EdgeId = u32;

/// A leaf (original edge) or an inner node of an edge cluster tree (§2.4).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EdgeNode {
    /// Leave after this frame …
    pub from: FrameRef,
    /// … and continue with this one (the medoid leaf's frames for inner nodes).
    pub to: FrameRef,
    /// `C(from + 1, to)/τ` of the (representative) edge.
    pub cost: f32,
    /// Parent node.
    pub parent: Option<EdgeId>,
    /// Children (none for leaves).
    pub children: [Option<EdgeId>; 2],
    /// Depth in its tree (roots 0).
    pub depth: u8,
}

impl EdgeNode {
    /// Whether this node is an original edge.
    pub fn is_leaf(&self) -> bool {
        self.children[0].is_none()
    }
}

/// Graph construction parameters (§4).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct GraphParams {
    /// Calibrates τ to this mean number of edges per frame (default 10).
    pub target_edges_per_frame: f64,
    /// Explicit τ (overrides the calibration).
    pub tau: Option<f64>,
    /// No edges within a clip closer than this (frames; default 15).
    pub min_self_gap: u32,
    /// Cap on k-means clusters per edge group (default 16).
    pub k_max: usize,
    /// Per-joint cost weights.
    pub joint_weights: JointWeights,
    /// Optional group id per clip; edges only inside a group (test hook, MG-7).
    pub partition: Option<Vec<u32>>,
    /// Memory guard on the estimated edge count (default 5·10⁷).
    pub max_edges: usize,
    /// Random pairs drawn to calibrate τ (default 10⁶).
    pub calibration_pairs: usize,
    /// Build the hierarchy (off: every leaf is a root, the "leaf-only" graph of §9).
    pub hierarchy: bool,
    /// Seed of calibration and clustering.
    pub seed: u64,
}

impl Default for GraphParams {
    fn default() -> Self {
        Self {
            target_edges_per_frame: 10.0,
            tau: None,
            min_self_gap: 15,
            k_max: 16,
            joint_weights: JointWeights::Default,
            partition: None,
            max_edges: 50_000_000,
            calibration_pairs: 1_000_000,
            hierarchy: true,
            seed: 1,
        }
    }
}

/// Graph statistics (§3.4).
#[derive(Clone, Debug, PartialEq, Default, Serialize)]
pub struct GraphStats {
    /// Database frames.
    pub frames: usize,
    /// Leaf (original) edges.
    pub leaf_edges: usize,
    /// Connected edge groups.
    pub groups: usize,
    /// Roots (edges of the coarsest graph G⁰).
    pub top_edges: usize,
    /// Deepest tree level.
    pub max_depth: usize,
    /// Strongly connected components of the clip-level graph.
    pub components: usize,
    /// τ used.
    pub tau: f64,
    /// Groups where k-means left a cluster empty (fewer roots than K).
    pub empty_clusters: usize,
}

/// The hierarchical motion graph (§2.4).
#[derive(Clone, Debug)]
pub struct MotionGraph {
    /// The database.
    pub db: Database,
    /// Per-frame features.
    pub features: FeatureTable,
    /// Arena of leaves and inner nodes.
    pub edges: Vec<EdgeNode>,
    /// Roots = coarsest graph G⁰.
    pub top: Vec<EdgeId>,
    /// τ.
    pub tau: f64,
    /// Top edges leaving each clip, sorted by `from.frame`.
    pub out_top: Vec<Vec<EdgeId>>,
    /// Top edges per ordered clip pair, sorted by `from.frame`.
    pub pair_top: HashMap<(u32, u32), Vec<EdgeId>>,
    /// Leaf edges leaving each clip, sorted by `from.frame`.
    pub out_leaf: Vec<Vec<EdgeId>>,
    /// Statistics.
    pub stats: GraphStats,
    /// Clip-level component of each clip (strongly connected).
    pub component: Vec<u32>,
    /// Minimum self gap used.
    pub min_self_gap: u32,
    /// Torso frame of every database frame (global index, as [`FeatureTable::torso`]) with its
    /// rotation as `(cos, sin)`: the search places pieces without trigonometry.
    pub torso_r: Vec<Rigid2>,
    /// Per edge node `(s, i) → (t, j)`: `T(s, i+1) ∘ T(t, j)⁻¹`, so the piece entered by the cut
    /// is placed at `W_prev ∘ delta` (§3.5).
    pub delta: Vec<Rigid2>,
}

/// Leaf edges `(i, j, cost)` of one ordered clip pair.
type PairLeaves = Vec<(u32, u32, f32)>;

/// f32 dot product with 8 independent accumulators (vectorises).
fn dot32(a: &[f32], b: &[f32]) -> f32 {
    let mut acc = [0.0f32; 8];
    let ca = a.chunks_exact(8);
    let cb = b.chunks_exact(8);
    let (ra, rb) = (ca.remainder(), cb.remainder());
    for (x, y) in ca.zip(cb) {
        for k in 0..8 {
            acc[k] += x[k] * y[k];
        }
    }
    let mut s: f32 = acc.iter().sum();
    for (x, y) in ra.iter().zip(rb) {
        s += x * y;
    }
    s
}

impl MotionGraph {
    /// Builds features, edges and the hierarchy (parallel over frame rows and clip pairs;
    /// deterministic). Errors: [`Error::TooManyEdges`] when the estimated edge count exceeds
    /// `p.max_edges`; [`Error::InvalidParameter`] for a bad τ, target or partition length.
    pub fn build(db: Database, p: &GraphParams) -> Result<MotionGraph> {
        if let Some(part) = &p.partition {
            if part.len() != db.clips.len() {
                return Err(Error::InvalidParameter(format!(
                    "partition has {} entries for {} clips",
                    part.len(),
                    db.clips.len()
                )));
            }
        }
        let feats = FeatureTable::build(&db, &p.joint_weights);
        let nf = feats.frames();
        let clip_of: Vec<u32> =
            (0..db.clips.len()).flat_map(|c| std::iter::repeat_n(c as u32, db.clips[c].len())).collect();
        let frame_of = |g: usize| (g - feats.offsets[clip_of[g] as usize]) as u32;
        let gap = p.min_self_gap as i64;
        let group = |c: u32| p.partition.as_ref().map_or(0, |v| v[c as usize]);
        // Admissible pair (f = s_{i+1} with i+1 ≥ 1, g = t_j).
        let admissible = |f: usize, g: usize| -> bool {
            let (cf, cg) = (clip_of[f], clip_of[g]);
            let ff = frame_of(f);
            if ff == 0 || f == g || group(cf) != group(cg) {
                return false;
            }
            !(cf == cg && ((ff as i64) - (frame_of(g) as i64)).abs() < gap)
        };
        // τ: given or calibrated from random admissible pairs.
        let n_adm_est = (nf as f64) * (nf as f64);
        let tau = match p.tau {
            Some(t) if t > 0.0 && t.is_finite() => t,
            Some(t) => return Err(Error::InvalidParameter(format!("tau = {t} must be positive"))),
            None => {
                if !(p.target_edges_per_frame > 0.0 && p.target_edges_per_frame.is_finite()) {
                    return Err(Error::InvalidParameter(format!(
                        "target_edges_per_frame = {}",
                        p.target_edges_per_frame
                    )));
                }
                let mut rng = Rng::new(p.seed ^ 0x7A0);
                let mut costs = Vec::with_capacity(p.calibration_pairs);
                let mut tries = 0;
                while costs.len() < p.calibration_pairs && tries < 20 * p.calibration_pairs.max(1) && nf > 1 {
                    tries += 1;
                    let (f, g) = (rng.below(nf), rng.below(nf));
                    if admissible(f, g) {
                        costs.push(feats.cost(f, g));
                    }
                }
                let frac = tries.max(1) as f64;
                let adm = n_adm_est * costs.len() as f64 / frac;
                if costs.is_empty() {
                    1.0
                } else {
                    costs.sort_by(f64::total_cmp);
                    let q = (p.target_edges_per_frame * nf as f64 / adm.max(1.0)).clamp(0.0, 1.0);
                    let k = ((q * costs.len() as f64) as usize).min(costs.len() - 1);
                    costs[k].max(1e-300)
                }
            }
        };
        // Memory guard: estimate from a sample of rows.
        {
            let mut rng = Rng::new(p.seed ^ 0x6A4D);
            let rows = 64.min(nf);
            let mut hits = 0usize;
            for _ in 0..rows {
                let f = rng.below(nf.max(1));
                for g in (0..nf).step_by((nf / 512).max(1)) {
                    if admissible(f, g) && feats.cost(f, g) < tau {
                        hits += 1;
                    }
                }
            }
            let per = hits as f64 / rows.max(1) as f64 * (nf as f64 / (nf / 512).max(1) as f64);
            let est = (per * nf as f64) as usize;
            if est > p.max_edges {
                return Err(Error::TooManyEdges { estimated: est, cap: p.max_edges });
            }
        }
        // Pairwise costs: f32 screening with the norm trick, f64 recheck below 1.05 τ.
        let d = feats.dim;
        let phi32: Vec<f32> = feats.phi.iter().map(|&x| x as f32).collect();
        let norms: Vec<f32> = (0..nf).map(|g| dot32(&phi32[g * d..(g + 1) * d], &phi32[g * d..(g + 1) * d])).collect();
        let screen = (1.05 * tau) as f32 + 1e-6 * (norms.iter().copied().fold(0.0f32, f32::max));
        let rows: Vec<Vec<(u32, f32)>> = (0..nf)
            .into_par_iter()
            .map(|f| {
                let mut out = Vec::new();
                if frame_of(f) == 0 {
                    return out;
                }
                let a = &phi32[f * d..(f + 1) * d];
                for g in 0..nf {
                    let approx = norms[f] + norms[g] - 2.0 * dot32(a, &phi32[g * d..(g + 1) * d]);
                    if approx < screen && admissible(f, g) {
                        let c = feats.cost(f, g);
                        if c < tau {
                            out.push((g as u32, (c / tau) as f32));
                        }
                    }
                }
                out
            })
            .collect();
        // Leaves grouped by ordered clip pair.
        let mut by_pair: BTreeMap<(u32, u32), PairLeaves> = BTreeMap::new();
        for (f, row) in rows.iter().enumerate() {
            for &(g, c) in row {
                let (s, i) = (clip_of[f], frame_of(f) - 1);
                let (t, j) = (clip_of[g as usize], frame_of(g as usize));
                by_pair.entry((s, t)).or_default().push((i, j, c));
            }
        }
        let k_max = p.k_max.max(1);
        let pairs: Vec<((u32, u32), PairLeaves)> = by_pair.into_iter().collect();
        let built: Vec<(Vec<EdgeNode>, Vec<u32>, usize, usize)> =
            pairs.par_iter().map(|((s, t), leaves)| cluster_pair(*s, *t, leaves, k_max, p.hierarchy, p.seed)).collect();
        let mut edges: Vec<EdgeNode> = Vec::new();
        let mut top = Vec::new();
        let mut groups = 0;
        let mut empty = 0;
        for (nodes, roots, g, e) in built {
            let base = edges.len() as u32;
            for mut n in nodes {
                n.parent = n.parent.map(|x| x + base);
                n.children = n.children.map(|c| c.map(|x| x + base));
                edges.push(n);
            }
            top.extend(roots.iter().map(|r| r + base));
            groups += g;
            empty += e;
        }
        let nclips = db.clips.len();
        let mut out_top = vec![Vec::new(); nclips];
        let mut pair_top: HashMap<(u32, u32), Vec<EdgeId>> = HashMap::new();
        for &e in &top {
            let n = &edges[e as usize];
            out_top[n.from.clip as usize].push(e);
            pair_top.entry((n.from.clip, n.to.clip)).or_default().push(e);
        }
        let mut out_leaf = vec![Vec::new(); nclips];
        for (e, n) in edges.iter().enumerate() {
            if n.is_leaf() {
                out_leaf[n.from.clip as usize].push(e as u32);
            }
        }
        let key = |e: &EdgeId| (edges[*e as usize].from.frame, *e);
        for v in out_top.iter_mut().chain(out_leaf.iter_mut()) {
            v.sort_by_key(key);
        }
        for v in pair_top.values_mut() {
            v.sort_by_key(key);
        }
        // Clip-level strongly connected components (edges + fragment continuation).
        let mut adj = vec![Vec::new(); nclips];
        for &e in &top {
            let n = &edges[e as usize];
            adj[n.from.clip as usize].push(n.to.clip as usize);
        }
        for (c, nx) in db.next.iter().enumerate() {
            if let Some(n) = nx {
                adj[c].push(*n as usize);
            }
        }
        let component = scc(&adj);
        let n_comp = component.iter().copied().max().map_or(0, |m| m as usize + 1);
        let leaf_edges = edges.iter().filter(|n| n.is_leaf()).count();
        let max_depth = edges.iter().map(|n| n.depth as usize).max().unwrap_or(0);
        let stats = GraphStats {
            frames: nf,
            leaf_edges,
            groups,
            top_edges: top.len(),
            max_depth,
            components: n_comp,
            tau,
            empty_clusters: empty,
        };
        let torso_r: Vec<Rigid2> = feats.torso.iter().map(|&t| Rigid2::from(t)).collect();
        let delta = edges
            .iter()
            .map(|n| {
                let a = torso_r[feats.global(n.from.clip, n.from.frame + 1)];
                let b = torso_r[feats.global(n.to.clip, n.to.frame)];
                a.compose(&b.inverse())
            })
            .collect();
        Ok(MotionGraph {
            db,
            features: feats,
            torso_r,
            delta,
            edges,
            top,
            tau,
            out_top,
            pair_top,
            out_leaf,
            stats,
            component,
            min_self_gap: p.min_self_gap,
        })
    }

    /// Statistics.
    pub fn stats(&self) -> GraphStats {
        self.stats.clone()
    }

    /// Length of clip `c` (frames).
    pub fn clip_len(&self, c: u32) -> u32 {
        self.db.clips[c as usize].len() as u32
    }

    /// Torso frame `T(clip, frame)` as a [`Rigid2`].
    #[inline]
    pub fn torso_r(&self, clip: u32, frame: u32) -> Rigid2 {
        self.torso_r[self.features.global(clip, frame)]
    }
}

/// Strongly connected components (Kosaraju, iterative); labels numbered in discovery order.
fn scc(adj: &[Vec<usize>]) -> Vec<u32> {
    let n = adj.len();
    let mut order = Vec::with_capacity(n);
    let mut seen = vec![false; n];
    for s in 0..n {
        if seen[s] {
            continue;
        }
        let mut stack = vec![(s, 0usize)];
        seen[s] = true;
        while let Some((v, i)) = stack.pop() {
            if i < adj[v].len() {
                stack.push((v, i + 1));
                let w = adj[v][i];
                if !seen[w] {
                    seen[w] = true;
                    stack.push((w, 0));
                }
            } else {
                order.push(v);
            }
        }
    }
    let mut radj = vec![Vec::new(); n];
    for (v, ws) in adj.iter().enumerate() {
        for &w in ws {
            radj[w].push(v);
        }
    }
    let mut comp = vec![u32::MAX; n];
    let mut c = 0;
    for &s in order.iter().rev() {
        if comp[s] != u32::MAX {
            continue;
        }
        let mut stack = vec![s];
        comp[s] = c;
        while let Some(v) = stack.pop() {
            for &w in &radj[v] {
                if comp[w] == u32::MAX {
                    comp[w] = c;
                    stack.push(w);
                }
            }
        }
        c += 1;
    }
    comp
}

/// Groups, k-means clusters and bisecting trees of one ordered clip pair (§3.4). Returns the
/// local node arena (leaves first), local root ids, the number of groups and of groups where
/// k-means emptied a cluster.
fn cluster_pair(
    s: u32,
    t: u32,
    leaves: &[(u32, u32, f32)],
    k_max: usize,
    hierarchy: bool,
    seed: u64,
) -> (Vec<EdgeNode>, Vec<u32>, usize, usize) {
    let m = leaves.len();
    let mut nodes: Vec<EdgeNode> = leaves
        .iter()
        .map(|&(i, j, c)| EdgeNode {
            from: FrameRef { clip: s, frame: i },
            to: FrameRef { clip: t, frame: j },
            cost: c,
            parent: None,
            children: [None, None],
            depth: 0,
        })
        .collect();
    if !hierarchy {
        return (nodes, (0..m as u32).collect(), m, 0);
    }
    // 8-neighbourhood groups.
    let index: HashMap<(u32, u32), usize> = leaves.iter().enumerate().map(|(k, &(i, j, _))| ((i, j), k)).collect();
    let mut uf = UnionFind::new(m);
    for (k, &(i, j, _)) in leaves.iter().enumerate() {
        for (di, dj) in [(1i64, -1i64), (1, 0), (1, 1), (0, 1)] {
            let (ni, nj) = (i as i64 + di, j as i64 + dj);
            if ni < 0 || nj < 0 {
                continue;
            }
            if let Some(&o) = index.get(&(ni as u32, nj as u32)) {
                uf.union(k as u32, o as u32);
            }
        }
    }
    let (ng, labels) = uf.labels();
    let mut members = vec![Vec::new(); ng];
    for (k, &l) in labels.iter().enumerate() {
        members[l as usize].push(k);
    }
    let mut roots = Vec::new();
    let mut empty = 0;
    for (gi, mem) in members.iter().enumerate() {
        let pts: Vec<[f64; 2]> = mem.iter().map(|&k| [leaves[k].0 as f64, leaves[k].1 as f64]).collect();
        let (_, _, (l1, l2)) = pca(&pts);
        let a = 4.0 * l1.sqrt() + 1.0;
        let b = 4.0 * l2.sqrt() + 1.0;
        let k = ((a / b).round() as usize).clamp(1, k_max.min(mem.len()));
        let mut h = seed ^ ((s as u64) << 40) ^ ((t as u64) << 20) ^ gi as u64;
        let mut rng = Rng::new(splitmix64(&mut h));
        let assign = kmeans(&pts, k, &mut rng, 50);
        let mut clusters = vec![Vec::new(); k];
        for (idx, &c) in assign.iter().enumerate() {
            clusters[c].push(mem[idx]);
        }
        if clusters.iter().any(|c| c.is_empty()) {
            empty += 1;
        }
        for cl in clusters.into_iter().filter(|c| !c.is_empty()) {
            let r = build_tree(&mut nodes, leaves, &cl);
            roots.push(r);
        }
    }
    // Depths top-down.
    for &r in &roots {
        let mut stack = vec![(r, 0u8)];
        while let Some((v, dpt)) = stack.pop() {
            nodes[v as usize].depth = dpt;
            for c in nodes[v as usize].children.into_iter().flatten() {
                stack.push((c, dpt.saturating_add(1)));
            }
        }
    }
    (nodes, roots, ng, empty)
}

/// Bisecting 2-means tree over leaf ids `set`; returns the root node id. Inner nodes take the
/// medoid leaf (nearest to the centroid in (i, j)) as representative.
fn build_tree(nodes: &mut Vec<EdgeNode>, leaves: &[(u32, u32, f32)], set: &[usize]) -> u32 {
    if set.len() == 1 {
        return set[0] as u32;
    }
    let pts: Vec<[f64; 2]> = set.iter().map(|&k| [leaves[k].0 as f64, leaves[k].1 as f64]).collect();
    let side = bisect(&pts);
    let left: Vec<usize> = set.iter().zip(&side).filter(|x| !*x.1).map(|x| *x.0).collect();
    let right: Vec<usize> = set.iter().zip(&side).filter(|x| *x.1).map(|x| *x.0).collect();
    let a = build_tree(nodes, leaves, &left);
    let b = build_tree(nodes, leaves, &right);
    let n = pts.len() as f64;
    let c = [pts.iter().map(|p| p[0]).sum::<f64>() / n, pts.iter().map(|p| p[1]).sum::<f64>() / n];
    let med = set
        .iter()
        .min_by(|&&x, &&y| {
            let dx = (leaves[x].0 as f64 - c[0]).powi(2) + (leaves[x].1 as f64 - c[1]).powi(2);
            let dy = (leaves[y].0 as f64 - c[0]).powi(2) + (leaves[y].1 as f64 - c[1]).powi(2);
            dx.total_cmp(&dy).then(x.cmp(&y))
        })
        .copied()
        .unwrap_or(set[0]);
    let rep = nodes[med];
    let id = nodes.len() as u32;
    nodes.push(EdgeNode {
        from: rep.from,
        to: rep.to,
        cost: rep.cost,
        parent: None,
        children: [Some(a), Some(b)],
        depth: 0,
    });
    nodes[a as usize].parent = Some(id);
    nodes[b as usize].parent = Some(id);
    id
}

//! Guided seed paths (ours; motion-graph.md §13 suggests a small best-first search over the graph
//! to seed paths, compared there with the random seeds of §3.7).
//!
//! A beam search over *checkpoints*: the output times of the body, joint and hard constraints,
//! the last frame `F* − 1`, and virtual checkpoints so that no two are more than
//! [`GuidedParams::max_gap`] frames apart. A beam state is a placed partial path (current piece:
//! clip, entry frame and time, placement `W`, §3.5). From each state every extension to the next
//! checkpoint time `t_c` with 0 cuts (stay in the clip), 1 cut (every leaf edge leaving the piece
//! early enough) or 2 cuts (sampled first edges × sampled second edges) is placed exactly and
//! ranked by the score terms of eq. 1 it fixes (`w_p‖x − x*‖² + w_o Δyaw²` for body constraints,
//! `w_j‖p − p*‖²` for joint constraints, `w_c cost(e)` for the cuts). At intermediate checkpoints
//! errors within a slack (0.15 m, 5°) rank alike, so the beam keeps diverse speeds and headings
//! instead of the last centimetre; the exact terms are accumulated separately and rank the last
//! checkpoint. A hard constraint at `t_c` is a filter (§3.7: exact) and its two-cut extensions are
//! exhaustive (every first edge × every top edge into a clip holding a matching frame: the
//! one-hop landing of §3.7). Checkpoints without constraints are ranked additionally by the
//! distance to the point interpolated between the neighbouring body constraints beyond a free
//! radius (half the distance left, so detours stay possible) and, before a hard constraint, by
//! the clip-level hops still needed to reach a clip that meets it. The `width` best extensions
//! with distinct `(clip, frame)` at `t_c`, at most `per_parent` per state, form the next beam.
//! The complete paths are scored with [`crate::path::score`] and enter the population; the
//! randomized search (§3.8) refines them.
//!
//! Two additions keep curved approaches that the interpolated guide point ranks down (session
//! 6; the MG-1 study in the README found every first constraint reachable without a cut while
//! the beam missed it by 0.5 m): half of every beam is chosen by a *projection rank* (the kept
//! terms plus the exact error at the next body constraint if the state stays in its clip until
//! then), and half of the start frames are *aimed*: the frames whose own clip, uncut, comes
//! closest to the first body constraint ([`GuidedParams::aimed_starts`]). [`guided_regrow`]
//! runs the same beam from kept prefixes of population paths (a large-neighbourhood mutation).
//!
//! Cost: `O(#checkpoints · width · (edges per piece + draws²))` placements of two planar
//! transforms each — a few tens of milliseconds for MG-1 (300 frames, 18k database frames).

use crate::eval::place_r;
use crate::graph::{EdgeId, FrameRef, MotionGraph};
use crate::path::{hard_ok, score, Compiled, Hard, Path, Scored};
use crate::rigid::Rigid2;
use geom_core::math::wrap_angle;
use geom_core::rng::Rng;
use serde::{Deserialize, Serialize};
use std::collections::HashSet;

/// Parameters of the guided seeds.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct GuidedParams {
    /// Beam width (complete paths returned at most; 0 disables guided seeds). Default 24.
    pub width: usize,
    /// First edges drawn per state for two-cut extensions. Default 24.
    pub first_draws: usize,
    /// Second edges drawn per first edge (at a hard constraint additionally every top edge into
    /// a matching clip). Default 12.
    pub second_draws: usize,
    /// Largest gap between checkpoints (frames); longer gaps get virtual checkpoints. Default 100.
    pub max_gap: u32,
    /// Weight of the interpolated guide point at checkpoints without a body constraint, relative
    /// to `w_p`. Default 0.25.
    pub guide_weight: f64,
    /// Random start frames tried, as a multiple of `width` (the first checkpoint chooses among
    /// them). Default 8.
    pub start_factor: usize,
    /// Most children one state may leave in the next beam (diversity). Default 4.
    pub per_parent: usize,
    /// Body position error (m) that costs nothing in the ranking at intermediate checkpoints, so
    /// that states within it are chosen at random (diverse speeds and headings) rather than by
    /// the last centimetre. Default 0.15.
    pub slack_m: f64,
    /// Heading error (deg) free in the ranking at intermediate checkpoints. Default 5.
    pub slack_deg: f64,
    /// Free radius around the guide point as a fraction of the distance left to the next body
    /// constraint (detours allowed). Default 0.5.
    pub guide_slack: f64,
    /// Run the beam again (fresh random starts and draws) every this many search iterations and
    /// add its results to the population (0 = only at the start). Default 2.
    pub every: usize,
    /// One-cut extensions per state: every leaf edge leaving the piece in time, or this many
    /// drawn uniformly among them when there are more (0 = always all; at a hard constraint
    /// always all). Default 0.
    pub one_cut_draws: usize,
    /// Regrow (ours): every this many search iterations (0 = never), the best paths of the
    /// population are kept up to a constraint before the worst-met one and the rest is searched
    /// again by the beam ([`guided_regrow`]). Default 2.
    pub regrow_every: usize,
    /// Share of the beam chosen by the *projection* rank (ours): the kept terms plus the error at
    /// the next body constraint if the state stays in its clip until then (no cut; states whose
    /// clip ends earlier have none). The rest is chosen by the rank of the module docs. Keeps
    /// states that "coast" to the next constraint, which the interpolated guide point ranks
    /// down when their path is curved. Default 0.5.
    pub projection_share: f64,
    /// Width of the first beam of a search (0 = `width`): one wide beam at the start finds
    /// much better first paths than the narrow ones run during the search. Default 0.
    pub initial_width: usize,
    /// Aimed starts (ours): this fraction of the start states are the database frames whose own
    /// clip, played on without a cut from the placed start, comes closest to the first body
    /// constraint (every frame is tried; at most 1/16 of them from one clip); the rest are
    /// random. Default 0.5.
    pub aimed_starts: f64,
}

impl Default for GuidedParams {
    fn default() -> Self {
        Self {
            width: 24,
            first_draws: 24,
            second_draws: 12,
            max_gap: 40,
            guide_weight: 0.25,
            start_factor: 8,
            per_parent: 4,
            slack_m: 0.15,
            slack_deg: 5.0,
            guide_slack: 0.5,
            every: 2,
            one_cut_draws: 0,
            regrow_every: 2,
            projection_share: 0.5,
            initial_width: 0,
            aimed_starts: 0.5,
        }
    }
}

/// One checkpoint of the beam.
struct Checkpoint {
    t: u32,
    /// Indices of the body constraints evaluated here.
    body: Vec<usize>,
    /// Indices of the joint constraints evaluated here.
    joints: Vec<usize>,
    hard: Option<Hard>,
    /// Clips holding at least one frame that meets `hard` (empty without a hard constraint).
    hard_clips: Vec<u32>,
    /// Before a hard constraint: per clip, the number of clip-level hops (top edges) to a clip
    /// that meets it; ranked as [`HOP_PENALTY`] per hop so the beam heads for it.
    hops: Option<std::rc::Rc<Vec<u32>>>,
    /// Interpolated target `(x, z)` when no body constraint sits here, and the radius around it
    /// that costs nothing in the ranking (`guide_slack` × distance left to the next target).
    guide: Option<(f64, f64, f64)>,
    /// Time and index of the next body constraint after this checkpoint (projection rank).
    next_body: Option<(u32, usize)>,
    last: bool,
}

/// A placed partial path.
#[derive(Clone)]
struct State {
    start: FrameRef,
    cuts: Vec<EdgeId>,
    clip: u32,
    /// Entry frame of the current piece and its output time.
    a: u32,
    ta: u32,
    /// Placement of the current piece.
    w: Rigid2,
    /// Earliest frame the current piece may be left from.
    min_from: u32,
    /// Accumulated score terms.
    acc: f64,
    /// Accumulated ranking terms (errors beyond the slack).
    racc: f64,
}

/// A ranked extension of a beam state to the next checkpoint.
struct Ext {
    rank: f64,
    /// Projection rank (see [`GuidedParams::projection_share`]).
    rank2: f64,
    acc: f64,
    racc: f64,
    parent: usize,
    fill: [EdgeId; 2],
    n: u8,
    clip: u32,
    a: u32,
    ta: u32,
    w: Rigid2,
    /// Database frame at the checkpoint.
    frame: u32,
}

/// The beam first ranks the best `PREFIX × width` extensions only (selection, then sorting).
const PREFIX: usize = 8;

/// Rank added per clip-level hop still needed to reach a clip meeting the next hard constraint.
const HOP_PENALTY: f64 = 20.0;

/// Clip-level hop counts to `targets` over the top edges (breadth-first on the reversed clip
/// graph; unreachable clips get `u32::MAX`).
fn hops_to(g: &MotionGraph, targets: &[u32]) -> Vec<u32> {
    let n = g.db.clips.len();
    let mut pred: Vec<Vec<u32>> = vec![Vec::new(); n];
    for &(a, b) in g.pair_top.keys() {
        pred[b as usize].push(a);
    }
    for p in &mut pred {
        p.sort_unstable();
    }
    let mut d = vec![u32::MAX; n];
    let mut queue = std::collections::VecDeque::new();
    for &t in targets {
        d[t as usize] = 0;
        queue.push_back(t);
    }
    while let Some(c) = queue.pop_front() {
        for &p in &pred[c as usize] {
            if d[p as usize] == u32::MAX {
                d[p as usize] = d[c as usize] + 1;
                queue.push_back(p);
            }
        }
    }
    d
}

/// The checkpoints of a problem, in time order.
fn checkpoints(g: &MotionGraph, cp: &Compiled, gp: &GuidedParams) -> Vec<Checkpoint> {
    let last = cp.target.saturating_sub(1);
    let clamp = |t: u32| t.min(last);
    let mut times: Vec<u32> = cp
        .pb
        .body
        .iter()
        .map(|b| clamp(b.time))
        .chain(cp.pb.joints.iter().map(|j| clamp(j.time)))
        .chain(cp.hard.iter().map(|h| h.0))
        .chain(std::iter::once(last))
        .filter(|&t| t > 0)
        .collect();
    times.sort_unstable();
    times.dedup();
    let gap = gp.max_gap.max(10);
    let mut all = Vec::new();
    let mut prev = 0u32;
    for &t in &times {
        let parts = (t - prev).div_ceil(gap);
        for k in 1..parts {
            all.push(prev + (t - prev) * k / parts);
        }
        all.push(t);
        prev = t;
    }
    let mut body: Vec<(u32, usize)> = cp.pb.body.iter().enumerate().map(|(i, b)| (clamp(b.time), i)).collect();
    body.sort_unstable();
    all.into_iter()
        .map(|t| {
            let here: Vec<usize> = body.iter().filter(|b| b.0 == t).map(|b| b.1).collect();
            let guide = if here.is_empty() {
                let p = body.iter().rev().find(|b| b.0 < t);
                let n = body.iter().find(|b| b.0 > t);
                match (p, n) {
                    (Some(&(tp, ip)), Some(&(tn, inn))) => {
                        let (bp, bn) = (&cp.pb.body[ip], &cp.pb.body[inn]);
                        let u = (t - tp) as f64 / (tn - tp) as f64;
                        let r = gp.guide_slack * (1.0 - u) * (bn.x - bp.x).hypot(bn.z - bp.z);
                        Some((bp.x + u * (bn.x - bp.x), bp.z + u * (bn.z - bp.z), r))
                    }
                    _ => None,
                }
            } else {
                None
            };
            Checkpoint {
                t,
                body: here,
                joints: cp.pb.joints.iter().enumerate().filter(|j| clamp(j.1.time) == t).map(|j| j.0).collect(),
                hard: cp.hard.iter().find(|h| h.0 == t).map(|h| h.1),
                hard_clips: cp
                    .hard
                    .iter()
                    .find(|h| h.0 == t)
                    .map(|(_, h)| {
                        (0..g.db.clips.len() as u32)
                            .filter(|&c| (0..g.clip_len(c)).any(|f| hard_ok(g, h, FrameRef { clip: c, frame: f })))
                            .collect()
                    })
                    .unwrap_or_default(),
                hops: None,
                guide,
                next_body: body.iter().find(|b| b.0 > t).copied(),
                last: t == last,
            }
        })
        .collect::<Vec<Checkpoint>>()
        .into_iter()
        .rev()
        .scan(None::<std::rc::Rc<Vec<u32>>>, |next_hops, mut c| {
            // Checkpoints without constraints of their own steer toward the next hard one.
            if c.body.is_empty() && c.joints.is_empty() && c.hard.is_none() {
                c.hops = next_hops.clone();
            }
            if c.hard.is_some() {
                *next_hops = Some(std::rc::Rc::new(hops_to(g, &c.hard_clips)));
            } else if !c.body.is_empty() {
                *next_hops = None;
            }
            Some(c)
        })
        .collect::<Vec<Checkpoint>>()
        .into_iter()
        .rev()
        .collect()
}

/// Beam search context.
struct Beam<'a> {
    g: &'a MotionGraph,
    cp: &'a Compiled,
    gp: &'a GuidedParams,
    minp: u32,
}

impl Beam<'_> {
    /// Places frame `a + (c.t − ta)` of a piece entered at frame `a`, time `ta`, placement `w`,
    /// on top of accumulated terms `(acc, racc)` and returns `(acc, racc, rank, frame)`, or `None`
    /// when the frame is outside the clip, misses the hard constraint or (at the last checkpoint)
    /// would make the piece shorter than `min_piece`. `jitter` ∈ [0, 1) breaks ties at random.
    #[allow(clippy::too_many_arguments)]
    fn eval(
        &self,
        c: &Checkpoint,
        (acc, racc): (f64, f64),
        clip: u32,
        a: u32,
        ta: u32,
        w: &Rigid2,
        jitter: f64,
    ) -> Option<(f64, f64, f64, f64, u32)> {
        let f = a + (c.t - ta);
        if f >= self.g.clip_len(clip) || (c.last && f + 1 < a + self.minp) {
            return None;
        }
        let fr = FrameRef { clip, frame: f };
        if let Some(h) = &c.hard {
            if !hard_ok(self.g, h, fr) {
                return None;
            }
        }
        let feat = &self.g.features;
        let wt = w.compose(&self.g.torso_r(clip, f));
        let (mut acc, mut racc) = (acc, racc);
        let (sp, sy) = if c.last { (0.0, 0.0) } else { (self.gp.slack_m, self.gp.slack_deg.to_radians()) };
        for &i in &c.body {
            let b = &self.cp.pb.body[i];
            let e = ((wt.x - b.x).powi(2) + (wt.z - b.z).powi(2)).sqrt();
            let dy = b.yaw.map_or(0.0, |y| wrap_angle(wt.yaw - y).abs());
            acc += self.cp.w_p * e * e + self.cp.w_o * dy * dy;
            racc += self.cp.w_p * (e - sp).max(0.0).powi(2) + self.cp.w_o * (dy - sy).max(0.0).powi(2);
        }
        for &i in &c.joints {
            let j = &self.cp.pb.joints[i];
            let x = wt.apply_point(feat.local(clip, f, j.joint as usize));
            let e = (x - j.pos).norm();
            acc += self.cp.w_j * e * e;
            racc += self.cp.w_j * (e - sp).max(0.0).powi(2);
        }
        let mut guide = c.guide.map_or(0.0, |(x, z, r)| {
            let d = ((wt.x - x).powi(2) + (wt.z - z).powi(2)).sqrt();
            self.gp.guide_weight * self.cp.w_p * (d - r).max(0.0).powi(2)
        });
        // Projection rank: stay in the clip until the next body constraint.
        let mut rank2 = f64::INFINITY;
        if let Some((tn, i)) = c.next_body {
            let fp = f + (tn - c.t);
            if fp < self.g.clip_len(clip) {
                let wp = w.compose(&self.g.torso_r(clip, fp));
                let b = &self.cp.pb.body[i];
                let dy = b.yaw.map_or(0.0, |y| wrap_angle(wp.yaw - y));
                rank2 = racc
                    + self.cp.w_p * ((wp.x - b.x).powi(2) + (wp.z - b.z).powi(2))
                    + self.cp.w_o * dy * dy
                    + 1e-6 * jitter;
            }
        }
        if let Some(h) = &c.hops {
            guide += HOP_PENALTY * h[clip as usize].min(1000) as f64;
        }
        Some((acc, racc, racc + guide + 1e-6 * jitter, rank2, f))
    }

    /// Range `[lo, hi)` of `out_leaf[clip]` leaving at frames `from ≤ i ≤ to`.
    fn leaves(&self, clip: u32, from: u32, to: u32) -> (usize, usize) {
        let outs = &self.g.out_leaf[clip as usize];
        let fr = |e: &EdgeId| self.g.edges[*e as usize].from.frame;
        let lo = outs.partition_point(|e| fr(e) < from);
        (lo, outs.partition_point(|e| fr(e) <= to).max(lo))
    }

    /// The piece entered through edge `e` from a piece `(clip, a, ta, w)`: `(clip, a, ta, w)`.
    fn follow(&self, e: EdgeId, a: u32, ta: u32, w: &Rigid2) -> (u32, u32, u32, Rigid2) {
        let n = &self.g.edges[e as usize];
        let w2 = w.compose(&self.g.delta[e as usize]);
        (n.to.clip, n.to.frame, ta + (n.from.frame - a) + 1, w2)
    }

    /// All ranked extensions of state `si` to checkpoint `c`.
    fn extend(&self, si: usize, s: &State, c: &Checkpoint, rng: &mut Rng, out: &mut Vec<Ext>) {
        let g = self.g;
        let cost = |e: EdgeId| self.cp.pb.weights.cut * g.edges[e as usize].cost as f64;
        let plus = |x: f64| (s.acc + x, s.racc + x);
        // Evaluates the state reached by `n` cuts through `fill` (cut cost `cut`) and keeps it
        // when it can still meet checkpoint `c`.
        let keep =
            |out: &mut Vec<Ext>, cut: f64, fill: [EdgeId; 2], n: u8, to: (u32, u32, u32, Rigid2), jitter: f64| {
                let (clip, a, ta, w) = to;
                if let Some((acc, racc, rank, rank2, frame)) = self.eval(c, plus(cut), clip, a, ta, &w, jitter) {
                    out.push(Ext { rank, rank2, acc, racc, parent: si, fill, n, clip, a, ta, w, frame });
                }
            };
        // 0 cuts: stay in the piece.
        keep(out, 0.0, [0; 2], 0, (s.clip, s.a, s.ta, s.w), rng.f64());
        // Leaving at frame i plays the entered frame at ta + i − a + 1 ≤ t_c.
        let Some(hi) = (s.a + (c.t - s.ta)).checked_sub(1) else { return };
        let (lo1, hi1) = self.leaves(s.clip, s.min_from, hi);
        let outs = &g.out_leaf[s.clip as usize];
        // 1 cut: every leaf edge, or `one_cut_draws` of them drawn uniformly when there are more
        // (dense graphs).
        let one = |e: EdgeId, out: &mut Vec<Ext>, jitter: f64| {
            keep(out, cost(e), [e, 0], 1, self.follow(e, s.a, s.ta, &s.w), jitter);
        };
        let n1 = hi1 - lo1;
        if self.gp.one_cut_draws == 0 || n1 <= self.gp.one_cut_draws || c.hard.is_some() {
            for &e in &outs[lo1..hi1] {
                one(e, out, rng.f64());
            }
        } else {
            for _ in 0..self.gp.one_cut_draws {
                let e = outs[lo1 + rng.below(n1)];
                one(e, out, rng.f64());
            }
        }
        // At a hard constraint: every first edge, then every top edge into a clip that holds a
        // matching frame (one-hop landing of §3.7, exhaustive over the first edge).
        if c.hard.is_some() {
            for &e1 in &outs[lo1..hi1] {
                let (c1, a1, t1, w1) = self.follow(e1, s.a, s.ta, &s.w);
                if t1 >= c.t {
                    continue;
                }
                let hi2 = a1 + (c.t - t1) - 1;
                for &l in &c.hard_clips {
                    let Some(es) = g.pair_top.get(&(c1, l)) else { continue };
                    let fr = |e: &EdgeId| g.edges[*e as usize].from.frame;
                    let lo = es.partition_point(|e| fr(e) < a1 + self.minp - 1);
                    for &e2 in es[lo..].iter().take_while(|e| fr(e) <= hi2) {
                        let to = self.follow(e2, a1, t1, &w1);
                        keep(out, cost(e1) + cost(e2), [e1, e2], 2, to, rng.f64());
                    }
                }
            }
        }
        // 2 cuts: drawn first edges, then drawn (or, at a hard constraint, all) second edges.
        let avail = hi1 - lo1;
        for _ in 0..self.gp.first_draws.min(avail) {
            let e1 = outs[lo1 + rng.below(avail)];
            let (c1, a1, t1, w1) = self.follow(e1, s.a, s.ta, &s.w);
            if t1 >= c.t {
                continue;
            }
            let Some(hi2) = (a1 + (c.t - t1)).checked_sub(1) else { continue };
            let (lo2, hi2) = self.leaves(c1, a1 + self.minp - 1, hi2);
            let outs2 = &g.out_leaf[c1 as usize];
            let n2 = hi2 - lo2;
            if n2 == 0 {
                continue;
            }
            let take = |e2: EdgeId, out: &mut Vec<Ext>, jitter: f64| {
                keep(out, cost(e1) + cost(e2), [e1, e2], 2, self.follow(e2, a1, t1, &w1), jitter);
            };
            if c.hard.is_some() {
                for &e2 in &outs2[lo2..hi2] {
                    take(e2, out, rng.f64());
                }
            } else {
                for _ in 0..self.gp.second_draws.min(n2) {
                    let e2 = outs2[lo2 + rng.below(n2)];
                    take(e2, out, rng.f64());
                }
            }
        }
    }
}

/// Up to `gp.width` guided seed paths for `cp`, best first; `Err(reason)` when no state reaches
/// some checkpoint (e.g. a hard constraint outside every reachable clip).
pub(crate) fn guided_seeds(
    g: &MotionGraph,
    cp: &Compiled,
    gp: &GuidedParams,
    min_piece: u32,
    rng: &mut Rng,
) -> std::result::Result<Vec<Scored>, String> {
    let minp = min_piece.max(1);
    let width = gp.width;
    if width == 0 || g.db.clips.is_empty() {
        return Ok(Vec::new());
    }
    // Start states: the time-0 hard constraint's frames, or random frames.
    let starts: Vec<FrameRef> = match cp.hard.first() {
        Some((0, h)) => {
            let all: Vec<FrameRef> = (0..g.db.clips.len() as u32)
                .flat_map(|c| (0..g.clip_len(c)).map(move |f| FrameRef { clip: c, frame: f }))
                .filter(|f| hard_ok(g, h, *f))
                .collect();
            if all.is_empty() {
                return Err("no frame meets the time-0 hard constraint".into());
            }
            (0..width * gp.start_factor.max(1)).map(|_| all[rng.below(all.len())]).collect()
        }
        _ => {
            let long: Vec<u32> = (0..g.db.clips.len() as u32).filter(|&c| g.clip_len(c) >= minp).collect();
            if long.is_empty() {
                return Err("every clip is shorter than a piece".into());
            }
            let n = width * gp.start_factor.max(1);
            let mut starts = aimed_starts(g, cp, minp, (gp.aimed_starts.clamp(0.0, 1.0) * n as f64) as usize);
            while starts.len() < n {
                let c = long[rng.below(long.len())];
                starts.push(FrameRef { clip: c, frame: rng.below((g.clip_len(c) - minp + 1) as usize) as u32 });
            }
            starts
        }
    };
    let beam: Vec<State> = starts
        .into_iter()
        .map(|s| State {
            start: s,
            cuts: Vec::new(),
            clip: s.clip,
            a: s.frame,
            ta: 0,
            w: cp.start_r.compose(&g.torso_r(s.clip, s.frame).inverse()),
            min_from: s.frame + minp - 1,
            acc: 0.0,
            racc: 0.0,
        })
        .collect();
    let ctx = Beam { g, cp, gp, minp };
    ctx.run(beam, checkpoints(g, cp, gp), width, rng)
}

/// Indices of up to `n` extensions with the smallest `key` (finite only), skipping `(clip, frame)`
/// pairs in `seen` and parents that already have `per_parent` children; updates both. Only a
/// prefix of the order is needed, so the best `PREFIX × n` are selected first and the rest is
/// sorted only if that prefix runs out.
fn take_best(
    exts: &[Ext],
    key: impl Fn(&Ext) -> f64,
    n: usize,
    per_parent: usize,
    seen: &mut HashSet<(u32, u32)>,
    children: &mut [usize],
) -> Vec<usize> {
    let mut out = Vec::with_capacity(n);
    if n == 0 {
        return out;
    }
    let mut order: Vec<(f64, u32)> =
        exts.iter().enumerate().map(|(i, x)| (key(x), i as u32)).filter(|k| k.0.is_finite()).collect();
    let cmp = |a: &(f64, u32), b: &(f64, u32)| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1));
    let pre = (PREFIX * n).min(order.len());
    if pre < order.len() {
        order.select_nth_unstable_by(pre, cmp);
    }
    order[..pre].sort_unstable_by(cmp);
    let mut sorted_rest = pre == order.len();
    for pos in 0..order.len() {
        if out.len() == n {
            break;
        }
        if pos == pre && !sorted_rest {
            order[pre..].sort_unstable_by(cmp);
            sorted_rest = true;
        }
        let i = order[pos].1 as usize;
        let x = &exts[i];
        if children[x.parent] >= per_parent.max(1) || !seen.insert((x.clip, x.frame)) {
            continue;
        }
        children[x.parent] += 1;
        out.push(i);
    }
    out
}

/// Up to `n` start frames whose clip, played on without a cut from the start placement, comes
/// closest to the first body constraint after time 0 (`w_p e² + w_o Δyaw²`), at most
/// `max(1, n/16)` per clip. Every database frame is tried: one placement each.
fn aimed_starts(g: &MotionGraph, cp: &Compiled, minp: u32, n: usize) -> Vec<FrameRef> {
    let last = cp.target.saturating_sub(1);
    let Some(b) = cp.pb.body.iter().filter(|b| b.time > 0).min_by_key(|b| b.time) else { return Vec::new() };
    let t1 = b.time.min(last);
    // The first piece must keep `minp` frames; staying until t1 keeps t1 + 1.
    if n == 0 || t1 == 0 || t1 + 1 < minp {
        return Vec::new();
    }
    let mut all: Vec<(f64, FrameRef)> = Vec::new();
    for c in 0..g.db.clips.len() as u32 {
        let len = g.clip_len(c);
        for f in 0..len.saturating_sub(t1) {
            let w0 = cp.start_r.compose(&g.torso_r(c, f).inverse());
            let wt = w0.compose(&g.torso_r(c, f + t1));
            let e2 = (wt.x - b.x).powi(2) + (wt.z - b.z).powi(2);
            let dy = b.yaw.map_or(0.0, |y| wrap_angle(wt.yaw - y));
            all.push((cp.w_p * e2 + cp.w_o * dy * dy, FrameRef { clip: c, frame: f }));
        }
    }
    all.sort_unstable_by(|a, b| a.0.total_cmp(&b.0).then(a.1.clip.cmp(&b.1.clip)).then(a.1.frame.cmp(&b.1.frame)));
    let cap = (n / 16).max(1);
    let mut per_clip = vec![0usize; g.db.clips.len()];
    let mut out = Vec::with_capacity(n);
    for (_, f) in all {
        if out.len() == n {
            break;
        }
        if per_clip[f.clip as usize] < cap {
            per_clip[f.clip as usize] += 1;
            out.push(f);
        }
    }
    out
}

/// Landing paths (ours): for the first hard constraint at `t_h > 0` that has a body constraint
/// at the same time, every path of one leaf cut `(s, i) → (c, j)` that plays a matching frame
/// `f` at `t_h` (start frame `s = i + 1 − (t_h − (f − j))` of the first clip, both pieces at
/// least `min_piece` long), ranked by the body-constraint terms at `t_h`; the best `n`, each
/// ending at `t_h` (to be continued by [`guided_regrow`] with `t_cut = t_h`). Enumerated per
/// edge into a clip holding a matching frame, over the matching frames: no start-frame loop.
pub(crate) fn landing_paths(g: &MotionGraph, cp: &Compiled, min_piece: u32, n: usize) -> Vec<Path> {
    let minp = min_piece.max(1);
    let Some(&(th, h)) = cp.hard.iter().find(|x| x.0 > 0) else { return Vec::new() };
    let body: Vec<&crate::problem::BodyConstraint> = cp.pb.body.iter().filter(|b| b.time == th).collect();
    if body.is_empty() || n == 0 {
        return Vec::new();
    }
    // Matching frames per clip.
    let matching: Vec<Vec<u32>> = (0..g.db.clips.len() as u32)
        .map(|c| (0..g.clip_len(c)).filter(|&f| hard_ok(g, &h, FrameRef { clip: c, frame: f })).collect())
        .collect();
    let mut all: Vec<(f64, Path)> = Vec::new();
    for (e, nd) in g.edges.iter().enumerate() {
        if !nd.is_leaf() || matching[nd.to.clip as usize].is_empty() {
            continue;
        }
        let (i, j) = (nd.from.frame, nd.to.frame);
        for &f in &matching[nd.to.clip as usize] {
            // The second piece [j, f] plays from t_in = t_h − (f − j); the first [s, i] has
            // t_in frames.
            if f + 1 < j + minp || f - j >= th {
                continue;
            }
            let t_in = th - (f - j);
            if t_in < minp || t_in > i + 1 {
                continue;
            }
            let s0 = i + 1 - t_in;
            let w = cp.start_r.compose(&g.torso_r(nd.from.clip, s0).inverse()).compose(&g.delta[e]);
            let wt = w.compose(&g.torso_r(nd.to.clip, f));
            let mut cost = cp.pb.weights.cut * nd.cost as f64;
            for b in &body {
                let dy = b.yaw.map_or(0.0, |y| wrap_angle(wt.yaw - y));
                cost += cp.w_p * ((wt.x - b.x).powi(2) + (wt.z - b.z).powi(2)) + cp.w_o * dy * dy;
            }
            all.push((
                cost,
                Path { start: FrameRef { clip: nd.from.clip, frame: s0 }, cuts: vec![e as EdgeId], end_frame: f },
            ));
        }
    }
    let cmp = |a: &(f64, Path), b: &(f64, Path)| {
        a.0.total_cmp(&b.0).then(a.1.start.clip.cmp(&b.1.start.clip)).then(a.1.cuts.cmp(&b.1.cuts))
    };
    if all.len() > n {
        all.select_nth_unstable_by(n, cmp);
        all.truncate(n);
    }
    all.sort_unstable_by(cmp);
    all.into_iter().map(|x| x.1).collect()
}

/// Regrown paths (ours, a large-neighbourhood mutation in the spirit of §3.8's *replace*): each
/// of `paths` is kept up to output time `t_cut` (its piece holding `t_cut` may only be left at or
/// after the frame played then) and the rest is searched again by the beam over the checkpoints
/// after `t_cut`, ranked as in [`guided_seeds`] with the kept prefix's terms included. Focusing
/// the whole beam on the part of the problem after a constraint that is already met finds
/// continuations a beam from scratch (which must also get the prefix right) rarely keeps.
/// Up to `width` paths, best first; `Err` when no state reaches some checkpoint.
#[allow(clippy::too_many_arguments)]
pub(crate) fn guided_regrow(
    g: &MotionGraph,
    cp: &Compiled,
    gp: &GuidedParams,
    min_piece: u32,
    width: usize,
    paths: &[&Path],
    t_cut: u32,
    rng: &mut Rng,
) -> std::result::Result<Vec<Scored>, String> {
    let minp = min_piece.max(1);
    if width == 0 || paths.is_empty() {
        return Ok(Vec::new());
    }
    let ctx = Beam { g, cp, gp, minp };
    let (before, after): (Vec<Checkpoint>, Vec<Checkpoint>) =
        checkpoints(g, cp, gp).into_iter().partition(|c| c.t <= t_cut);
    if after.is_empty() {
        return Ok(Vec::new());
    }
    let mut pieces = Vec::new();
    let mut beam = Vec::with_capacity(paths.len());
    for p in paths {
        if !place_r(g, p, &cp.start_r, minp, &mut pieces) {
            continue;
        }
        let Some(k) = pieces.iter().position(|q| q.t0 <= t_cut && t_cut < q.t_end()) else { continue };
        let q = pieces[k];
        // Terms of the kept prefix: its cuts and the checkpoints up to t_cut.
        let mut acc = p.cuts[..k].iter().map(|&e| cp.pb.weights.cut * g.edges[e as usize].cost as f64).sum::<f64>();
        let mut racc = acc;
        let mut ok = true;
        for c in &before {
            let Some(r) = pieces.iter().find(|r| r.t0 <= c.t && c.t < r.t_end()) else {
                ok = false;
                break;
            };
            match ctx.eval(c, (acc, racc), r.clip, r.first, r.t0, &r.w, 0.0) {
                Some((a2, r2, _, _, _)) => (acc, racc) = (a2, r2),
                None => {
                    ok = false;
                    break;
                }
            }
        }
        if !ok {
            continue;
        }
        beam.push(State {
            start: p.start,
            cuts: p.cuts[..k].to_vec(),
            clip: q.clip,
            a: q.first,
            ta: q.t0,
            w: q.w,
            min_from: (q.first + minp - 1).max(q.first + (t_cut - q.t0)),
            acc,
            racc,
        });
    }
    if beam.is_empty() {
        return Ok(Vec::new());
    }
    ctx.run(beam, after, width, rng)
}

impl Beam<'_> {
    /// Runs the beam from `beam` over `checkpoints` and scores the complete paths.
    fn run(
        &self,
        mut beam: Vec<State>,
        checkpoints: Vec<Checkpoint>,
        width: usize,
        rng: &mut Rng,
    ) -> std::result::Result<Vec<Scored>, String> {
        let (g, cp, gp, minp) = (self.g, self.cp, self.gp, self.minp);
        let ctx = self;
        let mut exts = Vec::new();
        for c in checkpoints {
            exts.clear();
            for (si, s) in beam.iter().enumerate() {
                ctx.extend(si, s, &c, rng, &mut exts);
            }
            if exts.is_empty() {
                return Err(format!("guided seeds: no path reaches frame {}", c.t));
            }
            // The beam: `width − quota` extensions by rank, then `quota` by projection rank
            // (distinct `(clip, frame)`, at most `per_parent` per state).
            let quota = ((gp.projection_share.clamp(0.0, 1.0) * width as f64) as usize).min(width);
            let mut seen = HashSet::new();
            let mut children = vec![0usize; beam.len()];
            let mut chosen = take_best(&exts, |x| x.rank, width - quota, gp.per_parent, &mut seen, &mut children);
            let more = take_best(&exts, |x| x.rank2, width - chosen.len(), gp.per_parent, &mut seen, &mut children);
            chosen.extend(more);
            let mut next = Vec::with_capacity(width);
            for i in chosen {
                let x = &exts[i];
                let p = &beam[x.parent];
                let mut cuts = p.cuts.clone();
                cuts.extend_from_slice(&x.fill[..x.n as usize]);
                let min_from = if x.n == 0 { p.min_from.max(x.frame) } else { (x.a + minp - 1).max(x.frame) };
                next.push(State {
                    start: p.start,
                    cuts,
                    clip: x.clip,
                    a: x.a,
                    ta: x.ta,
                    w: x.w,
                    min_from,
                    acc: x.acc,
                    racc: x.racc,
                });
            }
            beam = next;
        }
        let mut out: Vec<Scored> = beam
            .into_iter()
            .filter_map(|s| {
                let end_frame = s.a + (cp.target - 1 - s.ta);
                score(g, cp, &Path { start: s.start, cuts: s.cuts, end_frame }, minp)
            })
            .collect();
        out.sort_by(|a, b| a.score.total_cmp(&b.score));
        Ok(out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::db::{Database, DbParams};
    use crate::eval::PieceR;
    use crate::graph::GraphParams;
    use crate::problem::{random_mg1, Weights};
    use geom_core::anim::synth::{library, Preset};

    fn small_graph() -> MotionGraph {
        let clips = library(Preset::Mixed, 10, (90, 140), 30.0, 3);
        let db = Database::from_motions(clips, &DbParams::default()).unwrap();
        MotionGraph::build(db, &GraphParams { calibration_pairs: 50_000, ..Default::default() }).unwrap()
    }

    /// The `(clip, frame)` played at every output time `0 ..= t` of a placed path.
    fn frames_until(pieces: &[PieceR], t: u32) -> Vec<(u32, u32)> {
        (0..=t)
            .map(|u| {
                let p = pieces.iter().find(|p| p.t0 <= u && u < p.t_end()).unwrap();
                (p.clip, p.first + (u - p.t0))
            })
            .collect()
    }

    /// The aimed starts are the frames with the smallest uncut projection cost at the first
    /// body constraint (checked against a brute-force scan of every frame), in increasing cost,
    /// with at most `max(1, n/16)` per clip.
    #[test]
    fn aimed_starts_are_the_best_uncut_projections() {
        let g = small_graph();
        let pb = random_mg1(1, 200, 30.0, (1, 1), 4.0, (0.3, 0.8), 1.0, 9, Weights::default()).remove(0);
        let cp = Compiled::new(&g, pb).unwrap();
        let b = &cp.pb.body[1];
        let cost = |f: FrameRef| {
            let w0 = cp.start_r.compose(&g.torso_r(f.clip, f.frame).inverse());
            let wt = w0.compose(&g.torso_r(f.clip, f.frame + b.time));
            cp.w_p * ((wt.x - b.x).powi(2) + (wt.z - b.z).powi(2))
        };
        let mut brute = f64::INFINITY;
        for c in 0..g.db.clips.len() as u32 {
            for f in 0..g.clip_len(c).saturating_sub(b.time) {
                brute = brute.min(cost(FrameRef { clip: c, frame: f }));
            }
        }
        let n = 32;
        let starts = aimed_starts(&g, &cp, 6, n);
        // Few clips of this small database outlast the constraint time, so fewer than `n`.
        assert!(!starts.is_empty() && starts.len() <= n);
        // Same arithmetic as `aimed_starts` (no heading at the intermediate constraint): equal.
        assert_eq!(cost(starts[0]), brute);
        for w in starts.windows(2) {
            assert!(cost(w[0]) <= cost(w[1]));
        }
        for c in 0..g.db.clips.len() as u32 {
            assert!(starts.iter().filter(|s| s.clip == c).count() <= 2);
        }
    }

    /// Landing paths have one leaf cut, are valid, end at the hard constraint's time on a
    /// matching frame, and come in increasing order of the body-constraint terms there.
    #[test]
    fn landing_paths_meet_the_hard_constraint_with_one_cut() {
        let g = small_graph();
        let mut pb = random_mg1(1, 200, 30.0, (1, 1), 4.0, (0.3, 0.8), 1.0, 9, Weights::default()).remove(0);
        let label =
            g.db.labels.iter().find(|l| l.as_str() == "walk").cloned().unwrap_or_else(|| g.db.labels[0].clone());
        let th = pb.body[1].time;
        pb.hard.push(crate::problem::HardConstraint::Label { time: th, label });
        let cp = Compiled::new(&g, pb).unwrap();
        let (_, h) = cp.hard[0];
        let paths = landing_paths(&g, &cp, 6, 16);
        assert!(!paths.is_empty());
        let b = &cp.pb.body[1];
        let mut pieces = Vec::new();
        let mut prev = f64::NEG_INFINITY;
        for p in &paths {
            assert_eq!(p.cuts.len(), 1);
            assert!(place_r(&g, p, &cp.start_r, 6, &mut pieces));
            let last = pieces[1];
            assert_eq!(last.t_end(), th + 1);
            assert!(hard_ok(&g, &h, FrameRef { clip: last.clip, frame: p.end_frame }));
            let wt = last.w.compose(&g.torso_r(last.clip, p.end_frame));
            let cost = cp.pb.weights.cut * g.edges[p.cuts[0] as usize].cost as f64
                + cp.w_p * ((wt.x - b.x).powi(2) + (wt.z - b.z).powi(2));
            assert!(cost >= prev - 1e-9, "not sorted: {cost} after {prev}");
            prev = cost;
        }
    }

    /// A regrown path plays exactly the frames of one of the kept paths up to the cut time, is
    /// valid, and its score is the full score of eq. 1.
    #[test]
    fn regrow_keeps_the_prefix_up_to_the_cut() {
        let g = small_graph();
        let pb = random_mg1(1, 200, 30.0, (2, 2), 4.0, (0.3, 0.8), 1.0, 4, Weights::default()).remove(0);
        let cp = Compiled::new(&g, pb).unwrap();
        let gp = GuidedParams { width: 8, ..Default::default() };
        let mut rng = Rng::new(5);
        let seeds = guided_seeds(&g, &cp, &gp, 6, &mut rng).unwrap();
        assert!(!seeds.is_empty());
        let t_cut = cp.pb.body[1].time;
        let kept: Vec<&Path> = seeds.iter().map(|s| &s.path).collect();
        let out = guided_regrow(&g, &cp, &gp, 6, 8, &kept, t_cut, &mut rng).unwrap();
        assert!(!out.is_empty());
        let mut pieces = Vec::new();
        let prefixes: Vec<Vec<(u32, u32)>> = kept
            .iter()
            .map(|p| {
                assert!(place_r(&g, p, &cp.start_r, 6, &mut pieces));
                frames_until(&pieces, t_cut)
            })
            .collect();
        for s in &out {
            assert!(place_r(&g, &s.path, &cp.start_r, 6, &mut pieces));
            let mine = frames_until(&pieces, t_cut);
            assert!(prefixes.contains(&mine), "regrown path changed its prefix");
            let full = score(&g, &cp, &s.path, 6).unwrap();
            assert_eq!(full.score, s.score);
        }
    }
}

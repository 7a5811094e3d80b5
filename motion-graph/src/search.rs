//! Randomized search (motion-graph.md §3.7, §3.8): seed paths on the coarsest graph G⁰ that land
//! exactly on hard constraints, mutations (replace a range of edges by 0, 1 or 2 top edges;
//! demote two adjacent edges to their children; trim the ends), and the population loop that
//! keeps improving children, records local minima and adds fresh seeds every iteration.

use crate::eval::{edge_sum, mutated, place_r, score_view, PieceR};
use crate::graph::{EdgeId, FrameRef, MotionGraph};
use crate::guided::{guided_regrow, guided_seeds, landing_paths, GuidedParams};
use crate::path::{hard_ok, score, score_value, Compiled, Hard, Path, Scored};
use crate::problem::Problem;
use crate::{Error, Result};
use geom_core::rng::Rng;
use serde::{Deserialize, Serialize};
use std::collections::{HashMap, HashSet};
use std::time::{Duration, Instant};

/// Search parameters (§4).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SearchParams {
    /// Initial population (default 20).
    pub seeds: usize,
    /// Fresh seeds per iteration (default 2).
    pub new_seeds_per_iter: usize,
    /// Improving children kept per path (default 2).
    pub keep_best: usize,
    /// Population bound (default 64).
    pub population_cap: usize,
    /// Longest edge range replaced (default 4).
    pub max_span: usize,
    /// Candidates scored per path per iteration (default 4000).
    pub max_mutations: usize,
    /// Shortest piece (frames, default 6).
    pub min_piece_frames: u32,
    /// The seed walk stops this many frames before a hard constraint to land on it (default 90).
    pub landing_window: u32,
    /// Seed-generation retries (default 200).
    pub max_seed_tries: usize,
    /// Distinct local minima kept (default 5).
    pub results: usize,
    /// Enable the trim mutation (default on).
    pub trim: bool,
    /// Repair hard constraints of timing-changing mutations along the diagonal (§12.6; default
    /// on; off = reject them, as the paper does).
    pub repair: bool,
    /// All randomness.
    pub rng_seed: u64,
    /// Guided seeds (beam search toward the constraints, ours; `width: 0` disables them).
    pub guided: GuidedParams,
}

impl Default for SearchParams {
    fn default() -> Self {
        Self {
            seeds: 20,
            new_seeds_per_iter: 2,
            keep_best: 2,
            population_cap: 64,
            max_span: 4,
            max_mutations: 4000,
            min_piece_frames: 6,
            landing_window: 90,
            max_seed_tries: 200,
            results: 5,
            trim: true,
            repair: true,
            rng_seed: 1,
            guided: GuidedParams::default(),
        }
    }
}

/// "Acceptable" thresholds (§12.13).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Tolerance {
    /// Body position (m).
    pub pos_m: f64,
    /// Heading (deg).
    pub yaw_deg: f64,
    /// Length (frames).
    pub frames: u32,
    /// Joint position (m).
    pub joint_m: f64,
}

impl Default for Tolerance {
    fn default() -> Self {
        Self { pos_m: 0.30, yaw_deg: 10.0, frames: 10, joint_m: 0.30 }
    }
}

impl Tolerance {
    /// Whether a scored path meets the tolerance.
    pub fn met(&self, s: &Scored) -> bool {
        s.errors.body_pos.iter().all(|&e| e <= self.pos_m)
            && s.errors.body_yaw_deg.iter().all(|&e| e <= self.yaw_deg)
            && s.errors.joint.iter().all(|&e| e <= self.joint_m)
            && s.errors.length <= self.frames
    }
}

/// What one iteration did.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct StepReport {
    /// Iteration number (1-based).
    pub iteration: usize,
    /// Candidates scored.
    pub candidates: usize,
    /// Population size after the step.
    pub population: usize,
    /// Best score so far.
    pub best: f64,
}

/// The head of a random seed walk (§3.7): current clip `s` entered at frame `a` at output time
/// `ta`, the earliest frame it may be left from, and the cuts so far.
struct Walk {
    s: u32,
    a: u32,
    ta: u32,
    min_from: u32,
    cuts: Vec<EdgeId>,
}

impl Walk {
    /// Takes edge `e` (leaving the current clip): the entered frame plays right after `from`.
    fn follow(&mut self, g: &MotionGraph, e: EdgeId, min_piece: u32) {
        let n = &g.edges[e as usize];
        self.ta += n.from.frame - self.a + 1;
        self.s = n.to.clip;
        self.a = n.to.frame;
        self.min_from = self.a + min_piece - 1;
        self.cuts.push(e);
    }
}

/// An anytime randomized search (§2.4).
pub struct Search<'g> {
    g: &'g MotionGraph,
    cp: Compiled,
    p: SearchParams,
    rng: Rng,
    population: Vec<Scored>,
    results: Vec<Scored>,
    seen_results: HashSet<Vec<EdgeId>>,
    stalls: HashMap<Path, u8>,
    best: Option<Scored>,
    iterations: usize,
    /// Stop an iteration early once the best path meets this tolerance.
    stop_at: Option<Tolerance>,
    /// Seeds that failed (for reports).
    pub seed_failures: usize,
    /// Leaf edges per ordered clip pair keyed by their diagonal `from − to` (sorted), built on
    /// first use by the repair of hard constraints (§12.6).
    diagonals: HashMap<(u32, u32), Vec<(i64, EdgeId)>>,
    /// Candidates whose hard constraints were repaired (§12.6), for reports.
    pub repairs: usize,
}

/// Iterations without an improving candidate after which a path counts as a local minimum.
const STALL_LIMIT: u8 = 3;

/// First edges drawn per replaced range for two-edge (one-hop) fills.
const TWO_HOP_DRAWS: usize = 6;

/// Up to two replacement edges.
#[derive(Clone, Copy)]
struct Fill {
    e: [EdgeId; 2],
    n: u8,
}

impl Fill {
    fn of(es: &[EdgeId]) -> Fill {
        let mut e = [0; 2];
        e[..es.len()].copy_from_slice(es);
        Fill { e, n: es.len() as u8 }
    }
}

/// Reservoir of candidates (algorithm R): a uniform random subset of at most `cap` of all the
/// candidates offered, without materialising them all.
struct Reservoir<'r> {
    cap: usize,
    seen: usize,
    items: Vec<Cand>,
    rng: &'r mut Rng,
}

impl Reservoir<'_> {
    fn offer(&mut self, c: Cand) {
        self.seen += 1;
        if self.items.len() < self.cap {
            self.items.push(c);
        } else {
            let j = self.rng.below(self.seen);
            if j < self.cap {
                self.items[j] = c;
            }
        }
    }
}

/// A candidate mutation: replace `cuts[i..k]` by `with`, optionally set start/end frames.
struct Cand {
    i: usize,
    k: usize,
    with: Fill,
    start: Option<FrameRef>,
    end: Option<u32>,
}

impl<'g> Search<'g> {
    /// Validates the problem and builds the initial population. Errors: those of the problem
    /// (§8) and [`Error::NoSeedPath`] when no seed meets the hard constraints within
    /// `max_seed_tries`.
    pub fn new(g: &'g MotionGraph, pb: Problem, p: SearchParams) -> Result<Search<'g>> {
        let cp = Compiled::new(g, pb)?;
        let mut s = Search {
            g,
            cp,
            rng: Rng::new(p.rng_seed),
            p,
            population: Vec::new(),
            results: Vec::new(),
            seen_results: HashSet::new(),
            stalls: HashMap::new(),
            best: None,
            iterations: 0,
            stop_at: None,
            seed_failures: 0,
            diagonals: HashMap::new(),
            repairs: 0,
        };
        let mut last_reason = String::from("no attempt");
        let guided_reason = s.add_guided(s.p.guided.initial_width).err();
        s.add_landings();
        let mut tries = 0;
        while s.population.len() < s.p.seeds.max(1) && tries < s.p.max_seed_tries.max(1) {
            tries += 1;
            match s.seed() {
                Ok(sc) => s.push(sc),
                Err(r) => {
                    s.seed_failures += 1;
                    last_reason = r;
                }
            }
        }
        if s.population.is_empty() {
            let reason = match guided_reason {
                Some(g) => format!("{last_reason} (random walks); {g}"),
                None => last_reason,
            };
            return Err(Error::NoSeedPath { tries, reason });
        }
        Ok(s)
    }

    /// Adds the guided seeds (§13 beam search toward the constraints) to the population.
    /// `width` overrides the beam width when non-zero.
    fn add_guided(&mut self, width: usize) -> std::result::Result<(), String> {
        let mut rng = self.rng.clone();
        let mut gp = self.p.guided;
        if width > 0 {
            gp.width = width;
        }
        let r = guided_seeds(self.g, &self.cp, &gp, self.p.min_piece_frames, &mut rng);
        self.rng = rng;
        for sc in r? {
            self.push(sc);
        }
        Ok(())
    }

    /// Repair of hard constraints under mutation (§3.8, §12.6): `np` (a mutation of `old_path`,
    /// placed as `old`) misses a hard constraint because the mutation shifted the time of the
    /// pinned piece holding it by `δ` frames. The pinned piece's entry edge `(s, i) → (c, j)` is
    /// replaced by the cheapest leaf edge of the same clip pair on the diagonal
    /// `i' − j' = i − j − δ` (so the pinned frame plays at its time again; the rest of the path
    /// after the pinned piece keeps its timing), leaving the previous piece and entering the
    /// pinned one validly (the diagonal is computed from the mutated path's placement, so it also
    /// holds when the mutation changed the previous piece's entry). Repeated for each missed hard constraint; `None` when a missed one is
    /// in a piece the mutation changed or no edge lies on the diagonal (the candidate is then
    /// rejected, as the paper does).
    fn repair(&mut self, old: &[PieceR], old_path: &Path, mut np: Path) -> Option<Path> {
        let g = self.g;
        let minp = self.p.min_piece_frames.max(1);
        let mut pieces = Vec::new();
        for _ in 0..=self.cp.hard.len() {
            if !place_r(g, &np, &self.cp.start_r, minp, &mut pieces) {
                return None;
            }
            let at = |t: u32| pieces.iter().find(|p| p.t0 <= t && t < p.t_end());
            let miss = self.cp.hard.iter().find(|(t, h)| {
                at(*t).is_none_or(|p| !hard_ok(g, h, FrameRef { clip: p.clip, frame: p.first + (t - p.t0) }))
            });
            let Some(&(th, _)) = miss else { return Some(np) };
            // The pinned piece of the original path and its entry edge.
            let q = old.iter().position(|p| p.t0 <= th && th < p.t_end())?;
            if q == 0 {
                return None;
            }
            let e = old_path.cuts[q - 1];
            let f = old[q].first + (th - old[q].t0);
            // The same edge and piece in the mutated path.
            let m = (0..np.cuts.len()).rev().find(|&m| np.cuts[m] == e && pieces[m + 1].last == old[q].last)?;
            // Leaving the previous piece (entered at frame a at time t_a) at frame i' into frame
            // j' plays frame j' + t_h − (t_a + i' − a + 1) at t_h: it is f when
            // i' − j' = t_h − t_a + a − 1 − f (= i − j − δ when the previous piece only moved by δ).
            let n = &g.edges[e as usize];
            let (s, c) = (n.from.clip, n.to.clip);
            let diag = th as i64 - pieces[m].t0 as i64 + pieces[m].first as i64 - 1 - f as i64;
            if diag == n.from.frame as i64 - n.to.frame as i64 {
                return None;
            }
            let list = self.diagonals.entry((s, c)).or_insert_with(|| {
                let mut v: Vec<(i64, EdgeId)> = g.out_leaf[s as usize]
                    .iter()
                    .filter(|&&x| g.edges[x as usize].to.clip == c)
                    .map(|&x| {
                        let d = &g.edges[x as usize];
                        (d.from.frame as i64 - d.to.frame as i64, x)
                    })
                    .collect();
                v.sort_unstable();
                v
            });
            let lo = list.partition_point(|x| x.0 < diag);
            let prev_first = pieces[m].first;
            let best = list[lo..]
                .iter()
                .take_while(|x| x.0 == diag)
                .map(|x| x.1)
                .filter(|&x| {
                    let d = &g.edges[x as usize];
                    d.from.frame + 1 >= prev_first + minp && d.to.frame <= f && d.to.frame + minp <= old[q].last + 1
                })
                .min_by(|a, b| g.edges[*a as usize].cost.total_cmp(&g.edges[*b as usize].cost))?;
            np.cuts[m] = best;
        }
        None
    }

    /// Seeds that land on the first hard constraint with one leaf cut ranked by the body
    /// constraint at its time ([`landing_paths`]), continued by the beam ([`guided_regrow`]).
    fn add_landings(&mut self) {
        let width = self.p.guided.width;
        let Some(&(th, _)) = self.cp.hard.iter().find(|x| x.0 > 0) else { return };
        let paths = landing_paths(self.g, &self.cp, self.p.min_piece_frames, width);
        if paths.is_empty() {
            return;
        }
        let kept: Vec<&Path> = paths.iter().collect();
        let mut rng = self.rng.clone();
        let r = guided_regrow(self.g, &self.cp, &self.p.guided, self.p.min_piece_frames, width, &kept, th, &mut rng);
        self.rng = rng;
        if let Ok(r) = r {
            for sc in r {
                self.push(sc);
            }
        }
    }

    /// Regrows the best paths of the population after a cut time before the worst-met
    /// constraint of the best path (see [`guided_regrow`]) and adds the results.
    fn add_regrown(&mut self) {
        let Some(best) = &self.best else { return };
        let pb = &self.cp.pb;
        let last = self.cp.target.saturating_sub(1);
        // Worst constraint of the best path, by its error over the tolerance-like unit errors.
        let w = &pb.weights;
        let mut worst: Option<(f64, u32)> = None;
        for (i, b) in pb.body.iter().enumerate() {
            let e = (best.errors.body_pos[i] / w.pos_m).max(best.errors.body_yaw_deg[i] / w.yaw_deg);
            if b.time > 0 && worst.is_none_or(|x| e > x.0) {
                worst = Some((e, b.time.min(last)));
            }
        }
        for (i, j) in pb.joints.iter().enumerate() {
            let e = best.errors.joint[i] / w.joint_m;
            if worst.is_none_or(|x| e > x.0) {
                worst = Some((e, j.time.min(last)));
            }
        }
        let Some((_, t_worst)) = worst else { return };
        let mut cuts: Vec<u32> = std::iter::once(0)
            .chain(pb.body.iter().map(|b| b.time.min(last)))
            .chain(pb.joints.iter().map(|j| j.time.min(last)))
            .chain(self.cp.hard.iter().map(|h| h.0))
            .filter(|&t| t < t_worst)
            .collect();
        cuts.sort_unstable();
        cuts.dedup();
        // The constraint just before the worst one half of the time, else any earlier one.
        let t_cut = if self.rng.f64() < 0.5 { cuts[cuts.len() - 1] } else { cuts[self.rng.below(cuts.len())] };
        let width = self.p.guided.width;
        let mut paths: Vec<&Path> = vec![&best.path];
        paths
            .extend(self.population.iter().map(|s| &s.path).filter(|p| **p != best.path).take(width.saturating_sub(1)));
        let mut rng = self.rng.clone();
        let r =
            guided_regrow(self.g, &self.cp, &self.p.guided, self.p.min_piece_frames, width, &paths, t_cut, &mut rng);
        self.rng = rng;
        if let Ok(r) = r {
            for sc in r {
                self.push(sc);
            }
        }
    }

    fn push(&mut self, sc: Scored) {
        if self.best.as_ref().is_none_or(|b| sc.score < b.score) {
            self.best = Some(sc.clone());
        }
        self.population.push(sc);
    }

    /// Random choice among candidate edges, probability ∝ exp(−cost).
    fn pick(&mut self, cands: &[EdgeId]) -> Option<EdgeId> {
        if cands.is_empty() {
            return None;
        }
        let w: Vec<f64> = cands.iter().map(|&e| (-(self.g.edges[e as usize].cost as f64)).exp()).collect();
        let total: f64 = w.iter().sum();
        let mut u = self.rng.f64() * total;
        for (c, wi) in cands.iter().zip(&w) {
            if u < *wi {
                return Some(*c);
            }
            u -= wi;
        }
        cands.last().copied()
    }

    /// One random seed path (§3.7); `Err(reason)` on failure.
    fn seed(&mut self) -> std::result::Result<Scored, String> {
        let g = self.g;
        let minp = self.p.min_piece_frames.max(1);
        let target = self.cp.target;
        let hard = self.cp.hard.clone();
        // Start.
        let start = match hard.first() {
            Some((0, h)) => {
                let cands: Vec<FrameRef> = match h {
                    Hard::Frame(f) => vec![*f],
                    Hard::Label(_) => (0..g.db.clips.len() as u32)
                        .flat_map(|c| (0..g.clip_len(c)).map(move |f| FrameRef { clip: c, frame: f }))
                        .filter(|f| hard_ok(g, h, *f))
                        .collect(),
                };
                if cands.is_empty() {
                    return Err("no frame meets the time-0 hard constraint".into());
                }
                cands[self.rng.below(cands.len())]
            }
            _ => {
                let c = self.rng.below(g.db.clips.len()) as u32;
                let len = g.clip_len(c);
                if len < minp {
                    return Err("start clip shorter than a piece".into());
                }
                FrameRef { clip: c, frame: self.rng.below((len - minp + 1) as usize) as u32 }
            }
        };
        let mut next_hard = usize::from(matches!(hard.first(), Some((0, _))));
        let mut wk = Walk { s: start.clip, a: start.frame, ta: 0, min_from: start.frame + minp - 1, cuts: Vec::new() };
        for _ in 0..10_000 {
            let len = g.clip_len(wk.s);
            if let Some(&(th, h)) = hard.get(next_hard) {
                // Staying in this clip reaches t_h at frame a + (t_h − t_a).
                let fh = wk.a as u64 + (th - wk.ta) as u64;
                if fh < len as u64 && hard_ok(g, &h, FrameRef { clip: wk.s, frame: fh as u32 }) {
                    next_hard += 1;
                    wk.min_from = wk.min_from.max(fh as u32);
                    continue;
                }
                if th - wk.ta <= self.p.landing_window {
                    // Land exactly: a leaf (s, i) → (c, j) putting a matching frame at t_h.
                    let mut land = Vec::new();
                    for &e in &g.out_leaf[wk.s as usize] {
                        let n = &g.edges[e as usize];
                        let i = n.from.frame;
                        if i < wk.min_from {
                            continue;
                        }
                        let tn = wk.ta + (i - wk.a) + 1;
                        if tn > th {
                            break;
                        }
                        let f = n.to.frame + (th - tn);
                        if f < g.clip_len(n.to.clip) && hard_ok(g, &h, FrameRef { clip: n.to.clip, frame: f }) {
                            land.push(e);
                        }
                    }
                    if let Some(e) = self.pick(&land) {
                        wk.follow(g, e, minp);
                        let f = wk.a + (th - wk.ta);
                        wk.min_from = wk.min_from.max(f);
                        next_hard += 1;
                        continue;
                    }
                }
                // Random step that does not overshoot t_h.
                let limit = wk.a as u64 + (th - wk.ta) as u64;
                let outs: Vec<EdgeId> = g.out_top[wk.s as usize]
                    .iter()
                    .copied()
                    .filter(|&e| {
                        let fr = g.edges[e as usize].from.frame;
                        fr >= wk.min_from && (fr as u64) < limit
                    })
                    .collect();
                let Some(e) = self.pick(&outs) else {
                    return Err(format!("dead end before the hard constraint at frame {th}"));
                };
                wk.follow(g, e, minp);
                continue;
            }
            // No hard constraint pending: end when the length can be met.
            let remaining = target.saturating_sub(wk.ta);
            if wk.a + remaining <= len && remaining >= 1 && wk.a + remaining > wk.min_from {
                let path = Path { start, cuts: wk.cuts, end_frame: wk.a + remaining - 1 };
                return score(g, &self.cp, &path, minp).ok_or_else(|| "seed failed validation".to_string());
            }
            let outs: Vec<EdgeId> = g.out_top[wk.s as usize]
                .iter()
                .copied()
                .filter(|&e| g.edges[e as usize].from.frame >= wk.min_from)
                .collect();
            match self.pick(&outs) {
                Some(e) if wk.ta < target => wk.follow(g, e, minp),
                _ => {
                    // Cannot continue: end as close to the target as the clip allows.
                    if wk.min_from > len - 1 {
                        return Err("clip too short to end".into());
                    }
                    let end = (wk.a + remaining.max(1) - 1).clamp(wk.min_from, len - 1);
                    let path = Path { start, cuts: wk.cuts, end_frame: end };
                    return score(g, &self.cp, &path, minp).ok_or_else(|| "seed failed validation".to_string());
                }
            }
        }
        Err("seed walk too long".into())
    }

    /// Entry clip/frame and exit frame around cut range `[i, k)` of a path.
    fn hole(&self, path: &Path, i: usize, k: usize) -> (u32, u32, u32, u32) {
        let g = self.g;
        let (ca, a0) = if i == 0 {
            (path.start.clip, path.start.frame)
        } else {
            let n = &g.edges[path.cuts[i - 1] as usize];
            (n.to.clip, n.to.frame)
        };
        let (cb, b1) = if k < path.cuts.len() {
            let n = &g.edges[path.cuts[k] as usize];
            (n.from.clip, n.from.frame)
        } else {
            // Last piece's clip.
            let clip = if k == 0 { path.start.clip } else { g.edges[path.cuts[k - 1] as usize].to.clip };
            (clip, path.end_frame)
        };
        (ca, a0, cb, b1)
    }

    /// All mutation candidates of a path (§3.8 a–c); `pieces` is its placement.
    fn mutations(&self, path: &Path, pieces: &[PieceR], rng: &mut Rng) -> Vec<Cand> {
        let g = self.g;
        let minp = self.p.min_piece_frames.max(1);
        let n = path.cuts.len();
        let mut out = Reservoir { cap: self.p.max_mutations.max(1), seen: 0, items: Vec::new(), rng };
        // (a) replace cuts[i..k] (k − i ≤ max_span; k = i is an insertion into a piece).
        // One-edge fills: per range, the top edges A → B leaving late enough (a suffix of
        // `pair_top`, sorted by `from`); when they outnumber the candidate cap they are drawn
        // uniformly over all ranges instead of enumerated (profiling showed the enumeration, not
        // the scoring, dominating an iteration).
        let from_ok =
            |es: &[EdgeId], min_from1: u32| es.partition_point(|&e| g.edges[e as usize].from.frame + 1 < min_from1);
        let mut one: Vec<(usize, usize, &[EdgeId], u32)> = Vec::new();
        let mut total = 0usize;
        for i in 0..=n {
            for k in i..=(i + self.p.max_span).min(n) {
                let (ca, a0, cb, b1) = self.hole(path, i, k);
                // For an insertion the hole is the piece itself: from its entry to its exit.
                if k > i && ca == cb && a0 < b1 && b1 + 1 - a0 >= minp {
                    out.offer(Cand { i, k, with: Fill::of(&[]), start: None, end: None });
                }
                if let Some(es) = g.pair_top.get(&(ca, cb)) {
                    let es = &es[from_ok(es, a0 + minp)..];
                    if !es.is_empty() {
                        total += es.len();
                        one.push((i, k, es, b1));
                    }
                }
                // Two-edge fills A → u → B: `TWO_HOP_DRAWS` first edges among the top edges
                // leaving A late enough, and for each at most `TWO_HOP_DRAWS` second edges.
                let outs = &g.out_top[ca as usize];
                let lo = from_ok(outs, a0 + minp);
                let avail = outs.len() - lo;
                for _ in 0..TWO_HOP_DRAWS.min(avail) {
                    let e1 = outs[lo + out.rng.below(avail)];
                    let n1 = &g.edges[e1 as usize];
                    let Some(es) = g.pair_top.get(&(n1.to.clip, cb)) else { continue };
                    let es = &es[from_ok(es, n1.to.frame + minp)..];
                    let offer2 = |e2: EdgeId, out: &mut Reservoir| {
                        if g.edges[e2 as usize].to.frame + minp <= b1 + 1 {
                            out.offer(Cand { i, k, with: Fill::of(&[e1, e2]), start: None, end: None });
                        }
                    };
                    if es.len() <= TWO_HOP_DRAWS {
                        for &e2 in es {
                            offer2(e2, &mut out);
                        }
                    } else {
                        for _ in 0..TWO_HOP_DRAWS {
                            let e2 = es[out.rng.below(es.len())];
                            offer2(e2, &mut out);
                        }
                    }
                }
            }
        }
        let offer1 = |i: usize, k: usize, e: EdgeId, b1: u32, out: &mut Reservoir| {
            if g.edges[e as usize].to.frame + minp <= b1 + 1 {
                out.offer(Cand { i, k, with: Fill::of(&[e]), start: None, end: None });
            }
        };
        if total <= out.cap {
            for &(i, k, es, b1) in &one {
                for &e in es {
                    offer1(i, k, e, b1, &mut out);
                }
            }
        } else {
            for _ in 0..out.cap {
                let mut r = out.rng.below(total);
                for &(i, k, es, b1) in &one {
                    if r < es.len() {
                        offer1(i, k, es[r], b1, &mut out);
                        break;
                    }
                    r -= es.len();
                }
            }
        }
        // (b) demote adjacent pairs (and single edges).
        let kids = |e: EdgeId| -> Vec<EdgeId> {
            let nd = &g.edges[e as usize];
            if nd.is_leaf() {
                vec![e]
            } else {
                nd.children.iter().flatten().copied().collect()
            }
        };
        for k in 0..n {
            let e = path.cuts[k];
            if !g.edges[e as usize].is_leaf() {
                for c in kids(e) {
                    out.offer(Cand { i: k, k: k + 1, with: Fill::of(&[c]), start: None, end: None });
                }
            }
            if k + 1 < n {
                let e2 = path.cuts[k + 1];
                if !g.edges[e as usize].is_leaf() || !g.edges[e2 as usize].is_leaf() {
                    for c1 in kids(e) {
                        for c2 in kids(e2) {
                            out.offer(Cand { i: k, k: k + 2, with: Fill::of(&[c1, c2]), start: None, end: None });
                        }
                    }
                }
            }
        }
        // (d) tail (ours): leave the last piece by a top edge into any clip and end there at the
        // frame that fits F* (sampled, `TWO_HOP_DRAWS` edges), so short paths can grow.
        {
            if let Some(last) = pieces.last() {
                let outs = &g.out_top[last.clip as usize];
                let lo = outs.partition_point(|&e| g.edges[e as usize].from.frame + 1 < last.first + minp);
                let avail = outs.len() - lo;
                for _ in 0..(2 * TWO_HOP_DRAWS).min(avail) {
                    let e = outs[lo + out.rng.below(avail)];
                    let nd = &g.edges[e as usize];
                    let t_next = last.t0 + (nd.from.frame - last.first + 1);
                    let rem = self.cp.target.saturating_sub(t_next).max(minp);
                    let len = g.clip_len(nd.to.clip);
                    if nd.to.frame + minp > len {
                        continue;
                    }
                    let end = (nd.to.frame + rem - 1).clamp(nd.to.frame + minp - 1, len - 1);
                    out.offer(Cand { i: n, k: n, with: Fill::of(&[e]), start: None, end: Some(end) });
                }
            }
        }
        // (c) trim: end frame (and start frame without a time-0 hard constraint) to fit F*.
        if self.p.trim {
            if let Some(last) = pieces.last() {
                let d = self.cp.target as i64 - last.t_end() as i64;
                if d != 0 {
                    let last_clip = path.cuts.last().map_or(path.start.clip, |&e| g.edges[e as usize].to.clip);
                    let end = (path.end_frame as i64 + d).clamp(0, g.clip_len(last_clip) as i64 - 1) as u32;
                    out.offer(Cand { i: n, k: n, with: Fill::of(&[]), start: None, end: Some(end) });
                    if !matches!(self.cp.hard.first(), Some((0, _))) {
                        let st = (path.start.frame as i64 - d).max(0) as u32;
                        out.offer(Cand {
                            i: 0,
                            k: 0,
                            with: Fill::of(&[]),
                            start: Some(FrameRef { clip: path.start.clip, frame: st }),
                            end: None,
                        });
                    }
                }
            }
        }
        out.items
    }

    fn apply(path: &Path, c: &Cand) -> Path {
        let mut cuts = Vec::with_capacity(path.cuts.len() + 2);
        cuts.extend_from_slice(&path.cuts[..c.i]);
        cuts.extend_from_slice(&c.with.e[..c.with.n as usize]);
        cuts.extend_from_slice(&path.cuts[c.k..]);
        Path { start: c.start.unwrap_or(path.start), cuts, end_frame: c.end.unwrap_or(path.end_frame) }
    }

    /// One iteration of the loop of §3.8.
    pub fn step(&mut self) -> StepReport {
        self.iterations += 1;
        let minp = self.p.min_piece_frames.max(1);
        let pop = std::mem::take(&mut self.population);
        let mut next = Vec::new();
        let mut scored = 0;
        let mut pieces = Vec::new();
        let mut pop = pop.into_iter();
        while let Some(p) = pop.next() {
            if self.stop_at.is_some_and(|t| self.best.as_ref().is_some_and(|b| t.met(b))) {
                // Early termination at tolerance: the rest of the population carries over.
                next.push(p);
                next.extend(pop);
                break;
            }
            if !place_r(self.g, &p.path, &self.cp.start_r, minp, &mut pieces) {
                continue;
            }
            let base_edges = edge_sum(self.g, &p.path.cuts);
            let mut rng = self.rng.clone();
            let cands = self.mutations(&p.path, &pieces, &mut rng);
            self.rng = rng;
            // Screen by score value (incrementally, from the cached placement); keep the
            // `keep_best` best improving candidates.
            let mut top: Vec<(f64, Path)> = Vec::new();
            let keep = self.p.keep_best.max(1);
            for c in &cands {
                scored += 1;
                let mut v = if c.start.is_some() {
                    score_value(self.g, &self.cp, &Self::apply(&p.path, c), minp)
                } else {
                    let mut de = 0.0;
                    let fill = &c.with.e[..c.with.n as usize];
                    mutated(self.g, &pieces, &p.path.cuts, c.i, c.k, fill, c.end, minp, &mut de)
                        .and_then(|v| score_view(self.g, &self.cp, &v, base_edges + de, None))
                        .map(|x| x.0)
                };
                // §12.6: a candidate that misses a hard constraint because it moved a pinned
                // piece in time is repaired along the diagonal (full re-evaluation).
                let mut repaired = None;
                if v.is_none() && self.p.repair && !self.cp.hard.is_empty() {
                    if let Some(rp) = self.repair(&pieces, &p.path, Self::apply(&p.path, c)) {
                        v = score_value(self.g, &self.cp, &rp, minp);
                        if v.is_some() {
                            self.repairs += 1;
                            repaired = Some(rp);
                        }
                    }
                }
                if let Some(v) = v {
                    if v < p.score - 1e-12 && (top.len() < keep || v < top[top.len() - 1].0) {
                        let np = repaired.unwrap_or_else(|| Self::apply(&p.path, c));
                        if !top.iter().any(|t| t.1 == np) {
                            top.push((v, np));
                            top.sort_by(|a, b| a.0.total_cmp(&b.0));
                            top.truncate(keep);
                        }
                    }
                }
            }
            let mut improving: Vec<Scored> =
                top.iter().filter_map(|(_, np)| score(self.g, &self.cp, np, minp)).collect();
            if improving.is_empty() {
                // The candidate set is a random subset: a path is a local minimum only after
                // `STALL_LIMIT` consecutive iterations without an improving candidate.
                let stalls = self.stalls.entry(p.path.clone()).or_insert(0);
                *stalls += 1;
                if *stalls < STALL_LIMIT {
                    next.push(p);
                    continue;
                }
                self.stalls.remove(&p.path);
                if self.seen_results.insert(p.path.cuts.clone()) {
                    self.results.push(p);
                    self.results.sort_by(|a, b| a.score.total_cmp(&b.score));
                    self.results.truncate(self.p.results.max(1));
                }
            } else {
                improving.sort_by(|a, b| a.score.total_cmp(&b.score));
                improving.dedup_by(|a, b| a.path == b.path);
                improving.truncate(self.p.keep_best.max(1));
                for s in improving {
                    if self.best.as_ref().is_none_or(|b| s.score < b.score) {
                        self.best = Some(s.clone());
                    }
                    next.push(s);
                }
            }
        }
        self.population = next;
        if self.p.guided.every > 0 && self.iterations.is_multiple_of(self.p.guided.every) {
            let _ = self.add_guided(0);
        }
        if self.p.guided.regrow_every > 0 && self.iterations.is_multiple_of(self.p.guided.regrow_every) {
            self.add_regrown();
        }
        for _ in 0..self.p.new_seeds_per_iter {
            match self.seed() {
                Ok(s) => self.push(s),
                Err(_) => self.seed_failures += 1,
            }
        }
        self.population.sort_by(|a, b| a.score.total_cmp(&b.score));
        self.population.dedup_by(|a, b| a.path == b.path);
        self.population.truncate(self.p.population_cap.max(1));
        let alive: HashSet<&Path> = self.population.iter().map(|s| &s.path).collect();
        self.stalls.retain(|k, _| alive.contains(k));
        StepReport {
            iteration: self.iterations,
            candidates: scored,
            population: self.population.len(),
            best: self.best.as_ref().map_or(f64::INFINITY, |b| b.score),
        }
    }

    /// Iterates until `budget` has elapsed (at least one iteration unless the budget is zero).
    pub fn run_for(&mut self, budget: Duration) -> &[Scored] {
        let t0 = Instant::now();
        while t0.elapsed() < budget && !self.population.is_empty() {
            self.step();
        }
        &self.results
    }

    /// Iterates until the best path meets `tol` or `max` has elapsed or `max_iters` iterations ran.
    pub fn run_until(&mut self, tol: &Tolerance, max: Duration, max_iters: usize) -> &[Scored] {
        let t0 = Instant::now();
        self.stop_at = Some(*tol);
        let mut it = 0;
        while t0.elapsed() < max && it < max_iters {
            if self.best.as_ref().is_some_and(|b| tol.met(b)) {
                break;
            }
            if self.population.is_empty() {
                // Everything converged: restart from fresh seeds (anytime search).
                let _ = self.add_guided(0);
                for _ in 0..self.p.seeds.max(1) {
                    if let Ok(s) = self.seed() {
                        self.push(s);
                    }
                }
                if self.population.is_empty() {
                    break;
                }
            }
            self.step();
            it += 1;
        }
        &self.results
    }

    /// Early termination: once the best path meets `tol`, [`Search::step`] stops mutating the
    /// rest of the population (it carries over unchanged). `None` (default) always completes
    /// the iteration. [`Search::run_until`] sets it to its tolerance.
    pub fn stop_when(&mut self, tol: Option<Tolerance>) {
        self.stop_at = tol;
    }

    /// The best path found so far (always assemblable).
    pub fn best(&self) -> Option<&Scored> {
        self.best.as_ref()
    }

    /// Distinct local minima, best first.
    pub fn results(&self) -> &[Scored] {
        &self.results
    }

    /// The current population.
    pub fn population(&self) -> &[Scored] {
        &self.population
    }

    /// Iterations run.
    pub fn iterations(&self) -> usize {
        self.iterations
    }

    /// Interactive edit: replaces the problem and rescores the population (paths that no longer
    /// meet the hard constraints are dropped; new seeds refill it).
    pub fn set_problem(&mut self, pb: Problem) -> Result<()> {
        self.cp = Compiled::new(self.g, pb)?;
        let minp = self.p.min_piece_frames.max(1);
        let pop = std::mem::take(&mut self.population);
        self.best = None;
        self.results.clear();
        self.seen_results.clear();
        for p in pop {
            if let Some(s) = score(self.g, &self.cp, &p.path, minp) {
                self.push(s);
            }
        }
        let _ = self.add_guided(0);
        while self.population.len() < self.p.seeds {
            match self.seed() {
                Ok(s) => self.push(s),
                Err(_) => break,
            }
        }
        Ok(())
    }

    /// The compiled problem's start placement and min piece (for assembly).
    pub fn min_piece(&self) -> u32 {
        self.p.min_piece_frames.max(1)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::db::{Database, DbParams};
    use crate::graph::GraphParams;
    use crate::problem::{random_mg1, HardConstraint, JointConstraint, Weights};
    use geom_core::anim::synth::{library, Preset};
    use geom_core::math::Vec3;

    /// §12.6 repair: candidates that miss a hard `Frame` constraint only because they moved the
    /// pinned piece in time are repaired; every repaired path is valid, plays the required frame
    /// at its time, and differs from the unrepaired candidate in entry edges of pinned pieces
    /// only (same number of cuts). Some repairs must happen on this problem (non-vacuous).
    #[test]
    fn repair_restores_hard_constraints_along_the_diagonal() {
        let clips = library(Preset::Mixed, 10, (90, 140), 30.0, 3);
        let db = Database::from_motions(clips, &DbParams::default()).unwrap();
        let g = MotionGraph::build(db, &GraphParams { calibration_pairs: 50_000, ..Default::default() }).unwrap();
        let mut pb = random_mg1(1, 200, 30.0, (1, 1), 4.0, (0.3, 0.8), 1.0, 5, Weights::default()).remove(0);
        pb.hard.push(HardConstraint::Frame { time: 120, frame: FrameRef { clip: 3, frame: 60 } });
        let sp = SearchParams { seeds: 6, population_cap: 8, max_mutations: 400, rng_seed: 3, ..Default::default() };
        let mut s = Search::new(&g, pb, sp).unwrap();
        let minp = s.min_piece();
        let want = FrameRef { clip: 3, frame: 60 };
        let mut repaired = 0;
        for _ in 0..3 {
            let mut pieces = Vec::new();
            for p in s.population().to_vec() {
                assert!(place_r(&g, &p.path, &s.cp.start_r, minp, &mut pieces));
                let mut rng = Rng::new(11);
                for c in s.mutations(&p.path, &pieces, &mut rng) {
                    let np = Search::apply(&p.path, &c);
                    if score_value(&g, &s.cp, &np, minp).is_some() {
                        continue;
                    }
                    let Some(rp) = s.repair(&pieces, &p.path, np.clone()) else { continue };
                    repaired += 1;
                    assert!(score_value(&g, &s.cp, &rp, minp).is_some(), "repaired path invalid");
                    let mut rpieces = Vec::new();
                    assert!(place_r(&g, &rp, &s.cp.start_r, minp, &mut rpieces));
                    let q = rpieces.iter().find(|q| q.t0 <= 120 && 120 < q.t_end()).unwrap();
                    assert_eq!(FrameRef { clip: q.clip, frame: q.first + (120 - q.t0) }, want);
                    assert_eq!(rp.cuts.len(), np.cuts.len());
                    assert_eq!((rp.start, rp.end_frame), (np.start, np.end_frame));
                }
            }
            s.step();
        }
        assert!(repaired > 0, "no candidate was repaired");
    }

    /// The incremental candidate score (cached placement + view of the mutated path) equals the
    /// full re-evaluation of the mutated path for every candidate of every path of a population
    /// over a few iterations, including validity (both `None` or both `Some`). Tolerance 1e-12
    /// relative: the two differ only by the rounding of composing the suffix's rigid motion with
    /// the stored placements (≈ 1e-15 of the positions).
    #[test]
    fn incremental_score_equals_full_reevaluation() {
        let clips = library(Preset::Mixed, 10, (90, 140), 30.0, 3);
        let db = Database::from_motions(clips, &DbParams::default()).unwrap();
        let g = MotionGraph::build(db, &GraphParams { calibration_pairs: 50_000, ..Default::default() }).unwrap();
        let mut pbs = random_mg1(2, 200, 30.0, (1, 3), 4.0, (0.3, 0.8), 1.0, 5, Weights::default());
        // One problem with a joint constraint and a hard label (exercises those terms and the
        // hard check in the shifted suffix).
        let hand = g.db.skeleton.role(geom_core::anim::JointRole::RightHand).unwrap() as u16;
        pbs[1].joints.push(JointConstraint { time: 120, joint: hand, pos: Vec3::new(0.5, 1.2, 3.0) });
        if g.db.label_bit("walk").is_some() {
            pbs[1].hard.push(HardConstraint::Label { time: 60, label: "walk".into() });
        }
        let mut checked = 0;
        let mut valid = 0;
        for (k, pb) in pbs.into_iter().enumerate() {
            let sp = SearchParams {
                seeds: 6,
                population_cap: 8,
                max_mutations: 200,
                rng_seed: 7 + k as u64,
                ..Default::default()
            };
            let Ok(mut s) = Search::new(&g, pb, sp) else { continue };
            for _ in 0..3 {
                let minp = s.min_piece();
                let mut pieces = Vec::new();
                for p in s.population().to_vec() {
                    assert!(place_r(&g, &p.path, &s.cp.start_r, minp, &mut pieces));
                    let base = edge_sum(&g, &p.path.cuts);
                    let mut rng = Rng::new(99);
                    for c in s.mutations(&p.path, &pieces, &mut rng) {
                        if c.start.is_some() {
                            continue;
                        }
                        let full = score_value(&g, &s.cp, &Search::apply(&p.path, &c), minp);
                        let mut de = 0.0;
                        let inc = mutated(
                            &g,
                            &pieces,
                            &p.path.cuts,
                            c.i,
                            c.k,
                            &c.with.e[..c.with.n as usize],
                            c.end,
                            minp,
                            &mut de,
                        )
                        .and_then(|v| score_view(&g, &s.cp, &v, base + de, None))
                        .map(|x| x.0);
                        checked += 1;
                        match (full, inc) {
                            (None, None) => {}
                            (Some(a), Some(b)) => {
                                valid += 1;
                                assert!((a - b).abs() <= 1e-12 * a.abs().max(1.0), "full {a} vs incremental {b}");
                            }
                            _ => panic!("validity differs: full {full:?} vs incremental {inc:?}"),
                        }
                    }
                }
                s.step();
            }
        }
        assert!(checked > 500 && valid > 100, "checked {checked}, valid {valid}");
    }
}

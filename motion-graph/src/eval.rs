//! Fast and incremental path scoring for the search (motion-graph.md §3.6: "cache per path the
//! cumulative transforms and lengths so a mutation re-evaluates from the first changed piece
//! only").
//!
//! A path is placed once into [`PieceR`]s (placements as [`Rigid2`], per-edge transforms
//! `T(s, i+1) ∘ T(t, j)⁻¹` precomputed in [`MotionGraph::delta`], so no trigonometry). A mutation
//! that replaces cuts `e_i … e_{k−1}` by a fill of 0–2 edges leaves pieces `0 … i−1` unchanged,
//! changes the last frame of piece `i`, adds the fill's pieces, changes the first frame of piece
//! `k`, and moves every later piece by one rigid motion `R = W'_k ∘ W_k⁻¹` and one time shift
//! `δ`. A [`View`] describes the mutated path by those three parts without building it; the
//! constraint terms are then answered by locating each constraint time in the view (binary
//! search), so a candidate costs `O(#constraints · log #pieces)` instead of a re-placement.
//! [`score_view`] is also the full scorer (a view with only a prefix), so both agree up to the
//! rounding of composing `R` with the stored placements.

use crate::graph::{EdgeId, FrameRef, MotionGraph};
use crate::path::{hard_ok, Compiled, Errors, Path, ScoreParts};
use crate::rigid::Rigid2;
use geom_core::math::{wrap_angle, Vec3};

/// A placed piece: clip frames `[first, last]` played from output time `t0`, placed by `w`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct PieceR {
    pub clip: u32,
    pub first: u32,
    pub last: u32,
    pub t0: u32,
    pub w: Rigid2,
}

impl PieceR {
    /// Output time just after the piece.
    #[inline]
    pub fn t_end(&self) -> u32 {
        self.t0 + self.last + 1 - self.first
    }
}

/// Places `path` from `start` into `out` (cleared first). `false` if the path is invalid (§3.5
/// rules with `min_piece` frames per piece), as [`crate::path::place`].
pub(crate) fn place_r(g: &MotionGraph, path: &Path, start: &Rigid2, min_piece: u32, out: &mut Vec<PieceR>) -> bool {
    out.clear();
    let (mut clip, mut first) = (path.start.clip, path.start.frame);
    if clip as usize >= g.db.clips.len() || first >= g.clip_len(clip) {
        return false;
    }
    let mut w = start.compose(&g.torso_r(clip, first).inverse());
    let mut t0 = 0u32;
    for &e in &path.cuts {
        let Some(n) = g.edges.get(e as usize) else { return false };
        if n.from.clip != clip || n.from.frame < first || n.from.frame + 1 - first < min_piece {
            return false;
        }
        out.push(PieceR { clip, first, last: n.from.frame, t0, w });
        t0 += n.from.frame - first + 1;
        w = w.compose(&g.delta[e as usize]);
        clip = n.to.clip;
        first = n.to.frame;
    }
    let len = g.clip_len(clip);
    if path.end_frame >= len || path.end_frame < first || path.end_frame + 1 - first < min_piece {
        return false;
    }
    out.push(PieceR { clip, first, last: path.end_frame, t0, w });
    true
}

/// A (possibly mutated) path seen as `prefix ++ mid ++ suffix moved by (shift, r)`.
pub(crate) struct View<'a> {
    /// Unchanged leading pieces.
    pub prefix: &'a [PieceR],
    /// New or changed pieces (at most the changed piece `i`, two fill pieces and piece `k`).
    pub mid: [PieceR; 4],
    /// Number of valid entries of `mid`.
    pub n_mid: usize,
    /// Trailing pieces of the original path, to be shifted by `shift` frames and moved by `r`.
    pub suffix: &'a [PieceR],
    /// Time shift of the suffix.
    pub shift: i64,
    /// Rigid motion of the suffix.
    pub r: Rigid2,
    /// Output length (frames).
    pub frames: u32,
}

impl View<'_> {
    /// A view of a whole placed path.
    pub fn whole(pieces: &[PieceR]) -> View<'_> {
        let frames = pieces.last().map_or(0, PieceR::t_end);
        View {
            prefix: pieces,
            mid: [PieceR { clip: 0, first: 0, last: 0, t0: 0, w: Rigid2::default() }; 4],
            n_mid: 0,
            suffix: &[],
            shift: 0,
            r: Rigid2::default(),
            frames,
        }
    }

    /// Clip, database frame and placement at output time `t` (clamped to the last frame).
    #[inline]
    pub fn locate(&self, t: u32) -> (u32, u32, Rigid2) {
        let t = t.min(self.frames.saturating_sub(1));
        let mid_t0 = if self.n_mid > 0 { self.mid[0].t0 } else { self.prefix.last().map_or(0, PieceR::t_end) };
        if t < mid_t0 || (self.n_mid == 0 && self.suffix.is_empty()) {
            let k = self.prefix.partition_point(|p| p.t0 <= t).saturating_sub(1);
            let p = &self.prefix[k];
            return (p.clip, p.first + (t - p.t0), p.w);
        }
        for p in &self.mid[..self.n_mid] {
            if t < p.t_end() {
                return (p.clip, p.first + (t - p.t0), p.w);
            }
        }
        // Suffix: time in the original path.
        let to = (t as i64 - self.shift) as u32;
        let k = self.suffix.partition_point(|p| p.t0 <= to).saturating_sub(1);
        let p = &self.suffix[k];
        (p.clip, p.first + (to - p.t0), self.r.compose(&p.w))
    }
}

/// Builds the view of `pieces` (a placed path with cuts `cuts`) after replacing `cuts[i..k]` by
/// `fill` and, when `end` is given, ending the last piece at frame `end` (with `k = n` and a
/// non-empty fill the last piece may then be in any clip: the *tail* mutation). `None` when the
/// result is invalid (§3.5 rules, `min_piece`). `edge_delta` receives `Σ cost(fill) − Σ
/// cost(cuts[i..k])`.
#[allow(clippy::too_many_arguments)]
pub(crate) fn mutated<'a>(
    g: &MotionGraph,
    pieces: &'a [PieceR],
    cuts: &[EdgeId],
    i: usize,
    k: usize,
    fill: &[EdgeId],
    end: Option<u32>,
    min_piece: u32,
    edge_delta: &mut f64,
) -> Option<View<'a>> {
    let n = cuts.len();
    if i > k || k > n || pieces.len() != n + 1 {
        return None;
    }
    let pi = pieces[i];
    let pk = pieces[k];
    let last_k = if k == n { end.unwrap_or(pk.last) } else { pk.last };
    let mut d = 0.0;
    for &e in &cuts[i..k] {
        d -= g.edges[e as usize].cost as f64;
    }
    let mut mid = [pi; 4];
    let mut n_mid = 0;
    let mut cur = PieceR { clip: pi.clip, first: pi.first, last: 0, t0: pi.t0, w: pi.w };
    for &e in fill {
        let nd = g.edges.get(e as usize)?;
        d += nd.cost as f64;
        if nd.from.clip != cur.clip || nd.from.frame < cur.first || nd.from.frame + 1 - cur.first < min_piece {
            return None;
        }
        cur.last = nd.from.frame;
        mid[n_mid] = cur;
        n_mid += 1;
        cur = PieceR {
            clip: nd.to.clip,
            first: nd.to.frame,
            last: 0,
            t0: cur.t_end(),
            w: cur.w.compose(&g.delta[e as usize]),
        };
    }
    // The piece that continues into the unchanged suffix (or ends the path).
    let tail_free = k == n && end.is_some();
    if !tail_free && cur.clip != pk.clip {
        return None;
    }
    if last_k < cur.first || last_k + 1 - cur.first < min_piece || last_k >= g.clip_len(cur.clip) {
        return None;
    }
    cur.last = last_k;
    mid[n_mid] = cur;
    n_mid += 1;
    *edge_delta = d;
    let suffix = &pieces[k + 1..];
    let shift = cur.t_end() as i64 - pk.t_end() as i64;
    let r = cur.w.compose(&pk.w.inverse());
    let frames = if suffix.is_empty() { cur.t_end() } else { (pieces[n].t_end() as i64 + shift) as u32 };
    Some(View { prefix: &pieces[..i], mid, n_mid, suffix, shift, r, frames })
}

/// Score of eq. 1 for a view (`edge_sum` = `Σ cost(e)` of its cuts), its parts and length;
/// `None` when a hard constraint is missed. Constraint errors go to `errs` when given.
pub(crate) fn score_view(
    g: &MotionGraph,
    cp: &Compiled,
    v: &View,
    edge_sum: f64,
    mut errs: Option<&mut Errors>,
) -> Option<(f64, ScoreParts, u32)> {
    let frames = v.frames;
    for (t, h) in &cp.hard {
        if *t >= frames {
            return None;
        }
        let (clip, frame, _) = v.locate(*t);
        if !hard_ok(g, h, FrameRef { clip, frame }) {
            return None;
        }
    }
    let f = &g.features;
    let mut parts = ScoreParts { edge: cp.pb.weights.cut * edge_sum, ..Default::default() };
    let dl = frames as f64 - cp.target as f64;
    parts.length = cp.w_f * dl * dl;
    if let Some(e) = errs.as_deref_mut() {
        e.length = dl.abs() as u32;
    }
    for b in &cp.pb.body {
        let (clip, fr, w) = v.locate(b.time);
        let wt = w.compose(&g.torso_r(clip, fr));
        let e2 = (wt.x - b.x).powi(2) + (wt.z - b.z).powi(2);
        let dy = b.yaw.map_or(0.0, |y| wrap_angle(wt.yaw - y));
        parts.body += cp.w_p * e2 + cp.w_o * dy * dy;
        if let Some(e) = errs.as_deref_mut() {
            e.body_pos.push(e2.sqrt());
            e.body_yaw_deg.push(dy.abs().to_degrees());
        }
    }
    for j in &cp.pb.joints {
        let (clip, fr, w) = v.locate(j.time);
        let wt = w.compose(&g.torso_r(clip, fr));
        let x = wt.apply_point(f.local(clip, fr, j.joint as usize));
        let e2 = (x - j.pos).norm_squared();
        parts.joint += cp.w_j * e2;
        if let Some(e) = errs.as_deref_mut() {
            e.joint.push(e2.sqrt());
        }
    }
    for &(a, b, bit, w) in &cp.style {
        let mut lacking = 0;
        for t in a..=b.min(frames.saturating_sub(1)) {
            let (clip, fr, _) = v.locate(t);
            if g.db.clips[clip as usize].labels.bits.get(fr as usize).is_none_or(|x| x & bit == 0) {
                lacking += 1;
            }
        }
        parts.style += w * lacking as f64 / 30.0;
    }
    if !cp.pb.obstacles.is_empty() {
        for t in (0..frames).step_by(5) {
            let (clip, fr, w) = v.locate(t);
            let wt = w.compose(&g.torso_r(clip, fr));
            for d in &cp.pb.obstacles {
                let dist = Vec3::new(wt.x - d.x, 0.0, wt.z - d.z).norm();
                let pen = (d.radius - dist).max(0.0);
                parts.obstacle += cp.pb.weights.obstacle * pen * pen;
            }
        }
    }
    let score = parts.edge + parts.length + parts.body + parts.joint + parts.style + parts.obstacle;
    Some((score, parts, frames))
}

/// `Σ cost(e)` over `cuts` (f64).
pub(crate) fn edge_sum(g: &MotionGraph, cuts: &[EdgeId]) -> f64 {
    cuts.iter().map(|&e| g.edges[e as usize].cost as f64).sum()
}

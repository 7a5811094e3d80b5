//! Fixed-lag streaming interpretation (spec §13 item 1, beyond the paper): the recurrence of paper
//! eqs. 6–7 run online, one input frame at a time, committing the segment that covers frame
//! `t − lag` as soon as frame `t` has arrived. The output therefore lags the control by exactly
//! `lag` working frames — the path to live use — and the committed segments always form one chain.
//! The decision at frame `t` is the offline DP's answer for an input that stops at `t`, given the
//! committed prefix: the best chain whose last segment either ends at `t` or, with partial ends,
//! overhangs it (scored on its samples up to `t`, the `(d+1)/#in-range` scaling of the offline
//! DP's partial end). That last segment is cut by the end of the data, not by a decision, so it
//! is never committed: when it covers `t − lag`, only the segments before it are committed and
//! that frame waits (the measured latency, [`Streamed::latency_max_s`], can exceed the lag by up
//! to one segment).
//!
//! Per new frame `t` the DP computes the row of cells ending at `t` in pull form (cell `(t, c)`
//! takes the best live predecessor ending at `t − d_c`, ties to the lowest column as in
//! [`crate::dp::interpret`], the same beam per source row). Then, if frame `f = t − lag` is not yet
//! committed, the decision's chain is traced back to the last committed segment and its
//! segments up to the one covering `f` are committed. Committing restricts the DP: every cell
//! ending before the new frontier is dropped, the frontier row keeps only the committed cell,
//! start cells (no predecessor) are no longer allowed, and the rows after the frontier up to `t`
//! are recomputed, so every later chain extends the committed one. At the end of the input the
//! best full chain (partial ends as offline) completes it.
//!
//! With `lag ≥ T` nothing is committed before the end and the result equals the offline DP
//! exactly (same chain, same score; tested). Rows are parallel over columns with rayon
//! (bit-identical for any thread count: every cell is computed by one task in a fixed order).
//!
//! ```
//! use perf_control::stream::interpret_streaming;
//! use perf_control::{interpret, DpParams, MappingDb};
//! use perf_control::data::walk_take;
//! let db = MappingDb::from_takes(vec![walk_take(5, 12.0, 30.0)], 10.0).unwrap();
//! let x = walk_take(6, 6.0, 30.0).control.downsample(3);
//! let p = DpParams::default(); // exact
//! let s = interpret_streaming(&db, &x, &p, 10).unwrap();
//! assert_eq!(s.latency_s, 1.0);
//! // The committed chain can only be as good as the offline optimum.
//! let offline = interpret(&db, &x, &p).unwrap();
//! assert!(s.it.score >= offline.score - 1e-9);
//! ```

use std::time::Instant;

use geom_core::math::Vec3;
use rayon::prelude::*;

use crate::cell::{continuity, eval_cell, CellEval, Column};
use crate::db::MappingDb;
use crate::dp::{check_inputs, columns, finish, DpParams, DpStats, Forced, Interpretation};
use crate::error::{PcError, Result};
use crate::track::PointTrack;

/// The result of a streaming run.
#[derive(Clone, Debug)]
pub struct Streamed {
    /// The committed chain (scored like an offline interpretation).
    pub it: Interpretation,
    /// The lag (working frames).
    pub lag_frames: usize,
    /// The nominal latency of the output behind the control (s) = `lag / rate`: the decision
    /// delay of the segment covering frame `t − lag` (later frames of that segment wait less).
    pub latency_s: f64,
    /// The measured latency: the longest wait (s) between a frame's arrival and its commit, over
    /// the frames committed before the end of the input (NaN when none was). Larger than
    /// `latency_s` when the segment covering a frame was still the open last one.
    pub latency_max_s: f64,
    /// The median of the same waits (s).
    pub latency_median_s: f64,
    /// Commit events before the end of the input.
    pub commits: usize,
    /// Rows recomputed after commits (the streaming overhead, in rows of `P` cells).
    pub recomputed_rows: u64,
}

/// One computed cell of a row.
struct RowCell {
    q: f64,
    back: u32,
    eval: Option<CellEval>,
}

fn excluded(forced: &[Forced], inst: u32, start: i64, end: i64) -> bool {
    forced.iter().any(|f| f.instance != inst && start <= f.time as i64 && f.time as i64 <= end)
}

struct State<'a> {
    db: &'a MappingDb,
    x: &'a PointTrack,
    p: &'a DpParams,
    cols: Vec<Column>,
    np: usize,
    kt: usize,
    t_len: i64,
    s_lo: i64,
    beam: Option<f64>,
    q: Vec<f64>,
    back: Vec<u32>,
    /// Placed tails (positions and velocities, 2·K_t per cell) of the last `ring` rows, by row
    /// modulo `ring` (every predecessor and the frontier lie within it).
    tails: Vec<Vec3>,
    ring: usize,
    /// Live columns per row (the beam), valid once the row is computed.
    live: Vec<Vec<u32>>,
    /// Start cells (no predecessor) allowed: nothing committed yet.
    base_ok: bool,
    stats: DpStats,
}

impl State<'_> {
    /// Computes row `t` (cells ending at `t`) from the rows before it, and its live set.
    fn compute_row(&mut self, t: usize) {
        let np = self.np;
        let kt = self.kt;
        let (x, p, cols, s_lo, t_len) = (self.x, self.p, &self.cols, self.s_lo, self.t_len);
        let (q, tails, live, base_ok, ring) = (&self.q, &self.tails, &self.live, self.base_ok, self.ring);
        let wc = &self.db.control_weights;
        let wt = &self.db.target_weights;
        let row: Vec<RowCell> = (0..np)
            .into_par_iter()
            .map(|c| {
                let col = &cols[c];
                let s = t as i64 - col.d as i64;
                let none = RowCell { q: f64::INFINITY, back: u32::MAX, eval: None };
                if s < s_lo || s > t_len - 2 || excluded(&p.forced, col.inst, s, t as i64) {
                    return none;
                }
                let Some(e) = eval_cell(x, col, s, wc) else { return none };
                if s <= 0 {
                    let q0 = if base_ok { e.d } else { f64::INFINITY };
                    return RowCell { q: q0, back: u32::MAX, eval: Some(e) };
                }
                let (mut best, mut arg) = (f64::INFINITY, u32::MAX);
                let s = s as usize;
                for &r in &live[s] {
                    let r = r as usize;
                    let slot = (s % ring) * np + r;
                    let om = &tails[slot * 2 * kt..(slot + 1) * 2 * kt];
                    let z = q[s * np + r] + p.k * continuity(om, &e.alpha, wt, p.continuity_order, p.k_vel) + e.d;
                    if z < best {
                        best = z;
                        arg = r as u32;
                    }
                }
                RowCell { q: best, back: arg, eval: Some(e) }
            })
            .collect();
        for (c, rc) in row.into_iter().enumerate() {
            let cell = t * np + c;
            self.q[cell] = rc.q;
            self.back[cell] = rc.back;
            if let Some(e) = rc.eval {
                self.stats.cells_evaluated += 1;
                let s = t as i64 - self.cols[c].d as i64;
                if s > 0 {
                    self.stats.relaxations += self.live[s as usize].len() as u64;
                }
                let slot = (t % self.ring) * np + c;
                self.tails[slot * 2 * kt..(slot + 1) * 2 * kt].copy_from_slice(&e.omega);
            }
        }
        self.set_live(t);
    }

    /// The beam's live set of row `t` (every finite cell within `w` of the row's best).
    fn set_live(&mut self, t: usize) {
        let r = &self.q[t * self.np..(t + 1) * self.np];
        let best = r.iter().copied().fold(f64::INFINITY, f64::min);
        let cut = self.beam.map_or(f64::INFINITY, |w| best + w);
        self.live[t] = if best.is_finite() {
            (0..self.np).filter(|&c| r[c].is_finite() && r[c] <= cut).map(|c| c as u32).collect()
        } else {
            vec![]
        };
        self.stats.cells_expanded += self.live[t].len() as u64;
    }

    /// Best cell of row `t` (lowest column on ties), if any is finite.
    fn best_in_row(&self, t: usize) -> Option<usize> {
        let r = &self.q[t * self.np..(t + 1) * self.np];
        let mut best = (f64::INFINITY, usize::MAX);
        for (c, &v) in r.iter().enumerate() {
            if v < best.0 {
                best = (v, c);
            }
        }
        best.0.is_finite().then_some(best.1)
    }

    /// The decision at frame `t`: the best chain explaining frames `0..=t` given the committed
    /// prefix, as the offline DP would answer for an input that stopped at `t` — its last segment
    /// either ends at `t` (row `t`) or, with partial ends, overhangs `t` (a cell starting at
    /// `s ∈ (t − d, t)`, scored on its in-range samples with the `(d+1)/#in-range` scaling). That
    /// last segment is returned apart: its end is no decision yet. Returns the chain before it
    /// (time order, back to the frontier) or `None` when no chain reaches `t`. Ties: cells ending
    /// at `t` first (lowest column), then overhanging cells by start, column and predecessor
    /// column (strict `<`). Overhanging cells are evaluated in parallel over columns, each by one
    /// task, and reduced in that fixed order, so the decision does not depend on the thread count.
    fn decide(&self, t: usize, frontier: Option<(usize, usize)>) -> Option<Vec<(usize, i64)>> {
        let np = self.np;
        let kt = self.kt;
        // The best candidate so far: (score, chain before its last segment).
        let mut best: Option<(f64, Vec<(usize, i64)>)> = self.best_in_row(t).map(|c| {
            let mut chain = self.trace(t, c, frontier);
            chain.pop();
            (self.q[t * np + c], chain)
        });
        if !self.p.partial_ends {
            return best.map(|b| b.1);
        }
        let dmax = self.cols.iter().map(|c| c.d).max().unwrap_or(1) as i64;
        let w0 = (t as i64 - dmax).max(0) as usize;
        let xw = self.x.window(w0, t);
        let wc = &self.db.control_weights;
        let wt = &self.db.target_weights;
        for s in (t as i64 - dmax + 1).max(self.s_lo)..t as i64 {
            let base = s <= 0;
            if base && !self.base_ok {
                continue;
            }
            let live: &[u32] = if base { &[] } else { &self.live[s as usize] };
            if !base && live.is_empty() {
                continue;
            }
            // Overhanging cells starting at s (in-range part ends at t), per column.
            let cand: Vec<Option<(f64, u32)>> = self
                .cols
                .par_iter()
                .map(|col| {
                    if s + col.d as i64 <= t as i64 || excluded(&self.p.forced, col.inst, s, s + col.d as i64) {
                        return None;
                    }
                    let e = eval_cell(&xw, col, s - w0 as i64, wc)?;
                    if base {
                        return Some((e.d, u32::MAX));
                    }
                    let (mut b, mut arg) = (f64::INFINITY, u32::MAX);
                    let su = s as usize;
                    for &r in live {
                        let slot = (su % self.ring) * np + r as usize;
                        let om = &self.tails[slot * 2 * kt..(slot + 1) * 2 * kt];
                        let z = self.q[su * np + r as usize]
                            + self.p.k * continuity(om, &e.alpha, wt, self.p.continuity_order, self.p.k_vel)
                            + e.d;
                        if z < b {
                            b = z;
                            arg = r;
                        }
                    }
                    b.is_finite().then_some((b, arg))
                })
                .collect();
            for (v, arg) in cand.into_iter().flatten() {
                if best.as_ref().is_none_or(|b| v < b.0) {
                    let chain = if arg == u32::MAX { vec![] } else { self.trace(s as usize, arg as usize, frontier) };
                    best = Some((v, chain));
                }
            }
        }
        best.map(|b| b.1)
    }

    /// The chain ending at cell `(t, c)` back to (excluding) the frontier cell, in time order, as
    /// (column, start).
    fn trace(&self, t: usize, c: usize, frontier: Option<(usize, usize)>) -> Vec<(usize, i64)> {
        let mut out = Vec::new();
        let (mut t, mut c) = (t, c);
        loop {
            if frontier == Some((t, c)) {
                break;
            }
            let start = t as i64 - self.cols[c].d as i64;
            out.push((c, start));
            let b = self.back[t * self.np + c];
            if b == u32::MAX {
                break;
            }
            t = start as usize;
            c = b as usize;
        }
        out.reverse();
        out
    }
}

/// Interprets `x` online with a fixed lag of `lag` working frames (see the module docs). Same
/// parameters, errors and tie rules as [`crate::dp::interpret`]; the GEMM option is ignored.
pub fn interpret_streaming(db: &MappingDb, x: &PointTrack, p: &DpParams, lag: usize) -> Result<Streamed> {
    check_inputs(db, x, p)?;
    let clock = Instant::now();
    let cols = columns(db, p.stretch_limit_s);
    let np = cols.len();
    let t_len = x.len() as i64;
    let dmax = cols.iter().map(|c| c.d).max().unwrap_or(1) as i64;
    let kt = db.target_points();
    let s_lo: i64 = if p.partial_ends { -(dmax - 1) } else { 0 };
    let n_rows = if p.partial_ends { (t_len - 1 + dmax) as usize } else { t_len as usize };
    let ring = (dmax as usize).max(lag) + 2;
    let mut st = State {
        db,
        x,
        p,
        np,
        kt,
        t_len,
        s_lo,
        beam: p.beam.filter(|w| w.is_finite()),
        q: vec![f64::INFINITY; n_rows * np],
        back: vec![u32::MAX; n_rows * np],
        tails: vec![Vec3::zeros(); ring * np * 2 * kt],
        ring,
        live: vec![vec![]; n_rows],
        base_ok: true,
        stats: DpStats { columns: np, ..DpStats::default() },
        cols,
    };
    let mut committed: Vec<(usize, i64)> = Vec::new();
    let mut frontier: Option<(usize, usize)> = None;
    let mut committed_until: i64 = -1;
    // Per input frame: the frame at which it was committed (the end of the input for the rest).
    let mut commit_t = vec![t_len as usize - 1; t_len as usize];
    let (mut commits, mut recomputed) = (0usize, 0u64);
    for t in 1..t_len as usize {
        st.compute_row(t);
        let f = t as i64 - lag as i64;
        if f < 0 || f <= committed_until || t as i64 == t_len - 1 {
            continue;
        }
        // The chain explaining 0..=t without its last segment (which is cut at t, so its end is
        // no decision yet, and is never committed). Commit up to and including the segment
        // covering frame f, or, when f lies in the last one, every segment before it.
        let Some(chain) = st.decide(t, frontier) else { continue };
        let body = chain.len();
        let upto = chain[..body]
            .iter()
            .position(|&(col, start)| start + st.cols[col].d as i64 >= f)
            .unwrap_or(body.wrapping_sub(1));
        if upto >= body {
            continue;
        }
        committed.extend_from_slice(&chain[..=upto]);
        let (col, start) = chain[upto];
        let e = (start + st.cols[col].d as i64) as usize;
        let first = (committed_until + 1).max(0) as usize;
        commit_t[first..=e.min(t_len as usize - 1)].fill(t);
        frontier = Some((e, col));
        committed_until = e as i64;
        commits += 1;
        st.base_ok = false;
        // Restrict: rows before the frontier hold nothing, the frontier row only the committed
        // cell; recompute the rows after it.
        for r in 0..e {
            st.q[r * np..(r + 1) * np].fill(f64::INFINITY);
            st.live[r].clear();
        }
        let keep = st.q[e * np + col];
        st.q[e * np..(e + 1) * np].fill(f64::INFINITY);
        st.q[e * np + col] = keep;
        st.live[e] = vec![col as u32];
        for r in e + 1..=t {
            st.compute_row(r);
            recomputed += 1;
        }
    }
    for t in t_len as usize..n_rows {
        st.compute_row(t);
    }
    let last_row = if p.partial_ends { n_rows - 1 } else { (t_len - 1) as usize };
    let mut best = (f64::INFINITY, usize::MAX, usize::MAX);
    for t in (t_len - 1) as usize..=last_row {
        for c in 0..np {
            let v = st.q[t * np + c];
            if v < best.0 {
                best = (v, t, c);
            }
        }
    }
    if !best.0.is_finite() {
        return Err(PcError::NoInterpretation(format!(
            "streaming: no chain of the {} frames extends the committed segments",
            x.len()
        )));
    }
    committed.extend(st.trace(best.1, best.2, frontier));
    let it = finish(db, x, &st.cols, &committed, p, best.0, clock, st.stats);
    let waits: Vec<f64> = commit_t.iter().enumerate().map(|(f, &t)| (t.saturating_sub(f)) as f64 / x.rate_hz).collect();
    let committed_early: Vec<f64> =
        commit_t.iter().enumerate().filter(|(_, &t)| t + 1 < t_len as usize).map(|(f, _)| waits[f]).collect();
    Ok(Streamed {
        it,
        lag_frames: lag,
        latency_s: lag as f64 / x.rate_hz,
        latency_max_s: geom_core::stats::max(&committed_early),
        latency_median_s: geom_core::stats::median(&committed_early),
        commits,
        recomputed_rows: recomputed,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::data::walk_take;
    use crate::dp::interpret;

    fn setup() -> (MappingDb, PointTrack) {
        let db = MappingDb::from_takes(vec![walk_take(5, 12.0, 30.0)], 10.0).unwrap();
        let x = walk_take(6, 8.0, 30.0).control.downsample(3);
        (db, x)
    }

    /// With a lag of the whole input nothing is committed early: the result is the offline DP
    /// (same chain, same score), exact and with the beam.
    #[test]
    fn full_lag_equals_offline() {
        let (db, x) = setup();
        for beam in [None, Some(0.3)] {
            let p = DpParams { beam, ..DpParams::default() };
            let off = interpret(&db, &x, &p).unwrap();
            let s = interpret_streaming(&db, &x, &p, x.len()).unwrap();
            assert_eq!(s.commits, 0);
            assert_eq!(s.it.score, off.score, "beam {beam:?}");
            let chain =
                |it: &Interpretation| it.segments.iter().map(|c| (c.instance, c.start, c.end)).collect::<Vec<_>>();
            assert_eq!(chain(&s.it), chain(&off));
        }
    }

    /// A short lag commits early: the committed chain tiles the input (consecutive segments share
    /// their boundary frame), is never better than the offline optimum, and is bitwise identical
    /// for 1 and 2 rayon threads.
    #[test]
    fn short_lag_commits_a_valid_chain() {
        let (db, x) = setup();
        let p = DpParams::default();
        let off = interpret(&db, &x, &p).unwrap();
        let run = |n: usize| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(n)
                .build()
                .unwrap()
                .install(|| interpret_streaming(&db, &x, &p, 5).unwrap())
        };
        let (a, b) = (run(1), run(2));
        assert!(a.commits > 3, "{} commits", a.commits);
        assert_eq!(a.latency_s, 0.5);
        // No frame is committed before the lag, none waits more than the lag plus one segment.
        let dmax = crate::dp::columns(&db, p.stretch_limit_s).iter().map(|c| c.d).max().unwrap();
        assert!(a.latency_max_s >= 0.5 && a.latency_max_s <= (5 + dmax) as f64 / 10.0, "{}", a.latency_max_s);
        assert!(a.it.score >= off.score - 1e-9 * off.score.abs());
        for w in a.it.segments.windows(2) {
            assert_eq!(w[0].end, w[1].start, "segments must share their boundary");
        }
        assert!(a.it.segments[0].start <= 0 && a.it.segments.last().unwrap().end >= x.len() as i64 - 1);
        assert_eq!(a.it.score.to_bits(), b.it.score.to_bits());
        assert_eq!(a.it.segments.len(), b.it.segments.len());
    }
}

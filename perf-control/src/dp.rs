//! The dynamic program of paper eqs. 6–7 (spec §3.4–§3.6): the chain of stretched, placed
//! instances minimising `S = Σ D(x_i, a_{s_i}^{d_i}) + k Σ C_i` over the whole input, by a forward
//! (push) sweep over start times with an optional beam, partial ends and forced segments.

use crate::cell::{continuity, eval_cell, legal_durations, CellEval, Column};
use crate::db::MappingDb;
use crate::error::{check_finite, PcError, Result};
use crate::track::PointTrack;
use geom_core::math::{Planar, Vec3};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use std::time::Instant;

/// A constraint: instance `instance` must cover input frame `time` (spec §3.8).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Forced {
    /// Instance index in the database.
    pub instance: u32,
    /// Input frame (working rate).
    pub time: usize,
}

/// DP parameters (spec §4).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct DpParams {
    /// Continuity constant `k` (≥ 0).
    pub k: f64,
    /// ± uniform stretch allowed per segment (s); `Δ = round(limit × rate)` intervals.
    pub stretch_limit_s: f64,
    /// Beam width `w` (score units, m²); `None` = exact.
    pub beam: Option<f64>,
    /// First/last segment may overhang the input (spec §3.5, §12 item 3).
    pub partial_ends: bool,
    /// 0 = positions only (paper); 1 = + velocities.
    pub continuity_order: u8,
    /// Weight of the velocity term (s²) when `continuity_order = 1`.
    pub k_vel: f64,
    /// Forced segments (none when omitted in a scene file).
    #[serde(default)]
    pub forced: Vec<Forced>,
    /// Relax each start time as a min-plus product through one GEMM (spec §3.5 "faster
    /// equivalent"): `‖ω − α‖² = ‖ω‖² + ‖α‖² − 2ω·α` with the cross terms from faer's matmul.
    /// Same result as the push sweep to rounding (test §7.6). Off when omitted.
    #[serde(default)]
    pub gemm: bool,
}

impl Default for DpParams {
    /// The walk defaults of spec §4: `k = 10`, ±0.2 s, exact, partial ends, order 0.
    fn default() -> Self {
        Self {
            k: 10.0,
            stretch_limit_s: 0.2,
            beam: None,
            partial_ends: true,
            continuity_order: 0,
            k_vel: 0.0,
            forced: vec![],
            gemm: false,
        }
    }
}

/// One chosen segment of an interpretation.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Chosen {
    /// Instance index.
    pub instance: u32,
    /// First input frame covered (may be < 0 with partial ends).
    pub start: i64,
    /// Last input frame covered (may be ≥ T with partial ends); `end − start = d`.
    pub end: i64,
    /// Alignment `M`.
    pub m: Planar,
    /// `D` of the segment (m²).
    pub d: f64,
    /// Continuity `C` with the previous segment (0 for the first).
    pub c: f64,
}

/// Work counters of a DP run.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct DpStats {
    /// Legal (instance, duration) pairs `P`.
    pub columns: usize,
    /// Cells expanded (propagated to successors).
    pub cells_expanded: u64,
    /// Cell evaluations (alignments).
    pub cells_evaluated: u64,
    /// Relaxations `Q + kC + D` computed.
    pub relaxations: u64,
    /// Wall time (s).
    pub seconds: f64,
    /// Refinement only: segments whose fine stretch limit was widened by `u` (spec §3.8).
    pub widened: usize,
}

/// The chosen chain.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Interpretation {
    /// Rate of the frames `start`/`end` refer to (Hz).
    pub rate_hz: f64,
    /// Input length in frames.
    pub frames: usize,
    /// Segments in time order.
    pub segments: Vec<Chosen>,
    /// `S` (m²).
    pub score: f64,
    /// `Σ D`.
    pub d_total: f64,
    /// `Σ C` (without `k`).
    pub c_total: f64,
    /// Work counters.
    pub stats: DpStats,
}

/// Validates the database/input/parameter combination (spec §8).
pub(crate) fn check_inputs(db: &MappingDb, x: &PointTrack, p: &DpParams) -> Result<()> {
    if db.instances.is_empty() {
        return Err(PcError::EmptyDatabase("no instance".into()));
    }
    if x.len() < 2 {
        return Err(PcError::InputTooShort { frames: x.len() });
    }
    if x.n_points != db.control_points() {
        return Err(PcError::PointCountMismatch {
            what: "input control".into(),
            expected: db.control_points(),
            got: x.n_points,
        });
    }
    if !x.rate_hz.is_finite() || (x.rate_hz - db.working_rate_hz).abs() > 1e-9 * db.working_rate_hz {
        return Err(PcError::RateMismatch {
            what: "input control".into(),
            expected: db.working_rate_hz,
            got: x.rate_hz,
        });
    }
    check_finite("input control", &x.data, x.n_points)?;
    for (i, inst) in db.instances.iter().enumerate() {
        check_finite(&format!("instance {i} control"), &inst.control.data, inst.control.n_points)?;
        check_finite(&format!("instance {i} target"), &inst.target.data, inst.target.n_points)?;
    }
    let bad = |name: &'static str, msg: String| Err(PcError::BadParameter { name, msg });
    if !(p.k.is_finite() && p.k >= 0.0) {
        return bad("k", format!("{} must be finite and ≥ 0", p.k));
    }
    if !(p.stretch_limit_s.is_finite() && p.stretch_limit_s >= 0.0) {
        return bad("stretch_limit_s", format!("{} must be finite and ≥ 0", p.stretch_limit_s));
    }
    if let Some(w) = p.beam {
        if w.is_nan() || w < 0.0 {
            return bad("beam", format!("{w} must be ≥ 0 (∞ allowed)"));
        }
    }
    if p.continuity_order > 1 {
        return bad("continuity_order", format!("{} must be 0 or 1", p.continuity_order));
    }
    if !(p.k_vel.is_finite() && p.k_vel >= 0.0) {
        return bad("k_vel", format!("{} must be finite and ≥ 0", p.k_vel));
    }
    for w in db.control_weights.iter().chain(&db.target_weights) {
        if !(w.is_finite() && *w >= 0.0) {
            return bad("weights", format!("point weight {w} must be finite and ≥ 0"));
        }
    }
    for f in &p.forced {
        if f.instance as usize >= db.instances.len() {
            return Err(PcError::NoInterpretation(format!(
                "forced instance {} does not exist ({} instances)",
                f.instance,
                db.instances.len()
            )));
        }
        if f.time >= x.len() {
            return Err(PcError::NoInterpretation(format!(
                "forced time {} is outside the input (0…{})",
                f.time,
                x.len() - 1
            )));
        }
    }
    Ok(())
}

/// The DP columns: every legal (instance, duration) pair, instance-major, durations ascending.
pub fn columns(db: &MappingDb, stretch_limit_s: f64) -> Vec<Column> {
    let delta = (stretch_limit_s * db.working_rate_hz).round() as usize;
    let mut cols = Vec::new();
    for (s, inst) in db.instances.iter().enumerate() {
        for d in legal_durations(inst.n(), delta) {
            cols.push(Column::new(db, s as u32, d));
        }
    }
    cols
}

/// True when a cell of `inst` covering `[start, end]` violates a forced segment.
fn excluded(forced: &[Forced], inst: u32, start: i64, end: i64) -> bool {
    forced.iter().any(|f| f.instance != inst && start <= f.time as i64 && f.time as i64 <= end)
}

/// Interprets the input control `x` (working rate) as a chain of database instances (paper eqs.
/// 6–7; spec §3.5). Exact when `p.beam` is `None` (or ∞). Deterministic: ties go to the lowest
/// column index, then to the earliest end time. Memory `O(T·P)` for the scores and backpointers.
pub fn interpret(db: &MappingDb, x: &PointTrack, p: &DpParams) -> Result<Interpretation> {
    check_inputs(db, x, p)?;
    let clock = Instant::now();
    let cols = columns(db, p.stretch_limit_s);
    let np = cols.len();
    let t_len = x.len() as i64;
    let dmax = cols.iter().map(|c| c.d).max().unwrap_or(1) as i64;
    let kt = db.target_points();
    let wc = &db.control_weights;
    let wt = &db.target_weights;
    let s_lo: i64 = if p.partial_ends { -(dmax - 1) } else { 0 };
    let n_rows = if p.partial_ends { (t_len - 1 + dmax) as usize } else { t_len as usize };
    let mut q = vec![f64::INFINITY; n_rows * np];
    let mut back = vec![u32::MAX; n_rows * np];
    let ring = (dmax + 1) as usize;
    // Placed tails (positions and velocities, 2·K_t) of cells by end row modulo `ring`.
    let mut tails = vec![Vec3::zeros(); ring * np * 2 * kt];
    let mut succ_d = vec![f64::INFINITY; np];
    let mut succ_alpha = vec![Vec3::zeros(); np * 2 * kt];
    let mut live: Vec<usize> = Vec::with_capacity(np);
    let mut stats = DpStats { columns: np, ..DpStats::default() };
    let beam = p.beam.filter(|w| w.is_finite());
    for s0 in s_lo..=(t_len - 2) {
        let base = s0 <= 0;
        live.clear();
        if !base {
            let row = &q[s0 as usize * np..(s0 as usize + 1) * np];
            let best = row.iter().copied().fold(f64::INFINITY, f64::min);
            if !best.is_finite() {
                continue;
            }
            let cut = beam.map_or(f64::INFINITY, |w| best + w);
            live.extend((0..np).filter(|&c| row[c].is_finite() && row[c] <= cut));
        }
        // Successor cells starting at s0, evaluated in parallel over columns (each cell by one
        // task; copied out in column order, so the result does not depend on the thread count).
        let evals: Vec<Option<CellEval>> = cols
            .par_iter()
            .map(|col| {
                let t = s0 + col.d as i64;
                if (!p.partial_ends && t > t_len - 1) || excluded(&p.forced, col.inst, s0, t) {
                    return None;
                }
                eval_cell(x, col, s0, wc)
            })
            .collect();
        let mut any = false;
        for (c, e) in evals.into_iter().enumerate() {
            succ_d[c] = f64::INFINITY;
            let Some(CellEval { d, alpha, omega, .. }) = e else { continue };
            stats.cells_evaluated += 1;
            succ_d[c] = d;
            succ_alpha[c * 2 * kt..(c + 1) * 2 * kt].copy_from_slice(&alpha);
            let r = ((s0 + cols[c].d as i64) as usize) % ring;
            tails[(r * np + c) * 2 * kt..(r * np + c + 1) * 2 * kt].copy_from_slice(&omega);
            any = true;
        }
        if !any {
            continue;
        }
        if base {
            for (c, col) in cols.iter().enumerate() {
                if succ_d[c].is_finite() {
                    let t = (s0 + col.d as i64) as usize;
                    let cell = t * np + c;
                    if succ_d[c] < q[cell] {
                        q[cell] = succ_d[c];
                        back[cell] = u32::MAX;
                    }
                }
            }
            continue;
        }
        let r_src = (s0 as usize) % ring;
        if p.gemm {
            let ctx =
                GemmRow { cols: &cols, succ_d: &succ_d, succ_alpha: &succ_alpha, tails: &tails, r_src, np, kt, wt };
            gemm_relax(&ctx, &live, s0 as usize, p, &mut q, &mut back, &mut stats);
            continue;
        }
        // Relaxation, parallel over successor columns: every successor cell `(s0 + d_c, c)` is
        // written by one task only, which scans the live predecessors in ascending column order
        // with a strict `<` — the comparisons of the sequential push sweep, in the same order, so
        // the scores and backpointers are bitwise identical for any thread count.
        let s0u = s0 as usize;
        let qlive: Vec<f64> = live.iter().map(|&r| q[s0u * np + r]).collect();
        let (qr, br) = (&q, &back);
        let upd: Vec<Option<(f64, u32)>> = (0..np)
            .into_par_iter()
            .map(|c| {
                let dc = succ_d[c];
                if !dc.is_finite() {
                    return None;
                }
                let cell = (s0u + cols[c].d) * np + c;
                let (mut best, mut arg) = (qr[cell], br[cell]);
                let al = &succ_alpha[c * 2 * kt..(c + 1) * 2 * kt];
                for (&r, &qv) in live.iter().zip(&qlive) {
                    let om = &tails[(r_src * np + r) * 2 * kt..(r_src * np + r + 1) * 2 * kt];
                    let z = qv + p.k * continuity(om, al, wt, p.continuity_order, p.k_vel) + dc;
                    if z < best {
                        best = z;
                        arg = r as u32;
                    }
                }
                Some((best, arg))
            })
            .collect();
        stats.cells_expanded += live.len() as u64;
        for (c, u) in upd.into_iter().enumerate() {
            let Some((best, arg)) = u else { continue };
            stats.relaxations += live.len() as u64;
            let cell = (s0u + cols[c].d) * np + c;
            q[cell] = best;
            back[cell] = arg;
        }
    }
    // Answer: cells ending at T − 1 (or beyond with partial ends), earliest end, lowest column.
    let last_row = if p.partial_ends { n_rows - 1 } else { (t_len - 1) as usize };
    let mut best = (f64::INFINITY, usize::MAX, usize::MAX);
    for t in (t_len - 1) as usize..=last_row {
        for c in 0..np {
            let v = q[t * np + c];
            if v < best.0 {
                best = (v, t, c);
            }
        }
    }
    if !best.0.is_finite() {
        let why = if p.forced.is_empty() {
            format!(
                "the input of {} frames cannot be tiled by the allowed durations (partial ends {})",
                x.len(),
                if p.partial_ends { "on" } else { "off" }
            )
        } else {
            format!("the forced segments {:?} exclude every chain", p.forced)
        };
        return Err(PcError::NoInterpretation(why));
    }
    let mut chain = Vec::new();
    let (mut t, mut c) = (best.1, best.2);
    loop {
        let start = t as i64 - cols[c].d as i64;
        chain.push((c, start));
        let b = back[t * np + c];
        if b == u32::MAX {
            break;
        }
        t = start as usize;
        c = b as usize;
    }
    chain.reverse();
    let it = finish(db, x, &cols, &chain, p, best.0, clock, stats);
    Ok(it)
}

/// Inputs of one GEMM relaxation (one start time).
struct GemmRow<'a> {
    cols: &'a [Column],
    succ_d: &'a [f64],
    succ_alpha: &'a [Vec3],
    tails: &'a [Vec3],
    r_src: usize,
    np: usize,
    kt: usize,
    wt: &'a [f64],
}

/// Min-plus relaxation of all live cells ending at `s0` into all successors starting there, with
/// the cross terms of `‖ω − α‖²` from one matrix product. Positions are centred on the mean head
/// first so the expansion loses no precision (|p| ~ 1 m instead of the room size). Per successor,
/// predecessors are scanned in ascending column order with a strict `<`, the push sweep's tie rule.
fn gemm_relax(
    g: &GemmRow,
    live: &[usize],
    s0: usize,
    p: &DpParams,
    q: &mut [f64],
    back: &mut [u32],
    stats: &mut DpStats,
) {
    use geom_core::faer::{Accum, Mat, Par};
    use geom_core::linalg::dense::matmul;
    let (kt, np) = (g.kt, g.np);
    let succ: Vec<usize> = (0..np).filter(|&c| g.succ_d[c].is_finite()).collect();
    if succ.is_empty() || live.is_empty() {
        return;
    }
    let mut c0 = Vec3::zeros();
    for &c in &succ {
        for pnt in 0..kt {
            c0 += g.succ_alpha[c * 2 * kt + pnt];
        }
    }
    c0 /= (succ.len() * kt) as f64;
    let vel = p.continuity_order >= 1;
    let dim = 3 * kt * if vel { 2 } else { 1 };
    // Feature vector of a placed head/tail: √w·(x − c0), then √(k_vel·w)·v.
    let feat = |pts: &[Vec3], i: usize| -> f64 {
        let (block, rest) = (i / (3 * kt), i % (3 * kt));
        let (pnt, axis) = (rest / 3, rest % 3);
        if block == 0 {
            g.wt[pnt].sqrt() * (pts[pnt][axis] - c0[axis])
        } else {
            (p.k_vel * g.wt[pnt]).sqrt() * pts[kt + pnt][axis]
        }
    };
    let tail = |r: usize| &g.tails[(g.r_src * np + r) * 2 * kt..(g.r_src * np + r + 1) * 2 * kt];
    let head = |c: usize| &g.succ_alpha[c * 2 * kt..(c + 1) * 2 * kt];
    let a = Mat::<f64>::from_fn(live.len(), dim, |i, j| feat(tail(live[i]), j));
    let b = Mat::<f64>::from_fn(dim, succ.len(), |i, j| feat(head(succ[j]), i));
    let na: Vec<f64> = (0..live.len()).map(|i| (0..dim).map(|j| a[(i, j)] * a[(i, j)]).sum()).collect();
    let nb: Vec<f64> = (0..succ.len()).map(|j| (0..dim).map(|i| b[(i, j)] * b[(i, j)]).sum()).collect();
    let mut prod = Mat::<f64>::zeros(live.len(), succ.len());
    matmul(prod.as_mut(), Accum::Replace, a.as_ref(), b.as_ref(), 1.0, Par::Seq);
    stats.cells_expanded += live.len() as u64;
    stats.relaxations += (live.len() * succ.len()) as u64;
    for (j, &c) in succ.iter().enumerate() {
        let cell = (s0 + g.cols[c].d) * np + c;
        for (i, &r) in live.iter().enumerate() {
            let cont = (na[i] + nb[j] - 2.0 * prod[(i, j)]).max(0.0);
            let z = q[s0 * np + r] + p.k * cont + g.succ_d[c];
            if z < q[cell] {
                q[cell] = z;
                back[cell] = r as u32;
            }
        }
    }
}

/// Builds the [`Interpretation`] of a chain of (column, start) pairs, recomputing each cell.
#[allow(clippy::too_many_arguments)]
pub(crate) fn finish(
    db: &MappingDb,
    x: &PointTrack,
    cols: &[Column],
    chain: &[(usize, i64)],
    p: &DpParams,
    score: f64,
    clock: Instant,
    mut stats: DpStats,
) -> Interpretation {
    let mut segs = Vec::with_capacity(chain.len());
    let mut prev: Option<CellEval> = None;
    let (mut dt, mut ct) = (0.0, 0.0);
    for &(c, start) in chain {
        // Invariant: every cell of a finite chain was evaluable when the DP created it.
        let e = eval_cell(x, &cols[c], start, &db.control_weights).expect("cells of the chosen chain are in range");
        let cc = prev
            .as_ref()
            .map_or(0.0, |pv| continuity(&pv.omega, &e.alpha, &db.target_weights, p.continuity_order, p.k_vel));
        dt += e.d;
        ct += cc;
        segs.push(Chosen { instance: cols[c].inst, start, end: start + cols[c].d as i64, m: e.m, d: e.d, c: cc });
        prev = Some(e);
    }
    stats.seconds = clock.elapsed().as_secs_f64();
    Interpretation { rate_hz: x.rate_hz, frames: x.len(), segments: segs, score, d_total: dt, c_total: ct, stats }
}

/// Scores an explicit chain `(instance, start, end)` at the input's rate (spec §3.4), without
/// legality checks on the durations; `None` when a segment has fewer than 2 in-range samples or
/// consecutive segments do not share their boundary frame.
pub fn score_chain(db: &MappingDb, x: &PointTrack, chain: &[(u32, i64, i64)], p: &DpParams) -> Option<Interpretation> {
    if chain.windows(2).any(|w| w[0].2 != w[1].1) || chain.iter().any(|c| c.2 <= c.1) {
        return None;
    }
    let clock = Instant::now();
    let cols: Vec<Column> = chain.iter().map(|&(s, a, b)| Column::new(db, s, (b - a) as usize)).collect();
    let pairs: Vec<(usize, i64)> = chain.iter().enumerate().map(|(i, c)| (i, c.1)).collect();
    for (c, s) in &pairs {
        eval_cell(x, &cols[*c], *s, &db.control_weights)?;
    }
    let mut it = finish(db, x, &cols, &pairs, p, 0.0, clock, DpStats::default());
    it.score = it.d_total + p.k * it.c_total;
    Some(it)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::data::walk_take;

    /// The DP's cell evaluations and relaxations run in parallel over columns: the scores,
    /// chains and work counters are bitwise identical with 1 and 2 rayon threads, exact and with
    /// the beam.
    #[test]
    fn parallel_dp_is_thread_independent() {
        let db = MappingDb::from_takes(vec![walk_take(5, 12.0, 30.0)], 10.0).unwrap();
        let x = walk_take(6, 8.0, 30.0).control.downsample(3);
        for beam in [None, Some(0.3)] {
            let p = DpParams { beam, ..DpParams::default() };
            let run = |n: usize| {
                let pool = rayon::ThreadPoolBuilder::new().num_threads(n).build().unwrap();
                pool.install(|| interpret(&db, &x, &p).unwrap())
            };
            let (a, b) = (run(1), run(2));
            assert_eq!(a.score.to_bits(), b.score.to_bits(), "beam {beam:?}");
            assert_eq!(a.segments, b.segments);
            let counters = |s: &DpStats| (s.cells_expanded, s.cells_evaluated, s.relaxations);
            assert_eq!(counters(&a.stats), counters(&b.stats));
        }
    }
}

//! Upsampling refinement (spec §3.8, reconstructed, §12 item 5): the coarse chain found at the
//! working rate is re-timed at the full rate by a constrained DP that keeps the instance sequence
//! and moves each boundary within `±(u − 1)` fine frames of `u·b_i`.

use crate::cell::{continuity, eval_cell, CellEval, Column};
use crate::db::MappingDb;
use crate::dp::{check_inputs, finish, DpParams, DpStats, Interpretation};
use crate::error::{PcError, Result};
use crate::track::PointTrack;
use std::time::Instant;

/// Refines `coarse` (found on `x_fine.downsample(factor)`) at the full rate. `db_fine` must hold
/// the same instances at the fine rate ([`MappingDb::at_rate`]). The state of the DP is the pair
/// of a segment's boundaries, so continuity (which depends on both neighbours' alignments) is
/// exact: `O(L·(2u−1)³)` relaxations over `O(L·(2u−1)²)` cell evaluations. A segment whose fine
/// stretch limit admits no candidate pair has its limit widened by `u` fine frames; if the chain
/// is still infeasible (rounding of the fine limits can make neighbouring windows incompatible),
/// every limit is widened by `u`, then `2u`, then dropped (`stats.widened` counts the segments
/// whose limit was widened). Forced segments are not re-applied (the instance sequence is fixed
/// already).
pub fn refine(
    db_fine: &MappingDb,
    x_fine: &PointTrack,
    coarse: &Interpretation,
    factor: usize,
    p: &DpParams,
) -> Result<Interpretation> {
    let mut pf = p.clone();
    pf.forced.clear();
    check_inputs(db_fine, x_fine, &pf)?;
    if factor == 0 {
        return Err(PcError::BadParameter { name: "factor", msg: "must be ≥ 1".into() });
    }
    let l = coarse.segments.len();
    if l == 0 {
        return Err(PcError::NoInterpretation("the coarse interpretation is empty".into()));
    }
    if coarse.segments.iter().any(|s| s.instance as usize >= db_fine.instances.len()) {
        return Err(PcError::BadParameter { name: "db_fine", msg: "does not hold the coarse instances".into() });
    }
    let clock = Instant::now();
    let u = factor as i64;
    let tf = x_fine.len() as i64;
    let mut b: Vec<i64> = vec![coarse.segments[0].start];
    b.extend(coarse.segments.iter().map(|s| s.end));
    let cands: Vec<Vec<i64>> = (0..=l)
        .map(|i| {
            let c0 = u * b[i];
            let mut v: Vec<i64> = ((c0 - (u - 1))..=(c0 + (u - 1)))
                .filter(|&x| {
                    if i == 0 {
                        if p.partial_ends {
                            x <= 0
                        } else {
                            x == 0
                        }
                    } else if i == l {
                        if p.partial_ends {
                            x >= tf - 1
                        } else {
                            x == tf - 1
                        }
                    } else {
                        x >= 1 && x <= tf - 2
                    }
                })
                .collect();
            if v.is_empty() {
                v.push(if i == 0 {
                    0
                } else if i == l {
                    tf - 1
                } else {
                    c0.clamp(1, (tf - 2).max(1))
                });
            }
            v
        })
        .collect();
    let delta = (p.stretch_limit_s * x_fine.rate_hz).round() as i64;
    let mut stats = DpStats::default();
    let mut widened = 0usize;
    let mut limit: Vec<i64> = vec![delta; l];
    for i in 0..l {
        let n = db_fine.instances[coarse.segments[i].instance as usize].n() as i64;
        let ok = |lim: i64| cands[i].iter().any(|&a| cands[i + 1].iter().any(|&c| c > a && (c - a - n).abs() <= lim));
        if !ok(limit[i]) {
            limit[i] += u;
            widened += 1;
        }
    }
    // Widening ladder (spec §3.8): per-segment widening first, then every limit by u, 2u, and
    // finally no limit, so a coarse chain always refines.
    let mut found = solve(db_fine, x_fine, coarse, &cands, &limit, p, &mut stats);
    for extra in [u, 2 * u, i64::MAX / 4] {
        if found.is_some() {
            break;
        }
        let wide: Vec<i64> = limit.iter().map(|&v| v.saturating_add(extra)).collect();
        widened = l;
        found = solve(db_fine, x_fine, coarse, &cands, &wide, p, &mut stats);
    }
    let Some((best, pick, flat_cols)) = found else {
        return Err(PcError::NoInterpretation(format!(
            "refinement ×{factor}: no boundary placement within ±{} fine frames",
            u - 1
        )));
    };
    let chain: Vec<(usize, i64)> = (0..l).map(|i| (i, cands[i][pick[i]])).collect();
    stats.widened = widened;
    Ok(finish(db_fine, x_fine, &flat_cols, &chain, p, best, clock, stats))
}

/// The boundary DP of [`refine`] for given per-segment duration limits: best score, the chosen
/// candidate index per boundary and the chosen columns; `None` when no placement is legal.
fn solve(
    db_fine: &MappingDb,
    x_fine: &PointTrack,
    coarse: &Interpretation,
    cands: &[Vec<i64>],
    limit: &[i64],
    p: &DpParams,
    stats: &mut DpStats,
) -> Option<(f64, Vec<usize>, Vec<Column>)> {
    let l = coarse.segments.len();
    // Cell evaluations per segment: evals[i][ai * |c_{i+1}| + ci].
    let mut evals: Vec<Vec<Option<CellEval>>> = Vec::with_capacity(l);
    let mut cols: Vec<Vec<Option<Column>>> = Vec::with_capacity(l);
    for i in 0..l {
        let inst = coarse.segments[i].instance;
        let n = db_fine.instances[inst as usize].n() as i64;
        let mut ev = Vec::new();
        let mut cl = Vec::new();
        for &a in &cands[i] {
            for &c in &cands[i + 1] {
                let d = c - a;
                if d < 1 || (d - n).abs() > limit[i] {
                    ev.push(None);
                    cl.push(None);
                    continue;
                }
                let col = Column::new(db_fine, inst, d as usize);
                let e = eval_cell(x_fine, &col, a, &db_fine.control_weights);
                stats.cells_evaluated += 1;
                ev.push(e);
                cl.push(Some(col));
            }
        }
        evals.push(ev);
        cols.push(cl);
    }
    // V[i][(a, c)] = best score of segments 0..=i with segment i spanning (cands[i][a], cands[i+1][c]).
    let mut v: Vec<Vec<f64>> = Vec::with_capacity(l);
    let mut bp: Vec<Vec<usize>> = Vec::with_capacity(l);
    v.push(evals[0].iter().map(|e| e.as_ref().map_or(f64::INFINITY, |e| e.d)).collect());
    bp.push(vec![usize::MAX; evals[0].len()]);
    for i in 1..l {
        let (na, nb, nc) = (cands[i - 1].len(), cands[i].len(), cands[i + 1].len());
        let mut vi = vec![f64::INFINITY; nb * nc];
        let mut bi = vec![usize::MAX; nb * nc];
        for bj in 0..nb {
            for cj in 0..nc {
                let Some(e) = &evals[i][bj * nc + cj] else { continue };
                for ai in 0..na {
                    let prev = v[i - 1][ai * nb + bj];
                    let Some(pe) = &evals[i - 1][ai * nb + bj] else { continue };
                    if !prev.is_finite() {
                        continue;
                    }
                    stats.relaxations += 1;
                    let z = prev
                        + p.k * continuity(&pe.omega, &e.alpha, &db_fine.target_weights, p.continuity_order, p.k_vel)
                        + e.d;
                    if z < vi[bj * nc + cj] {
                        vi[bj * nc + cj] = z;
                        bi[bj * nc + cj] = ai;
                    }
                }
            }
        }
        v.push(vi);
        bp.push(bi);
    }
    let last = &v[l - 1];
    let (mut best, mut arg) = (f64::INFINITY, usize::MAX);
    for (j, &s) in last.iter().enumerate() {
        if s < best {
            best = s;
            arg = j;
        }
    }
    if !best.is_finite() {
        return None;
    }
    // Backtrack (a, c) index pairs.
    let mut pick = vec![0usize; l + 1];
    let nc_last = cands[l].len();
    pick[l] = arg % nc_last;
    pick[l - 1] = arg / nc_last;
    for i in (1..l).rev() {
        let nc = cands[i + 1].len();
        pick[i - 1] = bp[i][pick[i] * nc + pick[i + 1]];
    }
    let mut flat_cols = Vec::with_capacity(l);
    for i in 0..l {
        let nc = cands[i + 1].len();
        flat_cols.push(cols[i][pick[i] * nc + pick[i + 1]].clone()?);
    }
    Some((best, pick, flat_cols))
}

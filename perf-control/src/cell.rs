//! One DP cell (spec §3.5): instance `s` stretched to `d` intervals and placed on the input window
//! `[start, start + d]`. Shared by the DP sweep, the chain scorer and the refinement so that all
//! three score a cell identically.

use crate::align::align;
use crate::db::MappingDb;
use crate::track::{stretch_into, PointTrack};
use geom_core::math::{Planar, Vec3};

/// A legal (instance, duration) pair with its stretched control and target (spec §3.3, the
/// columns of the DP array).
#[derive(Clone, Debug)]
pub struct Column {
    /// Instance index.
    pub inst: u32,
    /// Duration in intervals at the working rate.
    pub d: usize,
    /// `a_s^d`: (d + 1) × K_c points.
    pub ctrl: Vec<Vec3>,
    /// `b_s^d`: (d + 1) × K_t points.
    pub tgt: Vec<Vec3>,
}

impl Column {
    /// Stretches instance `inst` of `db` to `d` intervals.
    pub fn new(db: &MappingDb, inst: u32, d: usize) -> Column {
        let i = &db.instances[inst as usize];
        let mut ctrl = Vec::new();
        let mut tgt = Vec::new();
        stretch_into(&i.control.data, i.control.n_points, d, &mut ctrl);
        stretch_into(&i.target.data, i.target.n_points, d, &mut tgt);
        Column { inst, d, ctrl, tgt }
    }
}

/// Legal durations of an instance of `n` intervals with stretch `delta` (spec §3.3):
/// `|d − n| ≤ Δ`, `d ≥ 1`.
pub fn legal_durations(n: usize, delta: usize) -> std::ops::RangeInclusive<usize> {
    n.saturating_sub(delta).max(1)..=n + delta
}

/// The quantities of a placed cell.
#[derive(Clone, Debug, Default)]
pub struct CellEval {
    /// `D`, scaled by `(d + 1)/#in-range` when partial (spec §3.5).
    pub d: f64,
    /// The alignment `M`.
    pub m: Planar,
    /// Placed first target sample `α` (K_t points), then its one-sided velocity (m/s).
    pub alpha: Vec<Vec3>,
    /// Placed last target sample `ω`, then its one-sided velocity.
    pub omega: Vec<Vec3>,
}

/// Evaluates the cell of column `col` starting at input frame `start` (may be negative or
/// overhang the end: only in-range samples enter `D`). `None` when fewer than 2 samples are in
/// range. `alpha`/`omega` hold `2·K_t` entries: positions then velocities.
pub fn eval_cell(x: &PointTrack, col: &Column, start: i64, wc: &[f64]) -> Option<CellEval> {
    let t_len = x.len() as i64;
    let end = start + col.d as i64;
    let lo = start.max(0);
    let hi = end.min(t_len - 1);
    let count = hi - lo + 1;
    if count < 2 {
        return None;
    }
    let kc = wc.len();
    let xs = &x.data[lo as usize * kc..(hi as usize + 1) * kc];
    let o = (lo - start) as usize;
    let a = &col.ctrl[o * kc..(o + count as usize) * kc];
    let al = align(xs, a, wc);
    let scale = (col.d + 1) as f64 / count as f64;
    let kt = col.tgt.len() / (col.d + 1);
    let rate = x.rate_hz;
    let m = al.m;
    let mut alpha = Vec::with_capacity(2 * kt);
    let mut omega = Vec::with_capacity(2 * kt);
    let last = col.d * kt;
    for p in 0..kt {
        alpha.push(m.apply_point(col.tgt[p]));
    }
    for p in 0..kt {
        omega.push(m.apply_point(col.tgt[last + p]));
    }
    for p in 0..kt {
        alpha.push(m.apply_dir(col.tgt[kt + p] - col.tgt[p]) * rate);
    }
    for p in 0..kt {
        omega.push(m.apply_dir(col.tgt[last + p] - col.tgt[last - kt + p]) * rate);
    }
    Some(CellEval { d: al.d * scale, m, alpha, omega })
}

/// Continuity `C` between a placed tail `omega` and head `alpha` (spec §3.4): `Σ_p w_p ‖ω − α‖²`,
/// plus `k_vel Σ_p w_p ‖v_out − v_in‖²` when `order = 1`.
#[inline]
pub fn continuity(omega: &[Vec3], alpha: &[Vec3], wt: &[f64], order: u8, k_vel: f64) -> f64 {
    let kt = wt.len();
    let mut c = 0.0;
    for p in 0..kt {
        c += wt[p] * (omega[p] - alpha[p]).norm_squared();
    }
    if order >= 1 {
        let mut v = 0.0;
        for p in 0..kt {
            v += wt[p] * (omega[kt + p] - alpha[kt + p]).norm_squared();
        }
        c += k_vel * v;
    }
    c
}

//! Every figure the scenes report (spec §3.11, §6, §9): parameter errors, the restricted
//! stiffness error, variability summaries, the cross-comparison diagonal, local minima of an
//! error map, the anytime curve.

use geom_core::stats::{max, mean};

use crate::objective::{EvalRecord, EvalStatus};
use crate::params::{FabricParams, ParamId, ParamSpace};
use crate::variability::ParamVariability;

/// Variability below which a parameter counts as identifiable (spec §3.11: 20 %).
pub const IDENTIFIABLE: f64 = 0.2;

/// Parameter error e of spec §3.11 for every free parameter: |ln(p̂/p*)| on log ranges,
/// |p̂ − p*|/(hi − lo) on linear ones.
pub fn param_errors(space: &ParamSpace, est: &FabricParams, truth: &FabricParams) -> Vec<(ParamId, f64)> {
    space.free.iter().map(|&id| (id, space.range(id).error(est.get(id), truth.get(id)))).collect()
}

/// The error of one parameter (NaN if it is not free).
pub fn error_of(errs: &[(ParamId, f64)], id: ParamId) -> f64 {
    errs.iter().find(|(i, _)| *i == id).map_or(f64::NAN, |(_, e)| *e)
}

/// The variability of one parameter (NaN if it was not analysed).
pub fn variability_of(v: &[ParamVariability], id: ParamId) -> f64 {
    v.iter().find(|p| p.id == id).map_or(f64::NAN, |p| p.variability)
}

/// `stiff_err` (spec §3.11): the largest error over {stretch, shear, bend} restricted to the
/// parameters whose variability at the truth is below 20 % (identifiable). NaN when none is.
pub fn stiff_err(errs: &[(ParamId, f64)], var_at_truth: &[ParamVariability]) -> f64 {
    let sel: Vec<f64> = ParamId::STIFFNESS
        .iter()
        .filter(|&&id| variability_of(var_at_truth, id) < IDENTIFIABLE)
        .map(|&id| error_of(errs, id))
        .collect();
    if sel.is_empty() {
        f64::NAN
    } else {
        max(&sel)
    }
}

/// `all_err` (spec §3.11): the mean error over all free parameters.
pub fn all_err(errs: &[(ParamId, f64)]) -> f64 {
    mean(&errs.iter().map(|e| e.1).collect::<Vec<_>>())
}

/// Rows of a square error matrix (row = footage, column = parameters) whose minimum is on the
/// diagonal (strictly smaller than every other entry of the row).
pub fn diagonal_minimal_rows(m: &[Vec<f64>]) -> usize {
    m.iter().enumerate().filter(|(i, row)| row.iter().enumerate().all(|(j, &v)| j == *i || row[*i] < v)).count()
}

/// Strict local minima of a grid (8-neighbourhood, every existing neighbour larger).
pub fn local_minima(grid: &[Vec<f64>]) -> Vec<(usize, usize)> {
    let n = grid.len();
    let mut out = Vec::new();
    for i in 0..n {
        let m = grid[i].len();
        for j in 0..m {
            let v = grid[i][j];
            let mut is_min = v.is_finite();
            for di in -1i64..=1 {
                for dj in -1i64..=1 {
                    if di == 0 && dj == 0 {
                        continue;
                    }
                    let (a, b) = (i as i64 + di, j as i64 + dj);
                    if a < 0 || b < 0 || a >= n as i64 || b >= grid[a as usize].len() as i64 {
                        continue;
                    }
                    if !(grid[a as usize][b as usize] > v) {
                        is_min = false;
                    }
                }
            }
            if is_min {
                out.push((i, j));
            }
        }
    }
    out
}

/// How many dynamic parameters are better determined (lower variability) by the waving test
/// than by the static test (spec §5: ≥ 4 of 6). A parameter whose static variability is not a
/// number (not analysed) does not count.
pub fn lower_variability_count(static_v: &[ParamVariability], waving_v: &[ParamVariability]) -> usize {
    ParamId::DYNAMIC
        .iter()
        .filter(|&&id| {
            let (s, w) = (variability_of(static_v, id), variability_of(waving_v, id));
            w < s
        })
        .count()
}

/// The anytime curve (spec §9): for every evaluation in `history` (in order), the cumulative
/// time, the best-so-far error and the parameter error of the best-so-far point.
pub fn anytime(history: &[EvalRecord], space: &ParamSpace, truth: &FabricParams) -> Vec<(f64, f64, f64)> {
    let mut best = f64::INFINITY;
    let mut best_err = f64::NAN;
    let mut out = Vec::with_capacity(history.len());
    for r in history {
        if r.status == EvalStatus::Ok && r.error < best {
            best = r.error;
            best_err = stiff_or_all(space, &r.params, truth);
        }
        out.push((r.t_s, best, best_err));
    }
    out
}

/// The bend error if bend is free (the best-identified parameter), else the mean error.
pub fn stiff_or_all(space: &ParamSpace, est: &FabricParams, truth: &FabricParams) -> f64 {
    let e = param_errors(space, est, truth);
    let b = error_of(&e, ParamId::Bend);
    if b.is_nan() {
        all_err(&e)
    } else {
        b
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn diagonal_and_minima() {
        let m = vec![vec![1.0, 2.0, 3.0], vec![2.0, 1.0, 0.5], vec![3.0, 3.0, 0.0]];
        assert_eq!(diagonal_minimal_rows(&m), 2);
        let g = vec![vec![3.0, 2.0, 3.0], vec![2.0, 1.0, 2.0], vec![3.0, 2.0, 0.5]];
        assert_eq!(local_minima(&g), vec![(2, 2)]);
        let flat = vec![vec![1.0, 1.0], vec![1.0, 1.0]];
        assert!(local_minima(&flat).is_empty());
    }
}

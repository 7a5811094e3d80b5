//! Preconditioners for [`super::pcg`]: the [`Preconditioner`] trait, [`Jacobi`] (diagonal) and
//! [`Ic0`] (zero-fill incomplete Cholesky, optionally modified: MIC(0)).
//!
//! IC(0)/MIC(0) follow Bridson's *Fluid Simulation for Computer Graphics* (2nd ed., §5.4,
//! "Modified Incomplete Cholesky"), written for general symmetric patterns: `L` has the
//! pattern of `A`'s lower triangle; every fill-in update `l_ik l_jk` that would land outside the
//! pattern is dropped (IC(0)), or, for MIC(0) with parameter `ω`, `ω·l_ik l_jk` is subtracted
//! from both diagonals `i` and `j` instead, so that for `ω = 1` the row sums of `L Lᵀ` equal those
//! of `A` (Bridson uses `ω = 0.97`). A pivot that falls to `≤ 0.25·a_kk` (`σ = 0.25`, Bridson's
//! safety rule) is replaced by `a_kk`, which keeps the factor SPD on any SPD input.

use super::{Csr, DOT_CHUNK};
use crate::error::{Error, Result};
use rayon::prelude::*;

/// Pivot safety factor `σ` of [`Ic0`]: a pivot `≤ σ·a_kk` is replaced by `a_kk`.
pub const IC0_PIVOT_SIGMA: f64 = 0.25;

/// An SPD approximation `M ≈ A` applied as `z = M⁻¹ r`.
pub trait Preconditioner: Sync {
    /// `z = M⁻¹ r` (`z` is output only; both have the system size).
    fn apply(&self, r: &[f64], z: &mut [f64]);
}

/// The identity: plain conjugate gradients.
#[derive(Clone, Copy, Debug, Default)]
pub struct Identity;

impl Preconditioner for Identity {
    fn apply(&self, r: &[f64], z: &mut [f64]) {
        z.copy_from_slice(r);
    }
}

/// Diagonal (Jacobi) preconditioner `M = diag(A)`.
#[derive(Clone, Debug)]
pub struct Jacobi {
    inv_diag: Vec<f64>,
}

/// The diagonal of a square matrix, checked to be finite and positive (an SPD necessity).
fn positive_diagonal(a: &Csr, who: &'static str) -> Result<Vec<f64>> {
    if a.nrows != a.ncols {
        return Err(Error::DimensionMismatch { what: who, expected: a.nrows, got: a.ncols });
    }
    if !super::all_finite(&a.val) {
        return Err(Error::NonFinite(who));
    }
    (0..a.nrows)
        .map(|i| {
            let d = a.get(i, i);
            if d > 0.0 {
                Ok(d)
            } else {
                Err(Error::NotPositiveDefinite { column: i })
            }
        })
        .collect()
}

impl Jacobi {
    /// From the diagonal of `a`. Errors: not square (`DimensionMismatch`), non-finite values
    /// (`NonFinite`), a diagonal entry `≤ 0` or missing (`NotPositiveDefinite` naming it).
    pub fn new(a: &Csr) -> Result<Self> {
        let d = positive_diagonal(a, "Jacobi::new: matrix")?;
        Ok(Self { inv_diag: d.iter().map(|d| 1.0 / d).collect() })
    }
}

impl Preconditioner for Jacobi {
    fn apply(&self, r: &[f64], z: &mut [f64]) {
        z.par_iter_mut()
            .with_min_len(DOT_CHUNK)
            .zip(r.par_iter().zip(self.inv_diag.par_iter()))
            .for_each(|(zi, (ri, di))| *zi = ri * di);
    }
}

/// Incomplete Cholesky `M = L Lᵀ` with zero fill, IC(0) or MIC(0); see the module docs.
///
/// Stored as `M = L̂ D² L̂ᵀ` with `L̂ = L D⁻¹` unit lower triangular and `D = diag(L)`, so that
/// applying `M⁻¹` is two sequential triangular solves without divisions (their dependency
/// chains are latency-bound) and one diagonal scaling. Deterministic.
#[derive(Clone, Debug)]
pub struct Ic0 {
    n: usize,
    /// Strictly lower part of `L̂` by columns: rows of column `k` are
    /// `row[col_ptr[k]..col_ptr[k + 1]]`, increasing.
    col_ptr: Vec<usize>,
    row: Vec<u32>,
    val: Vec<f64>,
    /// `1 / L_kk²`.
    inv_d2: Vec<f64>,
    /// Number of pivots replaced by the `σ` safety rule.
    replaced: usize,
}

impl Ic0 {
    /// Factors the symmetric matrix `a` (its lower triangle is read). `modified`: `None` for
    /// IC(0), `Some(ω)` with `0 ≤ ω ≤ 1` for MIC(0) (FT uses 0.97).
    ///
    /// Errors: not square, non-finite values, a diagonal entry `≤ 0` (`NotPositiveDefinite`),
    /// `ω` outside `[0, 1]` (`InvalidParameter`).
    pub fn new(a: &Csr, modified: Option<f64>) -> Result<Self> {
        let a_diag = positive_diagonal(a, "Ic0::new: matrix")?;
        let omega = modified.unwrap_or(0.0);
        if !(0.0..=1.0).contains(&omega) {
            return Err(Error::InvalidParameter(format!("Ic0::new: MIC(0) parameter ω = {omega} must lie in [0, 1]")));
        }
        let n = a.nrows;
        // Strictly lower triangle by columns (a transpose of the rows' j < i entries).
        let mut col_ptr = vec![0usize; n + 1];
        for i in 0..n {
            for &j in a.row(i).0 {
                if (j as usize) < i {
                    col_ptr[j as usize + 1] += 1;
                }
            }
        }
        for k in 0..n {
            col_ptr[k + 1] += col_ptr[k];
        }
        let mut cursor = col_ptr.clone();
        let mut row = vec![0u32; col_ptr[n]];
        let mut val = vec![0.0; col_ptr[n]];
        for i in 0..n {
            let (c, v) = a.row(i);
            for (&j, &x) in c.iter().zip(v) {
                if (j as usize) < i {
                    let p = &mut cursor[j as usize];
                    row[*p] = i as u32;
                    val[*p] = x;
                    *p += 1;
                }
            }
        }
        // Right-looking elimination restricted to the pattern; `d` holds the running pivots.
        let mut d = a_diag.clone();
        let mut lkk_all = vec![0.0; n];
        let mut replaced = 0;
        for k in 0..n {
            let mut dk = d[k];
            // Written so that a NaN pivot is also replaced.
            let safe = dk > IC0_PIVOT_SIGMA * a_diag[k];
            if !safe {
                dk = a_diag[k];
                replaced += 1;
            }
            let lkk = dk.sqrt();
            lkk_all[k] = lkk;
            let (s, e) = (col_ptr[k], col_ptr[k + 1]);
            for v in &mut val[s..e] {
                *v /= lkk;
            }
            for p in s..e {
                let i = row[p] as usize;
                let lik = val[p];
                d[i] -= lik * lik;
                // Pairs (i, j) with k < j < i, both in column k: update l_ij, or drop it.
                for q in s..p {
                    let j = row[q] as usize;
                    let update = lik * val[q];
                    let cj = &row[col_ptr[j]..col_ptr[j + 1]];
                    match cj.binary_search(&(i as u32)) {
                        Ok(t) => val[col_ptr[j] + t] -= update,
                        Err(_) => {
                            if omega != 0.0 {
                                d[i] -= omega * update;
                                d[j] -= omega * update;
                            }
                        }
                    }
                }
            }
        }
        // L̂ = L D⁻¹: scale column k by 1 / L_kk.
        for k in 0..n {
            for v in &mut val[col_ptr[k]..col_ptr[k + 1]] {
                *v /= lkk_all[k];
            }
        }
        let inv_d2 = lkk_all.iter().map(|l| 1.0 / (l * l)).collect();
        Ok(Self { n, col_ptr, row, val, inv_d2, replaced })
    }

    /// How many pivots were replaced by `a_kk` (the `σ = 0.25` safety rule).
    pub fn replaced_pivots(&self) -> usize {
        self.replaced
    }
}

impl Preconditioner for Ic0 {
    fn apply(&self, r: &[f64], z: &mut [f64]) {
        debug_assert!(r.len() == self.n && z.len() == self.n);
        z.copy_from_slice(r);
        // Forward: L̂ w = r, column-oriented (unit diagonal).
        for k in 0..self.n {
            let wk = z[k];
            let (s, e) = (self.col_ptr[k], self.col_ptr[k + 1]);
            for (&i, &v) in self.row[s..e].iter().zip(&self.val[s..e]) {
                z[i as usize] -= v * wk;
            }
        }
        // y = D⁻² w.
        for (zk, s) in z.iter_mut().zip(&self.inv_d2) {
            *zk *= s;
        }
        // Backward: L̂ᵀ x = y (row k of L̂ᵀ is column k of L̂).
        for k in (0..self.n).rev() {
            let (s, e) = (self.col_ptr[k], self.col_ptr[k + 1]);
            let mut acc = z[k];
            for (&i, &v) in self.row[s..e].iter().zip(&self.val[s..e]) {
                acc -= v * z[i as usize];
            }
            z[k] = acc;
        }
    }
}

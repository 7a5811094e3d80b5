//! [`SparseLlt`]: sparse Cholesky `A = L Lᵀ` of symmetric positive definite matrices, with the
//! symbolic analysis computed once per pattern and numeric refactorisation every step.
//!
//! Wraps faer 0.24's low-level supernodal/simplicial Cholesky (`SymbolicCholesky`,
//! `factorize_numeric_llt`, `LltRef`); see `faer-notes.md`. Only the lower triangle of the
//! input is read.
//!
//! Failure modes, all typed: a NaN or infinite value in the matrix or the right-hand side gives
//! [`Error::NonFinite`] (never a NaN solution); a non-positive pivot, or one that is
//! numerically zero (`d_k ≤` [`SINGULAR_PIVOT_TOL`]` · a_kk`: the matrix is singular to working
//! precision), gives [`Error::NotPositiveDefinite`] naming the original column. Shells reacts by
//! retrying with a diagonal shift.
//!
//! Determinism: factor and solve run with `Par::Seq` unless [`SparseLlt::set_par`] asks for
//! Rayon; faer's parallel supernodal factorisation changes the last bits with the thread count.

use super::csc::Csc;
use super::symbolic::{LltSymbolic, Ordering};
use crate::error::{Error, Result};
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::cholesky::llt::factor::LltError;
use faer::prelude::{Reborrow, ReborrowMut};
use faer::sparse::linalg::cholesky::{
    simplicial::SimplicialLltRef, supernodal::SupernodalLltRef, LltRef, SymbolicCholeskyRaw,
};
use faer::{Conj, Mat, MatMut, Par, Side};

/// Default relative pivot threshold below which [`SparseLlt::factor`] reports a matrix as
/// numerically singular: pivot `d_k = L_kk²` with `d_k ≤ SINGULAR_PIVOT_TOL · a_kk`.
///
/// Why this value: every ratio `d_k / a_kk` is at least the smallest eigenvalue of the
/// unit-diagonal scaling `D^{-1/2} A D^{-1/2}` (whose largest eigenvalue is ≥ 1), so only
/// matrices with a scaled condition number above 10¹⁰ can trip it (their solutions keep fewer
/// than ~6 correct digits). An exactly singular PSD matrix does not always produce a
/// non-positive pivot: rounding leaves one of size ≈ n·ε·a_kk (measured on free-boundary 2-D
/// Laplacians: 1.1e-12 at n = 4·10⁴, 2.4e-12 at 9·10⁴), which this threshold catches up to
/// ~10⁶–10⁷ unknowns. Change it per factorisation with [`SparseLlt::set_singular_tol`].
pub const SINGULAR_PIVOT_TOL: f64 = 1e-10;

/// Sparse Cholesky factorisation of an SPD matrix; see the module docs.
#[derive(Clone, Debug)]
pub struct SparseLlt {
    symbolic: LltSymbolic,
    /// Numeric values of `L` (length `symbolic.nnz_l()`), valid when `factored`.
    values: Vec<f64>,
    factored: bool,
    /// faer parallelism for factor and solve (default `Par::Seq`; see [`PARALLELISM_NOTE`]).
    par: Par,
    /// `min_k L_kk² / a_kk` of the last successful factorisation.
    min_pivot_ratio: f64,
    /// Singularity threshold on `L_kk² / a_kk` (default [`SINGULAR_PIVOT_TOL`]).
    singular_tol: f64,
}

impl SparseLlt {
    /// Symbolic analysis of `a`'s pattern (lower triangle) with the given ordering; call
    /// [`SparseLlt::factor`] before solving.
    pub fn analyze(a: &Csc, ordering: Ordering) -> Result<Self> {
        Ok(Self::from_symbolic(&LltSymbolic::analyze(a, &ordering)?))
    }

    /// A factorisation object sharing an existing analysis (cheap): e.g. tracks reuses the
    /// analysis of shells' Hessian.
    pub fn from_symbolic(s: &LltSymbolic) -> Self {
        Self {
            symbolic: s.clone(),
            values: Vec::new(),
            factored: false,
            par: Par::Seq,
            min_pivot_ratio: f64::NAN,
            singular_tol: SINGULAR_PIVOT_TOL,
        }
    }

    /// Numeric factorisation of `a`, which must have exactly the analysed pattern; reuses the
    /// symbolic analysis (no ordering, no allocation after the first call). On error the object
    /// is left unfactored.
    pub fn factor(&mut self, a: &Csc) -> Result<()> {
        self.factored = false;
        self.symbolic.check_pattern(a, "SparseLlt::factor: matrix")?;
        let s = &self.symbolic.inner;
        self.values.resize(s.chol.len_val(), 0.0);
        let par = self.par;
        let mut mem = MemBuffer::try_new(s.chol.factorize_numeric_llt_scratch::<f64>(par, Default::default()))
            .map_err(|_| Error::Factorization("SparseLlt::factor: out of memory for scratch space".into()))?;
        let res = s.chol.factorize_numeric_llt(
            &mut self.values,
            a.as_ref(),
            Side::Lower,
            Default::default(),
            par,
            MemStack::new(&mut mem),
            Default::default(),
        );
        if let Err(LltError::NonPositivePivot { index }) = res {
            // faer reports the simplicial pivot 1-based and the supernodal one 0-based (0.24.4).
            let k = match s.chol.raw() {
                SymbolicCholeskyRaw::Simplicial(_) => index.saturating_sub(1),
                SymbolicCholeskyRaw::Supernodal(_) => index,
            };
            return Err(Error::NotPositiveDefinite { column: s.perm[k.min(s.perm.len() - 1)] });
        }
        self.min_pivot_ratio = self.check_pivots(a)?;
        self.factored = true;
        Ok(())
    }

    /// Rejects numerically singular matrices (pivot `L_kk² ≤ singular_tol · a_kk`);
    /// returns the smallest ratio `L_kk² / a_kk`.
    fn check_pivots(&self, a: &Csc) -> Result<f64> {
        let s = &self.symbolic.inner;
        let val = a.val();
        let mut min_ratio = f64::INFINITY;
        let mut check = |k: usize, l_kk: f64| -> Result<()> {
            let old = s.perm[k];
            let a_kk = match s.diag_pos[old] {
                usize::MAX => 0.0,
                p => val[p],
            };
            // Written so that a NaN pivot also fails.
            let positive = l_kk * l_kk > self.singular_tol * a_kk;
            if !positive {
                return Err(Error::NotPositiveDefinite { column: old });
            }
            min_ratio = min_ratio.min(l_kk * l_kk / a_kk);
            Ok(())
        };
        match s.chol.raw() {
            SymbolicCholeskyRaw::Simplicial(sym) => {
                let l = SimplicialLltRef::new(sym, &self.values);
                let col_ptr = sym.col_ptr();
                for (k, &start) in col_ptr[..sym.nrows()].iter().enumerate() {
                    // The first stored entry of each column of L is its diagonal.
                    check(k, l.values()[start])?;
                }
            }
            SymbolicCholeskyRaw::Supernodal(sym) => {
                let l = SupernodalLltRef::new(sym, &self.values);
                for sn in 0..sym.n_supernodes() {
                    let node = l.supernode(sn);
                    let m = node.val();
                    for c in 0..m.ncols() {
                        check(node.start() + c, m[(c, c)])?;
                    }
                }
            }
        }
        Ok(min_ratio)
    }

    /// Solves `A x = b` in place (`x` holds `b` on entry).
    ///
    /// Errors: not factored (`InvalidParameter`), wrong length (`DimensionMismatch`), non-finite
    /// right-hand side or solution (`NonFinite`).
    pub fn solve_in_place(&self, x: &mut [f64]) -> Result<()> {
        let n = self.symbolic.n();
        if x.len() != n {
            return Err(Error::DimensionMismatch { what: "SparseLlt::solve_in_place: rhs", expected: n, got: x.len() });
        }
        self.solve_mat(MatMut::from_column_major_slice_mut(x, n, 1))
    }

    /// Solves `A X = B` for several right-hand sides at once (the columns of `x`, overwritten).
    pub fn solve_many_in_place(&self, x: &mut Mat<f64>) -> Result<()> {
        let n = self.symbolic.n();
        if x.nrows() != n {
            return Err(Error::DimensionMismatch {
                what: "SparseLlt::solve_many_in_place: rhs rows",
                expected: n,
                got: x.nrows(),
            });
        }
        self.solve_mat(x.as_mut())
    }

    fn solve_mat(&self, mut x: MatMut<'_, f64>) -> Result<()> {
        if !self.factored {
            return Err(Error::InvalidParameter("SparseLlt: solve called before a successful factor".into()));
        }
        if !mat_is_finite(x.rb()) {
            return Err(Error::NonFinite("SparseLlt::solve: right-hand side"));
        }
        let s = &self.symbolic.inner;
        let par = self.par;
        let mut mem = MemBuffer::try_new(s.chol.solve_in_place_scratch::<f64>(x.ncols(), par))
            .map_err(|_| Error::Factorization("SparseLlt::solve: out of memory for scratch space".into()))?;
        LltRef::new(&s.chol, &self.values).solve_in_place_with_conj(Conj::No, x.rb_mut(), par, MemStack::new(&mut mem));
        if !mat_is_finite(x.rb()) {
            return Err(Error::NonFinite("SparseLlt::solve: solution (overflow)"));
        }
        Ok(())
    }

    /// Sets the faer parallelism of later factorisations and solves. The default, `Par::Seq`,
    /// is bitwise reproducible on every machine; `Par::rayon(t)` is faster on large (3-D)
    /// factorisations and reproducible run to run for a fixed `t`, but its results differ in
    /// the last bits between thread counts (faer 0.24.4's supernodal scheduling).
    pub fn set_par(&mut self, par: Par) {
        self.par = par;
    }

    /// The elimination order, `perm[new] = old`.
    pub fn perm(&self) -> &[usize] {
        self.symbolic.perm()
    }

    /// Stored values of `L` (see [`LltSymbolic::nnz_l`]).
    pub fn nnz_l(&self) -> usize {
        self.symbolic.nnz_l()
    }

    /// The shared symbolic analysis (a cheap reference-counted clone).
    pub fn symbolic(&self) -> LltSymbolic {
        self.symbolic.clone()
    }

    /// Smallest pivot ratio `L_kk² / a_kk` of the last successful factorisation (NaN before
    /// one). Every pivot ratio is at least the smallest eigenvalue of the unit-diagonal scaling
    /// `D^{-1/2} A D^{-1/2}`, so a tiny ratio proves near-singularity (the converse does not
    /// hold: a singular matrix can leave a rounding-level pivot that is not tiny).
    pub fn min_pivot_ratio(&self) -> f64 {
        self.min_pivot_ratio
    }

    /// Sets the singularity threshold on `L_kk² / a_kk` used by later factorisations (default
    /// [`SINGULAR_PIVOT_TOL`]; `0` rejects only non-positive pivots). Negative or non-finite
    /// values are an `InvalidParameter` error.
    pub fn set_singular_tol(&mut self, tol: f64) -> Result<()> {
        if !(tol >= 0.0 && tol.is_finite()) {
            return Err(Error::InvalidParameter(format!("SparseLlt::set_singular_tol: {tol} must be finite and >= 0")));
        }
        self.singular_tol = tol;
        Ok(())
    }

    /// True after a successful [`SparseLlt::factor`].
    pub fn is_factored(&self) -> bool {
        self.factored
    }
}

/// True when every entry of `m` is finite.
pub(crate) fn mat_is_finite(m: faer::MatRef<'_, f64>) -> bool {
    (0..m.ncols()).all(|j| (0..m.nrows()).all(|i| m[(i, j)].is_finite()))
}

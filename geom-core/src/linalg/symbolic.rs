//! Fill-reducing [`Ordering`]s and [`LltSymbolic`], the symbolic analysis of a symmetric sparsity
//! pattern shared by [`super::SparseLlt`] and [`super::SparseLdlt`].
//!
//! The analysis (ordering, elimination tree, supernodes) depends only on the pattern, so it is
//! computed once and reused for every numeric factorisation with the same pattern (a time
//! step, a Newton iteration). Cloning an [`LltSymbolic`] is a reference-count increment.

use super::csc::Csc;
use crate::error::{Error, Result};
use faer::perm::PermRef;
use faer::sparse::linalg::cholesky::{
    factorize_symbolic_cholesky, CholeskySymbolicParams, SymbolicCholesky, SymmetricOrdering,
};
use faer::Side;
use std::sync::Arc;

/// Fill-reducing ordering for the sparse Cholesky/LDLᵀ factorisations.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub enum Ordering {
    /// Approximate minimum degree (faer's AMD). The default.
    #[default]
    Amd,
    /// No reordering (the matrix's own order).
    Natural,
    /// A given permutation, `perm[new] = old`: row/column `perm[k]` of the matrix is eliminated
    /// `k`-th. Used to put constraint rows last in a KKT system (tracks) by extending the
    /// primal block's AMD order ([`super::SparseLlt::perm`]).
    Custom(Vec<usize>),
}

/// The shared, immutable part of a symbolic analysis.
#[derive(Debug)]
pub(crate) struct SymbolicInner {
    pub(crate) chol: SymbolicCholesky<usize>,
    /// Pattern of the analysed matrix, to check that later numeric factorisations match it.
    col_ptr: Vec<usize>,
    col_nnz: Option<Vec<usize>>,
    row_idx: Vec<usize>,
    /// `perm[new] = old` (the identity for [`Ordering::Natural`]).
    pub(crate) perm: Vec<usize>,
    /// `diag_pos[j]`: index into the value array of the diagonal entry of column `j`, or
    /// `usize::MAX` when the diagonal is not stored.
    pub(crate) diag_pos: Vec<usize>,
}

/// The symbolic analysis of a symmetric sparsity pattern (ordering, elimination tree,
/// supernodal structure), reference counted: clone it freely to share one analysis between
/// several factorisations of matrices with the same pattern.
#[derive(Clone, Debug)]
pub struct LltSymbolic {
    pub(crate) inner: Arc<SymbolicInner>,
}

impl LltSymbolic {
    /// Analyses the lower triangle of the square matrix `a` (values are not read).
    ///
    /// Errors: `DimensionMismatch` if `a` is not square; `InvalidParameter` if a custom
    /// ordering is not a permutation of `0..n`; `Factorization` if faer's analysis fails
    /// (out of memory, index overflow).
    pub fn analyze(a: &Csc, ordering: &Ordering) -> Result<Self> {
        let n = a.nrows();
        if a.ncols() != n {
            return Err(Error::DimensionMismatch {
                what: "symbolic analysis: matrix columns",
                expected: n,
                got: a.ncols(),
            });
        }
        // faer 0.24.4's `SymmetricOrdering::Identity` analyses the given triangle as if it were
        // the upper one (wrong elimination tree for `Side::Lower`, then an index panic), so the
        // natural order is passed as an explicit identity permutation.
        let identity: Vec<usize>;
        let custom: &[usize] = match ordering {
            Ordering::Amd => &[],
            Ordering::Natural => {
                identity = (0..n).collect();
                &identity
            }
            Ordering::Custom(p) => p,
        };
        let custom_inv;
        let ord = match ordering {
            Ordering::Amd => SymmetricOrdering::Amd,
            Ordering::Natural | Ordering::Custom(_) => {
                custom_inv = inverse_permutation(custom, n)?;
                SymmetricOrdering::Custom(PermRef::new_checked(custom, &custom_inv, n))
            }
        };
        let chol = factorize_symbolic_cholesky(a.symbolic(), Side::Lower, ord, CholeskySymbolicParams::default())
            .map_err(|e| Error::Factorization(format!("symbolic analysis: {e:?}")))?;
        let perm = match chol.perm() {
            Some(p) => p.arrays().0.to_vec(),
            None => (0..n).collect(), // not produced by the orderings above; kept for safety
        };
        let sym = a.symbolic();
        let diag_pos = (0..n)
            .map(|j| {
                let range = sym.col_range(j);
                let start = range.start;
                sym.row_idx_of_col_raw(j).iter().position(|&i| i == j).map_or(usize::MAX, |p| start + p)
            })
            .collect();
        let (_, _, col_ptr, col_nnz, row_idx) = sym.parts();
        Ok(Self {
            inner: Arc::new(SymbolicInner {
                chol,
                col_ptr: col_ptr.to_vec(),
                col_nnz: col_nnz.map(|c| c.to_vec()),
                row_idx: row_idx.to_vec(),
                perm,
                diag_pos,
            }),
        })
    }

    /// Matrix size `n`.
    pub fn n(&self) -> usize {
        self.inner.perm.len()
    }

    /// The elimination order, `perm[new] = old`.
    pub fn perm(&self) -> &[usize] {
        &self.inner.perm
    }

    /// Number of stored values of the factor `L` (supernodal blocks count their explicit zeros):
    /// the memory, and roughly the work, of a numeric factorisation.
    pub fn nnz_l(&self) -> usize {
        self.inner.chol.len_val()
    }

    /// Checks that `a` has exactly the analysed pattern (same size and column/row structure).
    pub(crate) fn check_pattern(&self, a: &Csc, who: &'static str) -> Result<()> {
        let n = self.n();
        if a.nrows() != n || a.ncols() != n {
            return Err(Error::DimensionMismatch { what: who, expected: n, got: a.nrows() });
        }
        let (_, _, col_ptr, col_nnz, row_idx) = a.symbolic().parts();
        let s = &self.inner;
        if col_ptr != s.col_ptr.as_slice() || col_nnz != s.col_nnz.as_deref() || row_idx != s.row_idx.as_slice() {
            return Err(Error::InvalidParameter(format!(
                "{who}: the matrix's sparsity pattern differs from the analysed one (analyse it again)"
            )));
        }
        if !super::all_finite(a.val()) {
            return Err(Error::NonFinite(who));
        }
        Ok(())
    }
}

/// Checks that `p` is a permutation of `0..n` and returns its inverse.
fn inverse_permutation(p: &[usize], n: usize) -> Result<Vec<usize>> {
    if p.len() != n {
        return Err(Error::DimensionMismatch { what: "Ordering::Custom permutation", expected: n, got: p.len() });
    }
    let mut inv = vec![usize::MAX; n];
    for (new, &old) in p.iter().enumerate() {
        if old >= n || inv[old] != usize::MAX {
            return Err(Error::InvalidParameter(format!(
                "Ordering::Custom: entry {new} = {old} is out of range or repeated (not a permutation of 0..{n})"
            )));
        }
        inv[old] = new;
    }
    Ok(inv)
}

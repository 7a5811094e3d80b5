//! [`Csc`], faer's compressed sparse column matrix: the input type of the direct solvers, and the
//! conversions between it and our [`Csr`].
//!
//! Convention (GEOM-CORE.md §3.7): a symmetric matrix handed to a direct solver is read through
//! its **lower triangle** (rows ≥ columns); entries above the diagonal, if stored, are ignored.
//! [`sym_mul_vec`] and [`rel_residual`] follow the same convention, so a residual is always
//! computed for the matrix the factorisation saw.

use super::Csr;
use faer::sparse::{SparseColMat, SymbolicSparseColMat};

/// Compressed sparse column matrix with `usize` indices (faer's `SparseColMat`).
pub type Csc = SparseColMat<usize, f64>;

/// Builds a [`Csc`] from columns given as `(col_ptr, row_idx, val)` with sorted, distinct rows.
/// The caller guarantees the invariants (they are checked by faer, which panics otherwise).
pub(crate) fn csc_from_parts(
    nrows: usize,
    ncols: usize,
    col_ptr: Vec<usize>,
    row_idx: Vec<usize>,
    val: Vec<f64>,
) -> Csc {
    SparseColMat::new(SymbolicSparseColMat::new_checked(nrows, ncols, col_ptr, None, row_idx), val)
}

impl Csr {
    /// Converts to a [`Csc`] holding every stored entry (explicit zeros kept).
    pub fn to_csc(&self) -> Csc {
        self.to_csc_filtered(|_, _| true)
    }

    /// Converts to a [`Csc`] holding only the lower triangle (`row ≥ col`): the storage the
    /// direct solvers read for a symmetric matrix.
    pub fn to_csc_lower(&self) -> Csc {
        self.to_csc_filtered(|i, j| i >= j)
    }

    fn to_csc_filtered(&self, keep: impl Fn(usize, usize) -> bool) -> Csc {
        let mut col_ptr = vec![0usize; self.ncols + 1];
        for i in 0..self.nrows {
            for &j in self.row(i).0 {
                if keep(i, j as usize) {
                    col_ptr[j as usize + 1] += 1;
                }
            }
        }
        for j in 0..self.ncols {
            col_ptr[j + 1] += col_ptr[j];
        }
        let nnz = col_ptr[self.ncols];
        let mut cursor = col_ptr.clone();
        let mut row_idx = vec![0usize; nnz];
        let mut val = vec![0.0; nnz];
        // Rows are visited in increasing order, so every column's rows come out sorted.
        for i in 0..self.nrows {
            let (c, v) = self.row(i);
            for (&j, &a) in c.iter().zip(v) {
                if keep(i, j as usize) {
                    let k = &mut cursor[j as usize];
                    row_idx[*k] = i;
                    val[*k] = a;
                    *k += 1;
                }
            }
        }
        csc_from_parts(self.nrows, self.ncols, col_ptr, row_idx, val)
    }

    /// Converts a [`Csc`] (any faer layout: unsorted rows and per-column lengths allowed;
    /// duplicates are summed in storage order) to a [`Csr`]. Stores exactly what `a` stores: a
    /// lower-triangle matrix stays lower-triangular.
    ///
    /// # Panics
    /// If `a` has more than `u32::MAX` columns.
    pub fn from_csc(a: &Csc) -> Csr {
        assert!(a.ncols() <= u32::MAX as usize, "Csr::from_csc: too many columns for u32 indices");
        let mut t = super::Triplets::with_capacity(a.nrows(), a.ncols(), a.val().len());
        let sym = a.symbolic();
        for j in 0..a.ncols() {
            for (&i, &v) in sym.row_idx_of_col_raw(j).iter().zip(a.val_of_col(j)) {
                t.push(i as u32, j as u32, v);
            }
        }
        Csr::from_triplets(&t)
    }
}

/// `y = A x` for the symmetric matrix whose lower triangle is stored in `a` (entries above the
/// diagonal are ignored; see the module docs).
///
/// # Panics
/// If `a` is not square or the lengths do not match.
pub fn sym_mul_vec(a: &Csc, x: &[f64], y: &mut [f64]) {
    let n = a.nrows();
    assert_eq!(a.ncols(), n, "sym_mul_vec: matrix is not square");
    assert!(x.len() == n && y.len() == n, "sym_mul_vec: vector length differs from the matrix size");
    y.fill(0.0);
    let sym = a.symbolic();
    for j in 0..n {
        let xj = x[j];
        let mut yj = 0.0;
        for (&i, &v) in sym.row_idx_of_col_raw(j).iter().zip(a.val_of_col(j)) {
            if i > j {
                y[i] += v * xj;
                yj += v * x[i];
            } else if i == j {
                yj += v * xj;
            }
        }
        y[j] += yj;
    }
}

/// Relative residual `‖b − A x‖₂ / ‖b‖₂` of a symmetric system stored as its lower triangle
/// (the absolute residual `‖A x‖₂` when `b = 0`). The yardstick of the direct-solver tests.
///
/// # Panics
/// If the shapes do not match (see [`sym_mul_vec`]).
pub fn rel_residual(a: &Csc, x: &[f64], b: &[f64]) -> f64 {
    assert_eq!(b.len(), a.nrows(), "rel_residual: b has the wrong length");
    let mut r = vec![0.0; b.len()];
    sym_mul_vec(a, x, &mut r);
    for (ri, bi) in r.iter_mut().zip(b) {
        *ri = bi - *ri;
    }
    let nb = super::norm2(b);
    let nr = super::norm2(&r);
    if nb > 0.0 {
        nr / nb
    } else {
        nr
    }
}

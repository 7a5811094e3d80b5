//! Small dense helpers over `faer::Mat<f64>`: Cholesky ([`llt`]), numerical rank ([`rank`]) and
//! the matrix product ([`matmul`], faer's with the vector-register state cleaned up after it, see
//! [`super::zero_upper`]), with the same typed errors as the sparse solvers (tracks' Schur
//! complements, barnet's small constraint blocks).

use crate::error::{Error, Result};
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::cholesky::llt::factor::{cholesky_in_place, cholesky_in_place_scratch, LltError};
use faer::linalg::cholesky::llt::solve::{solve_in_place_scratch, solve_in_place_with_conj};
use faer::prelude::{Reborrow, ReborrowMut};
use faer::{Conj, Mat, MatMut, MatRef, Par};

/// A dense Cholesky factorisation `A = L Lᵀ`, computed and applied with `Par::Seq` so results
/// are bitwise reproducible on any machine (these matrices are small).
#[derive(Clone, Debug)]
pub struct DenseLlt {
    /// Lower-triangular factor (upper part zero).
    l: Mat<f64>,
}

fn is_finite(m: MatRef<'_, f64>) -> bool {
    super::llt::mat_is_finite(m)
}

/// `C = α·A·B` (`accum = Replace`) or `C += α·A·B` (`Accum::Add`): faer's `matmul` followed by
/// [`super::zero_upper`]. Call this instead of faer's `matmul` directly: faer leaves the upper
/// halves of the vector registers dirty, which slows later scalar code 15–21× until something
/// cleans the state (see the `upper_state` module docs).
pub fn matmul(c: MatMut<'_, f64>, accum: faer::Accum, a: MatRef<'_, f64>, b: MatRef<'_, f64>, alpha: f64, par: Par) {
    faer::linalg::matmul::matmul(c, accum, a, b, alpha, par);
    super::zero_upper();
}

/// Cholesky factorisation of a symmetric positive definite matrix (lower triangle read).
///
/// Errors: not square (`DimensionMismatch`), NaN/∞ (`NonFinite`), a non-positive pivot
/// (`NotPositiveDefinite { column }`).
pub fn llt(a: &Mat<f64>) -> Result<DenseLlt> {
    let n = a.nrows();
    if a.ncols() != n {
        return Err(Error::DimensionMismatch { what: "dense::llt: matrix columns", expected: n, got: a.ncols() });
    }
    if !is_finite(a.as_ref()) {
        return Err(Error::NonFinite("dense::llt: matrix"));
    }
    let mut l = Mat::from_fn(n, n, |i, j| if i >= j { a[(i, j)] } else { 0.0 });
    let mut mem = MemBuffer::try_new(cholesky_in_place_scratch::<f64>(n, Par::Seq, Default::default()))
        .map_err(|_| Error::Factorization("dense::llt: out of memory for scratch space".into()))?;
    match cholesky_in_place(l.as_mut(), Default::default(), Par::Seq, MemStack::new(&mut mem), Default::default()) {
        Ok(_) => {
            // faer leaves the strict upper triangle untouched (zero here).
            Ok(DenseLlt { l })
        }
        Err(LltError::NonPositivePivot { index }) => Err(Error::NotPositiveDefinite { column: index }),
    }
}

impl DenseLlt {
    /// Matrix size.
    pub fn n(&self) -> usize {
        self.l.nrows()
    }

    /// The lower-triangular factor `L`.
    pub fn l(&self) -> MatRef<'_, f64> {
        self.l.as_ref()
    }

    /// Solves `A x = b` in place. Errors: wrong length, non-finite right-hand side.
    pub fn solve_in_place(&self, x: &mut [f64]) -> Result<()> {
        let n = self.n();
        if x.len() != n {
            return Err(Error::DimensionMismatch { what: "DenseLlt::solve_in_place: rhs", expected: n, got: x.len() });
        }
        self.solve_mat(MatMut::from_column_major_slice_mut(x, n, 1))
    }

    /// Solves `A X = B` in place for the columns of `x`.
    pub fn solve_many_in_place(&self, x: &mut Mat<f64>) -> Result<()> {
        let n = self.n();
        if x.nrows() != n {
            return Err(Error::DimensionMismatch {
                what: "DenseLlt::solve_many_in_place: rhs rows",
                expected: n,
                got: x.nrows(),
            });
        }
        self.solve_mat(x.as_mut())
    }

    fn solve_mat(&self, mut x: MatMut<'_, f64>) -> Result<()> {
        if !is_finite(x.rb()) {
            return Err(Error::NonFinite("DenseLlt::solve: right-hand side"));
        }
        let mut mem = MemBuffer::try_new(solve_in_place_scratch::<f64>(self.n(), x.ncols(), Par::Seq))
            .map_err(|_| Error::Factorization("DenseLlt::solve: out of memory for scratch space".into()))?;
        solve_in_place_with_conj(self.l.as_ref(), Conj::No, x.rb_mut(), Par::Seq, MemStack::new(&mut mem));
        if !is_finite(x.rb()) {
            return Err(Error::NonFinite("DenseLlt::solve: solution (overflow)"));
        }
        Ok(())
    }
}

/// Numerical rank: the number of singular values `σ_i > rel_tol · σ_max` (0 for an empty or
/// zero matrix). A typical `rel_tol` is `max(m, n)·ε ≈ 1e-12` for "exactly" rank-deficient
/// data, larger for measured data.
///
/// Errors: NaN/∞ entries (`NonFinite`), `rel_tol` negative or non-finite (`InvalidParameter`),
/// SVD non-convergence (`Factorization`).
pub fn rank(a: &Mat<f64>, rel_tol: f64) -> Result<usize> {
    if !(rel_tol >= 0.0 && rel_tol.is_finite()) {
        return Err(Error::InvalidParameter(format!(
            "dense::rank: rel_tol = {rel_tol} must be finite and non-negative"
        )));
    }
    if !is_finite(a.as_ref()) {
        return Err(Error::NonFinite("dense::rank: matrix"));
    }
    if a.nrows() == 0 || a.ncols() == 0 {
        return Ok(0);
    }
    let s = a.singular_values().map_err(|e| Error::Factorization(format!("dense::rank: SVD failed: {e:?}")))?;
    let smax = s.iter().fold(0.0f64, |m, &v| m.max(v));
    if smax == 0.0 {
        return Ok(0);
    }
    Ok(s.iter().filter(|&&v| v > rel_tol * smax).count())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn llt_solves_and_rejects_indefinite() {
        let a = Mat::from_fn(3, 3, |i, j| if i == j { 4.0 } else { 1.0 });
        let f = llt(&a).expect("diagonally dominant SPD");
        let mut x = vec![6.0, 6.0, 6.0];
        f.solve_in_place(&mut x).expect("finite rhs");
        for xi in x {
            assert!((xi - 1.0).abs() < 1e-14);
        }
        let b = Mat::from_fn(2, 2, |i, j| if i == j { [1.0, -1.0][i] } else { 0.0 });
        assert!(matches!(llt(&b), Err(Error::NotPositiveDefinite { column: 1 })));
        let mut c = a.clone();
        c[(1, 1)] = f64::NAN;
        assert!(matches!(llt(&c), Err(Error::NonFinite(_))));
    }

    #[test]
    fn rank_of_outer_products() {
        // (i+1)·v_j with v = (-1.5, -0.5, 0.5, 1.5) (rank 1) plus (i·j mod 3), whose nonzero rows
        // are (0 1 2 0) and (0 2 1 0): these and v are independent, so the rank is exactly 3.
        let a = Mat::from_fn(5, 4, |i, j| (i as f64 + 1.0) * (j as f64 - 1.5) + ((i * j) % 3) as f64);
        assert_eq!(rank(&a, 1e-12).expect("finite"), 3);
        assert_eq!(rank(&Mat::<f64>::identity(4, 4), 1e-12).expect("finite"), 4);
        assert_eq!(rank(&Mat::<f64>::zeros(3, 3), 1e-12).expect("finite"), 0);
        let mut bad = Mat::<f64>::identity(2, 2);
        bad[(0, 1)] = f64::INFINITY;
        assert!(matches!(rank(&bad, 1e-12), Err(Error::NonFinite(_))));
    }

    #[test]
    fn matmul_matches_the_naive_product_and_accumulates() {
        // Integer-valued entries: every product and partial sum is exact in f64, so the faer
        // kernels' summation order cannot matter and the comparison is exact.
        let a = Mat::from_fn(7, 5, |i, j| (i as f64) - 2.0 * (j as f64));
        let b = Mat::from_fn(5, 9, |i, j| ((i * j) % 4) as f64 - 1.0);
        let mut c = Mat::<f64>::zeros(7, 9);
        matmul(c.as_mut(), faer::Accum::Replace, a.as_ref(), b.as_ref(), 2.0, Par::Seq);
        for i in 0..7 {
            for j in 0..9 {
                let naive: f64 = (0..5).map(|k| a[(i, k)] * b[(k, j)]).sum();
                assert_eq!(c[(i, j)], 2.0 * naive);
            }
        }
        matmul(c.as_mut(), faer::Accum::Add, a.as_ref(), b.as_ref(), -1.0, Par::Seq);
        for i in 0..7 {
            for j in 0..9 {
                let naive: f64 = (0..5).map(|k| a[(i, k)] * b[(k, j)]).sum();
                assert_eq!(c[(i, j)], naive);
            }
        }
    }
}

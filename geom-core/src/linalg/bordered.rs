//! [`BorderedLlt`]: saddle-point systems `[A Bᵀ; B 0] [x; y] = [b; r]` (A SPD, B full row rank,
//! m ≪ n border rows) solved through one sparse **LLᵀ** of the SPD bordered matrix
//! `K̃ = [A Bᵀ; B γI]` ordered A-block first (a given order, e.g. the untracked system's AMD) and
//! the border last, plus one dense m × m Cholesky of the Schur complement `S = B A⁻¹ Bᵀ`.
//!
//! Why: faer's sparse LDLᵀ costs about twice its LLᵀ on shell Hessians (measured, tracks'
//! README), so a constraint-last LDLᵀ of the KKT matrix pays that factor on all of A. With the
//! border last, `K̃ = L Lᵀ`, `L = [L_A 0; Yᵀ L₂₂]` where `L_A` is the factor of A alone (same
//! elimination order as the unconstrained solver), `Y = L_A⁻¹ Π Bᵀ` (the sparse-RHS triangular
//! solves of the Schur method, done by faer's supernodal kernels) and
//! `L₂₂ L₂₂ᵀ = γI − Yᵀ Y = γI − S`. S = YᵀY is accumulated from the border rows of L's A-columns
//! (no cancellation) and factorised densely. The solve needs two sparse solves with `K̃`
//! (derivation in [`BorderedLlt::solve`]).
//!
//! γ must exceed λ_max(S) for `K̃` to be SPD and should stay within a small factor of it (the solve
//! scales the multipliers by γ): a failed factorisation quadruples γ and retries; a success with
//! γ above 8× the Gershgorin bound of S refactors with twice that bound, which is also the next
//! call's first γ.

use super::csc::Csc;
use super::dense::{self, DenseLlt};
use super::symbolic::{LltSymbolic, Ordering};
use crate::error::{Error, Result};
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::cholesky::llt::factor::LltError;
use faer::prelude::ReborrowMut;
use faer::sparse::linalg::cholesky::{
    simplicial::SimplicialLltRef, supernodal::SupernodalLltRef, LltRef, SymbolicCholeskyRaw,
};
use faer::{Conj, Mat, MatMut, Par, Side};

/// Attempts per factorisation (γ × 4 on failure, one rescale on success): a first guess up to
/// 4¹⁰ ≈ 10⁶ too small.
const MAX_ATTEMPTS: usize = 12;

/// LLᵀ of the bordered matrix `[A Bᵀ; B γI]` and the dense Cholesky of `S = B A⁻¹ Bᵀ`; see the
/// module docs.
#[derive(Clone, Debug)]
pub struct BorderedLlt {
    symbolic: LltSymbolic,
    n: usize,
    m: usize,
    /// Working copy of the matrix with γ on the border diagonal.
    k: Csc,
    /// Value positions of the border diagonal entries in `k`.
    border_diag: Vec<usize>,
    values: Vec<f64>,
    /// γ of the current factorisation (used by the solve).
    gamma: f64,
    /// γ the next factorisation starts from.
    gamma_next: f64,
    s_llt: Option<DenseLlt>,
}

impl BorderedLlt {
    /// Analyses the lower triangle of `k` = `[A Bᵀ; B D]` (size n + m, A the leading n × n block;
    /// the border block must store its diagonal, values ignored) with the elimination order
    /// `a_perm` (`perm[new] = old`, a permutation of `0..n`) followed by the border rows.
    ///
    /// Errors: `DimensionMismatch` (k not square, `a_perm` not of length n ≤ size), a missing
    /// border diagonal entry (`InvalidParameter`), analysis failures as [`LltSymbolic::analyze`].
    pub fn analyze(k: &Csc, n: usize, a_perm: &[usize]) -> Result<Self> {
        let size = k.nrows();
        if k.ncols() != size || n > size || a_perm.len() != n {
            return Err(Error::DimensionMismatch {
                what: "BorderedLlt::analyze: a_perm",
                expected: n,
                got: a_perm.len(),
            });
        }
        let mut perm = a_perm.to_vec();
        perm.extend(n..size);
        let symbolic = LltSymbolic::analyze(k, &Ordering::Custom(perm))?;
        // faer may reorder within the given order (postordering); the border must stay last.
        if symbolic.perm().iter().enumerate().any(|(new, &old)| (new < n) != (old < n)) {
            return Err(Error::Factorization("BorderedLlt::analyze: the border was not eliminated last".into()));
        }
        let sym = k.symbolic();
        let border_diag = (n..size)
            .map(|j| {
                let start = sym.col_range(j).start;
                sym.row_idx_of_col_raw(j).iter().position(|&i| i == j).map(|p| start + p).ok_or_else(|| {
                    Error::InvalidParameter(format!("BorderedLlt::analyze: border column {j} has no diagonal entry"))
                })
            })
            .collect::<Result<Vec<_>>>()?;
        Ok(Self {
            symbolic,
            n,
            m: size - n,
            k: k.clone(),
            border_diag,
            values: Vec::new(),
            gamma: 0.0,
            gamma_next: 0.0,
            s_llt: None,
        })
    }

    /// Factorises `[A Bᵀ; B γI]` with the values of `k` (same pattern as analysed; the border
    /// block's values are ignored) and the Schur complement S. `gamma_hint` > 0 is the first γ
    /// tried when no earlier factorisation chose one.
    ///
    /// Errors: `NonFinite` values; `NotPositiveDefinite` when A is not SPD (a pivot of the
    /// A-block fails) or B is rank deficient (S singular), `Factorization` when no γ up to
    /// `gamma_hint · 4¹⁰` makes K̃ positive definite.
    pub fn factor(&mut self, k: &Csc, gamma_hint: f64) -> Result<()> {
        self.s_llt = None;
        self.symbolic.check_pattern(k, "BorderedLlt::factor: matrix")?;
        self.gamma = if self.gamma_next > 0.0 {
            self.gamma_next
        } else if gamma_hint > 0.0 && gamma_hint.is_finite() {
            gamma_hint
        } else {
            1.0
        };
        self.k.val_mut().copy_from_slice(k.val());
        let s = &self.symbolic.inner;
        self.values.resize(s.chol.len_val(), 0.0);
        let mut mem = MemBuffer::try_new(s.chol.factorize_numeric_llt_scratch::<f64>(Par::Seq, Default::default()))
            .map_err(|_| Error::Factorization("BorderedLlt::factor: out of memory for scratch space".into()))?;
        for _ in 0..MAX_ATTEMPTS {
            let kv = self.k.val_mut();
            for &p in &self.border_diag {
                kv[p] = self.gamma;
            }
            let res = s.chol.factorize_numeric_llt(
                &mut self.values,
                self.k.as_ref(),
                Side::Lower,
                Default::default(),
                Par::Seq,
                MemStack::new(&mut mem),
                Default::default(),
            );
            match res {
                Ok(_) => {
                    let (s_mat, bound) = self.schur();
                    let target = 2.0 * bound.max(f64::MIN_POSITIVE);
                    if self.gamma > 4.0 * target {
                        // γ far above λ_max(S) (a first guess): the solve would multiply rounding
                        // errors by γ/λ(S); refactor with the well-scaled γ.
                        self.gamma = target;
                        continue;
                    }
                    self.s_llt = Some(dense::llt(&s_mat)?);
                    // Next γ: twice the Gershgorin bound of S (K̃ SPD with margin, well scaled).
                    self.gamma_next = target;
                    return Ok(());
                }
                Err(LltError::NonPositivePivot { index }) => {
                    // faer reports the simplicial pivot 1-based and the supernodal one 0-based.
                    let k = match s.chol.raw() {
                        SymbolicCholeskyRaw::Simplicial(_) => index.saturating_sub(1),
                        SymbolicCholeskyRaw::Supernodal(_) => index,
                    };
                    if k < self.n {
                        // A pivot of A itself: A is not SPD, no γ helps.
                        return Err(Error::NotPositiveDefinite { column: s.perm[k] });
                    }
                    self.gamma *= 4.0;
                }
            }
        }
        Err(Error::Factorization(format!(
            "BorderedLlt::factor: [A Bᵀ; B γI] not positive definite up to γ = {}",
            self.gamma
        )))
    }

    /// S = YᵀY (dense, m × m) from the border rows Y of the A-columns of L (no cancellation,
    /// independent of γ) and its Gershgorin bound max_i Σ_j |S_ij|.
    fn schur(&self) -> (Mat<f64>, f64) {
        let (n, m) = (self.n, self.m);
        let mut sm = Mat::<f64>::zeros(m, m);
        let s = &self.symbolic.inner;
        // Factor rows are in elimination order; `perm[new] = old` maps border rows to B's rows.
        let perm = &s.perm;
        // Adds v vᵀ for one column's border entries (row − n, value).
        let mut add_outer = |col: &[(usize, f64)]| {
            for (ia, &(a, va)) in col.iter().enumerate() {
                for &(b, vb) in &col[..=ia] {
                    let (hi, lo) = if a >= b { (a, b) } else { (b, a) };
                    sm[(hi, lo)] += va * vb;
                }
            }
        };
        let mut col: Vec<(usize, f64)> = Vec::with_capacity(m);
        match s.chol.raw() {
            SymbolicCholeskyRaw::Simplicial(sym) => {
                let l = SimplicialLltRef::new(sym, &self.values);
                let (cp, ri) = (sym.col_ptr(), sym.row_idx());
                for j in 0..n {
                    col.clear();
                    col.extend((cp[j]..cp[j + 1]).filter(|&p| ri[p] >= n).map(|p| (perm[ri[p]] - n, l.values()[p])));
                    add_outer(&col);
                }
            }
            SymbolicCholeskyRaw::Supernodal(sym) => {
                let l = SupernodalLltRef::new(sym, &self.values);
                for sn in 0..sym.n_supernodes() {
                    let node = l.supernode(sn);
                    let (start, v) = (node.start(), node.val());
                    let ncols = v.ncols();
                    let nc = ncols.min(n.saturating_sub(start));
                    if nc == 0 {
                        continue;
                    }
                    // Border rows of this supernode: (row in `v`, row of S). Rows of the diagonal
                    // block at or past n lie below every A-column c < nc (lower part, valid).
                    let rows: Vec<(usize, usize)> = (nc..ncols)
                        .filter(|&r| start + r >= n)
                        .map(|r| (r, perm[start + r] - n))
                        .chain(
                            node.pattern()
                                .iter()
                                .enumerate()
                                .filter(|(_, &i)| i >= n)
                                .map(|(r, &i)| (ncols + r, perm[i] - n)),
                        )
                        .collect();
                    if rows.is_empty() {
                        continue;
                    }
                    // One dense product per supernode: Y_s Y_sᵀ (|rows| × |rows|).
                    let ys = Mat::<f64>::from_fn(rows.len(), nc, |a, c| v[(rows[a].0, c)]);
                    let mut prod = Mat::<f64>::zeros(rows.len(), rows.len());
                    super::dense::matmul(
                        prod.as_mut(),
                        faer::Accum::Replace,
                        ys.as_ref(),
                        ys.transpose(),
                        1.0,
                        Par::Seq,
                    );
                    for (a, &(_, sa)) in rows.iter().enumerate() {
                        for (b, &(_, sb)) in rows.iter().enumerate() {
                            if sa >= sb {
                                sm[(sa, sb)] += prod[(a, b)];
                            }
                        }
                    }
                }
            }
        }
        for i in 0..m {
            for j in 0..i {
                sm[(j, i)] = sm[(i, j)];
            }
        }
        let bound = (0..m).map(|i| (0..m).map(|j| sm[(i, j)].abs()).sum::<f64>()).fold(0.0, f64::max);
        (sm, bound)
    }

    fn solve_k(&self, x: &mut [f64]) {
        let s = &self.symbolic.inner;
        let len = x.len();
        let mut mem = MemBuffer::new(s.chol.solve_in_place_scratch::<f64>(1, Par::Seq));
        LltRef::new(&s.chol, &self.values).solve_in_place_with_conj(
            Conj::No,
            MatMut::from_column_major_slice_mut(x, len, 1).rb_mut(),
            Par::Seq,
            MemStack::new(&mut mem),
        );
    }

    /// Solves `[A Bᵀ; B 0] [x; y] = [b; r]`; `b` has length n, `r` length m; returns (x, y).
    ///
    /// With `[x₁; y₁] = K̃⁻¹[b; 0]`: `g = B A⁻¹ b = −(γI − S) y₁ = −L₂₂L₂₂ᵀ y₁ = S y₁ − γ y₁`,
    /// `y = S⁻¹(g − r)`, and `K̃⁻¹[b; r + γy]` has second block `y` and first block
    /// `A⁻¹(b − Bᵀy) = x` (substitute into `B x + γ y = r + γ y`).
    ///
    /// Errors: not factored (`InvalidParameter`), wrong lengths (`DimensionMismatch`), a
    /// non-finite right-hand side or solution (`NonFinite`).
    pub fn solve(&self, b: &[f64], r: &[f64]) -> Result<(Vec<f64>, Vec<f64>)> {
        let (n, m) = (self.n, self.m);
        let sl = self
            .s_llt
            .as_ref()
            .ok_or_else(|| Error::InvalidParameter("BorderedLlt: solve called before a successful factor".into()))?;
        if b.len() != n || r.len() != m {
            return Err(Error::DimensionMismatch {
                what: "BorderedLlt::solve: b, r",
                expected: n + m,
                got: b.len() + r.len(),
            });
        }
        if !super::all_finite(b) || !super::all_finite(r) {
            return Err(Error::NonFinite("BorderedLlt::solve: right-hand side"));
        }
        let mut z = b.to_vec();
        z.resize(n + m, 0.0);
        self.solve_k(&mut z);
        let y1 = &z[n..];
        // g − r = S y₁ − γ y₁ − r, with S applied from its Cholesky factor: S y₁ = L (Lᵀ y₁).
        let ls = sl.l();
        let mut t = vec![0.0; m];
        for j in 0..m {
            t[j] = (j..m).map(|i| ls[(i, j)] * y1[i]).sum();
        }
        let mut y: Vec<f64> =
            (0..m).map(|i| (0..=i).map(|j| ls[(i, j)] * t[j]).sum::<f64>() - self.gamma * y1[i] - r[i]).collect();
        sl.solve_in_place(&mut y)?;
        let mut x = b.to_vec();
        x.extend(r.iter().zip(&y).map(|(ri, yi)| ri + self.gamma * yi));
        self.solve_k(&mut x);
        x.truncate(n);
        if !super::all_finite(&x) || !super::all_finite(&y) {
            return Err(Error::NonFinite("BorderedLlt::solve: solution (overflow)"));
        }
        Ok((x, y))
    }

    /// Stored values of the sparse factor of K̃.
    pub fn nnz_l(&self) -> usize {
        self.symbolic.nnz_l()
    }

    /// The γ the next factorisation starts from (twice the last S's Gershgorin bound).
    pub fn next_gamma(&self) -> f64 {
        self.gamma_next
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::linalg::Triplets;
    use crate::linalg::{sym_mul_vec, Csr};

    /// [A Bᵀ; B 0] for a 1-D Laplacian + mass A (n = 40) and m = 3 local averaging rows.
    fn kkt() -> (Csc, usize, usize) {
        let (n, m) = (40usize, 3usize);
        let mut t = Triplets::new(n + m, n + m);
        for i in 0..n {
            t.push(i as u32, i as u32, 2.5);
            if i + 1 < n {
                t.push((i + 1) as u32, i as u32, -1.0);
            }
        }
        for r in 0..m {
            for k in 0..5 {
                let col = 3 + 12 * r + k;
                t.push((n + r) as u32, col as u32, 0.2 + 0.05 * k as f64);
            }
            t.push((n + r) as u32, (n + r) as u32, 0.0);
        }
        (Csr::from_triplets(&t).to_csc(), n, m)
    }

    #[test]
    fn bordered_solves_kkt() {
        let (k, n, m) = kkt();
        let perm: Vec<usize> = (0..n).rev().collect();
        let mut f = BorderedLlt::analyze(&k, n, &perm).expect("valid pattern");
        // A deliberately tiny first γ exercises the retry path.
        f.factor(&k, 1e-6).expect("SPD A, full-rank B");
        let b: Vec<f64> = (0..n).map(|i| (i as f64 * 0.37).sin()).collect();
        let r = vec![0.3, -0.2, 0.7];
        let (x, y) = f.solve(&b, &r).expect("factored");
        let mut sol = x.clone();
        sol.extend_from_slice(&y);
        let mut rhs = b.clone();
        rhs.extend_from_slice(&r);
        let mut kx = vec![0.0; n + m];
        sym_mul_vec(&k, &sol, &mut kx);
        let err = kx.iter().zip(&rhs).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
        // Backward-stable pieces on a matrix with condition number ~1e3: 1e-12 is ample.
        assert!(err < 1e-12, "KKT residual {err}");
        // A huge first γ is rescaled; the second factorisation starts from the adapted γ.
        let mut g = BorderedLlt::analyze(&k, n, &perm).expect("valid pattern");
        g.factor(&k, 1e9).expect("rescaled");
        let (x2, y2) = g.solve(&b, &r).expect("factored");
        let d = x2.iter().chain(&y2).zip(x.iter().chain(&y)).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
        assert!(d < 1e-12, "gamma-independent solution: {d}");
        assert!(f.next_gamma() > 0.0);
        f.factor(&k, 1.0).expect("same matrix");
    }

    #[test]
    fn indefinite_a_is_rejected() {
        let (mut k, n, _) = kkt();
        let p = k.symbolic().col_range(5).start; // first stored entry of column 5: the diagonal
        k.val_mut()[p] = -3.0;
        let perm: Vec<usize> = (0..n).collect();
        let mut f = BorderedLlt::analyze(&k, n, &perm).expect("valid pattern");
        assert!(matches!(f.factor(&k, 1.0), Err(Error::NotPositiveDefinite { .. })));
    }
}

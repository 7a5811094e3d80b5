//! Exact saddle-point solve by the augmented Lagrangian (method of multipliers) on one sparse
//! LLᵀ: our addition to the KKT solvers of spec §3.6 ([`crate::KktMethod::AugmentedLagrangian`]).
//!
//! The KKT system `A Δv + Ĉᵀμ = b`, `Ĉ Δv = r` is equivalent to
//!
//! ```text
//! (A + ρ ĈᵀĈ) Δv = b + ρ Ĉᵀ r − Ĉᵀ μ,      Ĉ Δv = r
//! ```
//!
//! for every ρ ≥ 0. `A_ρ = A + ρĈᵀĈ` is SPD, so it is factored once per step with the same
//! supernodal LLᵀ as the untracked solve (no LDLᵀ, no sign guard, no dense 3K × 3K Schur
//! block). Each iteration computes the exact KKT residuals (s₁, s₂) = (b − AΔv − Ĉᵀμ,
//! r − ĈΔv) with A itself and corrects with one pair of triangular solves:
//! `dx = A_ρ⁻¹(s₁ + ρĈᵀs₂)`, `dμ = ρ(Ĉdx − s₂)`. This is the Uzawa (multiplier) iteration,
//! whose error contracts by `(I + ρS)⁻¹`, S = ĈA⁻¹Ĉᵀ, written as iterative refinement, which
//! also removes the κ(A_ρ)·ε rounding error the large ρ puts into the null-space part of Δv
//! (measured: 8e-8 relative after the first solve, 1e-15 after the second). With
//! ρ = α·max diag(A)/max diag(ĈᵀĈ), α = 10⁶, and μ warm-started from the previous step, two
//! solves reach the tolerance. Unlike [`crate::KktMethod::Penalty`], the result is the exact KKT
//! solution (ρ only preconditions the iteration), so the residual is not ∝ 1/ρ.
//!
//! Cost against the untracked step: the LLᵀ of A_ρ instead of A (ĈᵀĈ adds one clique per
//! constraint support: small for clustered regions, a few extra entries per row for hats), plus
//! the extra solves. Pattern and symbolic analysis are built once; per step only values move.

use faer::sparse::{SparseColMat, SymbolicSparseColMat};
use geom_core::linalg::{sym_mul_vec, Csc, Ordering, SparseLlt};

/// Largest number of corrections (solves) per step; the measured count is 2.
pub const MAX_ITERS: u32 = 8;

/// Relative KKT residual at which the iteration stops: ‖b − AΔv − Ĉᵀμ‖∞ over
/// ‖b‖∞ + ‖AΔv‖∞ + ‖Ĉᵀμ‖∞, and ‖r − ĈΔv‖∞ over ‖r‖∞ + ‖ĈΔv‖∞ (a few ulps of the products).
pub const REL_TOL: f64 = 1e-13;

/// Pattern, value maps, factor and warm start of the augmented Lagrangian solver.
pub struct AugmentedLagrangian {
    /// Dimension (3 × free vertices).
    n: usize,
    /// Stored entries of the A it was built for (pattern-change check).
    a_pattern: SparsityPattern,
    /// A + ρĈᵀĈ in A's storage convention (A's entries, plus the lower triangle of ĈᵀĈ).
    mat: Csc,
    /// Position in `mat` of each stored entry of A.
    a_map: Vec<usize>,
    /// (position in `mat`, value of ĈᵀĈ) of every ĈᵀĈ entry.
    ctc: Vec<(usize, f64)>,
    /// max diag(ĈᵀĈ).
    ctc_max_diag: f64,
    llt: SparseLlt,
    /// Multipliers of the last step (warm start).
    mu: Vec<f64>,
    /// Uzawa iterations of the last solve.
    pub last_iters: u32,
}

/// Ĉ x for x of length 3 n_free → length 3K (`cft`: per free vertex, its (constraint, weight)).
pub(crate) fn c_mul(cft: &[Vec<(u32, f64)>], x: &[f64], out: &mut [f64]) {
    out.iter_mut().for_each(|o| *o = 0.0);
    for (f, row) in cft.iter().enumerate() {
        for &(i, w) in row {
            for d in 0..3 {
                out[3 * i as usize + d] += w * x[3 * f + d];
            }
        }
    }
}

/// Ĉᵀ μ → length 3 n_free.
pub(crate) fn ct_mul(cft: &[Vec<(u32, f64)>], mu: &[f64], out: &mut [f64]) {
    for (f, row) in cft.iter().enumerate() {
        for d in 0..3 {
            out[3 * f + d] = row.iter().map(|&(i, w)| w * mu[3 * i as usize + d]).sum();
        }
    }
}

impl AugmentedLagrangian {
    /// Builds the pattern of A + ĈᵀĈ (A's stored entries plus the lower triangle of ĈᵀĈ) and its
    /// AMD symbolic analysis. `k` is the number of constraints (3K multipliers).
    pub fn new(a: &Csc, cft: &[Vec<(u32, f64)>], k: usize) -> geom_core::Result<Self> {
        let n = a.nrows();
        // Constraint supports: per constraint, its (free vertex, weight) list.
        let mut rows: Vec<Vec<(usize, f64)>> = vec![Vec::new(); k];
        for (f, row) in cft.iter().enumerate() {
            for &(i, w) in row {
                rows[i as usize].push((f, w));
            }
        }
        // ĈᵀĈ per vertex pair (f ≥ g): Σ_i w_if w_ig, the same for each coordinate.
        let mut pairs: Vec<Vec<(usize, f64)>> = vec![Vec::new(); cft.len()];
        for row in &rows {
            for &(f, wf) in row {
                for &(g, wg) in row {
                    if f >= g {
                        pairs[g].push((f, wf * wg));
                    }
                }
            }
        }
        for p in &mut pairs {
            p.sort_unstable_by_key(|&(f, _)| f);
            let mut merged: Vec<(usize, f64)> = Vec::with_capacity(p.len());
            for &(f, w) in p.iter() {
                match merged.last_mut() {
                    Some(last) if last.0 == f => last.1 += w,
                    _ => merged.push((f, w)),
                }
            }
            *p = merged;
        }
        let sa = a.symbolic();
        let mut col_ptr = Vec::with_capacity(n + 1);
        let mut row_idx: Vec<usize> = Vec::new();
        let mut a_map = vec![0usize; a.val().len()];
        let mut ctc = Vec::new();
        let mut ctc_max_diag = 0.0f64;
        col_ptr.push(0);
        let mut col: Vec<(usize, Option<usize>, f64)> = Vec::new();
        for j in 0..n {
            col.clear();
            col.extend(sa.col_range(j).map(|kk| (sa.row_idx()[kk], Some(kk), 0.0)));
            let (g, d) = (j / 3, j % 3);
            for &(f, w) in &pairs[g] {
                let i = 3 * f + d;
                if i >= j {
                    col.push((i, None, w));
                    if i == j {
                        ctc_max_diag = ctc_max_diag.max(w);
                    }
                }
            }
            col.sort_by_key(|&(i, _, _)| i);
            let mut last = usize::MAX;
            for &(i, ak, w) in &col {
                if i != last {
                    row_idx.push(i);
                    last = i;
                }
                let pos = row_idx.len() - 1;
                match ak {
                    Some(kk) => a_map[kk] = pos,
                    None => ctc.push((pos, w)),
                }
            }
            col_ptr.push(row_idx.len());
        }
        let nnz = row_idx.len();
        let sym = SymbolicSparseColMat::new_checked(n, n, col_ptr, None, row_idx);
        let mat: Csc = SparseColMat::new(sym, vec![0.0; nnz]);
        let llt = SparseLlt::analyze(&mat, Ordering::Amd)?;
        Ok(Self {
            n,
            a_pattern: SparsityPattern::of(a),
            mat,
            a_map,
            ctc,
            ctc_max_diag,
            llt,
            mu: vec![0.0; 3 * k],
            last_iters: 0,
        })
    }

    /// Whether this cache was built for A's pattern (dimension, column pointers and row
    /// indices: IPC contact couplings change the pattern between Newton iterations).
    pub fn fits(&self, a: &Csc) -> bool {
        self.n == a.nrows() && self.a_pattern.matches(a)
    }

    /// Stored entries of the LLᵀ factor of A_ρ.
    pub fn nnz_l(&self) -> usize {
        self.llt.nnz_l()
    }

    /// Solves the KKT system with `A` (same pattern as at construction), `b`, `r`; returns
    /// (Δv, μ) and the final relative constraint residual. `alpha` sets ρ (see module docs).
    pub fn solve(
        &mut self,
        a: &Csc,
        b: &[f64],
        r: &[f64],
        cft: &[Vec<(u32, f64)>],
        alpha: f64,
    ) -> geom_core::Result<(Vec<f64>, Vec<f64>, f64)> {
        let av = a.val();
        let sa = a.symbolic();
        let max_diag = (0..self.n)
            .map(|j| sa.col_range(j).find(|&kk| sa.row_idx()[kk] == j).map_or(0.0, |kk| av[kk].abs()))
            .fold(0.0f64, f64::max);
        let rho = alpha * max_diag / self.ctc_max_diag.max(1e-300);
        {
            let mv = self.mat.val_mut();
            mv.iter_mut().for_each(|v| *v = 0.0);
            for (kk, &p) in self.a_map.iter().enumerate() {
                mv[p] += av[kk];
            }
            for &(p, w) in &self.ctc {
                mv[p] += rho * w;
            }
        }
        self.llt.factor(&self.mat)?;
        let m = r.len();
        if self.mu.len() != m {
            self.mu = vec![0.0; m];
        }
        let n = self.n;
        let norm = |v: &[f64]| v.iter().fold(0.0f64, |a, x| a.max(x.abs()));
        let (bnorm, rnorm) = (norm(b), norm(r));
        let mut x = vec![0.0; n];
        let (mut s1, mut ax, mut ctmu) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
        let (mut s2, mut cx) = (vec![0.0; m], vec![0.0; m]);
        let mut dx = vec![0.0; n];
        let mut res = f64::INFINITY;
        self.last_iters = 0;
        loop {
            // KKT residuals of the current (x, μ) with the exact A: s1 = b − Ax − Ĉᵀμ, s2 = r − Ĉx.
            sym_mul_vec(a, &x, &mut ax);
            ct_mul(cft, &self.mu, &mut ctmu);
            c_mul(cft, &x, &mut cx);
            for i in 0..n {
                s1[i] = b[i] - ax[i] - ctmu[i];
            }
            for i in 0..m {
                s2[i] = r[i] - cx[i];
            }
            let rel1 = norm(&s1) / (bnorm + norm(&ax) + norm(&ctmu)).max(1e-300);
            let rel2 = norm(&s2) / (rnorm + norm(&cx)).max(1e-300);
            let rel = rel1.max(rel2);
            if !rel.is_finite() {
                return Err(geom_core::Error::NonFinite("augmented Lagrangian: KKT residual"));
            }
            // Stop at the tolerance, at the iteration cap, or when rounding stalls the contraction
            // (keeping the better iterate is not needed: a stalled step changes x by rounding only).
            let stalled = self.last_iters > 0 && rel > 0.5 * res;
            res = res.min(rel);
            if rel <= REL_TOL || stalled || self.last_iters == MAX_ITERS {
                break;
            }
            self.last_iters += 1;
            // Correction (dx, dμ) of the KKT with right-hand side (s1, s2) through A_ρ:
            // A_ρ dx = s1 + ρĈᵀs2, dμ = ρ(Ĉdx − s2) (the multiplier consistent with dx).
            ct_mul(cft, &s2, &mut dx);
            dx.iter_mut().zip(&s1).for_each(|(d, &s)| *d = s + rho * *d);
            self.llt.solve_in_place(&mut dx)?;
            c_mul(cft, &dx, &mut cx);
            x.iter_mut().zip(&dx).for_each(|(xi, d)| *xi += d);
            self.mu.iter_mut().zip(cx.iter().zip(&s2)).for_each(|(mu, (c, s))| *mu += rho * (c - s));
        }
        Ok((x, self.mu.clone(), res))
    }
}

/// A copy of a sparse matrix's structure (column pointers and row indices), to tell whether a
/// cached symbolic analysis still fits a matrix: the IPC contact model grows the system's
/// pattern between Newton iterations (`shells::VelocitySolve::accepts_pattern_changes`), and two
/// patterns can have the same number of stored entries.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct SparsityPattern {
    col_ptr: Vec<usize>,
    row_idx: Vec<usize>,
}

impl SparsityPattern {
    /// The structure of `a`.
    pub(crate) fn of(a: &Csc) -> Self {
        let s = a.symbolic();
        Self { col_ptr: s.col_ptr().to_vec(), row_idx: s.row_idx().to_vec() }
    }

    /// Whether `a` has exactly this structure.
    pub(crate) fn matches(&self, a: &Csc) -> bool {
        let s = a.symbolic();
        s.col_ptr() == self.col_ptr.as_slice() && s.row_idx() == self.row_idx.as_slice()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use geom_core::linalg::{Csr, Triplets};

    /// A stiff SPD "cloth-like" matrix on a chain of `nv` vertices (3 DOFs each): mass + a
    /// spring Laplacian 10⁴× stronger, coupling x, y, z of neighbours; lower triangle stored.
    fn chain(nv: usize) -> Csc {
        let n = 3 * nv;
        let mut t = Triplets::new(n, n);
        for v in 0..nv {
            for d in 0..3 {
                let i = 3 * v + d;
                let deg = if v == 0 || v + 1 == nv { 1.0 } else { 2.0 };
                t.push(i as u32, i as u32, 1.0 + 1e4 * deg + 0.1 * d as f64);
                if v + 1 < nv {
                    t.push((i + 3) as u32, i as u32, -1e4);
                    // Off-diagonal cross-coordinate coupling (a bending-like 3×3 block).
                    if d < 2 {
                        t.push((i + 4) as u32, i as u32, 0.3);
                    }
                }
            }
        }
        Csr::from_triplets(&t).to_csc()
    }

    /// Dense reference: LU of the full KKT matrix.
    fn dense_kkt(a: &Csc, cft: &[Vec<(u32, f64)>], b: &[f64], r: &[f64]) -> Vec<f64> {
        let (n, m) = (a.nrows(), r.len());
        let mut k = nalgebra::DMatrix::<f64>::zeros(n + m, n + m);
        let s = a.symbolic();
        for j in 0..n {
            for kk in s.col_range(j) {
                let i = s.row_idx()[kk];
                k[(i, j)] = a.val()[kk];
                k[(j, i)] = a.val()[kk];
            }
        }
        for (f, row) in cft.iter().enumerate() {
            for &(c, w) in row {
                for d in 0..3 {
                    k[(n + 3 * c as usize + d, 3 * f + d)] = w;
                    k[(3 * f + d, n + 3 * c as usize + d)] = w;
                }
            }
        }
        let rhs = nalgebra::DVector::from_iterator(n + m, b.iter().chain(r).copied());
        k.lu().solve(&rhs).expect("KKT nonsingular (C full row rank)").iter().copied().collect()
    }

    /// Equals the dense KKT solution to 1e-12 relative (Δv and μ), for disjoint regions and for
    /// overlapping (hat-like) supports, over several steps with a warm start and changing A.
    #[test]
    fn matches_dense_kkt() {
        let nv = 24;
        let a0 = chain(nv);
        // Disjoint regions of 4 vertices, and overlapping windows of 6 vertices every 3.
        let disjoint: Vec<Vec<(u32, f64)>> = (0..nv).map(|v| vec![((v / 4) as u32, 0.2 + 0.01 * v as f64)]).collect();
        let mut overlap: Vec<Vec<(u32, f64)>> = vec![Vec::new(); nv];
        for c in 0..7 {
            for v in 3 * c..(3 * c + 6).min(nv) {
                overlap[v].push((c as u32, 1.0 / (1.0 + (v as f64 - 3.0 * c as f64 - 2.5).abs())));
            }
        }
        for (cft, k) in [(disjoint, 6usize), (overlap, 7usize)] {
            let mut al = AugmentedLagrangian::new(&a0, &cft, k).expect("analysis");
            for step in 0..3 {
                let mut a = a0.clone();
                a.val_mut().iter_mut().enumerate().for_each(|(i, v)| *v *= 1.0 + 0.01 * ((i + step) % 5) as f64);
                let b: Vec<f64> = (0..3 * nv).map(|i| ((i * 7 + step) % 11) as f64 - 5.0).collect();
                let r: Vec<f64> = (0..3 * k).map(|i| 0.1 * ((i * 3 + step) % 7) as f64 - 0.3).collect();
                let (x, mu, res) = al.solve(&a, &b, &r, &cft, 1e6).expect("solve");
                assert!(res <= REL_TOL, "residual {res}");
                let ref_sol = dense_kkt(&a, &cft, &b, &r);
                let scale = |v: &[f64]| v.iter().fold(0.0f64, |m, x| m.max(x.abs()));
                let dx = x.iter().zip(&ref_sol).fold(0.0f64, |m, (p, q)| m.max((p - q).abs()));
                let dmu = mu.iter().zip(&ref_sol[3 * nv..]).fold(0.0f64, |m, (p, q)| m.max((p - q).abs()));
                // Tolerance: the dense LU's own error is ~κ(KKT)·ε ≈ 1e-12 here.
                assert!(dx <= 1e-12 * scale(&ref_sol[..3 * nv]), "Δv differs by {dx}");
                assert!(dmu <= 1e-10 * scale(&ref_sol[3 * nv..]), "μ differs by {dmu}");
                assert!(al.last_iters <= 3, "{} corrections", al.last_iters);
            }
        }
    }
}

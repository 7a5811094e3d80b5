//! The saddle-point solve of the constrained implicit Euler step (spec §3.6):
//!
//! ```text
//! [ A   Ĉᵀ ] [ Δv ]   [ b ]        Ĉ = C_f ⊗ I₃,  r = c·(C̄ q̄(t_{k+1}) − C q⁰) / h_eff
//! [ Ĉ   0  ] [ μ  ] = [ r ]
//! ```
//!
//! with A, b, q⁰ = q_pred and h_eff exactly the `shells` system ([`shells::ImplicitSystem`]),
//! so g(q⁰ + h_eff Δv) = 0 to solver precision after one Newton step (g is linear). μ = −hλ of
//! the seed; the constraint force is f_c = −Ĉᵀμ/h. Methods: constraint-last LDLᵀ (default),
//! AMD-ordered regularised LDLᵀ with refinement, Schur complement through the LLᵀ of A, penalty,
//! and compliant (soft) constraints.

use std::time::Instant;

use faer::sparse::{SparseColMat, SymbolicSparseColMat};
use faer::Mat;
use geom_core::linalg::{
    dense, BorderedLlt, Csc, Csr, LltSymbolic, Ordering, Regularization, SparseLdlt, SparseLlt, Triplets,
};
use geom_core::math::{Pt3, Vec3};
use geom_core::NONE;
use shells::{ImplicitSystem, VelocitySolve};

use crate::augmented::{c_mul, ct_mul, AugmentedLagrangian, SparsityPattern};
use crate::constraints::TrackingConstraints;
use crate::guide::GuideAnimation;

/// Position-level constraint residual, relative to the guide's diagonal L, below which
/// [`KktMethod::AmdRegularizedLdlt`] accepts its warm-started shifted solve without refinement:
/// 10× below the spec's r_pre ≤ 1e-9·L, so the shift never decides that target.
pub const SHIFT_RESIDUAL_TOL: f64 = 1e-10;

/// Most refinement steps [`KktMethod::AmdRegularizedLdlt`] takes to reach
/// [`SHIFT_RESIDUAL_TOL`] (the spec's "2–3 refinement steps"); `refine_steps` above it wins.
pub const MAX_SHIFT_REFINE_STEPS: u32 = 3;

/// Saddle-point solver (spec §3.6).
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Deserialize, serde::Serialize)]
pub enum KktMethod {
    /// A-block in the AMD order of the untracked LLᵀ, multipliers last, LDLᵀ with sign guard.
    #[default]
    ConstraintLastLdlt,
    /// Our addition: the untracked AMD order of the A-block with each multiplier row inserted
    /// right after the last DOF of its support, LDLᵀ with sign guard (no shift). Every pivot of a
    /// multiplier is then −ĉ A₁₁⁻¹ ĉᵀ-like (negative, the constraint-last argument applied to the
    /// leading block), and local regions are eliminated locally instead of filling a dense
    /// trailing 3K × 3K block.
    InterleavedLdlt,
    /// AMD on the whole KKT pattern (on vertices and regions, 3 rows each:
    /// [`Ordering::AmdBlocks`]), (2,2) block −δ·max diag(A)·I, `refine_steps` rounds of
    /// refinement on the exact KKT. The shift perturbs the solution by O(δ): measured on a
    /// Xavier step (K = 280, δ = 1e-8), Δv within 1.4e-7 relative of the unshifted solution and
    /// a constraint residual of 1e-7 of the right-hand side unrefined; one refinement step
    /// reaches ~1e-12. Smaller δ trades this for pivot growth (δ = 1e-10: primal residual 70×
    /// larger), so the shift stays at 1e-8 and the scenes choose the refinement.
    AmdRegularizedLdlt {
        /// Quasi-definite shift relative to max diag(A) (default 1e-8).
        delta: f64,
    },
    /// Schur complement S = ĈA⁻¹Ĉᵀ (dense) through LLᵀ only: one sparse LLᵀ of the SPD bordered
    /// matrix [A Ĉᵀ; Ĉ γI] in the untracked order of A with the multipliers last (its leading
    /// block is the untracked factor L_A, its border rows Y = L_A⁻¹ΠĈᵀ are the sparse-RHS
    /// triangular solves of the spec), S = γI − L₂₂L₂₂ᵀ, dense Cholesky of S, two sparse solves
    /// (geom-core's `BorderedLlt`). Avoids faer's LDLᵀ, which costs ~2× its LLᵀ here.
    Schur,
    /// The Schur system S μ = ĈA⁻¹b − r solved by preconditioned CG, each iteration one LLᵀ solve,
    /// preconditioned with the dense Cholesky of an S computed exactly at an earlier step (lagged);
    /// S is recomputed (3K solves) when CG needs more than `refresh_iters` iterations. Exact to
    /// the CG tolerance (1e-10 relative); per step: the untracked LLᵀ plus 1 + (CG iterations)
    /// solves. Our addition: faer's LDLᵀ costs ~2× its LLᵀ on these matrices (measured).
    SchurPcg {
        /// Recompute S when CG takes more iterations than this.
        refresh_iters: u32,
    },
    /// Our addition: the augmented Lagrangian (method of multipliers) on one sparse LLᵀ of
    /// A + ρĈᵀĈ, ρ = α·max diag(A)/max diag(ĈᵀĈ), with warm-started Uzawa updates of μ until
    /// ‖ĈΔv − r‖ is at rounding level (typically 1–2 solves). Exact like the LDLᵀ methods, but
    /// only an SPD LLᵀ (the untracked factorisation's kernel) plus local ĈᵀĈ fill; see
    /// [`crate::augmented`].
    AugmentedLagrangian {
        /// Dimensionless ρ scale α (default 1e6; larger contracts faster, smaller pivots).
        alpha: f64,
    },
    /// (A + k_p ĈᵀĈ)Δv = b + k_p Ĉᵀr with LLᵀ (residual ∝ 1/k_p; comparison only).
    Penalty {
        /// k_p (kg).
        stiffness: f64,
    },
    /// Soft constraints: (2,2) block −εI, no refinement (violation = ε·μ).
    Compliant {
        /// ε (1/kg).
        compliance: f64,
    },
}

/// What the last solve did.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct KktStats {
    /// Wall time of the constrained solve (assembly of the KKT values, factorisation, solve) (s).
    pub t_kkt: f64,
    /// Constrained solves in the step (its Newton iterations).
    pub solves: u32,
    /// Wall time of the unused shadow LLᵀ of A (s), 0 unless shadow timing is on.
    pub t_shadow_llt: f64,
    /// max_i ‖g_i(q⁰ + h_eff Δv)‖ (m): the constraint residual before collisions.
    pub residual_pre: f64,
    /// Largest per-vertex constraint force ‖f_c‖ = ‖Ĉᵀμ‖/h (N).
    pub max_constraint_force: f64,
    /// Relative residual of the linear KKT solve after refinement.
    pub refinement_residual: f64,
    /// The guide was sampled past its end (held).
    pub guide_held: bool,
    /// Stored entries of the factor (LDLᵀ or LLᵀ).
    pub nnz_l: usize,
    /// Refinement steps the last solve took (AmdRegularizedLdlt adds steps, up to
    /// `MAX_SHIFT_REFINE_STEPS`, while its solve leaves a constraint residual above
    /// `SHIFT_RESIDUAL_TOL`·L).
    pub refine_steps_done: u32,
    /// Per method of `TrackOptions::compare`: wall time of its solve of the same system (s),
    /// max |Δv − Δv_main| / max |Δv_main|, and its factor's stored entries.
    pub compare: Vec<CompareStats>,
}

/// One alternative method's solve of the same system as the main solve (timing comparison).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct CompareStats {
    /// Wall time of the solve (s), same scope as [`KktStats::t_kkt`].
    pub t_solve: f64,
    /// max |Δv − Δv_main| / max |Δv_main|.
    pub rel_diff: f64,
    /// Stored entries of its factor.
    pub nnz_l: usize,
}

struct KktCache {
    n: usize,
    m: usize,
    exact: Csc,
    factor_mat: Option<Csc>,
    a_map: Vec<usize>,
    /// A's structure when this cache was built (rebuilt when IPC contact changes it).
    a_pattern: SparsityPattern,
    /// The LDLᵀ (ConstraintLast, Interleaved, AmdRegularized, Compliant) or the bordered LLᵀ
    /// (Schur).
    factor: KktFactor,
}

enum KktFactor {
    Ldlt(SparseLdlt),
    Bordered(Box<BorderedLlt>),
}

/// The constrained velocity solve, plugged into [`shells::ShellSim::step_with`].
pub struct TrackingSolver {
    cons: TrackingConstraints,
    guide: GuideAnimation,
    method: KktMethod,
    refine_steps: u32,
    correction_fraction: f64,
    shadow: bool,
    a_perm: Vec<usize>,
    a_symbolic: LltSymbolic,
    /// Per free vertex: (constraint, weight) of C_f, built at the first solve.
    cft: Option<Vec<Vec<(u32, f64)>>>,
    kkt: Option<KktCache>,
    llt: Option<SparseLlt>,
    shadow_llt: Option<SparseLlt>,
    penalty_symbolic: Option<LltSymbolic>,
    /// The augmented-Lagrangian cache (pattern, factor, warm-start μ).
    al: Option<AugmentedLagrangian>,
    /// Lagged dense Cholesky of S (SchurPcg) and whether to refresh it at the next step.
    lagged_s: Option<dense::DenseLlt>,
    refresh_s: bool,
    /// Multipliers of the previous solve (AmdRegularizedLdlt's warm-started shift).
    mu_prev: Vec<f64>,
    /// The guide's bounding-box diagonal L (m), the scale of the shift's residual test.
    guide_scale: f64,
    /// Solvers of `TrackOptions::compare`, run on every system after the main solve.
    shadows: Vec<TrackingSolver>,
    gbuf: Vec<Pt3>,
    /// Exact-penalty weight ρ of the IPC line search's merit (J·s/m, the multipliers' unit):
    /// twice the largest ‖μᵢ‖ of this step's solves; reset by [`TrackingSolver::begin_step`].
    merit_rho: f64,
    /// h_eff of the last solve (s): the merit's constraint values are g(q)/h_eff.
    merit_h: f64,
    /// max ‖gᵢ(q_pred)‖/h_eff of the last solve (m/s): the violation its step restores
    /// ([`VelocitySolve::constraint_violation`]).
    violation: f64,
    /// Statistics of the last solve.
    pub last: KktStats,
}

fn core(e: geom_core::Error) -> shells::Error {
    shells::Error::Core(e)
}

impl TrackingSolver {
    /// A solver for the constraints `cons` (already restricted to rows with free support).
    /// `a_perm` and `a_symbolic` are the untracked system's AMD order and symbolic analysis
    /// (`ShellSim::fill_reducing_perm`, `ShellSim::llt_symbolic`), reused by every method.
    pub fn new(
        cons: TrackingConstraints,
        guide: GuideAnimation,
        opts: &crate::tracker::TrackOptions,
        a_perm: Vec<usize>,
        a_symbolic: LltSymbolic,
    ) -> Self {
        let nb = guide.n_vertices();
        let shadows = opts
            .compare
            .iter()
            .map(|&kkt| {
                let o = crate::tracker::TrackOptions { kkt, shadow_timing: false, compare: Vec::new(), ..opts.clone() };
                Self::new(cons.clone(), guide.clone(), &o, a_perm.clone(), a_symbolic.clone())
            })
            .collect();
        let guide_scale = guide.scale();
        Self {
            shadows,
            cons,
            guide,
            method: opts.kkt,
            refine_steps: opts.refine_steps,
            correction_fraction: opts.correction_fraction,
            shadow: opts.shadow_timing,
            a_perm,
            a_symbolic,
            cft: None,
            kkt: None,
            llt: None,
            shadow_llt: None,
            penalty_symbolic: None,
            al: None,
            lagged_s: None,
            refresh_s: true,
            mu_prev: Vec::new(),
            guide_scale,
            gbuf: vec![Pt3::origin(); nb],
            merit_rho: 0.0,
            merit_h: 1.0,
            violation: 0.0,
            last: KktStats::default(),
        }
    }

    /// Starts a step: the time statistics of [`KktStats`] sum over the step's solves (one per
    /// Newton iteration of the IPC contact model).
    pub fn begin_step(&mut self) {
        self.last.t_kkt = 0.0;
        self.last.t_shadow_llt = 0.0;
        self.last.solves = 0;
        self.merit_rho = 0.0;
    }

    /// The constraints this solver enforces.
    pub fn constraints(&self) -> &TrackingConstraints {
        &self.cons
    }

    /// The method.
    pub fn method(&self) -> KktMethod {
        self.method
    }

    /// (Δv, μ) of the KKT system with right-hand side `r` by this solver's method.
    fn solve_method(&mut self, sys: &ImplicitSystem, r: &[f64]) -> shells::Result<(Vec<f64>, Vec<f64>)> {
        match self.method {
            KktMethod::SchurPcg { refresh_iters } => self.solve_schur_pcg(sys, r, refresh_iters),
            KktMethod::Penalty { stiffness } => self.solve_penalty(sys, r, stiffness),
            KktMethod::AugmentedLagrangian { alpha } => self.solve_augmented(sys, r, alpha),
            _ => self.solve_kkt(sys, r),
        }
    }

    fn build_cft(&mut self, sys: &ImplicitSystem) {
        if self.cft.is_some() {
            return;
        }
        let nf = sys.dofs.n_free();
        let mut cft: Vec<Vec<(u32, f64)>> = vec![Vec::new(); nf];
        for i in 0..self.cons.len() {
            let (c, v) = self.cons.c.row(i);
            for (&l, &w) in c.iter().zip(v) {
                let f = sys.dofs.free_index[l as usize];
                if f != NONE {
                    cft[f as usize].push((i as u32, w));
                }
            }
        }
        self.cft = Some(cft);
    }

    /// Ĉ x for x of length 3 n_free → length 3K.
    fn c_mul(&self, x: &[f64], out: &mut [f64]) {
        c_mul(self.cft.as_ref().expect("built before use"), x, out);
    }

    /// Ĉᵀ μ → length 3 n_free.
    fn ct_mul(&self, mu: &[f64], out: &mut [f64]) {
        ct_mul(self.cft.as_ref().expect("built before use"), mu, out);
    }

    /// [`KktMethod::AugmentedLagrangian`]: pattern and analysis on first use or when A's pattern
    /// changes, then one LLᵀ and warm-started Uzawa solves.
    fn solve_augmented(&mut self, sys: &ImplicitSystem, r: &[f64], alpha: f64) -> shells::Result<(Vec<f64>, Vec<f64>)> {
        let cft = self.cft.as_ref().expect("built before use");
        if !self.al.as_ref().is_some_and(|al| al.fits(sys.a)) {
            self.al = Some(AugmentedLagrangian::new(sys.a, cft, self.cons.len()).map_err(core)?);
        }
        let al = self.al.as_mut().expect("built above");
        let (dv, mu, res) = al.solve(sys.a, sys.b, r, cft, alpha).map_err(core)?;
        self.last.refinement_residual = res;
        self.last.nnz_l = al.nnz_l();
        Ok((dv, mu))
    }

    fn build_kkt(&mut self, a: &Csc) -> shells::Result<()> {
        let n = a.nrows();
        let m = 3 * self.cons.len();
        let cft = self.cft.as_ref().expect("built before use");
        let sa = a.symbolic();
        let mut col_ptr = Vec::with_capacity(n + m + 1);
        let mut row_idx = Vec::new();
        let mut a_map = vec![0usize; a.val().len()];
        col_ptr.push(0);
        for j in 0..n {
            for k in sa.col_range(j) {
                a_map[k] = row_idx.len();
                row_idx.push(sa.row_idx()[k]);
            }
            for &(i, _) in &cft[j / 3] {
                row_idx.push(n + 3 * i as usize + j % 3);
            }
            col_ptr.push(row_idx.len());
        }
        for r in 0..m {
            row_idx.push(n + r);
            col_ptr.push(row_idx.len());
        }
        let mut val = vec![0.0; row_idx.len()];
        for j in 0..n {
            let start = col_ptr[j] + sa.col_range(j).len();
            for (k, &(_, w)) in cft[j / 3].iter().enumerate() {
                val[start + k] = w;
            }
        }
        let sym = SymbolicSparseColMat::new_checked(n + m, n + m, col_ptr, None, row_idx);
        let exact: Csc = SparseColMat::new(sym, val);
        let ordering = match self.method {
            KktMethod::ConstraintLastLdlt => {
                let mut p = self.a_perm.clone();
                p.extend(n..n + m);
                Ordering::Custom(p)
            }
            KktMethod::InterleavedLdlt => Ordering::Custom(interleaved_order(&self.a_perm, cft, m)),
            // AMD on vertices and regions (3 rows each): the three multipliers of a region
            // each couple to one coordinate, which makes scalar AMD split the vertex blocks.
            _ => Ordering::AmdBlocks(
                (0..n as u32).map(|j| j / 3).chain((0..m as u32).map(|r| n as u32 / 3 + r / 3)).collect(),
            ),
        };
        let factor = match self.method {
            KktMethod::Schur => {
                KktFactor::Bordered(Box::new(BorderedLlt::analyze(&exact, n, &self.a_perm).map_err(core)?))
            }
            _ => KktFactor::Ldlt(SparseLdlt::analyze(&exact, ordering).map_err(core)?),
        };
        let factor_mat = match self.method {
            KktMethod::AmdRegularizedLdlt { .. } | KktMethod::Compliant { .. } => Some(exact.clone()),
            _ => None,
        };
        self.kkt = Some(KktCache { n, m, exact, factor_mat, a_map, a_pattern: SparsityPattern::of(a), factor });
        Ok(())
    }

    fn solve_kkt(&mut self, sys: &ImplicitSystem, r: &[f64]) -> shells::Result<(Vec<f64>, Vec<f64>)> {
        if self.kkt.as_ref().is_none_or(|k| k.n != sys.a.nrows() || !k.a_pattern.matches(sys.a)) {
            self.build_kkt(sys.a)?;
        }
        let method = self.method;
        let refine = self.refine_steps;
        let kkt = self.kkt.as_mut().expect("built above");
        let (n, m) = (kkt.n, kkt.m);
        let av = sys.a.val();
        let max_diag = (0..n)
            .map(|j| {
                let s = sys.a.symbolic();
                s.col_range(j).find(|&k| s.row_idx()[k] == j).map_or(0.0, |k| av[k].abs())
            })
            .fold(0.0f64, f64::max);
        {
            let ev = kkt.exact.val_mut();
            for (k, &p) in kkt.a_map.iter().enumerate() {
                ev[p] = av[k];
            }
        }
        let shift = match method {
            KktMethod::AmdRegularizedLdlt { delta } => delta * max_diag,
            KktMethod::Compliant { compliance } => compliance,
            _ => 0.0,
        };
        if let Some(fm) = kkt.factor_mat.as_mut() {
            fm.val_mut().copy_from_slice(kkt.exact.val());
            let s = fm.symbolic();
            let diag: Vec<usize> = (n..n + m).map(|j| s.col_range(j).start).collect();
            let fv = fm.val_mut();
            for p in diag {
                fv[p] = -shift;
            }
        }
        let mut rhs = sys.b.to_vec();
        rhs.extend_from_slice(r);
        let ldlt = match &mut kkt.factor {
            KktFactor::Bordered(bf) => {
                let min_diag = (0..n)
                    .map(|j| {
                        let s = sys.a.symbolic();
                        s.col_range(j).find(|&k| s.row_idx()[k] == j).map_or(f64::INFINITY, |k| av[k])
                    })
                    .fold(f64::INFINITY, f64::min);
                // First γ: rows have unit sums, so S_ii ≲ 1/λ_min(A) ~ 1/min diag(A) (a guess;
                // BorderedLlt retries with 4γ when it is too small).
                bf.factor(&kkt.exact, 4.0 / min_diag.max(1e-300)).map_err(core)?;
                let (mut x, mut mu) = bf.solve(sys.b, r).map_err(core)?;
                let mut res = f64::NAN;
                for it in 0..=refine {
                    let mut sol = x.clone();
                    sol.extend_from_slice(&mu);
                    let mut kx = vec![0.0; n + m];
                    geom_core::linalg::sym_mul_vec(&kkt.exact, &sol, &mut kx);
                    let d: Vec<f64> = rhs.iter().zip(&kx).map(|(a, b)| a - b).collect();
                    let norm = |v: &[f64]| v.iter().map(|x| x * x).sum::<f64>().sqrt();
                    res = norm(&d) / norm(&rhs).max(1e-300);
                    if it == refine {
                        break;
                    }
                    let (dx, dmu) = bf.solve(&d[..n], &d[n..]).map_err(core)?;
                    x.iter_mut().zip(&dx).for_each(|(a, b)| *a += b);
                    mu.iter_mut().zip(&dmu).for_each(|(a, b)| *a += b);
                }
                self.last.refinement_residual = res;
                self.last.refine_steps_done = refine;
                self.last.nnz_l = bf.nnz_l();
                return Ok((x, mu));
            }
            KktFactor::Ldlt(l) => l,
        };
        let mut reg = Regularization::kkt(n, m);
        reg.eps = 1e-13 * max_diag;
        reg.delta = 1e-8 * max_diag.max(1e-300);
        let fmat = kkt.factor_mat.as_ref().unwrap_or(&kkt.exact);
        ldlt.factor(fmat, &reg).map_err(core)?;
        let mut x = vec![0.0; n + m];
        self.last.refine_steps_done = if matches!(method, KktMethod::Compliant { .. }) { 0 } else { refine };
        let res = match method {
            KktMethod::Compliant { .. } => ldlt.solve_refined(fmat, &rhs, &mut x, 0),
            KktMethod::AmdRegularizedLdlt { .. } => {
                // Warm-started shift (one proximal-point iteration of the method of
                // multipliers per step): the shifted rows read ĈΔv − δμ = r − δμ_prev, so the
                // shift's error is δ(μ − μ_prev) instead of δμ, at no cost. Then `refine_steps`
                // rounds of refinement against the exact KKT, and more (up to
                // `MAX_SHIFT_REFINE_STEPS`) while the constraint rows still miss r by more than
                // `SHIFT_RESIDUAL_TOL`·L in position (h_eff·‖(ĈΔv − r)_i‖, the residual_pre
                // this solve would leave).
                x.copy_from_slice(&rhs);
                if self.mu_prev.len() == m {
                    x[n..].iter_mut().zip(&self.mu_prev).for_each(|(xi, mp)| *xi -= shift * mp);
                }
                let cft = self.cft.as_ref().expect("built before use");
                let tol = SHIFT_RESIDUAL_TOL * self.guide_scale / sys.h_eff.max(1e-300);
                let mut cx = vec![0.0; m];
                let mut misses = |x: &[f64]| {
                    c_mul(cft, &x[..n], &mut cx);
                    cx.chunks(3).zip(r.chunks(3)).any(|(a, b)| {
                        ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt() > tol
                    })
                };
                let max_steps = refine.max(MAX_SHIFT_REFINE_STEPS);
                let mut done = 0;
                let solved = ldlt.solve_in_place(&mut x).and_then(|()| {
                    // `refine` returns the residual after its step: only an unrefined solve
                    // needs the extra residual evaluation.
                    let mut res = None;
                    while done < refine || (done < max_steps && misses(&x)) {
                        res = Some(ldlt.refine(&kkt.exact, &rhs, &mut x, 1)?);
                        done += 1;
                    }
                    res.map_or_else(|| ldlt.refine(&kkt.exact, &rhs, &mut x, 0), Ok)
                });
                self.last.refine_steps_done = done;
                solved
            }
            _ => ldlt.solve_refined(&kkt.exact, &rhs, &mut x, refine),
        }
        .map_err(core)?;
        self.last.refinement_residual = res;
        self.last.nnz_l = ldlt.nnz_l();
        let mu = x.split_off(n);
        if matches!(method, KktMethod::AmdRegularizedLdlt { .. }) {
            self.mu_prev.clone_from(&mu);
        }
        Ok((x, mu))
    }

    /// Exact S by 3K dense-RHS solves with the LLᵀ of A (SchurPcg's refresh of its lagged S).
    fn solve_schur_dense(&mut self, sys: &ImplicitSystem, r: &[f64]) -> shells::Result<(Vec<f64>, Vec<f64>)> {
        let n = sys.a.nrows();
        let m = 3 * self.cons.len();
        let llt = self.llt.get_or_insert_with(|| SparseLlt::from_symbolic(&self.a_symbolic));
        llt.factor(sys.a).map_err(core)?;
        // Y = A⁻¹ Ĉᵀ (n × 3K).
        let cft = self.cft.as_ref().expect("built before use");
        let mut y = Mat::<f64>::zeros(n, m);
        for (f, row) in cft.iter().enumerate() {
            for &(i, w) in row {
                for d in 0..3 {
                    y[(3 * f + d, 3 * i as usize + d)] = w;
                }
            }
        }
        llt.solve_many_in_place(&mut y).map_err(core)?;
        let mut x0 = sys.b.to_vec();
        llt.solve_in_place(&mut x0).map_err(core)?;
        self.last.nnz_l = llt.nnz_l();
        // S = Ĉ Y (3K × 3K, SPD when Ĉ has full row rank).
        let mut s = Mat::<f64>::zeros(m, m);
        for (f, row) in cft.iter().enumerate() {
            for &(i, w) in row {
                for d in 0..3 {
                    let ri = 3 * i as usize + d;
                    for c in 0..m {
                        s[(ri, c)] += w * y[(3 * f + d, c)];
                    }
                }
            }
        }
        let sf = dense::llt(&s).map_err(core)?;
        self.lagged_s = Some(sf.clone());
        let sf = self.lagged_s.as_ref().expect("just set");
        let mut cx = vec![0.0; m];
        self.c_mul(&x0, &mut cx);
        let mut mu: Vec<f64> = cx.iter().zip(r).map(|(a, b)| a - b).collect();
        sf.solve_in_place(&mut mu).map_err(core)?;
        let mut dv = x0;
        for (jj, d) in dv.iter_mut().enumerate() {
            let mut acc = 0.0;
            for (c, &mc) in mu.iter().enumerate() {
                acc += y[(jj, c)] * mc;
            }
            *d -= acc;
        }
        self.last.refinement_residual = geom_core::linalg::rel_residual(sys.a, &dv, &{
            let mut ctm = vec![0.0; n];
            self.ct_mul(&mu, &mut ctm);
            sys.b.iter().zip(&ctm).map(|(b, c)| b - c).collect::<Vec<_>>()
        });
        Ok((dv, mu))
    }

    fn solve_schur_pcg(
        &mut self,
        sys: &ImplicitSystem,
        r: &[f64],
        refresh: u32,
    ) -> shells::Result<(Vec<f64>, Vec<f64>)> {
        let n = sys.a.nrows();
        let m = 3 * self.cons.len();
        if self.refresh_s || self.lagged_s.is_none() {
            // Exact S at this step (3K solves) and its dense Cholesky; then the solve is direct.
            let (dv, mu) = self.solve_schur_dense(sys, r)?;
            self.refresh_s = false;
            return Ok((dv, mu));
        }
        let llt = self.llt.get_or_insert_with(|| SparseLlt::from_symbolic(&self.a_symbolic));
        llt.factor(sys.a).map_err(core)?;
        self.last.nnz_l = llt.nnz_l();
        let mut x0 = sys.b.to_vec();
        llt.solve_in_place(&mut x0).map_err(core)?;
        let mut rhs = vec![0.0; m];
        self.c_mul(&x0, &mut rhs);
        rhs.iter_mut().zip(r).for_each(|(a, b)| *a -= b);
        let prec = self.lagged_s.as_ref().expect("checked above");
        let dot = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(x, y)| x * y).sum::<f64>();
        let bnorm = dot(&rhs, &rhs).sqrt();
        let mut mu = vec![0.0; m];
        let mut ay = vec![0.0; n]; // A⁻¹Ĉᵀμ accumulated
        let mut res = rhs.clone();
        let mut z = res.clone();
        prec.solve_in_place(&mut z).map_err(core)?;
        let mut p = z.clone();
        let mut rz = dot(&res, &z);
        let mut it = 0u32;
        let llt = self.llt.as_ref().expect("factored above");
        while dot(&res, &res).sqrt() > 1e-10 * bnorm.max(1e-300) && it < 50 {
            it += 1;
            let mut w = vec![0.0; n];
            self.ct_mul(&p, &mut w);
            llt.solve_in_place(&mut w).map_err(core)?;
            let mut sp = vec![0.0; m];
            self.c_mul(&w, &mut sp);
            let alpha = rz / dot(&p, &sp);
            for i in 0..m {
                mu[i] += alpha * p[i];
                res[i] -= alpha * sp[i];
            }
            ay.iter_mut().zip(&w).for_each(|(a, b)| *a += alpha * b);
            z.copy_from_slice(&res);
            prec.solve_in_place(&mut z).map_err(core)?;
            let rz_new = dot(&res, &z);
            let beta = rz_new / rz;
            rz = rz_new;
            for i in 0..m {
                p[i] = z[i] + beta * p[i];
            }
        }
        if it > refresh {
            self.refresh_s = true;
        }
        let dv: Vec<f64> = x0.iter().zip(&ay).map(|(a, b)| a - b).collect();
        self.last.refinement_residual = dot(&res, &res).sqrt() / bnorm.max(1e-300);
        Ok((dv, mu))
    }

    fn solve_penalty(&mut self, sys: &ImplicitSystem, r: &[f64], kp: f64) -> shells::Result<(Vec<f64>, Vec<f64>)> {
        let n = sys.a.nrows();
        let cft = self.cft.as_ref().expect("built before use");
        let sa = sys.a.symbolic();
        let av = sys.a.val();
        let mut t = Triplets::new(n, n);
        for j in 0..n {
            for k in sa.col_range(j) {
                t.push(sa.row_idx()[k] as u32, j as u32, av[k]);
            }
        }
        // k_p ĈᵀĈ, lower triangle: entries (3f+d, 3g+d) for f, g in a common constraint.
        let k = self.cons.len();
        let mut rows: Vec<Vec<(u32, f64)>> = vec![Vec::new(); k];
        for (f, row) in cft.iter().enumerate() {
            for &(i, w) in row {
                rows[i as usize].push((f as u32, w));
            }
        }
        for row in &rows {
            for &(f, wf) in row {
                for &(g, wg) in row {
                    if f >= g {
                        for d in 0..3 {
                            t.push(3 * f + d, 3 * g + d, kp * wf * wg);
                        }
                    }
                }
            }
        }
        let mat = Csr::from_triplets(&t).to_csc();
        let sym = match &self.penalty_symbolic {
            Some(s) => s.clone(),
            None => {
                let s = LltSymbolic::analyze(&mat, &Ordering::Amd).map_err(core)?;
                self.penalty_symbolic = Some(s.clone());
                s
            }
        };
        let mut llt = SparseLlt::from_symbolic(&sym);
        llt.factor(&mat).map_err(|_| shells::Error::FactorizationFailed)?;
        let mut ctr = vec![0.0; n];
        self.ct_mul(r, &mut ctr);
        let mut x: Vec<f64> = sys.b.iter().zip(&ctr).map(|(b, c)| b + kp * c).collect();
        llt.solve_in_place(&mut x).map_err(core)?;
        self.last.nnz_l = llt.nnz_l();
        // Equivalent multiplier μ = k_p (r − ĈΔv) (the penalty force).
        let mut cx = vec![0.0; r.len()];
        self.c_mul(&x, &mut cx);
        let mu: Vec<f64> = r.iter().zip(&cx).map(|(a, b)| kp * (b - a)).collect();
        self.last.refinement_residual = 0.0;
        Ok((x, mu))
    }
}

/// The A-block order `a_perm` (`perm[new] = old`, length n) with multiplier row `n + r` inserted
/// right after the last DOF of its support (`cft`: per free vertex, its constraints), so each
/// multiplier is eliminated as soon as its whole support is (see [`KktMethod::InterleavedLdlt`]).
fn interleaved_order(a_perm: &[usize], cft: &[Vec<(u32, f64)>], m: usize) -> Vec<usize> {
    let n = a_perm.len();
    let mut pos = vec![0usize; n];
    for (k, &j) in a_perm.iter().enumerate() {
        pos[j] = k;
    }
    // last[r]: position in a_perm of the last support DOF of multiplier row r.
    let mut last = vec![0usize; m];
    for (f, row) in cft.iter().enumerate() {
        for &(i, _) in row {
            for d in 0..3 {
                let r = 3 * i as usize + d;
                last[r] = last[r].max(pos[3 * f + d]);
            }
        }
    }
    let mut after: Vec<Vec<usize>> = vec![Vec::new(); n];
    for (r, &k) in last.iter().enumerate() {
        after[k].push(r);
    }
    let mut p = Vec::with_capacity(n + m);
    for (k, &j) in a_perm.iter().enumerate() {
        p.push(j);
        p.extend(after[k].iter().map(|&r| n + r));
    }
    p
}

impl VelocitySolve for TrackingSolver {
    /// ρ·Σᵢ‖gᵢ(q, t_next)‖/h_eff, the ℓ1 exact penalty of the constraints at positions `q`
    /// with ρ = 2·max‖μᵢ‖ of this step's solves (see [`VelocitySolve::merit`]).
    fn merit(&mut self, q: &[Pt3]) -> f64 {
        if self.merit_rho == 0.0 {
            return 0.0;
        }
        let mut g = vec![Vec3::zeros(); self.cons.len()];
        self.cons.residual(&self.gbuf, q, &mut g);
        self.merit_rho * g.iter().map(|x| x.norm()).sum::<f64>() / self.merit_h
    }

    fn constraint_violation(&self) -> f64 {
        self.violation
    }

    /// True for the factorisations that analyse the KKT (or A_ρ) pattern they are given and
    /// re-analyse when it changes; false for the methods that reuse the mesh pattern's
    /// symbolic analysis of A (Schur, SchurPcg, the shadow LLᵀ) or cache their own once
    /// (Penalty), and when a compared method is one of those.
    fn accepts_pattern_changes(&self) -> bool {
        let own = matches!(
            self.method,
            KktMethod::ConstraintLastLdlt
                | KktMethod::InterleavedLdlt
                | KktMethod::AmdRegularizedLdlt { .. }
                | KktMethod::Compliant { .. }
                | KktMethod::AugmentedLagrangian { .. }
        );
        own && !self.shadow && self.shadows.iter().all(|s| s.accepts_pattern_changes())
    }

    fn solve(&mut self, sys: &ImplicitSystem) -> shells::Result<Vec<f64>> {
        let t0 = Instant::now();
        self.build_cft(sys);
        self.last.guide_held = self.guide.sample(sys.t_next, &mut self.gbuf);
        let k = self.cons.len();
        let mut g = vec![Vec3::zeros(); k];
        self.cons.residual(&self.gbuf, sys.q_pred, &mut g);
        self.violation = g.iter().map(|x| x.norm()).fold(0.0, f64::max) / sys.h_eff;
        let c = self.correction_fraction / sys.h_eff;
        let r: Vec<f64> = g.iter().flat_map(|gi| [c * gi.x, c * gi.y, c * gi.z]).collect();
        let (dv, mu) = self.solve_method(sys, &r)?;
        self.last.solves += 1;
        // Exact-penalty weight above the multipliers (constraint rows cᵢ = gᵢ/h_eff, m/s).
        let mu_max = mu.chunks(3).map(|c| (c[0] * c[0] + c[1] * c[1] + c[2] * c[2]).sqrt()).fold(0.0, f64::max);
        self.merit_rho = self.merit_rho.max(2.0 * mu_max);
        self.merit_h = sys.h_eff;
        // Summed over the step's Newton iterations (IPC solves one KKT system per iteration;
        // `begin_step` resets).
        self.last.t_kkt += t0.elapsed().as_secs_f64();
        // Residual before collisions: g(q⁰ + h_eff Δv) on every vertex (constrained ones at q⁰).
        let mut q_end = sys.q_pred.to_vec();
        for (f, &v) in sys.dofs.free_vertices.iter().enumerate() {
            q_end[v as usize] += sys.h_eff * Vec3::new(dv[3 * f], dv[3 * f + 1], dv[3 * f + 2]);
        }
        self.last.residual_pre = self.cons.max_residual(&self.gbuf, &q_end);
        let mut fc = vec![0.0; dv.len()];
        self.ct_mul(&mu, &mut fc);
        self.last.max_constraint_force =
            fc.chunks(3).map(|c| (c[0] * c[0] + c[1] * c[1] + c[2] * c[2]).sqrt()).fold(0.0, f64::max) / sys.h;
        if self.shadow {
            let ts = Instant::now();
            let llt = self.shadow_llt.get_or_insert_with(|| SparseLlt::from_symbolic(&self.a_symbolic));
            llt.factor(sys.a).map_err(core)?;
            self.last.t_shadow_llt += ts.elapsed().as_secs_f64();
        }
        let scale = dv.iter().fold(0.0f64, |a, x| a.max(x.abs())).max(1e-300);
        let mut compare = Vec::with_capacity(self.shadows.len());
        for sh in &mut self.shadows {
            let ts = Instant::now();
            sh.build_cft(sys);
            let (dvs, _) = sh.solve_method(sys, &r)?;
            let t_solve = ts.elapsed().as_secs_f64();
            let diff = dvs.iter().zip(&dv).fold(0.0f64, |a, (x, y)| a.max((x - y).abs()));
            compare.push(CompareStats { t_solve, rel_diff: diff / scale, nnz_l: sh.last.nnz_l });
        }
        self.last.compare = compare;
        Ok(dv)
    }
}

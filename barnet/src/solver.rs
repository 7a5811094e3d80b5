//! [`FdmSolver`]: the linear force density method (spec §3.2, the seed's "Equation (4)",
//! reconstructed after Schek 1974):
//!
//! `D x = p_x − D_f x_f,  D y = p_y − D_f y_f,  D z = p_z − D_f z_f`, with `D = Cᵀ Q C` and
//! `D_f = Cᵀ Q C_f`.
//!
//! The three coordinates share one matrix, so one factorisation serves all three
//! back-substitutions, and a new frame whose force densities are unchanged costs only the
//! right-hand side and the back-substitutions. When q changes ([`FdmSolver::update_q`]) only the
//! values of `D` change: numeric refactorisation with the cached symbolic analysis.
//!
//! Paths: `n ≤ dense_threshold` ⇒ dense Cholesky (`linalg::dense::llt`); otherwise sparse
//! Cholesky (`linalg::SparseLlt`, AMD ordering, analysed once). If the Cholesky fails (negative
//! "compression" force densities make `D` indefinite, or an extreme stiffness ratio leaves a
//! pivot below the singularity threshold) the solver falls back to `linalg::SparseLdlt` and
//! sets [`FdmSolver::is_indefinite`]; a matrix that is singular to working precision is
//! reported as [`BarNetError::Singular`] (spec §8).
//!
//! Accuracy: after each solve the relative residual `‖b − D x‖ / ‖b‖` (Frobenius over the three
//! coordinates) is computed; while it exceeds `refine_tol` (1e-12), up to `refine_steps`
//! rounds of iterative refinement `x ← x + D⁻¹ (b − D x)` are applied (spec §8, huge ratios).

use crate::assemble::Assembly;
use crate::error::{check_finite, check_len, BarNetError, Result};
use crate::net::{BarNet, NetReport};
use geom_core::faer::Mat;
use geom_core::linalg::{dense, Ordering, Regularization, SparseLdlt, SparseLlt, SINGULAR_PIVOT_TOL};
use geom_core::math::{Pt3, Vec3};

/// Options of [`FdmSolver`] (spec §4).
#[derive(Clone, Debug)]
pub struct FdmOptions {
    /// Use the dense Cholesky when the number of free nodes is at most this (default 64).
    pub dense_threshold: usize,
    /// Maximum iterative-refinement steps per solve (default 2), applied only while the relative
    /// residual exceeds `refine_tol`.
    pub refine_steps: u32,
    /// Relative-residual threshold that triggers refinement (default 1e-12, spec §5/§8).
    pub refine_tol: f64,
    /// Fill-reducing ordering of the sparse path (default AMD).
    pub ordering: Ordering,
}

impl Default for FdmOptions {
    fn default() -> Self {
        Self { dense_threshold: 64, refine_steps: 2, refine_tol: 1e-12, ordering: Ordering::Amd }
    }
}

/// Which factorisation the solver holds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SolverPath {
    /// No free nodes: every solve is a no-op.
    Empty,
    /// Dense Cholesky.
    Dense,
    /// Sparse Cholesky (cached symbolic analysis).
    Sparse,
    /// Sparse LDLᵀ (indefinite or numerically near-singular `D`).
    Ldlt,
}

enum Factor {
    Empty,
    Dense(dense::DenseLlt),
    Sparse,
    Ldlt(SparseLdlt),
}

/// Per-solve figures.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SolveInfo {
    /// Final relative residual `‖b − D x‖_F / ‖b‖_F` over the three coordinates (absolute when
    /// `b = 0`).
    pub rel_residual: f64,
    /// Refinement steps applied.
    pub refinements: u32,
}

/// The force-density equilibrium solver of one net; see the module docs.
pub struct FdmSolver {
    net: BarNet,
    report: NetReport,
    free: Vec<u32>,
    fixed: Vec<u32>,
    index: Vec<u32>,
    asm: Assembly,
    opts: FdmOptions,
    /// Sparse Cholesky with its cached analysis (sparse path; analysed on first use).
    llt: Option<SparseLlt>,
    factor: Factor,
}

impl std::fmt::Debug for FdmSolver {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("FdmSolver")
            .field("n_free", &self.free.len())
            .field("n_fixed", &self.fixed.len())
            .field("path", &self.path())
            .finish()
    }
}

/// Threshold of the LDLᵀ singularity probe: a relative forward error above this on a known
/// solution means `D` is singular to working precision (condition number ≳ 1e12).
pub const SINGULAR_PROBE_TOL: f64 = 1e-4;

impl FdmSolver {
    /// Validates the net ([`BarNet::validate`]: unanchored parts, self-loops, bad indices and
    /// non-finite q are errors found before any factorisation), assembles `D`, `D_f` and
    /// factorises `D`.
    pub fn new(net: &BarNet, o: &FdmOptions) -> Result<Self> {
        let report = net.validate()?;
        let (free, fixed, index) = net.index_maps();
        let asm = Assembly::new(net, free.len(), fixed.len(), &index);
        let mut s = Self {
            net: net.clone(),
            report,
            free,
            fixed,
            index,
            asm,
            opts: o.clone(),
            llt: None,
            factor: Factor::Empty,
        };
        s.factorize()?;
        Ok(s)
    }

    fn factorize(&mut self) -> Result<()> {
        let n = self.free.len();
        self.factor = Factor::Empty;
        if n == 0 {
            return Ok(());
        }
        if n <= self.opts.dense_threshold {
            let mut a = Mat::<f64>::zeros(n, n);
            for i in 0..n {
                let (c, v) = self.asm.d.row(i);
                for (&j, &x) in c.iter().zip(v) {
                    a[(i, j as usize)] = x;
                }
            }
            match dense::llt(&a) {
                // Same singularity rule as the sparse path: pivot L_kk² > tol · a_kk.
                Ok(f) if (0..n).all(|k| f.l()[(k, k)].powi(2) > SINGULAR_PIVOT_TOL * a[(k, k)]) => {
                    self.factor = Factor::Dense(f);
                    return Ok(());
                }
                Ok(_) => {}
                Err(geom_core::Error::NotPositiveDefinite { .. }) => {}
                Err(e) => return Err(e.into()),
            }
        } else {
            if self.llt.is_none() {
                self.llt = Some(SparseLlt::analyze(&self.asm.d_lower, self.opts.ordering.clone())?);
            }
            let llt = self.llt.as_mut().expect("analysed just above");
            match llt.factor(&self.asm.d_lower) {
                Ok(()) => {
                    self.factor = Factor::Sparse;
                    return Ok(());
                }
                Err(geom_core::Error::NotPositiveDefinite { .. }) => {}
                Err(e) => return Err(e.into()),
            }
        }
        self.factor_ldlt()
    }

    /// LDLᵀ fallback (indefinite or numerically near-singular `D`), with a singularity probe.
    fn factor_ldlt(&mut self) -> Result<()> {
        let n = self.free.len();
        let mut ldlt = match &self.llt {
            Some(llt) => SparseLdlt::from_symbolic(&llt.symbolic()),
            None => SparseLdlt::analyze(&self.asm.d_lower, self.opts.ordering.clone())?,
        };
        // No regularisation: a zero pivot is a singular matrix, not something to perturb.
        let reg = Regularization { signs: None, delta: 0.0, eps: 0.0 };
        if let Err(e) = ldlt.factor(&self.asm.d_lower, &reg) {
            return Err(BarNetError::Singular(format!("LDLT factorisation failed: {e}")));
        }
        // Probe: solve D z = D z* for a known z* and check the forward error.
        let zs: Vec<f64> = (0..n).map(|i| 1.0 + 0.5 * ((i as f64) * 0.7).sin()).collect();
        let mut b = vec![0.0; n];
        self.asm.d_mul(&zs, &mut b);
        let mut z = vec![0.0; n];
        let probe = ldlt.solve_refined(&self.asm.d_lower, &b, &mut z, 2);
        let err = match probe {
            Ok(_) => {
                let num: f64 = z.iter().zip(&zs).map(|(a, b)| (a - b) * (a - b)).sum::<f64>().sqrt();
                let den: f64 = zs.iter().map(|a| a * a).sum::<f64>().sqrt();
                num / den
            }
            Err(_) => f64::INFINITY,
        };
        if err.is_nan() || err > SINGULAR_PROBE_TOL {
            return Err(BarNetError::Singular(format!(
                "LDLT probe solve has relative forward error {err:.3e} > {SINGULAR_PROBE_TOL:e} \
                 (check the signs of the force densities: compression bars can cancel the net's stiffness)"
            )));
        }
        self.factor = Factor::Ldlt(ldlt);
        Ok(())
    }

    /// Replaces every bar's force density (net bar order) and refactorises: numeric only, the
    /// symbolic analysis of the sparse path is reused (spec §3.6). If a force density becomes or
    /// was ≤ 0 the anchoring check is repeated first.
    ///
    /// Errors: wrong length, non-finite q, `Unanchored`, `Singular`.
    pub fn update_q(&mut self, q: &[f64]) -> Result<()> {
        check_len("force densities q", self.net.bars.len(), q.len())?;
        check_finite("force densities q", q)?;
        let recheck = q.iter().zip(&self.net.bars).any(|(&a, b)| a <= 0.0 || b.q <= 0.0);
        for (b, &v) in self.net.bars.iter_mut().zip(q) {
            b.q = v;
        }
        if recheck {
            self.report = self.net.validate()?;
        }
        self.asm.set_q(q);
        self.factorize()
    }

    /// Solves the equilibrium for loads on the free nodes (in free-node order) and positions of
    /// the fixed nodes (fixed-node order); returns the free-node positions.
    pub fn solve(&self, loads_free: &[Vec3], fixed_pos: &[Pt3]) -> Result<Vec<Pt3>> {
        let mut out = Vec::new();
        self.solve_into(loads_free, fixed_pos, &mut out)?;
        Ok(out)
    }

    /// [`FdmSolver::solve`] into a reusable buffer, returning the residual figures.
    ///
    /// Errors: wrong lengths, `NonFinite` loads or positions (checked before touching the
    /// factorisation), solver failures.
    pub fn solve_into(&self, loads_free: &[Vec3], fixed_pos: &[Pt3], out: &mut Vec<Pt3>) -> Result<SolveInfo> {
        let (n, nf) = (self.free.len(), self.fixed.len());
        check_len("free-node loads", n, loads_free.len())?;
        check_len("fixed-node positions", nf, fixed_pos.len())?;
        check_finite("free-node loads", geom_core::linalg::flat_vec(loads_free))?;
        check_finite("fixed-node positions", geom_core::linalg::flat(fixed_pos))?;
        let b = self.rhs(loads_free, fixed_pos);
        let mut x = b.clone();
        let info = self.solve_columns(&b, &mut x)?;
        out.clear();
        out.extend((0..n).map(|i| Pt3::new(x[i], x[n + i], x[2 * n + i])));
        Ok(info)
    }

    /// Column-major right-hand side `b_c = p_c − D_f x_f,c` (3 columns of length n).
    fn rhs(&self, loads: &[Vec3], fixed_pos: &[Pt3]) -> Vec<f64> {
        let (n, nf) = (self.free.len(), self.fixed.len());
        let mut b = vec![0.0; 3 * n];
        let mut xf = vec![0.0; nf];
        let mut t = vec![0.0; n];
        for c in 0..3 {
            for (k, p) in fixed_pos.iter().enumerate() {
                xf[k] = p[c];
            }
            self.asm.df_mul(&xf, &mut t);
            for i in 0..n {
                b[c * n + i] = loads[i][c] - t[i];
            }
        }
        b
    }

    /// Solves `D X = B` for the three columns of `b` (column-major, 3n) into `x`, refining while
    /// the residual is above `refine_tol`.
    pub fn solve_columns(&self, b: &[f64], x: &mut [f64]) -> Result<SolveInfo> {
        let n = self.free.len();
        check_len("right-hand side (3 columns)", 3 * n, b.len())?;
        check_len("solution (3 columns)", 3 * n, x.len())?;
        if n == 0 {
            return Ok(SolveInfo::default());
        }
        x.copy_from_slice(b);
        self.back_substitute(x)?;
        let mut r = vec![0.0; 3 * n];
        let mut rel = self.residual_columns(b, x, &mut r);
        let mut steps = 0;
        while rel > self.opts.refine_tol && steps < self.opts.refine_steps {
            self.back_substitute(&mut r)?;
            for (xi, di) in x.iter_mut().zip(&r) {
                *xi += di;
            }
            steps += 1;
            rel = self.residual_columns(b, x, &mut r);
        }
        Ok(SolveInfo { rel_residual: rel, refinements: steps })
    }

    /// In-place solve with the current factorisation, 3 columns of length n.
    fn back_substitute(&self, x: &mut [f64]) -> Result<()> {
        let n = self.free.len();
        match &self.factor {
            Factor::Empty => Ok(()),
            Factor::Dense(f) => {
                let mut m = Mat::from_fn(n, 3, |i, c| x[c * n + i]);
                f.solve_many_in_place(&mut m)?;
                copy_back(&m, x);
                Ok(())
            }
            Factor::Sparse => {
                let llt = self.llt.as_ref().expect("sparse path holds an analysed, factored SparseLlt");
                let mut m = Mat::from_fn(n, 3, |i, c| x[c * n + i]);
                llt.solve_many_in_place(&mut m)?;
                copy_back(&m, x);
                Ok(())
            }
            Factor::Ldlt(l) => {
                for col in x.chunks_mut(n) {
                    l.solve_in_place(col)?;
                }
                Ok(())
            }
        }
    }

    /// `r = b − D x` (3 columns), returns `‖r‖_F / ‖b‖_F` (absolute when `b = 0`).
    fn residual_columns(&self, b: &[f64], x: &[f64], r: &mut [f64]) -> f64 {
        let n = self.free.len();
        for c in 0..3 {
            let rc = &mut r[c * n..(c + 1) * n];
            self.asm.d_mul(&x[c * n..(c + 1) * n], rc);
            for (ri, bi) in rc.iter_mut().zip(&b[c * n..(c + 1) * n]) {
                *ri = bi - *ri;
            }
        }
        let nb = geom_core::linalg::norm2(b);
        let nr = geom_core::linalg::norm2(r);
        if nb > 0.0 {
            nr / nb
        } else {
            nr
        }
    }

    /// Relative equilibrium residual `‖D x − (P − D_f x_f)‖_F / ‖P − D_f x_f‖_F` of given
    /// free-node positions (spec §5, §7.3 e).
    pub fn residual(&self, x_free: &[Pt3], loads: &[Vec3], fixed: &[Pt3]) -> Result<f64> {
        let n = self.free.len();
        check_len("free-node positions", n, x_free.len())?;
        check_len("free-node loads", n, loads.len())?;
        check_len("fixed-node positions", self.fixed.len(), fixed.len())?;
        let b = self.rhs(loads, fixed);
        let x = columns(x_free);
        let mut r = vec![0.0; 3 * n];
        Ok(self.residual_columns(&b, &x, &mut r))
    }

    /// Componentwise backward error `max_i |b − D x|_i / (|D| |x| + |b|)_i` over the three
    /// coordinates (spec test 7.4 c): the figure that stays at rounding level when conditioning
    /// (extreme force-density ratios) limits the plain relative residual.
    pub fn backward_error(&self, x_free: &[Pt3], loads: &[Vec3], fixed: &[Pt3]) -> Result<f64> {
        let n = self.free.len();
        check_len("free-node positions", n, x_free.len())?;
        let b = self.rhs(loads, fixed);
        let x = columns(x_free);
        let d = &self.asm.d;
        let mut worst: f64 = 0.0;
        for c in 0..3 {
            for i in 0..n {
                let (cols, vals) = d.row(i);
                let mut ax = 0.0;
                let mut aabs = 0.0;
                for (&j, &v) in cols.iter().zip(vals) {
                    let xj = x[c * n + j as usize];
                    ax += v * xj;
                    aabs += v.abs() * xj.abs();
                }
                let bi = b[c * n + i];
                let den = aabs + bi.abs();
                let num = (bi - ax).abs();
                if den > 0.0 {
                    worst = worst.max(num / den);
                } else if num > 0.0 {
                    worst = f64::INFINITY;
                }
            }
        }
        Ok(worst)
    }

    /// Shape-holding loads `P0 = D X0 + D_f X0_f` (spec §3.5): the loads under which the given
    /// rest positions are the equilibrium. Returned in free-node order.
    pub fn rest_loads(&self, rest_free: &[Pt3], rest_fixed: &[Pt3]) -> Result<Vec<Vec3>> {
        let (n, nf) = (self.free.len(), self.fixed.len());
        check_len("rest free positions", n, rest_free.len())?;
        check_len("rest fixed positions", nf, rest_fixed.len())?;
        let mut p = vec![Vec3::zeros(); n];
        let (mut x, mut y) = (vec![0.0; n], vec![0.0; n]);
        let (mut xf, mut yf) = (vec![0.0; nf], vec![0.0; n]);
        for c in 0..3 {
            for (i, v) in rest_free.iter().enumerate() {
                x[i] = v[c];
            }
            for (k, v) in rest_fixed.iter().enumerate() {
                xf[k] = v[c];
            }
            self.asm.d_mul(&x, &mut y);
            self.asm.df_mul(&xf, &mut yf);
            for i in 0..n {
                p[i][c] = y[i] + yf[i];
            }
        }
        Ok(p)
    }

    /// Free nodes (net node indices), ascending: the order of every free-node slice.
    pub fn free_nodes(&self) -> &[u32] {
        &self.free
    }

    /// Fixed nodes (net node indices), ascending: the order of every fixed-node slice.
    pub fn fixed_nodes(&self) -> &[u32] {
        &self.fixed
    }

    /// Per net node: its position in [`FdmSolver::free_nodes`] or [`FdmSolver::fixed_nodes`].
    pub fn node_index(&self) -> &[u32] {
        &self.index
    }

    /// `D`, `D_f` and their lower-triangle copy.
    pub fn assembly(&self) -> &Assembly {
        &self.asm
    }

    /// The net as last updated (force densities of [`FdmSolver::update_q`]).
    pub fn net(&self) -> &BarNet {
        &self.net
    }

    /// The validation report of the current net.
    pub fn report(&self) -> &NetReport {
        &self.report
    }

    /// The factorisation in use.
    pub fn path(&self) -> SolverPath {
        match self.factor {
            Factor::Empty => SolverPath::Empty,
            Factor::Dense(_) => SolverPath::Dense,
            Factor::Sparse => SolverPath::Sparse,
            Factor::Ldlt(_) => SolverPath::Ldlt,
        }
    }

    /// True when the Cholesky failed and the LDLᵀ fallback is in use (spec §8 `indefinite`).
    pub fn is_indefinite(&self) -> bool {
        matches!(self.factor, Factor::Ldlt(_))
    }

    /// Stored entries of the sparse factor `L` (0 on the dense path).
    pub fn nnz_l(&self) -> usize {
        match (&self.factor, &self.llt) {
            (Factor::Sparse | Factor::Ldlt(_), Some(l)) => l.nnz_l(),
            _ => 0,
        }
    }
}

/// Column-major copy (3 columns of length n) of points.
pub(crate) fn columns(p: &[Pt3]) -> Vec<f64> {
    let n = p.len();
    let mut x = vec![0.0; 3 * n];
    for (i, v) in p.iter().enumerate() {
        for c in 0..3 {
            x[c * n + i] = v[c];
        }
    }
    x
}

fn copy_back(m: &Mat<f64>, x: &mut [f64]) {
    let n = m.nrows();
    for c in 0..m.ncols() {
        for i in 0..n {
            x[c * n + i] = m[(i, c)];
        }
    }
}

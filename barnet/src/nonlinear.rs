//! Nonlinear form finding (spec §3.7), beyond the paper's linear method: the comparison that
//! shows what the force density method saves.
//!
//! - [`NonlinearModel::PrescribedForces`] (Schek's nonlinear FDM): bar forces `s_j` are given,
//!   lengths unknown. Fixed-point iteration `q⁽ᵏ⁾ = s / l(x⁽ᵏ⁾)`, linear FDM solve for
//!   `x⁽ᵏ⁺¹⁾` (numeric refactorisation only); stop when the relative change < `fp_tol` (1e-12)
//!   or after `max_iter_fp` (200) iterations. Converges linearly for tension nets.
//! - [`NonlinearModel::ElasticBars`] (a mass–spring-like truss, `s = k (l − L0)`): Newton on
//!   `E(x) = Σ_j ½ k_j (l_j − L0_j)² − Σ_i p_i · x_i` with the tangent stiffness per bar
//!   `K_j = k_j [(1 − L0_j/l_j) I + (L0_j/l_j) ê êᵀ]` assembled into a 3n × 3n sparse matrix
//!   (interleaved xyz). Decision: instead of an LDLᵀ plus a descent test, the solver tries a
//!   sparse Cholesky of `H + μI` (success certifies a descent direction) with Levenberg damping
//!   `μ` doubled from `1e-8 · mean diag(H)` until it succeeds; the symbolic analysis is shared by
//!   every iteration. Backtracking (Armijo) line search on E. Stop at
//!   `‖∇E‖ ≤ 1e-10 ‖p‖ + 1e-12`.
//!
//! Both guard `1/l` with `l ≥ 1e-12 · scale` (scale = bounding-box diagonal of the fixed and
//! initial positions) and report how many bars needed the guard. Divergence or a failed solve
//! stops the iteration and returns the best iterate with `converged = false` (spec §8).

use crate::error::{check_finite, check_len, BarNetError, Result};
use crate::net::BarNet;
use crate::solver::{FdmOptions, FdmSolver};
use geom_core::linalg::{Csr, Ordering, SparseLlt, Triplets};
use geom_core::math::{Mat3, Pt3, Vec3};

/// The nonlinear bar model.
#[derive(Clone, Debug, PartialEq)]
pub enum NonlinearModel {
    /// Bar forces given (one per bar), lengths unknown (Schek's nonlinear FDM).
    PrescribedForces {
        /// Bar forces `s_j` (tension > 0).
        s: Vec<f64>,
    },
    /// Elastic bars `s = k (l − L0)`.
    ElasticBars {
        /// Axial stiffness per bar (force per length).
        k: Vec<f64>,
        /// Rest length per bar (m).
        rest_len: Vec<f64>,
    },
}

/// Options of [`form_find_nonlinear`] (spec §4).
#[derive(Clone, Debug)]
pub struct NewtonOptions {
    /// Newton iterations (default 50).
    pub max_iter: usize,
    /// Fixed-point iterations (default 200).
    pub max_iter_fp: usize,
    /// Relative gradient tolerance (default 1e-10 · ‖p‖).
    pub grad_rel: f64,
    /// Absolute gradient tolerance (default 1e-12).
    pub grad_abs: f64,
    /// Fixed-point relative-change tolerance (default 1e-12).
    pub fp_tol: f64,
}

impl Default for NewtonOptions {
    fn default() -> Self {
        Self { max_iter: 50, max_iter_fp: 200, grad_rel: 1e-10, grad_abs: 1e-12, fp_tol: 1e-12 }
    }
}

/// The outcome of a nonlinear solve.
#[derive(Clone, Debug)]
pub struct NonlinearResult {
    /// Free-node positions (best iterate).
    pub x: Vec<Pt3>,
    /// Iterations performed.
    pub iterations: usize,
    /// Whether the stopping test was met.
    pub converged: bool,
    /// Per iteration: ‖∇E‖ (Newton, index 0 = initial) or the relative change (fixed point).
    pub history: Vec<f64>,
    /// Bars whose length fell below the guard `1e-12 · scale`.
    pub guarded_bars: usize,
    /// Numeric factorisations performed.
    pub factorizations: usize,
}

/// All node positions from free and fixed parts.
fn assemble_positions(net: &BarNet, index: &[u32], free: &[Pt3], fixed: &[Pt3]) -> Vec<Pt3> {
    (0..net.n_nodes).map(|v| if net.fixed[v] { fixed[index[v] as usize] } else { free[index[v] as usize] }).collect()
}

fn scale_of(fixed: &[Pt3], x0: &[Pt3]) -> f64 {
    let mut lo = Vec3::repeat(f64::INFINITY);
    let mut hi = Vec3::repeat(f64::NEG_INFINITY);
    for p in fixed.iter().chain(x0) {
        lo = lo.inf(&p.coords);
        hi = hi.sup(&p.coords);
    }
    let d = (hi - lo).norm();
    if d.is_finite() && d > 0.0 {
        d
    } else {
        1.0
    }
}

/// Solves the nonlinear equilibrium of `net` for `loads` (free-node order), fixed positions
/// (fixed-node order) and a start `x0` (free-node order). Errors: bad lengths, non-finite input,
/// invalid net (`Unanchored`, …), non-positive stiffness.
pub fn form_find_nonlinear(
    net: &BarNet,
    model: &NonlinearModel,
    loads: &[Vec3],
    fixed: &[Pt3],
    x0: &[Pt3],
    o: &NewtonOptions,
) -> Result<NonlinearResult> {
    net.validate()?;
    let (free_nodes, fixed_nodes, _) = net.index_maps();
    check_len("loads", free_nodes.len(), loads.len())?;
    check_len("fixed positions", fixed_nodes.len(), fixed.len())?;
    check_len("initial free positions", free_nodes.len(), x0.len())?;
    check_finite("loads", geom_core::linalg::flat_vec(loads))?;
    check_finite("fixed positions", geom_core::linalg::flat(fixed))?;
    check_finite("initial free positions", geom_core::linalg::flat(x0))?;
    match model {
        NonlinearModel::PrescribedForces { s } => {
            check_len("bar forces s", net.bars.len(), s.len())?;
            check_finite("bar forces s", s)?;
            prescribed_forces(net, s, loads, fixed, x0, o)
        }
        NonlinearModel::ElasticBars { k, rest_len } => {
            check_len("bar stiffness k", net.bars.len(), k.len())?;
            check_len("bar rest lengths", net.bars.len(), rest_len.len())?;
            check_finite("bar stiffness k", k)?;
            check_finite("bar rest lengths", rest_len)?;
            if let Some(j) = k.iter().position(|&v| v <= 0.0) {
                return Err(BarNetError::InvalidParameter(format!("bar {j}: stiffness k = {} must be > 0", k[j])));
            }
            let elastic = Elastic::new(net, k, rest_len, loads, fixed, x0);
            elastic.newton(x0, o)
        }
    }
}

fn prescribed_forces(
    net: &BarNet,
    s: &[f64],
    loads: &[Vec3],
    fixed: &[Pt3],
    x0: &[Pt3],
    o: &NewtonOptions,
) -> Result<NonlinearResult> {
    let (_, _, index) = net.index_maps();
    let scale = scale_of(fixed, x0);
    let lmin = 1e-12 * scale;
    let mut x = x0.to_vec();
    let mut res = NonlinearResult {
        x: x.clone(),
        iterations: 0,
        converged: false,
        history: Vec::new(),
        guarded_bars: 0,
        factorizations: 0,
    };
    let mut solver: Option<FdmSolver> = None;
    let mut work = net.clone();
    for it in 0..o.max_iter_fp {
        let all = assemble_positions(net, &index, &x, fixed);
        let q: Vec<f64> = net
            .bars
            .iter()
            .zip(s)
            .map(|(b, &sj)| {
                let l = (all[b.a as usize] - all[b.b as usize]).norm();
                if l < lmin {
                    res.guarded_bars += 1;
                }
                sj / l.max(lmin)
            })
            .collect();
        let step = match &mut solver {
            None => {
                for (b, &qj) in work.bars.iter_mut().zip(&q) {
                    b.q = qj;
                }
                FdmSolver::new(&work, &FdmOptions::default()).map(|sv| solver = Some(sv))
            }
            Some(sv) => sv.update_q(&q),
        };
        if step.is_err() {
            return Ok(res);
        }
        res.factorizations += 1;
        let sv = solver.as_ref().expect("set just above");
        let xn = match sv.solve(loads, fixed) {
            Ok(v) => v,
            Err(_) => return Ok(res),
        };
        let change = xn.iter().zip(&x).map(|(a, b)| (a - b).norm()).fold(0.0, f64::max) / scale;
        res.history.push(change);
        res.iterations = it + 1;
        if !change.is_finite() {
            return Ok(res);
        }
        x = xn;
        res.x = x.clone();
        if change < o.fp_tol {
            res.converged = true;
            return Ok(res);
        }
    }
    Ok(res)
}

/// The elastic-bar energy, its gradient and Hessian (spec §3.7), over the free nodes with
/// interleaved xyz unknowns.
pub struct Elastic<'a> {
    net: &'a BarNet,
    k: &'a [f64],
    l0: &'a [f64],
    loads: &'a [Vec3],
    fixed: &'a [Pt3],
    index: Vec<u32>,
    lmin: f64,
}

impl<'a> Elastic<'a> {
    /// Binds the model's data (lengths checked by the caller).
    pub fn new(net: &'a BarNet, k: &'a [f64], l0: &'a [f64], loads: &'a [Vec3], fixed: &'a [Pt3], x0: &[Pt3]) -> Self {
        let (_, _, index) = net.index_maps();
        Self { net, k, l0, loads, fixed, index, lmin: 1e-12 * scale_of(fixed, x0) }
    }

    fn pos(&self, x: &[Pt3], v: u32) -> Pt3 {
        let i = self.index[v as usize] as usize;
        if self.net.fixed[v as usize] {
            self.fixed[i]
        } else {
            x[i]
        }
    }

    /// `E(x)`.
    pub fn energy(&self, x: &[Pt3]) -> f64 {
        let mut e = 0.0;
        for (j, b) in self.net.bars.iter().enumerate() {
            if self.net.fixed[b.a as usize] && self.net.fixed[b.b as usize] {
                continue;
            }
            let l = (self.pos(x, b.a) - self.pos(x, b.b)).norm();
            e += 0.5 * self.k[j] * (l - self.l0[j]).powi(2);
        }
        for (p, xi) in self.loads.iter().zip(x) {
            e -= p.dot(&xi.coords);
        }
        e
    }

    /// `∇E(x)` per free node.
    pub fn gradient(&self, x: &[Pt3]) -> Vec<Vec3> {
        let mut g: Vec<Vec3> = self.loads.iter().map(|p| -p).collect();
        for (j, b) in self.net.bars.iter().enumerate() {
            let (fa, fb) = (self.net.fixed[b.a as usize], self.net.fixed[b.b as usize]);
            if fa && fb {
                continue;
            }
            let d = self.pos(x, b.a) - self.pos(x, b.b);
            let l = d.norm().max(self.lmin);
            let f = d * (self.k[j] * (l - self.l0[j]) / l);
            if !fa {
                g[self.index[b.a as usize] as usize] += f;
            }
            if !fb {
                g[self.index[b.b as usize] as usize] -= f;
            }
        }
        g
    }

    /// The tangent stiffness (Hessian of E) as a full symmetric 3n × 3n [`Csr`], plus the
    /// number of guarded (too short) bars. The pattern depends only on the net.
    pub fn hessian(&self, x: &[Pt3]) -> (Csr, usize) {
        let n = x.len();
        let mut t = Triplets::with_capacity(3 * n, 3 * n, 36 * self.net.bars.len());
        let mut guarded = 0;
        for (j, b) in self.net.bars.iter().enumerate() {
            let (fa, fb) = (self.net.fixed[b.a as usize], self.net.fixed[b.b as usize]);
            if fa && fb {
                continue;
            }
            let d = self.pos(x, b.a) - self.pos(x, b.b);
            let l_raw = d.norm();
            if l_raw < self.lmin {
                guarded += 1;
            }
            let l = l_raw.max(self.lmin);
            let e = d / l;
            let r = self.l0[j] / l;
            let kk: Mat3 = (Mat3::identity() * (1.0 - r) + e * e.transpose() * r) * self.k[j];
            let (ia, ib) = (self.index[b.a as usize], self.index[b.b as usize]);
            if !fa {
                t.push_block3(ia, ia, &kk);
            }
            if !fb {
                t.push_block3(ib, ib, &kk);
            }
            if !fa && !fb {
                t.push_block3(ia, ib, &-kk);
                t.push_block3(ib, ia, &-kk);
            }
        }
        (Csr::from_triplets(&t), guarded)
    }

    /// Newton with Levenberg damping and backtracking line search; see the module docs.
    pub fn newton(&self, x0: &[Pt3], o: &NewtonOptions) -> Result<NonlinearResult> {
        let n = x0.len();
        let pnorm = self.loads.iter().map(|p| p.norm_squared()).sum::<f64>().sqrt();
        let tol = o.grad_rel * pnorm + o.grad_abs;
        let gnorm = |g: &[Vec3]| g.iter().map(|v| v.norm_squared()).sum::<f64>().sqrt();
        let mut x = x0.to_vec();
        let mut g = self.gradient(&x);
        let mut res = NonlinearResult {
            x: x.clone(),
            iterations: 0,
            converged: false,
            history: vec![gnorm(&g)],
            guarded_bars: 0,
            factorizations: 0,
        };
        if n == 0 || gnorm(&g) <= tol {
            res.converged = true;
            return Ok(res);
        }
        let mut llt: Option<SparseLlt> = None;
        let mut e = self.energy(&x);
        for it in 0..o.max_iter {
            let (h, guarded) = self.hessian(&x);
            res.guarded_bars = res.guarded_bars.max(guarded);
            let mean_diag = (0..3 * n).map(|i| h.get(i, i).abs()).sum::<f64>() / (3 * n) as f64;
            let mut mu = 0.0;
            let mut d = vec![0.0; 3 * n];
            let mut solved = false;
            for _ in 0..60 {
                let hm = if mu > 0.0 { h.add(&Csr::identity(3 * n), 1.0, mu) } else { h.clone() };
                let a = hm.to_csc_lower();
                if llt.is_none() {
                    llt = Some(SparseLlt::analyze(&a, Ordering::Amd)?);
                }
                let f = llt.as_mut().expect("analysed just above");
                res.factorizations += 1;
                if f.factor(&a).is_ok() {
                    for (i, gi) in g.iter().enumerate() {
                        for c in 0..3 {
                            d[3 * i + c] = -gi[c];
                        }
                    }
                    if f.solve_in_place(&mut d).is_ok() {
                        solved = true;
                        break;
                    }
                }
                mu = if mu == 0.0 { 1e-8 * mean_diag.max(1e-300) } else { 2.0 * mu };
            }
            if !solved {
                return Ok(res);
            }
            let slope: f64 =
                g.iter().enumerate().map(|(i, gi)| gi.x * d[3 * i] + gi.y * d[3 * i + 1] + gi.z * d[3 * i + 2]).sum();
            let mut alpha = 1.0;
            let mut xn = x.clone();
            let mut accepted = false;
            for _ in 0..40 {
                for (i, p) in xn.iter_mut().enumerate() {
                    *p = x[i] + Vec3::new(d[3 * i], d[3 * i + 1], d[3 * i + 2]) * alpha;
                }
                let en = self.energy(&xn);
                if en.is_finite() && en <= e + 1e-4 * alpha * slope {
                    e = en;
                    accepted = true;
                    break;
                }
                alpha *= 0.5;
            }
            res.iterations = it + 1;
            if !accepted {
                // No decrease possible at rounding level: accept the full step only if the
                // gradient shrinks, otherwise stop.
                for (i, p) in xn.iter_mut().enumerate() {
                    *p = x[i] + Vec3::new(d[3 * i], d[3 * i + 1], d[3 * i + 2]);
                }
                let gn = self.gradient(&xn);
                if gnorm(&gn) >= gnorm(&g) {
                    return Ok(res);
                }
                e = self.energy(&xn);
            }
            x = xn;
            g = self.gradient(&x);
            let gn = gnorm(&g);
            res.history.push(gn);
            res.x = x.clone();
            if !gn.is_finite() {
                return Ok(res);
            }
            if gn <= tol {
                res.converged = true;
                return Ok(res);
            }
        }
        Ok(res)
    }
}

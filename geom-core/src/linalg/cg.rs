//! Preconditioned conjugate gradients ([`pcg`]) for SPD [`Csr`] systems (FT's pressure solve,
//! RG's weights), deterministic for any thread count.
//!
//! Stopping rule: `‖b − A x‖₂ ≤ tol · ‖b‖₂` for the **true** residual. The recursively updated
//! residual drifts from the true one; when it first passes the test, the true residual is
//! computed, and if it does not pass, it replaces the recursive one and the iteration goes on
//! (residual replacement), so `converged` always refers to the true residual.
//!
//! Non-finite handling (decided here): invalid input (wrong lengths, NaN/∞ in `A`, `b` or the
//! warm start, `tol` not positive) is an error; the iteration itself never writes a NaN into `x`.
//! A breakdown (`pᵀAp ≤ 0` or `rᵀz ≤ 0` for a nonzero `r`: matrix or preconditioner not SPD, or a
//! non-finite product) stops with `converged = false`, `breakdown = true` and `x` at its last
//! (finite) iterate. Reaching `max_iters` is not an error either: the report says so.

use super::vector::{axpy, xpby};
use super::{dot, norm2, Csr, Preconditioner};
use crate::error::{Error, Result};

/// Options of [`pcg`].
#[derive(Clone, Debug, PartialEq)]
pub struct CgOptions {
    /// Relative tolerance: stop when `‖b − A x‖ ≤ tol · ‖b‖`.
    pub tol: f64,
    /// Iteration cap.
    pub max_iters: usize,
    /// Record the relative (recursive) residual of every iteration in [`CgReport::history`].
    pub history: bool,
}

impl Default for CgOptions {
    fn default() -> Self {
        Self { tol: 1e-8, max_iters: 1000, history: false }
    }
}

/// Outcome of [`pcg`].
#[derive(Clone, Debug, Default, PartialEq)]
pub struct CgReport {
    /// Iterations performed (matrix–vector products after the initial residual).
    pub iters: usize,
    /// Final true relative residual `‖b − A x‖ / ‖b‖` (0 when `b = 0`).
    pub rel_residual: f64,
    /// Whether `rel_residual ≤ tol`.
    pub converged: bool,
    /// The iteration stopped on a breakdown (`pᵀAp ≤ 0` or `rᵀz ≤ 0`): not SPD.
    pub breakdown: bool,
    /// Relative residual after each iteration, starting with the warm start's (empty unless
    /// [`CgOptions::history`]).
    pub history: Vec<f64>,
}

/// Solves the SPD system `A x = b` by conjugate gradients preconditioned with `m`, starting
/// from the given `x` (warm start). See the module docs for the stopping rule and failure modes.
/// `b = 0` sets `x = 0` and returns converged after 0 iterations.
pub fn pcg(a: &Csr, b: &[f64], x: &mut [f64], m: &dyn Preconditioner, o: &CgOptions) -> Result<CgReport> {
    let n = a.nrows;
    if a.ncols != n {
        return Err(Error::DimensionMismatch { what: "pcg: matrix columns", expected: n, got: a.ncols });
    }
    if b.len() != n || x.len() != n {
        return Err(Error::DimensionMismatch {
            what: "pcg: b or x",
            expected: n,
            got: if b.len() != n { b.len() } else { x.len() },
        });
    }
    if !(o.tol > 0.0 && o.tol.is_finite()) {
        return Err(Error::InvalidParameter(format!("pcg: tol = {} must be positive and finite", o.tol)));
    }
    if !super::all_finite(&a.val) {
        return Err(Error::NonFinite("pcg: matrix"));
    }
    if !super::all_finite(b) {
        return Err(Error::NonFinite("pcg: right-hand side"));
    }
    if !super::all_finite(x) {
        return Err(Error::NonFinite("pcg: warm start x"));
    }
    let mut rep = CgReport::default();
    let nb = norm2(b);
    if nb == 0.0 {
        x.fill(0.0);
        rep.converged = true;
        if o.history {
            rep.history.push(0.0);
        }
        return Ok(rep);
    }
    let target = o.tol * nb;
    let mut r = vec![0.0; n];
    let true_residual = |x: &[f64], r: &mut [f64]| {
        a.mul_vec_par(x, r);
        for (ri, bi) in r.iter_mut().zip(b) {
            *ri = bi - *ri;
        }
    };
    true_residual(x, &mut r);
    let mut rnorm = norm2(&r);
    if o.history {
        rep.history.push(rnorm / nb);
    }
    let mut z = vec![0.0; n];
    let mut p = vec![0.0; n];
    let mut q = vec![0.0; n];
    let mut restart = true;
    let mut rz = 0.0;
    loop {
        if rnorm <= target {
            // Confirm with the true residual (identical right after a restart).
            true_residual(x, &mut r);
            rnorm = norm2(&r);
            if rnorm <= target {
                rep.converged = true;
                break;
            }
            restart = true;
        }
        if rep.iters >= o.max_iters {
            break;
        }
        if restart {
            m.apply(&r, &mut z);
            rz = dot(&r, &z);
            if !(rz > 0.0 && rz.is_finite()) {
                rep.breakdown = true;
                break;
            }
            p.copy_from_slice(&z);
            restart = false;
        }
        a.mul_vec_par(&p, &mut q);
        let pq = dot(&p, &q);
        if !(pq > 0.0 && pq.is_finite()) {
            rep.breakdown = true;
            break;
        }
        let alpha = rz / pq;
        axpy(alpha, &p, x);
        axpy(-alpha, &q, &mut r);
        rep.iters += 1;
        rnorm = norm2(&r);
        if o.history {
            rep.history.push(rnorm / nb);
        }
        if rnorm <= target {
            continue;
        }
        m.apply(&r, &mut z);
        let rz_new = dot(&r, &z);
        if !(rz_new > 0.0 && rz_new.is_finite()) {
            rep.breakdown = true;
            break;
        }
        xpby(&z, rz_new / rz, &mut p);
        rz = rz_new;
    }
    if !super::all_finite(x) {
        // Unreachable with finite α (checked above), kept as the module's guarantee.
        return Err(Error::NonFinite("pcg: iterate"));
    }
    true_residual(x, &mut r);
    rep.rel_residual = norm2(&r) / nb;
    rep.converged = rep.converged || rep.rel_residual <= o.tol;
    Ok(rep)
}

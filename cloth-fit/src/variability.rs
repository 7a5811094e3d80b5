//! The perturbation analysis of the paper (Bhat et al. 2003 §4.2, Fig. 4: "we perturb each
//! parameter of the simulator individually up to ±0.20% of its value, compute the error and fit
//! a quadratic to the data. From the quadratic, the variability is computed as the change in
//! parameter values that results in a 1% change in the error"; spec §3.9, where the printed
//! "±0.20%" is read as ±20 %).
//!
//! Low variability means the parameter is reliably determined by the experiment.

use serde::{Deserialize, Serialize};

use crate::error::Result;
use crate::objective::{EvalStatus, Objective};
use crate::params::{FabricParams, ParamId};

/// Settings (spec §4.4).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct VariabilityOptions {
    /// Largest relative perturbation (0.2 = ±20 %).
    pub max_rel: f64,
    /// Samples per parameter, evenly spaced in [−max_rel, max_rel] (including 0 when odd).
    pub samples: usize,
    /// Relative error change that defines the variability (0.01 = 1 %).
    pub target_change: f64,
}

impl Default for VariabilityOptions {
    /// ±20 %, 9 samples, 1 %.
    fn default() -> Self {
        Self { max_rel: 0.2, samples: 9, target_change: 0.01 }
    }
}

/// One parameter's variability (spec §2 `ParamVariability`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ParamVariability {
    /// The parameter.
    pub id: ParamId,
    /// Smallest |δ| (relative) at which the fitted quadratic changes by target_change·E_ref;
    /// +∞ when it never does.
    pub variability: f64,
    /// Fitted (q0, q1, q2) of E(δ) ≈ q0 + q1 δ + q2 δ².
    pub quad: [f64; 3],
    /// True when the root lies beyond `max_rel` or does not exist (the paper's "> 20 %").
    pub extrapolated: bool,
    /// The sampled (δ, E) pairs.
    pub samples: Vec<(f64, f64)>,
    /// Perturbations whose simulation failed (their penalty values are excluded from the fit).
    pub failed: usize,
}

/// The perturbed parameters of `id` around `at`: p(1 + δ), or for a parameter at 0 (drag)
/// p = |δ|·(hi − lo) (±20 % of its range, mirrored at the bound so it stays ≥ 0).
pub fn perturbed(obj: &Objective, at: &FabricParams, id: ParamId, delta: f64) -> FabricParams {
    let v = at.get(id);
    let nv = if v == 0.0 {
        let r = obj.space().range(id);
        delta.abs() * (r.hi - r.lo)
    } else {
        v * (1.0 + delta)
    };
    at.with(id, nv)
}

/// Least-squares quadratic q0 + q1 δ + q2 δ² through the points.
pub fn fit_quadratic(pts: &[(f64, f64)]) -> [f64; 3] {
    use nalgebra::{Matrix3, Vector3};
    let mut a = Matrix3::<f64>::zeros();
    let mut b = Vector3::<f64>::zeros();
    for &(d, e) in pts {
        let phi = Vector3::new(1.0, d, d * d);
        a += phi * phi.transpose();
        b += phi * e;
    }
    match a.lu().solve(&b) {
        Some(q) => [q[0], q[1], q[2]],
        None => [f64::NAN; 3],
    }
}

/// Smallest positive |δ| with |q1 δ + q2 δ²| = c (c > 0), `None` when there is none.
pub fn smallest_root(q1: f64, q2: f64, c: f64) -> Option<f64> {
    let mut best: Option<f64> = None;
    for rhs in [c, -c] {
        // q2 δ² + q1 δ − rhs = 0.
        let roots: Vec<f64> = if q2.abs() < 1e-300 {
            if q1 != 0.0 {
                vec![rhs / q1]
            } else {
                vec![]
            }
        } else {
            let disc = q1 * q1 + 4.0 * q2 * rhs;
            if disc < 0.0 {
                vec![]
            } else {
                let s = disc.sqrt();
                vec![(-q1 + s) / (2.0 * q2), (-q1 - s) / (2.0 * q2)]
            }
        };
        for r in roots {
            let m = r.abs();
            if m > 0.0 && m.is_finite() && best.is_none_or(|b| m < b) {
                best = Some(m);
            }
        }
    }
    best
}

/// The variability of every free parameter at `at` (spec §2 `variability`). All perturbed
/// evaluations run as one parallel batch. `e_floor` (spec §3.9: 1e-3 × the median coarse-search
/// error) keeps the reference error positive in noise-free matched runs where E(p̂) = 0.
pub fn variability(
    obj: &Objective,
    at: &FabricParams,
    o: &VariabilityOptions,
    e_floor: f64,
) -> Result<Vec<ParamVariability>> {
    let free = obj.space().free.clone();
    let ns = o.samples.max(3);
    let deltas: Vec<f64> = (0..ns).map(|i| -o.max_rel + 2.0 * o.max_rel * i as f64 / (ns - 1) as f64).collect();
    let mut pts = Vec::with_capacity(free.len() * ns);
    for &id in &free {
        for &d in &deltas {
            pts.push(perturbed(obj, at, id, d));
        }
    }
    let recs = obj.eval_params(&pts);
    let mut out = Vec::with_capacity(free.len());
    for (k, &id) in free.iter().enumerate() {
        let rs = &recs[k * ns..(k + 1) * ns];
        let samples: Vec<(f64, f64)> = deltas.iter().zip(rs).map(|(&d, r)| (d, r.error)).collect();
        let ok: Vec<(f64, f64)> =
            deltas.iter().zip(rs).filter(|(_, r)| r.status == EvalStatus::Ok).map(|(&d, r)| (d, r.error)).collect();
        let failed = ns - ok.len();
        let quad = if ok.len() >= 3 { fit_quadratic(&ok) } else { [f64::NAN; 3] };
        let e_ref = quad[0].max(e_floor);
        let root = smallest_root(quad[1], quad[2], o.target_change * e_ref);
        let variability = match root {
            Some(r) => r,
            None if quad.iter().any(|q| q.is_nan()) => f64::NAN,
            None => f64::INFINITY,
        };
        out.push(ParamVariability {
            id,
            variability,
            quad,
            extrapolated: !(variability <= o.max_rel),
            samples,
            failed,
        });
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Spec T14: on E(p) = E0(1 + c(p/p0 − 1)²) the variability is sqrt(0.01/c).
    #[test]
    fn variability_of_a_quadratic() {
        for &c in &[0.5, 2.0, 10.0, 100.0] {
            let e0 = 3.0;
            let pts: Vec<(f64, f64)> =
                (0..9).map(|i| -0.2 + 0.05 * i as f64).map(|d| (d, e0 * (1.0 + c * d * d))).collect();
            let q = fit_quadratic(&pts);
            let v = smallest_root(q[1], q[2], 0.01 * q[0].max(0.0)).unwrap();
            let expect = (0.01f64 / c).sqrt();
            assert!((v - expect).abs() <= 1e-6 * expect, "c = {c}: {v} vs {expect}");
        }
        assert_eq!(smallest_root(0.0, 0.0, 1.0), None);
        assert_eq!(smallest_root(0.0, -1.0, 1.0), Some(1.0));
    }
}

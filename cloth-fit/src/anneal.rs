//! Continuous simulated annealing: the Metropolis algorithm combined with the downhill simplex
//! (Bhat et al. 2003 §4.2: "the continuous simulated annealing method presented in Press et
//! al., which combines the Metropolis algorithm with the downhill simplex method ... We found
//! it useful to reset the simplex with the current best solution when the temperature reduces by
//! a factor of 3"; Press et al., *Numerical Recipes* §10.9 `amebsa`; spec §3.8).
//!
//! Points live in the unit cube of the free parameters. At temperature T every stored vertex
//! value gets a positive thermal fluctuation y + T(−ln U) and every trial point a negative one
//! y − T(−ln U), so uphill moves are accepted with a probability that shrinks with T; the
//! Nelder–Mead logic (reflect, expand, contract, shrink) then runs on the fluctuating values.
//! T cools geometrically by epochs; whenever it has dropped by `reset_factor` the simplex is
//! rebuilt around the best point ever seen; the last `polish_fraction` of the budget runs at
//! T = 0 (plain Nelder–Mead).

use geom_core::rng::Rng;
use serde::{Deserialize, Serialize};

/// Annealing settings (spec §4.4).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct AnnealOptions {
    /// Evaluation budget (every objective call counts, cached or not).
    pub max_evals: usize,
    /// Evaluations per temperature epoch.
    pub epoch_len: usize,
    /// T ← cooling · T after every epoch.
    pub cooling: f64,
    /// Rebuild the simplex whenever T dropped by this factor (the paper: 3).
    pub reset_factor: f64,
    /// Initial simplex edge (unit cube).
    pub init_step: f64,
    /// T₀ = t0_factor · (25th percentile − minimum) of the coarse-search errors.
    pub t0_factor: f64,
    /// Final fraction of the budget at T = 0.
    pub polish_fraction: f64,
    /// Convergence: value spread ≤ ftol·(|y*| + 1e-12) …
    pub ftol: f64,
    /// … and simplex diameter ≤ xtol (only at T = 0).
    pub xtol: f64,
    /// Seed of the thermal fluctuations.
    pub seed: u64,
}

impl Default for AnnealOptions {
    /// 600 evaluations, epochs of 20, cooling 0.9, reset factor 3, step 0.15, T₀ factor 1,
    /// polish 10 %, ftol 1e-4, xtol 1e-3, seed 1 (spec §4.4).
    fn default() -> Self {
        Self {
            max_evals: 600,
            epoch_len: 20,
            cooling: 0.9,
            reset_factor: 3.0,
            init_step: 0.15,
            t0_factor: 1.0,
            polish_fraction: 0.1,
            ftol: 1e-4,
            xtol: 1e-3,
            seed: 1,
        }
    }
}

/// One evaluation as the annealer saw it.
#[derive(Clone, Debug, PartialEq)]
pub struct AnnealStep {
    /// The point.
    pub x: Vec<f64>,
    /// Its true (unperturbed) value.
    pub y: f64,
    /// Temperature when it was evaluated.
    pub t: f64,
}

/// Result of one annealing run (spec §2 `AnnealResult`).
#[derive(Clone, Debug, PartialEq)]
pub struct AnnealResult {
    /// Best point ever evaluated.
    pub best_x: Vec<f64>,
    /// Its value.
    pub best_y: f64,
    /// Every evaluation in order.
    pub history: Vec<AnnealStep>,
    /// Temperature after each epoch.
    pub temperatures: Vec<f64>,
    /// Evaluation counts at which the simplex was rebuilt.
    pub resets: Vec<usize>,
    /// Evaluations used.
    pub evals: usize,
}

/// Reflects a coordinate into [0, 1] (x < 0 → −x, x > 1 → 2 − x) and clamps.
pub fn reflect_into_box(x: f64) -> f64 {
    let y = if x < 0.0 {
        -x
    } else if x > 1.0 {
        2.0 - x
    } else {
        x
    };
    if y.is_nan() {
        0.5
    } else {
        y.clamp(0.0, 1.0)
    }
}

/// T₀ from the coarse-search errors (spec §3.8 step 2): `factor`·(25th percentile − min), or
/// half the spread of `simplex_values` without a coarse search, or 1e-3·max(E_min, 1e-12) when
/// that is 0.
pub fn initial_temperature(coarse: &[f64], simplex_values: &[f64], factor: f64) -> f64 {
    use geom_core::stats::{max, min, percentile};
    let t = if coarse.len() >= 2 {
        factor * (percentile(coarse, 25.0) - min(coarse))
    } else {
        0.5 * factor * (max(simplex_values) - min(simplex_values))
    };
    if t > 0.0 && t.is_finite() {
        t
    } else {
        let m = if coarse.is_empty() { min(simplex_values) } else { min(coarse) };
        1e-3 * m.max(1e-12)
    }
}

struct Annealer<'f> {
    f: &'f mut dyn FnMut(&[Vec<f64>]) -> Vec<f64>,
    rng: Rng,
    t: f64,
    history: Vec<AnnealStep>,
    best_x: Vec<f64>,
    best_y: f64,
    evals: usize,
}

impl Annealer<'_> {
    fn eval(&mut self, xs: &[Vec<f64>]) -> Vec<f64> {
        let ys = (self.f)(xs);
        for (x, &y) in xs.iter().zip(&ys) {
            self.evals += 1;
            self.history.push(AnnealStep { x: x.clone(), y, t: self.t });
            if y < self.best_y || self.best_y.is_nan() {
                self.best_y = y;
                self.best_x = x.clone();
            }
        }
        ys
    }

    /// −ln U with U uniform in (0, 1].
    fn fluct(&mut self) -> f64 {
        -(1.0 - self.rng.f64()).ln()
    }

    fn simplex_around(&mut self, x0: &[f64], step: f64, include_x0: Option<f64>) -> (Vec<Vec<f64>>, Vec<f64>) {
        let n = x0.len();
        let mut pts = vec![x0.to_vec()];
        for j in 0..n {
            let mut x = x0.to_vec();
            x[j] = if x0[j] + step <= 1.0 { x0[j] + step } else { x0[j] - step };
            x[j] = x[j].clamp(0.0, 1.0);
            pts.push(x);
        }
        let ys = match include_x0 {
            Some(y0) => {
                let mut v = vec![y0];
                v.extend(self.eval(&pts[1..]));
                v
            }
            None => self.eval(&pts),
        };
        (pts, ys)
    }
}

fn diameter(p: &[Vec<f64>]) -> f64 {
    let mut d: f64 = 0.0;
    for a in p {
        for b in p {
            let s: f64 = a.iter().zip(b).map(|(x, y)| (x - y).powi(2)).sum();
            d = d.max(s.sqrt());
        }
    }
    d
}

/// Runs the annealing from `start` at temperature `t0` (spec §2 `anneal`). `f` evaluates a
/// batch of unit-cube points (the shrink step's n points come as one batch, so the caller may
/// run them in parallel) and returns their values in order. Deterministic for a given seed.
pub fn anneal(
    f: &mut dyn FnMut(&[Vec<f64>]) -> Vec<f64>,
    start: &[f64],
    start_value: Option<f64>,
    t0: f64,
    o: &AnnealOptions,
) -> AnnealResult {
    let n = start.len();
    let x0: Vec<f64> = start.iter().map(|&v| reflect_into_box(v)).collect();
    let mut a = Annealer {
        f,
        rng: Rng::new(o.seed),
        t: t0.max(0.0),
        history: Vec::new(),
        best_x: x0.clone(),
        best_y: f64::INFINITY,
        evals: 0,
    };
    let polish_at = ((1.0 - o.polish_fraction.clamp(0.0, 1.0)) * o.max_evals as f64).floor() as usize;
    let mut temps = Vec::new();
    let mut resets = Vec::new();
    if let Some(y) = start_value {
        a.best_y = y;
    }
    let (mut p, mut y) = a.simplex_around(&x0, o.init_step, start_value);
    let mut t_reset = a.t;
    let mut next_epoch = o.epoch_len.max(1);
    let project = |x: Vec<f64>| -> Vec<f64> { x.into_iter().map(reflect_into_box).collect() };
    while a.evals < o.max_evals {
        // Cooling, polish, resets.
        while a.evals >= next_epoch {
            next_epoch += o.epoch_len.max(1);
            a.t *= o.cooling;
            temps.push(a.t);
        }
        if a.evals >= polish_at {
            a.t = 0.0;
        }
        // Convergence at T = 0.
        if a.t == 0.0 {
            let (ylo, yhi) = y.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), &v| (l.min(v), h.max(v)));
            if yhi - ylo <= o.ftol * (ylo.abs() + 1e-12) && diameter(&p) <= o.xtol {
                break;
            }
        }
        let collapsed = diameter(&p) < 1e-9;
        let t_dropped = a.t > 0.0 && t_reset > 0.0 && a.t <= t_reset / o.reset_factor;
        if collapsed || t_dropped {
            let step = if t0 > 0.0 { (o.init_step * (a.t / t0).sqrt()).max(0.02) } else { 0.02 };
            let bx = a.best_x.clone();
            let by = a.best_y;
            resets.push(a.evals);
            let (pp, yy) = a.simplex_around(&bx, step, Some(by));
            p = pp;
            y = yy;
            t_reset = a.t;
            continue;
        }
        // Thermal fluctuations of the stored values.
        let yh: Vec<f64> = (0..=n).map(|j| y[j] + a.t * a.fluct()).collect();
        let mut order: Vec<usize> = (0..=n).collect();
        order.sort_by(|&i, &j| yh[i].total_cmp(&yh[j]).then(i.cmp(&j)));
        let (ilo, inhi, ihi) = (order[0], order[n - 1], order[n]);
        let c: Vec<f64> =
            (0..n).map(|d| (0..=n).filter(|&j| j != ihi).map(|j| p[j][d]).sum::<f64>() / n as f64).collect();
        let along = |s: f64, w: &[f64]| -> Vec<f64> { (0..n).map(|d| c[d] + s * (w[d] - c[d])).collect() };
        let xr = project(along(-1.0, &p[ihi]));
        let yr = a.eval(std::slice::from_ref(&xr))[0];
        let yrh = yr - a.t * a.fluct();
        if yrh < yh[ilo] {
            if a.evals >= o.max_evals {
                p[ihi] = xr;
                y[ihi] = yr;
                break;
            }
            let xe = project(along(-2.0, &p[ihi]));
            let ye = a.eval(std::slice::from_ref(&xe))[0];
            let yeh = ye - a.t * a.fluct();
            if yeh < yrh {
                p[ihi] = xe;
                y[ihi] = ye;
            } else {
                p[ihi] = xr;
                y[ihi] = yr;
            }
        } else if yrh < yh[inhi] {
            p[ihi] = xr;
            y[ihi] = yr;
        } else {
            let mut worst_h = yh[ihi];
            if yrh < worst_h {
                p[ihi] = xr;
                y[ihi] = yr;
                worst_h = yrh;
            }
            if a.evals >= o.max_evals {
                break;
            }
            let xc = project(along(0.5, &p[ihi]));
            let yc = a.eval(std::slice::from_ref(&xc))[0];
            let ych = yc - a.t * a.fluct();
            if ych < worst_h {
                p[ihi] = xc;
                y[ihi] = yc;
            } else {
                // Shrink every vertex halfway toward the best; the n points form one batch.
                let lo = p[ilo].clone();
                let idx: Vec<usize> = (0..=n).filter(|&j| j != ilo).collect();
                let pts: Vec<Vec<f64>> =
                    idx.iter().map(|&j| project((0..n).map(|d| 0.5 * (p[j][d] + lo[d])).collect())).collect();
                let ys = a.eval(&pts);
                for ((j, x), v) in idx.into_iter().zip(pts).zip(ys) {
                    p[j] = x;
                    y[j] = v;
                }
            }
        }
    }
    AnnealResult { best_x: a.best_x, best_y: a.best_y, history: a.history, temperatures: temps, resets, evals: a.evals }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn batch(f: impl Fn(&[f64]) -> f64) -> impl FnMut(&[Vec<f64>]) -> Vec<f64> {
        move |xs: &[Vec<f64>]| xs.iter().map(|x| f(x)).collect()
    }

    /// Spec T13, part 1: Rosenbrock at T = 0 converges within 1e-3 in ≤ 2000 evaluations.
    #[test]
    fn rosenbrock_at_zero_temperature() {
        // z = 4x − 2 puts the minimum (1, 1) at x = (0.75, 0.75).
        let rb = |x: &[f64]| {
            let (a, b) = (4.0 * x[0] - 2.0, 4.0 * x[1] - 2.0);
            (1.0 - a).powi(2) + 100.0 * (b - a * a).powi(2)
        };
        let o = AnnealOptions { max_evals: 2000, ftol: 1e-14, xtol: 1e-9, polish_fraction: 1.0, ..Default::default() };
        let mut f = batch(rb);
        let r = anneal(&mut f, &[0.3, 0.6], None, 0.0, &o);
        assert!(r.evals <= 2000);
        let (a, b) = (4.0 * r.best_x[0] - 2.0, 4.0 * r.best_x[1] - 2.0);
        assert!((a - 1.0).abs() < 1e-3 && (b - 1.0).abs() < 1e-3, "({a}, {b}) after {} evals", r.evals);
    }

    /// Spec T13, part 2: on f = Σ z² + ½(1 − cos 2πz), z = 5.12(x − ½), 20 seeds × 600
    /// evaluations find the global basin (every |z| < ½) in ≥ 12 runs and in more runs than pure
    /// Nelder–Mead from the same starts; a seed reproduces its history; no point leaves the box.
    #[test]
    fn annealing_beats_nelder_mead_on_a_multimodal_function() {
        let f = |x: &[f64]| -> f64 {
            x.iter()
                .map(|&v| {
                    let z = 5.12 * (v - 0.5);
                    z * z + 0.5 * (1.0 - (std::f64::consts::TAU * z).cos())
                })
                .sum()
        };
        let basin = |x: &[f64]| x.iter().all(|&v| (5.12 * (v - 0.5)).abs() < 0.5);
        let (mut sa_hits, mut nm_hits) = (0, 0);
        for seed in 0..20u64 {
            let mut rng = Rng::new(1000 + seed);
            let start: Vec<f64> = (0..4).map(|_| rng.f64()).collect();
            let y0 = f(&start);
            let o = AnnealOptions { seed, max_evals: 600, ..Default::default() };
            let t0 = 2.0;
            let mut g = batch(f);
            let r = anneal(&mut g, &start, Some(y0), t0, &o);
            assert!(r.history.iter().all(|s| s.x.iter().all(|&v| (0.0..=1.0).contains(&v))));
            sa_hits += basin(&r.best_x) as usize;
            let mut g2 = batch(f);
            let r2 = anneal(&mut g2, &start, Some(y0), t0, &o);
            assert_eq!(r.history, r2.history, "same seed, same history");
            let mut g3 = batch(f);
            let nm = anneal(&mut g3, &start, Some(y0), 0.0, &AnnealOptions { polish_fraction: 1.0, ..o });
            nm_hits += basin(&nm.best_x) as usize;
        }
        assert!(sa_hits >= 12 && sa_hits > nm_hits, "annealing {sa_hits}/20, Nelder–Mead {nm_hits}/20");
    }

    #[test]
    fn temperature_fallbacks() {
        assert_eq!(initial_temperature(&[1.0, 2.0, 3.0, 4.0, 5.0], &[], 1.0), 1.0);
        assert_eq!(initial_temperature(&[2.0, 2.0, 2.0], &[], 1.0), 2e-3);
        assert_eq!(initial_temperature(&[], &[1.0, 3.0], 1.0), 1.0);
    }
}

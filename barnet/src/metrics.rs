//! Every figure the bar-net scenes report (spec §6): bulge height, position differences,
//! convergence orders and contraction ratios. Maxima propagate NaN
//! (`geom_core::stats::nan_max`): a failed frame reads NaN, never 0.
//!
//! ```
//! use barnet::metrics::{bulge, pairwise_orders};
//! // A fine vertex 1 mm further from the upper-arm axis than its LBS position.
//! assert!((bulge(&[[0.0, 0.046, 0.0]], &[[0.0, 0.045, 0.0]], 0.2) - 1e-3).abs() < 1e-7); // f32 input
//! let o = pairwise_orders(&[(0.1, 1e-2), (0.05, 2.5e-3)]);
//! assert!((o[1] - 2.0).abs() < 1e-12);
//! ```

use geom_core::math::Pt3;
use geom_core::stats::nan_max;

/// Bulge height (m): the largest increase of the distance to the upper-arm axis (the x axis,
/// which the elbow sweep does not move) of a fine vertex of the upper arm (rest-pose LBS
/// `x < x_max`), `fine` against the LBS skin `lbs` (spec §6.1). 0 when nothing bulges out.
pub fn bulge(fine: &[[f32; 3]], lbs: &[[f32; 3]], x_max: f64) -> f64 {
    let r = |p: &[f32; 3]| ((p[1] as f64).powi(2) + (p[2] as f64).powi(2)).sqrt();
    fine.iter().zip(lbs).filter(|(_, l)| (l[0] as f64) < x_max).map(|(f, l)| r(f) - r(l)).fold(0.0, nan_max)
}

/// `max_i ‖a_i − b_i‖` (m; 0 for empty input, NaN if a distance is NaN).
pub fn max_distance(a: &[Pt3], b: &[Pt3]) -> f64 {
    a.iter().zip(b).map(|(x, y)| (x - y).norm()).fold(0.0, nan_max)
}

/// Observed orders of convergence between consecutive `(h, error)` pairs,
/// `ln(e₀/e₁) / ln(h₀/h₁)`; the first entry is NaN (no predecessor).
pub fn pairwise_orders(errs: &[(f64, f64)]) -> Vec<f64> {
    let mut out = Vec::with_capacity(errs.len());
    for (i, &(h, e)) in errs.iter().enumerate() {
        out.push(if i == 0 {
            f64::NAN
        } else {
            let (h0, e0) = errs[i - 1];
            (e0 / e).ln() / (h0 / h).ln()
        });
    }
    out
}

/// Ratios `r_i = h_i / h_{i−1}` of a residual history (NaN for i = 0).
pub fn history_ratios(history: &[f64]) -> Vec<f64> {
    (0..history.len()).map(|i| if i > 0 { history[i] / history[i - 1] } else { f64::NAN }).collect()
}

/// The contraction ratios of a linearly converging iteration: [`history_ratios`] from the third
/// entry on, where the residual is still above the rounding floor (`> 1e-14`) and the ratio
/// finite (spec §7.5 d).
pub fn contraction_ratios(history: &[f64]) -> Vec<f64> {
    history_ratios(history)
        .into_iter()
        .enumerate()
        .filter(|&(i, r)| i >= 2 && r.is_finite() && history[i] > 1e-14)
        .map(|(_, r)| r)
        .collect()
}

/// The measured order of convergence of a residual history: the exponent p of
/// `g_{k+1} ≈ C·g_kᵖ`, the least-squares slope of ln g_{k+1} against ln g_k over the consecutive
/// pairs whose values both exceed `floor` (below it rounding dominates). Newton's quadratic tail
/// gives 2, a linearly converging method 1 (C is then its contraction ratio). NaN with fewer than
/// two such pairs.
pub fn convergence_order(history: &[f64], floor: f64) -> f64 {
    let pairs: Vec<(f64, f64)> =
        history.windows(2).filter(|w| w[0] > floor && w[1] > floor).map(|w| (w[0], w[1])).collect();
    geom_core::stats::loglog_fit(&pairs).1
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn maxima_propagate_nan() {
        assert!(bulge(&[[0.0, f32::NAN, 0.0]], &[[0.0, 0.0, 0.0]], 1.0).is_nan());
        assert!(max_distance(&[Pt3::new(f64::NAN, 0.0, 0.0)], &[Pt3::origin()]).is_nan());
        assert_eq!(max_distance(&[], &[]), 0.0);
    }

    #[test]
    fn orders_of_model_sequences() {
        let lin: Vec<f64> = (0..8).map(|k| 0.5f64.powi(k)).collect();
        assert!((convergence_order(&lin, 1e-300) - 1.0).abs() < 1e-12);
        assert!(contraction_ratios(&lin).iter().all(|r| (r - 0.5).abs() < 1e-15));
        let quad: Vec<f64> = (0..5).map(|k| 30.0 * 0.1f64.powi(1 << k)).collect();
        assert!((convergence_order(&quad, 1e-300) - 2.0).abs() < 1e-9);
        assert!(convergence_order(&[1.0, 0.5], 0.0).is_nan(), "one pair is not a fit");
    }
}

//! Analytic solutions the wrinkle figures are compared with (spec §6 W1).
//!
//! ```
//! use wrinkles::reference::strip_amplitude;
//! // The spec's values of A/λ at c = 0.9 and 0.7.
//! assert!((strip_amplitude(0.9) - 0.0993299).abs() < 1e-7);
//! assert!((strip_amplitude(0.7) - 0.1667054).abs() < 1e-7);
//! assert_eq!(strip_amplitude(1.1), 0.0);
//! ```

use std::f64::consts::TAU;

/// The 1-D buckled-strip amplitude ratio A/λ at compression `c` (flat rest, arc length kept): a
/// strip of rest length λ compressed to cλ buckles into `A sin(2πx/(cλ))` of the same arc length,
/// `mean_θ √(c² + (2πA/λ)² cos²θ) = 1`, solved for k = 2πA/λ by bisection on [0, 20] (k = π/2
/// at c = 0) with a 4096-point periodic midpoint rule (spectrally accurate for this analytic
/// periodic integrand). No compression (`c ≥ 1`): exactly 0. Dimensionless.
pub fn strip_amplitude(c: f64) -> f64 {
    if c >= 1.0 {
        return 0.0;
    }
    let n = 4096;
    let mean = |k: f64| {
        (0..n)
            .map(|i| {
                let th = TAU * (i as f64 + 0.5) / n as f64;
                (c * c + k * k * th.cos().powi(2)).sqrt()
            })
            .sum::<f64>()
            / n as f64
    };
    let (mut lo, mut hi) = (0.0, 20.0);
    for _ in 0..200 {
        let m = 0.5 * (lo + hi);
        if mean(m) < 1.0 {
            lo = m
        } else {
            hi = m
        }
    }
    0.5 * (lo + hi) / TAU
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn strip_amplitude_limits() {
        // Full compression: the mean of |k cos θ| is 2k/π = 1, so A/λ = (π/2)/(2π) = 1/4.
        // (|cos θ| has kinks: the midpoint rule is second order there, 1e-7 at 4096 points.)
        assert!((strip_amplitude(0.0) - 0.25).abs() < 1e-6);
        assert_eq!(strip_amplitude(1.0), 0.0);
        // Small compression: mean √(c² + k² cos²θ) ≈ c + k²/(4c) = 1, so A/λ ≈ √(1 − c)/π.
        let c: f64 = 0.9999;
        assert!((strip_amplitude(c) / ((1.0 - c).sqrt() / std::f64::consts::PI) - 1.0).abs() < 1e-3);
    }
}

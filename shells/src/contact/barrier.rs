//! The log barrier of Incremental Potential Contact (Li et al. 2020, eq. 6):
//! b(d) = −(d − d̂)² ln(d/d̂) for 0 < d < d̂ and 0 beyond, a C² function of the gap d (m) that is
//! exactly zero outside the activation distance d̂ and grows without bound as d → 0, so a line
//! search that never lets d reach 0 keeps every contact pair apart.
//!
//! We use the unsquared gap d (the distance minus any thickness or obstacle radius) so that
//! d̂ reads in metres; b is convex on (0, d̂) (b″ > 0), which the Gauss–Newton contact Hessian
//! b″(d)∇d∇dᵀ relies on.

/// b(d) (m²); +∞ for d ≤ 0, 0 for d ≥ d̂.
pub fn value(d: f64, dhat: f64) -> f64 {
    if d <= 0.0 {
        return f64::INFINITY;
    }
    if d >= dhat {
        return 0.0;
    }
    let x = d - dhat;
    -x * x * (d / dhat).ln()
}

/// b′(d) (m); ≤ 0, 0 for d ≥ d̂.
pub fn first(d: f64, dhat: f64) -> f64 {
    if d >= dhat {
        return 0.0;
    }
    let x = d - dhat;
    -2.0 * x * (d / dhat).ln() - x * x / d
}

/// b″(d) (dimensionless); > 0 on (0, d̂), 0 for d ≥ d̂.
pub fn second(d: f64, dhat: f64) -> f64 {
    if d >= dhat {
        return 0.0;
    }
    let x = d - dhat;
    -2.0 * (d / dhat).ln() - 4.0 * x / d + x * x / (d * d)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn derivatives_match_finite_differences_and_vanish_at_dhat() {
        let dhat = 1e-3;
        for k in 1..100 {
            let d = dhat * k as f64 / 100.0;
            let e = 1e-9 * dhat;
            let fd1 = (value(d + e, dhat) - value(d - e, dhat)) / (2.0 * e);
            let fd2 = (first(d + e, dhat) - first(d - e, dhat)) / (2.0 * e);
            assert!((fd1 - first(d, dhat)).abs() <= 1e-6 * first(d, dhat).abs().max(1e-9), "b' at {d}");
            assert!((fd2 - second(d, dhat)).abs() <= 1e-5 * second(d, dhat).abs().max(1e-6), "b'' at {d}");
            assert!(second(d, dhat) > 0.0 && first(d, dhat) < 0.0 && value(d, dhat) > 0.0);
        }
        assert_eq!(value(dhat, dhat), 0.0);
        assert_eq!(first(dhat, dhat), 0.0);
        assert_eq!(second(2.0 * dhat, dhat), 0.0);
        assert!(value(0.0, dhat).is_infinite());
        // C¹ at d̂: b′ → 0 from below.
        assert!(first(dhat * (1.0 - 1e-6), dhat).abs() < 1e-12);
    }
}

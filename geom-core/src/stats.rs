//! Small descriptive statistics and fits used by every experiment's figures — one copy.
//!
//! All functions are **NaN-propagating**: a NaN anywhere in the sample makes the result NaN (a
//! figure computed from a failed run must not read as 0), and an empty sample gives NaN. Use
//! [`max`]/[`min`] instead of `fold(0.0, f64::max)`, which silently turns NaN into 0.
//!
//! ```
//! use geom_core::stats;
//! assert_eq!(stats::median(&[3.0, 1.0, 2.0]), 2.0);
//! assert_eq!(stats::median(&[4.0, 1.0, 2.0, 3.0]), 2.5);
//! assert!(stats::max(&[1.0, f64::NAN]).is_nan());
//! let (a, b, r2) = stats::linear_fit(&[(0.0, 1.0), (1.0, 3.0), (2.0, 5.0)]);
//! assert!((a - 1.0).abs() < 1e-12 && (b - 2.0).abs() < 1e-12 && (r2 - 1.0).abs() < 1e-12);
//! ```

fn has_nan(xs: &[f64]) -> bool {
    xs.iter().any(|x| x.is_nan())
}

/// Arithmetic mean; NaN for an empty sample or one holding a NaN.
pub fn mean(xs: &[f64]) -> f64 {
    if xs.is_empty() {
        return f64::NAN;
    }
    xs.iter().sum::<f64>() / xs.len() as f64
}

/// Largest value; NaN if the sample is empty or holds a NaN (`+∞` is kept).
pub fn max(xs: &[f64]) -> f64 {
    if xs.is_empty() || has_nan(xs) {
        return f64::NAN;
    }
    xs.iter().copied().fold(f64::NEG_INFINITY, f64::max)
}

/// Smallest value; NaN if the sample is empty or holds a NaN.
pub fn min(xs: &[f64]) -> f64 {
    if xs.is_empty() || has_nan(xs) {
        return f64::NAN;
    }
    xs.iter().copied().fold(f64::INFINITY, f64::min)
}

/// A running maximum that remembers a NaN: `nan_max(a, b)` is NaN when either is NaN (unlike
/// `f64::max`, which returns the other operand). Start a fold from `f64::NEG_INFINITY` or 0.
pub fn nan_max(a: f64, b: f64) -> f64 {
    if a.is_nan() || b.is_nan() {
        f64::NAN
    } else {
        a.max(b)
    }
}

/// A running minimum that remembers a NaN (see [`nan_max`]).
pub fn nan_min(a: f64, b: f64) -> f64 {
    if a.is_nan() || b.is_nan() {
        f64::NAN
    } else {
        a.min(b)
    }
}

fn sorted(xs: &[f64]) -> Vec<f64> {
    let mut v = xs.to_vec();
    v.sort_by(f64::total_cmp);
    v
}

/// Median: the middle order statistic, or the mean of the two middle ones for an even count;
/// NaN for an empty sample or one holding a NaN.
pub fn median(xs: &[f64]) -> f64 {
    percentile(xs, 50.0)
}

/// Percentile `q ∈ [0, 100]` by linear interpolation between order statistics (the "linear"
/// method of NumPy); NaN for an empty sample or one holding a NaN.
pub fn percentile(xs: &[f64], q: f64) -> f64 {
    if xs.is_empty() || has_nan(xs) || q.is_nan() {
        return f64::NAN;
    }
    let v = sorted(xs);
    let r = (q.clamp(0.0, 100.0) / 100.0) * (v.len() - 1) as f64;
    let i = r.floor() as usize;
    let s = r - i as f64;
    if i + 1 < v.len() {
        v[i] + (v[i + 1] - v[i]) * s
    } else {
        v[i]
    }
}

/// Root mean square; NaN for an empty sample or one holding a NaN.
pub fn rms(xs: &[f64]) -> f64 {
    if xs.is_empty() {
        return f64::NAN;
    }
    (xs.iter().map(|x| x * x).sum::<f64>() / xs.len() as f64).sqrt()
}

/// Least-squares line `y = a + b·x` through the points: `(a, b, r²)`. NaN coefficients for fewer
/// than two points or no spread in x; r² = 1 when y has no spread.
pub fn linear_fit(pts: &[(f64, f64)]) -> (f64, f64, f64) {
    let n = pts.len() as f64;
    if pts.len() < 2 {
        return (f64::NAN, f64::NAN, f64::NAN);
    }
    let mx = pts.iter().map(|p| p.0).sum::<f64>() / n;
    let my = pts.iter().map(|p| p.1).sum::<f64>() / n;
    let sxx: f64 = pts.iter().map(|p| (p.0 - mx).powi(2)).sum();
    let sxy: f64 = pts.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    let syy: f64 = pts.iter().map(|p| (p.1 - my).powi(2)).sum();
    if sxx.is_nan() || sxx <= 0.0 {
        return (f64::NAN, f64::NAN, f64::NAN);
    }
    let b = sxy / sxx;
    let r2 = if syy > 0.0 { (sxy * sxy) / (sxx * syy) } else { 1.0 };
    (my - b * mx, b, r2)
}

/// Slope of the least-squares line of ln y against ln x (the exponent p of y ≈ c·xᵖ): `(ln c, p,
/// r²)`. Points with a non-positive coordinate make the fit NaN (they have no logarithm).
pub fn loglog_fit(pts: &[(f64, f64)]) -> (f64, f64, f64) {
    if pts.iter().any(|p| p.0.is_nan() || p.1.is_nan() || p.0 <= 0.0 || p.1 <= 0.0) {
        return (f64::NAN, f64::NAN, f64::NAN);
    }
    let logs: Vec<(f64, f64)> = pts.iter().map(|p| (p.0.ln(), p.1.ln())).collect();
    linear_fit(&logs)
}

/// Frequency (Hz) of the largest non-constant term of the discrete Fourier transform of a signal
/// sampled at `fs` Hz (the mean is removed first); NaN for fewer than 8 samples or NaN samples.
/// O(n²): meant for the few hundred samples of a scene's probe signal.
pub fn dominant_frequency(x: &[f64], fs: f64) -> f64 {
    let n = x.len();
    if n < 8 || has_nan(x) {
        return f64::NAN;
    }
    let m = mean(x);
    let (mut best, mut bf) = (0.0, f64::NAN);
    for k in 1..n / 2 {
        let (mut re, mut im) = (0.0, 0.0);
        for (j, v) in x.iter().enumerate() {
            let a = 2.0 * std::f64::consts::PI * (k * j) as f64 / n as f64;
            re += (v - m) * a.cos();
            im -= (v - m) * a.sin();
        }
        let p = re * re + im * im;
        if p > best {
            best = p;
            bf = k as f64 * fs / n as f64;
        }
    }
    bf
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nan_and_empty_propagate() {
        for f in [mean, max, min, median, rms] {
            assert!(f(&[]).is_nan());
            assert!(f(&[1.0, f64::NAN, 2.0]).is_nan());
        }
        assert!(percentile(&[1.0, f64::NAN], 90.0).is_nan());
        assert!(nan_max(0.0, f64::NAN).is_nan() && nan_max(f64::NAN, 0.0).is_nan());
        assert!(nan_min(0.0, f64::NAN).is_nan());
        assert_eq!([1.0, 3.0, 2.0].iter().copied().fold(0.0, nan_max), 3.0);
    }

    #[test]
    fn order_statistics() {
        assert_eq!(median(&[5.0]), 5.0);
        assert_eq!(median(&[1.0, 9.0]), 5.0);
        assert_eq!(percentile(&[0.0, 10.0, 20.0, 30.0, 40.0], 25.0), 10.0);
        assert_eq!(percentile(&[0.0, 10.0], 90.0), 9.0);
        assert_eq!(max(&[-1.0, f64::INFINITY]), f64::INFINITY);
        assert_eq!(min(&[-1.0, 2.0]), -1.0);
        assert!((rms(&[3.0, 4.0]) - 12.5f64.sqrt()).abs() < 1e-15);
    }

    #[test]
    fn fits_recover_exact_laws() {
        let pts: Vec<(f64, f64)> = (1..6).map(|i| (i as f64, 3.0 * (i as f64).powf(1.5))).collect();
        let (lc, p, r2) = loglog_fit(&pts);
        assert!((p - 1.5).abs() < 1e-12 && (lc - 3f64.ln()).abs() < 1e-12 && (r2 - 1.0).abs() < 1e-12);
        assert!(loglog_fit(&[(1.0, 1.0), (0.0, 2.0)]).1.is_nan());
        assert!(linear_fit(&[(1.0, 1.0)]).1.is_nan());
        assert!(linear_fit(&[(1.0, 1.0), (1.0, 2.0)]).1.is_nan());
    }

    #[test]
    fn dominant_frequency_of_a_sine() {
        let fs = 60.0;
        let x: Vec<f64> = (0..240).map(|i| (2.0 * std::f64::consts::PI * 1.5 * i as f64 / fs).sin()).collect();
        assert!((dominant_frequency(&x, fs) - 1.5).abs() < 1e-12);
        assert!(dominant_frequency(&x[..4], fs).is_nan());
    }
}

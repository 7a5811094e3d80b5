//! 1-D and keyframe curves: [`Curve1D`] (monotone cubic through keys, Fritsch–Carlson) and
//! [`catmull_rom`] over anything that can be linearly interpolated ([`Lerp`]).

use super::{Pt2, Pt3, Vec2, Vec3};
use crate::error::{Error, Result};
use serde::{Deserialize, Serialize};

/// Monotone piecewise-cubic Hermite interpolant through keys `(x_i, y_i)` with strictly
/// increasing `x` (F. N. Fritsch and R. E. Carlson, "Monotone Piecewise Cubic Interpolation",
/// SIAM J. Numer. Anal. 17(2), 1980): between keys the curve never overshoots the data, so
/// monotone data give a monotone curve. Outside `[x_0, x_n]` the curve is constant (the end
/// values) with zero derivative. A single key gives a constant curve.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Curve1D {
    x: Vec<f64>,
    y: Vec<f64>,
    /// Tangents dy/dx at the keys.
    m: Vec<f64>,
}

impl Curve1D {
    /// Builds the curve. Errors: no keys, non-finite values, or `x` not strictly increasing
    /// ([`Error::InvalidParameter`] naming the key).
    pub fn new(keys: &[(f64, f64)]) -> Result<Curve1D> {
        if keys.is_empty() {
            return Err(Error::InvalidParameter("Curve1D needs at least one key".into()));
        }
        for (i, &(x, y)) in keys.iter().enumerate() {
            if !x.is_finite() || !y.is_finite() {
                return Err(Error::InvalidParameter(format!("Curve1D key {i} is not finite")));
            }
            if i > 0 && x <= keys[i - 1].0 {
                return Err(Error::InvalidParameter(format!("Curve1D key {i}: x not strictly increasing")));
            }
        }
        let x: Vec<f64> = keys.iter().map(|k| k.0).collect();
        let y: Vec<f64> = keys.iter().map(|k| k.1).collect();
        let n = x.len();
        let mut m = vec![0.0; n];
        if n >= 2 {
            let d: Vec<f64> = (0..n - 1).map(|k| (y[k + 1] - y[k]) / (x[k + 1] - x[k])).collect();
            m[0] = d[0];
            m[n - 1] = d[n - 2];
            for k in 1..n - 1 {
                // Three-point average, zero at local extrema (FC step 1).
                m[k] = if d[k - 1] * d[k] <= 0.0 { 0.0 } else { 0.5 * (d[k - 1] + d[k]) };
            }
            // FC steps 2–5: limit (α, β) to the circle of radius 3 on every interval.
            for k in 0..n - 1 {
                if d[k] == 0.0 {
                    m[k] = 0.0;
                    m[k + 1] = 0.0;
                    continue;
                }
                let a = m[k] / d[k];
                let b = m[k + 1] / d[k];
                let s = a * a + b * b;
                if s > 9.0 {
                    let tau = 3.0 / s.sqrt();
                    m[k] = tau * a * d[k];
                    m[k + 1] = tau * b * d[k];
                }
            }
        }
        Ok(Curve1D { x, y, m })
    }

    /// Interval index `k` with `x_k ≤ t ≤ x_{k+1}` (caller ensures `t` is inside the range).
    fn interval(&self, t: f64) -> usize {
        let k = self.x.partition_point(|&xi| xi <= t);
        k.saturating_sub(1).min(self.x.len() - 2)
    }

    /// Value at `t` (the end values outside the key range).
    pub fn eval(&self, t: f64) -> f64 {
        let n = self.x.len();
        if n == 1 || t <= self.x[0] {
            return self.y[0];
        }
        if t >= self.x[n - 1] {
            return self.y[n - 1];
        }
        let k = self.interval(t);
        let h = self.x[k + 1] - self.x[k];
        let s = (t - self.x[k]) / h;
        let (s2, s3) = (s * s, s * s * s);
        let h00 = 2.0 * s3 - 3.0 * s2 + 1.0;
        let h10 = s3 - 2.0 * s2 + s;
        let h01 = -2.0 * s3 + 3.0 * s2;
        let h11 = s3 - s2;
        h00 * self.y[k] + h10 * h * self.m[k] + h01 * self.y[k + 1] + h11 * h * self.m[k + 1]
    }

    /// Derivative d/dt at `t` (0 outside the key range).
    pub fn deriv(&self, t: f64) -> f64 {
        let n = self.x.len();
        if n == 1 || t < self.x[0] || t > self.x[n - 1] {
            return 0.0;
        }
        let k = self.interval(t);
        let h = self.x[k + 1] - self.x[k];
        let s = (t - self.x[k]) / h;
        let s2 = s * s;
        let d00 = 6.0 * s2 - 6.0 * s;
        let d10 = 3.0 * s2 - 4.0 * s + 1.0;
        let d01 = -6.0 * s2 + 6.0 * s;
        let d11 = 3.0 * s2 - 2.0 * s;
        (d00 * self.y[k] + d01 * self.y[k + 1]) / h + d10 * self.m[k] + d11 * self.m[k + 1]
    }

    /// The key abscissae.
    pub fn xs(&self) -> &[f64] {
        &self.x
    }
}

/// Linear interpolation `a + t·(b − a)`; `t` may lie outside `[0, 1]` (extrapolation), which
/// [`catmull_rom`] relies on.
pub trait Lerp: Sized {
    /// `self + t·(other − self)`.
    fn lerp(&self, other: &Self, t: f64) -> Self;
}

impl Lerp for f64 {
    fn lerp(&self, other: &Self, t: f64) -> Self {
        self + t * (other - self)
    }
}
impl Lerp for Vec2 {
    fn lerp(&self, other: &Self, t: f64) -> Self {
        self + (other - self) * t
    }
}
impl Lerp for Vec3 {
    fn lerp(&self, other: &Self, t: f64) -> Self {
        self + (other - self) * t
    }
}
impl Lerp for Pt2 {
    fn lerp(&self, other: &Self, t: f64) -> Self {
        self + (other - self) * t
    }
}
impl Lerp for Pt3 {
    fn lerp(&self, other: &Self, t: f64) -> Self {
        self + (other - self) * t
    }
}
/// Element-wise; the result has the length of the shorter input (inputs should match).
impl<T: Lerp> Lerp for Vec<T> {
    fn lerp(&self, other: &Self, t: f64) -> Self {
        self.iter().zip(other).map(|(a, b)| a.lerp(b, t)).collect()
    }
}
impl<T: Lerp + Copy, const N: usize> Lerp for [T; N] {
    fn lerp(&self, other: &Self, t: f64) -> Self {
        std::array::from_fn(|i| self[i].lerp(&other[i], t))
    }
}

/// Uniform Catmull–Rom spline through keys `(time, value)` sorted by time, evaluated at `t`.
///
/// On the segment `[t_i, t_{i+1}]` (local parameter `u = (t − t_i)/(t_{i+1} − t_i)`) the curve
/// uses the control values `P_{i−1}, P_i, P_{i+1}, P_{i+2}` with the uniform parameterisation,
/// evaluated with the Barry–Goldman pyramid of lerps, so the tangent at key `i` is
/// `(P_{i+1} − P_{i−1})/2` per segment. Ends are one-sided: the missing neighbour is the
/// reflection `2P_0 − P_1`, which makes the end tangent `P_1 − P_0`. Outside the key range the
/// end values are held; a single key gives that value everywhere. Linear data are reproduced
/// exactly.
///
/// # Panics
/// If `keys` is empty (a programming error: there is nothing to interpolate; validate key lists
/// read from user files before calling).
pub fn catmull_rom<T: Lerp + Clone>(keys: &[(f64, T)], t: f64) -> T {
    assert!(!keys.is_empty(), "catmull_rom needs at least one key");
    let n = keys.len();
    if n == 1 || t <= keys[0].0 || t.is_nan() {
        return keys[0].1.clone();
    }
    if t >= keys[n - 1].0 {
        return keys[n - 1].1.clone();
    }
    // Segment i with t_i ≤ t < t_{i+1}.
    let i = keys.partition_point(|k| k.0 <= t).saturating_sub(1).min(n - 2);
    let (t0, t1) = (keys[i].0, keys[i + 1].0);
    let u = if t1 > t0 { (t - t0) / (t1 - t0) } else { 0.0 };
    let p1 = &keys[i].1;
    let p2 = &keys[i + 1].1;
    let p0 = if i > 0 { keys[i - 1].1.clone() } else { p1.lerp(p2, -1.0) };
    let p3 = if i + 2 < n { keys[i + 2].1.clone() } else { p1.lerp(p2, 2.0) };
    // Barry–Goldman with uniform knots −1, 0, 1, 2.
    let a1 = p0.lerp(p1, u + 1.0);
    let a2 = p1.lerp(p2, u);
    let a3 = p2.lerp(&p3, u - 1.0);
    let b1 = a1.lerp(&a2, 0.5 * (u + 1.0));
    let b2 = a2.lerp(&a3, 0.5 * u);
    b1.lerp(&b2, u)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn curve_interpolates_keys_and_is_constant_outside() {
        let c = Curve1D::new(&[(0.0, 1.0), (1.0, 3.0), (2.5, 3.5), (4.0, 0.0)]).unwrap();
        for &(x, y) in &[(0.0, 1.0), (1.0, 3.0), (2.5, 3.5), (4.0, 0.0)] {
            assert!((c.eval(x) - y).abs() < 1e-15);
        }
        assert_eq!(c.eval(-10.0), 1.0);
        assert_eq!(c.eval(10.0), 0.0);
        assert_eq!(c.deriv(-1.0), 0.0);
        assert_eq!(c.deriv(5.0), 0.0);
        let single = Curve1D::new(&[(2.0, 7.0)]).unwrap();
        assert_eq!(single.eval(0.0), 7.0);
        assert_eq!(single.eval(3.0), 7.0);
        assert_eq!(single.deriv(2.0), 0.0);
    }

    #[test]
    fn curve_is_monotone_on_monotone_data() {
        // Data with a sharp step: an ordinary cubic spline overshoots here.
        let keys = [(0.0, 0.0), (1.0, 0.0), (1.1, 1.0), (2.0, 1.0), (3.0, 1.05), (4.0, 3.0)];
        let c = Curve1D::new(&keys).unwrap();
        let mut prev = c.eval(0.0);
        for i in 1..=4000 {
            let v = c.eval(i as f64 * 1e-3);
            assert!(v >= prev - 1e-15, "not monotone at {}", i as f64 * 1e-3);
            prev = v;
        }
        // Flat pieces stay flat (no overshoot).
        assert!(c.eval(0.5).abs() < 1e-15);
        assert!((c.eval(1.5) - 1.0).abs() < 1e-15);
    }

    #[test]
    fn curve_derivative_matches_finite_differences() {
        let c = Curve1D::new(&[(0.0, 0.0), (0.7, 1.0), (1.5, 0.2), (3.0, 2.0)]).unwrap();
        let h = 1e-6;
        for i in 1..300 {
            let t = i as f64 * 0.01;
            if [0.7, 1.5].iter().any(|k| (t - k).abs() < 2.0 * h) {
                continue;
            }
            let fd = (c.eval(t + h) - c.eval(t - h)) / (2.0 * h);
            // Central difference error O(h²·f''') ≈ 1e-10, plus rounding 1e-16/h ≈ 1e-10.
            assert!((fd - c.deriv(t)).abs() < 1e-8, "t = {t}: {fd} vs {}", c.deriv(t));
        }
    }

    #[test]
    fn curve_rejects_bad_keys() {
        assert!(Curve1D::new(&[]).is_err());
        assert!(Curve1D::new(&[(0.0, 1.0), (0.0, 2.0)]).is_err());
        assert!(Curve1D::new(&[(1.0, 1.0), (0.0, 2.0)]).is_err());
        assert!(Curve1D::new(&[(0.0, f64::NAN)]).is_err());
    }

    #[test]
    fn catmull_rom_properties() {
        // Interpolates keys, holds outside.
        let keys = vec![(0.0, 1.0), (1.0, 2.0), (2.0, 0.0), (3.0, 5.0)];
        for (t, v) in &keys {
            assert!((catmull_rom(&keys, *t) - v).abs() < 1e-15);
        }
        assert_eq!(catmull_rom(&keys, -1.0), 1.0);
        assert_eq!(catmull_rom(&keys, 9.0), 5.0);
        // Reproduces linear data exactly (the one-sided ends keep lines straight).
        let lin: Vec<(f64, f64)> = (0..5).map(|i| (i as f64, 2.0 * i as f64 - 1.0)).collect();
        for i in 0..=40 {
            let t = i as f64 * 0.1;
            assert!((catmull_rom(&lin, t) - (2.0 * t - 1.0)).abs() < 1e-14);
        }
        // Interior tangent (P_{i+1} − P_{i−1})/2 at key 1: (0 − 1)/2, from both sides (C¹).
        // One-sided differences err by h·|f''|/2 ≈ 1e-6·O(10).
        let h = 1e-6;
        let dl = (catmull_rom(&keys, 1.0) - catmull_rom(&keys, 1.0 - h)) / h;
        let dr = (catmull_rom(&keys, 1.0 + h) - catmull_rom(&keys, 1.0)) / h;
        assert!((dl + 0.5).abs() < 2e-5 && (dr + 0.5).abs() < 2e-5, "{dl} {dr}");
        // End tangent one-sided: P_1 − P_0 = 1.
        let d0 = (catmull_rom(&keys, h) - catmull_rom(&keys, 0.0)) / h;
        assert!((d0 - 1.0).abs() < 1e-5, "{d0}");
        // Works on points and vectors of points.
        let pk = vec![(0.0, Pt3::new(0.0, 0.0, 0.0)), (1.0, Pt3::new(1.0, 2.0, 3.0))];
        assert!((catmull_rom(&pk, 0.5) - Pt3::new(0.5, 1.0, 1.5)).norm() < 1e-15);
        let vk = vec![(0.0, vec![Pt3::origin(); 2]), (2.0, vec![Pt3::new(2.0, 0.0, 0.0); 2])];
        assert!((catmull_rom(&vk, 1.0)[1] - Pt3::new(1.0, 0.0, 0.0)).norm() < 1e-15);
        assert_eq!(catmull_rom(&[(0.0, 4.0)], 3.0), 4.0);
    }
}

//! [`PointTrack`]: a point-cloud motion (frames × points), the representation every signal of the
//! method is compared in (spec §3.1), with uniform time stretch (§3.3), box-filtered downsampling
//! (§3.8) and planar transforms.

use geom_core::math::{Planar, Vec3};
use serde::{Deserialize, Serialize};

/// Point-cloud motion: `len()` frames of `n_points` points, world coordinates (Y up, metres),
/// frame-major (`data[f·n_points + p]`), sampled at `rate_hz`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PointTrack {
    /// Sample rate (Hz).
    pub rate_hz: f64,
    /// Points per frame.
    pub n_points: usize,
    /// Positions, frames × points.
    pub data: Vec<Vec3>,
}

/// Sample `k` of a uniform stretch of `n` intervals onto `d` intervals: source position
/// `k·n/d` as (integer part, remainder over `d`). Exact integer arithmetic, so `d = n` is the
/// identity bitwise and the last sample is the last source sample.
#[inline]
pub(crate) fn stretch_index(k: usize, n: usize, d: usize) -> (usize, f64) {
    let num = k * n;
    let i = num / d;
    let r = num % d;
    (i, r as f64 / d as f64)
}

/// Stretches frames × `k` points from `n + 1` samples to `d + 1` samples (spec §3.3:
/// `a^d(j) = a(j·n/d)`, linear interpolation), writing into `out`.
pub(crate) fn stretch_into(src: &[Vec3], k: usize, d: usize, out: &mut Vec<Vec3>) {
    out.clear();
    let n = src.len() / k - 1;
    for j in 0..=d {
        let (i, s) = if d == 0 { (0, 0.0) } else { stretch_index(j, n, d) };
        for p in 0..k {
            if s == 0.0 {
                out.push(src[i * k + p]);
            } else {
                out.push(src[i * k + p] + (src[(i + 1) * k + p] - src[i * k + p]) * s);
            }
        }
    }
}

impl PointTrack {
    /// A track from its parts (the data length must be a multiple of `n_points`; callers check).
    pub fn new(rate_hz: f64, n_points: usize, data: Vec<Vec3>) -> Self {
        Self { rate_hz, n_points, data }
    }

    /// Number of frames.
    pub fn len(&self) -> usize {
        self.data.len().checked_div(self.n_points).unwrap_or(0)
    }

    /// True when there is no frame.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The points of frame `k`.
    ///
    /// # Panics
    /// If `k ≥ len()`.
    pub fn frame(&self, k: usize) -> &[Vec3] {
        &self.data[k * self.n_points..(k + 1) * self.n_points]
    }

    /// Frames `[a, b]` (inclusive) as a new track.
    ///
    /// # Panics
    /// If `a > b` or `b ≥ len()`.
    pub fn window(&self, a: usize, b: usize) -> PointTrack {
        PointTrack::new(self.rate_hz, self.n_points, self.data[a * self.n_points..(b + 1) * self.n_points].to_vec())
    }

    /// Uniform time stretch to `n_out` frames with the same first and last frame (spec §3.3);
    /// `n_out = len()` is the identity (bitwise). `n_out ≤ 1` gives the first frame only; an
    /// empty track stays empty. The rate is unchanged (the motion plays faster or slower).
    pub fn stretch(&self, n_out: usize) -> PointTrack {
        if self.is_empty() || n_out == 0 {
            return PointTrack::new(self.rate_hz, self.n_points, vec![]);
        }
        if self.len() == 1 || n_out == 1 {
            return PointTrack::new(self.rate_hz, self.n_points, self.frame(0).to_vec());
        }
        let mut out = Vec::new();
        stretch_into(&self.data, self.n_points, n_out - 1, &mut out);
        PointTrack::new(self.rate_hz, self.n_points, out)
    }

    /// Box pre-filter of width `factor` (centred; an even width has half-weight end taps, so the
    /// filter stays symmetric; clamped at the ends), then keeps frames `0, factor, 2·factor, …`;
    /// the rate becomes `rate_hz / factor`. `factor ≤ 1` returns a copy.
    pub fn downsample(&self, factor: usize) -> PointTrack {
        if factor <= 1 || self.is_empty() {
            return self.clone();
        }
        let f = prefilter(self, factor);
        let k = self.n_points;
        let mut out = Vec::with_capacity(self.len().div_ceil(factor) * k);
        for j in (0..self.len()).step_by(factor) {
            out.extend_from_slice(f.frame(j));
        }
        PointTrack::new(self.rate_hz / factor as f64, k, out)
    }

    /// Every point moved by the planar transform `m`.
    pub fn transformed(&self, m: &Planar) -> PointTrack {
        PointTrack::new(self.rate_hz, self.n_points, self.data.iter().map(|p| m.apply_point(*p)).collect())
    }

    /// Per-frame positions resampled at fractional native frame `u` (linear, clamped).
    pub(crate) fn sample(&self, u: f64, out: &mut Vec<Vec3>) {
        let n = self.len();
        let u = u.clamp(0.0, (n - 1) as f64);
        let i = (u.floor() as usize).min(n.saturating_sub(2));
        let s = if n == 1 { 0.0 } else { u - i as f64 };
        let i1 = (i + 1).min(n - 1);
        for p in 0..self.n_points {
            let a = self.data[i * self.n_points + p];
            let b = self.data[i1 * self.n_points + p];
            out.push(if s == 0.0 { a } else { a + (b - a) * s });
        }
    }
}

/// Centred box filter of width `factor` (an even width has half-weight end taps so the filter
/// stays symmetric; clamped at the ends), without decimation.
pub(crate) fn prefilter(t: &PointTrack, factor: usize) -> PointTrack {
    let n = t.len();
    let k = t.n_points;
    let half = (factor / 2) as isize;
    let mut out = Vec::with_capacity(t.data.len());
    for f in 0..n as isize {
        for p in 0..k {
            let mut acc = Vec3::zeros();
            for o in -half..=half {
                let w = if factor & 1 == 0 && o.unsigned_abs() == factor / 2 { 0.5 } else { 1.0 } / factor as f64;
                let j = (f + o).clamp(0, n as isize - 1) as usize;
                acc += t.data[j * k + p] * w;
            }
            out.push(acc);
        }
    }
    PointTrack::new(t.rate_hz, k, out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stretch_identity_is_bitwise_and_linear_signals_are_exact() {
        let data: Vec<Vec3> =
            (0..14).map(|i| Vec3::new((i as f64).sin(), 0.3 * i as f64, (i as f64 * 0.7).cos())).collect();
        let t = PointTrack::new(30.0, 2, data);
        assert_eq!(t.stretch(7), t);
        // Linear in time: p(k) = a + b·k per point; stretched to m frames p(j·(n−1)/(m−1)).
        let a = Vec3::new(0.1, -0.2, 0.3);
        let b = Vec3::new(0.7, 0.05, -1.3);
        let lin = PointTrack::new(10.0, 1, (0..9).map(|k| a + b * k as f64).collect());
        for m in [2, 5, 9, 13, 20] {
            let s = lin.stretch(m);
            assert_eq!(s.len(), m);
            for j in 0..m {
                let u = j as f64 * 8.0 / (m - 1) as f64;
                assert!((s.frame(j)[0] - (a + b * u)).norm() <= 1e-12);
            }
        }
    }

    #[test]
    fn downsample_keeps_constants_and_linear_signals_in_the_interior() {
        let lin = PointTrack::new(30.0, 1, (0..31).map(|k| Vec3::new(k as f64, 1.0, 2.0)).collect());
        for f in [2, 3, 4] {
            let d = lin.downsample(f);
            assert!((d.rate_hz - 30.0 / f as f64).abs() < 1e-12);
            assert_eq!(d.len(), 31usize.div_ceil(f));
            // Symmetric filter: interior samples of a linear signal are unchanged.
            for j in 1..d.len() - 1 {
                if j * f + f / 2 < 31 {
                    assert!((d.frame(j)[0].x - (j * f) as f64).abs() < 1e-12);
                }
                assert!((d.frame(j)[0].y - 1.0).abs() < 1e-15);
            }
        }
    }
}

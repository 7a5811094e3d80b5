//! Several patterns and smooth switching (spec §3.10, weight function reconstructed): a
//! symmetric power smoothstep of the position of each linearised factor inside the transition
//! band `m̄ ± v·|m̄|`.

use serde::{Deserialize, Serialize};

/// Blend options.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct BlendOptions {
    /// Half-width v of the transition zone relative to the mean factor (≥ 0).
    pub variance: f64,
    /// Power n ≥ 1 of the smoothstep; `f64::INFINITY` = the paper's sudden switch.
    pub power: f64,
}

impl Default for BlendOptions {
    fn default() -> Self {
        Self { variance: 0.03, power: 4.0 }
    }
}

/// `S_n(t) = ½(2t)^n` for t ≤ ½, `1 − ½(2 − 2t)^n` above; `S_n(t) + S_n(1−t) = 1`.
pub fn smoothstep_n(t: f64, n: f64) -> f64 {
    let t = t.clamp(0.0, 1.0);
    if n.is_infinite() {
        return if t > 0.5 {
            1.0
        } else if t < 0.5 {
            0.0
        } else {
            0.5
        };
    }
    if t <= 0.5 {
        0.5 * (2.0 * t).powf(n)
    } else {
        1.0 - 0.5 * (2.0 - 2.0 * t).powf(n)
    }
}

/// Pattern weights from the linearised factors `m` of one triangle; patterns with
/// `active[i] == false` get weight 0 unless none is active (then all share equally). Ties split
/// evenly; never divides by zero.
pub fn pattern_weights(m: &[f64], active: &[bool], o: &BlendOptions, out: &mut [f64]) {
    let p = m.len();
    if p == 0 {
        return;
    }
    let n_act = active.iter().filter(|a| **a).count();
    if n_act == 0 {
        out.iter_mut().for_each(|w| *w = 1.0 / p as f64);
        return;
    }
    if n_act == 1 {
        for i in 0..p {
            out[i] = if active[i] { 1.0 } else { 0.0 };
        }
        return;
    }
    let mean = (0..p).filter(|&i| active[i]).map(|i| m[i]).sum::<f64>() / n_act as f64;
    let delta = o.variance * mean.abs();
    if delta.is_nan() || delta <= 0.0 || o.power.is_infinite() {
        // Hard switch: argmin, ties split evenly.
        let mn = (0..p).filter(|&i| active[i]).map(|i| m[i]).fold(f64::INFINITY, f64::min);
        let ties = (0..p).filter(|&i| active[i] && m[i] == mn).count();
        for i in 0..p {
            out[i] = if active[i] && m[i] == mn { 1.0 / ties as f64 } else { 0.0 };
        }
        if o.power.is_infinite() && delta > 0.0 {
            // With n = ∞ and a band, S_∞ is a step at t = ½: identical to argmin for P = 2.
        }
        return;
    }
    let mut sum = 0.0;
    for i in 0..p {
        out[i] = if active[i] { smoothstep_n((mean + delta - m[i]) / (2.0 * delta), o.power) } else { 0.0 };
        sum += out[i];
    }
    if sum > 0.0 {
        out.iter_mut().for_each(|w| *w /= sum);
    } else {
        for i in 0..p {
            out[i] = if active[i] { 1.0 / n_act as f64 } else { 0.0 };
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// T12: Σ W = 1; n = 1 is linear in MF; n = ∞ a step; for P = 2 and fixed mean, sweeping
    /// MF2 − MF1 in steps of 1e-4 changes W by at most 1e-4·n/(4 v m̄) per step (max slope of S_n
    /// is n, and ∂t/∂(MF2−MF1) = 1/(4δ)).
    #[test]
    fn t12_weight_function() {
        let act = [true, true];
        let mut w = [0.0; 2];
        let o = BlendOptions { variance: 0.03, power: 4.0 };
        pattern_weights(&[0.9, 1.1], &act, &o, &mut w);
        assert_eq!(w, [1.0, 0.0]); // full selection beyond the band
        for n in [1.0, 2.0, 4.0, 8.0] {
            let o = BlendOptions { variance: 0.05, power: n };
            let mbar = 1.2;
            let bound = 1e-4 * n / (4.0 * 0.05 * mbar);
            let mut prev: Option<f64> = None;
            let mut k = -1500i32;
            while k <= 1500 {
                let diff = k as f64 * 1e-4;
                let m = [mbar - 0.5 * diff, mbar + 0.5 * diff];
                pattern_weights(&m, &act, &o, &mut w);
                assert!((w[0] + w[1] - 1.0).abs() < 1e-12);
                if n == 1.0 {
                    // linear ramp: W1 = t1 = clamp((δ + diff/2)/(2δ))
                    let d = 0.05 * mbar;
                    let t = ((d + 0.5 * diff) / (2.0 * d)).clamp(0.0, 1.0);
                    assert!((w[0] - t).abs() < 1e-12);
                }
                if let Some(p) = prev {
                    assert!((w[0] - p).abs() <= bound * (1.0 + 1e-9), "n {n} jump {}", (w[0] - p).abs());
                }
                prev = Some(w[0]);
                k += 1;
            }
        }
        // n = ∞: a step.
        let o = BlendOptions { variance: 0.05, power: f64::INFINITY };
        pattern_weights(&[1.0 - 1e-9, 1.0 + 1e-9], &act, &o, &mut w);
        assert_eq!(w, [1.0, 0.0]);
        pattern_weights(&[1.0, 1.0], &act, &o, &mut w);
        assert_eq!(w, [0.5, 0.5]);
        // v = 0: ties split, no NaN.
        let o = BlendOptions { variance: 0.0, power: 4.0 };
        pattern_weights(&[1.0, 1.0, 1.0], &[true; 3], &o, &mut [0.0; 3]);
        let mut w3 = [0.0; 3];
        pattern_weights(&[1.0, 1.0, 2.0], &[true; 3], &o, &mut w3);
        assert_eq!(w3, [0.5, 0.5, 0.0]);
        // inactive pattern gets 0.
        pattern_weights(&[0.5, 1.0], &[false, true], &BlendOptions::default(), &mut w);
        assert_eq!(w, [0.0, 1.0]);
    }
}

//! Plastic update of a hinge's rest angle and stiffness (seed §4.4, shells.md §3.6).
//!
//! Δκ = (|ē|/(2Ā_e))·wrap(θ − θ̄). If |Δκ| > Δκ_max, with x = |Δκ| − Δκ_max:
//! `SeedLiteral`: θ̄ ← θ − sign(Δκ)(2Ā_e/|ē|)x; `ReturnMapping`: θ̄ ← θ̄ + sign(Δκ)(2Ā_e/|ē|)x;
//! both: k ← k·exp(ηx), clamped to [1e-6, 1e6]·k₀.

use super::bending::{wrap_angle, Hinge};
use crate::material::{PlasticRule, Plasticity};

/// Outcome of one plastic update.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct PlasticEvent {
    /// The hinge yielded (θ̄ and k changed).
    pub yielded: bool,
    /// k hit the [1e-6, 1e6]·k₀ clamp.
    pub clamped: bool,
}

/// Curvature deviation Δκ = |ē|/(2Ā_e)·wrap(θ − θ̄) (1/m).
pub fn curvature_deviation(h: &Hinge, theta: f64) -> f64 {
    h.edge_len / (2.0 * h.area_sum) * wrap_angle(theta - h.rest_theta)
}

/// Applies the plastic rule to `h` given its current angle `theta`; returns true if it yielded
/// (shells.md §2 signature). `k0` clamping uses the hinge's current stiffness as reference; use
/// [`plastic_update_clamped`] to clamp against the original stiffness.
pub fn plastic_update(h: &mut Hinge, theta: f64, p: &Plasticity) -> bool {
    let k0 = h.stiffness;
    plastic_update_clamped(h, theta, p, k0).yielded
}

/// [`plastic_update`] with the hardening clamp [1e-6, 1e6]·`k0` (k₀ the original stiffness).
pub fn plastic_update_clamped(h: &mut Hinge, theta: f64, p: &Plasticity, k0: f64) -> PlasticEvent {
    let dk = curvature_deviation(h, theta);
    if !(dk.abs() > p.max_curvature_dev) {
        return PlasticEvent::default();
    }
    let x = dk.abs() - p.max_curvature_dev;
    let scale = 2.0 * h.area_sum / h.edge_len;
    let sign = dk.signum();
    h.rest_theta = match p.rule {
        PlasticRule::SeedLiteral => wrap_angle(theta - sign * scale * x),
        PlasticRule::ReturnMapping => wrap_angle(h.rest_theta + sign * scale * x),
    };
    let mut clamped = false;
    if p.hardening != 0.0 {
        let k = h.stiffness * (p.hardening * x).exp();
        let (lo, hi) = (1e-6 * k0, 1e6 * k0);
        let kc = k.clamp(lo, hi);
        clamped = kc != k;
        h.stiffness = kc;
    }
    PlasticEvent { yielded: true, clamped }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn hinge() -> Hinge {
        Hinge { v: [0, 1, 2, 3], rest_theta: 0.0, weight: 3.0, stiffness: 2.0, edge_len: 0.1, area_sum: 0.01 }
    }

    /// §7 test 14.
    #[test]
    fn plastic_rules() {
        let p = Plasticity { max_curvature_dev: 2.0, hardening: 0.0, rule: PlasticRule::ReturnMapping };
        // Below yield: Δκ = 0.1/0.02·θ = 5θ; θ = 0.3 → 1.5 < 2.
        let mut h = hinge();
        assert!(!plastic_update(&mut h, 0.3, &p));
        assert_eq!(h, hinge());
        // Return map: |Δκ| after = Δκ_max.
        let theta = 0.9;
        let mut h = hinge();
        assert!(plastic_update(&mut h, theta, &p));
        assert!((curvature_deviation(&h, theta).abs() - 2.0).abs() < 1e-12);
        assert_eq!(h.stiffness, 2.0); // η = 0 keeps k
                                      // Seed literal: remaining deviation equals the excess.
        let ps = Plasticity { rule: PlasticRule::SeedLiteral, ..p };
        let mut h = hinge();
        plastic_update(&mut h, theta, &ps);
        assert!((curvature_deviation(&h, theta).abs() - (5.0 * theta - 2.0)).abs() < 1e-12);
        // Step-size independence of the return map with hardening.
        let ph = Plasticity { hardening: 0.3, ..p };
        let final_of = |n: usize| {
            let mut h = hinge();
            for i in 1..=n {
                plastic_update_clamped(&mut h, 1.5 * i as f64 / n as f64, &ph, 2.0);
            }
            (h.rest_theta, h.stiffness)
        };
        let (t1, k1) = final_of(1);
        for n in [10, 100] {
            let (tn, kn) = final_of(n);
            assert!((tn - t1).abs() <= 1e-10 * t1.abs(), "{n}: {tn} {t1}");
            assert!((kn - k1).abs() <= 1e-10 * k1, "{n}: {kn} {k1}");
        }
        // Infinite yield never updates.
        let pi = Plasticity { max_curvature_dev: f64::INFINITY, ..ph };
        let mut h = hinge();
        assert!(!plastic_update(&mut h, 3.0, &pi));
        // Hardening clamp.
        let pc = Plasticity { hardening: 1e3, max_curvature_dev: 0.0, rule: PlasticRule::ReturnMapping };
        let mut h = hinge();
        let ev = plastic_update_clamped(&mut h, 1.0, &pc, 2.0);
        assert!(ev.clamped && h.stiffness == 2e6);
    }
}

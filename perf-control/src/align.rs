//! Closed-form planar alignment of two equally sampled point clouds (spec §3.3, paper eqs. 1–2):
//! `min_M Σ_k Σ_p w_p ‖x_{k,p} − M a_{k,p}‖²` over `M ∈ Planar` (rotation about +Y, floor
//! translation).
//!
//! With the floor coordinates of a point as the complex number `u = z + i·x` (a rotation by `θ`
//! about +Y multiplies by `e^{iθ}`, geom-core's [`Planar`] convention), weighted means `ū`
//! (input) and `v̄` (segment) and centred `ũ`, `ṽ`:
//! `h = Σ w ũ conj(ṽ)`, `θ = arg h`, `t = ū − e^{iθ} v̄`,
//! `D = Σ w|ũ|² + Σ w|ṽ|² − 2|h| + Σ w (y_x − y_a)²`.
//! If `|h| < 1e-12·Σ w(|ũ|² + |ṽ|²)` the rotation is undetermined and `θ = 0` (spec §8).

use geom_core::math::{Planar, Vec3};

/// Result of an alignment: the transform applied to the segment and the residual.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Alignment {
    /// `M`: maps the segment `a` onto the input `x`.
    pub m: Planar,
    /// Minimum weighted squared distance (m²), clamped at 0 against cancellation.
    pub d: f64,
}

/// Aligns `a` onto `x` (both frames × `w.len()` points, same length). Weights `w_p ≥ 0` per
/// point; an all-zero weight set gives the identity and `D = 0`. O(len) time.
pub fn align(x: &[Vec3], a: &[Vec3], w: &[f64]) -> Alignment {
    let k = w.len();
    debug_assert_eq!(x.len(), a.len());
    let mut sw = 0.0;
    let (mut ux, mut uz, mut vx, mut vz) = (0.0, 0.0, 0.0, 0.0);
    for (i, (p, q)) in x.iter().zip(a).enumerate() {
        let wi = w[i % k];
        sw += wi;
        ux += wi * p.x;
        uz += wi * p.z;
        vx += wi * q.x;
        vz += wi * q.z;
    }
    if sw <= 0.0 {
        return Alignment { m: Planar::identity(), d: 0.0 };
    }
    let (ux, uz, vx, vz) = (ux / sw, uz / sw, vx / sw, vz / sw);
    // h = Σ w (ũ)(conj ṽ), with u = z + i x: re = uz·vz + ux·vx, im = ux·vz − uz·vx.
    let (mut hr, mut hi, mut su, mut sv, mut sy) = (0.0, 0.0, 0.0, 0.0, 0.0);
    for (i, (p, q)) in x.iter().zip(a).enumerate() {
        let wi = w[i % k];
        let (px, pz) = (p.x - ux, p.z - uz);
        let (qx, qz) = (q.x - vx, q.z - vz);
        hr += wi * (pz * qz + px * qx);
        hi += wi * (px * qz - pz * qx);
        su += wi * (px * px + pz * pz);
        sv += wi * (qx * qx + qz * qz);
        let dy = p.y - q.y;
        sy += wi * dy * dy;
    }
    let habs = hr.hypot(hi);
    let theta = if habs < 1e-12 * (su + sv) || habs == 0.0 { 0.0 } else { hi.atan2(hr) };
    let (s, c) = theta.sin_cos();
    // e^{iθ} v̄ with v̄ = vz + i vx: re = c vz − s vx (z), im = s vz + c vx (x).
    let tz = uz - (c * vz - s * vx);
    let tx = ux - (s * vz + c * vx);
    let rot = if theta == 0.0 { su + sv - 2.0 * hr } else { su + sv - 2.0 * habs };
    Alignment { m: Planar::new(tx, tz, theta), d: (rot + sy).max(0.0) }
}

/// `Σ_k Σ_p w_p ‖x − M a‖²` for a given `M` (used by tests and by the chain scorer).
pub fn residual(x: &[Vec3], a: &[Vec3], w: &[f64], m: &Planar) -> f64 {
    let k = w.len();
    x.iter().zip(a).enumerate().map(|(i, (p, q))| w[i % k] * (p - m.apply_point(*q)).norm_squared()).sum()
}

#[cfg(test)]
mod tests {
    use super::*;
    use geom_core::rng::Rng;

    fn cloud(r: &mut Rng, n: usize) -> Vec<Vec3> {
        (0..n).map(|_| Vec3::new(r.range(-1.0, 1.0), r.range(0.0, 1.8), r.range(-1.0, 1.0))).collect()
    }

    #[test]
    fn recovers_a_random_planar_transform() {
        let mut r = Rng::new(7);
        for _ in 0..1000 {
            let k = 2 + r.below(5);
            let frames = 3 + r.below(10);
            let w: Vec<f64> = (0..k).map(|_| r.range(0.1, 3.0)).collect();
            let a = cloud(&mut r, k * frames);
            let g = Planar::new(r.range(-5.0, 5.0), r.range(-5.0, 5.0), r.range(-3.1, 3.1));
            let x: Vec<Vec3> = a.iter().map(|p| g.apply_point(*p)).collect();
            let al = align(&x, &a, &w);
            // Tolerances: a few hundred flops of O(1..10) magnitudes, rounding ≈ 1e-15 relative.
            let dyaw = geom_core::math::wrap_angle(al.m.yaw - g.yaw);
            assert!(dyaw.abs() <= 1e-9, "angle error {dyaw}");
            assert!((al.m.x - g.x).abs() <= 1e-9 && (al.m.z - g.z).abs() <= 1e-9);
            let sv: f64 = {
                let sw: f64 = (0..a.len()).map(|i| w[i % k]).sum();
                let mx = a.iter().enumerate().map(|(i, p)| w[i % k] * p.x).sum::<f64>() / sw;
                let mz = a.iter().enumerate().map(|(i, p)| w[i % k] * p.z).sum::<f64>() / sw;
                a.iter().enumerate().map(|(i, p)| w[i % k] * ((p.x - mx).powi(2) + (p.z - mz).powi(2))).sum()
            };
            assert!(al.d / sv <= 1e-12, "relative residual {}", al.d / sv);
        }
    }

    #[test]
    fn closed_form_beats_a_brute_force_angle_scan_and_is_invariant() {
        let mut r = Rng::new(11);
        for case in 0..6 {
            let k = 2 + r.below(5);
            let frames = 3 + r.below(10);
            let w: Vec<f64> = (0..k).map(|_| r.range(0.1, 3.0)).collect();
            let a = cloud(&mut r, k * frames);
            let x = cloud(&mut r, k * frames);
            let al = align(&x, &a, &w);
            // Its own residual agrees with the closed-form D.
            let res = residual(&x, &a, &w, &al.m);
            assert!((res - al.d).abs() <= 1e-10 * (1.0 + res), "case {case}: {res} vs {}", al.d);
            // Scan: for a fixed angle the best translation is the mean difference.
            let eval = |th: f64| {
                let rot = Planar::new(0.0, 0.0, th);
                let ra: Vec<Vec3> = a.iter().map(|p| rot.apply_point(*p)).collect();
                let sw: f64 = (0..a.len()).map(|i| w[i % k]).sum();
                let mut t = Vec3::zeros();
                for (i, (p, q)) in x.iter().zip(&ra).enumerate() {
                    t += (p - q) * w[i % k];
                }
                t /= sw;
                t.y = 0.0;
                let m = Planar::new(t.x, t.z, th);
                residual(&x, &a, &w, &m)
            };
            let n = 100_000;
            let mut best = (f64::INFINITY, 0.0);
            for i in 0..n {
                let th = -std::f64::consts::PI + std::f64::consts::TAU * i as f64 / n as f64;
                let v = eval(th);
                if v < best.0 {
                    best = (v, th);
                }
            }
            // Golden-section refine in the bracket around the scan minimum.
            let h = std::f64::consts::TAU / n as f64;
            let (mut lo, mut hi) = (best.1 - h, best.1 + h);
            let g = 0.5 * (5f64.sqrt() - 1.0);
            for _ in 0..80 {
                let c = hi - g * (hi - lo);
                let d = lo + g * (hi - lo);
                if eval(c) < eval(d) {
                    hi = d;
                } else {
                    lo = c;
                }
            }
            let scan_min = eval(0.5 * (lo + hi)).min(best.0);
            assert!(al.d <= scan_min + 1e-10, "case {case}: {} > {}", al.d, scan_min);
            // Invariance: D(Gx, a) = D(x, a).
            let gm = Planar::new(r.range(-3.0, 3.0), r.range(-3.0, 3.0), r.range(-3.0, 3.0));
            let gx: Vec<Vec3> = x.iter().map(|p| gm.apply_point(*p)).collect();
            let d2 = align(&gx, &a, &w).d;
            assert!((d2 - al.d).abs() <= 1e-10 * al.d.max(1e-300), "invariance {d2} vs {}", al.d);
        }
    }

    #[test]
    fn coincident_points_are_degenerate_but_finite() {
        let x = vec![Vec3::new(1.0, 0.0, 2.0); 5];
        let a = vec![Vec3::new(-3.0, 0.5, 0.0); 5];
        let al = align(&x, &a, &[1.0]);
        assert_eq!(al.m.yaw, 0.0);
        assert!((al.d - 5.0 * 0.25).abs() < 1e-12);
        assert!((al.m.apply_point(a[0]) - Vec3::new(1.0, 0.5, 2.0)).norm() < 1e-12);
    }
}

//! Discrete Shells hinge bending energy E_e = k_e ω_e (Δθ_e)², ω_e = 3|ē|²/(Ā₁+Ā₂),
//! Δθ_e = wrap(θ_e − θ̄_e) (Grinspun et al. 2003; shells.md §3.2).
//!
//! ∇E = 2kωΔθ∇θ, ∇²E = 2kω(∇θ∇θᵀ + Δθ∇²θ). Only rest quantities enter ω, so the Hessian has no
//! area-derivative terms. `ProjectedCheap` keeps the rank-one Gauss–Newton term only (and never
//! computes ∇²θ), `ProjectedEigen` clamps the exact 12×12, `Full` keeps it.

use super::hinge::{hinge_is_collapsed, HingeFrame, Mat12};
use super::psd::{project_psd, HessianMode};
use geom_core::math::Pt3;
use nalgebra::SVector;
use serde::{Deserialize, Serialize};
use std::f64::consts::PI;

/// 12-vector over a hinge's four vertices.
pub type Vec12 = SVector<f64, 12>;

/// One interior edge with its rest data (shells.md §2, §3.1).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Hinge {
    /// `[a, b, w1, w2]`: triangle 1 = (a, b, w1) holds a→b, triangle 2 = (b, a, w2) holds b→a.
    pub v: [u32; 4],
    /// Rest angle θ̄ (rad, in (−π, π]); changed by plasticity.
    pub rest_theta: f64,
    /// ω_e = 3|ē|²/(Ā₁+Ā₂) (dimensionless).
    pub weight: f64,
    /// k_e (J); k_B unless painted or hardened by plasticity.
    pub stiffness: f64,
    /// Rest edge length |ē| (m).
    pub edge_len: f64,
    /// Ā_e = Ā₁ + Ā₂ (m²).
    pub area_sum: f64,
}

/// Wraps an angle difference into (−π, π].
#[inline]
pub fn wrap_angle(x: f64) -> f64 {
    if x > -PI && x <= PI {
        return x;
    }
    let y = (x + PI).rem_euclid(2.0 * PI) - PI;
    if y <= -PI {
        y + 2.0 * PI
    } else {
        y
    }
}

/// Result of one hinge evaluation.
#[derive(Clone, Debug)]
pub struct BendingOut {
    /// Energy k ω Δθ² (J).
    pub energy: f64,
    /// Gradient (N), blocks a, b, w1, w2.
    pub grad: Vec12,
    /// Hessian in the requested mode (N/m).
    pub hess: Mat12,
    /// Gauss–Newton part 2kω∇θ∇θᵀ (for damping), when asked for.
    pub gauss_newton: Option<Mat12>,
    /// True when the hinge was skipped because a triangle collapsed (§8); everything is zero.
    pub skipped: bool,
}

/// Bending element: energy, gradient and Hessian of one hinge in `mode` (shells.md §2).
/// A collapsed hinge (|Nᵢ| < 1e-14ℓ²) contributes zeros.
pub fn bending_element(h: &Hinge, x: &[Pt3; 4], mode: HessianMode) -> (f64, Vec12, Mat12) {
    let o = bending_eval(h, x, mode, false);
    (o.energy, o.grad, o.hess)
}

/// Energy only.
pub fn bending_energy(h: &Hinge, x: &[Pt3; 4]) -> f64 {
    if hinge_is_collapsed(x) {
        return 0.0;
    }
    let d = wrap_angle(super::hinge::hinge_angle(x) - h.rest_theta);
    h.stiffness * h.weight * d * d
}

/// Full evaluation; `want_gn` also returns the Gauss–Newton matrix (used by damping).
pub fn bending_eval(h: &Hinge, x: &[Pt3; 4], mode: HessianMode, want_gn: bool) -> BendingOut {
    if hinge_is_collapsed(x) {
        return BendingOut {
            energy: 0.0,
            grad: Vec12::zeros(),
            hess: Mat12::zeros(),
            gauss_newton: want_gn.then(Mat12::zeros),
            skipped: true,
        };
    }
    let fr = HingeFrame::new(x);
    let d = wrap_angle(fr.angle() - h.rest_theta);
    let kw = h.stiffness * h.weight;
    let g4 = fr.grad();
    let mut gt = Vec12::zeros();
    for (v, gv) in g4.iter().enumerate() {
        gt.fixed_rows_mut::<3>(3 * v).copy_from(gv);
    }
    let gn = 2.0 * kw * gt * gt.transpose();
    let hess = match mode {
        HessianMode::ProjectedCheap => gn,
        HessianMode::Full | HessianMode::ProjectedEigen => {
            let full = gn + 2.0 * kw * d * fr.hessian();
            let full = (full + full.transpose()) * 0.5;
            if mode == HessianMode::ProjectedEigen {
                project_psd(&full)
            } else {
                full
            }
        }
    };
    BendingOut {
        energy: kw * d * d,
        grad: 2.0 * kw * d * gt,
        hess,
        gauss_newton: want_gn.then_some(gn),
        skipped: false,
    }
}

#[cfg(test)]
mod tests {
    use super::super::hinge::hinge_angle;
    use super::*;
    use crate::kernels::testutil::TestRng;
    use nalgebra::SymmetricEigen;

    fn random_hinge(r: &mut TestRng) -> [Pt3; 4] {
        loop {
            let p = [
                Pt3::new(r.range(-0.1, 0.1), r.range(-0.1, 0.1), r.range(-0.1, 0.1)),
                Pt3::new(1.0 + r.range(-0.1, 0.1), r.range(-0.1, 0.1), r.range(-0.1, 0.1)),
                Pt3::new(r.range(0.1, 0.9), r.range(0.4, 1.2), r.range(-0.8, 0.8)),
                Pt3::new(r.range(0.1, 0.9), -r.range(0.4, 1.2), r.range(-0.8, 0.8)),
            ];
            if !hinge_is_collapsed(&p) && hinge_angle(&p).abs() < 3.0 {
                return p;
            }
        }
    }

    fn hinge(r: &mut TestRng) -> Hinge {
        Hinge {
            v: [0, 1, 2, 3],
            rest_theta: r.range(-1.0, 1.0),
            weight: 2.5,
            stiffness: 0.7,
            edge_len: 1.0,
            area_sum: 1.2,
        }
    }

    /// §7 test 4 (bending): energy gradient and Hessian (Full) vs finite differences.
    #[test]
    fn bending_fd() {
        let mut r = TestRng::new(3);
        for _ in 0..100 {
            let h = hinge(&mut r);
            let x = random_hinge(&mut r);
            let (_, g, hh) = bending_element(&h, &x, HessianMode::Full);
            let eps = 1e-6;
            let mut gfd = Vec12::zeros();
            let mut hfd = Mat12::zeros();
            for j in 0..12 {
                let (mut xp, mut xm) = (x, x);
                xp[j / 3][j % 3] += eps;
                xm[j / 3][j % 3] -= eps;
                gfd[j] = (bending_energy(&h, &xp) - bending_energy(&h, &xm)) / (2.0 * eps);
                let gp = bending_element(&h, &xp, HessianMode::Full).1;
                let gm = bending_element(&h, &xm, HessianMode::Full).1;
                hfd.set_column(j, &((gp - gm) / (2.0 * eps)));
            }
            assert!((g - gfd).amax() < 1e-6 * gfd.amax().max(1e-6));
            assert!((hh - hfd).amax() < 1e-6 * hfd.amax());
        }
    }

    /// §7 test 7 (bending half): projected matrices PSD; unchanged at rest.
    #[test]
    fn bending_psd_projection() {
        let mut r = TestRng::new(4);
        for _ in 0..1000 {
            let h = hinge(&mut r);
            let x = random_hinge(&mut r);
            for mode in [HessianMode::ProjectedCheap, HessianMode::ProjectedEigen] {
                let (_, _, m) = bending_element(&h, &x, mode);
                let ev = SymmetricEigen::new(m).eigenvalues;
                assert!(ev.min() >= -1e-10 * m.amax());
            }
            let rest = Hinge { rest_theta: hinge_angle(&x), ..h };
            let (e, g, full) = bending_element(&rest, &x, HessianMode::Full);
            assert_eq!(e, 0.0);
            assert_eq!(g.amax(), 0.0);
            for mode in [HessianMode::ProjectedCheap, HessianMode::ProjectedEigen] {
                let (_, _, m) = bending_element(&rest, &x, mode);
                assert!((m - full).amax() <= 1e-12 * full.amax());
            }
        }
    }

    /// Energy continuous across the ±π branch cut thanks to the wrap.
    #[test]
    fn wrap_is_continuous() {
        assert_eq!(wrap_angle(PI), PI);
        assert!((wrap_angle(-PI) - PI).abs() < 1e-15);
        assert!((wrap_angle(3.0 * PI / 2.0) + PI / 2.0).abs() < 1e-15);
        assert!((wrap_angle(-7.0) - (-7.0 + 2.0 * PI)).abs() < 1e-15);
        let h = Hinge { v: [0, 1, 2, 3], rest_theta: 3.1, weight: 1.0, stiffness: 1.0, edge_len: 1.0, area_sum: 1.0 };
        let mk = |t: f64| {
            [
                Pt3::new(0.0, 0.0, 0.0),
                Pt3::new(1.0, 0.0, 0.0),
                Pt3::new(0.5, 1.0, 0.0),
                Pt3::new(0.5, -t.cos(), -t.sin()),
            ]
        };
        // θ just below and just above π (w2 rotated about the edge).
        let e1 = bending_energy(&h, &mk(PI - 1e-7));
        let e2 = bending_energy(&h, &mk(-PI + 1e-7));
        assert!((e1 - e2).abs() < 1e-5, "{e1} {e2}");
    }
}

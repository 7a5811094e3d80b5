//! Modulation tests: T5–T11, T16, T21, T22 and the W1 1-D analytic amplitudes.

mod common;

use common::*;
use geom_core::math::{Mat2, Pt3, Vec3};
use geom_core::rng::Rng;
use nalgebra::{Rotation3, Unit};
use wrinkles::modulation::{exact_terms, solve_exact, wrinkled_area};
use wrinkles::*;

const LIN_GREEN: ModulationMode = ModulationMode::Linearized { strain: StrainMeasure::Green };
const LIN_ABD: ModulationMode = ModulationMode::Linearized { strain: StrainMeasure::PaperAbd };

fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs()
}

/// The T9 fixture: 2-triangle 0.1 m square, 8 periods along x (λ = 12.5 mm), phase 0, slope s.
fn t9_rig(s: f64) -> WrinkleRig {
    precompute(&two_triangle_square(0.1), &[sinusoid(0.0125, 0.0, s)], &exact_opts(1e-6)).unwrap()
}

/// T9: analytic sinusoid values (spec §3.5, §7): 10% compression across / along the crests.
#[test]
fn t9_analytic_sinusoid() {
    let rig = t9_rig(1.0);
    let across = Mat2::new(0.9, 0.0, 0.0, 1.0); // along the wave vector
    let along = Mat2::new(1.0, 0.0, 0.0, 0.9); // along the crests
    for t in 0..2 {
        let cases = [
            (LIN_ABD, across, 1.218844),
            (LIN_ABD, along, 1.318844),
            (LIN_GREEN, across, 1.207902),
            (LIN_GREEN, along, 1.302902),
            (ModulationMode::ExactWrinkledRest, across, 1.193647),
            (ModulationMode::ExactWrinkledRest, along, 1.326275),
        ];
        for (mode, f, want) in cases {
            let h = h_of(&rig, mode, &f, t);
            // 1e-5 rel: the spec's figures carry 7 digits.
            assert!(rel(h, want) < 1e-5, "{mode:?} {f:?}: {h} vs {want}");
        }
    }
}

/// W1 analytic check: ExactFlatRest amplitude h·η equals the 1-D buckled-strip amplitude
/// (spec values A/λ = 0.0707189, 0.0993299, 0.1383959, 0.1667054 at c = 0.95 … 0.7).
#[test]
fn w1_flat_rest_matches_strip() {
    let rig = t9_rig(1.0);
    let lam = 0.0125;
    for (c, want) in [(0.95, 0.0707189), (0.9, 0.0993299), (0.8, 0.1383959), (0.7, 0.1667054)] {
        let strip = strip_amplitude(c);
        assert!(rel(strip, want) < 1e-6, "strip {strip} vs spec {want}");
        for t in 0..2 {
            let h = h_of(&rig, ModulationMode::ExactFlatRest, &Mat2::new(c, 0.0, 0.0, 1.0), t);
            assert!(rel(h * rig.eta[0] / lam, strip) < 1e-5, "c {c}: {} vs {strip}", h * rig.eta[0] / lam);
        }
    }
}

/// T5: the linearisation is second order: area residual for F = I + δG, δ = 0.05·2^−j, has a
/// log-log slope of 2 ± 0.1 (δ ≤ 0.05 as in W1: at δ = 0.1 third-order terms still bend the
/// line, measured slope 1.87 over 0.1…0.00625).
#[test]
fn t5_linearisation_second_order() {
    let rig = precompute(&two_triangle_square(0.1), &[sinusoid(0.02, 30.0, 0.8)], &exact_opts(1e-7)).unwrap();
    let g = Mat2::new(-0.6, 0.3, 0.1, -0.4);
    let mut pts = Vec::new();
    for j in 0..5 {
        let d = 0.05 * 0.5f64.powi(j);
        let f = Mat2::identity() + g * d;
        let h = h_of(&rig, LIN_GREEN, &f, 0);
        let c = rig.coeff(0, 0);
        let cc = f.transpose() * f;
        let res = (wrinkled_area(&c.grad_samples, &cc, h) - c.area_wrinkled).abs() / c.area_wrinkled;
        pts.push((d.ln(), res.ln()));
    }
    let slope = geom_core::stats::linear_fit(&pts).1;
    assert!((slope - 2.0).abs() < 0.1, "slope {slope}: {pts:?}");
}

/// T6: Green and PaperAbd agree to O(δ²): |h_G − h_A|/δ² varies < 20% over δ = 0.1·2^−j.
#[test]
fn t6_green_vs_abd() {
    let rig = precompute(&two_triangle_square(0.1), &[sinusoid(0.02, 30.0, 0.8)], &exact_opts(1e-6)).unwrap();
    let g = Mat2::new(-0.6, 0.3, 0.1, -0.4);
    let ratios: Vec<f64> = (1..5)
        .map(|j| {
            let d = 0.1 * 0.5f64.powi(j);
            let f = Mat2::identity() + g * d;
            (h_of(&rig, LIN_GREEN, &f, 0) - h_of(&rig, LIN_ABD, &f, 0)).abs() / (d * d)
        })
        .collect();
    let (mn, mx) = ratios.iter().fold((f64::INFINITY, 0.0f64), |(a, b), r| (a.min(*r), b.max(*r)));
    assert!(mn > 0.0 && (mx - mn) / mx < 0.2, "{ratios:?}");
}

/// T7: exact solves: residual ≤ 1e-10 A*, ≤ 30 iterations, Newton iterates monotone.
#[test]
fn t7_exact_solver() {
    let rig = precompute(&two_triangle_square(0.1), &[sinusoid(0.02, 30.0, 0.8)], &exact_opts(1e-6)).unwrap();
    let c = rig.coeff(0, 0);
    let mut rng = Rng::new(5);
    let mut q = Vec::new();
    for _ in 0..20 {
        let f = Mat2::new(rng.range(0.5, 1.0), rng.range(-0.3, 0.3), rng.range(-0.3, 0.3), rng.range(0.5, 1.0));
        let cc = f.transpose() * f;
        for mode in [ModulationMode::ExactWrinkledRest, ModulationMode::ExactFlatRest, ModulationMode::PrincipalLength]
        {
            let (delta, a_star) = exact_terms(mode, &c.grad_samples, &cc, false, &mut q);
            let mut trace = Vec::new();
            let s = solve_exact(&c.grad_samples.w, &q, delta, a_star, 1e-12, 30, Some(&mut trace));
            assert!(s.rel_residual <= 1e-10, "{mode:?}: {}", s.rel_residual);
            assert!(s.iterations <= 30 && !s.bisected);
            assert!(trace.windows(2).all(|w| w[1] <= w[0]), "not monotone: {trace:?}");
        }
    }
}

/// T8: sign and zero behaviour.
#[test]
fn t8_sign_and_zero() {
    let rig = t9_rig(1.0);
    let flat = ModulationMode::ExactFlatRest;
    for t in 0..2 {
        for k in 0..=10 {
            let c = 1.0 + 0.05 * k as f64;
            assert_eq!(h_of(&rig, flat, &Mat2::new(c, 0.0, 0.0, 1.0), t), 0.0);
            assert_eq!(h_of(&rig, flat, &Mat2::new(1.0, 0.0, 0.0, c), t), 0.0);
        }
        assert_eq!(h_of(&rig, flat, &Mat2::new(1.2, 0.0, 0.0, 1.1), t), 0.0); // biaxial stretch
        assert_eq!(h_of(&rig, flat, &Mat2::new(1.0, 0.2, 0.0, 1.0), t), 0.0); // pure shear
        let mut prev = 0.0;
        for k in 1..=8 {
            let c = 1.0 - 0.05 * k as f64;
            let h = h_of(&rig, flat, &Mat2::new(c, 0.0, 0.0, 1.0), t);
            assert!(h > prev, "c {c}: {h} ≤ {prev}");
            prev = h;
        }
        assert!((h_of(&rig, LIN_GREEN, &Mat2::identity(), t) - 1.0).abs() < 1e-14);
        assert!(h_of(&rig, LIN_GREEN, &(Mat2::identity() * 0.95), t) > 1.0);
        assert!(h_of(&rig, LIN_GREEN, &(Mat2::identity() * 1.05), t) < 1.0);
        assert!(h_of(&rig, ModulationMode::PrincipalLength, &Mat2::new(1.0, 0.2, 0.0, 1.0), t) > 0.0);
    }
}

/// T10: rigid motion of the deformed mesh leaves every h unchanged (1e-12).
#[test]
fn t10_rigid_invariance() {
    let mesh = grid_mesh(4, 0.2);
    let pat = sinusoid(0.05, 20.0, 0.7);
    let rig = precompute(&mesh, &[pat], &PrecomputeOptions::default()).unwrap();
    let mut rng = Rng::new(9);
    let def: Vec<Pt3> =
        mesh.positions.iter().map(|p| Pt3::new(0.9 * p.x + 0.02 * p.y * p.y, p.y, 0.1 * p.x * p.y)).collect();
    let rot = Rotation3::from_axis_angle(&Unit::new_normalize(rng.unit_vec3()), 1.1);
    let tr = Vec3::new(0.3, -1.0, 2.0);
    let moved: Vec<Pt3> = def.iter().map(|p| rot * p + tr).collect();
    for mode in [
        LIN_GREEN,
        LIN_ABD,
        ModulationMode::ExactWrinkledRest,
        ModulationMode::ExactFlatRest,
        ModulationMode::PrincipalLength,
    ] {
        let mut a = WrinkleAnimator::new(rig.clone(), mod_opts(mode)).unwrap();
        let h0 = a.frame(&def).unwrap().tri_h;
        let h1 = a.frame(&moved).unwrap().tri_h;
        for (x, y) in h0.iter().zip(&h1) {
            assert!((x - y).abs() <= 1e-12 * x.abs().max(1.0), "{mode:?}: {x} vs {y}");
        }
    }
}

/// T11: two orthogonal sinusoids (s = 1), 10% compression along pattern 1's wave vector:
/// MF1 < MF2 and W1 = 1 with v = 0.03.
#[test]
fn t11_direction_preference() {
    let mesh = two_triangle_square(0.1);
    let rig = precompute(&mesh, &[sinusoid(0.0125, 0.0, 1.0), sinusoid(0.0125, 90.0, 1.0)], &exact_opts(1e-6)).unwrap();
    let mut o = mod_opts(LIN_GREEN);
    o.blend = BlendOptions { variance: 0.03, power: 4.0 };
    let mut a = WrinkleAnimator::new(rig, o).unwrap();
    let fm = a.frame(&deform(&mesh, &Mat2::new(0.9, 0.0, 0.0, 1.0))).unwrap();
    for t in 0..2 {
        assert!(fm.tri_mf_lin[2 * t] < fm.tri_mf_lin[2 * t + 1]);
        assert_eq!(fm.tri_weight[2 * t], 1.0);
        assert_eq!(fm.tri_weight[2 * t + 1], 0.0);
    }
}

/// T16: constant pattern: status ConstantPattern; h = 1 in paper modes, 0 in flat modes; no NaN.
#[test]
fn t16_constant_pattern() {
    let mesh = two_triangle_square(0.1);
    let pat =
        WrinklePattern::new(&PatternSource::Procedural(Procedural::Constant { value: 0.4 }), PatternOptions::default())
            .unwrap();
    let rig = precompute(&mesh, &[pat], &PrecomputeOptions::default()).unwrap();
    assert!(rig.coeffs.iter().all(|c| c.status == CoeffStatus::ConstantPattern));
    let f = Mat2::new(0.8, 0.1, 0.0, 0.9);
    for (mode, want) in [
        (LIN_GREEN, 1.0),
        (ModulationMode::ExactWrinkledRest, 1.0),
        (ModulationMode::ExactFlatRest, 0.0),
        (ModulationMode::PrincipalLength, 0.0),
    ] {
        let mut a = WrinkleAnimator::new(rig.clone(), ModulationOptions { mode, ..Default::default() }).unwrap();
        let def = deform(&mesh, &f);
        let fm = a.frame(&def).unwrap();
        assert!(fm.tri_h.iter().all(|h| *h == want), "{mode:?}");
        let dm = a.displaced_mesh(&def, &fm, 3).unwrap();
        assert!(dm.positions.iter().all(|p| p.coords.iter().all(|c| c.is_finite())));
        assert!(fm.vertex_mod.iter().chain(&fm.vertex_weight).all(|v| v.is_finite()));
    }
}

/// T21: gradient-bin compression K = 72 vs K = 0 changes exact-mode h by ≤ 1e-3 relative.
#[test]
fn t21_gradient_bins() {
    let mesh = two_triangle_square(0.1);
    let pats = [sinusoid(0.02, 30.0, 1.0)];
    let full = precompute(&mesh, &pats, &exact_opts(1e-5)).unwrap();
    let binned = precompute(
        &mesh,
        &pats,
        &PrecomputeOptions { tolerance: 1e-5, max_depth: 8, gradient_bins: 72, gradient_samples: true },
    )
    .unwrap();
    assert!(binned.coeff(0, 0).grad_samples.g.len() <= 72);
    for f in [Mat2::new(0.9, 0.0, 0.0, 1.0), Mat2::new(0.85, 0.1, -0.05, 0.95), Mat2::new(1.0, 0.0, 0.0, 0.8)] {
        for mode in [ModulationMode::ExactWrinkledRest, ModulationMode::ExactFlatRest, ModulationMode::PrincipalLength]
        {
            let (a, b) = (h_of(&full, mode, &f, 0), h_of(&binned, mode, &f, 0));
            assert!(rel(b, a) < 1e-3, "{mode:?} {f:?}: {b} vs {a}");
        }
    }
}

/// T22: per-triangle wrinkled area from the stored samples vs an independent uniform-subdivision
/// rule on the rendered surface (1e-5 rel).
#[test]
fn t22_area_report() {
    let mesh = two_triangle_square(0.1);
    let rig = precompute(&mesh, &[sinusoid(0.025, 30.0, 0.8)], &exact_opts(1e-7)).unwrap();
    let mut a = WrinkleAnimator::new(rig, mod_opts(ModulationMode::ExactFlatRest)).unwrap();
    let def = deform(&mesh, &Mat2::new(0.85, 0.05, 0.0, 0.97));
    let fm = a.frame(&def).unwrap();
    let s = a.area_report(&def, &fm, AreaCheck::PerTriangle).unwrap();
    let u = a.area_report(&def, &fm, AreaCheck::Rendered { level: 5 }).unwrap();
    assert!(s.max_rel < 1e-10, "solver residual {}", s.max_rel);
    for t in 0..2 {
        assert!(rel(s.area[t], u.area[t]) < 1e-5, "{} vs {}", s.area[t], u.area[t]);
    }
}

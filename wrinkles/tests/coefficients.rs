//! Coefficient tests: T1 (affine closed forms), T2 (finite differences), T3 (quadrature
//! convergence), T4 (invariant), T20 (UV chain rule).

mod common;

use common::*;
use geom_core::math::{Mat2, Pt2, Pt3, Vec2};
use geom_core::mesh::Uv;
use geom_core::rng::Rng;
use wrinkles::quadrature::uniform;
use wrinkles::*;

fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs().max(1e-300)
}

/// T1: constant g on a random triangle: C1 = A(1+g_y²)/W, C2 = −A g_x g_y/W, C3 = A(1+g_x²)/W,
/// C4 = A|g|²/W, A^w = A·W (1e-12 rel: the rule integrates constants exactly; round-off only).
#[test]
fn t1_affine_pattern_closed_forms() {
    let mut rng = Rng::new(11);
    for _ in 0..5 {
        let p: Vec<Pt3> =
            (0..3).map(|_| Pt3::new(rng.range(-1.0, 1.0), rng.range(-1.0, 1.0), rng.range(-1.0, 1.0))).collect();
        let uv = Uv::PerVertex((0..3).map(|_| Pt2::new(rng.range(0.0, 1.0), rng.range(0.0, 1.0))).collect());
        let mesh = RestMesh::new(p, vec![[0, 1, 2]], uv).unwrap();
        let pat = WrinklePattern::new(
            &PatternSource::Procedural(Procedural::Ramp { gradient: [rng.range(-2.0, 2.0), rng.range(-2.0, 2.0)] }),
            PatternOptions { normalization: Normalization::Metres(rng.range(0.2, 1.0)), ..Default::default() },
        )
        .unwrap();
        let rig = precompute(&mesh, std::slice::from_ref(&pat), &PrecomputeOptions::default()).unwrap();
        let c = rig.coeff(0, 0);
        let rf = &rig.frames[0];
        let g = rf.j.transpose() * pat.grad_uv(&Pt2::origin()) * rig.eta[0];
        let w = (1.0 + g.norm_squared()).sqrt();
        let a = rf.area;
        assert_eq!(c.status, CoeffStatus::Ok);
        assert!(rel(c.k[(0, 0)], a * (1.0 + g.y * g.y) / w) < 1e-12);
        assert!(rel(c.k[(0, 1)], -a * g.x * g.y / w) < 1e-12);
        assert!(rel(c.k[(1, 1)], a * (1.0 + g.x * g.x) / w) < 1e-12);
        assert!(rel(c.c4, a * g.norm_squared() / w) < 1e-12);
        assert!(rel(c.area_wrinkled, a * w) < 1e-12);
        // C4 split by barycentric weight: each third (∫λ_k = A/3).
        for k in 0..3 {
            assert!(rel(c.c4_vertex[k], c.c4 / 3.0) < 1e-12);
        }
    }
}

/// Exact wrinkled area A(a, b, d, h) from a triangle's (unbinned) samples, C = [[a², ab], [ab, b²+d²]].
fn area_abdh(gs: &GradientSamples, a: f64, b: f64, d: f64, h: f64) -> f64 {
    let c = Mat2::new(a * a, a * b, a * b, b * b + d * d);
    wrinkles::modulation::wrinkled_area(gs, &c, h)
}

fn two_sine_rig() -> WrinkleRig {
    // Two sinusoids summed through an image-free route: a Folds pattern with 2 components and no
    // irregularity is a smooth sum of two sinusoids.
    let mesh = two_triangle_square(0.1);
    let pat = WrinklePattern::new(
        &PatternSource::Procedural(Procedural::Folds {
            wavelength_uv: 0.03,
            angle_deg: 20.0,
            spread_deg: 30.0,
            count: 2,
            irregularity: 0.0,
            seed: 3,
        }),
        PatternOptions { normalization: Normalization::TargetRestSlope(0.8), ..Default::default() },
    )
    .unwrap();
    precompute(&mesh, &[pat], &exact_opts(1e-6)).unwrap()
}

/// T2: C1..C4 are the partial derivatives of the exact A_t(a, b, d, h) at (1, 0, 1, 1) (central
/// differences, step 1e-6: truncation ~1e-12·A''' and round-off ~1e-16·A/1e-6 ≪ 1e-6 rel);
/// ⟨K, ·⟩ is the derivative with respect to the Green strain.
#[test]
fn t2_coefficients_are_area_derivatives() {
    let rig = two_sine_rig();
    let e = 1e-6;
    for t in 0..2 {
        let c = rig.coeff(t, 0);
        let gs = &c.grad_samples;
        let fd = |f: &dyn Fn(f64) -> f64| (f(e) - f(-e)) / (2.0 * e);
        let d1 = fd(&|s| area_abdh(gs, 1.0 + s, 0.0, 1.0, 1.0));
        let d2 = fd(&|s| area_abdh(gs, 1.0, s, 1.0, 1.0));
        let d3 = fd(&|s| area_abdh(gs, 1.0, 0.0, 1.0 + s, 1.0));
        let d4 = fd(&|s| area_abdh(gs, 1.0, 0.0, 1.0, 1.0 + s));
        assert!(rel(d1, c.k[(0, 0)]) < 1e-6, "C1 {d1} {}", c.k[(0, 0)]);
        assert!((d2 - c.k[(0, 1)]).abs() < 1e-6 * c.k[(0, 0)], "C2 {d2} {}", c.k[(0, 1)]);
        assert!(rel(d3, c.k[(1, 1)]) < 1e-6);
        assert!(rel(d4, c.c4) < 1e-6);
        // Green strain: A(I + 2E) with E = ε·sym(e_i e_jᵀ): dA/dE11 = K11, dA/dE12 (both) = 2K12.
        let area_c = |c: Mat2| wrinkles::modulation::wrinkled_area(gs, &c, 1.0);
        let g11 = (area_c(Mat2::new(1.0 + 2.0 * e, 0.0, 0.0, 1.0)) - area_c(Mat2::new(1.0 - 2.0 * e, 0.0, 0.0, 1.0)))
            / (2.0 * e);
        let g12 = (area_c(Mat2::new(1.0, 2.0 * e, 2.0 * e, 1.0)) - area_c(Mat2::new(1.0, -2.0 * e, -2.0 * e, 1.0)))
            / (2.0 * e);
        let g22 = (area_c(Mat2::new(1.0, 0.0, 0.0, 1.0 + 2.0 * e)) - area_c(Mat2::new(1.0, 0.0, 0.0, 1.0 - 2.0 * e)))
            / (2.0 * e);
        assert!(rel(g11, c.k[(0, 0)]) < 1e-6);
        assert!((g12 - 2.0 * c.k[(0, 1)]).abs() < 1e-6 * c.k[(0, 0)]);
        assert!(rel(g22, c.k[(1, 1)]) < 1e-6);
    }
}

/// T3: adaptive results at τ = 1e-3 … 1e-6 against a reference (degree-5 rule on a level-6
/// uniform subdivision, error ~4^-18 relative): actual error ≤ 3τ·A_T, estimate ≥ 0.1 × actual.
#[test]
fn t3_quadrature_convergence() {
    let mesh = two_triangle_square(0.1);
    let pat = sinusoid(0.1 / 3.3, 25.0, 1.0);
    let rig0 = precompute(&mesh, std::slice::from_ref(&pat), &exact_opts(1e-6)).unwrap();
    let rf = &rig0.frames[0];
    let eta = rig0.eta[0];
    let mut f = |b: [f64; 3], o: &mut [f64]| {
        let uv = Pt2::from(mesh.uv(0, 0).coords * b[0] + mesh.uv(0, 1).coords * b[1] + mesh.uv(0, 2).coords * b[2]);
        let g: Vec2 = rf.j.transpose() * pat.grad_uv(&uv) * eta;
        let w = (1.0 + g.norm_squared()).sqrt();
        o[0] = (1.0 + g.y * g.y) / w;
        o[1] = -g.x * g.y / w;
        o[2] = (1.0 + g.x * g.x) / w;
        o[3] = g.norm_squared() / w;
        o[4] = w;
    };
    let r = uniform(rf.area, 5, &mut f, 6);
    for tau in [1e-3, 1e-4, 1e-5, 1e-6] {
        let rig = precompute(
            &mesh,
            std::slice::from_ref(&pat),
            &PrecomputeOptions { tolerance: tau, max_depth: 9, gradient_bins: 0, gradient_samples: true },
        )
        .unwrap();
        let c = rig.coeff(0, 0);
        let got = [c.k[(0, 0)], c.k[(0, 1)], c.k[(1, 1)], c.c4, c.area_wrinkled];
        let actual = got.iter().zip(&r).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
        assert!(actual <= 3.0 * tau * rf.area, "τ {tau}: error {actual:e} vs {:e}", 3.0 * tau * rf.area);
        assert!(c.quad_error >= 0.1 * actual, "τ {tau}: estimate {:e} < 0.1·{actual:e}", c.quad_error);
        assert_eq!(c.status, CoeffStatus::Ok);
    }
}

/// T4: C1 + C3 − C4 = 2∫1/W (1e-10 rel; an identity of the integrands, so only round-off).
#[test]
fn t4_invariant() {
    let rig = two_sine_rig();
    for t in 0..2 {
        let c = rig.coeff(t, 0);
        assert!(rel(c.k[(0, 0)] + c.k[(1, 1)] - c.c4, 2.0 * c.inv_w) < 1e-10);
    }
}

/// T20: a sinusoid in a scaled/rotated UV chart equals the same function written directly in
/// local coordinates (1e-10 rel).
#[test]
fn t20_uv_chain_rule() {
    let l = 0.1;
    let p = vec![Pt3::new(0.0, 0.0, 0.0), Pt3::new(l, 0.0, 0.0), Pt3::new(0.3 * l, 0.8 * l, 0.0)];
    let (s, th) = (2.5, 35f64.to_radians());
    let m = Mat2::new(th.cos(), -th.sin(), th.sin(), th.cos()) * s;
    let uv_a = Uv::PerVertex(p.iter().map(|q| Pt2::from(m * Vec2::new(q.x, q.y))).collect());
    let uv_b = Uv::PerVertex(p.iter().map(|q| Pt2::new(q.x, q.y)).collect());
    let k = Vec2::new(std::f64::consts::TAU / 0.04, 0.0); // wave vector in chart A (angle 0, λ 0.04)
    let kb = m.transpose() * k; // the same function in local (x, y)
    let mk = |lam: f64, ang: f64| {
        WrinklePattern::new(
            &PatternSource::Procedural(Procedural::Sinusoid { wavelength_uv: lam, angle_deg: ang, phase: 0.4 }),
            PatternOptions { normalization: Normalization::Metres(0.004), ..Default::default() },
        )
        .unwrap()
    };
    let pa = mk(0.04, 0.0);
    let pb = mk(std::f64::consts::TAU / kb.norm(), kb.y.atan2(kb.x).to_degrees());
    let o = exact_opts(1e-7);
    let ra = precompute(&RestMesh::new(p.clone(), vec![[0, 1, 2]], uv_a).unwrap(), &[pa], &o).unwrap();
    let rb = precompute(&RestMesh::new(p, vec![[0, 1, 2]], uv_b).unwrap(), &[pb], &o).unwrap();
    let (a, b) = (ra.coeff(0, 0), rb.coeff(0, 0));
    assert!(rel(a.k[(0, 0)], b.k[(0, 0)]) < 1e-10);
    assert!((a.k[(0, 1)] - b.k[(0, 1)]).abs() < 1e-10 * a.k[(0, 0)]);
    assert!(rel(a.k[(1, 1)], b.k[(1, 1)]) < 1e-10);
    assert!(rel(a.c4, b.c4) < 1e-10);
    assert!(rel(a.area_wrinkled, b.area_wrinkled) < 1e-10);
}

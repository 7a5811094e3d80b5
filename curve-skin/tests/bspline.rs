//! The `QuadraticBSpline` curve shape (spec §3.4.2 option): C¹ continuity with the bones, end
//! interpolation, orthonormal rotation-minimising frames, rigid invariance, bind pose, and its
//! floating Bone_CP rule (fold-free where the cap allows).

mod common;

use common::*;
use curve_skin::curve::{
    build_curve_skeleton, CentreMode, CurveFrame, CurveShape, JointCurveDefaults, QuadBSpline, TopologyRules,
};
use curve_skin::metrics::fold_fraction;
use curve_skin::{CurveOptions, CurveSkin, DeformOutput, Skinner};
use geom_core::math::{Iso3, Pt3, UnitQuat, Vec3};
use geom_core::rng::Rng;

fn bspline_skin(a: &Arm, centre: CentreMode, opts: CurveOptions) -> CurveSkin {
    let d = JointCurveDefaults { shape: CurveShape::QuadraticBSpline, centre, ..Default::default() };
    let cs = build_curve_skeleton(&a.sk, &TopologyRules::default(), &d);
    CurveSkin::new(&a.sk, cs, &a.mesh.positions, None, opts).unwrap()
}

fn frame(cur: &CurveSkin, a: &Arm, bend: f64, twist: f64) -> CurveFrame {
    posed_curve(cur, 0, &arm_pose(&a.sk, bend, twist).0)
}

#[test]
fn bspline_interpolates_ends_and_is_c1() {
    let a = arm(10, 8);
    let cur = bspline_skin(&a, CentreMode::OnSkeleton, CurveOptions::default());
    for bend in [0.0, 20.0, 90.0, 140.0, 179.0] {
        let f = frame(&cur, &a, bend, 0.0);
        let fd_checks = bend < 170.0; // at 179° κ_max·L ≈ 1.3e4: finite differences are meaningless
        let q = f.quad.expect("B-spline shape");
        let total = f.curve_length();
        let first = f.l_in - f.l_cp;
        let mid = f.l_cp * q.total();
        assert!((total - (f.l_in + f.l_out - 2.0 * f.l_cp + mid)).abs() < 1e-12);
        // End interpolation: domain ends and the Bone_CPs P₀, P₂ (1e-12).
        let (p_start, psi0) = f.curve_point(0.0);
        let (p_end, psi1) = f.curve_point(total);
        assert!((p_start - (f.j + f.u_in * f.l_in)).norm() < 1e-12, "{bend}");
        assert!((p_end - (f.j + f.u_out * f.l_out)).norm() < 1e-12, "{bend}");
        assert!(psi0.abs() < 1e-15 && (psi1 - f.beta).abs() < 1e-15);
        assert!((f.curve_point(first).0 - (f.j + f.u_in * f.l_cp)).norm() < 1e-12, "{bend}: P0");
        assert!((f.curve_point(first + mid).0 - (f.j + f.u_out * f.l_cp)).norm() < 1e-12, "{bend}: P2");
        // Arc-length parametrisation: unit speed everywhere (central differences, h = 1e-6,
        // error O(h²κ²) + rounding 1e-10/h).
        let h = 1e-6;
        let n = 400;
        let mut prev_t: Option<Vec3> = None;
        let kmax = q.max_curvature_l() / f.l_cp;
        let du = total / n as f64;
        for i in (1..n).filter(|_| fd_checks) {
            let u = i as f64 * du;
            let d = (f.curve_point(u + h).0 - f.curve_point(u - h).0) / (2.0 * h);
            assert!((d.norm() - 1.0).abs() < 1e-6, "{bend}: speed {} at {u}", d.norm());
            // The swing angle is the tangent's angle from t₁ in the bend plane.
            let t1 = -f.u_in;
            let n_pl = f.b.cross(&t1);
            let psi = f.curve_point(u).1;
            let ang = d.dot(&n_pl).atan2(d.dot(&t1));
            assert!((ang - psi).abs() < 1e-6, "{bend}: ψ {psi} vs tangent angle {ang} at {u}");
            // C¹: the unit tangent turns at most κ_max per unit length — no jump anywhere,
            // including the junctions with the straight bone parts.
            let t = d.normalize();
            if let Some(p) = prev_t {
                let turn = (t - p).norm();
                assert!(turn <= kmax * du * 1.01 + 1e-6, "{bend}: tangent jump {turn} at {u}");
            }
            prev_t = Some(t);
        }
        // One-sided tangents at the junctions equal the bone directions (C¹ with the bones).
        let hh = 1e-7;
        let d0 = (f.curve_point(first + hh).0 - f.curve_point(first).0) / hh;
        let d1 = (f.curve_point(first + mid).0 - f.curve_point(first + mid - hh).0) / hh;
        assert!((d0 + f.u_in).norm() < 1e-5 && (d1 - f.u_out).norm() < 1e-5, "{bend}");
    }
}

fn rot_of(q: &UnitQuat) -> nalgebra::Matrix3<f64> {
    *q.to_rotation_matrix().matrix()
}

#[test]
fn bspline_frames_are_orthonormal_and_rotation_minimising() {
    // Centre on the curve: the frame's x axis is the curve tangent; without twist the frame
    // rotates only about the binormal (angular velocity ⟂ tangent: rotation-minimising).
    let a = arm(10, 8);
    let cur = bspline_skin(&a, CentreMode::OnCurve, CurveOptions::default());
    for (bend, twist) in [(30.0, 0.0), (100.0, 0.0), (100.0, 75.0)] {
        let f = frame(&cur, &a, bend, twist);
        let tw = &cur.skeleton.curves[0].twist;
        let h = 1e-6;
        for i in 1..200 {
            let s = i as f64 / 200.0;
            let (_, r, _) = f.eval(s, tw);
            let m = rot_of(&r);
            assert!((m.transpose() * m - nalgebra::Matrix3::identity()).norm() < 1e-12);
            assert!((m.determinant() - 1.0).abs() < 1e-12);
            let (cp, rp, _) = f.eval(s + h, tw);
            let (cm, rm, _) = f.eval(s - h, tw);
            let tangent = (cp - cm).normalize();
            assert!((m.column(0) - tangent).norm() < 1e-6, "{bend}/{twist}: x axis vs tangent at σ = {s}");
            // Angular velocity ω from R(σ+h)R(σ−h)ᵀ (axis·angle / 2h).
            let w = (rp * rm.inverse()).scaled_axis() / (2.0 * h);
            let twist_rate = w.dot(&tangent);
            if twist == 0.0 {
                assert!(twist_rate.abs() < 1e-6, "{bend}: twist rate {twist_rate} at σ = {s}");
            } else {
                // The only rotation about the tangent is the authored twist distribution's.
                let d = (tw.eval(s + h) - tw.eval(s - h)) / (2.0 * h);
                assert!((twist_rate - f.theta * d).abs() < 1e-5, "{twist}: {twist_rate} vs {}", f.theta * d);
            }
        }
    }
}

#[test]
fn bspline_rigid_invariance_and_bind_pose() {
    // Issue "Must hold" for the option: f64 1e-9, f32 1e-5; bind pose 1e-12 (f64), 1e-6 (f32).
    let a = arm(100, 32);
    let mut cur = bspline_skin(&a, CentreMode::OnSkeleton, CurveOptions::default());
    let rest = &a.mesh.positions;
    let mut o = vec![Pt3::origin(); rest.len()];
    cur.deform_f64(&mut o);
    assert!(max_diff(&o, rest) < 1e-12);
    let (posed, _) = arm_pose(&a.sk, 70.0, 40.0);
    let g = Iso3::new(Vec3::new(0.7, -1.3, 2.1), Vec3::new(0.4, 1.1, -0.6));
    let moved: Vec<Iso3> = posed.iter().map(|p| g * p).collect();
    let run = |cur: &mut CurveSkin, frames: &[Iso3]| {
        cur.prepare(&a.sk, frames).unwrap();
        let mut o = vec![Pt3::origin(); rest.len()];
        cur.deform_f64(&mut o);
        let mut o32 = vec![[0f32; 3]; rest.len()];
        cur.deform(DeformOutput { positions: &mut o32, normals: None });
        (o, to_f64(&o32))
    };
    let (a64, a32) = run(&mut cur, &posed);
    let (b64, b32) = run(&mut cur, &moved);
    let apply = |p: &[Pt3]| p.iter().map(|x| g * x).collect::<Vec<_>>();
    let e = max_diff(&b64, &apply(&a64));
    assert!(e < 1e-9, "f64 {e}");
    let e = max_diff(&b32, &apply(&a32));
    assert!(e < 1e-5, "f32 {e}");
    // The f32 table path stays within the §7.5 i bound of the exact path (≤ 2e-3 R combined).
    let e = max_diff(&a32, &a64) / R;
    assert!(e < 2e-3, "table error {e} R");
}

#[test]
fn bspline_floating_rule_formula_no_bulge_and_fold_free() {
    // L = safety·d·g(β) before clamping; centre on skeleton ⇒ max dist/R ≤ 1 + 1e-9 (the
    // theorem of §7.4 b does not depend on the shape); fold fraction 0 where the cap is not hit
    // (β ≤ 90° on the reference arm: g(90°) = 1.62 ⇒ L = 0.27 < cap 0.5), cap reported at 135°.
    let a = arm(40, 16);
    let mut cur = bspline_skin(&a, CentreMode::OnSkeleton, CurveOptions::default());
    let mut rng = Rng::new(5);
    let samples: Vec<Pt3> = (0..20_000)
        .map(|_| {
            let r = 0.98 * R * rng.f64().sqrt();
            let phi = rng.range(0.0, std::f64::consts::TAU);
            Pt3::new(rng.range(-0.95, 0.95), r * phi.cos(), r * phi.sin())
        })
        .collect();
    for bend in [10.0f64, 45.0, 90.0] {
        let (posed, _) = arm_pose(&a.sk, bend, 0.0);
        cur.prepare(&a.sk, &posed).unwrap();
        let g = QuadBSpline::new(bend.to_radians()).fold_factor_skeleton();
        let expect = (1.1 * R * g).clamp(0.02, 0.5);
        assert!((cur.frames()[0].l_cp - expect).abs() < 1e-12, "{bend}");
        // Larger than the circular arc's L (curvature concentrates at the middle).
        let b = bend.to_radians();
        assert!(g > b / (2.0 * (b / 2.0).cos()));
        assert_eq!(cur.diagnostics().cap_hits, 0);
        assert_eq!(fold_fraction(&|x| cur.map_point(&x), &samples, 1e-5), 0.0, "{bend}");
        let mut o = vec![Pt3::origin(); a.mesh.positions.len()];
        cur.deform_f64(&mut o);
        let (_, hi) = curve_skin::metrics::distance_to_bones(&side_only(&o, &a.side), &bones(&posed));
        assert!(hi / R <= 1.0 + 1e-9, "{bend}: {}", hi / R);
    }
    let (posed, _) = arm_pose(&a.sk, 135.0, 0.0);
    cur.prepare(&a.sk, &posed).unwrap();
    assert!(cur.diagnostics().cap_hits > 0);
}

#[test]
fn bspline_degenerate_bends_stay_finite() {
    // Spec §8 for the option: straight limb (β = 0: frames are the bone frames, curve straight)
    // and a fully folded joint (β = 180°: cap reported, output finite, no NaN).
    let a = arm(40, 16);
    let mut cur = bspline_skin(&a, CentreMode::OnSkeleton, CurveOptions::default());
    let f = frame(&cur, &a, 0.0, 0.0);
    let tw = &cur.skeleton.curves[0].twist;
    for i in 0..=10 {
        let (_, r, _) = f.eval(i as f64 / 10.0, tw);
        assert!(qdist(&r, &f.f_in) < 1e-15, "σ = {i}/10");
    }
    for bend in [179.999, 180.0] {
        let (posed, _) = arm_pose(&a.sk, bend, 0.0);
        cur.prepare(&a.sk, &posed).unwrap();
        assert!(cur.diagnostics().cap_hits > 0, "{bend}");
        let mut o = vec![Pt3::origin(); a.mesh.positions.len()];
        cur.deform_f64(&mut o);
        assert!(o.iter().all(|p| p.coords.iter().all(|c| c.is_finite())), "{bend}");
        let mut o32 = vec![[0f32; 3]; o.len()];
        cur.deform(DeformOutput { positions: &mut o32, normals: None });
        assert!(o32.iter().all(|p| p.iter().all(|c| c.is_finite())), "{bend}");
    }
}

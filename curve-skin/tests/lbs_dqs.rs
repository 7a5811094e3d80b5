//! Spec §7.2 (LBS) and §7.3 (DQS) on the cylinder arm.

mod common;

use common::*;
use curve_skin::dqs::dqs_f64;
use curve_skin::lbs::lbs_f64;
use curve_skin::metrics::{joint_radius_ratio, ring_radius_ratio, signed_volume};
use curve_skin::{skinning_transforms, Antipodal, Dqs, SkinError};
use geom_core::math::{Iso3, Mat34, Pt3, Vec3};

fn lbs_at(a: &Arm, h: f64, bend: f64, twist: f64) -> Vec<Pt3> {
    let w = ramp4(&a.mesh, h);
    let (posed, _) = arm_pose(&a.sk, bend, twist);
    lbs_f64(&a.mesh.positions, &w, &skinning_transforms(&a.sk, &posed))
}

#[test]
fn lbs_bend_collapses_to_cos_half_angle() {
    // 7.2 a (reference mesh; joint ring at x = ±0.0025).
    let a = reference_arm();
    for beta in [45.0f64, 90.0, 135.0] {
        let out = lbs_at(&a, R, beta, 0.0);
        let (posed, _) = arm_pose(&a.sk, beta, 0.0);
        let j = Pt3::from(posed[1].translation.vector);
        let r = joint_radius_ratio(&out, &a.mesh.positions, j, Pt3::origin(), R, 0.003);
        let expect = (beta.to_radians() / 2.0).cos();
        assert!((r - expect).abs() < 0.01, "β={beta}: {r} vs {expect}");
    }
}

#[test]
fn lbs_twist_ring_radius_follows_rho() {
    // 7.2 b: ring of weight w keeps ρ(w) = sqrt(1 − 2w(1−w)(1 − cos θ)) of its radius (± 1e-5).
    let a = arm(400, 96);
    let w = ramp4(&a.mesh, R);
    for theta in [90.0f64, 180.0] {
        let out = lbs_at(&a, R, 0.0, theta);
        for &ring in &[150usize, 190, 199, 205, 240] {
            let x = -1.0 + 2.0 * ring as f64 / 399.0;
            let v = ring * 96;
            let wv = if w.bone[v][0] == 1 { w.w[v][0] } else { w.w[v][1] } as f64;
            let rho = (1.0 - 2.0 * wv * (1.0 - wv) * (1.0 - theta.to_radians().cos())).sqrt();
            let r = ring_radius_ratio(&out, &a.mesh.positions, Pt3::origin(), Vec3::x(), x - 1e-6, x + 1e-6, R);
            // The ring polygon's vertices all sit at the same radius, so this is exact up to f32 weights.
            assert!((r - rho).abs() < 1e-5, "θ={theta} ring {ring}: {r} vs {rho}");
        }
    }
    // Nearest ring to the joint at 180°: ρ(0.4875) ≈ 0.025, far from |cos 90°| = 0.
    let out = lbs_at(&a, R, 0.0, 180.0);
    let r = ring_radius_ratio(&out, &a.mesh.positions, Pt3::origin(), Vec3::x(), -0.003, 0.003, R);
    assert!((r - 0.025).abs() < 2e-3, "{r}");
}

fn candy_volume_ratio(rings: usize, segments: usize, h: f64) -> f64 {
    let a = arm(rings, segments);
    let out = lbs_at(&a, h, 0.0, 180.0);
    signed_volume(&out, &a.mesh.tris) / signed_volume(&a.mesh.positions, &a.mesh.tris)
}

#[test]
fn lbs_candy_wrapper_closed_form_and_second_order_convergence() {
    // 7.2 c: V/V₀ = 1 − (2h/ℓ)(1 − cos θ)·2·I_w, I_w = 9/70 (smoothstep), ℓ = 2, θ = 180°.
    let closed = |h: f64| 1.0 - (2.0 * h / 2.0) * 2.0 * 2.0 * 9.0 / 70.0;
    let e1 = (candy_volume_ratio(400, 96, R) - closed(R)).abs();
    assert!(e1 < 2e-3, "h=R error {e1}");
    let e2 = (candy_volume_ratio(400, 96, 2.0 * R) - closed(2.0 * R)).abs();
    assert!(e2 < 2e-3, "h=2R error {e2}");
    // Doubling rings and segments divides the error by ≈ 4.
    let e_fine = (candy_volume_ratio(800, 192, R) - closed(R)).abs();
    let ratio = e1 / e_fine;
    assert!(ratio > 3.0 && ratio < 5.5, "convergence ratio {ratio} ({e1} → {e_fine})");
}

#[test]
fn dqs_antipodality_350_equals_minus_10() {
    // 7.3 b.
    let a = arm(60, 24);
    let w = ramp4(&a.mesh, 2.0 * R);
    // Both rules: the hierarchy rule also flips the 350° bone into its parent's hemisphere.
    for ap in [Antipodal::PerVertexPivot, Antipodal::Hierarchy] {
        let run = |deg: f64| {
            let (posed, _) = arm_pose(&a.sk, deg, 0.0);
            dqs_f64(&a.mesh.positions, &w, &skinning_transforms(&a.sk, &posed), &a.sk.parent, ap)
        };
        let e = max_diff(&run(350.0), &run(-10.0));
        assert!(e < 1e-9, "{e}");
    }
}

#[test]
fn dqs_two_bones_about_one_joint_keep_distances_to_it() {
    // 7.3 c: both bones rotate about the elbow ⇒ every vertex keeps its distance to the elbow.
    let a = arm(100, 32);
    let w = ramp4(&a.mesh, 2.0 * R);
    let about = |axis: Vec3, deg: f64| {
        let r = geom_core::math::UnitQuat::from_axis_angle(&nalgebra::Unit::new_normalize(axis), deg.to_radians());
        Iso3::from_parts(nalgebra::Translation3::identity(), r)
    };
    let t = vec![about(Vec3::new(0.0, 0.3, 1.0), 30.0), about(Vec3::new(0.2, 1.0, 0.4), -100.0), Iso3::identity()];
    for ap in [Antipodal::PerVertexPivot, Antipodal::Hierarchy] {
        let out = dqs_f64(&a.mesh.positions, &w, &t, &a.sk.parent, ap);
        for (o, r) in out.iter().zip(&a.mesh.positions) {
            assert!((o.coords.norm() - r.coords.norm()).abs() < 1e-9);
        }
    }
}

#[test]
fn dqs_pure_twist_keeps_volume_and_rings() {
    // 7.3 d.
    let a = reference_arm();
    let w = ramp4(&a.mesh, R);
    for theta in [90.0, 180.0] {
        let (posed, _) = arm_pose(&a.sk, 0.0, theta);
        let out = dqs_f64(
            &a.mesh.positions,
            &w,
            &skinning_transforms(&a.sk, &posed),
            &a.sk.parent,
            Antipodal::PerVertexPivot,
        );
        let v = signed_volume(&out, &a.mesh.tris) / signed_volume(&a.mesh.positions, &a.mesh.tris);
        assert!((v - 1.0).abs() < 1e-3, "{v}");
        let r = ring_radius_ratio(&out, &a.mesh.positions, Pt3::origin(), Vec3::x(), -1.0, 1.0, R);
        assert!((r - 1.0).abs() < 1e-9, "{r}");
    }
}

#[test]
fn dqs_hierarchy_matches_pivot_below_180() {
    // 7.3 e.
    let a = arm(60, 24);
    let w = ramp4(&a.mesh, 2.0 * R);
    for (b, t) in [(30.0, 20.0), (120.0, -150.0), (170.0, 0.0)] {
        let (posed, _) = arm_pose(&a.sk, b, t);
        let tr = skinning_transforms(&a.sk, &posed);
        let p = dqs_f64(&a.mesh.positions, &w, &tr, &a.sk.parent, Antipodal::PerVertexPivot);
        let h = dqs_f64(&a.mesh.positions, &w, &tr, &a.sk.parent, Antipodal::Hierarchy);
        assert!(max_diff(&p, &h) < 1e-12);
    }
}

#[test]
fn dqs_refuses_non_rigid_unless_allowed() {
    // 7.3 f.
    let a = arm(20, 8);
    let w = ramp4(&a.mesh, R);
    let mut d = Dqs::new(a.mesh.positions_f32(), None, w).unwrap();
    let mut s = Mat34::identity();
    s[(0, 0)] = 1.5;
    let ident = Mat34::identity();
    let r = d.set_affine(&[ident, s, ident], &a.sk.parent);
    assert!(matches!(r, Err(SkinError::NonRigidForDqs { bone: 1, .. })), "{r:?}");
    d.allow_scale = true;
    d.set_affine(&[ident, s, ident], &a.sk.parent).unwrap();
    let mut out = vec![[0f32; 3]; d_len(&d)];
    use curve_skin::Skinner;
    d.deform(curve_skin::DeformOutput { positions: &mut out, normals: None });
    // Vertices fully on bone 1 (x > h) are stretched along x by 1.5.
    let v = a.mesh.positions.iter().position(|p| p.x > 0.9).unwrap();
    assert!((out[v][0] as f64 - 1.5 * a.mesh.positions[v].x).abs() < 1e-5);
}

fn d_len<const K: usize>(d: &Dqs<K>) -> usize {
    use curve_skin::Skinner;
    d.len()
}

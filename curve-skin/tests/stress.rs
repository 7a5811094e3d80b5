//! Spec §8: hard cases that must stay numerically stable.

mod common;

use common::*;
use curve_skin::curve::{
    build_curve_skeleton, CurveFrame, FrameHistory, JointCurveDefaults, TopologyRules, TwistChoice, VolumeComp,
};
use curve_skin::metrics::ring_radius_ratio;
use curve_skin::poses::{axis_deg, SkinPose};
use curve_skin::{CurveOptions, CurveSkin, DeformOutput, Lbs, PackedWeights, SkinError, SkinSkeleton, Skinner};
use geom_core::math::{Iso3, Pt3, Vec3};

fn finite(p: &[Pt3]) -> bool {
    p.iter().all(|x| x.coords.iter().all(|c| c.is_finite()))
}

#[test]
fn collinear_bones_give_straight_curve_with_bone_frames() {
    let a = arm(20, 8);
    let cur = curve_skin(&a, CurveOptions::default());
    let (posed, _) = arm_pose(&a.sk, 0.0, 0.0);
    let c = &cur.skeleton.curves[0];
    let (f, _) =
        CurveFrame::new(c, &cur.rigs()[0], &posed, &FrameHistory::default(), TwistChoice::Principal, VolumeComp::Off);
    assert_eq!(f.beta, 0.0);
    for k in 0..=10 {
        let (centre, rot, _) = f.eval(k as f64 / 10.0, &c.twist);
        assert!(qdist(&rot, &posed[0].rotation) < 1e-14);
        assert!(centre.y.abs() < 1e-15 && centre.z.abs() < 1e-15);
    }
}

#[test]
fn fully_folded_joint_is_finite_and_reported() {
    let a = arm(40, 16);
    let mut cur = curve_skin(&a, CurveOptions::default());
    for bend in [179.0, 179.999, 180.0] {
        let (posed, _) = arm_pose(&a.sk, bend, 0.0);
        cur.prepare(&a.sk, &posed).unwrap();
        assert!(cur.diagnostics().cap_hits > 0);
        let mut o = vec![Pt3::origin(); a.mesh.positions.len()];
        cur.deform_f64(&mut o);
        assert!(finite(&o), "{bend}");
        let mut o32 = vec![[0f32; 3]; o.len()];
        cur.deform(DeformOutput { positions: &mut o32, normals: None });
        assert!(o32.iter().all(|p| p.iter().all(|c| c.is_finite())));
    }
}

#[test]
fn twist_sweep_through_180_does_not_flip() {
    // 0 → 360° twist with unwrapping: ring radius stays ≥ 0.999 and the twist angle is continuous.
    let a = arm(80, 24);
    let mut cur = curve_skin(&a, CurveOptions::default());
    let mut prev = 0.0;
    for deg in (0..=360).step_by(5) {
        let (posed, _) = arm_pose(&a.sk, 0.0, deg as f64);
        cur.prepare(&a.sk, &posed).unwrap();
        let th = cur.frames()[0].theta;
        assert!((th - (deg as f64).to_radians()).abs() < 1e-9, "{deg}: θ = {th}");
        assert!((th - prev).abs() < 0.1 + 1e-9);
        prev = th;
        let mut o = vec![Pt3::origin(); a.mesh.positions.len()];
        cur.deform_f64(&mut o);
        let r = ring_radius_ratio(&o, &a.mesh.positions, Pt3::origin(), Vec3::x(), -1.0, 1.0, R);
        assert!(r >= 0.999, "{deg}: {r}");
    }
    // A twist hint decides ±180° and beyond.
    cur.reset_history();
    cur.twist_hint[1] = Some(-std::f64::consts::PI);
    let (posed, _) = arm_pose(&a.sk, 0.0, 180.0);
    cur.prepare(&a.sk, &posed).unwrap();
    assert_eq!(cur.frames()[0].theta, -std::f64::consts::PI);
}

#[test]
fn zero_length_bone_falls_back_to_the_other_curve() {
    // Joint 2 coincides with joint 1: the middle bone has length 0.
    let pos = [Pt3::new(-1.0, 0.0, 0.0), Pt3::new(0.0, 0.0, 0.0), Pt3::new(0.0, 0.0, 0.0), Pt3::new(1.0, 0.0, 0.0)];
    let names = (0..4).map(|i| format!("j{i}")).collect();
    let sk = SkinSkeleton::from_positions(names, vec![None, Some(0), Some(1), Some(2)], &pos).unwrap();
    let cs = build_curve_skeleton(&sk, &TopologyRules::default(), &JointCurveDefaults::default());
    let a = arm(40, 16);
    let mut cur = CurveSkin::new(&sk, cs, &a.mesh.positions, None, CurveOptions::default()).unwrap();
    let mut p = SkinPose::rest(&sk);
    p.set_world(&sk, 1, axis_deg(Vec3::z(), 40.0));
    p.set_world(&sk, 2, axis_deg(Vec3::z(), 40.0));
    cur.prepare(&sk, &p.globals(&sk)).unwrap();
    let mut o = vec![Pt3::origin(); a.mesh.positions.len()];
    cur.deform_f64(&mut o);
    assert!(finite(&o));
    let mut o32 = vec![[0f32; 3]; o.len()];
    cur.deform(DeformOutput { positions: &mut o32, normals: None });
    assert!(o32.iter().all(|p| p.iter().all(|c| c.is_finite())));
    // Every vertex is bound (no empty rows).
    assert!((0..cur.binding.len()).all(|v| !cur.binding.row(v).is_empty()));
}

#[test]
fn vertex_equidistant_from_two_curves_and_on_the_skeleton() {
    // A fork: two children of the root at ±45°; the point on the bisector is equidistant from the
    // two fork curves that share the incoming bone; points exactly on the skeleton have ℓ = 0.
    let pos = [Pt3::new(0.0, 0.0, 0.0), Pt3::new(0.0, 1.0, 0.0), Pt3::new(0.7, 1.7, 0.0), Pt3::new(-0.7, 1.7, 0.0)];
    let names = (0..4).map(|i| format!("j{i}")).collect();
    let sk = SkinSkeleton::from_positions(names, vec![None, Some(0), Some(1), Some(1)], &pos).unwrap();
    let cs = build_curve_skeleton(&sk, &TopologyRules::default(), &JointCurveDefaults::default());
    assert_eq!(cs.curves.len(), 3);
    let pts = [Pt3::new(0.0, 0.6, 0.1), Pt3::new(0.0, 0.5, 0.0), Pt3::new(0.35, 1.35, 0.0), Pt3::new(5.0, 9.0, 0.0)];
    let mut cur = CurveSkin::new(&sk, cs, &pts, None, CurveOptions::default()).unwrap();
    let r0 = cur.binding.row(0);
    assert_eq!(r0.len(), 2, "two equidistant fork curves");
    let (w0, w1) = (cur.binding.w[r0.start], cur.binding.w[r0.start + 1]);
    assert!((w0 - w1).abs() < 1e-12);
    // On the skeleton: zero local offset.
    for e in cur.binding.row(1) {
        assert!(Vec3::from(cur.binding.local[e]).norm() < 1e-12);
    }
    // Far outside every domain: clamped, counted.
    assert_eq!(cur.binding.stats.clamped, 1);
    let mut p = SkinPose::rest(&sk);
    p.set_world(&sk, 1, axis_deg(Vec3::z(), 60.0));
    let posed = p.globals(&sk);
    cur.prepare(&sk, &posed).unwrap();
    let mut o = vec![Pt3::origin(); pts.len()];
    cur.deform_f64(&mut o);
    assert!(finite(&o));
    // The point on the skeleton stays on the posed skeleton (bone 0 is not moved).
    assert!((o[1] - pts[1]).norm() < 1e-12);
}

#[test]
fn bad_weights_and_empty_inputs() {
    assert!(matches!(PackedWeights::<4>::from_sparse(&[vec![(0, f32::NAN)]]), Err(SkinError::BadWeights { .. })));
    let (w, dropped) = PackedWeights::<2>::from_sparse(&[vec![(0, -0.5), (1, 2.0), (2, 1.0), (3, 1.0)]]).unwrap();
    assert!((dropped - 0.25).abs() < 1e-6);
    assert!((w.w[0][0] - 2.0 / 3.0).abs() < 1e-6);
    // Empty mesh: no-op.
    let a = arm(10, 8);
    let mut l = Lbs::new(Vec::new(), None, PackedWeights::<4> { bone: vec![], w: vec![] }).unwrap();
    l.prepare(&a.sk, &a.sk.rest_world).unwrap();
    l.deform(DeformOutput { positions: &mut [], normals: None });
    // Zero bones.
    let empty = SkinSkeleton { names: vec![], parent: vec![], rest_world: vec![] };
    assert!(matches!(l.prepare(&empty, &[]), Err(SkinError::EmptySkeleton)));
    let cs = build_curve_skeleton(&empty, &TopologyRules::default(), &JointCurveDefaults::default());
    assert!(matches!(
        CurveSkin::new(&empty, cs, &a.mesh.positions, None, CurveOptions::default()),
        Err(SkinError::EmptySkeleton)
    ));
    // Mismatched pose.
    let mut cur = curve_skin(&a, CurveOptions::default());
    assert!(cur.prepare(&a.sk, &[Iso3::identity()]).is_err());
}

#[test]
fn non_unit_quaternion_input_is_normalised() {
    let a = arm(10, 8);
    let mut p = SkinPose::rest(&a.sk);
    p.rot[1] = geom_core::math::UnitQuat::new_unchecked(axis_deg(Vec3::z(), 30.0).into_inner() * (1.0 + 1e-9));
    let g = p.globals(&a.sk);
    assert!((g[2].rotation.norm() - 1.0).abs() < 1e-15);
}

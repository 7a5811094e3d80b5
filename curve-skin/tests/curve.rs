//! Spec §7.4 (quality targets on the cylinder) and §7.5 (curve-skin internals).

mod common;

use common::*;
use curve_skin::curve::{
    build_curve_skeleton, BoneCp, CurveFrame, FrameHistory, JointCurveDefaults, TopologyRules, TwistChoice, VolumeComp,
};
use curve_skin::dqs::dqs_f64;
use curve_skin::metrics::{distance_to_bones, fold_fraction, joint_radius_ratio, ring_radius_ratio, signed_volume};
use curve_skin::poses::{axis_deg, SkinPose};
use curve_skin::{skinning_transforms, Antipodal, CurveOptions, CurveSkin, DeformOutput, SkinSkeleton, Skinner};
use geom_core::math::{Pt3, Vec3};
use geom_core::rng::Rng;

struct Figures {
    volume: f64,
    joint: f64,
    min_d: f64,
    max_d: f64,
}

fn figures(a: &Arm, out: &[Pt3], bend: f64) -> Figures {
    let (posed, _) = arm_pose(&a.sk, bend, 0.0);
    let j = Pt3::from(posed[1].translation.vector);
    let (lo, hi) = distance_to_bones(&side_only(out, &a.side), &bones(&posed));
    Figures {
        volume: signed_volume(out, &a.mesh.tris) / signed_volume(&a.mesh.positions, &a.mesh.tris),
        joint: joint_radius_ratio(out, &a.mesh.positions, j, Pt3::origin(), R, 0.003),
        min_d: lo / R,
        max_d: hi / R,
    }
}

fn curve_out(a: &Arm, cur: &mut CurveSkin, bend: f64, twist: f64) -> Vec<Pt3> {
    let (posed, _) = arm_pose(&a.sk, bend, twist);
    cur.prepare(&a.sk, &posed).unwrap();
    let mut o = vec![Pt3::origin(); a.mesh.positions.len()];
    cur.deform_f64(&mut o);
    o
}

#[test]
fn curve_quality_table_no_collapse_no_bulge() {
    // 7.4 table (curve rows, ±0.003 volume, ±0.01 others) and hard assertions a, b.
    let a = reference_arm();
    let mut cur = curve_skin(&a, CurveOptions::default());
    for (bend, vol, joint, min_d) in
        [(45.0, 0.9982, 0.994, 0.929), (90.0, 0.9817, 0.988, 0.715), (135.0, 0.8921, 0.985, 0.388)]
    {
        let o = curve_out(&a, &mut cur, bend, 0.0);
        let f = figures(&a, &o, bend);
        assert!((f.volume - vol).abs() < 0.003, "{bend}: volume {}", f.volume);
        assert!((f.joint - joint).abs() < 0.01, "{bend}: joint {}", f.joint);
        assert!((f.min_d - min_d).abs() < 0.01, "{bend}: min {}", f.min_d);
        assert!(f.max_d <= 1.0 + 1e-9, "{bend}: max {}", f.max_d);
        // f32 table path: max dist ≤ 1 + 1e-5.
        let mut o32 = vec![[0f32; 3]; o.len()];
        cur.deform(DeformOutput { positions: &mut o32, normals: None });
        let f32f = figures(&a, &to_f64(&o32), bend);
        assert!(f32f.max_d <= 1.0 + 1e-5, "{bend}: f32 max {}", f32f.max_d);
    }
    for bend in [30.0, 60.0, 120.0, 150.0] {
        let o = curve_out(&a, &mut cur, bend, 0.0);
        let f = figures(&a, &o, bend);
        assert!(f.joint >= 0.98, "{bend}: curve joint {}", f.joint);
        assert!(f.max_d <= 1.0 + 1e-9);
    }
}

#[test]
fn dqs_rows_of_the_table_and_its_bulge() {
    // 7.4 DQS rows at 90° and the documented bulge (max dist/R > 1.15 at h = 2R).
    let a = reference_arm();
    for (h, vol, maxd) in [(R, 1.0, 1.088), (2.0 * R, 1.0, 1.207)] {
        let w = ramp4(&a.mesh, h);
        let (posed, _) = arm_pose(&a.sk, 90.0, 0.0);
        let o = dqs_f64(
            &a.mesh.positions,
            &w,
            &skinning_transforms(&a.sk, &posed),
            &a.sk.parent,
            Antipodal::PerVertexPivot,
        );
        let f = figures(&a, &o, 90.0);
        assert!((f.volume - vol).abs() < 0.003, "h={h}: {}", f.volume);
        assert!((f.max_d - maxd).abs() < 0.01, "h={h}: {}", f.max_d);
        assert!(f.joint >= 0.98);
    }
}

fn interior_samples(n: usize) -> Vec<Pt3> {
    let mut rng = Rng::new(11);
    (0..n)
        .map(|_| {
            let r = 0.98 * R * rng.f64().sqrt();
            let phi = rng.range(0.0, std::f64::consts::TAU);
            Pt3::new(rng.range(-0.95, 0.95), r * phi.cos(), r * phi.sin())
        })
        .collect()
}

#[test]
fn floating_rule_is_fold_free_up_to_135() {
    // 7.4 c: fold fraction 0 with 60k interior samples for bends ≤ 135°; at 150°/180° the cap is
    // hit and reported, and nothing is NaN.
    let a = arm(40, 16);
    let mut cur = curve_skin(&a, CurveOptions::default());
    let samples = interior_samples(60_000);
    for bend in [45.0, 90.0, 135.0] {
        let (posed, _) = arm_pose(&a.sk, bend, 0.0);
        cur.prepare(&a.sk, &posed).unwrap();
        assert_eq!(cur.diagnostics().cap_hits, 0, "{bend}");
        let f = fold_fraction(&|x| cur.map_point(&x), &samples, 1e-5);
        assert_eq!(f, 0.0, "{bend}");
    }
    for bend in [150.0, 180.0] {
        let (posed, _) = arm_pose(&a.sk, bend, 0.0);
        cur.prepare(&a.sk, &posed).unwrap();
        assert!(cur.diagnostics().cap_hits > 0, "{bend}");
        let mut o = vec![Pt3::origin(); a.mesh.positions.len()];
        cur.deform_f64(&mut o);
        assert!(o.iter().all(|p| p.coords.iter().all(|c| c.is_finite())));
    }
}

#[test]
fn candy_wrapper_removed() {
    // 7.4 d.
    let a = reference_arm();
    let mut cur = curve_skin(&a, CurveOptions::default());
    for theta in [90.0, 180.0] {
        let o = curve_out(&a, &mut cur, 0.0, theta);
        let v = signed_volume(&o, &a.mesh.tris) / signed_volume(&a.mesh.positions, &a.mesh.tris);
        assert!((0.999..=1.001).contains(&v), "{theta}: {v}");
        let r = ring_radius_ratio(&o, &a.mesh.positions, Pt3::origin(), Vec3::x(), -1.0, 1.0, R);
        assert!(r >= 0.999, "{theta}: ring {r}");
    }
}

#[test]
fn volume_compensation_restores_volume() {
    // 7.4 e: Isotropic with max_scale = ∞ ⇒ V/V₀ = 1 ± 1e-3 for bends ≤ 135°; table rows for the
    // joint ratio (1.171 at 90°, 1.590 at 135°, ± 0.01).
    let a = reference_arm();
    let opts = CurveOptions { volume_comp: VolumeComp::Isotropic { max_scale: f64::INFINITY }, ..Default::default() };
    let mut cur = curve_skin(&a, opts);
    for (bend, joint) in [(45.0, None), (90.0, Some(1.171)), (135.0, Some(1.590))] {
        let o = curve_out(&a, &mut cur, bend, 0.0);
        let f = figures(&a, &o, bend);
        assert!((f.volume - 1.0).abs() < 1e-3, "{bend}: {}", f.volume);
        if let Some(j) = joint {
            assert!((f.joint - j).abs() < 0.01, "{bend}: joint {}", f.joint);
        }
    }
}

fn bent_rest_arm(rest_bend_deg: f64) -> (SkinSkeleton, Vec<Pt3>) {
    // A two-bone arm whose rest elbow is bent; the mesh is the straight arm mapped rigidly per side.
    let a = arm(60, 24);
    let mut p = SkinPose::rest(&a.sk);
    p.set_world(&a.sk, 1, axis_deg(Vec3::z(), rest_bend_deg));
    let g = p.globals(&a.sk);
    let t = skinning_transforms(&a.sk, &g);
    let pos: Vec<Pt3> = a.mesh.positions.iter().map(|x| if x.x > 0.0 { t[1] * x } else { *x }).collect();
    let jp: Vec<Pt3> = g.iter().map(|f| Pt3::from(f.translation.vector)).collect();
    let sk = SkinSkeleton::from_positions(a.sk.names.clone(), a.sk.parent.clone(), &jp).unwrap();
    (sk, pos)
}

#[test]
fn bind_pose_reproduced_including_bent_rest() {
    // 7.5 a: 1e-12 in f64.
    let (sk, pos) = bent_rest_arm(30.0);
    for centre in [curve_skin::curve::CentreMode::OnSkeleton, curve_skin::curve::CentreMode::OnCurve] {
        let d = JointCurveDefaults { centre, ..Default::default() };
        let cs = build_curve_skeleton(&sk, &TopologyRules::default(), &d);
        let cur = CurveSkin::new(&sk, cs, &pos, None, CurveOptions::default()).unwrap();
        let mut o = vec![Pt3::origin(); pos.len()];
        cur.deform_f64(&mut o);
        assert!(max_diff(&o, &pos) < 1e-12, "{centre:?}: {}", max_diff(&o, &pos));
    }
}

#[test]
fn arc_is_circular_and_tangent_to_bones() {
    // 7.5 b: points of the curve's arc at distance r from the arc centre; end tangents = bones.
    let a = arm(10, 8);
    let cur = curve_skin(&a, CurveOptions::default());
    for bend in [20.0, 90.0, 140.0] {
        let (posed, _) = arm_pose(&a.sk, bend, 0.0);
        let f = posed_curve(&cur, 0, &posed);
        let beta: f64 = f64::to_radians(bend);
        let r = f.l_cp / (beta / 2.0).tan();
        let t1 = -f.u_in;
        let p0 = f.j + f.u_in * f.l_cp;
        let o = p0 + f.b.cross(&t1) * r;
        let first = f.l_in - f.l_cp;
        let arc = r * beta;
        for k in 0..=20 {
            let (p, _) = f.curve_point(first + arc * k as f64 / 20.0);
            assert!(((p - o).norm() - r).abs() < 1e-12, "{bend} {k}");
        }
        // End tangents by one-sided differences along the curve parameter.
        let h = 1e-7;
        let d0 = (f.curve_point(first + h).0 - f.curve_point(first).0) / h;
        let d1 = (f.curve_point(first + arc).0 - f.curve_point(first + arc - h).0) / h;
        assert!((d0 - t1).norm() < 1e-6 && (d1 - f.u_out).norm() < 1e-6);
    }
}

#[test]
fn floating_l_matches_formula() {
    // 7.5 c: L = safety·d·β/(2cos(β/2)) before clamping (d = R, safety 1.1).
    let a = arm(40, 16);
    let mut cur = curve_skin(&a, CurveOptions::default());
    assert!((cur.rigs()[0].skin_dist - R).abs() < 1e-12);
    for bend in [10.0f64, 45.0, 90.0, 120.0] {
        let (posed, _) = arm_pose(&a.sk, bend, 0.0);
        cur.prepare(&a.sk, &posed).unwrap();
        let b = bend.to_radians();
        let l = 1.1 * R * b / (2.0 * (b / 2.0).cos());
        let expect = l.clamp(0.02, 0.5);
        assert!((cur.frames()[0].l_cp - expect).abs() < 1e-12, "{bend}: {} vs {expect}", cur.frames()[0].l_cp);
    }
    // Reference values of the table: L = 0.47R at 45°, 1.22R at 90°, capped 3.33R at 135°.
    for (bend, lr) in [(45.0, 0.4675), (90.0, 1.2218), (135.0, 1.0 / 0.3 * 1.0)] {
        let (posed, _) = arm_pose(&a.sk, bend, 0.0);
        cur.prepare(&a.sk, &posed).unwrap();
        assert!((cur.frames()[0].l_cp / R - lr).abs() < 1e-3, "{bend}");
    }
    let _ = BoneCp::default();
}

fn chain3() -> SkinSkeleton {
    let pos = [Pt3::new(-1.0, 0.0, 0.0), Pt3::new(0.0, 0.0, 0.0), Pt3::new(0.8, 0.0, 0.0), Pt3::new(1.6, 0.0, 0.0)];
    let names = (0..4).map(|i| format!("j{i}")).collect();
    SkinSkeleton::from_positions(names, vec![None, Some(0), Some(1), Some(2)], &pos).unwrap()
}

#[test]
fn seamless_at_bone_midpoints_and_frames_equal_bone_frames() {
    // 7.5 d: a vertex at the midpoint of the middle bone deformed by either adjacent curve gives
    // the same position (1e-12); frames at σ = 0 / 1 equal the bone travel frames (1e-12).
    let sk = chain3();
    let cs = build_curve_skeleton(&sk, &TopologyRules::default(), &JointCurveDefaults::default());
    assert_eq!(cs.curves.len(), 2);
    let x = Pt3::new(0.4, 0.1, -0.05);
    let cur = CurveSkin::new(&sk, cs, &[x], None, CurveOptions::default()).unwrap();
    let mut p = SkinPose::rest(&sk);
    p.set_world(&sk, 1, axis_deg(Vec3::new(0.0, 0.3, 1.0), 70.0) * axis_deg(Vec3::x(), 50.0));
    p.set_world(&sk, 2, axis_deg(Vec3::new(0.2, 1.0, 0.0), -40.0) * axis_deg(Vec3::x(), -120.0));
    let posed = p.globals(&sk);
    let mut fr = Vec::new();
    for (i, c) in cur.skeleton.curves.iter().enumerate() {
        let (f, _) = CurveFrame::new(
            c,
            &cur.rigs()[i],
            &posed,
            &FrameHistory::default(),
            TwistChoice::Principal,
            VolumeComp::Off,
        );
        let (_, r0, _) = f.eval(0.0, &c.twist);
        let (_, r1, _) = f.eval(1.0, &c.twist);
        let fa = posed[c.bone_in.owner].rotation * cur.rigs()[i].e_in;
        let fc = posed[c.bone_out.owner].rotation * cur.rigs()[i].e_out;
        assert!(qdist(&r0, &fa) < 1e-12 && qdist(&r1, &fc) < 1e-12, "curve {i}");
        fr.push(f);
    }
    // Same point through each curve: curve 0 at σ = 1, curve 1 at σ = 0 (rest frames for ℓ).
    let rest = cur.rest_frames();
    let through = |i: usize, s: f64| {
        let tw = &cur.skeleton.curves[i].twist;
        let (c0, r0, _) = rest[i].eval(s, tw);
        let l = r0.inverse() * (x - c0);
        let (c1, r1, _) = fr[i].eval(s, tw);
        c1 + r1 * l
    };
    assert!((through(0, 1.0) - through(1, 0.0)).norm() < 1e-12);
}

#[test]
fn table_error_small_and_second_order() {
    // 7.5 i: K = 64 table vs exact: ≤ 1e-3 R (bend ≤ 150°, no twist; twist ≤ 180°, no bend),
    // ≤ 2e-3 R combined; ∝ K⁻² with the kink samples, first order without them.
    let a = arm(200, 48);
    let err = |k: usize, kinks: bool, bend: f64, twist: f64| {
        let mut cur = curve_skin(&a, CurveOptions { table_samples: k, kink_samples: kinks, ..Default::default() });
        let (posed, _) = arm_pose(&a.sk, bend, twist);
        cur.prepare(&a.sk, &posed).unwrap();
        let mut exact = vec![Pt3::origin(); a.mesh.positions.len()];
        cur.deform_f64(&mut exact);
        let mut t = vec![[0f32; 3]; exact.len()];
        cur.deform(DeformOutput { positions: &mut t, normals: None });
        max_diff(&to_f64(&t), &exact) / R
    };
    for bend in [30.0, 90.0, 150.0] {
        let e = err(64, true, bend, 0.0);
        assert!(e <= 1e-3, "bend {bend}: {e}");
    }
    for twist in [90.0, 180.0] {
        let e = err(64, true, 0.0, twist);
        assert!(e <= 1e-3, "twist {twist}: {e}");
    }
    let e = err(64, true, 90.0, 180.0);
    assert!(e <= 2e-3, "combined {e}");
    let (e32, e128) = (err(32, true, 90.0, 0.0), err(128, true, 90.0, 0.0));
    assert!(e32 / e128 > 3.0, "second order: {e32} → {e128}");
    let (n32, n128) = (err(32, false, 90.0, 0.0), err(128, false, 90.0, 0.0));
    assert!(n32 / n128 < 3.0 && n128 > e128, "first order without kinks: {n32} → {n128}");
}

#[test]
fn curve_skin_surface_does_not_self_intersect_up_to_135() {
    // 7.4 f: curve skin = 0 for bends ≤ 135°; LBS/DQS counts are reported by the scene.
    let a = arm(200, 48);
    let mut cur = curve_skin(&a, CurveOptions::default());
    for bend in [45.0, 90.0, 135.0] {
        let o = curve_out(&a, &mut cur, bend, 0.0);
        assert_eq!(curve_skin::metrics::self_intersections(&o, &a.mesh.tris), 0, "{bend}");
    }
    let o = curve_out(&a, &mut cur, 0.0, 180.0);
    assert_eq!(curve_skin::metrics::self_intersections(&o, &a.mesh.tris), 0, "twist 180");
}

//! Every curve-skin experiment (the scenes of `scenes/curve-skin/`) at `Size::Tiny` through the
//! no-op recorder: the spec's checks that hold at that size, and bitwise-identical figures with
//! one and with two rayon threads.

use curve_skin::experiments::{arm, humanoid, perf, walk};
use geom_core::experiment::{Report, Size};
use geom_core::record::NullRecorder;
use tests::{assert_checks_pass, assert_thread_independent, scene_params};

/// Asserts the checks of `keys` (present and passing): the arm checks that hold at the tiny
/// mesh (100 × 32); the others are stated for the spec's reference mesh (400 × 96), which the
/// default-size scenes run.
fn assert_these_checks_pass(name: &str, r: &Report, keys: &[&str]) {
    for k in keys {
        let c = r.checks.iter().find(|c| c.key == *k).unwrap_or_else(|| panic!("{name}: no check of {k}"));
        assert!(c.pass, "{name}: {k} = {} misses {} ({})", c.value, c.target.describe(), c.source);
    }
}

fn arm_scene(id: &str) -> Report {
    let p: arm::Params = scene_params(id);
    assert_thread_independent(id, || arm::run(&p, Size::Tiny, &mut NullRecorder::default()).unwrap())
}

#[test]
fn elbow_bend() {
    let r = arm_scene("curve-skin/elbow-bend");
    let keys =
        ["lbs_joint_radius_ratio", "dqs_joint_radius_ratio", "curve_max_dist_over_r", "curve_max_dist_over_r_f64"];
    assert_these_checks_pass("elbow-bend", &r, &keys);
    assert_these_checks_pass("elbow-bend", &r, &["curve_fold_fraction"]);
    // LBS collapses at the elbow, curve skin does not (spec §7.4 a), and the action line shortens.
    assert!(r.get_f64("curve_joint_radius_ratio") > 0.95, "{}", r.get_f64("curve_joint_radius_ratio"));
    let (lm, vm, v) =
        (r.get_f64("muscle_length_ratio"), r.get_f64("muscle_bulge_volume_ratio"), r.get_f64("curve_volume_ratio"));
    assert!(lm < 0.9 && vm > v, "the biceps shortens ({lm}) and bulges the skin ({vm} > {v})");
}

#[test]
fn candy_wrapper() {
    let r = arm_scene("curve-skin/candy-wrapper");
    assert_these_checks_pass("candy-wrapper", &r, &["lbs_volume_ratio"]);
    // LBS pinches the ring nearest the joint (x = ±1/99 of 100 rings, smoothstep weight w over
    // [−R, R]) to ρ(w) = √(1 − 2w(1 − w)(1 − cos θ)) (spec §3.2, §7.2 b).
    let xi = (1.0 / 99.0 + 0.15) / 0.3;
    let rho = curve_skin::reference::lbs_twist_ring_ratio(xi * xi * (3.0 - 2.0 * xi), std::f64::consts::PI);
    let got = r.get_f64("lbs_ring_radius_ratio");
    assert!((got - rho).abs() < 1e-4, "LBS ring ratio {got} vs ρ(w) = {rho}");
    for m in ["curve", "dqs"] {
        let v = r.get_f64(&format!("{m}_volume_ratio"));
        assert!((v - 1.0).abs() < 3e-3, "{m}: V/V0 = {v} under a pure twist");
    }
}

#[test]
fn humanoid_poses() {
    let p: humanoid::Params = scene_params("curve-skin/humanoid-poses");
    let r = assert_thread_independent("humanoid-poses", || {
        humanoid::run(&p, Size::Tiny, &mut NullRecorder::default()).unwrap()
    });
    assert_checks_pass("humanoid-poses", &r);
    for m in ["lbs", "dqs", "curve"] {
        let v = r.get_f64(&format!("{m}_volume_ratio_elbows_90"));
        assert!((0.8..1.2).contains(&v), "{m}: V/V0 = {v}");
    }
}

#[test]
fn walk() {
    let p: walk::Params = scene_params("curve-skin/walk");
    let r = assert_thread_independent("walk", || walk::run(&p, Size::Tiny, &mut NullRecorder::default()).unwrap());
    for m in ["lbs", "dqs", "curve"] {
        let (lo, hi) = (r.get_f64(&format!("{m}_min_volume_ratio")), r.get_f64(&format!("{m}_max_volume_ratio")));
        assert!(0.9 < lo && lo <= hi && hi < 1.1, "{m}: V/V0 in [{lo}, {hi}]");
    }
}

#[test]
fn perf() {
    let p: perf::Params = scene_params("curve-skin/perf");
    let r = assert_thread_independent("perf", || perf::run(&p, Size::Tiny, &mut NullRecorder::default()).unwrap());
    assert!(r.get_f64("summary_vertices") > 1000.0);
    assert!(r.get_f64("lbs_mverts_per_s") > 0.0 && r.get_f64("curve_mverts_per_s_2t_normals") > 0.0);
}

#[test]
fn bad_parameters_are_errors() {
    let mut p: arm::Params = scene_params("curve-skin/elbow-bend");
    p.shapes.clear();
    let e = arm::run(&p, Size::Tiny, &mut NullRecorder::default()).unwrap_err();
    assert!(e.to_string().contains("shapes"), "{e}");
    let mut w: walk::Params = scene_params("curve-skin/walk");
    w.fps = f64::NAN;
    assert!(walk::run(&w, Size::Tiny, &mut NullRecorder::default()).is_err());
}

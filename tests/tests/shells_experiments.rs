//! The `shells` experiments at their tiny size (issues 20 and 21): a 9×9 (tube 8×8) variant of
//! each contact-suite scene and of `drape` and `fold-stress`, 0.3 s each, run through the no-op
//! recorder from the scene files themselves, with 1 and with 2 threads (every non-timing figure
//! bitwise identical), asserting the contact invariants through the report's own checks:
//! penetration ≤ 1e-4 m, no self-intersection, no failed step, compression ≤ 0.5, strain ≤ 0.10
//! (0.15 on `twist`), `energy_gain_rel` ≤ 0.01 on the passive scenes. Timing checks (drape's
//! `s_per_step`) are not asserted here; the other experiments run once at their tiny size.

use std::path::PathBuf;

use geom_core::experiment::{Report, Size};
use geom_core::record::NullRecorder;
use shells::experiments::{self as ex, scene_params};
use tests::{assert_thread_independent, with_threads};

fn scene(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../scenes/shells").join(format!("{name}.ron"))
}

/// Asserts every check of the report that is not on a timing figure.
fn assert_invariants(name: &str, r: &Report, expect_energy: bool) {
    let keys: Vec<&str> = r.checks.iter().map(|c| c.key.as_str()).collect();
    for k in ["max_obstacle_penetration_m", "max_intersections", "nan_steps", "max_edge_compression", "max_edge_strain"]
    {
        assert!(keys.contains(&k), "{name}: no check on {k}");
    }
    assert_eq!(keys.contains(&"energy_gain_rel"), expect_energy, "{name}: energy_gain_rel check");
    let failed: Vec<String> = r
        .checks
        .iter()
        .filter(|c| !r.is_timing(&c.key) && !c.pass)
        .map(|c| format!("{} = {} (target {})", c.key, c.value, c.target.describe()))
        .collect();
    assert!(failed.is_empty(), "{name}: failed invariants:\n  {}", failed.join("\n  "));
    assert!(r.get_f64("steps") > 0.0, "{name}: no step taken");
}

fn contact(name: &str, passive: bool) {
    let p: ex::contact::Params = scene_params(&scene(name)).unwrap();
    let r = assert_thread_independent(name, || ex::contact::run(&p, Size::Tiny, &mut NullRecorder::default()).unwrap());
    assert_invariants(name, &r, passive);
}

#[test]
fn sphere_drop_tiny_holds_the_invariants() {
    contact("sphere-drop", true);
}

#[test]
fn spinning_sphere_tiny_holds_the_invariants() {
    contact("spinning-sphere", false);
}

#[test]
fn table_tiny_holds_the_invariants() {
    contact("table", true);
}

#[test]
fn twist_tiny_holds_the_invariants() {
    contact("twist", false);
}

#[test]
fn drape_tiny_holds_the_invariants() {
    let p: ex::drape::Params = scene_params(&scene("drape")).unwrap();
    let r =
        assert_thread_independent("drape", || ex::drape::run(&p, Size::Tiny, &mut NullRecorder::default()).unwrap());
    assert_invariants("drape", &r, true);
    assert!(r.checks.iter().any(|c| c.key == "s_per_step"), "drape keeps its timing target");
}

#[test]
fn fold_stress_tiny_holds_the_invariants() {
    let p: ex::fold_stress::Params = scene_params(&scene("fold-stress")).unwrap();
    let r = assert_thread_independent("fold-stress", || {
        ex::fold_stress::run(&p, Size::Tiny, &mut NullRecorder::default()).unwrap()
    });
    assert_invariants("fold-stress", &r, true);
}

/// The wind flag reports the sanity figures (no energy figure: the wind drives it) and its
/// flutter, identically with 1 and 2 threads.
#[test]
fn wind_flag_tiny_reports_sanity() {
    let p: ex::wind_flag::Params = scene_params(&scene("wind-flag")).unwrap();
    let r = assert_thread_independent("wind-flag", || {
        ex::wind_flag::run(&p, Size::Tiny, &mut NullRecorder::default()).unwrap()
    });
    for k in ["max_edge_strain", "max_edge_compression", "max_obstacle_penetration_m", "max_intersections"] {
        assert!(r.get_f64(k).is_finite(), "wind-flag: {k} = {}", r.get_f64(k));
    }
    assert_eq!(r.get_f64("nan_steps"), 0.0);
    assert!(r.get("energy_gain_rel").is_none(), "wind-flag is not passive");
    assert!(r.get_f64("mean_drag_N") > 0.0, "the wind pushes the flag downwind");
}

/// The static and quasi-static experiments run at their tiny size and pass their paper checks
/// (calibration within 1 %; the elastic crease returns flat).
#[test]
fn calibration_cantilever_and_crease_tiny() {
    let calib: ex::calib_bend::Params = scene_params(&scene("calib-bend")).unwrap();
    let r = ex::calib_bend::run(&calib, Size::Tiny, &mut NullRecorder::default()).unwrap();
    tests::assert_checks_pass("calib-bend", &r);
    let cant: ex::cantilever::Params = scene_params(&scene("cantilever")).unwrap();
    let r = with_threads(1, || ex::cantilever::run(&cant, Size::Tiny, &mut NullRecorder::default()).unwrap());
    assert!(r.get_f64("small_load_tip_rel_err").is_finite(), "cantilever: {:?}", r.figures);
    assert!(r.get_f64("moment_circle_gap_rel").is_finite(), "cantilever: {:?}", r.figures);
    let crease: ex::plastic_crease::Params = scene_params(&scene("plastic-crease")).unwrap();
    let r = ex::plastic_crease::run(&crease, Size::Tiny, &mut NullRecorder::default()).unwrap();
    assert_eq!(r.get_f64("diverged_runs"), 0.0, "plastic-crease: {:?}", r.figures);
    assert!(r.get_f64("elastic_final_max_angle") < 0.02, "plastic-crease: {:?}", r.figures);
}

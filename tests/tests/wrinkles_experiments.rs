//! Every wrinkles experiment (the scenes of `scenes/wrinkles/`) at `Size::Tiny` through the
//! no-op recorder: the spec's W1 and W2 criteria, and bitwise-identical figures with one and
//! with two rayon threads (the precomputation runs in parallel over triangles).

use geom_core::experiment::Size;
use geom_core::record::NullRecorder;
use tests::{assert_checks_pass, assert_thread_independent, scene_params};
use wrinkles::experiments::{four_stage, precompute_cost, realtime_small, uniaxial};

macro_rules! tiny {
    ($m:ident, $id:literal) => {{
        let p: $m::Params = scene_params($id);
        assert_thread_independent($id, || $m::run(&p, Size::Tiny, &mut NullRecorder::default()).unwrap())
    }};
}

#[test]
fn uniaxial() {
    let r = tiny!(uniaxial, "wrinkles/uniaxial");
    assert_checks_pass("uniaxial", &r);
    assert_eq!(r.get_f64("pass"), 1.0);
    assert!((r.get_f64("strip_amp_over_lambda_c0.90") - 0.0993299).abs() < 1e-7);
}

#[test]
fn four_stage() {
    let r = tiny!(four_stage, "wrinkles/four-stage");
    assert_checks_pass("four-stage", &r);
}

#[test]
fn precompute_cost() {
    let r = tiny!(precompute_cost, "wrinkles/precompute-cost");
    assert_eq!(r.get_f64("image_side"), 32.0);
    assert!(r.get_f64("s_per_1000_tri_tol1e-3") > 0.0);
}

#[test]
fn realtime_small() {
    let r = tiny!(realtime_small, "wrinkles/realtime-small");
    assert_eq!(r.get_f64("triangles"), 98.0);
    assert!(r.get_f64("last_displaced_area_m2") > 0.3 * 0.3, "wrinkles add area to the 0.3 m sheet");
}

#[test]
fn bad_parameters_are_errors() {
    let mut p: four_stage::Params = scene_params("wrinkles/four-stage");
    p.marked = [5.0, 5.0];
    let e = four_stage::run(&p, Size::Tiny, &mut NullRecorder::default()).unwrap_err();
    assert!(e.to_string().contains("outside the sheet"), "{e}");
    let mut u: uniaxial::Params = scene_params("wrinkles/uniaxial");
    u.tolerance = geom_core::experiment::BySize::Same(-1.0);
    assert!(uniaxial::run(&u, Size::Tiny, &mut NullRecorder::default()).is_err());
}

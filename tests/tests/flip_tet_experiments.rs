//! Every flip-tet experiment at `Size::Tiny` through the no-op recorder: the figures are bitwise
//! identical with 1 and 2 rayon threads, and the paper checks that are meaningful at that size
//! pass (the resting pools, the exact nodal projection). The tiny sizes are set here (the scene
//! files and presets give quick / default / full).

use flip_tet::experiments as ex;
use flip_tet::presets;
use geom_core::experiment::{BySize, Report, Size};
use geom_core::record::{NullRecorder, Recorder};
use tests::{assert_checks_pass, assert_thread_independent};

type Run<P> = fn(&P, Size, &mut dyn Recorder) -> flip_tet::error::Result<Report>;

fn tiny<P>(p: &P, run: Run<P>) -> Report {
    run(p, Size::Tiny, &mut NullRecorder::default()).expect("the experiment runs at the tiny size")
}

/// `b` with `tiny` as its tiny-size value.
fn t<T: Clone>(b: &BySize<T>, tiny: T) -> BySize<T> {
    BySize::Named {
        quick: b.get(Size::Quick),
        default: b.get(Size::Default),
        full: b.get(Size::Full),
        tiny: Some(tiny),
    }
}

#[test]
fn rest_pool_rests_and_is_thread_independent() {
    let mut p = presets::rest_pool();
    (p.finest, p.duration) = (t(&p.finest, 8), t(&p.duration, 5.0 / 120.0));
    p.variants.jitter_steps = t(&p.variants.jitter_steps, 6);
    p.variants.finest = Some(BySize::Same(8));
    let r = assert_thread_independent("rest-pool", || tiny(&p, ex::rest_pool::run));
    assert_checks_pass("rest-pool", &r);
    assert!(r.get_f64("s1b_first_order_max_speed") > 1e-4, "first order moves the offset pool");
}

#[test]
fn dam_break_is_thread_independent() {
    let mut p = presets::dam_break();
    (p.finest, p.duration) = (t(&p.finest, 16), t(&p.duration, 0.03));
    let r = assert_thread_independent("dam-break", || tiny(&p, ex::dam_break::run));
    assert!(r.get_f64("front_rms_rel_err").is_finite());
}

#[test]
fn standing_wave_is_thread_independent() {
    let mut p = presets::standing_wave();
    (p.finest, p.duration) = (t(&p.finest, 8), t(&p.duration, 0.05));
    p.variants.finest = Some(BySize::Same(8));
    assert_thread_independent("standing-wave", || tiny(&p, ex::standing_wave::run));
}

#[test]
fn drop_pool_and_adaptivity_payoff_are_thread_independent() {
    let mut p = presets::drop_pool();
    (p.finest, p.duration) = (t(&p.finest, 16), t(&p.duration, 0.05));
    assert_thread_independent("drop-pool", || tiny(&p, ex::drop_pool::run));
    let mut p = presets::adaptivity_payoff();
    (p.finest, p.duration, p.sizes) = (t(&p.finest, 16), t(&p.duration, 0.04), t(&p.sizes, vec![16]));
    let r = assert_thread_independent("adaptivity-payoff", || tiny(&p, ex::adaptivity_payoff::run));
    assert!(r.get_f64("particle_ratio_adaptive_over_uniform") < 1.0);
}

#[test]
fn holes_plate_is_thread_independent() {
    let mut p = presets::holes_plate();
    (p.finest, p.duration) = (t(&p.finest, 16), t(&p.duration, 0.04));
    let r = assert_thread_independent("holes-plate", || tiny(&p, ex::holes_plate::run));
    assert!(r.get_f64("rim_tets") > 0.0);
}

#[test]
fn static_experiments_pass_and_are_thread_independent() {
    let mut p = presets::fvm_vs_nodal();
    p.finest = t(&p.finest, 16);
    let r = assert_thread_independent("fvm-vs-nodal", || tiny(&p, ex::fvm_vs_nodal::run));
    assert_checks_pass("fvm-vs-nodal", &r);
    let mut p = presets::surface_mixed_radii();
    p.finest = t(&p.finest, 32);
    let r = assert_thread_independent("surface-mixed-radii", || tiny(&p, ex::surface_mixed_radii::run));
    assert!(r.get_f64("flat_patch_vertices") > 0.0);
}

#[test]
fn splash_and_corridor_are_thread_independent() {
    let mut p = presets::open_splash();
    (p.finest, p.duration) = (t(&p.finest, 16), t(&p.duration, 0.05));
    assert_thread_independent("open-splash", || tiny(&p, ex::open_splash::run));
    let mut p = presets::corridor_camera();
    (p.finest, p.duration) = (t(&p.finest, 16), t(&p.duration, 0.05));
    assert_thread_independent("corridor-camera", || tiny(&p, ex::corridor_camera::run));
}

/// Issue 26: the gate lifted as a moving obstacle (scene file's tiny size).
#[test]
fn dam_break_gate_is_thread_independent() {
    let p: ex::dam_break_gate::Params = tests::scene_params("flip-tet/dam-break-gate");
    let r = assert_thread_independent("dam-break-gate", || tiny(&p, ex::dam_break_gate::run));
    assert!(r.get_f64("front_rms_rel_err_gate").is_finite());
    assert_eq!(r.get("finite_gate"), Some(&geom_core::experiment::Value::Bool(true)));
    // The gate force is measured (its first-step value is far from hydrostatic: README, issue 26 item 5).
    assert!(r.get_f64("gate_force_x_first_step_N").is_finite());
    assert!(r.get_f64("particle_volume_drift_rel_gate").abs() < 1e-9);
}

/// Issue 26: force probes, a mesh obstacle and a moving paddle (scene file's tiny size).
#[test]
fn obstacle_force_is_thread_independent() {
    let mut p: ex::obstacle_force::Params = tests::scene_params("flip-tet/obstacle-force");
    p.resolve_paths(&std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes/flip-tet"));
    let r = assert_thread_independent("obstacle-force", || tiny(&p, ex::obstacle_force::run));
    for k in ["buoyancy_rel_err_box", "buoyancy_rel_err_mesh", "paddle_force_rel_err_rest"] {
        assert!(r.get_f64(k).is_finite(), "{k}");
    }
    assert!(r.get_f64("mesh_vs_box_force_rel_diff") < 0.05, "{}", r.get_f64("mesh_vs_box_force_rel_diff"));
}

/// Issue 26: an emitter and an outflow region (scene file's tiny size).
#[test]
fn inflow_is_thread_independent() {
    let p: ex::inflow::Params = tests::scene_params("flip-tet/inflow");
    let r = assert_thread_independent("inflow", || tiny(&p, ex::inflow::run));
    assert!(r.get_f64("inflow_emitted_volume_m3") > 0.0);
    assert_eq!(r.get("finite"), Some(&geom_core::experiment::Value::Bool(true)));
}

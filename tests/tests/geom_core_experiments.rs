//! geom-core's own experiments (the scenes of `scenes/geom-core/` and the solver benchmark) at
//! `Size::Tiny` through the no-op recorder: their invariants, and bitwise-identical figures with
//! one and with two rayon threads.

use std::path::PathBuf;

use geom_core::experiment::Size;
use geom_core::experiments::{mocap, render, solvers, subdivision};
use geom_core::record::NullRecorder;
use tests::{assert_checks_pass, assert_thread_independent, scene_params};

/// The folder of geom-core's scene files: their relative paths (`../../assets/…`) resolve there.
fn workspace() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../scenes/geom-core")
}

#[test]
fn render() {
    let p = render::Params { root: workspace(), ..scene_params("geom-core/render") };
    let r = assert_thread_independent("render", || render::run(&p, Size::Tiny, &mut NullRecorder::default()).unwrap());
    assert_checks_pass("render", &r);
    assert_eq!(r.get_f64("image_width"), 160.0);
    assert!(r.get_f64("icosphere_depth_max_m") > 0.0);
}

#[test]
fn subdivision() {
    let p = subdivision::Params { root: workspace(), ..scene_params("geom-core/subdivision") };
    let r = assert_thread_independent("subdivision", || {
        subdivision::run(&p, Size::Tiny, &mut NullRecorder::default()).unwrap()
    });
    assert_checks_pass("subdivision", &r);
    assert_eq!(r.get_f64("icosahedron_euler_characteristic"), 2.0);
    assert_eq!(r.get_f64("sheet_euler_characteristic"), 1.0);
}

#[test]
fn mocap() {
    let p = mocap::Params { root: workspace(), ..scene_params("geom-core/mocap") };
    let r = assert_thread_independent("mocap", || mocap::run(&p, Size::Tiny, &mut NullRecorder::default()).unwrap());
    assert_checks_pass("mocap", &r);
    assert_eq!(r.get_f64("01_01_frame_rate_hz").round(), 120.0);
}

#[test]
fn solvers() {
    let p = solvers::Params { sheet_quads: vec![7, 15], sphere_levels: vec![2], reps: 1 };
    let r =
        assert_thread_independent("solvers", || solvers::run(&p, Size::Tiny, &mut NullRecorder::default()).unwrap());
    assert!(r.get_f64("max_residual_direct") <= solvers::MAX_DIRECT_RESIDUAL);
    assert!(r.get_f64("kkt_residual") < 1e-8);
    assert_eq!(r.get_f64("largest_sheet_n"), 256.0);
}

#[test]
fn missing_files_are_errors() {
    let p = mocap::Params { clips: vec!["../../assets/no/such.bvh".into()], quick_frames: 10, root: workspace() };
    let e = mocap::run(&p, Size::Tiny, &mut NullRecorder::default()).unwrap_err();
    assert!(e.to_string().contains("no/such.bvh"), "{e}");
}

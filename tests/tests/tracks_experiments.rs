//! Every `tracks` experiment at `Size::Tiny` through the `NullRecorder` (issue 21): the shipped
//! scene file parses, the experiment runs, the checks that are meaningful at this size hold
//! (constraint residual at solver precision; the physical-sanity invariants of issue 20 on the
//! tracked and the untracked cloth), and 1 and 2 rayon threads give bitwise-identical figures.

use geom_core::experiment::{Report, Size};
use geom_core::record::NullRecorder;
use serde::de::DeserializeOwned;
use tests::assert_thread_independent;
use tracks::experiments as ex;

#[derive(serde::Deserialize)]
struct File<P> {
    params: P,
}

fn params<P: DeserializeOwned>(scene: &str) -> P {
    let path = format!("{}/../scenes/tracks/{scene}.ron", env!("CARGO_MANIFEST_DIR"));
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{path}: {e}"));
    ron::from_str::<File<P>>(&text).unwrap_or_else(|e| panic!("{path}: {e}")).params
}

/// Asserts the checks of `r` whose keys start with one of `prefixes`.
fn assert_checks(name: &str, r: &Report, prefixes: &[&str]) {
    let mut n = 0;
    for c in r.checks.iter().filter(|c| prefixes.iter().any(|p| c.key.starts_with(p))) {
        n += 1;
        assert!(c.pass, "{name}: {} = {} (target {}; {})", c.key, c.value, c.target.describe(), c.source);
    }
    assert!(n > 0, "{name}: no check matches {prefixes:?}");
}

/// The checks every tracking scene's tiny run must pass (solver precision; issue 20's strain and
/// intersection targets on the tracked and the untracked cloth).
const SANITY: &[&str] = &["max_residual_pre", "max_edge_strain_", "max_intersections_"];

/// Asserts the scene reports every sanity figure of issue 20, finite, for both runs.
fn assert_sanity_figures(name: &str, r: &Report) {
    for run in ["tracked", "untracked"] {
        for k in ["max_edge_strain", "max_edge_compression", "max_obstacle_penetration_m", "max_intersections"] {
            let v = r.get_f64(&format!("{k}_{run}"));
            assert!(v.is_finite(), "{name}: {k}_{run} = {v}");
        }
    }
}

fn run<P: DeserializeOwned + Sync>(
    scene: &str,
    f: fn(&P, Size, &mut dyn geom_core::record::Recorder) -> tracks::Result<Report>,
) -> Report {
    let p: P = params(scene);
    assert_thread_independent(scene, || f(&p, Size::Tiny, &mut NullRecorder::default()).expect(scene))
}

#[test]
fn flag() {
    let r = run("flag", ex::flag::run);
    assert_checks("flag", &r, SANITY);
    assert_sanity_figures("flag", &r);
    assert_eq!(r.get_f64("constraints"), 4.0);
    for k in ["stuck_preview_found", "tracked_stuck", "untracked_stuck"] {
        assert!(r.get(k).is_some(), "flag: {k} missing");
    }
}

#[test]
fn box_twist() {
    let r = run("box", ex::box_twist::run);
    assert_checks("box", &r, &["max_residual_pre"]);
    assert_sanity_figures("box", &r);
    assert_eq!(r.get_f64("constraints"), 8.0);
}

#[test]
fn bag() {
    let r = run("bag", ex::bag::run);
    assert_checks("bag", &r, SANITY);
    assert_sanity_figures("bag", &r);
    assert_eq!(r.get_f64("constraints"), 88.0);
}

/// Xavier's guide (linear blend skinning of the stand-in character) itself stretches its edges by
/// 0.19 at one frame and 0.38 at two (measured, `examples/xavier_guide_strain.rs`): the issue's
/// 0.10 on the tracked cloth is a reported miss (tracks README). What must hold here: the
/// tracked cloth stretches no more than the guide asks, the untracked one stays within 0.10, no
/// run self-intersects, and the residual is at solver precision.
#[test]
fn xavier() {
    let r = run("xavier", ex::xavier::run);
    assert_checks("xavier", &r, &["max_residual_pre", "max_intersections_", "max_edge_strain_untracked"]);
    assert_sanity_figures("xavier", &r);
    let (tracked, guide) = (r.get_f64("max_edge_strain_tracked"), r.get_f64("max_edge_strain_guide"));
    assert!(tracked <= guide, "tracked strain {tracked} above the guide's own {guide}");
    let f = r.get_f64("feet_over_body_deviation");
    assert!(f.is_finite() && f > 0.0, "feet_over_body_deviation = {f}");
}

#[test]
fn fig3_band() {
    let r = run("fig3-band", ex::fig3_band::run);
    assert_checks("fig3-band", &r, &["max_residual_pre"]);
}

#[test]
fn fig4_sphere() {
    let r = run("fig4-sphere", ex::fig4_sphere::run);
    assert_checks("fig4-sphere", &r, &["max_residual_pre"]);
    // Quasi-static start: the averaged sphere scales uniformly, with (nearly) no bending.
    assert!(r.get_f64("bend_energy_max_slow_averaged_J") < r.get_f64("bend_energy_max_slow_pointwise_J"));
    assert_eq!(r.get_f64("claims_total"), 5.0);
}

/// Fig. 5: the two halves of the heterogeneous clustering are measured on their own (finite
/// wavelengths and deviations); the residual is at solver precision and no run self-intersects.
#[test]
fn fig5_heterogeneous() {
    let r = run("fig5-heterogeneous", ex::fig5_heterogeneous::run);
    assert_checks("fig5-heterogeneous", &r, &["max_residual_pre", "max_intersections_"]);
    assert_sanity_figures("fig5-heterogeneous", &r);
    for k in ["wavelength_upper_m", "wavelength_lower_m", "deviation_upper", "deviation_lower"] {
        assert!(r.get_f64(k).is_finite() && r.get_f64(k) > 0.0, "{k} = {}", r.get_f64(k));
    }
    assert_eq!(r.get_f64("constraints"), 272.0);
}

/// A user's own guide (`tracks/track` on the committed `assets/guides/flag-preview.usda`, read
/// through the user-file path): the guide loads at its frame rate, the residual is at solver
/// precision, both twins stay physical.
#[test]
fn own_guide() {
    let mut p: ex::track::Params = params("own-guide");
    p.resolve_paths(std::path::Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/../scenes/tracks")));
    let r = assert_thread_independent("own-guide", || {
        ex::track::run(&p, Size::Tiny, &mut NullRecorder::default()).expect("own-guide")
    });
    assert_checks("own-guide", &r, SANITY);
    assert_sanity_figures("own-guide", &r);
    assert_eq!((r.get_f64("guide_vertices"), r.get_f64("guide_frames")), (35.0, 121.0));
    assert_eq!(r.get_f64("guide_fps"), 30.0);
    assert_eq!(r.get_f64("constraints"), 4.0);
}

/// Bad user input to `tracks/track` is an error naming what is wrong, never a panic.
#[test]
fn own_guide_bad_input() {
    let mut p: ex::track::Params = params("own-guide");
    p.guide = ex::track::GuideSource::Usd { path: "/nonexistent/guide.usda".into() };
    let e = ex::track::run(&p, Size::Tiny, &mut NullRecorder::default()).unwrap_err().to_string();
    assert!(e.contains("/nonexistent/guide.usda"), "{e}");
    let mut p: ex::track::Params = params("own-guide");
    p.resolve_paths(std::path::Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/../scenes/tracks")));
    p.test_functions = ex::track::Design::Clustered { regions: 4, seed: 1 };
    let e = ex::track::run(&p, Size::Tiny, &mut NullRecorder::default()).unwrap_err().to_string();
    assert!(e.contains("identical meshes"), "{e}");
}

#[test]
fn fig6_partitions() {
    let r = run("fig6-partitions", ex::fig6_partitions::run);
    assert_checks("fig6-partitions", &r, &["max_residual_pre"]);
    assert_eq!(r.get_f64("deviation_monotone"), 1.0, "more regions track closer");
}

#[test]
fn fig7_clustering() {
    let r = run("fig7-clustering", ex::fig7_clustering::run);
    assert!(r.get_f64("regions_animated") > 0.0);
    assert!(r.get_f64("non_rigidity_animated").is_finite() && r.get_f64("non_rigidity_static").is_finite());
    assert_eq!(r.get_f64("claims_total"), 3.0);
}

#[test]
fn table55() {
    let r = run("table55", ex::table55::run);
    assert_checks("table55", &r, &["max_residual_pre"]);
    for s in ["flag", "box", "bag", "xavier"] {
        assert!(r.get_f64(&format!("kkt_over_untracked_factor_{s}")) > 0.0, "{s}");
    }
}

#[test]
fn box_variants() {
    let r = run("box-variants", ex::box_variants::run);
    assert_checks("box-variants", &r, &["max_residual_pre"]);
    assert_eq!(r.get_f64("claims_total"), 5.0);
}

#[test]
fn bag_variants() {
    let r = run("bag-variants", ex::bag_variants::run);
    assert_checks("bag-variants", &r, &["max_residual_pre", "tracked_intersection_free"]);
    assert_eq!(r.get_f64("claims_total"), 4.0);
}

//! Every barnet experiment (the scenes of `scenes/barnet/`) at `Size::Tiny` through the no-op
//! recorder: the spec's checks (every frame in equilibrium, O(h²) membrane, the paper's "lower
//! q, bigger bulge"), and bitwise-identical figures with one and with two rayon threads.

use barnet::experiments::{arm_muscle, elbow_volume, nonlinear_vs_fdm, scaling, stiffness, topology};
use geom_core::experiment::Size;
use geom_core::record::NullRecorder;
use tests::{assert_checks_pass, assert_thread_independent, scene_params};

macro_rules! tiny {
    ($m:ident, $id:literal) => {{
        let p: $m::Params = scene_params($id);
        let r = assert_thread_independent($id, || $m::run(&p, Size::Tiny, &mut NullRecorder::default()).unwrap());
        assert_checks_pass($id, &r);
        r
    }};
}

#[test]
fn arm_muscle() {
    let r = tiny!(arm_muscle, "barnet/arm-muscle");
    assert_eq!(r.get_f64("fine_faces"), 2816.0, "the paper's face count");
    // Displacements scale with 1/q (spec §7.2 d): q = 2 gives half the bulge of q = 1.
    let (b1, b2) = (r.get_f64("bulge_height_m_q1"), r.get_f64("bulge_height_m_q2"));
    assert!(b1 > 0.0 && (b1 / b2 - 2.0).abs() < 0.05, "bulges {b1} (q = 1), {b2} (q = 2)");
}

#[test]
fn elbow_volume() {
    let r = tiny!(elbow_volume, "barnet/elbow-volume");
    assert!(r.get_f64("volume_loss_lbs_max_rel") > 0.01, "LBS loses volume at the elbow");
}

#[test]
fn stiffness() {
    let r = tiny!(stiffness, "barnet/stiffness");
    assert!(r.get_f64("refactorizations") > 0.0);
    assert!(r.get_f64("bulge_max_m_animated_q") > r.get_f64("bulge_max_m_constant_q"), "softer biceps, bigger bulge");
}

#[test]
fn topology() {
    let r = tiny!(topology, "barnet/topology");
    assert!(r.get_f64("faces_tri") > 0.0 && r.get_f64("faces_quad") > 0.0 && r.get_f64("faces_pent") > 0.0);
}

#[test]
fn scaling() {
    tiny!(scaling, "barnet/scaling");
}

#[test]
fn nonlinear_vs_fdm() {
    let r = tiny!(nonlinear_vs_fdm, "barnet/nonlinear-vs-fdm");
    // The FDM is exact at the reference state and drifts from the elastic model as loads grow.
    assert!(r.get_f64("shape_diff_rel_edge_at_scale1") > 0.0);
}

#[test]
fn bad_parameters_are_errors() {
    let mut p: elbow_volume::Params = scene_params("barnet/elbow-volume");
    p.deformer.loads.clear();
    let e = elbow_volume::run(&p, Size::Tiny, &mut NullRecorder::default()).unwrap_err();
    assert!(e.to_string().contains("load channel"), "{e}");
    let mut a: arm_muscle::Params = scene_params("barnet/arm-muscle");
    a.deformer.free = barnet::deformer::NodeSet::Named("no_such_set".into());
    assert!(arm_muscle::run(&a, Size::Tiny, &mut NullRecorder::default()).is_err());
}

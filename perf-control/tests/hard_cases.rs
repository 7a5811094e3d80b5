//! Hard cases of spec §8: clear errors, never a panic or NaN.

mod common;

use common::{random_db, random_take, smooth_track};
use geom_core::math::Vec3;
use geom_core::rng::Rng;
use perf_control::cell::Column;
use perf_control::data::straight_stroke;
use perf_control::{interpret, path_control, target_points, DpParams, Forced, MappingDb, PcError, PointTrack};

fn params() -> DpParams {
    DpParams {
        k: 1.0,
        stretch_limit_s: 0.1,
        beam: None,
        partial_ends: true,
        continuity_order: 0,
        k_vel: 0.0,
        forced: vec![],
        gemm: false,
    }
}

#[test]
fn empty_database_and_short_input() {
    assert!(matches!(MappingDb::from_takes(vec![], 10.0), Err(PcError::EmptyDatabase(_))));
    let db = random_db(1, &[4, 5], 2, 2, 10.0);
    let x = PointTrack::new(10.0, 2, vec![Vec3::zeros(); 2]);
    assert!(matches!(interpret(&db, &x, &params()), Err(PcError::InputTooShort { frames: 1 })));
    let mut empty = db.clone();
    empty.instances.clear();
    let mut rng = Rng::new(2);
    let x = smooth_track(&mut rng, 10, 2, 10.0);
    assert!(matches!(interpret(&empty, &x, &params()), Err(PcError::EmptyDatabase(_))));
}

#[test]
fn non_finite_values_are_reported_with_their_place() {
    let db = random_db(3, &[4, 5], 2, 2, 10.0);
    let mut rng = Rng::new(4);
    let mut x = smooth_track(&mut rng, 10, 2, 10.0);
    x.data[7].z = f64::NAN;
    match interpret(&db, &x, &params()) {
        Err(PcError::NonFinite { frame: 3, point: 1, .. }) => {}
        other => panic!("{other:?}"),
    }
    let mut take = random_take(&mut rng, &[4, 5], 2, 2, 10.0);
    take.target.data[3].y = f64::INFINITY;
    assert!(matches!(MappingDb::from_takes(vec![take], 10.0), Err(PcError::NonFinite { .. })));
}

#[test]
fn point_count_and_rate_mismatches() {
    let db = random_db(5, &[4, 5], 2, 2, 10.0);
    let mut rng = Rng::new(6);
    let x3 = smooth_track(&mut rng, 10, 3, 10.0);
    assert!(matches!(interpret(&db, &x3, &params()), Err(PcError::PointCountMismatch { expected: 2, got: 3, .. })));
    let x = smooth_track(&mut rng, 10, 2, 30.0);
    assert!(matches!(interpret(&db, &x, &params()), Err(PcError::RateMismatch { .. })));
    let a = random_take(&mut rng, &[4, 5], 2, 2, 10.0);
    let b = random_take(&mut rng, &[4, 5], 3, 2, 10.0);
    assert!(matches!(MappingDb::from_takes(vec![a, b], 10.0), Err(PcError::PointCountMismatch { .. })));
}

#[test]
fn coincident_points_standing_still() {
    // One control point that never moves, in input and database.
    let mut rng = Rng::new(7);
    let mut take = random_take(&mut rng, &[4, 5, 6], 1, 2, 10.0);
    for p in &mut take.control.data {
        *p = Vec3::new(0.3, 0.0, -0.2);
    }
    let db = MappingDb::from_takes(vec![take], 10.0).unwrap();
    let x = PointTrack::new(10.0, 1, vec![Vec3::new(2.0, 0.0, 1.0); 20]);
    let it = interpret(&db, &x, &params()).unwrap();
    assert!(it.score.is_finite());
    assert!(it.segments.iter().all(|s| s.m.yaw == 0.0 && s.d.is_finite()));
}

#[test]
fn untileable_input_without_partial_ends() {
    // Only durations of exactly 4 intervals: 14 frames (13 intervals) cannot be tiled.
    let db = random_db(8, &[4, 4], 2, 2, 10.0);
    let mut rng = Rng::new(9);
    let x = smooth_track(&mut rng, 14, 2, 10.0);
    let mut p = params();
    p.stretch_limit_s = 0.0;
    p.partial_ends = false;
    assert!(matches!(interpret(&db, &x, &p), Err(PcError::NoInterpretation(_))));
    p.partial_ends = true;
    let it = interpret(&db, &x, &p).unwrap();
    assert!(it.segments.iter().all(|s| s.end - s.start == 4));
    // 13 frames (12 intervals) tile exactly with stretch limit 0.
    let x = smooth_track(&mut rng, 13, 2, 10.0);
    p.partial_ends = false;
    assert_eq!(interpret(&db, &x, &p).unwrap().segments.len(), 3);
}

#[test]
fn extreme_k_and_zero_beam() {
    let db = random_db(10, &[4, 5, 6, 5], 2, 2, 10.0);
    let mut rng = Rng::new(11);
    let x = smooth_track(&mut rng, 30, 2, 10.0);
    for k in [0.0, 1e9] {
        let mut p = params();
        p.k = k;
        let it = interpret(&db, &x, &p).unwrap();
        assert!(it.score.is_finite() && it.d_total.is_finite() && it.c_total.is_finite());
        p.beam = Some(0.0);
        let g = interpret(&db, &x, &p).unwrap();
        assert!(g.score.is_finite() && g.score >= it.score - 1e-9 * it.score.abs().max(1.0));
    }
    let mut p = params();
    p.k = f64::NAN;
    assert!(matches!(interpret(&db, &x, &p), Err(PcError::BadParameter { name: "k", .. })));
    p.k = 1.0;
    p.beam = Some(-1.0);
    assert!(matches!(interpret(&db, &x, &p), Err(PcError::BadParameter { name: "beam", .. })));
}

#[test]
fn too_short_instances_are_dropped_with_a_warning() {
    let mut rng = Rng::new(12);
    // Native 30 Hz, working 5 Hz: a 2-frame segment has 0 intervals and is dropped.
    let take = random_take(&mut rng, &[2, 12, 15], 2, 2, 30.0);
    let db = MappingDb::from_takes(vec![take], 5.0).unwrap();
    assert_eq!(db.instances.len(), 2);
    assert_eq!(db.warnings.len(), 1);
    let take = random_take(&mut rng, &[2, 2], 2, 2, 30.0);
    assert!(matches!(MappingDb::from_takes(vec![take], 5.0), Err(PcError::EmptyDatabase(_))));
}

#[test]
fn one_instance_database_repeats_it() {
    let db = random_db(13, &[5], 2, 2, 10.0);
    let mut rng = Rng::new(14);
    let x = smooth_track(&mut rng, 23, 2, 10.0);
    let it = interpret(&db, &x, &params()).unwrap();
    assert!(it.segments.len() >= 4 && it.segments.iter().all(|s| s.instance == 0));
    assert_eq!(target_points(&db, &it, true).unwrap().len(), 23);
}

#[test]
fn input_far_outside_the_database() {
    // A walk-like 2-point database driven by a 6 m/s stroke: finishes, large D.
    let db = random_db(15, &[5, 6, 5, 6], 2, 2, 10.0);
    let x = path_control(&straight_stroke(6.0, 10.0, 6.0), 10.0, 0.2, 3);
    let it = interpret(&db, &x, &params()).unwrap();
    assert!(it.score.is_finite() && it.d_total > 1.0);
}

#[test]
fn ties_go_to_the_lowest_column() {
    // Two identical instances: every chain could use either; the lower index must win.
    let mut rng = Rng::new(16);
    let mut take = random_take(&mut rng, &[5, 5], 2, 2, 10.0);
    for f in 0..=5 {
        for p in 0..2 {
            take.control.data[(5 + f) * 2 + p] = take.control.data[f * 2 + p];
            take.target.data[(5 + f) * 2 + p] = take.target.data[f * 2 + p];
        }
    }
    let db = MappingDb::from_takes(vec![take], 10.0).unwrap();
    let col = Column::new(&db, 1, 5);
    let x = PointTrack::new(10.0, 2, col.ctrl.clone());
    let it = interpret(&db, &x, &params()).unwrap();
    assert_eq!(it.segments.len(), 1);
    assert_eq!(it.segments[0].instance, 0);
}

#[test]
fn constraints_excluding_every_cell_name_the_problem() {
    let db = random_db(17, &[4, 5], 2, 2, 10.0);
    let mut rng = Rng::new(18);
    let x = smooth_track(&mut rng, 20, 2, 10.0);
    let mut p = params();
    p.forced = vec![Forced { instance: 0, time: 10 }, Forced { instance: 1, time: 10 }];
    match interpret(&db, &x, &p) {
        Err(PcError::NoInterpretation(msg)) => assert!(msg.contains("forced")),
        other => panic!("{other:?}"),
    }
    p.forced = vec![Forced { instance: 0, time: 25 }];
    assert!(matches!(interpret(&db, &x, &p), Err(PcError::NoInterpretation(_))));
}

#[test]
fn stretch_limit_zero_uses_native_durations() {
    let db = random_db(19, &[4, 6, 5], 2, 2, 10.0);
    let mut rng = Rng::new(20);
    let x = smooth_track(&mut rng, 31, 2, 10.0);
    let mut p = params();
    p.stretch_limit_s = 0.0;
    let it = interpret(&db, &x, &p).unwrap();
    assert!(it.segments.iter().all(|s| (s.end - s.start) as usize == db.instances[s.instance as usize].n()));
    assert_eq!(it.stats.columns, 3);
}

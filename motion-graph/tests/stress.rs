//! Hard cases of motion-graph.md §8: clear errors, no panics.

use geom_core::anim::synth::{library, Preset};
use geom_core::anim::Skeleton;
use motion_graph::*;
use std::sync::Arc;
use std::time::Duration;

fn problem(len: u32, end: (f64, f64)) -> Problem {
    Problem {
        length: Some(len),
        body: vec![
            BodyConstraint { time: 0, x: 0.0, z: 0.0, yaw: Some(0.0) },
            BodyConstraint { time: len - 1, x: end.0, z: end.1, yaw: None },
        ],
        ..Default::default()
    }
}

fn small() -> SearchParams {
    SearchParams { seeds: 6, population_cap: 12, max_mutations: 200, ..Default::default() }
}

#[test]
fn empty_database_and_single_frame_clips() {
    assert!(matches!(Database::from_motions(vec![], &DbParams::default()), Err(Error::EmptyDatabase(_))));
    let clips: Vec<_> = library(Preset::Walk2Min, 3, (60, 60), 30.0, 1).into_iter().map(|m| m.slice(0, 1)).collect();
    assert!(matches!(Database::from_motions(clips, &DbParams::default()), Err(Error::EmptyDatabase(_))));
    // Mixed: short clips skipped with a warning, the rest kept.
    let mut clips = library(Preset::Walk2Min, 2, (60, 60), 30.0, 1);
    clips.push(clips[0].slice(0, 2));
    let db = Database::from_motions(clips, &DbParams::default()).unwrap();
    assert_eq!(db.clips.len(), 2);
    assert!(db.warnings.iter().any(|w| w.contains("skipped")));
}

#[test]
fn skeleton_mismatch_names_the_joint() {
    let mut clips = library(Preset::Walk2Min, 2, (40, 40), 30.0, 1);
    let mut s = Skeleton::standard_humanoid();
    s.joints[3].offset.y += 0.05;
    clips[1].skeleton = Arc::new(s);
    match Database::from_motions(clips, &DbParams::default()) {
        Err(Error::SkeletonMismatch { clip: 1, what }) => assert!(what.contains("Neck"), "{what}"),
        other => panic!("{other:?}"),
    }
}

#[test]
fn disconnected_graph_hard_constraints_give_no_seed_path() {
    let clips = library(Preset::Football, 8, (90, 120), 30.0, 2);
    let db = Database::from_motions(clips, &DbParams::default()).unwrap();
    let part = (0..8).map(|c| u32::from(c >= 4)).collect();
    let g =
        MotionGraph::build(db, &GraphParams { partition: Some(part), calibration_pairs: 50_000, ..Default::default() })
            .unwrap();
    // No edge crosses the partition.
    for e in &g.edges {
        assert_eq!(e.from.clip >= 4, e.to.clip >= 4);
    }
    let mut pb = problem(200, (0.0, 8.0));
    pb.hard = vec![
        HardConstraint::Frame { time: 0, frame: FrameRef { clip: 0, frame: 5 } },
        HardConstraint::Frame { time: 150, frame: FrameRef { clip: 7, frame: 5 } },
    ];
    let r = Search::new(&g, pb, SearchParams { max_seed_tries: 50, ..small() });
    assert!(matches!(r, Err(Error::NoSeedPath { .. })), "{:?}", r.err());
    // Soft-only problem: every result stays in the start group.
    let mut s = Search::new(&g, problem(200, (0.0, 8.0)), small()).unwrap();
    s.run_for(Duration::from_millis(300));
    for r in s.results().iter().chain(s.population()) {
        let g0 = r.path.start.clip >= 4;
        for &e in &r.path.cuts {
            assert_eq!(g.edges[e as usize].to.clip >= 4, g0);
        }
    }
}

#[test]
fn infeasible_request_returns_a_finite_best() {
    let clips = library(Preset::Football, 8, (90, 150), 30.0, 3);
    let g = MotionGraph::build(
        Database::from_motions(clips, &DbParams::default()).unwrap(),
        &GraphParams { calibration_pairs: 50_000, ..Default::default() },
    )
    .unwrap();
    let mut s = Search::new(&g, problem(150, (0.0, 100.0)), small()).unwrap();
    // Budget 0: the best seed is returned.
    s.run_for(Duration::ZERO);
    assert!(s.best().is_some_and(|b| b.score.is_finite()));
    s.run_for(Duration::from_millis(300));
    let b = s.best().unwrap();
    assert!(b.score.is_finite() && b.errors.body_pos[1] > 10.0);
}

#[test]
fn tiny_and_huge_tau() {
    let clips = library(Preset::Mixed, 4, (60, 80), 30.0, 4);
    let db = Database::from_motions(clips, &DbParams::default()).unwrap();
    let g = MotionGraph::build(db.clone(), &GraphParams { tau: Some(1e-12), ..Default::default() }).unwrap();
    assert_eq!(g.stats().leaf_edges, 0);
    // Single-clip paths still work.
    let mut s = Search::new(&g, problem(40, (0.0, 1.0)), small()).unwrap();
    s.run_for(Duration::from_millis(50));
    assert!(s.best().is_some_and(|b| b.path.cuts.is_empty()));
    let r = MotionGraph::build(db, &GraphParams { tau: Some(1e12), max_edges: 1000, ..Default::default() });
    assert!(matches!(r, Err(Error::TooManyEdges { .. })));
}

#[test]
fn problem_errors() {
    let clips = library(Preset::Mixed, 3, (60, 80), 30.0, 5);
    let g = MotionGraph::build(
        Database::from_motions(clips, &DbParams::default()).unwrap(),
        &GraphParams { calibration_pairs: 20_000, ..Default::default() },
    )
    .unwrap();
    let mut pb = problem(100, (0.0, 3.0));
    pb.body[1].time = 5000;
    assert!(matches!(Search::new(&g, pb, small()), Err(Error::ConstraintOutOfRange { .. })));
    let mut pb = problem(100, (0.0, 3.0));
    pb.hard.push(HardConstraint::Label { time: 10, label: "no-such-label".into() });
    assert!(matches!(Search::new(&g, pb, small()), Err(Error::UnknownLabel(_))));
    let mut pb = problem(100, (0.0, 3.0));
    pb.hard = vec![
        HardConstraint::Frame { time: 10, frame: FrameRef { clip: 0, frame: 1 } },
        HardConstraint::Frame { time: 10, frame: FrameRef { clip: 0, frame: 2 } },
    ];
    assert!(matches!(Search::new(&g, pb, small()), Err(Error::ConflictingHard { time: 10 })));
}

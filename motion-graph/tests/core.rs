//! Core checks of motion-graph.md §7.2–§7.4 on a small synthetic database.

use geom_core::anim::synth::{library, Preset};
use geom_core::math::Planar;
use motion_graph::*;
use std::time::Duration;

fn graph(n: usize, seed: u64) -> MotionGraph {
    let clips = library(Preset::Football, n, (90, 150), 30.0, seed);
    let db = Database::from_motions(clips, &DbParams::default()).unwrap();
    MotionGraph::build(db, &GraphParams { calibration_pairs: 100_000, ..Default::default() }).unwrap()
}

/// Small search settings so the tests stay short in the dev profile.
fn small(seed: u64) -> SearchParams {
    SearchParams { seeds: 8, population_cap: 16, max_mutations: 400, rng_seed: seed, ..Default::default() }
}

fn problem() -> Problem {
    Problem {
        length: Some(200),
        body: vec![
            BodyConstraint { time: 0, x: 0.0, z: 0.0, yaw: Some(0.0) },
            BodyConstraint { time: 100, x: 1.0, z: 4.0, yaw: None },
            BodyConstraint { time: 199, x: 2.0, z: 8.0, yaw: Some(0.3) },
        ],
        ..Default::default()
    }
}

#[test]
fn cost_is_symmetric_and_zero_on_diagonal_and_graph_invariants_hold() {
    let g = graph(12, 1);
    let f = &g.features;
    for (a, b) in [(0, 5), (17, 300), (40, 41)] {
        assert_eq!(f.cost(a, a), 0.0);
        let (x, y) = (f.cost(a, b), f.cost(b, a));
        assert!((x - y).abs() <= 1e-9 * x.max(1e-300));
    }
    let s = g.stats();
    // τ calibration: mean stored edges per frame near the target (±25 % on a small database).
    let per = s.leaf_edges as f64 / s.frames as f64;
    assert!((7.5..=12.5).contains(&per), "{per} edges per frame");
    for e in &g.edges {
        assert!((e.cost as f64) < 1.0 + 1e-6);
        if e.from.clip == e.to.clip {
            assert!((e.from.frame as i64 + 1 - e.to.frame as i64).abs() >= g.min_self_gap as i64);
        }
        assert!(e.from.frame + 1 < g.clip_len(e.from.clip));
    }
    // Hierarchy: every leaf under exactly one root; representatives are leaves below the node.
    let mut root_of = vec![u32::MAX; g.edges.len()];
    for &r in &g.top {
        let mut st = vec![r];
        while let Some(v) = st.pop() {
            assert_eq!(root_of[v as usize], u32::MAX, "node {v} under two roots");
            root_of[v as usize] = r;
            st.extend(g.edges[v as usize].children.iter().flatten());
        }
    }
    for (i, e) in g.edges.iter().enumerate() {
        assert_ne!(root_of[i], u32::MAX);
        if !e.is_leaf() {
            let mut st = vec![i as u32];
            let mut found = false;
            while let Some(v) = st.pop() {
                let n = &g.edges[v as usize];
                if n.is_leaf() && n.from == e.from && n.to == e.to {
                    found = true;
                }
                st.extend(n.children.iter().flatten());
            }
            assert!(found);
        }
    }
    assert!(s.top_edges < s.leaf_edges);
}

#[test]
fn search_assemble_smooth_enforce() {
    let g = graph(20, 2);
    let pb = problem();
    let p = small(3);
    let mut s = Search::new(&g, pb.clone(), p.clone()).unwrap();
    s.run_until(&Tolerance::default(), Duration::from_secs(3), 30);
    let best = s.best().unwrap().clone();
    // Fast scoring equals the measurement on the assembled motion (§7.3 test 14).
    let start = Planar::new(0.0, 0.0, 0.0);
    let mut a = assemble(&g, &best.path, start, p.min_piece_frames).unwrap();
    let m0 = evaluate(&g, &a, &pb);
    for (x, y) in m0.body_pos.iter().zip(&best.errors.body_pos) {
        assert!((x - y).abs() <= 1e-9, "{x} vs {y}");
    }
    smooth(&mut a, 30);
    enforce_body(&mut a, &pb.body);
    let m = evaluate(&g, &a, &pb);
    for e in &m.body_pos {
        assert!(*e <= 1e-9, "{:?} {:?} frames {}", m.body_pos, m.body_yaw_deg, a.motion.len());
    }
    for e in &m.body_yaw_deg {
        assert!(*e <= 1e-9, "{e}");
    }
    // Determinism.
    let mut s2 = Search::new(&g, pb.clone(), p).unwrap();
    for _ in 0..s.iterations() {
        s2.step();
    }
    let mut s3 = Search::new(&g, pb, small(3)).unwrap();
    for _ in 0..s.iterations() {
        s3.step();
    }
    assert_eq!(s2.best().unwrap().path, s3.best().unwrap().path);
}

#[test]
fn hard_label_constraint_is_met_exactly() {
    let g = graph(20, 4);
    let mut pb = problem();
    pb.hard.push(HardConstraint::Label { time: 120, label: "jump".into() });
    let mut s = Search::new(&g, pb.clone(), small(1)).unwrap();
    for _ in 0..10 {
        s.step();
    }
    let jump = g.db.label_bit("jump").unwrap();
    for sc in s.population().iter().chain(s.results()) {
        let a = assemble(&g, &sc.path, Planar::identity(), 6).unwrap();
        assert!(a.motion.labels.bits[120] & jump != 0);
    }
}

#[test]
fn errors_are_typed() {
    let g = graph(8, 5);
    let mut pb = problem();
    pb.body.remove(0);
    assert!(matches!(Search::new(&g, pb, SearchParams::default()), Err(Error::NoStartConstraint)));
    let mut pb = problem();
    pb.hard = vec![
        HardConstraint::Label { time: 5, label: "jump".into() },
        HardConstraint::Label { time: 5, label: "wave".into() },
    ];
    assert!(matches!(
        Search::new(&g, pb, SearchParams::default()),
        Err(Error::ConflictingHard { time: 5 }) | Err(Error::UnknownLabel(_))
    ));
    assert!(matches!(Database::from_motions(vec![], &DbParams::default()), Err(Error::EmptyDatabase(_))));
}

#[test]
fn identity_splice_reproduces_the_clip() {
    // One 200-frame clip split into fragments of ≤ 120 frames (one-frame overlap): the zero-cost
    // continuation edge re-joins them into exactly the original clip (§7.3 test 13).
    let clip = library(Preset::Mixed, 1, (200, 200), 30.0, 8).remove(0);
    let other = library(Preset::Mixed, 2, (90, 90), 30.0, 9);
    let mut ms = vec![clip.clone()];
    ms.extend(other);
    let db = Database::from_motions(ms, &DbParams { max_clip_frames: 120, ..Default::default() }).unwrap();
    assert_eq!(db.next[0], Some(1));
    let g = MotionGraph::build(db, &GraphParams { calibration_pairs: 50_000, ..Default::default() }).unwrap();
    let len0 = g.clip_len(0);
    let e = g
        .edges
        .iter()
        .position(|n| {
            n.is_leaf() && n.from == FrameRef { clip: 0, frame: len0 - 2 } && n.to == FrameRef { clip: 1, frame: 0 }
        })
        .expect("continuation edge") as u32;
    assert!(g.edges[e as usize].cost.abs() < 1e-6);
    let path = Path { start: FrameRef { clip: 0, frame: 0 }, cuts: vec![e], end_frame: g.clip_len(1) - 1 };
    let a = assemble(&g, &path, clip.torso_frame(0), 6).unwrap();
    assert_eq!(a.motion.len(), clip.len());
    let nj = clip.n_joints();
    let (mut p, mut q) = (vec![geom_core::math::Pt3::origin(); nj], vec![geom_core::math::Pt3::origin(); nj]);
    for f in 0..clip.len() {
        clip.joint_positions(f, &mut p);
        a.motion.joint_positions(f, &mut q);
        for (x, y) in p.iter().zip(&q) {
            assert!((x - y).norm() <= 1e-12, "frame {f}: {}", (x - y).norm());
        }
    }
}

#[test]
fn smoothing_removes_a_step_and_leaves_the_outside_untouched() {
    // A 0.3 rad step in one joint at a cut with zero natural velocity (§7.4 test 19).
    let g = graph(6, 6);
    let clip = &g.db.clips[0];
    let n = 120;
    let mut m = clip.slice(0, 1).time_stretch(n);
    let nj = m.n_joints();
    let j = 7;
    for f in 60..n {
        m.rot[f * nj + j] = geom_core::math::axis_quat(0, 0.3) * m.rot[f * nj + j];
    }
    let orig = m.clone();
    let mut a =
        Assembled { source: vec![FrameRef { clip: 0, frame: 0 }; n], pieces: vec![], cuts: vec![60], motion: m };
    smooth(&mut a, 30);
    let q = |f: usize| a.motion.rot[f * nj + j];
    let jump = geom_core::math::quat_log(&(q(59).inverse() * q(60))).norm();
    assert!(jump <= 1e-9, "{jump}");
    for f in (0..30).chain(90..n) {
        for k in 0..nj {
            assert_eq!(a.motion.rot[f * nj + k], orig.rot[f * nj + k], "frame {f} joint {k}");
        }
    }
    // Kernel: s(0) = 1, s(1) = s'(1) = 0 (finite difference, step 1e-7).
    assert_eq!(kernel(0.0), 1.0);
    assert_eq!(kernel(1.0), 0.0);
    let d = (kernel(1.0) - kernel(1.0 - 1e-7)) / 1e-7;
    assert!(d.abs() <= 1e-6, "{d}");
}

#[test]
fn cost_is_invariant_to_moving_a_clip_on_the_floor() {
    // §7.2 test 8: a planar rigid motion of a whole clip leaves its costs unchanged.
    let clips = library(Preset::Mixed, 3, (60, 80), 30.0, 12);
    let mut moved = clips.clone();
    let w = Planar::new(3.0, -2.0, 1.1);
    let q = geom_core::math::axis_quat(1, w.yaw);
    let nj = moved[0].n_joints();
    for f in 0..moved[0].len() {
        moved[0].root_pos[f] = w.apply_point(moved[0].root_pos[f]);
        moved[0].rot[f * nj] = q * moved[0].rot[f * nj];
    }
    let fa = FeatureTable::build(&Database::from_motions(clips, &DbParams::default()).unwrap(), &JointWeights::Default);
    let fb = FeatureTable::build(&Database::from_motions(moved, &DbParams::default()).unwrap(), &JointWeights::Default);
    let n0 = fa.offsets[1];
    for f in (0..n0).step_by(7) {
        for g in (n0..fa.frames()).step_by(5) {
            let (x, y) = (fa.cost(f, g), fb.cost(f, g));
            assert!((x - y).abs() <= 1e-9 * x.max(1.0), "{f} {g}: {x} vs {y}");
        }
    }
}

/// Guided seeds (beam search toward the constraints): on constraints read off a real path of the
/// graph (so an exact solution exists), the best guided seed beats the best of the random seeds
/// and lands within 1 m of every constraint (the beam is not exhaustive; measured ≈ 0.1–0.5 m).
#[test]
fn guided_seeds_approach_constraints_taken_from_a_real_path() {
    let g = graph(12, 1);
    let mut pb = problem();
    let random = SearchParams { guided: GuidedParams { width: 0, ..Default::default() }, ..small(5) };
    let s0 = Search::new(&g, pb.clone(), random.clone()).unwrap();
    let a0 = assemble(&g, &s0.best().unwrap().path, Planar::identity(), 6).unwrap();
    for b in pb.body.iter_mut() {
        let tf = a0.motion.torso_frame(b.time as usize);
        (b.x, b.z) = (tf.x, tf.z);
        if b.yaw.is_some() {
            b.yaw = Some(tf.yaw);
        }
    }
    let r = Search::new(&g, pb.clone(), SearchParams { rng_seed: 9, ..random }).unwrap();
    let guided = Search::new(&g, pb, SearchParams { guided: GuidedParams::default(), ..small(9) }).unwrap();
    let (rb, gb) = (r.best().unwrap(), guided.best().unwrap());
    assert!(gb.score <= rb.score, "guided {} vs random {}", gb.score, rb.score);
    let worst = gb.errors.body_pos.iter().copied().fold(0.0, f64::max);
    assert!(worst < 1.0, "guided seed error {worst} m");
    assert_eq!(gb.frames, 200);
}

/// The contact fix removes a known slide: a synthesised walk (zero stance skate by construction)
/// with a root drift of 1 cm per frame slides 30 cm/s; after `fix_contacts` every held contact
/// point moves ≤ 1e-9 m per frame, and rotations and root heights are untouched.
#[test]
fn fix_contacts_cancels_a_known_slide() {
    let mut m = library(Preset::Walk2Min, 1, (120, 120), 30.0, 3).remove(0);
    for (f, p) in m.root_pos.iter_mut().enumerate() {
        p.x += 0.01 * f as f64;
    }
    let slid = geom_core::anim::metrics::foot_skate(&m, &m.labels);
    assert!(slid.contact_frames > 0);
    assert!((slid.mean_mm - 10.0).abs() < 1.0, "mean slide {} mm per contact frame", slid.mean_mm);
    let (rot, ys): (Vec<_>, Vec<f64>) = (m.rot.clone(), m.root_pos.iter().map(|p| p.y).collect());
    let mut a = Assembled { motion: m, pieces: Vec::new(), cuts: Vec::new(), source: Vec::new() };
    fix_contacts(&mut a);
    let s = geom_core::anim::metrics::foot_skate(&a.motion, &a.motion.labels);
    assert!(s.slide_m <= 1e-9 * s.contact_frames as f64, "residual slide {} m", s.slide_m);
    assert_eq!(a.motion.rot, rot);
    assert!(a.motion.root_pos.iter().zip(&ys).all(|(p, y)| p.y == *y));
}

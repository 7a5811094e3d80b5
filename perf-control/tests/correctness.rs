//! Correctness tests of spec §7 (numbering in the test names).

mod common;

use common::{random_db, smooth_track};
use geom_core::math::Planar;
use geom_core::rng::Rng;
use perf_control::cell::{eval_cell, Column};
use perf_control::data::{walk_motion, walk_take};
use perf_control::dp::columns;
use perf_control::output::postprocess_segments;
use perf_control::{
    interpret, placed_motions, placed_segments, refine, score_chain, target_points, ClusterBy, ClusterDistance,
    ClusterOptions, DpParams, Forced, Interpretation, MappingDb, PcError, PointTrack, Representative, Signal,
};

fn params(k: f64, stretch: f64, partial: bool) -> DpParams {
    DpParams {
        k,
        stretch_limit_s: stretch,
        beam: None,
        partial_ends: partial,
        continuity_order: 0,
        k_vel: 0.0,
        forced: vec![],
        gemm: false,
    }
}

/// §7.3: an input that is one placed, stretched instance is explained by that instance.
#[test]
fn t03_single_segment_is_recovered() {
    let db = random_db(3, &[5, 7, 6, 8], 3, 2, 10.0);
    let mut rng = Rng::new(4);
    for s in 0..4u32 {
        let n = db.instances[s as usize].n();
        for d in [n - 1, n, n + 1] {
            let col = Column::new(&db, s, d);
            let g = Planar::new(rng.range(-3.0, 3.0), rng.range(-3.0, 3.0), rng.range(-3.0, 3.0));
            let x = PointTrack::new(10.0, 3, col.ctrl.clone()).transformed(&g);
            let it = interpret(&db, &x, &params(1.0, 0.1, false)).unwrap();
            assert_eq!(it.segments.len(), 1, "s {s} d {d}");
            let c = it.segments[0];
            assert_eq!((c.instance, (c.end - c.start) as usize), (s, d));
            assert!(c.d <= 1e-12, "D = {}", c.d);
            assert!(geom_core::math::wrap_angle(c.m.yaw - g.yaw).abs() <= 1e-9);
            assert!((c.m.x - g.x).abs() <= 1e-9 && (c.m.z - g.z).abs() <= 1e-9);
        }
    }
}

/// A chain `(instance, start, end)` per segment.
type ChainVec = Vec<(u32, i64, i64)>;
/// Best score and chain.
type Best = (f64, ChainVec);

/// Brute force over every chain (same cell rules as the DP), depth-first with every cell
/// evaluated once; ties keep the first chain found in (start, column) order.
fn brute(db: &MappingDb, x: &PointTrack, p: &DpParams) -> Option<Best> {
    use perf_control::cell::{continuity, CellEval};
    let cols = columns(db, p.stretch_limit_s);
    let t = x.len() as i64;
    let dmax = cols.iter().map(|c| c.d).max().unwrap() as i64;
    let lo = -(dmax - 1);
    // cells[(start − lo) * P + c]
    let np = cols.len();
    let mut cells: Vec<Option<CellEval>> = Vec::new();
    for s in lo..t {
        for col in &cols {
            cells.push(eval_cell(x, col, s, &db.control_weights));
        }
    }
    struct Ctx<'a> {
        p: &'a DpParams,
        cols: &'a [Column],
        cells: &'a [Option<CellEval>],
        wt: &'a [f64],
        lo: i64,
        t: i64,
        np: usize,
        best: Option<Best>,
    }
    fn rec(c: &mut Ctx, chain: &mut Vec<(u32, i64, i64)>, start: i64, score: f64, prev: Option<&CellEval>) {
        for (ci, col) in c.cols.iter().enumerate() {
            let end = start + col.d as i64;
            if !c.p.partial_ends && end > c.t - 1 {
                continue;
            }
            let Some(e) = c.cells[(start - c.lo) as usize * c.np + ci].as_ref() else { continue };
            let cc = prev.map_or(0.0, |pv| continuity(&pv.omega, &e.alpha, c.wt, c.p.continuity_order, c.p.k_vel));
            let z = score + c.p.k * cc + e.d;
            chain.push((col.inst, start, end));
            if end >= c.t - 1 {
                if c.best.as_ref().is_none_or(|b| z < b.0) {
                    c.best = Some((z, chain.clone()));
                }
            } else {
                rec(c, chain, end, z, Some(e));
            }
            chain.pop();
        }
    }
    let mut ctx = Ctx { p, cols: &cols, cells: &cells, wt: &db.target_weights, lo, t, np, best: None };
    let starts: Vec<i64> = if p.partial_ends { (lo..=0).collect() } else { vec![0] };
    for s in starts {
        rec(&mut ctx, &mut vec![], s, 0.0, None);
    }
    // Cross-check the winner with the independent chain scorer.
    if let Some((s, ch)) = &ctx.best {
        let it = score_chain(db, x, ch, p).unwrap();
        assert!((it.score - s).abs() <= 1e-9 * (1.0 + s));
    }
    ctx.best
}

fn chain_of(it: &Interpretation) -> Vec<(u32, i64, i64)> {
    it.segments.iter().map(|s| (s.instance, s.start, s.end)).collect()
}

/// §7.4: the DP equals exhaustive enumeration on tiny problems (partial ends off and on).
#[test]
fn t04_dp_equals_brute_force() {
    let mut rng = Rng::new(44);
    let mut checked = 0;
    for case in 0..200u64 {
        let lens: Vec<usize> = (0..3).map(|_| 3 + rng.below(3)).collect();
        let db = random_db(1000 + case, &lens, 2, 2, 10.0);
        let x = smooth_track(&mut rng, 14, 2, 10.0);
        let k = [0.0, 0.5, 3.0, 20.0][case as usize % 4];
        for partial in [false, true] {
            let mut p = params(k, 0.1, partial);
            // Every third case adds the velocity continuity term (order 1).
            if case % 3 == 2 {
                p.continuity_order = 1;
                p.k_vel = 0.05;
            }
            let b = brute(&db, &x, &p);
            match interpret(&db, &x, &p) {
                Ok(it) => {
                    let (bs, bc) = b.expect("DP found a chain, brute force must too");
                    // Tolerance: sums of ~30 terms of O(1..100) in a different order.
                    assert!((it.score - bs).abs() <= 1e-9 * (1.0 + bs), "case {case}: {} vs {bs}", it.score);
                    assert_eq!(chain_of(&it), bc, "case {case} partial {partial}");
                    assert!((it.score - (it.d_total + k * it.c_total)).abs() <= 1e-9 * (1.0 + bs));
                    checked += 1;
                }
                Err(PcError::NoInterpretation(_)) => assert!(b.is_none(), "case {case}"),
                Err(e) => panic!("{e}"),
            }
        }
    }
    assert!(checked >= 300, "only {checked} cases had a solution");
}

/// §7.5: a training take's own control is reinterpreted as that take's instances in order.
#[test]
fn t05_identity_reinterpretation() {
    let take = walk_take(5, 8.0, 30.0);
    let x = take.control.clone();
    let db = MappingDb::from_takes(vec![take], 30.0).unwrap();
    for k in [0.1, 10.0, 1000.0] {
        let it = interpret(&db, &x, &params(k, 0.0, true)).unwrap();
        let insts: Vec<u32> = it.segments.iter().map(|s| s.instance).collect();
        assert_eq!(insts, (0..db.instances.len() as u32).collect::<Vec<_>>(), "k {k}");
        assert!(it.d_total <= 1e-9 && it.c_total <= 1e-9, "k {k}: D {} C {}", it.d_total, it.c_total);
    }
}

/// §7.6: the GEMM min-plus relaxation gives the push sweep's scores and chains (random
/// databases with and without the velocity term, and a walk input, exact and with beam).
#[test]
fn t06_gemm_equals_push() {
    let mut rng = Rng::new(66);
    let compare = |db: &MappingDb, x: &PointTrack, p: &DpParams| {
        let push = interpret(db, x, p).unwrap();
        let mut pg = p.clone();
        pg.gemm = true;
        let gemm = interpret(db, x, &pg).unwrap();
        // Tolerance: the expansion ‖ω‖² + ‖α‖² − 2ω·α of centred O(1 m) points loses ~1e-15 per
        // relaxation; scores are sums of O(100) such terms.
        assert!(
            (push.score - gemm.score).abs() <= 1e-9 * push.score.abs().max(1.0),
            "{} vs {}",
            push.score,
            gemm.score
        );
        assert_eq!(chain_of(&push), chain_of(&gemm));
        assert_eq!(push.stats.relaxations, gemm.stats.relaxations);
    };
    for case in 0..20u64 {
        let db = random_db(600 + case, &[4, 5, 6, 5, 4, 6], 2, 3, 10.0);
        let x = smooth_track(&mut rng, 40, 2, 10.0);
        let mut p = params(3.0, 0.2, case % 2 == 0);
        if case % 3 == 0 {
            p.continuity_order = 1;
            p.k_vel = 0.02;
        }
        compare(&db, &x, &p);
        p.beam = Some(1.0);
        compare(&db, &x, &p);
    }
    let db = MappingDb::from_takes(vec![walk_take(61, 20.0, 30.0)], 10.0).unwrap();
    let x = walk_take(62, 8.0, 30.0).control.downsample(3);
    let mut p = params(10.0, 0.2, true);
    compare(&db, &x, &p);
    p.beam = Some(0.3);
    compare(&db, &x, &p);
}

/// §7.7: an infinite beam is exact; a zero beam is greedy but complete and cheaper.
#[test]
fn t07_beam() {
    let db = random_db(7, &[4, 5, 6, 5, 4, 6, 5, 7], 2, 3, 10.0);
    let mut rng = Rng::new(8);
    let x = smooth_track(&mut rng, 60, 2, 10.0);
    let exact = interpret(&db, &x, &params(3.0, 0.2, true)).unwrap();
    let mut p = params(3.0, 0.2, true);
    p.beam = Some(f64::INFINITY);
    let inf = interpret(&db, &x, &p).unwrap();
    assert_eq!(chain_of(&inf), chain_of(&exact));
    assert_eq!(inf.score, exact.score);
    p.beam = Some(0.0);
    let greedy = interpret(&db, &x, &p).unwrap();
    assert!(greedy.segments[0].start <= 0 && greedy.segments.last().unwrap().end >= 59);
    assert!(greedy.segments.windows(2).all(|w| w[0].end == w[1].start));
    assert!(greedy.stats.cells_expanded < exact.stats.cells_expanded);
    assert!(greedy.score >= exact.score - 1e-9);
}

/// §7.8: forced segments are honoured; impossible constraints give `NoInterpretation`.
#[test]
fn t08_forced_segments() {
    let db = random_db(9, &[4, 5, 6, 5], 2, 2, 10.0);
    let mut rng = Rng::new(10);
    let x = smooth_track(&mut rng, 30, 2, 10.0);
    for inst in 0..4u32 {
        for time in [0usize, 7, 15, 29] {
            let mut p = params(2.0, 0.1, true);
            p.forced = vec![Forced { instance: inst, time }];
            let it = interpret(&db, &x, &p).unwrap();
            assert!(
                it.segments.iter().any(|s| s.instance == inst && s.start <= time as i64 && time as i64 <= s.end),
                "instance {inst} at {time}"
            );
        }
    }
    // Two different instances forced strictly inside the same frame span: impossible.
    let mut p = params(2.0, 0.1, true);
    p.forced =
        vec![Forced { instance: 0, time: 12 }, Forced { instance: 1, time: 12 }, Forced { instance: 2, time: 12 }];
    assert!(matches!(interpret(&db, &x, &p), Err(PcError::NoInterpretation(_))));
    p.forced = vec![Forced { instance: 9, time: 3 }];
    assert!(matches!(interpret(&db, &x, &p), Err(PcError::NoInterpretation(_))));
}

/// §7.9: refinement keeps the instances, moves boundaries within ±(u−1) of u·b and never scores
/// worse than the naive upsampled boundaries.
#[test]
fn t09_refinement() {
    let db_fine = MappingDb::from_takes(vec![walk_take(21, 16.0, 30.0)], 30.0).unwrap();
    let db = db_fine.at_rate(10.0).unwrap();
    let held = walk_take(22, 6.0, 30.0);
    let x_fine = held.control.clone();
    let x = x_fine.downsample(3);
    let p = params(10.0, 0.2, true);
    let coarse = interpret(&db, &x, &p).unwrap();
    let fine = refine(&db_fine, &x_fine, &coarse, 3, &p).unwrap();
    assert_eq!(fine.segments.len(), coarse.segments.len());
    for (f, c) in fine.segments.iter().zip(&coarse.segments) {
        assert_eq!(f.instance, c.instance);
        assert!((f.start - 3 * c.start).abs() <= 2 && (f.end - 3 * c.end).abs() <= 2);
    }
    assert!(fine.segments[0].start <= 0 && fine.segments.last().unwrap().end >= x_fine.len() as i64 - 1);
    // Naive upsampled chain (its last boundary snapped into the legal end range).
    let mut naive: Vec<(u32, i64, i64)> =
        coarse.segments.iter().map(|s| (s.instance, 3 * s.start, 3 * s.end)).collect();
    let last = naive.len() - 1;
    naive[last].2 = naive[last].2.max(x_fine.len() as i64 - 1);
    let delta = (0.2f64 * 30.0).round() as i64;
    let legal = naive.iter().all(|&(s, a, b)| ((b - a) - db_fine.instances[s as usize].n() as i64).abs() <= delta);
    let ns = score_chain(&db_fine, &x_fine, &naive, &p).unwrap();
    if legal {
        assert!(fine.score <= ns.score + 1e-9, "fine {} naive {}", fine.score, ns.score);
    }
    assert!(fine.score.is_finite() && fine.stats.relaxations > 0);
}

/// §7.10: post-processing closes every seam and adds a linear offset inside each segment.
#[test]
fn t10_postprocessing() {
    let db = random_db(12, &[4, 5, 6, 5, 4, 6], 2, 4, 10.0);
    let mut rng = Rng::new(13);
    let x = smooth_track(&mut rng, 40, 2, 10.0);
    let it = interpret(&db, &x, &params(1.0, 0.1, true)).unwrap();
    assert!(it.segments.len() >= 3);
    let raw = placed_segments(&db, &it, Signal::Target).unwrap();
    let mut post = raw.clone();
    postprocess_segments(&mut post);
    for i in 0..post.len() - 1 {
        let w = post[i].frame(post[i].len() - 1);
        let a = post[i + 1].frame(0);
        for p in 0..4 {
            assert!((w[p] - a[p]).norm() <= 1e-9);
        }
    }
    for (r, q) in raw.iter().zip(&post) {
        for f in 1..r.len() - 1 {
            for p in 0..4 {
                let o = |g: usize| q.frame(g)[p] - r.frame(g)[p];
                assert!((o(f + 1) - 2.0 * o(f) + o(f - 1)).norm() <= 1e-12);
            }
        }
    }
    let out = target_points(&db, &it, true).unwrap();
    assert_eq!(out.len(), 40);
}

/// §7.10 for skeletal output: rotations and root meet at every seam after post-processing.
#[test]
fn t10_postprocessing_motion() {
    let db = MappingDb::from_takes(vec![walk_take(31, 8.0, 30.0)], 30.0).unwrap();
    let held = walk_take(32, 3.0, 30.0);
    let it = interpret(&db, &held.control, &params(10.0, 0.1, true)).unwrap();
    assert!(it.segments.len() >= 3);
    let segs = placed_motions(&db, &it, true).unwrap();
    let nj = segs[0].n_joints();
    for w in segs.windows(2) {
        let la = w[0].len() - 1;
        assert!((w[0].root_pos[la] - w[1].root_pos[0]).norm() <= 1e-9);
        for j in 0..nj {
            let a = w[0].rot[la * nj + j];
            let b = w[1].rot[j];
            assert!(a.angle_to(&b) <= 1e-9, "joint {j}: {}", a.angle_to(&b));
        }
    }
    let m = perf_control::target_motion(&db, &it, true).unwrap();
    assert_eq!(m.len(), held.control.len());
}

/// §7.11: clustering bounds the spread of every cluster and hits target sizes.
#[test]
fn t11_cluster_reduction() {
    let lens: Vec<usize> = (0..60).map(|i| 4 + i % 3).collect();
    let base = random_db(15, &lens, 2, 2, 10.0);
    for thr in [0.05, 0.2, 1.0] {
        let mut db = base.clone();
        let o = ClusterOptions {
            by: ClusterBy::Threshold(thr),
            distance: ClusterDistance::ControlAndTarget,
            stretch_limit_s: 0.1,
            representative: Representative::Random,
            seed: 1,
        };
        let r = db.cluster(&o).unwrap();
        assert!(r.max_intra <= thr);
        assert_eq!(db.instances.len(), r.after);
    }
    for want in [10, 25, 40] {
        for mode in [ClusterDistance::ControlOnly, ClusterDistance::ControlAndTarget] {
            let mut db = base.clone();
            let o = ClusterOptions {
                by: ClusterBy::TargetSize(want),
                distance: mode,
                stretch_limit_s: 0.1,
                representative: Representative::Medoid,
                seed: 1,
            };
            let r = db.cluster(&o).unwrap();
            assert!(r.after.abs_diff(want) <= 2, "want {want} got {}", r.after);
        }
    }
}

/// §7.12: hips control has exactly the normalized width, on the floor.
#[test]
fn t12_hips_control_width() {
    let m = walk_motion(3, 3.0, 30.0);
    let c = perf_control::hips_control(&m, 0.2);
    for f in 0..c.len() {
        let (a, b) = (c.frame(f)[0], c.frame(f)[1]);
        assert!(((a - b).norm() - 0.2).abs() <= 1e-12 && a.y == 0.0 && b.y == 0.0);
    }
}

/// §7.13: walk generator — stance feet fixed, one instance per step, boundaries at plants.
#[test]
fn t13_walk_generator() {
    let take = walk_take(41, 12.0, 30.0);
    let m = take.source.as_ref().unwrap();
    let plants = perf_control::eval::plants(&m.labels);
    // Every interior boundary is a plant.
    for b in &take.boundaries[1..take.boundaries.len() - 1] {
        assert!(plants.iter().any(|(f, _)| f == b), "boundary {b}");
    }
    // Steps alternate feet and last a plausible time (0.3–0.9 s).
    let labs = &take.labels[1..take.labels.len() - 1];
    assert!(labs.windows(2).all(|w| w[0] != w[1]));
    for w in take.boundaries[1..take.boundaries.len() - 1].windows(2) {
        let s = (w[1] - w[0]) as f64 / 30.0;
        assert!((0.25..=0.9).contains(&s), "step of {s} s");
    }
    // Stance ankles fixed: ankle position constant while its contact bit is set.
    let t = &take.target;
    for (p, bit) in [(2usize, geom_core::anim::FrameLabels::L_ANKLE), (3, geom_core::anim::FrameLabels::R_ANKLE)] {
        for f in 1..m.len() {
            if m.labels.contacts[f] & bit != 0 && m.labels.contacts[f - 1] & bit != 0 {
                assert!((t.frame(f)[p] - t.frame(f - 1)[p]).norm() <= 1e-9, "foot {p} frame {f}");
            }
        }
    }
    let db = MappingDb::from_takes(vec![take.clone()], 30.0).unwrap();
    assert_eq!(db.instances.len(), take.boundaries.len() - 1);
}

/// §7.13 / §12 item 11: every sharp turn starts on a plant of the foot on the turn side, in the
/// final walk (the onset search synthesises truncated walks; the plan must be causal).
#[test]
fn t13_turns_start_on_the_turn_side_foot() {
    let (m, turns) = perf_control::data::walk_motion_with_turns(43, 45.0, 30.0);
    assert!(turns.len() >= 2, "{} turns", turns.len());
    let plants = perf_control::eval::plants(&m.labels);
    for t in &turns {
        let foot = if t.angle > 0.0 { 0 } else { 1 };
        let f = (t.start * 30.0).round() as usize;
        assert!(plants.iter().any(|&(pf, ft)| ft == foot && pf == f), "turn at {} s (foot {foot})", t.start);
    }
}

/// §3.11: annotations are propagated with the chosen instances; reinterpreting a take's own
/// control returns its annotations exactly, and a stretched single instance keeps its pattern.
#[test]
fn annotations_propagate() {
    let mut rng = Rng::new(70);
    let mut take = common::random_take(&mut rng, &[5, 6, 7, 5], 2, 2, 10.0);
    let n = take.control.len();
    take.annotations = Some((0..n).map(|f| 1u64 << (f % 7) | (f as u64 / 5) << 8).collect());
    let db = MappingDb::from_takes(vec![take.clone()], 10.0).unwrap();
    let it = interpret(&db, &take.control, &params(10.0, 0.0, false)).unwrap();
    assert_eq!(it.segments.len(), 4);
    let a = perf_control::propagate(&db, &it).unwrap().unwrap();
    assert_eq!(&a, take.annotations.as_ref().unwrap());
    // Stretch instance 1 (6 intervals) to 9: nearest-sample pattern.
    let col = Column::new(&db, 1, 9);
    let x = PointTrack::new(10.0, 2, col.ctrl.clone());
    let it = interpret(&db, &x, &params(1.0, 0.3, false)).unwrap();
    assert_eq!((it.segments.len(), it.segments[0].instance), (1, 1));
    let a = perf_control::propagate(&db, &it).unwrap().unwrap();
    let src = db.instances[1].annotations.as_ref().unwrap();
    for (j, v) in a.iter().enumerate() {
        assert_eq!(*v, src[((j * 6) as f64 / 9.0).round() as usize]);
    }
    // A take without annotations propagates nothing.
    let plain = common::random_db(71, &[4, 5], 2, 2, 10.0);
    let x = smooth_track(&mut rng, 12, 2, 10.0);
    let it = interpret(&plain, &x, &params(1.0, 0.1, true)).unwrap();
    assert_eq!(perf_control::propagate(&plain, &it).unwrap(), None);
    // Wrong annotation length is a clear error.
    let mut bad = take;
    bad.annotations = Some(vec![0; 3]);
    assert!(matches!(MappingDb::from_takes(vec![bad], 10.0), Err(PcError::BadParameter { name: "annotations", .. })));
}

/// §7.14: fixed seeds give identical results.
#[test]
fn t14_determinism() {
    let run = || {
        let db = random_db(50, &[4, 5, 6, 5, 4], 2, 2, 10.0);
        let mut rng = Rng::new(51);
        let x = smooth_track(&mut rng, 35, 2, 10.0);
        let mut p = params(5.0, 0.2, true);
        p.beam = Some(0.5);
        let it = interpret(&db, &x, &p).unwrap();
        (chain_of(&it), it.score, target_points(&db, &it, true).unwrap())
    };
    assert_eq!(run(), run());
}

/// §7.15: partial ends at the native rate: a cut training take keeps exact interior segments.
#[test]
fn t15_partial_ends() {
    let db = random_db(60, &[5, 6, 7, 5, 6], 2, 2, 10.0);
    let take = &db.takes[0];
    let n = take.control.len();
    let x = take.control.window(2, n - 4);
    let it = interpret(&db, &x, &params(10.0, 0.0, true)).unwrap();
    assert_eq!(it.segments.len(), 5);
    for (i, s) in it.segments.iter().enumerate() {
        assert_eq!(s.instance, i as u32);
        assert!(s.d <= 1e-9, "segment {i}: D {}", s.d);
    }
    assert!(it.segments[0].start == -2 && it.segments[4].end == x.len() as i64 - 1 + 3);
}

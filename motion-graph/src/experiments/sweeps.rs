//! The library calls of the accuracy-versus-time sweeps of spec §9 (`cargo xtask bench
//! motion-graph`: search budget with the hierarchy on and off, graph density, database size,
//! smoothing window): the benchmark's database and problems, and one batch solve that returns the
//! figures of a sweep point.
//!
//! A problem whose search cannot start or whose best path cannot be assembled is **failed**: it
//! is counted in [`BatchFigures::failed`] and enters the error and skate samples as NaN, so the
//! medians of a sweep point with a failure are NaN instead of silently covering fewer problems
//! (issue 21).
//!
//! ```no_run
//! use motion_graph::experiments::sweeps::{bench_problems, football_graph, solve_batch};
//! use motion_graph::GraphParams;
//! let (g, build_s) = football_graph(20, &GraphParams::default()).unwrap();
//! let f = solve_batch(&g, &bench_problems(3), 0.1, 30);
//! println!("built in {build_s} s; median error {} m, {} failed", f.err_m_median, f.failed);
//! ```

use std::time::{Duration, Instant};

use geom_core::anim::synth::{library, Preset};
use geom_core::math::Planar;
use geom_core::rng::Rng;
use geom_core::stats::percentile;

use crate::assemble::{assemble, enforce_body, evaluate, smooth};
use crate::db::{Database, DbParams};
use crate::graph::{GraphParams, MotionGraph};
use crate::problem::{BodyConstraint, Problem};
use crate::search::{Search, SearchParams};
use crate::Result;

/// The benchmark's graph: `clips` clips of the `Football` preset (150–300 frames at 30 Hz, seed
/// 7), and the seconds spent building database and graph (the clip synthesis excluded).
pub fn football_graph(clips: usize, gp: &GraphParams) -> Result<(MotionGraph, f64)> {
    let lib = library(Preset::Football, clips, (150, 300), 30.0, 7);
    let t = Instant::now();
    let db = Database::from_motions(lib, &DbParams::default())?;
    let g = MotionGraph::build(db, gp)?;
    Ok((g, t.elapsed().as_secs_f64()))
}

/// The benchmark's MG-1-style problems: 300 frames, start at the origin facing +Z, body
/// constraints at frames 100, 200 and 299, each `U(0.3, 0.8) × 4 m/s × 100/30 s` from the
/// previous one with the direction turning by `U(−1, 1)` rad (seed 11; the step uses 100 frames
/// for every segment).
pub fn bench_problems(n: usize) -> Vec<Problem> {
    let mut rng = Rng::new(11);
    (0..n)
        .map(|_| {
            let mut body = vec![BodyConstraint { time: 0, x: 0.0, z: 0.0, yaw: Some(0.0) }];
            let (mut x, mut z, mut dir) = (0.0, 0.0, 0.0f64);
            for t in [100u32, 200, 299] {
                let d = rng.range(0.3, 0.8) * 4.0 * 100.0 / 30.0;
                dir += rng.range(-1.0, 1.0);
                x += d * dir.sin();
                z += d * dir.cos();
                body.push(BodyConstraint { time: t, x, z, yaw: None });
            }
            Problem { length: Some(300), body, ..Default::default() }
        })
        .collect()
}

/// Figures of one sweep point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BatchFigures {
    /// Median over problems of the largest body-constraint error after smoothing, before §3.11
    /// (m); NaN when a problem failed.
    pub err_m_median: f64,
    /// p95 of `J_v` over every cut after smoothing (m/s).
    pub jv_p95: f64,
    /// Median foot skate after §3.11 (cm/s, no contact fix); NaN when a problem failed.
    pub skate_cm_s_median: f64,
    /// Median seconds per search iteration (timing).
    pub s_per_iter_median: f64,
    /// Problems that failed.
    pub failed: usize,
}

/// Solves every problem with the default search (seed `1 + k`) for `budget_s` seconds,
/// assembles from the origin with 6-frame pieces, smooths over ±`window` frames and measures.
pub fn solve_batch(g: &MotionGraph, pbs: &[Problem], budget_s: f64, window: u32) -> BatchFigures {
    let (mut err, mut jv, mut sk, mut per_it) = (vec![], vec![], vec![], vec![]);
    let mut failed = 0;
    for (k, pb) in pbs.iter().enumerate() {
        let sp = SearchParams { rng_seed: 1 + k as u64, ..Default::default() };
        let mut fail = || {
            failed += 1;
            err.push(f64::NAN);
            sk.push(f64::NAN);
        };
        let Ok(mut s) = Search::new(g, pb.clone(), sp) else {
            fail();
            continue;
        };
        let t = Instant::now();
        s.run_for(Duration::from_secs_f64(budget_s));
        per_it.push(t.elapsed().as_secs_f64() / s.iterations().max(1) as f64);
        let Some(mut a) = s.best().and_then(|best| assemble(g, &best.path, Planar::identity(), 6)) else {
            fail();
            continue;
        };
        smooth(&mut a, window);
        let m = evaluate(g, &a, pb);
        err.push(m.body_pos.iter().copied().fold(0.0, geom_core::stats::nan_max));
        jv.extend(m.cut_jumps.iter().map(|j| j.jv));
        enforce_body(&mut a, &pb.body);
        sk.push(evaluate(g, &a, pb).skate.rate_cm_s);
    }
    BatchFigures {
        err_m_median: percentile(&err, 50.0),
        jv_p95: percentile(&jv, 95.0),
        skate_cm_s_median: percentile(&sk, 50.0),
        s_per_iter_median: percentile(&per_it, 50.0),
        failed,
    }
}

//! MG-1 without xtask, for profiling the search (`perf record`) and quick experiments:
//! builds the `Football` database, solves the random MG-1 problems with the parameters of
//! `scenes/motion-graph/football.ron` and prints, per problem, the search time, iterations and
//! the body-constraint errors after smoothing (before §3.11), then the medians and p90s the
//! scene reports, and the database's torso-speed histogram.
//!
//! `cargo run --release -p motion-graph --example mg1 -- [clips] [problems] [budget_s]
//! [max_mutations] [guided_every] [guided_width] [turn_rad] [dist_frac_lo] [edges_per_frame] [one_cut_draws] [slack_m]
//! [per_parent] [keep_best] [population_cap] [regrow_every] [projection_share] [initial_width] [aimed_starts]` (defaults 80, 20, 2,
//! 300, 2, 24, 1, 0.3, 10, 0, 0.15, 4, 2, 32, 2, 0.5, 0, 0.5). Search times are wall-clock; `cpu` is the search thread's CPU time.

use std::time::{Duration, Instant};

use geom_core::anim::metrics::percentile;
use geom_core::anim::synth::{library, Preset};
use geom_core::math::Planar;
use motion_graph::{
    assemble, evaluate, random_mg1, smooth, Database, DbParams, GraphParams, MotionGraph, Search, SearchParams,
    Tolerance, Weights,
};

fn arg<T: std::str::FromStr>(i: usize, default: T) -> T {
    std::env::args().nth(i).and_then(|s| s.parse().ok()).unwrap_or(default)
}

fn main() -> motion_graph::Result<()> {
    let clips: usize = arg(1, 80);
    let n: usize = arg(2, 20);
    let budget = Duration::from_secs_f64(arg(3, 2.0));
    let t = Instant::now();
    let db = Database::from_motions(
        library(Preset::Football, clips, (150, 300), 30.0, 7),
        &DbParams { rate_hz: 30.0, max_clip_frames: 300, ..Default::default() },
    )?;
    let g = MotionGraph::build(
        db,
        &GraphParams { target_edges_per_frame: arg(9, 10.0), min_self_gap: 15, k_max: 16, ..Default::default() },
    )?;
    println!(
        "build {:.2} s, {} frames, {} leaf / {} top edges",
        t.elapsed().as_secs_f64(),
        g.stats.frames,
        g.stats.leaf_edges,
        g.stats.top_edges
    );
    // Torso speed over 0.5 s windows, every 5th frame.
    let mut hist = [0usize; 7];
    for c in 0..g.db.clips.len() as u32 {
        let len = g.clip_len(c);
        for f in (0..len.saturating_sub(15)).step_by(5) {
            let (a, b) = (g.features.torso(c, f), g.features.torso(c, f + 15));
            let v = (b.x - a.x).hypot(b.z - a.z) / 0.5;
            hist[(v as usize).min(6)] += 1;
        }
    }
    println!("torso speed histogram (1 m/s bins, 0..6+): {hist:?}");
    let problems = random_mg1(
        n,
        300,
        30.0,
        (1, 3),
        4.0,
        (arg(8, 0.3), 0.8),
        arg(7, 1.0),
        // `MG1_SEED` draws a different problem set (held-out checks of parameter choices).
        std::env::var("MG1_SEED").ok().and_then(|v| v.parse().ok()).unwrap_or(11),
        Weights::default(),
    );
    let tol = Tolerance::default();
    let sp = SearchParams {
        seeds: 20,
        new_seeds_per_iter: 2,
        keep_best: arg(13, 2),
        population_cap: arg(14, 32),
        max_span: 4,
        max_mutations: arg(4, 300),
        guided: motion_graph::GuidedParams {
            every: arg(5, 2),
            width: arg(6, 24),
            one_cut_draws: arg(10, 0),
            slack_m: arg(11, 0.15),
            per_parent: arg(12, 4),
            regrow_every: arg(15, 2),
            projection_share: arg(16, 0.5),
            initial_width: arg(17, 0),
            aimed_starts: arg(18, 0.5),
            ..Default::default()
        },
        ..Default::default()
    };
    let (mut times, mut errs, mut cpus) = (Vec::new(), Vec::new(), Vec::new());
    for (k, pb) in problems.iter().enumerate() {
        let t0 = Instant::now();
        let c0 = geom_core::clock::thread_cpu_s();
        let mut s = Search::new(&g, pb.clone(), SearchParams { rng_seed: 1 + k as u64, ..sp.clone() })?;
        let mut it = 0;
        let mut met = None;
        while t0.elapsed() < budget && it < 10_000 {
            if s.best().is_some_and(|b| tol.met(b)) {
                met = Some(t0.elapsed().as_secs_f64());
                break;
            }
            s.step();
            it += 1;
            if s.population().is_empty() {
                s.run_until(&tol, Duration::ZERO, 0);
                break;
            }
        }
        let st = met.unwrap_or(t0.elapsed().as_secs_f64());
        times.push(st);
        let cpu = geom_core::clock::thread_cpu_s() - c0;
        cpus.push(cpu);
        let Some(best) = s.best() else { continue };
        let Some(mut a) = assemble(&g, &best.path, Planar::identity(), sp.min_piece_frames) else { continue };
        smooth(&mut a, 30);
        let m = evaluate(&g, &a, pb);
        let chord: Vec<String> = pb
            .body
            .windows(2)
            .map(|w| {
                let d = (w[1].x - w[0].x).hypot(w[1].z - w[0].z);
                format!("{:.1}", d / ((w[1].time - w[0].time) as f64 / 30.0))
            })
            .collect();
        let e: Vec<String> = m.body_pos.iter().skip(1).map(|x| format!("{x:.2}")).collect();
        println!(
            "problem {k:2}: {st:.3} s (cpu {cpu:.3}), {it:4} it, met {}, pieces {:2}, chord m/s [{}], err m [{}]",
            met.is_some(),
            best.path.cuts.len() + 1,
            chord.join(" "),
            e.join(" ")
        );
        errs.extend(m.body_pos.iter().skip(1).copied());
    }
    println!(
        "search_s median {:.3} p90 {:.3} (cpu median {:.3}); err_before p90 {:.3} m",
        percentile(&times, 50.0),
        percentile(&times, 90.0),
        percentile(&cpus, 50.0),
        percentile(&errs, 90.0)
    );
    Ok(())
}

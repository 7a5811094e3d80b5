//! `cargo xtask bench motion-graph` (spec §9): search budget against constraint error with the
//! hierarchy on and off (`mg_anytime`), graph density (`mg_density`), database size
//! (`mg_scale`) and smoothing window (`mg_window`). CSV and PNG per sweep.

use std::time::{Duration, Instant};

use geom_core::anim::metrics::percentile;
use geom_core::anim::synth::{library, Preset};
use geom_core::math::Planar;
use geom_core::rng::Rng;
use motion_graph::{
    assemble, enforce_body, evaluate, smooth, BodyConstraint, Database, DbParams, GraphParams, MotionGraph, Problem,
    Search, SearchParams,
};

use crate::error::{Error, Result};
use crate::out::{Cell, CsvWriter, Summary};
use crate::plot::{LinePlot, Series};
use crate::registry::BenchCtx;

fn mg<T>(r: motion_graph::Result<T>) -> Result<T> {
    r.map_err(|e| Error::Run(format!("motion-graph: {e}")))
}

fn build(clips: usize, gp: &GraphParams) -> Result<(MotionGraph, f64)> {
    let lib = library(Preset::Football, clips, (150, 300), 30.0, 7);
    let t = Instant::now();
    let db = mg(Database::from_motions(lib, &DbParams::default()))?;
    let g = mg(MotionGraph::build(db, gp))?;
    Ok((g, t.elapsed().as_secs_f64()))
}

/// MG-1-style problems: 300 frames, two intermediate constraints reachable at 4 m/s.
fn problems(n: usize) -> Vec<Problem> {
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

/// Median body error before correction, splice J_v p95 (m/s), skate median (cm/s) and mean
/// seconds per iteration at a time budget.
fn solve(g: &MotionGraph, pbs: &[Problem], budget: f64, window: u32) -> (f64, f64, f64, f64) {
    let (mut err, mut jv, mut sk, mut per_it) = (vec![], vec![], vec![], vec![]);
    for (k, pb) in pbs.iter().enumerate() {
        let sp = SearchParams { rng_seed: 1 + k as u64, ..Default::default() };
        let Ok(mut s) = Search::new(g, pb.clone(), sp) else { continue };
        let t = Instant::now();
        s.run_for(Duration::from_secs_f64(budget));
        per_it.push(t.elapsed().as_secs_f64() / s.iterations().max(1) as f64);
        let Some(best) = s.best() else { continue };
        let Some(mut a) = assemble(g, &best.path, Planar::identity(), 6) else { continue };
        smooth(&mut a, window);
        let m = evaluate(g, &a, pb);
        err.push(m.body_pos.iter().copied().fold(0.0, f64::max));
        jv.extend(m.cut_jumps.iter().map(|j| j.jv));
        enforce_body(&mut a, &pb.body);
        sk.push(evaluate(g, &a, pb).skate.rate_cm_s);
    }
    (percentile(&err, 50.0), percentile(&jv, 95.0), percentile(&sk, 50.0), percentile(&per_it, 50.0))
}

/// Runs the four sweeps.
pub fn run(ctx: &BenchCtx) -> Result<Summary> {
    let q = ctx.quick;
    let out = &ctx.out_dir;
    let mut sum = Summary::new();
    let n_clips = if q { 20 } else { 80 };
    let pbs = problems(if q { 3 } else { 10 });
    let gp = GraphParams { calibration_pairs: if q { 100_000 } else { 1_000_000 }, ..Default::default() };
    // mg_anytime: hierarchy on / off.
    let (g_on, _) = build(n_clips, &gp)?;
    let (g_off, _) = build(n_clips, &GraphParams { hierarchy: false, ..gp.clone() })?;
    let budgets: Vec<f64> = if q { vec![0.02, 0.1, 0.3] } else { vec![0.01, 0.03, 0.1, 0.3, 1.0, 3.0] };
    let mut csv = CsvWriter::create(
        &out.join("mg_anytime.csv"),
        &["budget_s", "hierarchy", "err_m_median", "jv_p95", "s_per_iter"],
    )?;
    let mut on = vec![];
    let mut off = vec![];
    for &b in &budgets {
        for (h, g, v) in [(1, &g_on, &mut on), (0, &g_off, &mut off)] {
            let (e, jv, _, it) = solve(g, &pbs, b, 30);
            csv.row(&[Cell::Num(b), Cell::Int(h), Cell::Num(e), Cell::Num(jv), Cell::Num(it)])?;
            v.push((b, e));
        }
    }
    sum.set("anytime_err_m_at_max_budget_hierarchy", on.last().map_or(0.0, |x| x.1));
    sum.set("anytime_err_m_at_max_budget_leaves", off.last().map_or(0.0, |x| x.1));
    LinePlot::new("mg_anytime: body error vs search budget", "budget (s)", "median max error (m)")
        .log(true, false)
        .with(Series::new("hierarchy", on))
        .with(Series::new("leaf edges only", off))
        .write_png(&out.join("mg_anytime.png"))?;
    // mg_density.
    let dens: Vec<f64> = if q { vec![2.0, 10.0] } else { vec![2.0, 5.0, 10.0, 20.0, 40.0] };
    let mut csv = CsvWriter::create(
        &out.join("mg_density.csv"),
        &["edges_per_frame", "build_s", "leaf_edges", "top_edges", "err_m_median", "jv_p95", "skate_cm_s"],
    )?;
    let (mut pe, mut pj) = (vec![], vec![]);
    for &d in &dens {
        let (g, bs) = build(n_clips, &GraphParams { target_edges_per_frame: d, ..gp.clone() })?;
        let (e, jv, sk, _) = solve(&g, &pbs, if q { 0.1 } else { 0.5 }, 30);
        let st = g.stats();
        csv.row(&[
            Cell::Num(d),
            Cell::Num(bs),
            Cell::Int(st.leaf_edges as i64),
            Cell::Int(st.top_edges as i64),
            Cell::Num(e),
            Cell::Num(jv),
            Cell::Num(sk),
        ])?;
        pe.push((d, e));
        pj.push((d, jv));
    }
    LinePlot::new("mg_density: error and splice jump vs edges per frame", "edges per frame", "value")
        .with(Series::new("median error (m)", pe))
        .with(Series::new("splice J_v p95 (m/s)", pj))
        .write_png(&out.join("mg_density.png"))?;
    // mg_scale.
    let sizes: Vec<usize> = if q { vec![10, 20] } else { vec![20, 40, 60, 80, 100] };
    let mut csv =
        CsvWriter::create(&out.join("mg_scale.csv"), &["clips", "frames", "build_s", "s_per_iter", "err_m_median"])?;
    let (mut pb_, mut pi) = (vec![], vec![]);
    for &n in &sizes {
        let (g, bs) = build(n, &gp)?;
        let (e, _, _, it) = solve(&g, &pbs, if q { 0.1 } else { 0.5 }, 30);
        csv.row(&[
            Cell::Int(n as i64),
            Cell::Int(g.stats().frames as i64),
            Cell::Num(bs),
            Cell::Num(it),
            Cell::Num(e),
        ])?;
        pb_.push((n as f64, bs));
        pi.push((n as f64, it * 1000.0));
    }
    if let (Some(a), Some(b)) = (pi.first(), pi.last()) {
        if a.1 > 0.0 && b.0 > a.0 {
            sum.set("iteration_time_scaling_exponent", (b.1 / a.1).ln() / (b.0 / a.0).ln());
        }
    }
    LinePlot::new("mg_scale: build time and time per iteration vs clips", "clips", "s / ms")
        .log(true, true)
        .with(Series::new("build (s)", pb_))
        .with(Series::new("iteration (ms)", pi))
        .write_png(&out.join("mg_scale.png"))?;
    // mg_window.
    let wins: Vec<u32> = if q { vec![0, 10, 30] } else { vec![0, 5, 10, 20, 30, 45] };
    let mut csv = CsvWriter::create(&out.join("mg_window.csv"), &["window", "jv_p95", "skate_cm_s"])?;
    let (mut wj, mut ws) = (vec![], vec![]);
    for &w in &wins {
        let (_, jv, sk, _) = solve(&g_on, &pbs, if q { 0.1 } else { 0.5 }, w);
        csv.row(&[Cell::Int(w as i64), Cell::Num(jv), Cell::Num(sk)])?;
        wj.push((w as f64, jv));
        ws.push((w as f64, sk));
    }
    LinePlot::new("mg_window: splice J_v p95 and skate vs smoothing half-width", "W (frames)", "value")
        .with(Series::new("J_v p95 (m/s)", wj))
        .with(Series::new("skate (cm/s)", ws))
        .write_png(&out.join("mg_window.png"))?;
    Ok(sum)
}

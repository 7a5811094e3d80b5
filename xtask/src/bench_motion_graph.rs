//! `cargo xtask bench motion-graph` (spec §9): search budget against constraint error with the
//! hierarchy on and off (`mg_anytime`), graph density (`mg_density`), database size
//! (`mg_scale`) and smoothing window (`mg_window`). CSV and PNG per sweep; every point is one
//! call of [`motion_graph::experiments::sweeps::solve_batch`] (failed problems are counted in the
//! `failed` column and make the point's error NaN).

use motion_graph::experiments::sweeps::{bench_problems, football_graph, solve_batch};
use motion_graph::GraphParams;

use crate::error::Result;
use crate::out::{Cell, CsvWriter, Summary};
use crate::plot::{LinePlot, Series};
use crate::registry::BenchCtx;

/// Runs the four sweeps.
pub fn run(ctx: &BenchCtx) -> Result<Summary> {
    let q = ctx.quick;
    let out = &ctx.out_dir;
    let mut sum = Summary::new();
    let n_clips = if q { 20 } else { 80 };
    let pbs = bench_problems(if q { 3 } else { 10 });
    let gp = GraphParams { calibration_pairs: if q { 100_000 } else { 1_000_000 }, ..Default::default() };
    let mut failed = 0usize;
    // mg_anytime: hierarchy on / off.
    let (g_on, _) = football_graph(n_clips, &gp)?;
    let (g_off, _) = football_graph(n_clips, &GraphParams { hierarchy: false, ..gp.clone() })?;
    let budgets: Vec<f64> = if q { vec![0.02, 0.1, 0.3] } else { vec![0.01, 0.03, 0.1, 0.3, 1.0, 3.0] };
    let mut csv = CsvWriter::create(
        &out.join("mg_anytime.csv"),
        &["budget_s", "hierarchy", "err_m_median", "jv_p95", "s_per_iter", "failed"],
    )?;
    let mut on = vec![];
    let mut off = vec![];
    for &b in &budgets {
        for (h, g, v) in [(1, &g_on, &mut on), (0, &g_off, &mut off)] {
            let f = solve_batch(g, &pbs, b, 30);
            csv.row(&[
                Cell::Num(b),
                Cell::Int(h),
                Cell::Num(f.err_m_median),
                Cell::Num(f.jv_p95),
                Cell::Num(f.s_per_iter_median),
                Cell::Int(f.failed as i64),
            ])?;
            failed += f.failed;
            v.push((b, f.err_m_median));
        }
    }
    sum.set("anytime_err_m_at_max_budget_hierarchy", on.last().map_or(f64::NAN, |x| x.1));
    sum.set("anytime_err_m_at_max_budget_leaves", off.last().map_or(f64::NAN, |x| x.1));
    LinePlot::new("mg_anytime: body error vs search budget", "budget (s)", "median max error (m)")
        .log(true, false)
        .with(Series::new("hierarchy", on))
        .with(Series::new("leaf edges only", off))
        .write_png(&out.join("mg_anytime.png"))?;
    // mg_density.
    let dens: Vec<f64> = if q { vec![2.0, 10.0] } else { vec![2.0, 5.0, 10.0, 20.0, 40.0] };
    let mut csv = CsvWriter::create(
        &out.join("mg_density.csv"),
        &["edges_per_frame", "build_s", "leaf_edges", "top_edges", "err_m_median", "jv_p95", "skate_cm_s", "failed"],
    )?;
    let (mut pe, mut pj) = (vec![], vec![]);
    for &d in &dens {
        let (g, bs) = football_graph(n_clips, &GraphParams { target_edges_per_frame: d, ..gp.clone() })?;
        let f = solve_batch(&g, &pbs, if q { 0.1 } else { 0.5 }, 30);
        let st = g.stats();
        csv.row(&[
            Cell::Num(d),
            Cell::Num(bs),
            Cell::Int(st.leaf_edges as i64),
            Cell::Int(st.top_edges as i64),
            Cell::Num(f.err_m_median),
            Cell::Num(f.jv_p95),
            Cell::Num(f.skate_cm_s_median),
            Cell::Int(f.failed as i64),
        ])?;
        failed += f.failed;
        pe.push((d, f.err_m_median));
        pj.push((d, f.jv_p95));
    }
    LinePlot::new("mg_density: error and splice jump vs edges per frame", "edges per frame", "value")
        .with(Series::new("median error (m)", pe))
        .with(Series::new("splice J_v p95 (m/s)", pj))
        .write_png(&out.join("mg_density.png"))?;
    // mg_scale.
    let sizes: Vec<usize> = if q { vec![10, 20] } else { vec![20, 40, 60, 80, 100] };
    let mut csv = CsvWriter::create(
        &out.join("mg_scale.csv"),
        &["clips", "frames", "build_s", "s_per_iter", "err_m_median", "failed"],
    )?;
    let (mut pb_, mut pi) = (vec![], vec![]);
    for &n in &sizes {
        let (g, bs) = football_graph(n, &gp)?;
        let f = solve_batch(&g, &pbs, if q { 0.1 } else { 0.5 }, 30);
        csv.row(&[
            Cell::Int(n as i64),
            Cell::Int(g.stats().frames as i64),
            Cell::Num(bs),
            Cell::Num(f.s_per_iter_median),
            Cell::Num(f.err_m_median),
            Cell::Int(f.failed as i64),
        ])?;
        failed += f.failed;
        pb_.push((n as f64, bs));
        pi.push((n as f64, f.s_per_iter_median * 1000.0));
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
    let mut csv = CsvWriter::create(&out.join("mg_window.csv"), &["window", "jv_p95", "skate_cm_s", "failed"])?;
    let (mut wj, mut ws) = (vec![], vec![]);
    for &w in &wins {
        let f = solve_batch(&g_on, &pbs, if q { 0.1 } else { 0.5 }, w);
        csv.row(&[
            Cell::Int(w as i64),
            Cell::Num(f.jv_p95),
            Cell::Num(f.skate_cm_s_median),
            Cell::Int(f.failed as i64),
        ])?;
        failed += f.failed;
        wj.push((w as f64, f.jv_p95));
        ws.push((w as f64, f.skate_cm_s_median));
    }
    LinePlot::new("mg_window: splice J_v p95 and skate vs smoothing half-width", "W (frames)", "value")
        .with(Series::new("J_v p95 (m/s)", wj))
        .with(Series::new("skate (cm/s)", ws))
        .write_png(&out.join("mg_window.png"))?;
    // Problems that failed over all sweep points (issue 21: counted, never dropped).
    sum.set_count("problems_failed", failed as u64);
    Ok(sum)
}

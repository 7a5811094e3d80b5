//! `cargo xtask bench flip-tet` (spec §9): accuracy against time for
//! (a) finest resolution (dam break, RMS front error vs Martin & Moyce 1952),
//! (b) adaptivity levels at a fixed finest resolution (coarsest = finest … 8; same error),
//! (c) solver and tolerance (rest pool: max speed and level-set volume drift; direct vs
//!     MIC(0)-PCG at tolerances 1e−2 … 1e−8),
//! (d) free-surface boundary order (first vs second order; dam-break front error, and with the
//!     full sweep the standing-wave period error).
//! Writes `accuracy_vs_time.csv`, `pareto.png` and returns summary figures.

use std::path::Path;

use flip_tet::error::SolverKind;
use flip_tet::metrics;
use flip_tet::scene::Scene;

use crate::error::Result;
use crate::out::{Cell, CsvWriter, Summary};
use crate::plot::{LinePlot, Series};
use crate::registry::BenchCtx;
use crate::scene::{scenes_dir, Mode};
use crate::scenes::flip_tet::{front_errors, load_file, simulate, FrameOutput};

struct Row {
    knob: &'static str,
    value: String,
    wall: f64,
    steps: usize,
    particles: f64,
    metric: &'static str,
    error: f64,
}

fn dam_break(scene: &Scene, dir: &Path) -> Result<(f64, f64, usize, f64)> {
    let a = match scene.liquid.first() {
        Some(flip_tet::scene::Shape::Box { min, max }) => max[0] - min[0],
        _ => 0.05715,
    };
    let g = -scene.gravity[1];
    let mut front = Vec::new();
    let (stats, wall, _) = simulate(scene, dir, FrameOutput { obj: 0, ply: 0 }, &mut |sim, st| {
        front.push((st.t * (2.0 * g / a).sqrt(), metrics::front_position(sim.particles(), scene.domain.min[0]) / a));
    })?;
    let (_, rms) = front_errors(&front);
    let pavg = stats.iter().map(|x| x.n_particles as f64).sum::<f64>() / stats.len().max(1) as f64;
    Ok((rms, wall, stats.len(), pavg))
}

fn rest(scene: &Scene, dir: &Path) -> Result<(f64, f64, f64, usize)> {
    let (stats, wall, _) = simulate(scene, dir, FrameOutput { obj: 0, ply: 0 }, &mut |_, _| {})?;
    let vmax = stats.iter().map(|x| x.max_speed).fold(0.0, f64::max);
    let v0 = stats.first().map_or(1.0, |x| x.vol_levelset);
    let drift = stats.iter().map(|x| (x.vol_levelset - v0).abs()).fold(0.0, f64::max) / v0.max(1e-300);
    Ok((vmax, drift, wall, stats.len()))
}

fn wave(scene: &Scene, dir: &Path) -> Result<(f64, f64, usize)> {
    let (mean, len) = match scene.liquid.first() {
        Some(flip_tet::scene::Shape::CosineSurface { mean, length, .. }) => (*mean, *length),
        _ => (0.5, 1.0),
    };
    let k = std::f64::consts::PI / len;
    let g = -scene.gravity[1];
    let t_th = 2.0 * std::f64::consts::PI / (g * k * (k * (mean - scene.domain.min[1])).tanh()).sqrt();
    let zc = 0.5 * (scene.domain.min[2] + scene.domain.max[2]);
    let mut eta = Vec::new();
    let (stats, wall, _) = simulate(scene, dir, FrameOutput { obj: 0, ply: 0 }, &mut |sim, st| {
        if let Some(h) = metrics::surface_height(sim, scene.domain.min[0] + sim.spec().h_min() / 2.0, zc) {
            eta.push((st.t, h));
        }
    })?;
    let p = metrics::zero_crossing_period(&eta, 0.5 * t_th).map_or(f64::NAN, |p| (p - t_th).abs() / t_th);
    Ok((p, wall, stats.len()))
}

/// The benchmark entry point.
pub fn run(ctx: &BenchCtx) -> Result<Summary> {
    let dir = scenes_dir().join("flip-tet");
    let mode = if ctx.quick { Mode::Quick } else { Mode::Default };
    let mut rows: Vec<Row> = Vec::new();
    let mut summary = Summary::new();
    summary.set_str("profile", if cfg!(debug_assertions) { "debug" } else { "release" });
    let tmp = ctx.out_dir.join("runs");

    // (a) resolution (dam break).
    let (_, dam) = load_file(&dir.join("dam-break.ron"), mode)?;
    let res: &[u32] = if ctx.quick { &[16, 32] } else { &[16, 32, 64] };
    for &n in res {
        let mut s = dam.clone();
        s.resolution.finest = n;
        let (rms, wall, steps, p) = dam_break(&s, &tmp.join(format!("res_{n}")))?;
        rows.push(Row {
            knob: "resolution",
            value: n.to_string(),
            wall,
            steps,
            particles: p,
            metric: "front_rms_rel_err",
            error: rms,
        });
        summary.set(&format!("dam_front_rms_finest_{n}"), rms);
    }
    // (b) levels at fixed finest.
    let finest = if ctx.quick { 32 } else { 64 };
    for coarsest in [finest, finest / 2, 8] {
        let mut s = dam.clone();
        s.resolution.finest = finest;
        s.resolution.coarsest = coarsest;
        let (rms, wall, steps, p) = dam_break(&s, &tmp.join(format!("levels_{coarsest}")))?;
        rows.push(Row {
            knob: "levels",
            value: format!("{coarsest}-{finest}"),
            wall,
            steps,
            particles: p,
            metric: "front_rms_rel_err",
            error: rms,
        });
    }
    // (c) solver / tolerance (rest pool).
    let (_, pool) = load_file(&dir.join("rest-pool.ron"), Mode::Quick)?;
    let tols: &[f64] = if ctx.quick { &[1e-2, 1e-6] } else { &[1e-2, 1e-3, 1e-4, 1e-6, 1e-8] };
    let mut variants: Vec<(String, SolverKind, f64)> = vec![("direct".into(), SolverKind::DirectCholesky, 1e-6)];
    variants.extend(tols.iter().map(|&t| (format!("mic_pcg_{t:e}"), SolverKind::PcgIc0, t)));
    for (name, kind, tol) in variants {
        let mut s = pool.clone();
        s.pressure.solver = kind;
        s.pressure.tol = tol;
        let (vmax, drift, wall, steps) = rest(&s, &tmp.join(format!("tol_{name}")))?;
        rows.push(Row {
            knob: "solver_tol",
            value: name.clone(),
            wall,
            steps,
            particles: 0.0,
            metric: "rest_max_speed",
            error: vmax,
        });
        rows.push(Row {
            knob: "solver_tol",
            value: name.clone(),
            wall,
            steps,
            particles: 0.0,
            metric: "rest_volume_drift_rel",
            error: drift,
        });
        summary.set(&format!("rest_max_speed_{name}"), vmax);
    }
    // (d) boundary order.
    for second in [true, false] {
        let mut s = dam.clone();
        s.resolution.finest = 32;
        s.pressure.second_order = second;
        let tag = if second { "second" } else { "first" };
        let (rms, wall, steps, p) = dam_break(&s, &tmp.join(format!("bc_{tag}")))?;
        rows.push(Row {
            knob: "bc_order",
            value: tag.into(),
            wall,
            steps,
            particles: p,
            metric: "front_rms_rel_err",
            error: rms,
        });
        summary.set(&format!("dam_front_rms_{tag}_order"), rms);
        if !ctx.quick {
            let (_, w) = load_file(&dir.join("standing-wave.ron"), Mode::Quick)?;
            let mut w = w;
            w.pressure.second_order = second;
            let (perr, wall, steps) = wave(&w, &tmp.join(format!("wave_{tag}")))?;
            rows.push(Row {
                knob: "bc_order",
                value: tag.into(),
                wall,
                steps,
                particles: 0.0,
                metric: "wave_period_rel_err",
                error: perr,
            });
            summary.set(&format!("wave_period_rel_err_{tag}_order"), perr);
        }
    }
    let mut csv = CsvWriter::create(
        &ctx.out_dir.join("accuracy_vs_time.csv"),
        &["knob", "value", "wall_s", "steps", "particles_avg", "metric", "error"],
    )?;
    for r in &rows {
        csv.row(&[
            Cell::Text(r.knob.into()),
            Cell::Text(r.value.clone()),
            Cell::Num(r.wall),
            Cell::Int(r.steps as i64),
            Cell::Num(r.particles),
            Cell::Text(r.metric.into()),
            Cell::Num(r.error),
        ])?;
    }
    let mut plot =
        LinePlot::new("flip-tet: dam-break front error vs wall time", "wall time (s)", "RMS relative front error")
            .log(true, true);
    for knob in ["resolution", "levels", "bc_order"] {
        let pts: Vec<(f64, f64)> = rows
            .iter()
            .filter(|r| r.knob == knob && r.metric == "front_rms_rel_err")
            .map(|r| (r.wall, r.error.max(1e-6)))
            .collect();
        plot = plot.with(Series::new(knob, pts));
    }
    plot.write_png(&ctx.out_dir.join("pareto.png"))?;
    let pts: Vec<(f64, f64)> =
        rows.iter().filter(|r| r.metric == "rest_max_speed").map(|r| (r.wall, r.error.max(1e-18))).collect();
    LinePlot::new(
        "flip-tet: rest-pool max speed vs wall time (direct, MIC-PCG tolerances)",
        "wall time (s)",
        "max speed (m/s)",
    )
    .log(true, true)
    .with(Series::new("solver/tolerance", pts))
    .write_png(&ctx.out_dir.join("solver_tol.png"))?;
    Ok(summary)
}

//! `cargo xtask bench shells`: accuracy versus time of the shell integrator (shells.md §9).
//!
//! Sweeps substeps × Newton iterations × Hessian mode on `drape` (collisions off, so the error
//! measures the integrator) and `wind-flag`, each against a fine reference of the same scene
//! (16× the default substeps, 20 Newton iterations with line search, ProjectedEigen). Error: mass-
//! weighted RMS vertex distance at the end time over the bounding-box diagonal. Writes
//! `accuracy.csv`, `accuracy.png` (error vs ms/frame) and the summary.

use std::time::Instant;

use geom_core::math::Pt3;
use shells::scene::{MeshSpec, ShellScene};
use shells::{HessianMode, ShellSim};

use crate::error::{Error, Result};
use crate::out::{Cell, CsvWriter, Summary};
use crate::plot::{LinePlot, Series};
use crate::registry::BenchCtx;
use crate::scenes::shells::{DrapeParams, WindParams};

fn err(e: shells::Error) -> Error {
    Error::Run(format!("shells: {e}"))
}

/// Simulates `shell` for `duration` seconds; returns (final positions, masses, ms per frame,
/// regularisations).
fn simulate(shell: &ShellScene, duration: f64) -> Result<(Vec<Pt3>, Vec<f64>, f64, u32)> {
    let b = shell.build(&crate::out::workspace_root()).map_err(err)?;
    let mut sim = ShellSim::new(b.desc).map_err(err)?;
    let h = shell.integrator.h();
    let frames = (duration * shell.integrator.fps).round() as usize;
    let mut regs = 0;
    let t0 = Instant::now();
    for _ in 0..frames * shell.integrator.substeps as usize {
        let st = sim.step(h).map_err(err)?;
        regs += (st.regularization_shift > 0.0) as u32;
    }
    let ms = 1e3 * t0.elapsed().as_secs_f64() / frames.max(1) as f64;
    Ok((sim.state().q.clone(), sim.mesh().mass.clone(), ms, regs))
}

fn error(a: &[Pt3], b: &[Pt3], m: &[f64]) -> f64 {
    let mt: f64 = m.iter().sum();
    let rms = (a.iter().zip(b).zip(m).map(|((x, y), w)| w * (x - y).norm_squared()).sum::<f64>() / mt).sqrt();
    let diag = geom_core::mesh::bbox_of(b).map(|(lo, hi)| (hi - lo).norm()).unwrap_or(1.0);
    rms / diag
}

fn set_grid(s: &mut ShellScene, nx: u32, ny: u32) {
    if let MeshSpec::Grid { nx: a, ny: b, .. } = &mut s.mesh {
        *a = nx;
        *b = ny;
    }
}

/// The benchmark entry point.
pub fn run(ctx: &BenchCtx) -> Result<Summary> {
    let dir = crate::scene::scenes_dir().join("shells");
    let drape: DrapeParams = crate::scene::load(&dir.join("drape.ron"))?.params;
    let wind: WindParams = crate::scene::load(&dir.join("wind-flag.ron"))?.params;
    let mut d = drape.shell.clone();
    d.effects.collision = None;
    d.effects.self_collision = false;
    let mut w = wind.shell.clone();
    let (duration, subs, iters): (f64, Vec<u32>, Vec<u32>) =
        if ctx.quick { (0.5, vec![1, 4], vec![1]) } else { (1.0, vec![1, 2, 4, 8, 16], vec![1, 3]) };
    if ctx.quick {
        set_grid(&mut d, 9, 9);
        set_grid(&mut w, 9, 7);
    } else {
        set_grid(&mut d, 17, 17);
        set_grid(&mut w, 13, 9);
    }
    let mut csv = CsvWriter::create(
        &ctx.out_dir.join("accuracy.csv"),
        &["scene", "substeps", "newton_iters", "hessian", "ms_per_frame", "rel_error", "regularizations"],
    )?;
    let mut s = Summary::new();
    let mut plot = LinePlot::new("shells: error vs cost", "ms per frame", "RMS error / bbox diagonal").log(true, true);
    for (name, base) in [("drape", d), ("wind-flag", w)] {
        let mut reference = base.clone();
        reference.integrator.substeps = base.integrator.substeps * if ctx.quick { 4 } else { 16 };
        reference.integrator.newton_iters = 20;
        reference.integrator.line_search = true;
        reference.integrator.hessian = HessianMode::ProjectedEigen;
        let (qr, m, ms_ref, _) = simulate(&reference, duration)?;
        s.set(&format!("{name}_reference_ms_per_frame"), ms_ref);
        let mut best: Option<(f64, f64, String)> = None;
        for mode in [HessianMode::ProjectedCheap, HessianMode::ProjectedEigen] {
            for &it in &iters {
                let mut pts = Vec::new();
                for &sub in &subs {
                    let mut c = base.clone();
                    c.integrator.substeps = sub;
                    c.integrator.newton_iters = it;
                    c.integrator.hessian = mode;
                    let (q, _, ms, regs) = simulate(&c, duration)?;
                    let e = error(&q, &qr, &m);
                    csv.row(&[
                        Cell::Text(name.into()),
                        Cell::Int(sub as i64),
                        Cell::Int(it as i64),
                        Cell::Text(format!("{mode:?}")),
                        Cell::Num(ms),
                        Cell::Num(e),
                        Cell::Int(regs as i64),
                    ])?;
                    pts.push((ms, e));
                    // Cheapest configuration within 1e-2 error.
                    if e < 1e-2 && best.as_ref().is_none_or(|b| ms < b.0) {
                        best = Some((ms, e, format!("{mode:?} x{it} substeps {sub}")));
                    }
                }
                plot = plot.with(Series::new(format!("{name} {mode:?} newton {it}"), pts));
            }
        }
        if let Some((ms, e, cfg)) = best {
            s.set(&format!("{name}_best_ms_per_frame_err_1e-2"), ms);
            s.set(&format!("{name}_best_err"), e);
            s.set_str(&format!("{name}_best_config"), &cfg);
        }
    }
    plot.write_png(&ctx.out_dir.join("accuracy.png"))?;
    s.set("duration_s", duration);
    s.set_str("profile", if cfg!(debug_assertions) { "dev" } else { "release" });
    Ok(s)
}

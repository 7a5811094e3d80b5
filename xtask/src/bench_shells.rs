//! `cargo xtask bench shells`: accuracy versus time of the shell integrator (shells.md §9).
//!
//! Sweeps substeps × Newton iterations × Hessian mode on `drape` (collisions off, so the error
//! measures the integrator) and `wind-flag`, each against a fine reference of the same scene
//! (16× the default substeps, 20 Newton iterations with line search, ProjectedEigen). Error: mass-
//! weighted RMS vertex distance at the end time over the bounding-box diagonal. Writes
//! `accuracy.csv`, `accuracy.png` (error vs ms/frame) and the summary. The runs, the reference
//! and the error are `shells::experiments::accuracy` and `shells::metrics`.

use shells::experiments::{accuracy, drape, wind_flag};
use shells::scene::{MeshSpec, ShellScene};
use shells::HessianMode;

use crate::error::Result;
use crate::out::{Cell, CsvWriter, Summary};
use crate::plot::{LinePlot, Series};
use crate::registry::BenchCtx;

fn set_grid(s: &mut ShellScene, nx: u32, ny: u32) {
    if let MeshSpec::Grid { nx: a, ny: b, .. } = &mut s.mesh {
        *a = nx;
        *b = ny;
    }
}

/// The benchmark entry point.
pub fn run(ctx: &BenchCtx) -> Result<Summary> {
    let dir = crate::scene::scenes_dir().join("shells");
    let drape: drape::Params = crate::scene::load(&dir.join("drape.ron"))?.params;
    let wind: wind_flag::Params = crate::scene::load(&dir.join("wind-flag.ron"))?.params;
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
        let fine = accuracy::simulate(&accuracy::reference(&base, if ctx.quick { 4 } else { 16 }), duration)?;
        s.set(&format!("{name}_reference_ms_per_frame"), fine.ms_per_frame);
        let mut best: Option<(f64, f64, String)> = None;
        for mode in [HessianMode::ProjectedCheap, HessianMode::ProjectedEigen] {
            for &it in &iters {
                let mut pts = Vec::new();
                for &sub in &subs {
                    let r = accuracy::simulate(&accuracy::configured(&base, sub, it, mode), duration)?;
                    let e = shells::metrics::rms_distance_rel(&r.q, &fine.q, &fine.mass);
                    csv.row(&[
                        Cell::Text(name.into()),
                        Cell::Int(sub as i64),
                        Cell::Int(it as i64),
                        Cell::Text(format!("{mode:?}")),
                        Cell::Num(r.ms_per_frame),
                        Cell::Num(e),
                        Cell::Int(r.regularizations as i64),
                    ])?;
                    pts.push((r.ms_per_frame, e));
                    // Cheapest configuration within 1e-2 error.
                    if e < 1e-2 && best.as_ref().is_none_or(|b| r.ms_per_frame < b.0) {
                        best = Some((r.ms_per_frame, e, format!("{mode:?} x{it} substeps {sub}")));
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

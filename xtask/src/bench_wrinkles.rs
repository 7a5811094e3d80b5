//! `cargo xtask bench wrinkles` (spec §9): accuracy against time for the knobs of the wrinkle
//! pipeline on a 0.5 m sheet (12² quads = 288 triangles; quick: 6² = 72) carrying a `Folds`
//! pattern, gathered towards the top edge:
//! (a) `precompute.tolerance` 1e-2 … 1e-6 — precompute ms against the max relative C4 error vs a
//!     τ = 1e-8 reference;
//! (b) `gradient_bins` K ∈ {8, 18, 32, 72, 128, 0 = all} — exact-mode ms per frame against the
//!     max relative h error vs K = 0;
//! (c) mode Linearized vs ExactFlatRest vs PrincipalLength — ms per frame against the mean
//!     per-triangle area residual (against each mode's own target);
//! (d) smoothing VertexAverage vs AreaConsistent — ms per frame against the mean rendered area
//!     residual |A_rendered − A*|/A* (degree-5 rule on 4² sub-triangles);
//! (e) displaced-mesh level L ∈ {2, 4, 8, 16} — ms per mesh against the relative surface-area
//!     error vs L = 32.
//! Writes `bench.csv` and `pareto.png` (error against ms, one series per knob).

use std::time::Instant;

use geom_core::math::Pt3;
use geom_core::stats::max;
use wrinkles::metrics::relative_errors;
use wrinkles::presets::{folds, gather, sheet};
use wrinkles::{
    precompute, AreaCheck, AreaReport, HMax, ModulationMode, ModulationOptions, PrecomputeOptions, Smoothing,
    StrainMeasure, VertexWeights, WrinkleAnimator, WrinkleRig,
};

use crate::error::Result;
use crate::out::{Cell, CsvWriter, Summary};
use crate::plot::{LinePlot, Series};
use crate::registry::BenchCtx;

/// Mean seconds of `f`, repeated for at least `min` seconds (and twice).
fn time_it(min: f64, mut f: impl FnMut() -> Result<()>) -> Result<f64> {
    f()?;
    let t0 = Instant::now();
    let mut n = 0usize;
    while n < 2 || t0.elapsed().as_secs_f64() < min {
        f()?;
        n += 1;
    }
    Ok(t0.elapsed().as_secs_f64() / n as f64)
}

/// Mean seconds per `frame` of a fresh animator with options `o` on the deformed positions `def`,
/// and the area report of the last frame.
fn timed_frame(
    rig: &WrinkleRig,
    o: ModulationOptions,
    def: &[Pt3],
    min_t: f64,
    check: AreaCheck,
) -> Result<(f64, AreaReport)> {
    let mut a = WrinkleAnimator::new(rig.clone(), o)?;
    let mut fm = None;
    let secs = time_it(min_t, || {
        fm = Some(a.frame(def)?);
        Ok(())
    })?;
    let fm = fm.expect("time_it runs the frame at least once");
    Ok((secs, a.area_report(def, &fm, check)?))
}

/// Records one per-frame measurement of knob `(knob, name)`: a CSV row, the summary keys
/// `ms_per_frame_{name}` and `{error_key}_{name}`, and a point (ms, error) of the knob's series.
fn record_frame(
    csv: &mut CsvWriter,
    summary: &mut Summary,
    pts: &mut Vec<(f64, f64)>,
    (knob, name, error_key): (&str, &str, &str),
    secs: f64,
    err: f64,
) -> Result<()> {
    csv.row(&[Cell::Text(knob.into()), Cell::Text(name.into()), 0.0.into(), (1e3 * secs).into(), err.into()])?;
    summary.set(&format!("ms_per_frame_{name}"), 1e3 * secs);
    summary.set(&format!("{error_key}_{name}"), err);
    pts.push((1e3 * secs, err.max(1e-16)));
    Ok(())
}

/// Runs the sweep.
pub fn run(ctx: &BenchCtx) -> Result<Summary> {
    let quads = if ctx.quick { 6 } else { 12 };
    let min_t = if ctx.quick { 0.05 } else { 0.3 };
    let l = 0.5;
    let mesh = sheet(quads, l)?;
    let pats = [folds(0.08, 0.0, 7, 0.5)?];
    // Gather: x squeezed towards the top edge (up to 40 %), a gentle bulge.
    let def: Vec<Pt3> = gather(&mesh, l);
    let mut csv =
        CsvWriter::create(&ctx.out_dir.join("bench.csv"), &["knob", "value", "precompute_ms", "ms", "error"])?;
    let mut summary = Summary::new();
    summary.set_str("profile", if cfg!(debug_assertions) { "debug" } else { "release" });
    summary.set_count("triangles", mesh.faces.len() as u64);
    let mut series: Vec<Series> = Vec::new();

    // (a) tolerance.
    let reference = precompute(
        &mesh,
        &pats,
        &PrecomputeOptions { tolerance: 1e-8, max_depth: 10, gradient_bins: 0, gradient_samples: false },
    )?;
    let c4_ref: Vec<f64> = reference.coeffs.iter().map(|c| c.c4).collect();
    let mut pts = Vec::new();
    let tols: &[f64] = if ctx.quick { &[1e-2, 1e-3, 1e-4] } else { &[1e-2, 1e-3, 1e-4, 1e-5, 1e-6] };
    for &tol in tols {
        let o = PrecomputeOptions { tolerance: tol, max_depth: 10, gradient_bins: 72, gradient_samples: true };
        let mut rig = None;
        let secs = time_it(min_t, || {
            rig = Some(precompute(&mesh, &pats, &o)?);
            Ok(())
        })?;
        let rig = rig.expect("time_it runs the closure at least once");
        let c4: Vec<f64> = rig.coeffs.iter().map(|c| c.c4).collect();
        let err = max(&relative_errors(&c4, &c4_ref, 1e-300));
        csv.row(&[Cell::Text("tolerance".into()), tol.into(), (1e3 * secs).into(), (1e3 * secs).into(), err.into()])?;
        summary.set(&format!("precompute_ms_tol{tol:e}"), 1e3 * secs);
        summary.set(&format!("c4_max_rel_err_tol{tol:e}"), err);
        pts.push((1e3 * secs, err.max(1e-16)));
    }
    series.push(Series::new("tolerance (precompute ms)", pts));

    // (b) gradient bins, exact flat mode.
    let flat = ModulationOptions {
        mode: ModulationMode::ExactFlatRest,
        smoothing: Smoothing::PerTriangle,
        h_max: HMax::Fixed(1e3),
        ..Default::default()
    };
    let ref_rig = precompute(
        &mesh,
        &pats,
        &PrecomputeOptions { tolerance: 1e-4, max_depth: 8, gradient_bins: 0, gradient_samples: true },
    )?;
    let mut ra = WrinkleAnimator::new(ref_rig, flat.clone())?;
    let h_ref = ra.frame(&def)?.tri_h;
    // Triangles with a wrinkle in the reference (relative errors of h > 0 only).
    let wrinkled: Vec<usize> = (0..h_ref.len()).filter(|&t| h_ref[t] > 0.0).collect();
    let mut pts = Vec::new();
    for k in [8usize, 18, 32, 72, 128, 0] {
        let t0 = Instant::now();
        let rig = precompute(
            &mesh,
            &pats,
            &PrecomputeOptions { tolerance: 1e-4, max_depth: 8, gradient_bins: k, gradient_samples: true },
        )?;
        let pre = t0.elapsed().as_secs_f64();
        let mut a = WrinkleAnimator::new(rig, flat.clone())?;
        let mut h = Vec::new();
        let secs = time_it(min_t, || {
            h = a.frame(&def)?.tri_h;
            Ok(())
        })?;
        let pick = |v: &[f64]| -> Vec<f64> { wrinkled.iter().map(|&t| v[t]).collect() };
        let errs = relative_errors(&pick(&h), &pick(&h_ref), 0.0);
        let err = if errs.is_empty() { 0.0 } else { max(&errs) };
        csv.row(&[
            Cell::Text("gradient_bins".into()),
            (k as f64).into(),
            (1e3 * pre).into(),
            (1e3 * secs).into(),
            err.into(),
        ])?;
        summary.set(&format!("exact_ms_per_frame_K{k}"), 1e3 * secs);
        summary.set(&format!("h_max_rel_err_K{k}"), err);
        if k > 0 {
            pts.push((1e3 * secs, err.max(1e-16)));
        }
    }
    series.push(Series::new("gradient bins (exact ms/frame)", pts));

    // (c) mode and (d) smoothing on the default rig.
    let rig = precompute(&mesh, &pats, &PrecomputeOptions::default())?;
    let mean_c4 = rig.coeffs.iter().map(|c| c.c4).sum::<f64>() / rig.coeffs.len().max(1) as f64;
    let mut pts = Vec::new();
    for (name, mode) in [
        ("linearized", ModulationMode::Linearized { strain: StrainMeasure::Green }),
        ("exact_wrinkled", ModulationMode::ExactWrinkledRest),
        ("exact_flat", ModulationMode::ExactFlatRest),
        ("principal_length", ModulationMode::PrincipalLength),
    ] {
        let o = ModulationOptions {
            mode,
            smoothing: Smoothing::PerTriangle,
            h_max: HMax::Fixed(1e3),
            ..Default::default()
        };
        let (secs, rep) = timed_frame(&rig, o, &def, min_t, AreaCheck::PerTriangle)?;
        record_frame(&mut csv, &mut summary, &mut pts, ("mode", name, "area_residual_mean"), secs, rep.mean_rel)?;
    }
    series.push(Series::new("mode (ms/frame)", pts));
    let mut pts = Vec::new();
    for (name, sm) in [
        ("per_triangle", Smoothing::PerTriangle),
        ("vertex_average", Smoothing::VertexAverage { weights: VertexWeights::Area }),
        ("area_consistent", Smoothing::AreaConsistent { mu: 1e-3 * mean_c4 }),
    ] {
        let o = ModulationOptions {
            mode: ModulationMode::ExactFlatRest,
            smoothing: sm,
            h_max: HMax::Fixed(1e3),
            ..Default::default()
        };
        let (secs, rep) = timed_frame(&rig, o, &def, min_t, AreaCheck::Rendered { level: 2 })?;
        record_frame(
            &mut csv,
            &mut summary,
            &mut pts,
            ("smoothing", name, "rendered_area_residual_mean"),
            secs,
            rep.mean_rel,
        )?;
    }
    series.push(Series::new("smoothing (ms/frame)", pts));

    // (e) displaced-mesh level.
    let mut a = WrinkleAnimator::new(rig.clone(), ModulationOptions::default())?;
    let fm = a.frame(&def)?;
    let area_ref = a.displaced_mesh(&def, &fm, 32)?.area();
    let mut pts = Vec::new();
    for lv in [2u32, 4, 8, 16] {
        let mut area = 0.0;
        let secs = time_it(min_t, || {
            area = a.displaced_mesh(&def, &fm, lv)?.area();
            Ok(())
        })?;
        let err = (area - area_ref).abs() / area_ref;
        csv.row(&[Cell::Text("level".into()), (lv as f64).into(), 0.0.into(), (1e3 * secs).into(), err.into()])?;
        summary.set(&format!("ms_displaced_mesh_L{lv}"), 1e3 * secs);
        summary.set(&format!("surface_area_rel_err_L{lv}"), err);
        pts.push((1e3 * secs, err.max(1e-16)));
    }
    series.push(Series::new("subdivision L (ms/mesh)", pts));

    let mut plot = LinePlot::new("wrinkles: error against time", "ms", "error (relative)").log(true, true);
    for s in series {
        plot = plot.with(s);
    }
    plot.write_png(&ctx.out_dir.join("pareto.png"))?;
    Ok(summary)
}

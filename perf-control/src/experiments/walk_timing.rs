//! PC-2 (spec §6): DP time without and with the beam on a 57 s walk input at 10 Hz, refinement to
//! 30 Hz, skeletal output with post-processing, the GEMM min-plus variant of the exact DP, and DP
//! time against input length (15 … 480 s) with a linear fit.
//!
//! Outputs: table `timing` (one row per length and mode), plots `time_vs_length` and `topview`.
//!
//! ```no_run
//! use geom_core::experiment::Size;
//! use geom_core::record::NullRecorder;
//! use perf_control::experiments::walk_timing::{run, Params};
//! let text = std::fs::read_to_string("scenes/perf-control/walk-timing.ron").unwrap();
//! #[derive(serde::Deserialize)]
//! struct Scene { params: Params }
//! let s: Scene = ron::from_str(&text).unwrap();
//! let r = run(&s.params, Size::Quick, &mut NullRecorder::default()).unwrap();
//! println!("exact DP {} s, beam {} s", r.get_f64("dp_exact_s"), r.get_f64("dp_beam_s"));
//! ```

use std::time::Instant;

use geom_core::experiment::{BySize, Report, Size, Target};
use geom_core::record::{Cell, Recorder, Series};
use geom_core::stats::linear_fit;
use serde::Deserialize;

use crate::data::walk::HIP_WIDTH;
use crate::data::walk_motion;
use crate::dp::{interpret, DpParams, Interpretation};
use crate::error::Result;
use crate::experiments::common::topview;
use crate::output::target_motion;
use crate::presets::{walk_database, WalkDbParams};
use crate::refine::refine;
use crate::{hips_control, tracking_error};

/// Parameters of PC-2 (the RON `params` block of `perf-control/walk-timing`).
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Params {
    /// The walk database.
    pub database: WalkDbParams,
    /// DP parameters of the exact run (`beam` is ignored).
    pub dp: DpParams,
    /// Beam width of the beam runs (m²).
    pub beam: f64,
    /// Seed of the input walk (the length sweep uses `input_seed + 1000`).
    pub input_seed: u64,
    /// Input length (s; paper 57 s).
    pub input_secs: f64,
    /// Input lengths of the sweep (s).
    pub lengths: BySize<Vec<f64>>,
    /// Also time the exact DP in the length sweep.
    pub exact_sweep: bool,
}

/// Same chain (instances and boundaries) in two interpretations.
pub fn same_chain(a: &Interpretation, b: &Interpretation) -> bool {
    a.segments.iter().map(|s| (s.instance, s.start, s.end)).eq(b.segments.iter().map(|s| (s.instance, s.start, s.end)))
}

/// Runs PC-2: see the module documentation.
pub fn run(p: &Params, size: Size, rec: &mut dyn Recorder) -> Result<Report> {
    let w = walk_database(&p.database, p.dp.stretch_limit_s, size)?;
    let u = p.database.factor;
    let native = p.database.native_hz;
    let truth = walk_motion(p.input_seed, p.input_secs, native);
    let x_fine = hips_control(&truth, HIP_WIDTH);
    let x = x_fine.downsample(u);
    let exact_p = DpParams { beam: None, ..p.dp.clone() };
    let beam_p = DpParams { beam: Some(p.beam), ..p.dp.clone() };
    let t0 = Instant::now();
    let exact = interpret(&w.db, &x, &exact_p)?;
    let exact_s = t0.elapsed().as_secs_f64();
    let t1 = Instant::now();
    let beam = interpret(&w.db, &x, &beam_p)?;
    let beam_s = t1.elapsed().as_secs_f64();
    let t2 = Instant::now();
    let fine = refine(&w.fine, &x_fine, &beam, u, &beam_p)?;
    let refine_s = t2.elapsed().as_secs_f64();
    let t3 = Instant::now();
    let out = target_motion(&w.fine, &fine, true)?;
    let post_s = t3.elapsed().as_secs_f64();
    let t4 = Instant::now();
    let _raw = target_motion(&w.fine, &fine, false)?;
    let build_s = t4.elapsed().as_secs_f64();
    rec.table("timing", &["input_s", "frames", "mode", "dp_s", "cells_expanded", "relaxations", "score"])?;
    let mut beam_pts = Vec::new();
    let mut exact_pts = Vec::new();
    let lengths = p.lengths.get(size);
    for (i, &len) in lengths.iter().enumerate() {
        rec.progress(i as u64, lengths.len() as u64);
        let xl = hips_control(&walk_motion(p.input_seed + 1000, len, native), HIP_WIDTH).downsample(u);
        let modes: Vec<(&str, &DpParams)> =
            if p.exact_sweep { vec![("beam", &beam_p), ("exact", &exact_p)] } else { vec![("beam", &beam_p)] };
        for (name, dpp) in modes {
            let t = Instant::now();
            let it = interpret(&w.db, &xl, dpp)?;
            let s = t.elapsed().as_secs_f64();
            rec.row(
                "timing",
                &[
                    len.into(),
                    xl.len().into(),
                    name.into(),
                    s.into(),
                    Cell::Int(it.stats.cells_expanded as i64),
                    Cell::Int(it.stats.relaxations as i64),
                    it.score.into(),
                ],
            )?;
            if name == "beam" {
                beam_pts.push((len, s))
            } else {
                exact_pts.push((len, s))
            }
        }
    }
    // GEMM variant last. Before geom-core's `dense::matmul` (faer's product + `vzeroupper`), the
    // rest of the process ran 5–8× slower after it (see README); the order is kept as a guard.
    let gemm_p = DpParams { gemm: true, ..exact_p.clone() };
    let tg = Instant::now();
    let gemm = interpret(&w.db, &x, &gemm_p)?;
    let gemm_s = tg.elapsed().as_secs_f64();
    let (_, slope, r2) = linear_fit(&beam_pts);
    let axes = ("input length (s)".to_string(), "DP time (s)".to_string());
    for (label, pts) in [("beam", &beam_pts), ("exact", &exact_pts)] {
        if !pts.is_empty() {
            let s = Series {
                plot: "time_vs_length".into(),
                label: label.into(),
                axes: axes.clone(),
                log: (false, false),
                points: pts.clone(),
            };
            rec.series(&s)?;
        }
    }
    let achieved = hips_control(&out, HIP_WIDTH);
    topview(rec, &x_fine, &achieved)?;
    let mut r = Report::default();
    r.count("db_instances", w.db.instances.len() as u64);
    r.count("columns_p", exact.stats.columns as u64);
    r.num("input_s", p.input_secs);
    r.timing("dp_exact_s", exact_s);
    r.timing("dp_beam_s", beam_s);
    r.timing("dp_exact_gemm_s", gemm_s);
    r.count("gemm_same_chain", same_chain(&gemm, &exact) as u64);
    r.num("gemm_score_diff_rel", (gemm.score - exact.score).abs() / exact.score);
    r.num("beam_width", p.beam);
    r.num("beam_score_excess_rel", (beam.score - exact.score) / exact.score);
    r.count("beam_same_chain", same_chain(&exact, &beam) as u64);
    r.timing("refine_s", refine_s);
    r.timing("post_s", post_s);
    r.timing("build_raw_s", build_s);
    r.timing("input_s_per_compute_s_beam", p.input_secs / beam_s);
    r.num("exact_cells_expanded", exact.stats.cells_expanded as f64);
    r.num("beam_cells_expanded", beam.stats.cells_expanded as f64);
    r.timing("length_fit_slope_s_per_s", slope);
    r.timing("length_fit_r2", r2);
    r.num("tracking_mid_rms_m", tracking_error(&x_fine, &achieved).rms_m);
    let src = "PC-2 (spec §6): walk timing, 57 s input";
    r.check("dp_exact_s", Target::AtMost(1.5), src);
    r.check("dp_beam_s", Target::AtMost(0.25), src);
    r.check("beam_score_excess_rel", Target::AtMost(0.01), src);
    r.check("refine_s", Target::AtMost(0.1), src);
    r.check("post_s", Target::AtMost(0.1), src);
    r.check("length_fit_r2", Target::AtLeast(0.98), src);
    r.check("gemm_score_diff_rel", Target::AtMost(1e-9), "spec §7.6: GEMM min-plus = push sweep");
    Ok(r)
}

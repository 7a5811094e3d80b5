//! `cargo xtask bench perf-control` (spec §9): accuracy against time of the example-based walk
//! control. Database: the PC-1 walk (120 s, 40 s with `--quick`), input: a held-out walk (57 s,
//! 20 s with `--quick`). Sweeps (`--sweep <name>`, default all):
//! - `beam`: beam width w ∈ {0, 0.01, 0.03, 0.1, 0.3, 1, 3, ∞}: DP time vs relative score excess
//!   over the exact optimum and vs tracking RMS;
//! - `rate`: working rate 5, 7.5, 10, 15, 30 Hz (factor 6, 4, 3, 2, 1), beam 0.3: time vs tracking
//!   RMS with refinement on, and the coarse-only tracking RMS (refinement off);
//! - `cluster`: database size (all, 140, 100, 70, 50, 35), both distance modes: time vs error;
//! - `stretch`: stretch limit 0 … 0.3 s: time (P grows) vs error;
//! - `k`: continuity constant 0 … 100: tracking error and seam jumps (quality only);
//! - `dance`: the dance rows — beam width w ∈ {0, 0.1, 0.3, 1, 3, 10, ∞} on the PC-4 database and
//!   first test dance: DP wall and CPU time vs score excess and two-beat error rate, and whether
//!   the labels equal the exact run's (`pc_dance.csv`, `pc_dance.png`;
//!   [`perf_control::experiments::sweeps::evaluate_dance`]).
//!
//! Every point is one call of [`perf_control::experiments::sweeps::evaluate`]. Writes
//! `pc_<sweep>.csv` and `pc_<sweep>.png` per sweep.

use perf_control::experiments::sweeps::{evaluate, evaluate_dance, DanceSweep, SweepPoint, WalkSweep};
use perf_control::{ClusterDistance, DpParams};

use crate::bench_points::{self as P, pts};
use crate::error::{Error, Result};
use crate::out::{Cell, CsvWriter, Summary};
use crate::plot::{LinePlot, Series};
use crate::registry::BenchCtx;

/// The sweeps `--sweep` accepts.
pub const SWEEPS: &[&str] = &["beam", "rate", "cluster", "stretch", "k", "dance"];

/// The CSV columns of every sweep.
const HEADER: [&str; 10] = [
    "sweep",
    "value",
    "mode",
    "dp_s",
    "score",
    "score_excess_rel",
    "track_rms_m",
    "coarse_rms_m",
    "seam_jump_max_m",
    "columns",
];

/// Writes one CSV row (the columns of `HEADER`).
fn row(csv: &mut CsvWriter, r: &SweepPoint, sweep: &str, value: f64, mode: &str, excess: f64) -> Result<()> {
    csv.row(&[
        sweep.into(),
        value.into(),
        mode.into(),
        r.dp_s.into(),
        r.score.into(),
        excess.into(),
        r.rms.into(),
        r.coarse_rms.into(),
        r.jump.into(),
        r.columns.into(),
    ])
}

/// Runs the selected sweeps.
pub fn run(ctx: &BenchCtx) -> Result<Summary> {
    let quick = ctx.quick;
    let s = WalkSweep::new(quick);
    let sel: Vec<&str> = match ctx.sweep.as_deref() {
        None | Some("all") => SWEEPS.to_vec(),
        Some(x) if SWEEPS.contains(&x) => vec![x],
        Some(x) => return Err(Error::Usage(format!("unknown sweep '{x}' (one of {SWEEPS:?} or all)"))),
    };
    let mut summary = Summary::new();
    summary.set_str("mode", if quick { "quick" } else { "default" });
    let cat = ClusterDistance::ControlAndTarget;
    for sw in sel {
        if sw == "dance" {
            dance(ctx, &mut summary)?;
            summary.set_count("dance_done", 1);
            continue;
        }
        let mut csv = CsvWriter::create(&ctx.out_dir.join(format!("pc_{sw}.csv")), &HEADER)?;
        // The walk defaults of spec §4 (k = 10, ±0.2 s, exact, partial ends); PC-1's database size.
        let p0 = DpParams::default();
        let beam = DpParams { beam: Some(0.3), ..p0.clone() };
        let size = s.db_size();
        let mut series: Vec<(String, Vec<(f64, f64)>)> = Vec::new();
        let mut add = |label: &str, pt: (f64, f64)| {
            if let Some(e) = series.iter_mut().find(|e| e.0 == label) {
                e.1.push(pt);
            } else {
                series.push((label.to_string(), vec![pt]));
            }
        };
        let (x_label, y_label) = match sw {
            "beam" => {
                let exact = evaluate(&s, 3, Some(size), cat, &p0)?;
                let mut chosen = f64::INFINITY;
                for w in [0.0, 0.01, 0.03, 0.1, 0.3, 1.0, 3.0, f64::INFINITY] {
                    let r = evaluate(&s, 3, Some(size), cat, &DpParams { beam: Some(w), ..p0.clone() })?;
                    let excess = (r.score - exact.score) / exact.score;
                    row(&mut csv, &r, "beam", w, "", excess)?;
                    add("beam widths", (r.dp_s, excess.max(1e-9)));
                    if excess <= 0.01 && (r.rms - exact.rms).abs() <= 1e-3 && w < chosen {
                        chosen = w;
                    }
                }
                summary.set("beam_exact_dp_s", exact.dp_s);
                summary.set("beam_default_w", chosen);
                ("DP time (s)", "relative score excess (floored at 1e-9)")
            }
            "rate" => {
                for (hz, f) in pts(ctx, P::perf_control_rate(s.quick)) {
                    let r = evaluate(&s, f, Some(size), cat, &beam)?;
                    row(&mut csv, &r, "rate", hz, "beam0.3", f64::NAN)?;
                    add("refined (30 Hz skeleton)", (r.dp_s, r.rms));
                    add("coarse placed control", (r.dp_s, r.coarse_rms));
                }
                ("DP time (s)", "tracking RMS (m)")
            }
            "cluster" => {
                let sizes: Vec<Option<usize>> = if s.quick {
                    vec![None, Some(50), Some(35)]
                } else {
                    vec![None, Some(140), Some(100), Some(70), Some(50), Some(35)]
                };
                for mode in [ClusterDistance::ControlAndTarget, ClusterDistance::ControlOnly] {
                    for &n in &sizes {
                        let r = evaluate(&s, 3, n, mode, &beam)?;
                        let v = n.map_or(f64::NAN, |n| n as f64);
                        row(&mut csv, &r, "cluster", v, &format!("{mode:?}"), f64::NAN)?;
                        add(&format!("{mode:?}"), (r.dp_s, r.rms));
                    }
                }
                ("DP time (s)", "tracking RMS (m)")
            }
            "stretch" => {
                for lim in pts(ctx, P::PERF_CONTROL_STRETCH.to_vec()) {
                    let r = evaluate(&s, 3, Some(size), cat, &DpParams { stretch_limit_s: lim, ..beam.clone() })?;
                    row(&mut csv, &r, "stretch", lim, "beam0.3", f64::NAN)?;
                    add("stretch limits", (r.dp_s, r.rms));
                }
                ("DP time (s)", "tracking RMS (m)")
            }
            _ => {
                for k in pts(ctx, P::PERF_CONTROL_K.to_vec()) {
                    let r = evaluate(&s, 3, Some(size), cat, &DpParams { k, ..beam.clone() })?;
                    row(&mut csv, &r, "k", k, "beam0.3", f64::NAN)?;
                    add("tracking RMS (m)", (k, r.rms));
                    add("max raw seam jump (m)", (k, r.jump));
                }
                ("k", "metres")
            }
        };
        let mut plot = LinePlot::new(&format!("perf-control: {sw} sweep"), x_label, y_label);
        if sw == "beam" {
            plot = plot.log(false, true);
        }
        for (l, pts) in series {
            plot = plot.with(Series::new(l, pts));
        }
        plot.write_png(&ctx.out_dir.join(format!("pc_{sw}.png")))?;
        summary.set_count(&format!("{sw}_done"), 1);
    }
    Ok(summary)
}

/// The dance rows (spec §9): beam widths on the PC-4 database and first test dance.
fn dance(ctx: &BenchCtx, summary: &mut Summary) -> Result<()> {
    let s = DanceSweep::new(ctx.quick)?;
    let header = [
        "w",
        "dp_s",
        "dp_cpu_s",
        "score",
        "score_excess_rel",
        "two_beat_error_rate",
        "labels_as_exact",
        "cells_expanded",
    ];
    let mut csv = CsvWriter::create(&ctx.out_dir.join("pc_dance.csv"), &header)?;
    let p0 = DpParams { stretch_limit_s: 0.15, ..DpParams::default() };
    let exact = evaluate_dance(&s, &p0)?;
    let (mut wall, mut cpu) = (Vec::new(), Vec::new());
    for w in [0.0, 0.1, 0.3, 1.0, 3.0, 10.0, f64::INFINITY] {
        let r = evaluate_dance(&s, &DpParams { beam: Some(w), ..p0.clone() })?;
        let excess = (r.score - exact.score) / exact.score;
        csv.row(&[
            w.into(),
            r.dp_s.into(),
            r.dp_cpu_s.into(),
            r.score.into(),
            excess.into(),
            r.two_beat_error_rate.into(),
            Cell::Int(i64::from(r.labels == exact.labels)),
            Cell::Int(r.cells_expanded as i64),
        ])?;
        wall.push((r.dp_s, excess.max(1e-9)));
        cpu.push((r.dp_cpu_s, excess.max(1e-9)));
    }
    summary.set("dance_exact_two_beat_error_rate", exact.two_beat_error_rate);
    LinePlot::new("perf-control: dance beam sweep", "DP time (s)", "relative score excess (floored at 1e-9)")
        .log(false, true)
        .with(Series::new("wall", wall))
        .with(Series::new("CPU", cpu))
        .write_png(&ctx.out_dir.join("pc_dance.png"))?;
    Ok(())
}

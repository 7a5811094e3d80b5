//! `cargo xtask bench perf-control` (spec §9): accuracy against time of the example-based walk
//! control. Database: the PC-1 walk (120 s, 40 s with `--quick`), input: a held-out walk (57 s,
//! 20 s with `--quick`). Sweeps (`--sweep <name>`, default all):
//! - `beam`: beam width w ∈ {0, 0.01, 0.03, 0.1, 0.3, 1, 3, ∞}: DP time vs relative score excess
//!   over the exact optimum and vs tracking RMS;
//! - `rate`: working rate 5, 7.5, 10, 15, 30 Hz (factor 6, 4, 3, 2, 1), beam 0.3: time vs tracking
//!   RMS with refinement on, and the coarse-only tracking RMS (refinement off);
//! - `cluster`: database size (all, 140, 100, 70, 50, 35), both distance modes: time vs error;
//! - `stretch`: stretch limit 0 … 0.3 s: time (P grows) vs error;
//! - `k`: continuity constant 0 … 100: tracking error and seam jumps (quality only).
//!
//! Writes `pc_<sweep>.csv` and `pc_<sweep>.png` per sweep.

use std::time::Instant;

use perf_control::data::walk::HIP_WIDTH;
use perf_control::data::{walk_motion, walk_take};
use perf_control::eval::seam_jumps;
use perf_control::{
    achieved_control, hips_control, interpret, refine, target_motion, target_points, tracking_error, ClusterBy,
    ClusterDistance, ClusterOptions, DpParams, MappingDb, PointTrack, Representative, Take,
};

use crate::error::{Error, Result};
use crate::out::{CsvWriter, Summary};
use crate::plot::{LinePlot, Series};
use crate::registry::BenchCtx;

/// The sweeps `--sweep` accepts.
pub const SWEEPS: &[&str] = &["beam", "rate", "cluster", "stretch", "k"];

fn pc<T>(r: perf_control::Result<T>) -> Result<T> {
    r.map_err(|e| Error::Run(format!("perf-control: {e}")))
}

struct Setup {
    take: Take,
    x_fine: PointTrack,
    quick: bool,
}

/// What one evaluation measured.
struct Eval {
    /// DP wall time (s).
    dp_s: f64,
    /// DP score `S` (m²).
    score: f64,
    /// Tracking RMS after refinement and skeletal output (m).
    rms: f64,
    /// Tracking RMS of the coarse placed control, refinement off (m).
    coarse_rms: f64,
    /// Largest raw seam jump of the target points, before blending (m).
    jump: f64,
    /// DP columns `P`.
    columns: usize,
}

impl Eval {
    /// Writes one CSV row (the columns of `HEADER`).
    fn row(&self, csv: &mut CsvWriter, sweep: &str, value: f64, mode: &str, excess: f64) -> Result<()> {
        csv.row(&[
            sweep.into(),
            value.into(),
            mode.into(),
            self.dp_s.into(),
            self.score.into(),
            excess.into(),
            self.rms.into(),
            self.coarse_rms.into(),
            self.jump.into(),
            self.columns.into(),
        ])
    }
}

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

/// One evaluation: database reduced to `size` at `factor` (working rate 30/factor Hz), DP with `p`,
/// refinement to 30 Hz and skeletal output.
fn evaluate(s: &Setup, factor: usize, size: Option<usize>, mode: ClusterDistance, p: &DpParams) -> Result<Eval> {
    let mut db = pc(MappingDb::from_takes(vec![s.take.clone()], 30.0 / factor as f64))?;
    if let Some(n) = size.filter(|&n| n < db.instances.len()) {
        pc(db.cluster(&ClusterOptions {
            by: ClusterBy::TargetSize(n),
            distance: mode,
            stretch_limit_s: p.stretch_limit_s,
            representative: Representative::Random,
            seed: 11,
        }))?;
    }
    let x = s.x_fine.downsample(factor);
    let t0 = Instant::now();
    let it = pc(interpret(&db, &x, p))?;
    let dp_s = t0.elapsed().as_secs_f64();
    let coarse_rms = tracking_error(&x, &pc(achieved_control(&db, &it))?).rms_m;
    let fine_db = pc(db.at_rate(30.0))?;
    let fine = if factor > 1 { pc(refine(&fine_db, &s.x_fine, &it, factor, p))? } else { it.clone() };
    let out = pc(target_motion(&fine_db, &fine, true))?;
    let rms = tracking_error(&s.x_fine, &hips_control(&out, HIP_WIDTH)).rms_m;
    let pts = pc(target_points(&fine_db, &fine, false))?;
    let seams: Vec<usize> = fine.segments[1..].iter().filter(|c| c.start > 0).map(|c| c.start as usize).collect();
    let jump = seam_jumps(&pts, &seams).0.into_iter().fold(0.0, f64::max);
    Ok(Eval { dp_s, score: it.score, rms, coarse_rms, jump, columns: it.stats.columns })
}

/// Runs the selected sweeps.
pub fn run(ctx: &BenchCtx) -> Result<Summary> {
    let quick = ctx.quick;
    let s = Setup {
        take: walk_take(11, if quick { 40.0 } else { 120.0 }, 30.0),
        x_fine: hips_control(&walk_motion(301, if quick { 20.0 } else { 57.0 }, 30.0), HIP_WIDTH),
        quick,
    };
    let sel: Vec<&str> = match ctx.sweep.as_deref() {
        None | Some("all") => SWEEPS.to_vec(),
        Some(x) if SWEEPS.contains(&x) => vec![x],
        Some(x) => return Err(Error::Usage(format!("unknown sweep '{x}' (one of {SWEEPS:?} or all)"))),
    };
    let mut summary = Summary::new();
    summary.set_str("mode", if quick { "quick" } else { "default" });
    for sw in sel {
        let mut csv = CsvWriter::create(&ctx.out_dir.join(format!("pc_{sw}.csv")), &HEADER)?;
        // The walk defaults of spec §4 (k = 10, ±0.2 s, exact, partial ends); PC-1's database size.
        let p0 = DpParams::default();
        let size = if s.quick { 40 } else { 70 };
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
                let exact = evaluate(&s, 3, Some(size), ClusterDistance::ControlAndTarget, &p0)?;
                let mut chosen = f64::INFINITY;
                for w in [0.0, 0.01, 0.03, 0.1, 0.3, 1.0, 3.0, f64::INFINITY] {
                    let mut p = p0.clone();
                    p.beam = Some(w);
                    let r = evaluate(&s, 3, Some(size), ClusterDistance::ControlAndTarget, &p)?;
                    let excess = (r.score - exact.score) / exact.score;
                    r.row(&mut csv, "beam", w, "", excess)?;
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
                for (hz, f) in [(5.0, 6usize), (7.5, 4), (10.0, 3), (15.0, 2), (30.0, 1)] {
                    if s.quick && f == 1 {
                        continue;
                    }
                    let mut p = p0.clone();
                    p.beam = Some(0.3);
                    let r = evaluate(&s, f, Some(size), ClusterDistance::ControlAndTarget, &p)?;
                    r.row(&mut csv, "rate", hz, "beam0.3", f64::NAN)?;
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
                        let mut p = p0.clone();
                        p.beam = Some(0.3);
                        let r = evaluate(&s, 3, n, mode, &p)?;
                        let v = n.map_or(f64::NAN, |n| n as f64);
                        r.row(&mut csv, "cluster", v, &format!("{mode:?}"), f64::NAN)?;
                        add(&format!("{mode:?}"), (r.dp_s, r.rms));
                    }
                }
                ("DP time (s)", "tracking RMS (m)")
            }
            "stretch" => {
                for lim in [0.0, 0.1, 0.15, 0.2, 0.3] {
                    let mut p = p0.clone();
                    p.stretch_limit_s = lim;
                    p.beam = Some(0.3);
                    let r = evaluate(&s, 3, Some(size), ClusterDistance::ControlAndTarget, &p)?;
                    r.row(&mut csv, "stretch", lim, "beam0.3", f64::NAN)?;
                    add("stretch limits", (r.dp_s, r.rms));
                }
                ("DP time (s)", "tracking RMS (m)")
            }
            _ => {
                for k in [0.0, 1.0, 3.0, 10.0, 30.0, 100.0] {
                    let mut p = p0.clone();
                    p.k = k;
                    p.beam = Some(0.3);
                    let r = evaluate(&s, 3, Some(size), ClusterDistance::ControlAndTarget, &p)?;
                    r.row(&mut csv, "k", k, "beam0.3", f64::NAN)?;
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

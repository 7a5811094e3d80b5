//! perf-control's scenes (spec §6): example-based control of a walking character.
//!
//! - `perf-control/walk` (PC-1, [`run_walk`]): a 120 s walk database clustered to 70 instances,
//!   driven by the hips control of held-out walks (long and short); tracking error, stride
//!   frequency ratio, phase agreement, seam jumps, foot skate.
//! - `perf-control/walk-timing` (PC-2, [`run_timing`]): a 57 s input, DP without and with beam,
//!   refinement, post-processing, then a length sweep with a linear fit of time against length.
//! - `perf-control/mouse-paths` (PC-3, [`run_mouse`]): random performed mouse paths and one
//!   too-fast stroke drive the same database through the Frenet-frame path control.
//! - `perf-control/real-data` (PC-6, [`run_real`]): CMU 01_01 + 01_03 with detected contacts
//!   (foot-plant segmentation), trained on 01_03 and the first half of 01_01, tested on the second
//!   half of 01_01; tracking error only.

use std::path::Path;
use std::time::Instant;

use geom_core::anim::bvh::{self, BvhWriteOptions};
use geom_core::anim::metrics::foot_skate;
use geom_core::anim::Motion;
use perf_control::data::walk::HIP_WIDTH;
use perf_control::data::{mouse_path, straight_stroke, walk_motion, walk_take};
use perf_control::eval::{phase_agreement, seam_jumps, step_frequency};
use perf_control::{
    hips_control, interpret, path_control, refine, target_motion, target_points, tracking_error, ClusterBy,
    ClusterDistance, ClusterOptions, DpParams, Interpretation, MappingDb, PointTrack, Representative, TrackingStats,
};
use serde::Deserialize;

use crate::error::{Error, Result};
use crate::out::{Cell, CsvWriter, Summary};
use crate::plot::{LinePlot, Series};
use crate::registry::{RunCtx, Runner};
use crate::scene;

/// Adds perf-control's runners.
pub fn register(v: &mut Vec<Runner>) {
    v.push(Runner { method: "perf-control/walk", run: run_walk });
    v.push(Runner { method: "perf-control/walk-timing", run: run_timing });
    v.push(Runner { method: "perf-control/mouse-paths", run: run_mouse });
    v.push(Runner { method: "perf-control/real-data", run: run_real });
}

fn pc<T>(r: perf_control::Result<T>) -> Result<T> {
    r.map_err(|e| Error::Run(format!("perf-control: {e}")))
}

/// The walk database of a scene.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct WalkDbParams {
    seed: u64,
    /// [quick, default, full] length of the database walk (s).
    secs: [f64; 3],
    /// Native rate (Hz) of the synthesised walks.
    native_hz: f64,
    /// Downsampling factor `u` (working rate = native / u).
    factor: usize,
    /// [quick, default, full] target database size after clustering (0 = no clustering).
    cluster_to: [usize; 3],
    cluster_distance: ClusterDistance,
}

struct WalkDb {
    db: MappingDb,
    fine: MappingDb,
    before: usize,
    cluster_s: f64,
}

fn build_db(p: &WalkDbParams, dp: &DpParams, ctx: &RunCtx) -> Result<WalkDb> {
    if p.factor == 0 || p.native_hz <= 0.0 {
        return Err(scene::invalid(&ctx.scene_file, "factor and native_hz must be positive"));
    }
    let secs = ctx.mode.pick(p.secs[0], p.secs[1], p.secs[2]);
    let take = walk_take(p.seed, secs, p.native_hz);
    let working = p.native_hz / p.factor as f64;
    let mut db = pc(MappingDb::from_takes(vec![take], working))?;
    let before = db.instances.len();
    let t0 = Instant::now();
    let target = ctx.mode.pick(p.cluster_to[0], p.cluster_to[1], p.cluster_to[2]);
    if target > 0 && target < before {
        pc(db.cluster(&ClusterOptions {
            by: ClusterBy::TargetSize(target),
            distance: p.cluster_distance,
            stretch_limit_s: dp.stretch_limit_s,
            representative: Representative::Random,
            seed: p.seed,
        }))?;
    }
    let cluster_s = t0.elapsed().as_secs_f64();
    let fine = pc(db.at_rate(p.native_hz))?;
    Ok(WalkDb { db, fine, before, cluster_s })
}

/// Result of driving the database with one fine-rate control.
struct Drive {
    coarse: Interpretation,
    fine: Interpretation,
    out: Motion,
    dp_s: f64,
    refine_s: f64,
    post_s: f64,
}

fn drive(w: &WalkDb, x_fine: &PointTrack, factor: usize, dp: &DpParams) -> Result<Drive> {
    let x = x_fine.downsample(factor);
    let t0 = Instant::now();
    let coarse = pc(interpret(&w.db, &x, dp))?;
    let dp_s = t0.elapsed().as_secs_f64();
    let t1 = Instant::now();
    let fine = pc(refine(&w.fine, x_fine, &coarse, factor, dp))?;
    let refine_s = t1.elapsed().as_secs_f64();
    let t2 = Instant::now();
    let out = pc(target_motion(&w.fine, &fine, true))?;
    let post_s = t2.elapsed().as_secs_f64();
    Ok(Drive { coarse, fine, out, dp_s, refine_s, post_s })
}

fn write_segments(path: &Path, w: &WalkDb, d: &Drive) -> Result<()> {
    let mut csv = CsvWriter::create(
        path,
        &["i", "instance", "label", "start_work", "end_work", "start_fine", "end_fine", "theta", "tx", "tz", "D", "C"],
    )?;
    for (i, (c, f)) in d.coarse.segments.iter().zip(&d.fine.segments).enumerate() {
        let label = format!("{:?}", w.db.instances[c.instance as usize].label).replace(['{', '}', ' '], "");
        csv.row(&[
            Cell::Int(i as i64),
            Cell::Int(c.instance as i64),
            label.into(),
            Cell::Int(c.start),
            Cell::Int(c.end),
            Cell::Int(f.start),
            Cell::Int(f.end),
            f.m.yaw.into(),
            f.m.x.into(),
            f.m.z.into(),
            f.d.into(),
            f.c.into(),
        ])?;
    }
    Ok(())
}

fn topview(path: &Path, title: &str, requested: &PointTrack, achieved: &PointTrack) -> Result<()> {
    let mid = |t: &PointTrack| -> Vec<(f64, f64)> {
        (0..t.len())
            .map(|f| (0.5 * (t.frame(f)[0].x + t.frame(f)[1].x), 0.5 * (t.frame(f)[0].z + t.frame(f)[1].z)))
            .collect()
    };
    LinePlot::new(title, "x (m)", "z (m)")
        .with(Series::new("requested", mid(requested)))
        .with(Series::new("achieved", mid(achieved)))
        .write_png(path)?;
    Ok(())
}

fn mean(v: &[f64]) -> f64 {
    if v.is_empty() {
        f64::NAN
    } else {
        v.iter().sum::<f64>() / v.len() as f64
    }
}

// ---------------------------------------------------------------------------------------------
// PC-1 walk

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct WalkParams {
    database: WalkDbParams,
    dp: DpParams,
    long_seeds: Vec<u64>,
    /// [quick, default, full] long inputs used (prefix of `long_seeds`).
    long_count: [usize; 3],
    /// [quick, default, full] long input length (s).
    long_secs: [f64; 3],
    short_seeds: Vec<u64>,
    short_count: [usize; 3],
    short_secs: f64,
}

/// PC-1: held-out walks through the walk database.
pub fn run_walk(ctx: &RunCtx) -> Result<Summary> {
    let p: WalkParams = scene::load(&ctx.scene_file)?.params;
    let w = build_db(&p.database, &p.dp, ctx)?;
    let u = p.database.factor;
    let long_secs = ctx.mode.pick(p.long_secs[0], p.long_secs[1], p.long_secs[2]);
    let nl = ctx.mode.pick(p.long_count[0], p.long_count[1], p.long_count[2]).min(p.long_seeds.len());
    let ns = ctx.mode.pick(p.short_count[0], p.short_count[1], p.short_count[2]).min(p.short_seeds.len());
    let inputs: Vec<(&str, u64, f64)> = p.long_seeds[..nl]
        .iter()
        .map(|&s| ("long", s, long_secs))
        .chain(p.short_seeds[..ns].iter().map(|&s| ("short", s, p.short_secs)))
        .collect();
    let mut csv = CsvWriter::create(
        &ctx.out_dir.join("metrics.csv"),
        &[
            "kind",
            "seed",
            "secs",
            "segments",
            "mid_rms_m",
            "mid_max_m",
            "heading_rms_deg",
            "stride_ratio",
            "phase",
            "seam_jump_max_m",
            "within_jump_median_m",
            "skate_cm_s",
            "dp_s",
            "refine_s",
            "post_s",
        ],
    )?;
    let mut timing =
        CsvWriter::create(&ctx.out_dir.join("timing.csv"), &["kind", "seed", "input_s", "dp_s", "refine_s", "post_s"])?;
    let mut agg: std::collections::BTreeMap<&str, Vec<[f64; 7]>> = Default::default();
    for (idx, &(kind, seed, secs)) in inputs.iter().enumerate() {
        let truth = walk_motion(seed, secs, p.database.native_hz);
        let x_fine = hips_control(&truth, HIP_WIDTH);
        let d = drive(&w, &x_fine, u, &p.dp)?;
        let achieved = hips_control(&d.out, HIP_WIDTH);
        let tr: TrackingStats = tracking_error(&x_fine, &achieved);
        let stride = step_frequency(&d.out) / step_frequency(&truth);
        let phase = phase_agreement(&d.out, &truth);
        let pts = pc(target_points(&w.fine, &d.fine, true))?;
        let seams: Vec<usize> =
            d.fine.segments[1..].iter().map(|s| s.start).filter(|&s| s > 0).map(|s| s as usize).collect();
        let (js, med) = seam_jumps(&pts, &seams);
        let seam_max = js.iter().copied().fold(0.0, f64::max);
        let skate = foot_skate(&d.out, &d.out.labels).rate_cm_s;
        csv.row(&[
            kind.into(),
            Cell::Int(seed as i64),
            secs.into(),
            d.fine.segments.len().into(),
            tr.rms_m.into(),
            tr.max_m.into(),
            tr.heading_rms_deg.into(),
            stride.into(),
            phase.into(),
            seam_max.into(),
            med.into(),
            skate.into(),
            d.dp_s.into(),
            d.refine_s.into(),
            d.post_s.into(),
        ])?;
        timing.row(&[
            kind.into(),
            Cell::Int(seed as i64),
            secs.into(),
            d.dp_s.into(),
            d.refine_s.into(),
            d.post_s.into(),
        ])?;
        agg.entry(kind).or_default().push([tr.rms_m, tr.max_m, tr.heading_rms_deg, stride, phase, skate, d.dp_s]);
        if idx == 0 {
            write_segments(&ctx.out_dir.join("segments.csv"), &w, &d)?;
            topview(&ctx.out_dir.join("topview.png"), "PC-1: requested vs achieved hips midpoint", &x_fine, &achieved)?;
            let bvh_path = ctx.out_dir.join("target.bvh");
            std::fs::write(&bvh_path, bvh::write(&d.out, &BvhWriteOptions::default()))
                .map_err(crate::error::io_err(&bvh_path))?;
            let mut pcsv =
                CsvWriter::create(&ctx.out_dir.join("target_points.csv"), &["frame", "point", "x", "y", "z"])?;
            for f in 0..pts.len() {
                for (k, q) in pts.frame(f).iter().enumerate() {
                    pcsv.row(&[Cell::Int(f as i64), Cell::Int(k as i64), q.x.into(), q.y.into(), q.z.into()])?;
                }
            }
        }
    }
    let mut s = Summary::new();
    s.set_str("mode", ctx.mode.name());
    s.set_count("db_instances_before", w.before as u64);
    s.set_count("db_instances", w.db.instances.len() as u64);
    s.set("cluster_s", w.cluster_s);
    for (kind, rows) in &agg {
        let col = |i: usize| rows.iter().map(|r| r[i]).collect::<Vec<f64>>();
        s.set(&format!("{kind}_mid_rms_m"), mean(&col(0)));
        s.set(&format!("{kind}_mid_max_m"), col(1).iter().copied().fold(0.0, f64::max));
        s.set(&format!("{kind}_heading_rms_deg"), mean(&col(2)));
        s.set(&format!("{kind}_stride_ratio"), mean(&col(3)));
        s.set(&format!("{kind}_phase_agreement"), mean(&col(4)));
        s.set(&format!("{kind}_skate_cm_s"), mean(&col(5)));
        s.set(&format!("{kind}_dp_s"), mean(&col(6)));
        s.set_count(&format!("{kind}_inputs"), rows.len() as u64);
    }
    Ok(s)
}

// ---------------------------------------------------------------------------------------------
// PC-2 timing

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct TimingParams {
    database: WalkDbParams,
    dp: DpParams,
    /// Beam width of the beam runs (m²).
    beam: f64,
    input_seed: u64,
    input_secs: f64,
    /// [quick, default, full] input lengths of the sweep (s).
    lengths: [Vec<f64>; 3],
    /// Also time the exact DP in the length sweep.
    exact_sweep: bool,
}

/// Least-squares line `y = a + b x` and its R².
fn linear_fit(pts: &[(f64, f64)]) -> (f64, f64, f64) {
    let n = pts.len() as f64;
    let mx = pts.iter().map(|p| p.0).sum::<f64>() / n;
    let my = pts.iter().map(|p| p.1).sum::<f64>() / n;
    let sxx: f64 = pts.iter().map(|p| (p.0 - mx).powi(2)).sum();
    let sxy: f64 = pts.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    let syy: f64 = pts.iter().map(|p| (p.1 - my).powi(2)).sum();
    let b = if sxx > 0.0 { sxy / sxx } else { 0.0 };
    let r2 = if syy > 0.0 { (sxy * sxy) / (sxx * syy) } else { 1.0 };
    (my - b * mx, b, r2)
}

/// PC-2: DP, refinement and post-processing time on a 57 s input; time against input length.
pub fn run_timing(ctx: &RunCtx) -> Result<Summary> {
    let p: TimingParams = scene::load(&ctx.scene_file)?.params;
    let w = build_db(&p.database, &p.dp, ctx)?;
    let u = p.database.factor;
    let native = p.database.native_hz;
    let truth = walk_motion(p.input_seed, p.input_secs, native);
    let x_fine = hips_control(&truth, HIP_WIDTH);
    let x = x_fine.downsample(u);
    let mut exact_p = p.dp.clone();
    exact_p.beam = None;
    let mut beam_p = p.dp.clone();
    beam_p.beam = Some(p.beam);
    let t0 = Instant::now();
    let exact = pc(interpret(&w.db, &x, &exact_p))?;
    let exact_s = t0.elapsed().as_secs_f64();
    let t1 = Instant::now();
    let beam = pc(interpret(&w.db, &x, &beam_p))?;
    let beam_s = t1.elapsed().as_secs_f64();
    let t2 = Instant::now();
    let fine = pc(refine(&w.fine, &x_fine, &beam, u, &beam_p))?;
    let refine_s = t2.elapsed().as_secs_f64();
    let t3 = Instant::now();
    let out = pc(target_motion(&w.fine, &fine, true))?;
    let post_s = t3.elapsed().as_secs_f64();
    let t4 = Instant::now();
    let _raw = pc(target_motion(&w.fine, &fine, false))?;
    let build_s = t4.elapsed().as_secs_f64();
    let same_chain = exact
        .segments
        .iter()
        .map(|s| (s.instance, s.start, s.end))
        .eq(beam.segments.iter().map(|s| (s.instance, s.start, s.end)));
    let lengths = ctx.mode.pick(&p.lengths[0], &p.lengths[1], &p.lengths[2]).clone();
    let mut csv = CsvWriter::create(
        &ctx.out_dir.join("timing.csv"),
        &["input_s", "frames", "mode", "dp_s", "cells_expanded", "relaxations", "score"],
    )?;
    let mut beam_pts = Vec::new();
    let mut exact_pts = Vec::new();
    for &len in &lengths {
        let xl = hips_control(&walk_motion(p.input_seed + 1000, len, native), HIP_WIDTH).downsample(u);
        let modes: Vec<(&str, &DpParams)> =
            if p.exact_sweep { vec![("beam", &beam_p), ("exact", &exact_p)] } else { vec![("beam", &beam_p)] };
        for (name, dpp) in modes {
            let t = Instant::now();
            let it = pc(interpret(&w.db, &xl, dpp))?;
            let s = t.elapsed().as_secs_f64();
            csv.row(&[
                len.into(),
                xl.len().into(),
                name.into(),
                s.into(),
                Cell::Int(it.stats.cells_expanded as i64),
                Cell::Int(it.stats.relaxations as i64),
                it.score.into(),
            ])?;
            if name == "beam" {
                beam_pts.push((len, s))
            } else {
                exact_pts.push((len, s))
            }
        }
    }
    // GEMM variant last. Before geom-core's `dense::matmul` (faer's product + `vzeroupper`), the
    // rest of the process ran 5–8× slower after it (see README); the order is kept as a guard.
    let mut gemm_p = exact_p.clone();
    gemm_p.gemm = true;
    let tg = Instant::now();
    let gemm = pc(interpret(&w.db, &x, &gemm_p))?;
    let gemm_s = tg.elapsed().as_secs_f64();
    let gemm_same = gemm
        .segments
        .iter()
        .map(|s| (s.instance, s.start, s.end))
        .eq(exact.segments.iter().map(|s| (s.instance, s.start, s.end)));
    let (_, slope, r2) = linear_fit(&beam_pts);
    let mut plot = LinePlot::new("PC-2: DP time vs input length", "input length (s)", "DP time (s)")
        .with(Series::new("beam", beam_pts.clone()));
    if !exact_pts.is_empty() {
        plot = plot.with(Series::new("exact", exact_pts.clone()));
    }
    plot.write_png(&ctx.out_dir.join("time_vs_length.png"))?;
    let achieved = hips_control(&out, HIP_WIDTH);
    topview(&ctx.out_dir.join("topview.png"), "PC-2: 57 s input", &x_fine, &achieved)?;
    let mut s = Summary::new();
    s.set_str("mode", ctx.mode.name());
    s.set_count("db_instances", w.db.instances.len() as u64);
    s.set_count("columns_p", exact.stats.columns as u64);
    s.set("input_s", p.input_secs);
    s.set("dp_exact_s", exact_s);
    s.set("dp_beam_s", beam_s);
    s.set("dp_exact_gemm_s", gemm_s);
    s.set_count("gemm_same_chain", gemm_same as u64);
    s.set("gemm_score_diff_rel", (gemm.score - exact.score).abs() / exact.score);
    s.set("beam_width", p.beam);
    s.set("beam_score_excess_rel", (beam.score - exact.score) / exact.score);
    s.set_count("beam_same_chain", same_chain as u64);
    s.set("refine_s", refine_s);
    s.set("post_s", post_s);
    s.set("build_raw_s", build_s);
    s.set("input_s_per_compute_s_beam", p.input_secs / beam_s);
    s.set("exact_cells_expanded", exact.stats.cells_expanded as f64);
    s.set("beam_cells_expanded", beam.stats.cells_expanded as f64);
    s.set("length_fit_slope_s_per_s", slope);
    s.set("length_fit_r2", r2);
    s.set("tracking_mid_rms_m", tracking_error(&x_fine, &achieved).rms_m);
    Ok(s)
}

// ---------------------------------------------------------------------------------------------
// PC-3 mouse paths

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct MouseParams {
    database: WalkDbParams,
    dp: DpParams,
    seeds: Vec<u64>,
    /// [quick, default, full] paths used (prefix of `seeds`).
    count: [usize; 3],
    secs: f64,
    speed: (f64, f64),
    smooth: usize,
    fast_speed: f64,
    fast_secs: f64,
}

/// PC-3: mouse paths (Frenet-frame control) and one too-fast stroke.
pub fn run_mouse(ctx: &RunCtx) -> Result<Summary> {
    let p: MouseParams = scene::load(&ctx.scene_file)?.params;
    let w = build_db(&p.database, &p.dp, ctx)?;
    let u = p.database.factor;
    let native = p.database.native_hz;
    // Fastest walk in the database: largest mean root speed of an instance's source slice.
    let fastest = {
        let take = &w.fine.takes[0];
        let m = take.source.as_ref().ok_or_else(|| Error::Run("walk take without motion".into()))?;
        w.fine
            .instances
            .iter()
            .map(|i| {
                let (_, a, b) = i.source;
                let d = m.root_pos[b] - m.root_pos[a];
                d.x.hypot(d.z) / ((b - a) as f64 / native)
            })
            .fold(0.0, f64::max)
    };
    let n = ctx.mode.pick(p.count[0], p.count[1], p.count[2]).min(p.seeds.len());
    let mut csv = CsvWriter::create(
        &ctx.out_dir.join("metrics.csv"),
        &[
            "path",
            "path_rms_m",
            "path_max_m",
            "mid_rms_m",
            "heading_rms_deg",
            "requested_speed",
            "achieved_speed",
            "intrinsic_speed",
            "D_per_frame",
            "dp_s",
        ],
    )?;
    let mut feasible = Vec::new();
    let mut fast_row = [0.0; 5];
    let cases: Vec<(String, Vec<[f64; 2]>)> = p.seeds[..n]
        .iter()
        .map(|&s| (format!("seed{s}"), mouse_path(s, p.secs, native, p.speed)))
        .chain(std::iter::once(("fast".to_string(), straight_stroke(p.fast_secs, native, p.fast_speed))))
        .collect();
    for (ci, (name, path)) in cases.iter().enumerate() {
        let x_fine = path_control(path, native, HIP_WIDTH, p.smooth);
        let d = drive(&w, &x_fine, u, &p.dp)?;
        let achieved = hips_control(&d.out, HIP_WIDTH);
        let tr = tracking_error(&x_fine, &achieved);
        // Output pelvis floor point vs the requested path point at the same time.
        let nf = path.len().min(d.out.len());
        let errs: Vec<f64> =
            (0..nf).map(|f| (d.out.root_pos[f].x - path[f][0]).hypot(d.out.root_pos[f].z - path[f][1])).collect();
        let prms = (errs.iter().map(|e| e * e).sum::<f64>() / nf as f64).sqrt();
        let pmax = errs.iter().copied().fold(0.0, f64::max);
        let len_path: f64 = path.windows(2).map(|q| (q[1][0] - q[0][0]).hypot(q[1][1] - q[0][1])).sum();
        let len_out: f64 = d.out.root_pos.windows(2).map(|q| (q[1].x - q[0].x).hypot(q[1].z - q[0].z)).sum();
        let dur = (nf.max(2) - 1) as f64 / native;
        let (vreq, vout) = (len_path / dur, len_out / dur);
        let dpf = d.fine.d_total / x_fine.len() as f64;
        // Speed of the motion itself: raw output (no seam offsets), seam frames excluded, so the
        // alignment jumps between segments do not count as walking.
        let raw = pc(target_motion(&w.fine, &d.fine, false))?;
        let seam_frames: Vec<usize> =
            d.fine.segments.iter().filter(|c| c.start > 0).map(|c| c.start as usize).collect();
        let (mut dist, mut steps) = (0.0, 0usize);
        for f in 1..raw.len() {
            if !seam_frames.contains(&f) {
                let q = raw.root_pos[f] - raw.root_pos[f - 1];
                dist += q.x.hypot(q.z);
                steps += 1;
            }
        }
        let intrinsic = dist / (steps.max(1) as f64 / native);
        csv.row(&[
            name.as_str().into(),
            prms.into(),
            pmax.into(),
            tr.rms_m.into(),
            tr.heading_rms_deg.into(),
            vreq.into(),
            vout.into(),
            intrinsic.into(),
            dpf.into(),
            d.dp_s.into(),
        ])?;
        if name == "fast" {
            fast_row = [prms, vout, vreq, dpf, intrinsic];
        } else {
            feasible.push((prms, pmax, tr.heading_rms_deg, dpf));
        }
        if ci == 0 {
            topview(&ctx.out_dir.join("topview.png"), "PC-3: requested path vs achieved hips", &x_fine, &achieved)?;
        }
    }
    let mut s = Summary::new();
    s.set_str("mode", ctx.mode.name());
    s.set_count("paths", feasible.len() as u64);
    s.set_count("db_instances", w.db.instances.len() as u64);
    s.set("path_rms_m_mean", mean(&feasible.iter().map(|r| r.0).collect::<Vec<_>>()));
    s.set("path_rms_m_worst", feasible.iter().map(|r| r.0).fold(0.0, f64::max));
    s.set("path_max_m", feasible.iter().map(|r| r.1).fold(0.0, f64::max));
    s.set("heading_rms_deg_mean", mean(&feasible.iter().map(|r| r.2).collect::<Vec<_>>()));
    s.set("d_per_frame_mean", mean(&feasible.iter().map(|r| r.3).collect::<Vec<_>>()));
    s.set("fast_path_rms_m", fast_row[0]);
    s.set("fast_achieved_speed_m_s", fast_row[1]);
    s.set("fast_requested_speed_m_s", fast_row[2]);
    s.set("fast_d_per_frame", fast_row[3]);
    s.set("fast_intrinsic_speed_m_s", fast_row[4]);
    s.set("db_fastest_step_speed_m_s", fastest);
    Ok(s)
}

// ---------------------------------------------------------------------------------------------
// PC-6 real data

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RealParams {
    /// BVH files relative to the workspace root: [training, split] (the second is cut in half).
    train: String,
    split: String,
    rate_hz: f64,
    factor: usize,
    dp: DpParams,
}

/// PC-6: real capture (CMU), detected foot plants, one held-out half.
pub fn run_real(ctx: &RunCtx) -> Result<Summary> {
    let p: RealParams = scene::load(&ctx.scene_file)?.params;
    if p.factor == 0 || !p.rate_hz.is_finite() || p.rate_hz <= 0.0 {
        return Err(scene::invalid(&ctx.scene_file, "factor and rate_hz must be positive"));
    }
    let root = crate::out::workspace_root();
    let load = |name: &str| -> Result<Motion> {
        let m = bvh::read_file(root.join(name), &bvh::BvhOptions::default())?;
        let mut m = m.resample(1.0 / p.rate_hz)?;
        m.detect_contacts(&geom_core::anim::ContactParams::default());
        Ok(m)
    };
    let a = load(&p.train)?;
    let b = load(&p.split)?;
    let half = b.len() / 2;
    let (b1, b2) = (b.slice(0, half), b.slice(half, b.len()));
    let takes = vec![perf_control::data::take_from_walk(a), perf_control::data::take_from_walk(b1)];
    let segs: usize = takes.iter().map(|t| t.boundaries.len() - 1).sum();
    let working = p.rate_hz / p.factor as f64;
    let db = pc(MappingDb::from_takes(takes, working))?;
    let w = WalkDb { fine: pc(db.at_rate(p.rate_hz))?, before: db.instances.len(), db, cluster_s: 0.0 };
    let x_fine = hips_control(&b2, HIP_WIDTH);
    let d = drive(&w, &x_fine, p.factor, &p.dp)?;
    let achieved = hips_control(&d.out, HIP_WIDTH);
    let tr = tracking_error(&x_fine, &achieved);
    topview(
        &ctx.out_dir.join("topview.png"),
        "PC-6: CMU 01_01 second half, requested vs achieved",
        &x_fine,
        &achieved,
    )?;
    write_segments(&ctx.out_dir.join("segments.csv"), &w, &d)?;
    let bvh_path = ctx.out_dir.join("target.bvh");
    std::fs::write(&bvh_path, bvh::write(&d.out, &BvhWriteOptions::default()))
        .map_err(crate::error::io_err(&bvh_path))?;
    let mut s = Summary::new();
    s.set_str("mode", ctx.mode.name());
    s.set_count("segments_detected", segs as u64);
    s.set_count("db_instances", w.before as u64);
    s.set_count("input_frames", x_fine.len() as u64);
    s.set_count("chosen_segments", d.fine.segments.len() as u64);
    s.set("mid_rms_m", tr.rms_m);
    s.set("mid_max_m", tr.max_m);
    s.set("heading_rms_deg", tr.heading_rms_deg);
    s.set("d_per_frame", d.fine.d_total / x_fine.len() as f64);
    s.set("dp_s", d.dp_s);
    s.set("refine_s", d.refine_s);
    Ok(s)
}

#[cfg(test)]
mod tests {
    use crate::registry::builtin_scenes;
    use crate::run::run_scene;
    use crate::scene::Mode;

    /// Every built-in perf-control scene parses and runs end to end in quick mode (each well under
    /// a second in release), and the quick walk and mouse-path runs meet the spec's tracking targets
    /// (PC-1: midpoint RMS ≤ 0.10 m, heading RMS ≤ 10°; PC-3: path RMS ≤ 0.15 m). Quick mode uses
    /// a smaller database, so the stride and phase figures are left to the default run.
    #[test]
    fn perf_control_scenes_run_quick() {
        let root = std::env::temp_dir().join(format!("xtask-pc-scenes-{}", std::process::id()));
        let mut ran = 0;
        for s in builtin_scenes().unwrap().into_iter().filter(|s| s.id.starts_with("perf-control/")) {
            let dir = root.join(&s.id);
            let sum = run_scene(&s.id, &s.file, Mode::Quick, &dir).unwrap_or_else(|e| panic!("{}: {e}", s.id));
            assert!(dir.join("summary.json").is_file(), "{}: no summary.json", s.id);
            match s.id.as_str() {
                "perf-control/walk" => {
                    assert!(sum.get("long_mid_rms_m").unwrap() <= 0.10);
                    assert!(sum.get("short_mid_rms_m").unwrap() <= 0.10);
                    assert!(sum.get("long_heading_rms_deg").unwrap() <= 10.0);
                }
                "perf-control/mouse-paths" => assert!(sum.get("path_rms_m_worst").unwrap() <= 0.15),
                "perf-control/walk-timing" => {
                    assert!(sum.get("beam_score_excess_rel").unwrap() >= 0.0);
                    assert!(sum.get("gemm_score_diff_rel").unwrap() < 1e-9);
                }
                _ => {}
            }
            ran += 1;
        }
        assert!(ran >= 4, "expected the four perf-control scenes, ran {ran}");
        std::fs::remove_dir_all(&root).unwrap();
    }
}

//! PC-1 (spec §6): a walk database (one generated 120 s take, segmented at every foot plant,
//! clustered to 70 instances) driven by the hips control of held-out walks, 60 s ("long") and
//! 10 s ("short"). Figures per kind: midpoint tracking RMS and max, heading RMS, stride frequency
//! ratio, phase agreement with the true walk, foot skate, DP time. Beside the offline DP, the
//! fixed-lag streaming DP ([`crate::stream`], spec §13) interprets every input with the lag
//! `streaming_lag_s`: its label agreement with the offline chain per working frame (the walk's
//! labels are the steps' lead feet), score excess and measured latency (the longest wait of a
//! frame for its commit).
//!
//! Outputs: tables `metrics` (one row per input), `timing`, `streaming` (one row per input and
//! lag), `segments` and `target_points`
//! (first input), plot `topview` (requested vs achieved hips midpoint of the first input), file
//! `target.bvh` (first input).
//!
//! ```no_run
//! use geom_core::experiment::Size;
//! use geom_core::record::NullRecorder;
//! use perf_control::experiments::walk::{run, Params};
//! let text = std::fs::read_to_string("scenes/perf-control/walk.ron").unwrap();
//! #[derive(serde::Deserialize)]
//! struct Scene { params: Params }
//! let s: Scene = ron::from_str(&text).unwrap();
//! let r = run(&s.params, Size::Quick, &mut NullRecorder::default()).unwrap();
//! println!("long walks: midpoint RMS {} m", r.get_f64("long_mid_rms_m"));
//! ```

use std::collections::BTreeMap;

use geom_core::anim::metrics::foot_skate;
use geom_core::experiment::{BySize, Report, Size, Target};
use geom_core::record::{Cell, Recorder};
use geom_core::stats::{max, mean};
use serde::Deserialize;

use crate::data::walk::HIP_WIDTH;
use crate::data::walk_motion;
use crate::dp::DpParams;
use crate::error::Result;
use crate::eval::dance::frame_labels;
use crate::eval::{phase_agreement, seam_frames, seam_jumps, step_frequency, tracking_error};
use crate::experiments::common::{record_segments, record_target_points, topview};
use crate::output::target_points;
use crate::pipeline::drive;
use crate::presets::{walk_database, WalkDbParams};
use crate::stream::interpret_streaming;
use crate::{hips_control, TrackingStats};

/// Parameters of PC-1 (the RON `params` block of `perf-control/walk`).
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Params {
    /// The walk database.
    pub database: WalkDbParams,
    /// DP parameters (paper: k = 10, ±0.2 s, beam).
    pub dp: DpParams,
    /// Seeds of the long held-out walks.
    pub long_seeds: Vec<u64>,
    /// Long inputs used (a prefix of `long_seeds`).
    pub long_count: BySize<usize>,
    /// Long input length (s).
    pub long_secs: BySize<f64>,
    /// Seeds of the short held-out walks.
    pub short_seeds: Vec<u64>,
    /// Short inputs used.
    pub short_count: BySize<usize>,
    /// Short input length (s).
    pub short_secs: f64,
    /// Lag of the streaming DP run beside the offline DP (s; none when omitted).
    #[serde(default)]
    pub streaming_lag_s: Option<f64>,
}

const METRICS: [&str; 15] = [
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
];

/// Runs PC-1: see the module documentation.
pub fn run(p: &Params, size: Size, rec: &mut dyn Recorder) -> Result<Report> {
    let w = walk_database(&p.database, p.dp.stretch_limit_s, size)?;
    let u = p.database.factor;
    let long_secs = p.long_secs.get(size);
    let nl = p.long_count.get(size).min(p.long_seeds.len());
    let ns = p.short_count.get(size).min(p.short_seeds.len());
    let inputs: Vec<(&str, u64, f64)> = p.long_seeds[..nl]
        .iter()
        .map(|&s| ("long", s, long_secs))
        .chain(p.short_seeds[..ns].iter().map(|&s| ("short", s, p.short_secs)))
        .collect();
    rec.table("metrics", &METRICS)?;
    rec.table("timing", &["kind", "seed", "input_s", "dp_s", "refine_s", "post_s"])?;
    rec.table(
        "streaming",
        &["kind", "seed", "lag_s", "label_agreement", "score_excess_rel", "latency_max_s", "latency_median_s"],
    )?;
    let mut agg: BTreeMap<&str, Vec<[f64; 7]>> = BTreeMap::new();
    // Streaming: (agreeing frames, frames, score excess, measured latency) per kind.
    let mut sagg: BTreeMap<&str, Vec<[f64; 4]>> = BTreeMap::new();
    for (idx, &(kind, seed, secs)) in inputs.iter().enumerate() {
        rec.progress(idx as u64, inputs.len() as u64);
        let truth = walk_motion(seed, secs, p.database.native_hz);
        let x_fine = hips_control(&truth, HIP_WIDTH);
        let d = drive(&w.db, &w.fine, &x_fine, u, &p.dp)?;
        let achieved = hips_control(&d.motion, HIP_WIDTH);
        let tr: TrackingStats = tracking_error(&x_fine, &achieved);
        let stride = step_frequency(&d.motion) / step_frequency(&truth);
        let phase = phase_agreement(&d.motion, &truth);
        let pts = target_points(&w.fine, &d.fine, true)?;
        let (js, med) = seam_jumps(&pts, &seam_frames(&d.fine));
        let skate = foot_skate(&d.motion, &d.motion.labels).rate_cm_s;
        rec.row(
            "metrics",
            &[
                kind.into(),
                Cell::Int(seed as i64),
                secs.into(),
                d.fine.segments.len().into(),
                tr.rms_m.into(),
                tr.max_m.into(),
                tr.heading_rms_deg.into(),
                stride.into(),
                phase.into(),
                js.iter().copied().fold(0.0, geom_core::stats::nan_max).into(),
                med.into(),
                skate.into(),
                d.dp_s.into(),
                d.refine_s.into(),
                d.post_s.into(),
            ],
        )?;
        rec.row(
            "timing",
            &[kind.into(), Cell::Int(seed as i64), secs.into(), d.dp_s.into(), d.refine_s.into(), d.post_s.into()],
        )?;
        agg.entry(kind).or_default().push([tr.rms_m, tr.max_m, tr.heading_rms_deg, stride, phase, skate, d.dp_s]);
        if let Some(lag_s) = p.streaming_lag_s {
            let x = x_fine.downsample(u);
            let lag = (lag_s * x.rate_hz).floor() as usize;
            let s = interpret_streaming(&w.db, &x, &p.dp, lag)?;
            let (a, b) = (frame_labels(&w.db, &s.it), frame_labels(&w.db, &d.coarse));
            let agree = a.iter().zip(&b).filter(|(x, y)| x == y).count() as f64;
            let frames = a.len().min(b.len()) as f64;
            let excess = (s.it.score - d.coarse.score) / d.coarse.score;
            rec.row(
                "streaming",
                &[
                    kind.into(),
                    Cell::Int(seed as i64),
                    s.latency_s.into(),
                    (agree / frames).into(),
                    excess.into(),
                    s.latency_max_s.into(),
                    s.latency_median_s.into(),
                ],
            )?;
            sagg.entry(kind).or_default().push([agree, frames, excess, s.latency_max_s]);
        }
        if idx == 0 {
            record_segments(rec, &w.db, &d.coarse, &d.fine)?;
            topview(rec, &x_fine, &achieved)?;
            if rec.keeps_outputs() {
                let bvh = geom_core::anim::bvh::write(&d.motion, &Default::default());
                rec.file("target.bvh", bvh.as_bytes())?;
            }
            record_target_points(rec, &pts)?;
        }
    }
    rec.progress(inputs.len() as u64, inputs.len() as u64);
    let mut r = Report::default();
    r.count("db_instances_before", w.before as u64);
    r.count("db_instances", w.db.instances.len() as u64);
    r.timing("cluster_s", w.cluster_s);
    for (kind, rows) in &agg {
        let col = |i: usize| rows.iter().map(|r| r[i]).collect::<Vec<f64>>();
        r.num(&format!("{kind}_mid_rms_m"), mean(&col(0)));
        r.num(&format!("{kind}_mid_max_m"), max(&col(1)));
        r.num(&format!("{kind}_heading_rms_deg"), mean(&col(2)));
        r.num(&format!("{kind}_stride_ratio"), mean(&col(3)));
        r.num(&format!("{kind}_phase_agreement"), mean(&col(4)));
        r.num(&format!("{kind}_skate_cm_s"), mean(&col(5)));
        r.timing(&format!("{kind}_dp_s"), mean(&col(6)));
        r.count(&format!("{kind}_inputs"), rows.len() as u64);
    }
    if let Some(lag_s) = p.streaming_lag_s {
        let all: Vec<[f64; 4]> = sagg.values().flatten().copied().collect();
        let agreement =
            |rows: &[[f64; 4]]| rows.iter().map(|r| r[0]).sum::<f64>() / rows.iter().map(|r| r[1]).sum::<f64>();
        for (kind, rows) in &sagg {
            r.num(&format!("{kind}_streaming_label_agreement"), agreement(rows));
        }
        r.num("streaming_lag_s", lag_s);
        r.num("streaming_label_agreement", agreement(&all));
        r.num("streaming_latency_s", max(&all.iter().map(|r| r[3]).collect::<Vec<f64>>()));
        r.num("streaming_score_excess_rel", mean(&all.iter().map(|r| r[2]).collect::<Vec<f64>>()));
        r.check("streaming_label_agreement", Target::AtLeast(0.95), "issue 27: fixed-lag streaming DP in PC-1");
        r.check("streaming_latency_s", Target::AtMost(1.0), "issue 27: fixed-lag streaming DP in PC-1");
    }
    for kind in agg.keys() {
        let src = "PC-1 (spec §6): tracking of held-out walks";
        r.check(&format!("{kind}_mid_rms_m"), Target::AtMost(0.10), src);
        r.check(&format!("{kind}_heading_rms_deg"), Target::AtMost(10.0), src);
        r.check(&format!("{kind}_stride_ratio"), Target::Within(0.9, 1.1), src);
    }
    if agg.contains_key("long") {
        r.check("long_phase_agreement", Target::AtLeast(0.8), "PC-1 (spec §6): expected for 60 s walks");
    }
    Ok(r)
}

//! PC-4 (spec §6): dance semantics. The 12 generated training dances (364 two-beat instances,
//! clustered to 168, 7.5 Hz, ±0.15 s) form the database; the leader's hands and ankles of the 3
//! test dances (91 patterns, 21 unique of which 14 novel) are the control; the synthesised
//! follower is compared with the true one: two-beat error rate, pattern matches, validity of the
//! mismatched patterns, rhythm before and after refinement, follower RMS in closed and open
//! stances, handhold annotation accuracy and the held-hand gap raw, post-processed and after the
//! hand snap ([`crate::handhold::close_hands`]). The whole study is repeated for every toggle-cue
//! amplitude (spec: 0.03, 0.06, 0.12 m; keys `cue_<mm>mm_*`); the unprefixed keys are those of
//! `duet.toggle_cue_m`. At that cue the fixed-lag streaming DP ([`crate::stream`]) runs beside the
//! offline DP on every test dance and its label agreement (per working frame, dance labels) is
//! reported, with its nominal lag and its measured latency (the longest wait of a frame for its
//! commit, `streaming_latency_s`).
//!
//! These figures check the pipeline on generated data (the generator is not tuned to them; spec
//! §6 PC-4): they depend on the cue amplitudes, the toggle rule and the noise.
//!
//! Outputs: tables `dances` (one row per cue and test dance), `confusion` (true label × output
//! label, at the main cue), `streaming` (every lag of `streaming_lag_sweep_s` on every test dance), plots `labels` (true and output label of every two-beat segment of the
//! first test dance) and `held_hand` (gap over time, first test dance).
//!
//! ```no_run
//! use geom_core::experiment::Size;
//! use geom_core::record::NullRecorder;
//! use perf_control::experiments::dance::{run, Params};
//! let text = std::fs::read_to_string("scenes/perf-control/dance.ron").unwrap();
//! #[derive(serde::Deserialize)]
//! struct Scene { params: Params }
//! let s: Scene = ron::from_str(&text).unwrap();
//! let r = run(&s.params, Size::Quick, &mut NullRecorder::default()).unwrap();
//! println!("two-beat error rate {}", r.get_f64("two_beat_error_rate"));
//! ```

use geom_core::experiment::{BySize, Report, Size, Target};
use geom_core::record::{Cell, Recorder, Series};
use geom_core::stats::{mean, median};
use serde::Deserialize;

use crate::dance::grammar::{basic_patterns, label_set, DanceLabel};
use crate::data::duet::{test_dances, DuetParams, DuetTruth};
use crate::db::{MappingDb, Take};
use crate::dp::DpParams;
use crate::error::{PcError, Result};
use crate::eval::dance::{annotation_hits, frame_labels, rhythm_errors, segment_labels, Semantics, StanceError};
use crate::handhold::{close_hands, held_gaps};
use crate::pipeline::{drive_points, DrivenPoints};
use crate::presets::{dance_database, DanceDbParams, PreparedDb};
use crate::stream::interpret_streaming;

/// Parameters of PC-4 (the RON `params` block of `perf-control/dance`).
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Params {
    /// The duet generator (its `toggle_cue_m` is the main cue).
    #[serde(default)]
    pub duet: DuetParams,
    /// Every toggle-cue amplitude studied (m).
    pub toggle_cues_m: Vec<f64>,
    /// The training database.
    pub database: DanceDbParams,
    /// Seed of the test dances.
    pub test_seed: u64,
    /// Test dances used (a prefix of the 3).
    pub test_dances: BySize<usize>,
    /// Patterns kept per test dance (0 = all).
    pub test_patterns: BySize<usize>,
    /// DP parameters (paper: k = 10, ±0.15 s, beam).
    pub dp: DpParams,
    /// Lag of the streaming DP (s).
    pub streaming_lag_s: f64,
    /// Further lags (s) run on every test dance at the main cue for the table `streaming`.
    #[serde(default)]
    pub streaming_lag_sweep_s: Vec<f64>,
    /// Ramp of the hand snap (frames at the full rate).
    pub ik_ramp_frames: usize,
}

/// Everything measured at one cue amplitude.
#[derive(Default)]
struct CueResult {
    sem: Semantics,
    rhythm_coarse: Vec<f64>,
    rhythm_fine: Vec<f64>,
    stance: StanceError,
    ann: (usize, usize),
    gaps: [Vec<f64>; 3],
    dp_s: f64,
    refine_s: f64,
    post_s: f64,
    columns: usize,
    stream_agree: (usize, usize),
    stream_excess: Vec<f64>,
    stream_lag_s: f64,
    stream_latency_s: f64,
    stream_latency_median: Vec<f64>,
}

fn study(
    p: &Params,
    cue: f64,
    size: Size,
    main: bool,
    rec: &mut dyn Recorder,
) -> Result<(CueResult, PreparedDb, Vec<DuetTruth>)> {
    let duet = DuetParams { toggle_cue_m: cue, ..p.duet.clone() };
    let (w, train) = dance_database(&p.database, &duet, p.dp.stretch_limit_s, size)?;
    let mut tests = test_dances(&duet, p.test_seed, Some(p.test_patterns.get(size)).filter(|&n| n > 0))?;
    tests.truncate(p.test_dances.get(size).max(1));
    let factor = p.database.factor;
    let lag = (p.streaming_lag_s * w.db.working_rate_hz).floor() as usize;
    let mut r = CueResult::default();
    for (k, (take, truth)) in tests.iter().enumerate() {
        let d = drive_points(&w.db, &w.fine, &take.control, factor, &p.dp)?;
        r.columns = d.coarse.stats.columns;
        r.dp_s += d.dp_s;
        r.refine_s += d.refine_s;
        r.post_s += d.post_s;
        let out = segment_labels(&w.fine, &d.fine, truth);
        r.sem.add(truth, &out);
        r.rhythm_coarse.extend(rhythm_errors(&d.coarse, truth));
        r.rhythm_fine.extend(rhythm_errors(&d.fine, truth));
        r.stance.add(&d.post, &take.target, truth);
        let ann = d.annotations.clone().ok_or_else(|| PcError::BadParameter {
            name: "database",
            msg: "dance instances carry no handhold annotations".into(),
        })?;
        let (h, n) = annotation_hits(&ann, &truth.annotations);
        r.ann = (r.ann.0 + h, r.ann.1 + n);
        let mut ik = d.post.clone();
        close_hands(&mut ik, &take.control, &ann, p.ik_ramp_frames);
        let gaps = [&d.raw, &d.post, &ik].map(|t| held_gaps(t, &take.control, &truth.annotations));
        if main && k == 0 {
            record_first_dance(rec, &w.fine, &d, truth, &gaps[0], &gaps[1], &gaps[2])?;
        }
        for (all, g) in r.gaps.iter_mut().zip(gaps) {
            all.extend(g);
        }
        rec.row(
            "dances",
            &[
                cue.into(),
                Cell::Int(k as i64),
                truth.bpm.into(),
                truth.patterns.len().into(),
                out.iter().zip(&truth.segments).filter(|(o, s)| **o != Some(s.2)).count().into(),
                d.coarse.segments.len().into(),
                d.dp_s.into(),
            ],
        )?;
        if main {
            stream(&mut r, &w, take, &d, &p.dp, lag)?;
            for &extra in &p.streaming_lag_sweep_s {
                let lag = (extra * w.db.working_rate_hz).floor() as usize;
                let mut e = CueResult::default();
                stream(&mut e, &w, take, &d, &p.dp, lag)?;
                rec.row(
                    "streaming",
                    &[
                        Cell::Int(k as i64),
                        e.stream_lag_s.into(),
                        (e.stream_agree.0 as f64 / e.stream_agree.1 as f64).into(),
                        e.stream_excess[0].into(),
                        e.stream_latency_s.into(),
                        e.stream_latency_median[0].into(),
                    ],
                )?;
            }
        }
    }
    Ok((r, w, train))
}

/// Streaming DP on one test dance against the offline coarse chain: label agreement per working
/// frame and score excess.
fn stream(r: &mut CueResult, w: &PreparedDb, take: &Take, d: &DrivenPoints, dp: &DpParams, lag: usize) -> Result<()> {
    let x = take.control.downsample((take.control.rate_hz / w.db.working_rate_hz).round() as usize);
    let s = interpret_streaming(&w.db, &x, dp, lag)?;
    let (a, b) = (frame_labels(&w.db, &s.it), frame_labels(&w.db, &d.coarse));
    let agree = a.iter().zip(&b).filter(|(x, y)| x.dance() == y.dance()).count();
    r.stream_agree = (r.stream_agree.0 + agree, r.stream_agree.1 + a.len().min(b.len()));
    r.stream_excess.push((s.it.score - d.coarse.score) / d.coarse.score);
    r.stream_lag_s = s.latency_s;
    r.stream_latency_s = geom_core::stats::nan_max(r.stream_latency_s, s.latency_max_s);
    r.stream_latency_median.push(s.latency_median_s);
    Ok(())
}

fn label_code(l: Option<DanceLabel>, vocab: &[DanceLabel]) -> f64 {
    l.and_then(|l| vocab.iter().position(|v| *v == l)).map_or(-1.0, |i| i as f64)
}

#[allow(clippy::too_many_arguments)]
fn record_first_dance(
    rec: &mut dyn Recorder,
    fine: &MappingDb,
    d: &DrivenPoints,
    truth: &DuetTruth,
    raw: &[f64],
    post: &[f64],
    ik: &[f64],
) -> Result<()> {
    let vocab = label_set(&basic_patterns());
    let out = segment_labels(fine, &d.fine, truth);
    let axes = ("two-beat segment".to_string(), "label index (vocabulary order; -1 none)".to_string());
    let truth_pts: Vec<(f64, f64)> =
        truth.segments.iter().enumerate().map(|(i, s)| (i as f64, label_code(Some(s.2), &vocab))).collect();
    let out_pts: Vec<(f64, f64)> = out.iter().enumerate().map(|(i, l)| (i as f64, label_code(*l, &vocab))).collect();
    for (label, pts) in [("true", truth_pts), ("synthesised follower", out_pts)] {
        rec.series(&Series {
            plot: "labels".into(),
            label: label.into(),
            axes: axes.clone(),
            log: (false, false),
            points: pts,
        })?;
    }
    let axes = ("held frame".to_string(), "held-hand gap (cm)".to_string());
    for (label, g) in [("raw", raw), ("post-processed", post), ("hand snap", ik)] {
        let pts = g.iter().enumerate().map(|(i, v)| (i as f64, 100.0 * v)).collect();
        rec.series(&Series {
            plot: "held_hand".into(),
            label: label.into(),
            axes: axes.clone(),
            log: (false, false),
            points: pts,
        })?;
    }
    Ok(())
}

fn cue_key(cue: f64) -> String {
    format!("cue_{}mm_", (cue * 1000.0).round() as i64)
}

/// Runs PC-4: see the module documentation.
pub fn run(p: &Params, size: Size, rec: &mut dyn Recorder) -> Result<Report> {
    let main_cue = p.duet.toggle_cue_m;
    if !p.toggle_cues_m.contains(&main_cue) {
        return Err(PcError::BadParameter {
            name: "toggle_cues_m",
            msg: format!("must hold duet.toggle_cue_m = {main_cue}"),
        });
    }
    rec.table("dances", &["cue_m", "dance", "bpm", "patterns", "two_beat_errors", "segments_out", "dp_s"])?;
    rec.table(
        "streaming",
        &["dance", "lag_s", "label_agreement", "score_excess_rel", "latency_max_s", "latency_median_s"],
    )?;
    let basic = basic_patterns();
    let mut r = Report::default();
    for (i, &cue) in p.toggle_cues_m.iter().enumerate() {
        rec.progress(i as u64, p.toggle_cues_m.len() as u64);
        let main = cue == main_cue;
        let (c, w, train) = study(p, cue, size, main, rec)?;
        let pre = cue_key(cue);
        r.num(&format!("{pre}two_beat_error_rate"), c.sem.error_rate());
        r.count(&format!("{pre}pattern_matches"), c.sem.pattern_matches as u64);
        r.num(&format!("{pre}mismatch_valid_share"), c.sem.valid_share());
        r.num(&format!("{pre}rhythm_error_median_frames_30hz"), median(&c.rhythm_fine));
        r.num(&format!("{pre}closed_rms_m"), c.stance.closed_rms());
        r.num(&format!("{pre}open_rms_m"), c.stance.open_rms());
        if !main {
            continue;
        }
        r.count("training_dances", train.len() as u64);
        r.count("training_patterns", train.iter().map(|t| t.patterns.len() as u64).sum());
        r.count("db_instances_before", w.before as u64);
        r.count("db_instances", w.db.instances.len() as u64);
        r.count("columns_p", c.columns as u64);
        r.num("toggle_cue_m", cue);
        r.count("two_beat_segments", c.sem.segments as u64);
        r.count("two_beat_errors", c.sem.segment_errors as u64);
        r.num("two_beat_error_rate", c.sem.error_rate());
        r.count("patterns", c.sem.patterns as u64);
        r.count("pattern_matches", c.sem.pattern_matches as u64);
        r.count("mismatches_valid", c.sem.mismatches_valid as u64);
        r.num("mismatch_valid_share", c.sem.valid_share());
        r.count("unique_patterns", c.sem.unique.len() as u64);
        r.count("novel_patterns", c.sem.novel(&basic) as u64);
        r.num("rhythm_error_median_frames_working", median(&c.rhythm_coarse));
        r.num("rhythm_error_median_frames_30hz", median(&c.rhythm_fine));
        r.num("rhythm_error_median_ms", median(&c.rhythm_fine) * 1000.0 / p.duet.rate_hz);
        r.num("closed_rms_m", c.stance.closed_rms());
        r.num("open_rms_m", c.stance.open_rms());
        r.num("closed_over_open_rms", c.stance.closed_rms() / c.stance.open_rms());
        r.num("handhold_annotation_accuracy", c.ann.0 as f64 / c.ann.1 as f64);
        r.num("held_gap_cm_raw", 100.0 * mean(&c.gaps[0]));
        r.num("held_gap_cm_post", 100.0 * mean(&c.gaps[1]));
        r.num("held_gap_cm_ik", 100.0 * mean(&c.gaps[2]));
        r.num("streaming_label_agreement", c.stream_agree.0 as f64 / c.stream_agree.1 as f64);
        r.num("streaming_lag_s", c.stream_lag_s);
        r.num("streaming_latency_s", c.stream_latency_s);
        r.num("streaming_latency_median_s", median(&c.stream_latency_median));
        r.num("streaming_score_excess_rel", mean(&c.stream_excess));
        r.timing("dp_s", c.dp_s);
        r.timing("refine_s", c.refine_s);
        r.timing("post_s", c.post_s);
        record_confusion(rec, &c.sem)?;
    }
    rec.progress(p.toggle_cues_m.len() as u64, p.toggle_cues_m.len() as u64);
    let src = "PC-4 (spec §6, issue 27): dance semantics at the main toggle cue";
    r.check("two_beat_error_rate", Target::AtMost(0.02), src);
    r.check("pattern_matches", Target::AtLeast(86.0), src);
    r.check("rhythm_error_median_frames_working", Target::AtMost(1.0), src);
    r.check("rhythm_error_median_frames_30hz", Target::AtMost(1.0), src);
    r.check("closed_over_open_rms", Target::Below(1.0), src);
    r.check("unique_patterns", Target::Equals(21.0), "spec §3.13: 21 composable test patterns");
    r.check("novel_patterns", Target::Equals(14.0), "spec §3.13: 14 of them novel");
    r.check("streaming_label_agreement", Target::AtLeast(0.95), "issue 27: fixed-lag streaming DP");
    r.check("streaming_latency_s", Target::AtMost(1.0), "issue 27: fixed-lag streaming DP");
    Ok(r)
}

/// Table `confusion`: one row per true label, one column per output label (and `none`).
fn record_confusion(rec: &mut dyn Recorder, sem: &Semantics) -> Result<()> {
    let mut outs: Vec<Option<DanceLabel>> = sem.confusion.keys().map(|k| k.1).collect();
    outs.sort();
    outs.dedup();
    let mut trues: Vec<DanceLabel> = sem.confusion.keys().map(|k| k.0).collect();
    trues.sort();
    trues.dedup();
    let names: Vec<String> = outs.iter().map(|o| o.map_or("none".to_string(), |l| l.to_string())).collect();
    let mut header: Vec<&str> = vec!["true"];
    header.extend(names.iter().map(String::as_str));
    rec.table("confusion", &header)?;
    for t in trues {
        let mut row = vec![Cell::Text(t.to_string())];
        row.extend(outs.iter().map(|o| Cell::Int(sem.confusion.get(&(t, *o)).copied().unwrap_or(0) as i64)));
        rec.row("confusion", &row)?;
    }
    Ok(())
}

//! The library calls of the accuracy-versus-time sweeps of spec §9 (`cargo xtask bench
//! perf-control`): the benchmark's walk database and input, and one evaluation of a sweep point
//! (database reduced at a working rate, DP, refinement, skeletal output, tracking and seams);
//! the dance rows: the PC-4 database and one test dance, and one DP of a dance sweep point
//! ([`DanceSweep`], [`evaluate_dance`]).
//!
//! ```no_run
//! use perf_control::experiments::sweeps::{evaluate, WalkSweep};
//! use perf_control::{ClusterDistance, DpParams};
//! let s = WalkSweep::new(true);
//! let e = evaluate(&s, 3, Some(40), ClusterDistance::ControlAndTarget, &DpParams::default()).unwrap();
//! println!("DP {} s, tracking RMS {} m", e.dp_s, e.rms);
//! ```

use std::time::Instant;

use geom_core::experiment::{BySize, Size};

use crate::dance::grammar::DanceLabel;
use crate::data::duet::{test_dances, DuetParams, DuetTruth};
use crate::data::walk::HIP_WIDTH;
use crate::data::{walk_motion, walk_take};
use crate::db::{MappingDb, Take};
use crate::dp::{interpret, DpParams};
use crate::error::Result;
use crate::eval::dance::segment_labels;
use crate::eval::{seam_frames, seam_jumps};
use crate::output::{achieved_control, target_motion, target_points};
use crate::presets::{dance_database, DanceDbParams, PreparedDb};
use crate::reduce::{ClusterBy, ClusterDistance, ClusterOptions, Representative};
use crate::refine::refine;
use crate::track::PointTrack;
use crate::{hips_control, tracking_error};
use geom_core::clock::process_cpu_s;

/// The walk sweeps' data: a database take (120 s, 40 s quick) and a held-out input (57 s, 20 s
/// quick), both at 30 Hz.
#[derive(Clone, Debug)]
pub struct WalkSweep {
    /// The database take (seed 11).
    pub take: Take,
    /// The input's hips control at 30 Hz (seed 301).
    pub x_fine: PointTrack,
    /// Reduced sizes.
    pub quick: bool,
}

impl WalkSweep {
    /// The sweeps' data at default or quick size.
    pub fn new(quick: bool) -> WalkSweep {
        WalkSweep {
            take: walk_take(11, if quick { 40.0 } else { 120.0 }, 30.0),
            x_fine: hips_control(&walk_motion(301, if quick { 20.0 } else { 57.0 }, 30.0), HIP_WIDTH),
            quick,
        }
    }

    /// PC-1's database size at this scale (70, 40 quick).
    pub fn db_size(&self) -> usize {
        if self.quick {
            40
        } else {
            70
        }
    }
}

/// What one sweep point measured.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SweepPoint {
    /// DP wall time (s).
    pub dp_s: f64,
    /// DP score `S` (m²).
    pub score: f64,
    /// Tracking RMS after refinement and skeletal output (m).
    pub rms: f64,
    /// Tracking RMS of the coarse placed control, refinement off (m).
    pub coarse_rms: f64,
    /// Largest raw seam jump of the target points, before blending (m); NaN without seams.
    pub jump: f64,
    /// DP columns `P`.
    pub columns: usize,
}

/// One evaluation: database reduced to `size` (random representatives, seed 11) at `factor`
/// (working rate 30/factor Hz), DP with `p`, refinement to 30 Hz and skeletal output.
pub fn evaluate(
    s: &WalkSweep,
    factor: usize,
    size: Option<usize>,
    mode: ClusterDistance,
    p: &DpParams,
) -> Result<SweepPoint> {
    let mut db = MappingDb::from_takes(vec![s.take.clone()], 30.0 / factor as f64)?;
    if let Some(n) = size.filter(|&n| n < db.instances.len()) {
        db.cluster(&ClusterOptions {
            by: ClusterBy::TargetSize(n),
            distance: mode,
            stretch_limit_s: p.stretch_limit_s,
            representative: Representative::Random,
            seed: 11,
        })?;
    }
    let x = s.x_fine.downsample(factor);
    let t0 = Instant::now();
    let it = interpret(&db, &x, p)?;
    let dp_s = t0.elapsed().as_secs_f64();
    let coarse_rms = tracking_error(&x, &achieved_control(&db, &it)?).rms_m;
    let fine_db = db.at_rate(30.0)?;
    let fine = if factor > 1 { refine(&fine_db, &s.x_fine, &it, factor, p)? } else { it.clone() };
    let out = target_motion(&fine_db, &fine, true)?;
    let rms = tracking_error(&s.x_fine, &hips_control(&out, HIP_WIDTH)).rms_m;
    let pts = target_points(&fine_db, &fine, false)?;
    let jump = geom_core::stats::max(&seam_jumps(&pts, &seam_frames(&fine)).0);
    Ok(SweepPoint { dp_s, score: it.score, rms, coarse_rms, jump, columns: it.stats.columns })
}

/// The dance sweeps' data (spec §9, dance rows): the PC-4 database (the 12 training dances at the
/// default generator, two-beat instances at 7.5 Hz, ±0.15 s, clustered to 168) and the first PC-4
/// test dance (125 bpm; its first 10 patterns with `quick`, all 30 otherwise).
#[derive(Clone, Debug)]
pub struct DanceSweep {
    /// The database and its full-rate twin.
    pub db: PreparedDb,
    /// The leader's points of the test dance at 30 Hz.
    pub x_fine: PointTrack,
    /// The test dance's truth.
    pub truth: DuetTruth,
    /// Downsampling factor (4: 30 → 7.5 Hz).
    pub factor: usize,
}

impl DanceSweep {
    /// The dance sweeps' data at default or quick size (seeds of `scenes/perf-control/dance.ron`).
    pub fn new(quick: bool) -> Result<DanceSweep> {
        let duet = DuetParams::default();
        let p = DanceDbParams {
            seed: 27,
            dances: BySize::Same(12),
            factor: 4,
            cluster_to: BySize::Same(168),
            cluster_distance: ClusterDistance::ControlAndTarget,
        };
        let (db, _) = dance_database(&p, &duet, 0.15, Size::Default)?;
        let mut tests = test_dances(&duet, 271, quick.then_some(10))?;
        let (take, truth) = tests.swap_remove(0);
        Ok(DanceSweep { db, x_fine: take.control, truth, factor: p.factor })
    }
}

/// What one dance sweep point measured.
#[derive(Clone, Debug, PartialEq)]
pub struct DanceSweepPoint {
    /// DP wall time (s).
    pub dp_s: f64,
    /// DP CPU time of the process, every thread (s).
    pub dp_cpu_s: f64,
    /// DP score `S` (m²).
    pub score: f64,
    /// Two-beat error rate against the truth (coarse chain, segment midpoints).
    pub two_beat_error_rate: f64,
    /// The output label of every true two-beat segment.
    pub labels: Vec<Option<DanceLabel>>,
    /// Cells expanded by the DP.
    pub cells_expanded: u64,
    /// DP columns `P`.
    pub columns: usize,
}

/// One dance DP with `p` on the sweep's test dance (stretch limit as in `p`; the database was
/// built at ±0.15 s).
pub fn evaluate_dance(s: &DanceSweep, p: &DpParams) -> Result<DanceSweepPoint> {
    let x = s.x_fine.downsample(s.factor);
    let (t0, c0) = (Instant::now(), process_cpu_s());
    let it = interpret(&s.db.db, &x, p)?;
    let (dp_s, dp_cpu_s) = (t0.elapsed().as_secs_f64(), process_cpu_s() - c0);
    let labels = segment_labels(&s.db.db, &it, &s.truth);
    let errors = labels.iter().zip(&s.truth.segments).filter(|(o, t)| **o != Some(t.2)).count();
    Ok(DanceSweepPoint {
        dp_s,
        dp_cpu_s,
        score: it.score,
        two_beat_error_rate: errors as f64 / labels.len() as f64,
        labels,
        cells_expanded: it.stats.cells_expanded,
        columns: it.stats.columns,
    })
}

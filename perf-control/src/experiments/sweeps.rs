//! The library calls of the accuracy-versus-time sweeps of spec §9 (`cargo xtask bench
//! perf-control`): the benchmark's walk database and input, and one evaluation of a sweep point
//! (database reduced at a working rate, DP, refinement, skeletal output, tracking and seams).
//!
//! ```no_run
//! use perf_control::experiments::sweeps::{evaluate, WalkSweep};
//! use perf_control::{ClusterDistance, DpParams};
//! let s = WalkSweep::new(true);
//! let e = evaluate(&s, 3, Some(40), ClusterDistance::ControlAndTarget, &DpParams::default()).unwrap();
//! println!("DP {} s, tracking RMS {} m", e.dp_s, e.rms);
//! ```

use std::time::Instant;

use crate::data::walk::HIP_WIDTH;
use crate::data::{walk_motion, walk_take};
use crate::db::{MappingDb, Take};
use crate::dp::{interpret, DpParams};
use crate::error::Result;
use crate::eval::{seam_frames, seam_jumps};
use crate::output::{achieved_control, target_motion, target_points};
use crate::reduce::{ClusterBy, ClusterDistance, ClusterOptions, Representative};
use crate::refine::refine;
use crate::track::PointTrack;
use crate::{hips_control, tracking_error};

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

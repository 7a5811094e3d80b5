//! The end-to-end call of the method (spec §2, §3.5–§3.10): a control signal at the full rate →
//! the target motion. The control is downsampled to the working rate, interpreted by the DP
//! (paper eqs. 6–7), the chain is refined at the full rate (§3.8), and the chosen source slices
//! are stretched, placed and blended at the seams (§3.9–§3.10).
//!
//! ```no_run
//! use perf_control::data::{walk::HIP_WIDTH, walk_motion, walk_take};
//! use perf_control::{drive, hips_control, DpParams, PreparedDb};
//! let w = PreparedDb::unclustered(vec![walk_take(11, 40.0, 30.0)], 10.0, 30.0).unwrap();
//! let control = hips_control(&walk_motion(101, 20.0, 30.0), HIP_WIDTH);
//! let d = drive(&w.db, &w.fine, &control, 3, &DpParams { beam: Some(0.3), ..DpParams::default() }).unwrap();
//! println!("{} segments, {} frames, DP {:.3} s", d.fine.segments.len(), d.motion.len(), d.dp_s);
//! ```

use std::time::Instant;

use geom_core::anim::Motion;

use crate::db::MappingDb;
use crate::dp::{interpret, DpParams, Interpretation};
use crate::error::Result;
use crate::output::{propagate, target_motion, target_points};
use crate::refine::refine;
use crate::track::PointTrack;

/// What driving a database with one control produced.
#[derive(Clone, Debug)]
pub struct Driven {
    /// The DP's chain at the working rate.
    pub coarse: Interpretation,
    /// The chain refined at the full rate.
    pub fine: Interpretation,
    /// The skeletal output, post-processed (§3.10).
    pub motion: Motion,
    /// DP wall time (s).
    pub dp_s: f64,
    /// Refinement wall time (s).
    pub refine_s: f64,
    /// Skeletal output and post-processing wall time (s).
    pub post_s: f64,
}

/// Drives the database: `db` at the working rate, `db_fine` the same instances at the full rate
/// ([`MappingDb::at_rate`]), `x_fine` the control at the full rate, `factor` the downsampling
/// factor `u` (working rate = full rate / `u`). The takes must carry their source motions.
pub fn drive(db: &MappingDb, db_fine: &MappingDb, x_fine: &PointTrack, factor: usize, dp: &DpParams) -> Result<Driven> {
    let x = x_fine.downsample(factor);
    let t0 = Instant::now();
    let coarse = interpret(db, &x, dp)?;
    let dp_s = t0.elapsed().as_secs_f64();
    let t1 = Instant::now();
    let fine = refine(db_fine, x_fine, &coarse, factor, dp)?;
    let refine_s = t1.elapsed().as_secs_f64();
    let t2 = Instant::now();
    let motion = target_motion(db_fine, &fine, true)?;
    let post_s = t2.elapsed().as_secs_f64();
    Ok(Driven { coarse, fine, motion, dp_s, refine_s, post_s })
}

/// What driving a point-cloud database (no source skeletons, e.g. the dance) produced.
#[derive(Clone, Debug)]
pub struct DrivenPoints {
    /// The DP's chain at the working rate.
    pub coarse: Interpretation,
    /// The chain refined at the full rate.
    pub fine: Interpretation,
    /// Target points, raw concatenation of the placed segments (§3.9).
    pub raw: PointTrack,
    /// Target points post-processed (§3.10).
    pub post: PointTrack,
    /// The propagated per-frame annotations (§3.11), `None` when the instances carry none.
    pub annotations: Option<Vec<u64>>,
    /// DP wall time (s).
    pub dp_s: f64,
    /// Refinement wall time (s).
    pub refine_s: f64,
    /// Target points (raw and post-processed) and annotation propagation wall time (s).
    pub post_s: f64,
}

/// [`drive`] for point output: the same DP and refinement, then the raw and post-processed target
/// points and the propagated annotations (no skeleton needed).
pub fn drive_points(
    db: &MappingDb,
    db_fine: &MappingDb,
    x_fine: &PointTrack,
    factor: usize,
    dp: &DpParams,
) -> Result<DrivenPoints> {
    let x = x_fine.downsample(factor);
    let t0 = Instant::now();
    let coarse = interpret(db, &x, dp)?;
    let dp_s = t0.elapsed().as_secs_f64();
    let t1 = Instant::now();
    let fine = refine(db_fine, x_fine, &coarse, factor, dp)?;
    let refine_s = t1.elapsed().as_secs_f64();
    let t2 = Instant::now();
    let raw = target_points(db_fine, &fine, false)?;
    let post = target_points(db_fine, &fine, true)?;
    let annotations = propagate(db_fine, &fine)?;
    let post_s = t2.elapsed().as_secs_f64();
    Ok(DrivenPoints { coarse, fine, raw, post, annotations, dp_s, refine_s, post_s })
}

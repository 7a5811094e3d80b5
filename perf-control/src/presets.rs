//! The paper's setups (spec §6, §4): the walk database of PC-1/2/3 (one long generated walk take,
//! segmented at every foot plant, cut at the working rate and clustered to a target size) with
//! its full-rate twin for the refinement of §3.8; the dance database of PC-4/PC-5 (the 12
//! generated training dances, two-beat instances at 7.5 Hz clustered to 168).

use std::time::Instant;

use geom_core::experiment::{BySize, Size};
use serde::Deserialize;

use crate::data::duet::{training_dances, DuetParams, DuetTruth};
use crate::data::walk_take;
use crate::db::MappingDb;
use crate::error::{PcError, Result};
use crate::reduce::{ClusterBy, ClusterDistance, ClusterOptions, Representative};

/// The walk database of a scene (the RON `database` block of PC-1, PC-2, PC-3).
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct WalkDbParams {
    /// Generator seed of the database walk (also the clustering seed).
    pub seed: u64,
    /// Length of the database walk (s; paper: 120 s).
    pub secs: BySize<f64>,
    /// Native rate (Hz) of the synthesised walks.
    pub native_hz: f64,
    /// Downsampling factor `u` (working rate = native / u; paper: 30 → 10 Hz).
    pub factor: usize,
    /// Target database size after clustering (0 = no clustering; paper: 70).
    pub cluster_to: BySize<usize>,
    /// Which signals define instance similarity (spec §3.7).
    pub cluster_distance: ClusterDistance,
}

/// A database at the working rate and the same instances at the native rate.
#[derive(Clone, Debug)]
pub struct PreparedDb {
    /// Instances at the working rate (the DP's database).
    pub db: MappingDb,
    /// The same instances at the native rate (refinement, skeletal output).
    pub fine: MappingDb,
    /// Instances before clustering.
    pub before: usize,
    /// Clustering wall time (s).
    pub cluster_s: f64,
}

impl PreparedDb {
    /// A database from takes at `working_hz`, unclustered, with its twin at `native_hz`.
    pub fn unclustered(takes: Vec<crate::db::Take>, working_hz: f64, native_hz: f64) -> Result<PreparedDb> {
        let db = MappingDb::from_takes(takes, working_hz)?;
        Ok(PreparedDb { fine: db.at_rate(native_hz)?, before: db.instances.len(), db, cluster_s: 0.0 })
    }
}

/// Builds the walk database of `p` at run size `size`: a walk take of `secs` seconds at
/// `native_hz` ([`walk_take`]), instances at `native_hz / factor`, clustered to `cluster_to`
/// (random representatives with the seed `p.seed`; the `2Δ` rule uses `stretch_limit_s`).
pub fn walk_database(p: &WalkDbParams, stretch_limit_s: f64, size: Size) -> Result<PreparedDb> {
    if p.factor == 0 || !(p.native_hz.is_finite() && p.native_hz > 0.0) {
        return Err(PcError::BadParameter { name: "database", msg: "factor and native_hz must be positive".into() });
    }
    let take = walk_take(p.seed, p.secs.get(size), p.native_hz);
    let working = p.native_hz / p.factor as f64;
    let mut db = MappingDb::from_takes(vec![take], working)?;
    let before = db.instances.len();
    let t0 = Instant::now();
    let target = p.cluster_to.get(size);
    if target > 0 && target < before {
        db.cluster(&ClusterOptions {
            by: ClusterBy::TargetSize(target),
            distance: p.cluster_distance,
            stretch_limit_s,
            representative: Representative::Random,
            seed: p.seed,
        })?;
    }
    let cluster_s = t0.elapsed().as_secs_f64();
    let fine = db.at_rate(p.native_hz)?;
    Ok(PreparedDb { db, fine, before, cluster_s })
}

/// The dance database of a scene (the RON `database` block of PC-4 and PC-5, spec §6).
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DanceDbParams {
    /// Seed of the training dances (also the clustering seed).
    pub seed: u64,
    /// Training dances used (a prefix of the 12 of spec §3.13).
    pub dances: BySize<usize>,
    /// Downsampling factor `u` (working rate = duet rate / u; spec: 30 → 7.5 Hz).
    pub factor: usize,
    /// Target database size after clustering (0 = no clustering; spec: 364 → 168).
    pub cluster_to: BySize<usize>,
    /// Which signals define instance similarity (spec §3.7).
    pub cluster_distance: ClusterDistance,
}

/// Builds the dance database of `p` at run size `size` for the generator `duet`: the first
/// `dances` training dances ([`training_dances`]), instances at `duet.rate_hz / factor`, clustered
/// to `cluster_to` (random representatives, seed `p.seed`; the `2Δ` rule uses `stretch_limit_s`),
/// with the twin at the duet rate. Returns the database and the truths of the dances used.
pub fn dance_database(
    p: &DanceDbParams,
    duet: &DuetParams,
    stretch_limit_s: f64,
    size: Size,
) -> Result<(PreparedDb, Vec<DuetTruth>)> {
    if p.factor == 0 {
        return Err(PcError::BadParameter { name: "database.factor", msg: "must be positive".into() });
    }
    let mut dances = training_dances(duet, p.seed)?;
    dances.truncate(p.dances.get(size).max(1));
    let (takes, truths): (Vec<_>, Vec<_>) = dances.into_iter().unzip();
    let mut db = MappingDb::from_takes(takes, duet.rate_hz / p.factor as f64)?;
    let before = db.instances.len();
    let t0 = Instant::now();
    let target = p.cluster_to.get(size);
    if target > 0 && target < before {
        db.cluster(&ClusterOptions {
            by: ClusterBy::TargetSize(target),
            distance: p.cluster_distance,
            stretch_limit_s,
            representative: Representative::Random,
            seed: p.seed,
        })?;
    }
    let cluster_s = t0.elapsed().as_secs_f64();
    let fine = db.at_rate(duet.rate_hz)?;
    Ok((PreparedDb { db, fine, before, cluster_s }, truths))
}

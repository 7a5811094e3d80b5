//! Database reduction by complete-linkage clustering (spec §3.7): similar instances are merged
//! and one representative per cluster is kept, which shrinks `P` (DP cost ∝ P²) and removes
//! ambiguity for the beam.

use crate::align::{align, residual};
use crate::db::MappingDb;
use crate::error::{PcError, Result};
use crate::track::stretch_into;
use geom_core::cluster::{cluster_count, complete_linkage, Cut};
use geom_core::rng::Rng;
use serde::{Deserialize, Serialize};

/// How far to reduce.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub enum ClusterBy {
    /// Merge while the complete-linkage distance is ≤ this (m², per-sample mean).
    Threshold(f64),
    /// Aim for this many clusters (±2).
    TargetSize(usize),
}

/// Which signals define instance similarity (spec §12 item 4).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum ClusterDistance {
    /// Control only (the paper, eq. 1).
    ControlOnly,
    /// `max(control, target)`, the target placed by the control's alignment (default).
    ControlAndTarget,
}

/// Which member represents a cluster.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum Representative {
    /// A member drawn with the seeded RNG (the paper).
    Random,
    /// The member with the smallest largest distance to the others.
    Medoid,
}

/// Clustering options.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct ClusterOptions {
    /// Cut.
    pub by: ClusterBy,
    /// Distance mode.
    pub distance: ClusterDistance,
    /// Stretch limit (s) of the DP: instances whose lengths differ by more than `2Δ` are never
    /// merged.
    pub stretch_limit_s: f64,
    /// Representative choice.
    pub representative: Representative,
    /// RNG seed (random representatives).
    pub seed: u64,
}

/// What the reduction did.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ClusterReport {
    /// Instances before.
    pub before: usize,
    /// Instances after (clusters).
    pub after: usize,
    /// Largest distance between two members of one cluster (m²).
    pub max_intra: f64,
    /// For every old instance, the index of its cluster's representative in the new database.
    pub map: Vec<u32>,
}

/// One-directional distance (spec §3.7): instance `v` stretched to `u`'s length and aligned by
/// the control; per-sample mean of the control residual, and of the target residual placed by the
/// same `M` (mode `ControlAndTarget`).
fn directed(db: &MappingDb, u: usize, v: usize, mode: ClusterDistance) -> f64 {
    let (iu, iv) = (&db.instances[u], &db.instances[v]);
    let n = iu.n();
    let mut ac = Vec::new();
    stretch_into(&iv.control.data, iv.control.n_points, n, &mut ac);
    let al = align(&iu.control.data, &ac, &db.control_weights);
    let dc = al.d / (n + 1) as f64;
    match mode {
        ClusterDistance::ControlOnly => dc,
        ClusterDistance::ControlAndTarget => {
            let mut at = Vec::new();
            stretch_into(&iv.target.data, iv.target.n_points, n, &mut at);
            let dt = residual(&iu.target.data, &at, &db.target_weights, &al.m) / (n + 1) as f64;
            dc.max(dt)
        }
    }
}

/// Symmetric instance distance: `∞` if `|n_u − n_v| > 2Δ`, else the maximum of both directions.
pub fn instance_distance(db: &MappingDb, u: usize, v: usize, delta: usize, mode: ClusterDistance) -> f64 {
    let (nu, nv) = (db.instances[u].n(), db.instances[v].n());
    if nu.abs_diff(nv) > 2 * delta {
        return f64::INFINITY;
    }
    directed(db, u, v, mode).max(directed(db, v, u, mode))
}

impl MappingDb {
    /// Reduces the database in place (spec §3.7); instance indices change, `report.map` gives
    /// the new index of every old instance's representative.
    pub fn cluster(&mut self, o: &ClusterOptions) -> Result<ClusterReport> {
        if !(o.stretch_limit_s.is_finite() && o.stretch_limit_s >= 0.0) {
            return Err(PcError::BadParameter { name: "stretch_limit_s", msg: format!("{}", o.stretch_limit_s) });
        }
        let n = self.instances.len();
        let delta = (o.stretch_limit_s * self.working_rate_hz).round() as usize;
        let mut dm = vec![0.0; n * n];
        for u in 0..n {
            for v in (u + 1)..n {
                let d = instance_distance(self, u, v, delta, o.distance);
                dm[u * n + v] = d;
                dm[v * n + u] = d;
            }
        }
        let cut = match o.by {
            ClusterBy::Threshold(t) if t.is_nan() => {
                return Err(PcError::BadParameter { name: "cluster threshold", msg: "NaN".into() });
            }
            ClusterBy::Threshold(t) => Cut::Threshold(t),
            ClusterBy::TargetSize(0) => {
                return Err(PcError::BadParameter { name: "cluster target size", msg: "must be ≥ 1".into() });
            }
            ClusterBy::TargetSize(m) => Cut::TargetCount { n: m, tol: 2 },
        };
        let labels = complete_linkage(n, &|i, j| dm[i * n + j], cut);
        let nc = cluster_count(&labels);
        let mut members: Vec<Vec<usize>> = vec![vec![]; nc];
        for (i, &l) in labels.iter().enumerate() {
            members[l as usize].push(i);
        }
        let mut rng = Rng::new(o.seed);
        let mut max_intra: f64 = 0.0;
        let reps: Vec<usize> = members
            .iter()
            .map(|m| {
                for &a in m {
                    for &b in m {
                        max_intra = max_intra.max(dm[a * n + b]);
                    }
                }
                match o.representative {
                    Representative::Random => m[rng.below(m.len())],
                    Representative::Medoid => *m
                        .iter()
                        .min_by(|&&a, &&b| {
                            let fa = m.iter().map(|&c| dm[a * n + c]).fold(0.0, f64::max);
                            let fb = m.iter().map(|&c| dm[b * n + c]).fold(0.0, f64::max);
                            fa.total_cmp(&fb)
                        })
                        .unwrap_or(&m[0]),
                }
            })
            .collect();
        let map = labels.clone();
        self.instances = reps.iter().map(|&r| self.instances[r].clone()).collect();
        Ok(ClusterReport { before: n, after: nc, max_intra, map })
    }
}

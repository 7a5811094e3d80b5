//! The coarse exhaustive search that starts the annealing (Bhat et al. 2003 §4.2: "we choose
//! four values for each cloth parameter across its entire range ... We initialize the
//! optimizer with the point corresponding to the minimum error"; spec §3.8).
//!
//! Grid values sit at the unit-cube cell centres (2i + 1)/(2k), i = 0..k−1 ({1/8, 3/8, 5/8, 7/8}
//! for k = 4), which avoids the most extreme corners of the ranges. Points run in parallel.

use geom_core::rng::Rng;
use serde::{Deserialize, Serialize};

use crate::error::{FitError, Result};
use crate::objective::{EvalRecord, EvalStatus, Objective};
use crate::params::ParamId;

/// The coarse search (spec §2 `CoarseSearch`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum CoarseSearch {
    /// No search: start from the base point. (Not `None`: inside the untagged `BySize` of a
    /// scene file, ron hands a bare `None` to serde as an empty option, and `Some(None)` no
    /// longer parsed as this variant.)
    Off,
    /// A full grid over `params` with `values_per_param` cell centres each; the other free
    /// parameters stay at the base point.
    Grid {
        /// Values per parameter (2–5).
        values_per_param: usize,
        /// The gridded parameters.
        params: Vec<ParamId>,
    },
    /// A Latin hypercube over all free parameters (a cheap alternative, §9).
    LatinHypercube {
        /// Number of samples.
        samples: usize,
        /// Seed.
        seed: u64,
    },
}

/// The unit-cube points of the search, in evaluation order. `base` gives the coordinates of
/// the parameters that are not gridded.
pub fn coarse_points(c: &CoarseSearch, free: &[ParamId], base: &[f64]) -> Result<Vec<Vec<f64>>> {
    match c {
        CoarseSearch::Off => Ok(vec![base.to_vec()]),
        CoarseSearch::Grid { values_per_param: k, params } => {
            if !(1..=8).contains(k) {
                return Err(FitError::BadParameter(format!("coarse grid: values_per_param {k} outside 1..=8")));
            }
            let dims: Vec<usize> = params
                .iter()
                .map(|id| {
                    free.iter().position(|f| f == id).ok_or_else(|| {
                        FitError::BadParameter(format!("coarse grid parameter {} is not free", id.name()))
                    })
                })
                .collect::<Result<_>>()?;
            let total = k.pow(dims.len() as u32);
            let mut pts = Vec::with_capacity(total);
            for n in 0..total {
                let mut x = base.to_vec();
                let mut m = n;
                // First gridded parameter varies slowest.
                for &d in dims.iter().rev() {
                    x[d] = (2 * (m % k) + 1) as f64 / (2 * k) as f64;
                    m /= k;
                }
                pts.push(x);
            }
            Ok(pts)
        }
        CoarseSearch::LatinHypercube { samples, seed } => {
            if *samples == 0 {
                return Err(FitError::BadParameter("Latin hypercube with 0 samples".into()));
            }
            let mut rng = Rng::new(*seed);
            let n = free.len();
            let cols: Vec<Vec<usize>> = (0..n)
                .map(|_| {
                    let mut v: Vec<usize> = (0..*samples).collect();
                    rng.shuffle(&mut v);
                    v
                })
                .collect();
            // Sample-major, dimension-minor: the order the rng is drawn in.
            let pts: Vec<Vec<f64>> = (0..*samples)
                .map(|s| cols.iter().map(|c| (c[s] as f64 + rng.f64()) / *samples as f64).collect())
                .collect();
            Ok(pts)
        }
    }
}

/// Evaluates the coarse search (in parallel) and returns the records in point order (spec §2
/// `coarse_search`). Errors: [`FitError::NoValidStart`] when every point failed to simulate.
pub fn coarse_search(obj: &Objective, c: &CoarseSearch, base: &[f64]) -> Result<Vec<EvalRecord>> {
    let pts = coarse_points(c, &obj.space().free, base)?;
    let recs = obj.eval_batch(&pts);
    let reasons: Vec<String> = recs
        .iter()
        .filter_map(|r| match &r.status {
            EvalStatus::SimFailed(m) => Some(m.clone()),
            EvalStatus::Ok => None,
        })
        .collect();
    if reasons.len() == recs.len() {
        return Err(FitError::NoValidStart {
            count: reasons.len(),
            first_reason: reasons.first().cloned().unwrap_or_default(),
            reasons,
        });
    }
    Ok(recs)
}

/// The best successful record (lowest error; ties: the earlier one).
pub fn best_record(recs: &[EvalRecord]) -> Option<&EvalRecord> {
    recs.iter().filter(|r| r.status == EvalStatus::Ok).fold(None, |b: Option<&EvalRecord>, r| match b {
        Some(b) if b.error <= r.error => Some(b),
        _ => Some(r),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn grid_uses_cell_centres() {
        let free = [ParamId::Stretch, ParamId::Shear, ParamId::Bend, ParamId::BendDamp];
        let c = CoarseSearch::Grid { values_per_param: 4, params: vec![ParamId::Stretch, ParamId::Bend] };
        let pts = coarse_points(&c, &free, &[0.5, 0.5, 0.5, 0.375]).unwrap();
        assert_eq!(pts.len(), 16);
        assert_eq!(pts[0], vec![0.125, 0.5, 0.125, 0.375]);
        assert_eq!(pts[1], vec![0.125, 0.5, 0.375, 0.375]);
        assert_eq!(pts[15], vec![0.875, 0.5, 0.875, 0.375]);
        let bad = CoarseSearch::Grid { values_per_param: 4, params: vec![ParamId::DragF] };
        assert!(coarse_points(&bad, &free, &[0.5; 4]).is_err());
        let lhs = coarse_points(&CoarseSearch::LatinHypercube { samples: 8, seed: 1 }, &free, &[0.5; 4]).unwrap();
        for d in 0..4 {
            let mut cells: Vec<usize> = lhs.iter().map(|x| (x[d] * 8.0) as usize).collect();
            cells.sort_unstable();
            assert_eq!(cells, (0..8).collect::<Vec<_>>());
        }
    }
}

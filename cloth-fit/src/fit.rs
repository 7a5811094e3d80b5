//! The full fitting pipeline (spec §3.10): coarse search, simulated annealing per trial (or
//! jointly), trial selection, variability at the chosen point.
//!
//! The paper: "We performed two trials per experiment ... we started the optimizations on the
//! two trials (per fabric) with the same initial guess and chose parameters (optimized) that
//! minimized the total error on the two trials" (Bhat et al. 2003 §5); optimising across trials
//! simultaneously is its stated future work (`TrialPolicy::Joint`).

use geom_core::rng::Rng;
use geom_core::stats::median;
use serde::{Deserialize, Serialize};

use crate::anneal::{anneal, initial_temperature, AnnealOptions, AnnealResult};
use crate::coarse::{best_record, coarse_search, CoarseSearch};
use crate::error::{FitError, Result};
use crate::forward::ForwardModel;
use crate::objective::{EvalRecord, EvalSetup, EvalStatus, Objective, Target};
use crate::params::{FabricParams, ParamSpace};
use crate::variability::{variability, ParamVariability, VariabilityOptions};

/// How several trials of one experiment are used (spec §2 `TrialPolicy`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum TrialPolicy {
    /// Anneal each trial from the same start, keep the set with the smallest summed error
    /// (paper).
    #[default]
    PerTrialThenSelect,
    /// One annealing run on the summed objective (ours; the paper's future work).
    Joint,
}

/// Where the parameters that the coarse grid does not cover start (spec §3.8).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub enum DynamicInit {
    /// The same unit coordinate for all of them (static test: the cell centre 3/8).
    Fixed(f64),
    /// One seeded uniformly random point (waving test: the paper's "random guess").
    Random {
        /// Seed.
        seed: u64,
    },
}

/// Search settings of a fit (the `fit` block of a scene, spec §2).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FitOptions {
    /// Coarse search.
    pub coarse: CoarseSearch,
    /// Start of the non-gridded parameters.
    pub dynamic_init: DynamicInit,
    /// Annealing.
    pub anneal: AnnealOptions,
    /// Trial policy.
    #[serde(default)]
    pub trials: TrialPolicy,
    /// Variability analysis at the chosen point (`None` = skipped).
    #[serde(default)]
    pub variability: Option<VariabilityOptions>,
}

/// One trial's annealing.
#[derive(Clone, Debug)]
pub struct TrialFit {
    /// Best parameters of this trial's run.
    pub params: FabricParams,
    /// Its error on its own trial.
    pub own_error: f64,
    /// Its error on every trial (in trial order).
    pub errors: Vec<f64>,
    /// The annealing run.
    pub anneal: AnnealResult,
    /// Every objective evaluation of this trial's run, in order.
    pub history: Vec<EvalRecord>,
}

/// Everything a fit produced (spec §3.10 step 6).
#[derive(Clone, Debug)]
pub struct FitReport {
    /// The chosen parameters.
    pub params: FabricParams,
    /// Summed error of the chosen set over all trials.
    pub error: f64,
    /// Which trial's run was chosen (`None` for `Joint`).
    pub chosen_trial: Option<usize>,
    /// The coarse-search records (on trial 0, or on all trials for `Joint`).
    pub coarse: Vec<EvalRecord>,
    /// The annealing start (unit cube).
    pub start: Vec<f64>,
    /// T₀.
    pub t0: f64,
    /// Per trial (one entry for `Joint`).
    pub trials: Vec<TrialFit>,
    /// Variability at the chosen point (empty when skipped).
    pub variability: Vec<ParamVariability>,
    /// Objective evaluations that ran a simulation (cache hits excluded).
    pub simulations: usize,
    /// Objective calls in all (cache hits included).
    pub evaluations: usize,
    /// Simulations that failed (diverged) and got the penalty.
    pub failures: usize,
}

fn start_point(space: &ParamSpace, init: &DynamicInit) -> Vec<f64> {
    match *init {
        DynamicInit::Fixed(u) => vec![u; space.dim()],
        DynamicInit::Random { seed } => {
            let mut r = Rng::new(seed);
            (0..space.dim()).map(|_| r.f64()).collect()
        }
    }
}

/// Runs the pipeline on `targets` (one per trial). `progress(done, total)` is called after every
/// batch of evaluations. Errors: invalid settings, mismatched footage (before any evaluation),
/// and [`FitError::NoValidStart`] when every coarse point fails.
pub fn fit(
    targets: &[Target],
    forward: &dyn ForwardModel,
    space: &ParamSpace,
    setup: &EvalSetup,
    o: &FitOptions,
    progress: &mut dyn FnMut(u64, u64),
) -> Result<FitReport> {
    if targets.is_empty() {
        return Err(FitError::BadParameter("fit without targets".into()));
    }
    let per_trial: Vec<Objective> = targets
        .iter()
        .map(|t| Objective::new(std::slice::from_ref(t), forward, space, setup))
        .collect::<Result<_>>()?;
    let joint = Objective::new(targets, forward, space, setup)?;
    let n_coarse = crate::coarse::coarse_points(&o.coarse, &space.free, &vec![0.5; space.dim()])?.len();
    let runs = if o.trials == TrialPolicy::Joint { 1 } else { targets.len() };
    let n_var = o.variability.map_or(0, |v| v.samples.max(3) * space.dim());
    let total = (n_coarse + runs * o.anneal.max_evals + runs * targets.len() + n_var) as u64;
    let mut done = 0u64;
    // 1. Coarse search.
    let base = start_point(space, &o.dynamic_init);
    let coarse_obj = if o.trials == TrialPolicy::Joint { &joint } else { &per_trial[0] };
    let coarse = coarse_search(coarse_obj, &o.coarse, &base)?;
    done += coarse.len() as u64;
    progress(done, total);
    let best = best_record(&coarse).expect("coarse_search returns at least one successful record");
    let start = best.x.clone();
    let coarse_errors: Vec<f64> = coarse.iter().filter(|r| r.status == EvalStatus::Ok).map(|r| r.error).collect();
    let e_floor = 1e-3 * median(&coarse_errors);
    // 2. Annealing per trial (or jointly).
    let objs: Vec<&Objective> = if o.trials == TrialPolicy::Joint { vec![&joint] } else { per_trial.iter().collect() };
    let mut t0 = 0.0;
    let mut trials = Vec::new();
    for (k, obj) in objs.iter().enumerate() {
        let y0 = obj.eval(&start).error;
        if k == 0 {
            t0 = initial_temperature(&coarse_errors, &[y0], o.anneal.t0_factor);
        }
        let mut f = |xs: &[Vec<f64>]| -> Vec<f64> {
            let r = obj.eval_batch(xs);
            done += xs.len() as u64;
            progress(done.min(total), total);
            r.into_iter().map(|r| r.error).collect()
        };
        let ar = anneal(&mut f, &start, Some(y0), t0, &o.anneal);
        let params = space.from_unit(&ar.best_x);
        trials.push(TrialFit { params, own_error: ar.best_y, errors: Vec::new(), anneal: ar, history: obj.history() });
    }
    // 3. Selection: every run's parameters on every trial.
    for tf in trials.iter_mut() {
        tf.errors = per_trial.iter().map(|obj| obj.eval_params(&[tf.params])[0].error).collect();
        done += per_trial.len() as u64;
    }
    progress(done.min(total), total);
    let (chosen, error) = trials
        .iter()
        .enumerate()
        .map(|(k, t)| (k, t.errors.iter().sum::<f64>()))
        .fold((0, f64::INFINITY), |b, c| if c.1 < b.1 { c } else { b });
    let params = trials[chosen].params;
    // 4. Variability on the summed objective.
    let var = match &o.variability {
        Some(v) => {
            let r = variability(&joint, &params, v, e_floor)?;
            done += n_var as u64;
            progress(done.min(total), total);
            r
        }
        None => Vec::new(),
    };
    let all: Vec<&Objective> = per_trial.iter().chain(std::iter::once(&joint)).collect();
    let evaluations = all.iter().map(|o| o.history().len()).sum();
    let simulations = all.iter().map(|o| o.history().iter().filter(|r| !r.cached).count()).sum();
    let failures = all.iter().map(|o| o.failures()).sum();
    Ok(FitReport {
        params,
        error,
        chosen_trial: (o.trials == TrialPolicy::PerTrialThenSelect).then_some(chosen),
        coarse,
        start,
        t0,
        trials,
        variability: var,
        simulations,
        evaluations,
        failures,
    })
}

/// E_val(p̂)/E_val(p*) on a held-out target (spec §3.10 step 5): how much worse the fitted
/// parameters explain new footage than the true ones. Returns (ratio, E_val(p̂), E_val(p*)).
pub fn validation_ratio(
    target: &Target,
    forward: &dyn ForwardModel,
    space: &ParamSpace,
    setup: &EvalSetup,
    fitted: &FabricParams,
    truth: &FabricParams,
) -> Result<(f64, f64, f64)> {
    let obj = Objective::new(std::slice::from_ref(target), forward, space, setup)?;
    let r = obj.eval_params(&[*fitted, *truth]);
    Ok((r[0].error / r[1].error, r[0].error, r[1].error))
}

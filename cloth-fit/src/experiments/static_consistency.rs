//! C2 `cloth-fit/static-consistency` (Bhat et al. 2003 §5, Fig. 9; spec §6 C2): "we performed
//! a set of optimizations (on a single fabric) with very similar initial values ... the final
//! error values are very close. We get consistent estimates for parameters that have lower
//! variability (e.g., bend, stretch)." Several annealing runs of the static test from starts
//! within ±5 % of each other (each with its own seed).
//!
//! ```no_run
//! # fn demo(p: &cloth_fit::experiments::static_consistency::Params) -> cloth_fit::Result<()> {
//! use cloth_fit::experiments::static_consistency::run;
//! use geom_core::experiment::Size;
//! use geom_core::record::NullRecorder;
//! let report = run(p, Size::Quick, &mut NullRecorder::default())?;
//! println!("{:?}", report.get("bend_cv"));
//! # Ok(()) }
//! ```

use geom_core::experiment::{BySize, Report, Size, Target};
use geom_core::record::{Cell, Recorder};
use geom_core::rng::Rng;
use geom_core::stats::{max, mean, min};
use serde::{Deserialize, Serialize};

use super::common::{history_rows, history_table, space, truths, FitScale, SearchScale};
use super::static_test::static_truth;
use crate::anneal::{anneal, initial_temperature, AnnealOptions};
use crate::coarse::{best_record, coarse_search, CoarseSearch};
use crate::error::Result;
use crate::forward::ShellsForward;
use crate::metrics::{error_of, param_errors};
use crate::objective::{EvalStatus, Objective};
use crate::params::ParamId;
use crate::presets::{static_trial, FabricPreset};
use crate::synthetic::Condition;

/// Scene parameters (the RON `params` block).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Params {
    /// The fabric (the spec: satin).
    pub fabric: FabricPreset,
    /// Number of runs.
    pub runs: BySize<usize>,
    /// Relative spread of the starts (±, physical values).
    pub start_spread: f64,
    /// Frames of the static trial.
    pub frames: BySize<usize>,
    /// Synthetic condition.
    pub condition: BySize<Condition>,
    /// Parameters free in the annealing.
    pub anneal_free: BySize<Vec<ParamId>>,
    /// Fit-side scale.
    pub fit: FitScale,
    /// Search budgets.
    pub search: SearchScale,
}

/// Runs C2.
pub fn run(p: &Params, size: Size, rec: &mut dyn Recorder) -> Result<Report> {
    let setup = p.fit.setup(size)?;
    let fwd = ShellsForward;
    let f = p.fabric;
    let truth = static_truth(f);
    let cond = p.condition.get(size);
    let free = p.anneal_free.get(size);
    let six = space(&ParamId::CLOTH, truth)?;
    let mut fixed = truth;
    for id in ParamId::CLOTH {
        if !free.contains(&id) {
            fixed.set(id, six.range(id).from_unit(0.375));
        }
    }
    let sp = space(&free, fixed)?;
    let tr = truths(&fwd, &[static_trial(f, 0, p.frames.get(size).max(1))], truth, &setup, cond, p.fit.noise)?;
    let targets = [tr[0].target.clone()];
    let obj = Objective::new(&targets, &fwd, &sp, &setup)?;
    let coarse =
        CoarseSearch::Grid { values_per_param: p.search.coarse_values.get(size), params: ParamId::STIFFNESS.to_vec() };
    let recs = coarse_search(&obj, &coarse, &vec![0.375; sp.dim()])?;
    let base = best_record(&recs).expect("coarse_search guarantees a success").params;
    let errs: Vec<f64> = recs.iter().filter(|r| r.status == EvalStatus::Ok).map(|r| r.error).collect();
    let t0 = initial_temperature(&errs, &[], p.search.anneal.get(size).t0_factor);
    let runs = p.runs.get(size).max(2);
    rec.note(&format!(
        "# C2 static consistency\n\n{}, {runs} runs from starts within ±{:.0} % of the best coarse point, {}",
        f.name(),
        100.0 * p.start_spread,
        cond.name()
    ))?;
    history_table(rec, "history")?;
    let mut head = vec!["run", "error"];
    head.extend(free.iter().map(|i| i.name()));
    rec.table("consistency", &head)?;
    let mut rng = Rng::new(7);
    let (mut finals, mut bends, mut stretches) = (Vec::new(), Vec::new(), Vec::new());
    let mut bend_errs = Vec::new();
    for k in 0..runs {
        let mut start_p = base;
        for &id in &free {
            start_p.set(id, base.get(id) * (1.0 + p.start_spread * (2.0 * rng.f64() - 1.0)));
        }
        let x0 = sp.to_unit(&start_p);
        let o = AnnealOptions {
            max_evals: p.search.anneal_evals.get(size),
            seed: 100 + k as u64,
            ..p.search.anneal.get(size)
        };
        let run_obj = Objective::new(&targets, &fwd, &sp, &setup)?;
        let y0 = run_obj.eval(&x0).error;
        let mut fb = |xs: &[Vec<f64>]| -> Vec<f64> {
            let v: Vec<f64> = run_obj.eval_batch(xs).into_iter().map(|r| r.error).collect();
            v
        };
        let a = anneal(&mut fb, &x0, Some(y0), t0, &o);
        rec.progress((k + 1) as u64, runs as u64);
        history_rows(rec, "history", &format!("run{k}"), &run_obj.history())?;
        let est = sp.from_unit(&a.best_x);
        let mut row = vec![Cell::from(k), Cell::from(a.best_y)];
        row.extend(free.iter().map(|&id| Cell::from(est.get(id))));
        rec.row("consistency", &row)?;
        finals.push(a.best_y);
        bends.push(est.bend);
        stretches.push(est.stretch);
        bend_errs.push(error_of(&param_errors(&sp, &est, &truth), ParamId::Bend));
    }
    let cv = |v: &[f64]| {
        let m = mean(v);
        (v.iter().map(|x| (x - m).powi(2)).sum::<f64>() / v.len() as f64).sqrt() / m
    };
    let mut r = Report::default();
    r.num("final_error_spread", max(&finals) / min(&finals) - 1.0);
    r.num("final_error_mean", mean(&finals));
    r.num("bend_cv", cv(&bends));
    r.num("stretch_cv", cv(&stretches));
    r.num("bend_err_max", max(&bend_errs));
    r.count("runs", runs as u64);
    r.check("final_error_spread", Target::AtMost(0.10), "spec §6 C2: final errors within 10 % of each other");
    r.check("bend_cv", Target::Below(0.10), "spec §6 C2: bend coefficient of variation < 10 %");
    Ok(r)
}

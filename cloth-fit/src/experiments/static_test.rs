//! C1 `cloth-fit/static` — the static test (Bhat et al. 2003 §5, Figs. 8–9; spec §6 C1).
//!
//! "In the static test, the two top corners of the fabric are held stationary, and the fabric
//! is allowed to sag under gravity ... The static test give a good estimate for the static
//! stiffness and bend parameters." For every fabric: synthetic truths of the static trials
//! (separations 0.40 and 0.30 m), the coarse stiffness grid, simulated annealing per trial,
//! selection on the summed error, and the variability analysis at the truth, which should
//! reproduce the paper's finding: bend well determined, damping not at all (drag is fixed at
//! its mid-range, as in the paper).
//!
//! ```no_run
//! # fn demo(p: &cloth_fit::experiments::static_test::Params) -> cloth_fit::Result<()> {
//! use cloth_fit::experiments::static_test::run;
//! use geom_core::experiment::Size;
//! use geom_core::record::NullRecorder;
//! let report = run(p, Size::Quick, &mut NullRecorder::default())?;
//! println!("{:?}", report.get("stiff_err_matched"));
//! # Ok(()) }
//! ```

use std::time::Instant;

use geom_core::experiment::{BySize, Report, Size, Target};
use geom_core::image::ImageF32;
use geom_core::record::{Cell, Recorder};
use geom_core::stats::{max, median, min};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use super::common::{
    fit_images, history_rows, history_table, per_fabric, picks, space, strip, truths, FitScale, SearchScale,
};
use crate::error::Result;
use crate::fit::{fit, DynamicInit, FitReport, TrialPolicy};
use crate::forward::ShellsForward;
use crate::metrics::{all_err, error_of, param_errors, stiff_err, variability_of};
use crate::objective::{EvalSetup, Objective};
use crate::params::{FabricParams, ParamId};
use crate::presets::{drag_midpoint, fit_model, static_trial, FabricPreset};
use crate::synthetic::{Condition, TruthSequence};
use crate::variability::{variability, ParamVariability, VariabilityOptions};

/// Scene parameters (the RON `params` block).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Params {
    /// Fabrics to fit.
    pub fabrics: Vec<FabricPreset>,
    /// Static trials per fabric (1: separation 0.40 m; 2: also 0.30 m).
    pub trials: BySize<usize>,
    /// Frames per trial (the scene is static: identical renders).
    pub frames: BySize<usize>,
    /// Synthetic conditions to run (matched carries the must-hold figures).
    pub conditions: BySize<Vec<Condition>>,
    /// Parameters free in the annealing (the paper: all six cloth parameters).
    pub anneal_free: BySize<Vec<ParamId>>,
    /// Fit-side scale.
    pub fit: FitScale,
    /// Search budgets.
    pub search: SearchScale,
    /// Time one static evaluation at the spec's full size (12², 320 × 240, 5 frames).
    pub time_full_eval: BySize<bool>,
}

/// The static truth: the preset with the drag at its mid-range (the static test fixes it there,
/// so the matched fit model reproduces the truth exactly).
pub fn static_truth(f: FabricPreset) -> FabricParams {
    FabricParams { drag: drag_midpoint(), ..f.params() }
}

/// One evaluation of a static trial at the spec's full size: the medians of the wall and
/// process CPU seconds (all threads) of three evaluations (bend ×1.1, ×1.2, ×1.3).
pub fn time_full_static_eval(f: FabricPreset) -> Result<(f64, f64)> {
    let setup = EvalSetup {
        rig: crate::presets::rig_spec(320, 240).build()?.rig,
        model: fit_model(),
        render: Default::default(),
        angle: Default::default(),
        metric: Default::default(),
    };
    let truth = static_truth(f);
    let fwd = ShellsForward;
    let t = truths(&fwd, &[static_trial(f, 0, 5)], truth, &setup, Condition::Matched, Default::default())?;
    let targets = [t[0].target.clone()];
    let sp = space(&ParamId::CLOTH, truth)?;
    let obj = Objective::new(&targets, &fwd, &sp, &setup)?;
    Ok(median_eval_time(&obj, truth))
}

/// Medians of (wall, CPU) seconds of three fresh evaluations at bend ×1.1, ×1.2, ×1.3.
pub fn median_eval_time(obj: &Objective, truth: FabricParams) -> (f64, f64) {
    let (mut walls, mut cpus) = (Vec::new(), Vec::new());
    for k in 1..=3 {
        let p = truth.with(ParamId::Bend, (1.0 + 0.1 * k as f64) * truth.bend);
        let (_, wall, cpu) = geom_core::clock::timed(|| obj.eval_params(&[p]));
        walls.push(wall);
        cpus.push(cpu);
    }
    (median(&walls), median(&cpus))
}

/// One fabric's fit in one condition, everything the recording needs.
struct FabricFit {
    f: FabricPreset,
    cond: Condition,
    tr: Vec<TruthSequence>,
    fr: FitReport,
    errs: Vec<(ParamId, f64)>,
    var: Vec<ParamVariability>,
    e_star: f64,
    wall: f64,
    fit_img: Vec<ImageF32>,
}

fn fit_fabric(p: &Params, size: Size, setup: &EvalSetup, f: FabricPreset, cond: Condition) -> Result<FabricFit> {
    let fwd = ShellsForward;
    let t0 = Instant::now();
    let n_trials = p.trials.get(size).clamp(1, 2);
    let frames = p.frames.get(size).max(1);
    let free = p.anneal_free.get(size);
    let truth = static_truth(f);
    let exps: Vec<_> = (0..n_trials).map(|k| static_trial(f, k, frames)).collect();
    // Non-free cloth parameters sit at the grid's cell centre 3/8, not at the truth.
    let six = space(&ParamId::CLOTH, truth)?;
    let mut fixed = truth;
    for id in ParamId::CLOTH {
        if !free.contains(&id) {
            fixed.set(id, six.range(id).from_unit(0.375));
        }
    }
    let fit_space = space(&free, fixed)?;
    let search = p.search.options(size, DynamicInit::Fixed(0.375), TrialPolicy::PerTrialThenSelect, false);
    let tr = truths(&fwd, &exps, truth, setup, cond, p.fit.noise)?;
    let targets: Vec<_> = tr.iter().map(|t| t.target.clone()).collect();
    let fr = fit(&targets, &fwd, &fit_space, setup, &search, &mut |_, _| {})?;
    let wall = t0.elapsed().as_secs_f64();
    let errs = param_errors(&six, &fr.params, &truth);
    // Variability at the truth on the same footage, all six cloth parameters.
    let obj6 = Objective::new(&targets, &fwd, &six, setup)?;
    let coarse: Vec<f64> = fr.coarse.iter().map(|r| r.error).collect();
    let floor = 1e-3 * median(&coarse);
    let vo = VariabilityOptions { samples: p.search.variability_samples.get(size), ..Default::default() };
    let var = variability(&obj6, &truth, &vo, floor)?;
    let e_star = obj6.eval_params(&[truth])[0].error;
    let fit_img = exps.iter().map(|e| fit_images(&fwd, &fr.params, e, setup)[0].clone()).collect();
    Ok(FabricFit { f, cond, tr, fr, errs, var, e_star, wall, fit_img })
}

/// Runs C1. Fabrics (and conditions) are fitted in parallel, as many at a time as there are
/// rayon threads; each fit is independent, so the figures do not depend on the thread count.
pub fn run(p: &Params, size: Size, rec: &mut dyn Recorder) -> Result<Report> {
    let setup = p.fit.setup(size)?;
    let n_trials = p.trials.get(size).clamp(1, 2);
    let frames = p.frames.get(size).max(1);
    let conditions = p.conditions.get(size);
    let free = p.anneal_free.get(size);
    let mut r = Report::default();
    rec.note(&format!(
        "# C1 static test\n\n{} fabric(s), {n_trials} trial(s), {frames} frame(s), {}×{} px, fitting mesh {}², dt {:.5} s; annealing over {:?}",
        p.fabrics.len(),
        setup.rig.camera.width,
        setup.rig.camera.height,
        setup.model.res,
        setup.model.dt,
        free.iter().map(|i| i.name()).collect::<Vec<_>>()
    ))?;
    history_table(rec, "history")?;
    let mut head = vec!["fabric", "condition", "trial", "error"];
    head.extend(ParamId::CLOTH.iter().map(|i| i.name()));
    head.extend(["own_error", "evaluations"]);
    rec.table("static_table", &head)?;
    let mut vhead = vec!["fabric"];
    let vnames: Vec<String> = ParamId::CLOTH.iter().map(|i| format!("{}_variability", i.name())).collect();
    vhead.extend(vnames.iter().map(String::as_str));
    rec.table("variability", &vhead)?;
    let (mut e_star, mut stiff_m, mut stiff_mm, mut bend_var, mut damp_var, mut failures) =
        (Vec::new(), Vec::new(), Vec::new(), Vec::new(), Vec::new(), 0usize);
    let mut damp_de = Vec::new();
    let jobs: Vec<(FabricPreset, Condition)> =
        p.fabrics.iter().flat_map(|&f| conditions.iter().map(move |&c| (f, c))).collect();
    let chunk = rayon::current_num_threads().max(1);
    let mut done = 0;
    for batch in jobs.chunks(chunk) {
        let fits: Vec<FabricFit> =
            batch.par_iter().map(|&(f, c)| fit_fabric(p, size, &setup, f, c)).collect::<Result<_>>()?;
        done += batch.len();
        rec.progress(done as u64, jobs.len() as u64);
        for ff in fits {
            let (f, cond) = (ff.f, ff.cond);
            let c = cond.name();
            failures += ff.fr.failures;
            for (k, t) in ff.fr.trials.iter().enumerate() {
                history_rows(rec, "history", &format!("{}-{c}-trial{k}", f.name()), &t.history)?;
                let mut row =
                    vec![Cell::from(f.name()), Cell::from(c), Cell::from(k), Cell::from(t.errors.iter().sum::<f64>())];
                row.extend(ParamId::CLOTH.iter().map(|&id| Cell::from(t.params.get(id))));
                row.extend([Cell::from(t.own_error), Cell::from(t.anneal.evals)]);
                rec.row("static_table", &row)?;
            }
            let se = stiff_err(&ff.errs, &ff.var);
            per_fabric(&mut r, &format!("stiff_err_{c}"), f, se);
            for id in ParamId::CLOTH {
                per_fabric(&mut r, &format!("{}_err_{c}", id.name()), f, error_of(&ff.errs, id));
            }
            per_fabric(&mut r, &format!("all_err_{c}"), f, all_err(&ff.errs));
            r.timing(&format!("fit_wall_s_{c}_{}", f.name()), ff.wall);
            r.count(&format!("simulations_{c}_{}", f.name()), ff.fr.simulations as u64);
            if cond == Condition::Matched {
                per_fabric(&mut r, "e_star", f, ff.e_star);
                e_star.push(ff.e_star);
                stiff_m.push(se);
                let mut row = vec![Cell::from(f.name())];
                row.extend(ParamId::CLOTH.iter().map(|&id| Cell::from(variability_of(&ff.var, id))));
                rec.row("variability", &row)?;
                for id in ParamId::CLOTH {
                    per_fabric(&mut r, &format!("static_{}_variability", id.name()), f, variability_of(&ff.var, id));
                }
                let dv: Vec<f64> = [ParamId::StretchDamp, ParamId::ShearDamp, ParamId::BendDamp]
                    .iter()
                    .map(|&id| variability_of(&ff.var, id))
                    .collect();
                per_fabric(&mut r, "static_damping_variability_min", f, min(&dv));
                damp_var.extend(dv);
                // What the damping variability rests on: the largest change of E over the ±20 %
                // damping perturbations (0 exactly when the static frames do not depend on
                // damping, which makes the variability +∞, written as JSON null).
                let de: Vec<f64> = ff
                    .var
                    .iter()
                    .filter(|v| matches!(v.id, ParamId::StretchDamp | ParamId::ShearDamp | ParamId::BendDamp))
                    .flat_map(|v| v.samples.iter().map(|&(_, e)| (e - ff.e_star).abs()))
                    .collect();
                per_fabric(&mut r, "static_damping_max_de", f, max(&de));
                damp_de.extend(de);
                bend_var.push(variability_of(&ff.var, ParamId::Bend));
            } else {
                stiff_mm.push(se);
            }
            // Truth versus fit, frame 0 of every trial.
            let truth_img: Vec<_> = ff.tr.iter().map(|t| t.images[0].clone()).collect();
            rec.file(&format!("{}/{c}/strip.png", f.name()), &strip(&truth_img, &ff.fit_img, &picks(ff.tr.len(), 2)))?;
            rec.note(&format!(
                "- {} ({c}): bend error {:.4}, stiff_err {:.4}, {} simulations in {:.1} s",
                f.name(),
                error_of(&ff.errs, ParamId::Bend),
                se,
                ff.fr.simulations,
                ff.wall
            ))?;
        }
    }
    if !e_star.is_empty() {
        r.num("e_star", max(&e_star.iter().map(|v| v.abs()).collect::<Vec<_>>()));
        r.num("stiff_err_matched", max(&stiff_m));
        r.num("static_bend_variability", max(&bend_var));
        r.num("static_damping_variability_min", min(&damp_var));
        r.num("static_damping_max_de", max(&damp_de));
        r.check("e_star", Target::Equals(0.0), "spec §5: matched, noise-free E(p*) = 0 exactly");
        r.check("stiff_err_matched", Target::AtMost(0.05), "spec §5 / issue 24: bend within 5 % (matched)");
        r.check("static_bend_variability", Target::Below(0.10), "paper §5: bend well determined by the static test");
        r.check(
            "static_damping_variability_min",
            Target::Above(0.20),
            "paper §5: static tests cannot estimate damping",
        );
    }
    if !stiff_mm.is_empty() {
        r.num("stiff_err_mismatched", max(&stiff_mm));
    }
    r.count("sim_failures", failures as u64);
    if p.time_full_eval.get(size) {
        let (s, cpu) = time_full_static_eval(FabricPreset::Linen)?;
        r.timing("static_eval_s", s);
        r.timing("static_eval_cpu_s", cpu);
        r.check("static_eval_s", Target::AtMost(1.0), "spec §5: one static evaluation ≤ 1 s");
    }
    Ok(r)
}

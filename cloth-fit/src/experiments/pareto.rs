//! C7 `cloth-fit/pareto` (spec §6 C7, §9): accuracy against time, and the integrator bias.
//!
//! 1. **Integrator bias.** The paper "found that implicit integration introduced damping which
//!    could not be eliminated by optimizing cloth parameters" (Bhat et al. 2003 §3). A waving
//!    truth from BDF2 at a fine step is fitted for the three damping coefficients (stiffness and
//!    drag at the truth) with backward Euler and with BDF2 at dt ∈ {1/120, 1/240, 1/480}: the
//!    recovered β / true β shows how much of the numerical damping the fit absorbs.
//! 2. **Knob sweeps.** One-at-a-time settings around a base (annealing budget, coarse search,
//!    mesh and image resolution, dt, frames used, supersampling, render subdivision), each a
//!    full waving fit against the same mismatched footage: wall time, evaluations, time per
//!    evaluation by stage, `stiff_err`, `all_err`, `val_ratio`; the Pareto front of
//!    (wall time, stiff_err), and the anytime curve of the base run.
//!
//! ```no_run
//! # fn demo(p: &cloth_fit::experiments::pareto::Params) -> cloth_fit::Result<()> {
//! use cloth_fit::experiments::pareto::run;
//! use geom_core::experiment::Size;
//! use geom_core::record::NullRecorder;
//! let report = run(p, Size::Quick, &mut NullRecorder::default())?;
//! println!("{:?}", report.get("dt_bias_bend_damp_ratio_be_max"));
//! # Ok(()) }
//! ```

use std::collections::BTreeMap;
use std::time::Instant;

use geom_core::experiment::{BySize, Report, Size};
use geom_core::record::{Cell, Recorder, Series};
use serde::{Deserialize, Serialize};

use super::common::{space, FitScale, SearchScale};
use crate::coarse::CoarseSearch;
use crate::error::Result;
use crate::fit::{fit, validation_ratio, DynamicInit, FitOptions, TrialPolicy};
use crate::forward::{Integrator, ShellsForward, SimOptions};
use crate::metrics::{all_err, anytime, error_of, param_errors};
use crate::objective::{EvalSetup, Objective};
use crate::params::ParamId;
use crate::presets::{rig_spec, validation_trial, waving_trial, FabricPreset};
use crate::synthetic::{synthesize, Condition, SyntheticSource, TruthSequence};

/// One knob setting of the sweep: each field overrides the base.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Knob {
    /// Label (CSV, plots).
    pub name: String,
    /// Annealing budget.
    pub anneal_evals: Option<usize>,
    /// Coarse search.
    pub coarse: Option<CoarseSearch>,
    /// Fitting mesh resolution.
    pub res: Option<usize>,
    /// Image size.
    pub image: Option<(u32, u32)>,
    /// Fitting time step (s).
    pub dt: Option<f64>,
    /// Use every k-th frame of the footage.
    pub frame_stride: Option<usize>,
    /// Supersampling of the fit renderer.
    pub supersample: Option<u32>,
    /// Render subdivision of the fitting mesh.
    pub render_subdivision: Option<u32>,
}

/// Scene parameters (the RON `params` block).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Params {
    /// The fabric.
    pub fabric: FabricPreset,
    /// Frames of the waving footage.
    pub frames: BySize<usize>,
    /// Frames of the validation sequence (0 = no val_ratio).
    pub validation_frames: BySize<usize>,
    /// Synthetic condition of the sweep's footage.
    pub condition: BySize<Condition>,
    /// Seed of the random dynamic start.
    pub dynamic_seed: u64,
    /// Base fit-side scale.
    pub fit: FitScale,
    /// Base search budgets.
    pub search: SearchScale,
    /// The sweep (the first entry is the base; empty = no sweep).
    pub knobs: BySize<Vec<Knob>>,
    /// Fitting steps of the integrator-bias study (s; empty = skipped).
    pub dt_bias: BySize<Vec<f64>>,
    /// Truth step of the bias study (BDF2, s).
    pub dt_bias_truth_dt: f64,
    /// Annealing budget per bias fit.
    pub dt_bias_evals: BySize<usize>,
}

/// What one knob setting gave.
#[derive(Clone, Debug, PartialEq)]
pub struct KnobResult {
    /// The setting's name.
    pub name: String,
    /// Wall time of the fit (s).
    pub wall_s: f64,
    /// Objective calls.
    pub evaluations: usize,
    /// Simulations run.
    pub simulations: usize,
    /// Mean time per simulated evaluation by stage: simulation, render, filter, metric (s).
    pub stage_s: [f64; 4],
    /// stiff_err (max over the stiffnesses; no identifiability restriction here).
    pub stiff_err: f64,
    /// all_err.
    pub all_err: f64,
    /// val_ratio (NaN without validation).
    pub val_ratio: f64,
    /// Anytime curve (t, best E, bend error) of this fit's first trial.
    pub anytime: Vec<(f64, f64, f64)>,
}

/// Runs one knob setting: footage rendered at the setting's image size (cached per size in
/// `footage`), a one-trial waving fit, the errors and the validation ratio.
#[allow(clippy::too_many_arguments)]
pub fn run_knob(
    p: &Params,
    size: Size,
    k: &Knob,
    footage: &mut BTreeMap<(u32, u32), (TruthSequence, Option<TruthSequence>)>,
    progress: &mut dyn FnMut(u64, u64),
) -> Result<KnobResult> {
    let fwd = ShellsForward;
    let f = p.fabric;
    let truth = f.params();
    let mut setup = p.fit.setup(size)?;
    let image = k.image.unwrap_or(p.fit.image.get(size));
    if k.image.is_some() {
        setup.rig = rig_spec(image.0, image.1).build()?.rig;
    }
    if let Some(r) = k.res {
        setup.model.res = r;
    }
    if let Some(dt) = k.dt {
        setup.model.dt = dt;
    }
    if let Some(s) = k.supersample {
        setup.render.supersample = s;
    }
    if let Some(l) = k.render_subdivision {
        setup.model.render_subdivision = l;
    }
    let cond = p.condition.get(size);
    let frames = p.frames.get(size).max(2);
    let nv = p.validation_frames.get(size);
    if let std::collections::btree_map::Entry::Vacant(slot) = footage.entry(image) {
        // The footage does not depend on the fitting model: render it with the base model.
        let base = EvalSetup { model: p.fit.setup(size)?.model, ..setup.clone() };
        let src = SyntheticSource::new(cond, truth, &base, p.fit.noise);
        let t = synthesize(&fwd, &waving_trial(f, 0, frames), &base.rig, &src, &base.angle)?;
        let v =
            if nv > 0 { Some(synthesize(&fwd, &validation_trial(f, nv), &base.rig, &src, &base.angle)?) } else { None };
        slot.insert((t, v));
    }
    let (t, v) = &footage[&image];
    let mut target = t.target.clone();
    if let Some(s) = k.frame_stride.filter(|&s| s > 1) {
        // Every s-th frame: the experiment keeps its frame times by scaling fps would change the
        // physics, so the stride selects frames and the model samples the same times.
        let keep: Vec<usize> = (0..target.frames.len()).step_by(s).collect();
        target.frames = keep.iter().map(|&i| target.frames[i].clone()).collect();
        target.experiment.frames = target.frames.len();
        setup.rig.fps /= s as f64;
    }
    let sp = space(&ParamId::ALL, truth)?;
    let mut opts: FitOptions =
        p.search.options(size, DynamicInit::Random { seed: p.dynamic_seed }, TrialPolicy::PerTrialThenSelect, false);
    if let Some(e) = k.anneal_evals {
        opts.anneal.max_evals = e;
    }
    if let Some(c) = &k.coarse {
        opts.coarse = c.clone();
    }
    let t0 = Instant::now();
    let fr = fit(std::slice::from_ref(&target), &fwd, &sp, &setup, &opts, progress)?;
    let wall_s = t0.elapsed().as_secs_f64();
    let errs = param_errors(&sp, &fr.params, &truth);
    let stiff = ParamId::STIFFNESS.iter().map(|&id| error_of(&errs, id)).fold(0.0, geom_core::stats::nan_max);
    let hist = &fr.trials[0].history;
    let sims: Vec<_> = hist.iter().filter(|r| !r.cached).collect();
    let n = sims.len().max(1) as f64;
    let stage_s = [
        sims.iter().map(|r| r.sim_s).sum::<f64>() / n,
        sims.iter().map(|r| r.render_s).sum::<f64>() / n,
        sims.iter().map(|r| r.filter_s).sum::<f64>() / n,
        sims.iter().map(|r| r.metric_s).sum::<f64>() / n,
    ];
    let val_ratio = match v {
        Some(v) => validation_ratio(&v.target, &fwd, &sp, &setup, &fr.params, &truth)?.0,
        None => f64::NAN,
    };
    Ok(KnobResult {
        name: k.name.clone(),
        wall_s,
        evaluations: fr.evaluations,
        simulations: fr.simulations,
        stage_s,
        stiff_err: stiff,
        all_err: all_err(&errs),
        val_ratio,
        anytime: anytime(hist, &sp, &truth),
    })
}

/// Indices of the results on the Pareto front of (wall time, stiff_err): no other result is at
/// least as fast and at least as accurate with one of them strictly better.
pub fn pareto_front(rs: &[KnobResult]) -> Vec<usize> {
    (0..rs.len())
        .filter(|&i| {
            !rs.iter().enumerate().any(|(j, o)| {
                j != i
                    && o.wall_s <= rs[i].wall_s
                    && o.stiff_err <= rs[i].stiff_err
                    && (o.wall_s < rs[i].wall_s || o.stiff_err < rs[i].stiff_err)
            })
        })
        .collect()
}

/// Result of one integrator-bias fit.
#[derive(Clone, Debug, PartialEq)]
pub struct BiasResult {
    /// Fitting integrator.
    pub integrator: Integrator,
    /// Fitting step (s).
    pub dt: f64,
    /// Recovered / true β for stretch, shear, bend damping.
    pub ratios: [f64; 3],
    /// E at the true parameters with this integrator and step (0 only for an exact model).
    pub e_truth: f64,
    /// E at the fit.
    pub e_fit: f64,
}

/// The integrator-bias study (spec C7): BDF2 truth at `truth_dt`, fits of the three damping
/// coefficients with backward Euler and BDF2 at every `dts`.
pub fn dt_bias(p: &Params, size: Size, dts: &[f64], progress: &mut dyn FnMut(u64, u64)) -> Result<Vec<BiasResult>> {
    let fwd = ShellsForward;
    let f = p.fabric;
    let truth = f.params();
    let base = p.fit.setup(size)?;
    let frames = p.frames.get(size).max(2);
    let truth_model = SimOptions { dt: p.dt_bias_truth_dt, integrator: Integrator::Bdf2, ..base.model };
    let src = SyntheticSource { truth, model: truth_model, render: base.render, noise: None };
    let tr = synthesize(&fwd, &waving_trial(f, 0, frames), &base.rig, &src, &base.angle)?;
    let damp = [ParamId::StretchDamp, ParamId::ShearDamp, ParamId::BendDamp];
    let sp = space(&damp, truth)?;
    let mut out = Vec::new();
    let total = (2 * dts.len()) as u64;
    for (ii, integrator) in [Integrator::BackwardEuler, Integrator::Bdf2].into_iter().enumerate() {
        for (di, &dt) in dts.iter().enumerate() {
            let setup = EvalSetup { model: SimOptions { dt, integrator, ..base.model }, ..base.clone() };
            let opts = FitOptions {
                coarse: CoarseSearch::Grid { values_per_param: 3, params: damp.to_vec() },
                dynamic_init: DynamicInit::Fixed(0.5),
                anneal: crate::anneal::AnnealOptions {
                    max_evals: p.dt_bias_evals.get(size),
                    ..p.search.anneal.get(size)
                },
                trials: TrialPolicy::PerTrialThenSelect,
                variability: None,
            };
            let fr = fit(std::slice::from_ref(&tr.target), &fwd, &sp, &setup, &opts, &mut |_, _| {})?;
            let obj = Objective::new(std::slice::from_ref(&tr.target), &fwd, &sp, &setup)?;
            let e_truth = obj.eval_params(&[truth])[0].error;
            out.push(BiasResult {
                integrator,
                dt,
                ratios: damp.map(|id| fr.params.get(id) / truth.get(id)),
                e_truth,
                e_fit: fr.error,
            });
            progress((ii * dts.len() + di + 1) as u64, total);
        }
    }
    Ok(out)
}

fn integrator_name(i: Integrator) -> &'static str {
    match i {
        Integrator::BackwardEuler => "be",
        Integrator::Bdf2 => "bdf2",
    }
}

/// Runs C7.
pub fn run(p: &Params, size: Size, rec: &mut dyn Recorder) -> Result<Report> {
    let mut r = Report::default();
    rec.note(&format!("# C7 accuracy versus time ({})\n", p.fabric.name()))?;
    // 1. Integrator bias.
    let dts = p.dt_bias.get(size);
    if !dts.is_empty() {
        let bias = dt_bias(p, size, &dts, &mut |d, t| rec.progress(d, t))?;
        rec.table(
            "dt_bias",
            &["integrator", "dt", "stretch_damp_ratio", "shear_damp_ratio", "bend_damp_ratio", "e_truth", "e_fit"],
        )?;
        for b in &bias {
            rec.row(
                "dt_bias",
                &[
                    Cell::from(integrator_name(b.integrator)),
                    Cell::from(b.dt),
                    Cell::from(b.ratios[0]),
                    Cell::from(b.ratios[1]),
                    Cell::from(b.ratios[2]),
                    Cell::from(b.e_truth),
                    Cell::from(b.e_fit),
                ],
            )?;
            let tag = format!("{}_dt{}", integrator_name(b.integrator), (1.0 / b.dt).round() as u64);
            r.num(&format!("dt_bias_bend_damp_ratio_{tag}"), b.ratios[2]);
            r.num(&format!("dt_bias_stretch_damp_ratio_{tag}"), b.ratios[0]);
            r.num(&format!("dt_bias_e_truth_{tag}"), b.e_truth);
        }
        for integ in [Integrator::BackwardEuler, Integrator::Bdf2] {
            let pts: Vec<(f64, f64)> =
                bias.iter().filter(|b| b.integrator == integ).map(|b| (b.dt, b.ratios[2])).collect();
            rec.series(&Series {
                plot: "dt_bias".into(),
                label: format!("{} bend β recovered / true", integrator_name(integ)),
                axes: ("dt (s)".into(), "β_bend fit / β_bend truth".into()),
                log: (true, true),
                points: pts,
            })?;
        }
        let be: Vec<f64> =
            bias.iter().filter(|b| b.integrator == Integrator::BackwardEuler).map(|b| b.ratios[2]).collect();
        r.num("dt_bias_bend_damp_ratio_be_max", geom_core::stats::max(&be));
    }
    // 2. Knob sweeps.
    let knobs = p.knobs.get(size);
    if !knobs.is_empty() {
        let mut footage = BTreeMap::new();
        let mut results = Vec::new();
        for (i, k) in knobs.iter().enumerate() {
            let kr = run_knob(p, size, k, &mut footage, &mut |d, t| rec.progress(d, t))?;
            rec.note(&format!(
                "- {}: {:.1} s, {} simulations, stiff_err {:.3}, all_err {:.3}, val_ratio {:.3}",
                kr.name, kr.wall_s, kr.simulations, kr.stiff_err, kr.all_err, kr.val_ratio
            ))?;
            if i == 0 {
                rec.series(&Series {
                    plot: "anytime".into(),
                    label: format!("{}: bend error of the best-so-far point", kr.name),
                    axes: ("time (s)".into(), "bend error |ln(p/p*)|".into()),
                    log: (false, false),
                    points: kr.anytime.iter().filter(|a| a.2.is_finite()).map(|a| (a.0, a.2)).collect(),
                })?;
            }
            results.push(kr);
        }
        rec.table(
            "pareto",
            &[
                "setting",
                "wall_s",
                "evaluations",
                "simulations",
                "sim_s",
                "render_s",
                "filter_s",
                "metric_s",
                "stiff_err",
                "all_err",
                "val_ratio",
                "front",
            ],
        )?;
        let front = pareto_front(&results);
        for (i, k) in results.iter().enumerate() {
            rec.row(
                "pareto",
                &[
                    Cell::from(k.name.as_str()),
                    Cell::from(k.wall_s),
                    Cell::from(k.evaluations),
                    Cell::from(k.simulations),
                    Cell::from(k.stage_s[0]),
                    Cell::from(k.stage_s[1]),
                    Cell::from(k.stage_s[2]),
                    Cell::from(k.stage_s[3]),
                    Cell::from(k.stiff_err),
                    Cell::from(k.all_err),
                    Cell::from(k.val_ratio),
                    Cell::from(front.contains(&i)),
                ],
            )?;
            r.num(&format!("stiff_err_{}", k.name), k.stiff_err);
            r.num(&format!("all_err_{}", k.name), k.all_err);
            r.num(&format!("val_ratio_{}", k.name), k.val_ratio);
            r.timing(&format!("wall_s_{}", k.name), k.wall_s);
        }
        let mut fp: Vec<(f64, f64)> = front.iter().map(|&i| (results[i].wall_s, results[i].stiff_err)).collect();
        fp.sort_by(|a, b| a.0.total_cmp(&b.0));
        rec.series(&Series {
            plot: "pareto".into(),
            label: "Pareto front (wall time, stiff_err)".into(),
            axes: ("wall time (s)".into(), "stiff_err".into()),
            log: (true, false),
            points: fp,
        })?;
        r.count("settings", results.len() as u64);
        r.count("pareto_front_size", front.len() as u64);
    }
    Ok(r)
}

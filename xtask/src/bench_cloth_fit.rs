//! `cargo xtask bench cloth-fit` (spec §9): accuracy against time of the fit. Every setting is
//! one waving fit of linen (one trial, mismatched footage with noise) through the library's
//! `cloth_fit::experiments::pareto::run_knob`; the base setting is the scene-independent
//! default below. Sweeps (`--sweep <name>`, default all):
//! - `budget`: annealing evaluations (quick 20/40, default 30/60/120);
//! - `coarse`: none, Latin hypercube, grid 2³, grid 3³;
//! - `res`: fitting mesh 6, 8, 12;
//! - `image`: 96×72, 160×120, 320×240 (quick: the first two);
//! - `dt`: 1/120, 1/240 s;
//! - `stage`: one evaluation at the spec's full size (12², 320×240, 50 frames) split into
//!   simulation, rendering, angle maps and metric.
//!
//! Writes `cloth_fit_<sweep>.csv`, `cloth_fit_<sweep>.png` (stiff_err against wall time) and
//! `anytime.png` (the base fit's bend error of the best-so-far point against time).

use std::collections::BTreeMap;

use cloth_fit::coarse::CoarseSearch;
use cloth_fit::experiments::common::{FitScale, SearchScale};
use cloth_fit::experiments::pareto::{run_knob, Knob, KnobResult, Params};
use cloth_fit::objective::Objective;
use cloth_fit::params::ParamId;
use cloth_fit::presets::{default_ranges, fit_model, rig_spec, waving_trial, FabricPreset};
use cloth_fit::synthetic::{synthesize, Condition, SyntheticSource};
use geom_core::experiment::{BySize, Size};

use crate::error::{Error, Result};
use crate::out::{CsvWriter, Summary};
use crate::plot::{LinePlot, Series};
use crate::registry::BenchCtx;

/// The sweeps `--sweep` accepts.
pub const SWEEPS: &[&str] = &["budget", "coarse", "res", "image", "dt", "stage"];

fn base(quick: bool) -> Params {
    Params {
        fabric: FabricPreset::Linen,
        frames: BySize::Same(if quick { 10 } else { 20 }),
        validation_frames: BySize::Same(if quick { 0 } else { 30 }),
        condition: BySize::Same(Condition::Mismatched),
        dynamic_seed: 3,
        fit: FitScale {
            image: BySize::Same(if quick { (96, 72) } else { (160, 120) }),
            res: BySize::Same(if quick { 6 } else { 8 }),
            dt: BySize::Same(1.0 / 120.0),
            integrator: Default::default(),
            render: Default::default(),
            angle: Default::default(),
            metric: Default::default(),
            noise: Default::default(),
        },
        search: SearchScale {
            coarse_values: BySize::Same(2),
            anneal_evals: BySize::Same(if quick { 20 } else { 60 }),
            variability_samples: BySize::Same(5),
            anneal: BySize::Same(Default::default()),
        },
        knobs: BySize::Same(Vec::new()),
        dt_bias: BySize::Same(Vec::new()),
        dt_bias_truth_dt: 1.0 / 960.0,
        dt_bias_evals: BySize::Same(0),
    }
}

fn knob(name: &str) -> Knob {
    Knob { name: name.to_string(), ..Knob::default() }
}

fn settings(sweep: &str, quick: bool) -> Vec<Knob> {
    let k = knob;
    match sweep {
        "budget" => {
            let b: &[usize] = if quick { &[20, 40] } else { &[30, 60, 120] };
            b.iter().map(|&e| Knob { anneal_evals: Some(e), ..k(&format!("evals{e}")) }).collect()
        }
        "coarse" => vec![
            Knob { coarse: Some(CoarseSearch::Off), ..k("none") },
            Knob { coarse: Some(CoarseSearch::LatinHypercube { samples: 8, seed: 1 }), ..k("lhs8") },
            Knob {
                coarse: Some(CoarseSearch::Grid { values_per_param: 2, params: ParamId::STIFFNESS.to_vec() }),
                ..k("grid2")
            },
            Knob {
                coarse: Some(CoarseSearch::Grid { values_per_param: 3, params: ParamId::STIFFNESS.to_vec() }),
                ..k("grid3")
            },
        ],
        "res" => [6, 8, 12].iter().map(|&r| Knob { res: Some(r), ..k(&format!("res{r}")) }).collect(),
        "image" => {
            let s: &[(u32, u32)] = if quick { &[(96, 72), (160, 120)] } else { &[(96, 72), (160, 120), (320, 240)] };
            s.iter().map(|&i| Knob { image: Some(i), ..k(&format!("img{}", i.0)) }).collect()
        }
        "dt" => [120.0, 240.0].iter().map(|&f| Knob { dt: Some(1.0 / f), ..k(&format!("dt{f}")) }).collect(),
        _ => Vec::new(),
    }
}

fn cf<T>(r: cloth_fit::Result<T>) -> Result<T> {
    r.map_err(Error::from)
}

/// One evaluation at the spec's full size, split by stage (s): (wall, sim, render, filter, metric).
fn stage_timing() -> Result<[f64; 5]> {
    let rig = cf(rig_spec(320, 240).build())?.rig;
    let setup = cloth_fit::objective::EvalSetup {
        rig,
        model: fit_model(),
        render: Default::default(),
        angle: Default::default(),
        metric: Default::default(),
    };
    let truth = FabricPreset::Linen.params();
    let fwd = cloth_fit::forward::ShellsForward;
    let src = SyntheticSource::new(Condition::Matched, truth, &setup, Default::default());
    let t = cf(synthesize(&fwd, &waving_trial(FabricPreset::Linen, 0, 50), &setup.rig, &src, &setup.angle))?;
    let targets = [t.target];
    let space = cf(cloth_fit::params::ParamSpace::new(default_ranges(), ParamId::ALL.to_vec(), truth))?;
    let obj = cf(Objective::new(&targets, &fwd, &space, &setup))?;
    let r = obj.eval_params(&[truth.with(ParamId::Bend, 1.2 * truth.bend)]).remove(0);
    Ok([r.wall_s, r.sim_s, r.render_s, r.filter_s, r.metric_s])
}

const HEADER: [&str; 11] = [
    "sweep",
    "setting",
    "wall_s",
    "evaluations",
    "simulations",
    "sim_s",
    "render_s",
    "filter_s",
    "stiff_err",
    "all_err",
    "val_ratio",
];

fn write_rows(csv: &mut CsvWriter, sweep: &str, rs: &[KnobResult]) -> Result<()> {
    for r in rs {
        csv.row(&[
            sweep.into(),
            r.name.as_str().into(),
            r.wall_s.into(),
            r.evaluations.into(),
            r.simulations.into(),
            r.stage_s[0].into(),
            r.stage_s[1].into(),
            r.stage_s[2].into(),
            r.stiff_err.into(),
            r.all_err.into(),
            r.val_ratio.into(),
        ])?;
    }
    Ok(())
}

/// Runs the bench.
pub fn run(ctx: &BenchCtx) -> Result<Summary> {
    let quick = ctx.quick;
    let p = base(quick);
    let sweeps: Vec<&str> = match ctx.sweep.as_deref() {
        None | Some("all") => SWEEPS.to_vec(),
        Some(s) => vec![SWEEPS.iter().copied().find(|x| *x == s).unwrap_or("stage")],
    };
    let mut s = Summary::new();
    let mut footage = BTreeMap::new();
    let size = Size::Default;
    for sweep in sweeps {
        if sweep == "stage" {
            let t = stage_timing()?;
            let mut csv = CsvWriter::create(
                &ctx.out_dir.join("cloth_fit_stage.csv"),
                &["wall_s", "sim_s", "render_s", "filter_s", "metric_s"],
            )?;
            csv.row(&[t[0].into(), t[1].into(), t[2].into(), t[3].into(), t[4].into()])?;
            s.set("eval_waving_full_s", t[0]).set("eval_waving_full_sim_s", t[1]);
            s.set("eval_waving_full_render_s", t[2]).set("eval_waving_full_filter_s", t[3]);
            continue;
        }
        let mut rs = Vec::new();
        for k in settings(sweep, quick) {
            let r = cf(run_knob(&p, size, &k, &mut footage, &mut |_, _| {}))?;
            println!("  {sweep}/{}: {:.1} s, stiff_err {:.3}, all_err {:.3}", r.name, r.wall_s, r.stiff_err, r.all_err);
            s.set(&format!("{sweep}_{}_stiff_err", r.name), r.stiff_err);
            s.set(&format!("{sweep}_{}_all_err", r.name), r.all_err);
            s.set(&format!("{sweep}_{}_wall_s", r.name), r.wall_s);
            rs.push(r);
        }
        let mut csv = CsvWriter::create(&ctx.out_dir.join(format!("cloth_fit_{sweep}.csv")), &HEADER)?;
        write_rows(&mut csv, sweep, &rs)?;
        let mut plot = LinePlot::new(&format!("cloth-fit: {sweep}"), "wall time (s)", "stiff_err").log(true, false);
        for r in &rs {
            plot.series.push(Series::new(r.name.clone(), vec![(r.wall_s, r.stiff_err)]));
        }
        plot.write_png(&ctx.out_dir.join(format!("cloth_fit_{sweep}.png")))?;
        if sweep == "budget" {
            if let Some(last) = rs.last() {
                let pts: Vec<(f64, f64)> =
                    last.anytime.iter().filter(|a| a.2.is_finite()).map(|a| (a.0, a.2)).collect();
                LinePlot::new("anytime: bend error of the best-so-far point", "time (s)", "|ln(B/B*)|")
                    .with(Series::new(last.name.clone(), pts))
                    .write_png(&ctx.out_dir.join("anytime.png"))?;
            }
        }
    }
    Ok(s)
}

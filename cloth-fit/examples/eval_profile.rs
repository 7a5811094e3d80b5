//! One static and one waving evaluation of linen at the spec's full size (12² swatch, 320×240,
//! 5 and 50 frames), split into simulation, rendering, angle maps and metric; the truth is the
//! matched model, so E(p*) = 0.
//!
//! `cargo run --release -p cloth-fit --example eval_profile [-- <repeats>]`

use cloth_fit::objective::{EvalSetup, Objective};
use cloth_fit::params::{ParamId, ParamSpace};
use cloth_fit::presets::{default_ranges, fit_model, rig_spec, static_trial, waving_trial, FabricPreset};
use cloth_fit::synthetic::{synthesize, Condition, SyntheticSource};
use cloth_fit::{angle::AngleOptions, forward::ShellsForward, noise::NoiseModel};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let repeats: usize = std::env::args().nth(1).map(|s| s.parse()).transpose()?.unwrap_or(3);
    let rig = rig_spec(320, 240).build()?.rig;
    let setup = EvalSetup {
        rig,
        model: fit_model(),
        render: Default::default(),
        angle: AngleOptions::default(),
        metric: Default::default(),
    };
    let truth = FabricPreset::Linen.params();
    let space = ParamSpace::new(default_ranges(), ParamId::ALL.to_vec(), truth)?;
    let fwd = ShellsForward;
    for (name, e) in
        [("static", static_trial(FabricPreset::Linen, 0, 5)), ("waving", waving_trial(FabricPreset::Linen, 0, 50))]
    {
        let src = SyntheticSource::new(Condition::Matched, truth, &setup, NoiseModel::default());
        let t = synthesize(&fwd, &e, &setup.rig, &src, &setup.angle)?;
        let targets = [t.target];
        for k in 0..repeats {
            let obj = Objective::new(&targets, &fwd, &space, &setup)?;
            let p = truth.with(ParamId::Bend, truth.bend * (1.0 + 0.1 * k as f64));
            let r = obj.eval_params(&[p]).remove(0);
            println!(
                "{name}: E = {:.4}  wall {:.3} s  (sim {:.3}, render {:.3}, filter {:.3}, metric {:.3} summed over frames)",
                r.error, r.wall_s, r.sim_s, r.render_s, r.filter_s, r.metric_s
            );
        }
    }
    Ok(())
}

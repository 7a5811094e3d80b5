//! One static and one waving evaluation of linen at the spec's full size (12² swatch, 320×240,
//! 5 and 50 frames), split into simulation, rendering, angle maps and metric; the truth is the
//! matched model, so E(p*) = 0.
//!
//! `cargo run --release -p cloth-fit --example eval_profile [-- <repeats> [<width> <height> <res> <dt> <frames>]]`

use cloth_fit::objective::{EvalSetup, Objective};
use cloth_fit::params::{ParamId, ParamSpace};
use cloth_fit::presets::{default_ranges, fit_model, rig_spec, static_trial, waving_trial, FabricPreset};
use cloth_fit::synthetic::{synthesize, Condition, SyntheticSource};
use cloth_fit::{angle::AngleOptions, forward::ShellsForward, noise::NoiseModel};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let a: Vec<String> = std::env::args().collect();
    let arg = |i: usize, d: f64| -> f64 { a.get(i).and_then(|s| s.parse().ok()).unwrap_or(d) };
    let repeats = arg(1, 3.0) as usize;
    let (w, h, res, dt, frames) =
        (arg(2, 320.0) as u32, arg(3, 240.0) as u32, arg(4, 12.0) as usize, arg(5, 1.0 / 240.0), arg(6, 50.0) as usize);
    let rig = rig_spec(w, h).build()?.rig;
    let setup = EvalSetup {
        rig,
        model: cloth_fit::forward::SimOptions { res, dt, ..fit_model() },
        render: cloth_fit::render::RenderOptions {
            shadows: std::env::var("SHADOWS").map_or(true, |v| v != "0"),
            supersample: std::env::var("SS").ok().and_then(|v| v.parse().ok()).unwrap_or(2),
            ..Default::default()
        },
        angle: AngleOptions { grad_threshold: 0.01 * 320.0 / w as f64, ..AngleOptions::default() },
        metric: Default::default(),
    };
    let truth = FabricPreset::Linen.params();
    let space = ParamSpace::new(default_ranges(), ParamId::ALL.to_vec(), truth)?;
    let fwd = ShellsForward;
    for (name, e) in [
        ("static", static_trial(FabricPreset::Linen, 0, 5.min(frames))),
        ("waving", waving_trial(FabricPreset::Linen, 0, frames)),
    ] {
        let src = SyntheticSource::new(Condition::Matched, truth, &setup, NoiseModel::default());
        let t = synthesize(&fwd, &e, &setup.rig, &src, &setup.angle)?;
        let targets = [t.target];
        for k in 0..repeats {
            let obj = Objective::new(&targets, &fwd, &space, &setup)?;
            let p = truth.with(ParamId::Bend, truth.bend * (1.0 + 0.1 * k as f64));
            let (mut r, _, cpu) = geom_core::clock::timed(|| obj.eval_params(&[p]));
            let r = r.remove(0);
            println!(
                "{name}: E = {:.4}  wall {:.3} s  CPU {cpu:.2} s  (sim {:.3}, render {:.3}, filter {:.3}, metric {:.3} summed over frames)",
                r.error, r.wall_s, r.sim_s, r.render_s, r.filter_s, r.metric_s
            );
        }
    }
    Ok(())
}

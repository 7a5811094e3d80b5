//! The static objective around the truth (matched, default scene size): E, E_fold and E_silh
//! for relative perturbations of each cloth parameter, and the coarse-grid error scale.
//! Diagnoses the variability and the fit of scene C1.
//!
//! `cargo run --release -p cloth-fit --example static_landscape [fabric]`

use cloth_fit::experiments::common::{space, truths};
use cloth_fit::experiments::static_test::static_truth;
use cloth_fit::forward::{ShellsForward, SimOptions};
use cloth_fit::objective::{EvalSetup, Objective};
use cloth_fit::params::ParamId;
use cloth_fit::presets::{fit_model, rig_spec, static_trial, FabricPreset};
use cloth_fit::synthetic::Condition;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let f = match std::env::args().nth(1).as_deref() {
        Some("fleece") => FabricPreset::Fleece,
        Some("satin") => FabricPreset::Satin,
        Some("knit") => FabricPreset::Knit,
        _ => FabricPreset::Linen,
    };
    let rig = rig_spec(160, 120).build()?.rig;
    let angle = cloth_fit::angle::AngleOptions { grad_threshold: 0.02, ..Default::default() };
    let setup = EvalSetup {
        rig,
        model: SimOptions { res: 8, dt: 1.0 / 120.0, ..fit_model() },
        render: Default::default(),
        angle,
        metric: Default::default(),
    };
    let truth = static_truth(f);
    let fwd = ShellsForward;
    let mut e = static_trial(f, 0, 1);
    let env = |k: &str| std::env::var(k).ok().and_then(|v| v.parse::<f64>().ok());
    if let Some(b) = env("BULGE") {
        e.settle.bulge_m = b;
    }
    if let Some(n) = env("RELAX_STEPS") {
        e.settle.relax_steps = n as usize;
    }
    if let Some(h) = env("RELAX_DT") {
        e.settle.relax_dt = h;
    }
    if let Some(n) = env("QS") {
        e.settle.quasi_static_steps = n as usize;
    }
    let t = truths(&fwd, &[e], truth, &setup, Condition::Matched, Default::default())?;
    let targets = [t[0].target.clone()];
    let sp = space(&ParamId::CLOTH, truth)?;
    let obj = Objective::new(&targets, &fwd, &sp, &setup)?;
    let fold_px: usize = t[0].target.frames.iter().map(|a| a.fold_mask.count()).sum();
    let valid_px: usize = t[0].target.frames.iter().map(|a| a.valid.count()).sum();
    println!("{}: truth fold pixels {fold_px}, valid pixels {valid_px}", f.name());
    for id in ParamId::CLOTH {
        let mut line = format!("{:12}", id.name());
        for d in [-0.5, -0.2, -0.1, -0.05, -0.01, 0.01, 0.05, 0.1, 0.2, 0.5, 1.0] {
            let r = &obj.eval_params(&[truth.with(id, truth.get(id) * (1.0 + d))])[0];
            line += &format!(" {d:+}:{:.3}({:.3}/{})", r.error, r.fold, r.silh);
        }
        println!("{line}");
        let h = obj.history();
        let walls: Vec<f64> = h.iter().filter(|r| !r.cached).map(|r| r.sim_s).collect();
        println!("{:12} median simulation {:.3} s", "", geom_core::stats::median(&walls));
    }
    Ok(())
}

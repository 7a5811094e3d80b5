//! How much the settled static shape depends on damping and drag (it should not: spec §3.2):
//! the largest vertex distance between static drapes whose damping or drag differ by 5 %, and
//! the settle time used.
//!
//! `cargo run --release -p cloth-fit --example relax_check`

use cloth_fit::forward::{ShellsForward, SimOptions};
use cloth_fit::params::ParamId;
use cloth_fit::presets::{fit_model, rig_spec, static_trial, FabricPreset};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let rig = rig_spec(160, 120).build()?.rig;
    let model = SimOptions { res: 8, dt: 1.0 / 120.0, ..fit_model() };
    for f in FabricPreset::ALL {
        let p = f.params();
        let mut e = static_trial(f, 0, 1);
        if let Some(n) = std::env::args().nth(1) {
            e.settle.relax_steps = n.parse()?;
        }
        if let Some(h) = std::env::args().nth(2) {
            e.settle.relax_dt = h.parse()?;
        }
        let base = ShellsForward.simulate_raw(&p, &e, &rig, &model)?;
        let mut short = e.clone();
        short.settle.settle_s = 1.0;
        short.settle.ke_per_mass = std::env::var("KE").ok().and_then(|s| s.parse().ok()).unwrap_or(1e-4);
        let s1 = ShellsForward.simulate_raw(&p, &short, &rig, &model)?;
        let d = base.frames[0].iter().zip(&s1.frames[0]).map(|(a, b)| (a - b).norm()).collect::<Vec<_>>();
        let d = geom_core::stats::max(&d);
        println!(
            "{:6} settle 1.0 s instead of 2.5 s: max |Δx| = {d:.3e} m (steps {} vs {})",
            f.name(),
            s1.steps,
            base.steps
        );
        for id in [ParamId::StretchDamp, ParamId::ShearDamp, ParamId::BendDamp, ParamId::DragN] {
            let q = p.with(id, p.get(id) * 1.05);
            let other = ShellsForward.simulate_raw(&q, &e, &rig, &model)?;
            let d: Vec<f64> = base.frames[0].iter().zip(&other.frames[0]).map(|(a, b)| (a - b).norm()).collect();
            let d = geom_core::stats::max(&d);
            println!(
                "{:6} {:12}: max |Δx| = {:.3e} m  (settle {:.3} s vs {:.3} s, settled {} / {})",
                f.name(),
                id.name(),
                d,
                base.settle_s,
                other.settle_s,
                base.settled,
                other.settled
            );
        }
    }
    Ok(())
}

//! flip-tet's scenes: each runs one of `flip_tet::experiments` through
//! [`run_experiment`](crate::record::run_experiment) (the scene file's `params` block is the
//! experiment's `Params`); setups, protocols and figures live in the crate.

use flip_tet::experiments as ex;

use crate::error::Error;
use crate::record::run_experiment;
use crate::registry::Runner;

impl From<flip_tet::error::SimError> for Error {
    fn from(e: flip_tet::error::SimError) -> Self {
        Error::Run(format!("flip-tet: {e}"))
    }
}

/// Adds flip-tet's runners.
pub fn register(v: &mut Vec<Runner>) {
    v.push(Runner { method: "flip-tet/rest-pool", run: |c| run_experiment(c, ex::rest_pool::run) });
    v.push(Runner { method: "flip-tet/dam-break", run: |c| run_experiment(c, ex::dam_break::run) });
    v.push(Runner { method: "flip-tet/standing-wave", run: |c| run_experiment(c, ex::standing_wave::run) });
    v.push(Runner { method: "flip-tet/drop-pool", run: |c| run_experiment(c, ex::drop_pool::run) });
    v.push(Runner { method: "flip-tet/holes-plate", run: |c| run_experiment(c, ex::holes_plate::run) });
    v.push(Runner { method: "flip-tet/adaptivity-payoff", run: |c| run_experiment(c, ex::adaptivity_payoff::run) });
    v.push(Runner { method: "flip-tet/surface-mixed-radii", run: |c| run_experiment(c, ex::surface_mixed_radii::run) });
    v.push(Runner { method: "flip-tet/fvm-vs-nodal", run: |c| run_experiment(c, ex::fvm_vs_nodal::run) });
    v.push(Runner { method: "flip-tet/open-splash", run: |c| run_experiment(c, ex::open_splash::run) });
    v.push(Runner { method: "flip-tet/corridor-camera", run: |c| run_experiment(c, ex::corridor_camera::run) });
    v.push(Runner { method: "flip-tet/dam-break-gate", run: |c| run_experiment(c, ex::dam_break_gate::run) });
    v.push(Runner { method: "flip-tet/inflow", run: |c| run_experiment(c, ex::inflow::run) });
    v.push(Runner {
        method: "flip-tet/obstacle-force",
        run: |c| {
            // Mesh paths resolve against the scene file's folder.
            run_experiment(c, |p: &ex::obstacle_force::Params, size, rec| {
                let mut p = p.clone();
                p.resolve_paths(&c.resolve("."));
                ex::obstacle_force::run(&p, size, rec)
            })
        },
    });
}

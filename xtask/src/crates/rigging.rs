//! rigging's scenes (spec §6): thin adapters over `rigging::experiments` — the test set, stage
//! timings, learning Γ, a walk, the bone-heat figure, odd shapes and arm weight on the torso.

use rigging::experiments::{animate, heat_two_bone, odd_shapes, test16, timing, train, weights_vs_proximity};
use rigging::RigError;

use crate::error::Error;
use crate::record::run_experiment;
use crate::registry::Runner;

impl From<RigError> for Error {
    fn from(e: RigError) -> Self {
        match e {
            RigError::Core(c) => Error::Core(c),
            other => Error::Run(format!("rigging: {other}")),
        }
    }
}

/// Adds rigging's runners.
pub fn register(v: &mut Vec<Runner>) {
    v.push(Runner { method: "rigging/test16", run: |c| run_experiment(c, test16::run) });
    v.push(Runner { method: "rigging/timing", run: |c| run_experiment(c, timing::run) });
    v.push(Runner { method: "rigging/train", run: |c| run_experiment(c, train::run) });
    v.push(Runner { method: "rigging/animate", run: |c| run_experiment(c, animate::run) });
    v.push(Runner { method: "rigging/heat-two-bone", run: |c| run_experiment(c, heat_two_bone::run) });
    v.push(Runner { method: "rigging/odd-shapes", run: |c| run_experiment(c, odd_shapes::run) });
    v.push(Runner { method: "rigging/weights-vs-proximity", run: |c| run_experiment(c, weights_vs_proximity::run) });
}

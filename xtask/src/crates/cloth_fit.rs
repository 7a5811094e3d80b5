//! cloth-fit scenes (Bhat et al. 2003; spec `cloth-fit.md` §6): every runner is the crate's
//! experiment behind [`run_experiment`]. The spec's `cargo xtask cloth-fit <scene>` is
//! `cargo xtask run cloth-fit/<scene>`.

use cloth_fit::experiments::{
    confusion, errormap, pareto, real_roundtrip, static_consistency, static_test, validate, waving, waving_linen,
};

use crate::error::Error;
use crate::record::run_experiment;
use crate::registry::Runner;

impl From<cloth_fit::FitError> for Error {
    fn from(e: cloth_fit::FitError) -> Self {
        match e {
            cloth_fit::FitError::Core(c) => Error::Core(c),
            other => Error::Run(other.to_string()),
        }
    }
}

/// Registers the cloth-fit runners (C1–C8 and the single-fabric waving protocol; C9 `skirt`
/// waits for the contact suite of `shells`).
pub fn register(v: &mut Vec<Runner>) {
    v.push(Runner { method: "cloth-fit/static", run: |c| run_experiment(c, static_test::run) });
    v.push(Runner { method: "cloth-fit/static-consistency", run: |c| run_experiment(c, static_consistency::run) });
    v.push(Runner { method: "cloth-fit/waving", run: |c| run_experiment(c, waving::run) });
    v.push(Runner { method: "cloth-fit/waving-linen", run: |c| run_experiment(c, waving_linen::run) });
    v.push(Runner { method: "cloth-fit/errormap", run: |c| run_experiment(c, errormap::run) });
    v.push(Runner { method: "cloth-fit/confusion", run: |c| run_experiment(c, confusion::run) });
    v.push(Runner { method: "cloth-fit/validate", run: |c| run_experiment(c, validate::run) });
    v.push(Runner { method: "cloth-fit/pareto", run: |c| run_experiment(c, pareto::run) });
    v.push(Runner { method: "cloth-fit/real-roundtrip", run: |c| run_experiment(c, real_roundtrip::run) });
}

//! shells' scenes: each runs one of `shells::experiments` through
//! [`run_experiment`](crate::record::run_experiment) (the scene file's `params` block is the
//! experiment's `Params`); setups, protocols and figures live in the crate.

use geom_core::experiment::{Report, Size};
use geom_core::record::Recorder;
use serde::de::DeserializeOwned;
use shells::experiments as ex;

use crate::error::{Error, Result};
use crate::out::Summary;
use crate::record::run_experiment;
use crate::registry::{RunCtx, Runner};
use crate::scene;

impl From<shells::Error> for Error {
    fn from(e: shells::Error) -> Self {
        Error::Run(format!("shells: {e}"))
    }
}

/// The signature of every shells experiment.
type Experiment<P> = fn(&P, Size, &mut dyn Recorder) -> shells::Result<Report>;

/// Runs one experiment on the context's scene file; a bad parameter (the message names the
/// field, e.g. `pins[0]` or `effects.mesh_obstacles[1]`) becomes an error naming the file.
fn run<P: DeserializeOwned>(ctx: &RunCtx, f: Experiment<P>) -> Result<Summary> {
    run_experiment(ctx, |p: &P, size, rec| {
        f(p, size, rec).map_err(|e| match e {
            shells::Error::BadParameter(m) => scene::invalid(&ctx.scene_file, format!("params: {m}")),
            other => Error::from(other),
        })
    })
}

/// Adds the shells runners.
pub fn register(v: &mut Vec<Runner>) {
    v.push(Runner { method: "shells/calib-bend", run: |c| run(c, ex::calib_bend::run) });
    v.push(Runner { method: "shells/cantilever", run: |c| run(c, ex::cantilever::run) });
    v.push(Runner { method: "shells/drape", run: |c| run(c, ex::drape::run) });
    v.push(Runner { method: "shells/fold-stress", run: |c| run(c, ex::fold_stress::run) });
    v.push(Runner { method: "shells/plastic-crease", run: |c| run(c, ex::plastic_crease::run) });
    v.push(Runner { method: "shells/wind-flag", run: |c| run(c, ex::wind_flag::run) });
    v.push(Runner { method: "shells/contact", run: |c| run(c, ex::contact::run) });
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::Mode;

    /// A bad parameter found by the crate (an empty pin set) is an error naming the scene file
    /// and the field, raised before any step.
    #[test]
    fn bad_parameter_names_file_and_field() {
        let dir = std::env::temp_dir().join(format!("xtask-shells-bad-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let file = dir.join("bad.ron");
        let text = std::fs::read_to_string(scene::scenes_dir().join("shells/drape.ron")).unwrap();
        std::fs::write(&file, text.replace("pins: [TopCorners]", "pins: [TopCorners, Vertices([])]")).unwrap();
        let ctx = RunCtx { scene_file: file.clone(), mode: Mode::Quick, out_dir: dir.join("out") };
        let e = run(&ctx, ex::drape::run).unwrap_err().to_string();
        assert!(e.contains("bad.ron") && e.contains("pins[1]"), "{e}");
        assert!(!dir.join("out/frames").exists(), "no step was taken");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}

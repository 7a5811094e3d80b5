//! The paper experiments of perf-control (spec §6), callable without xtask. Each module has a
//! `Params` (the `params` block of its scene file `scenes/perf-control/<scene>.ron`) and
//! `run(&Params, Size, &mut dyn Recorder) -> Result<Report>`:
//! [`walk`] (PC-1), [`walk_timing`] (PC-2), [`mouse_paths`] (PC-3), [`real_data`] (PC-6), [`dance`] (PC-4), [`dance_timing`] (PC-5);
//! [`sweeps`] holds the library calls of the accuracy-versus-time benchmark (spec §9).

pub mod common;
pub mod dance;
pub mod dance_timing;
pub mod mouse_paths;
pub mod real_data;
pub mod sweeps;
pub mod walk;
pub mod walk_timing;

use std::path::Path;

use serde::de::DeserializeOwned;

use crate::error::{PcError, Result};

/// The envelope of a scene file: `(method: "…", description: "…", params: (…))`.
#[derive(serde::Deserialize)]
struct SceneFile<P> {
    #[allow(dead_code)] // part of the format; the runner is chosen by the caller
    method: String,
    #[serde(default)]
    #[allow(dead_code)]
    description: String,
    params: P,
}

/// Reads the `params` block of a scene file (e.g. `scenes/perf-control/walk.ron`) as `P` (an
/// experiment's `Params`); errors name the file, line and column.
pub fn load_params<P: DeserializeOwned>(path: &Path) -> Result<P> {
    let at = |msg: String| PcError::BadParameter { name: "scene file", msg: format!("{}: {msg}", path.display()) };
    let text = std::fs::read_to_string(path).map_err(|e| at(e.to_string()))?;
    let f: SceneFile<P> = ron::from_str(&text).map_err(|e| at(e.to_string()))?;
    Ok(f.params)
}

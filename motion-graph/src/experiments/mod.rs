//! The paper experiments of motion-graph (spec §6.2), callable without xtask:
//! [`search`] is the one experiment behind every scene file `scenes/motion-graph/*.ron` (MG-1 …
//! MG-8, its `Params` is the scene's `params` block); [`sweeps`] holds the library calls of the
//! accuracy-versus-time benchmark (spec §9).

pub mod search;
pub mod sweeps;

use std::path::Path;

use serde::de::DeserializeOwned;

use crate::{Error, Result};

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

/// Reads the `params` block of a scene file (e.g. `scenes/motion-graph/football.ron`) as `P`
/// (an experiment's `Params`); errors name the file, line and column.
pub fn load_params<P: DeserializeOwned>(path: &Path) -> Result<P> {
    let at =
        |msg: String| Error::File { path: path.display().to_string(), source: geom_core::Error::InvalidParameter(msg) };
    let text = std::fs::read_to_string(path).map_err(|e| at(e.to_string()))?;
    let f: SceneFile<P> = ron::from_str(&text).map_err(|e| at(e.to_string()))?;
    Ok(f.params)
}

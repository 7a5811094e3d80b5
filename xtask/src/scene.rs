//! Scene files (RON). A scene file names the runner (`method: "<crate>/<runner>"`), says in one
//! line what it shows, and carries the runner's typed parameters, the list of effects included:
//!
//! ```ron
//! (
//!     method: "geom-core/render",
//!     description: "Depth, normal, silhouette and shaded images of procedural meshes",
//!     params: ( width: 480, height: 360 ),
//! )
//! ```
//!
//! Errors name the file, the line and column, and what is wrong.

use std::path::{Path, PathBuf};

use serde::de::DeserializeOwned;
use serde::Deserialize;

use crate::error::{io_err, Error, Result};

/// How big a run is: `--quick` is a smoke run (well under a minute), `--full` the paper scale.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum Mode {
    /// Reduced sizes for smoke tests.
    Quick,
    /// The default: fits the 30-minute budget of `repro` together with every other scene.
    Default,
    /// Paper scale.
    Full,
}

impl Mode {
    /// Lower-case name written into summaries.
    pub fn name(self) -> &'static str {
        match self {
            Mode::Quick => "quick",
            Mode::Default => "default",
            Mode::Full => "full",
        }
    }

    /// The experiment size of geom-core this mode runs at.
    #[allow(dead_code)] // used as the adapters move onto `record::run_experiment` (issue 21)
    pub fn size(self) -> geom_core::experiment::Size {
        use geom_core::experiment::Size;
        match self {
            Mode::Quick => Size::Quick,
            Mode::Default => Size::Default,
            Mode::Full => Size::Full,
        }
    }

    /// Picks one of three values by mode.
    pub fn pick<T>(self, quick: T, default: T, full: T) -> T {
        match self {
            Mode::Quick => quick,
            Mode::Default => default,
            Mode::Full => full,
        }
    }
}

/// The envelope every scene file shares.
#[derive(Debug, Deserialize)]
pub struct SceneFile<P> {
    /// The runner, `<crate>/<runner>`.
    pub method: String,
    /// One line saying what the scene shows.
    #[serde(default)]
    pub description: String,
    /// The runner's parameters.
    pub params: P,
}

/// The envelope without parameters, to find the runner of a file before parsing its parameters.
#[derive(Debug, Deserialize)]
pub struct SceneHeader {
    /// The runner, `<crate>/<runner>`.
    pub method: String,
    /// One line saying what the scene shows.
    #[serde(default)]
    pub description: String,
}

fn options() -> ron::Options {
    ron::Options::default().with_default_extension(ron::extensions::Extensions::IMPLICIT_SOME)
}

fn read_text(path: &Path) -> Result<String> {
    std::fs::read_to_string(path).map_err(io_err(path))
}

fn spanned(path: &Path, e: ron::error::SpannedError) -> Error {
    Error::Scene { file: path.to_path_buf(), line: e.span.start.line, col: e.span.start.col, msg: e.code.to_string() }
}

/// Parses scene text (the path is only used in messages).
pub fn parse<P: DeserializeOwned>(path: &Path, text: &str) -> Result<SceneFile<P>> {
    options().from_str(text).map_err(|e| spanned(path, e))
}

/// Reads only the envelope of a scene file.
pub fn load_header(path: &Path) -> Result<SceneHeader> {
    let text = read_text(path)?;
    options().from_str(&text).map_err(|e| spanned(path, e))
}

/// Reads a whole scene file with typed parameters.
pub fn load<P: DeserializeOwned>(path: &Path) -> Result<SceneFile<P>> {
    let sc: SceneFile<P> = parse(path, &read_text(path)?)?;
    if !sc.method.contains('/') {
        return Err(invalid(path, format!("method '{}' must be <crate>/<runner>", sc.method)));
    }
    if sc.description.trim().is_empty() {
        return Err(invalid(path, "description is empty: say in one line what the scene shows"));
    }
    Ok(sc)
}

/// An error about a scene's content found after parsing (an out-of-range parameter): names the
/// file and the parameter; line 0 means "not tied to one line".
pub fn invalid(path: &Path, msg: impl Into<String>) -> Error {
    Error::Scene { file: path.to_path_buf(), line: 0, col: 0, msg: msg.into() }
}

/// The built-in scene directory, `<workspace>/scenes`.
pub fn scenes_dir() -> PathBuf {
    crate::out::workspace_root().join("scenes")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(Debug, Deserialize)]
    #[serde(deny_unknown_fields)]
    struct P {
        n: u32,
        #[serde(default)]
        scale: Option<f64>,
    }

    #[test]
    fn parses_envelope_and_params() {
        let s: SceneFile<P> =
            parse(Path::new("x.ron"), "(method: \"a/b\", description: \"d\", params: (n: 3, scale: 2.0))").unwrap();
        assert_eq!(s.method, "a/b");
        assert_eq!(s.params.n, 3);
        assert_eq!(s.params.scale, Some(2.0));
    }

    #[test]
    fn errors_name_file_line_and_problem() {
        let text = "(\n  method: \"a/b\",\n  params: (\n    n: -3,\n  ),\n)";
        let e = parse::<P>(Path::new("bad.ron"), text).unwrap_err();
        let msg = e.to_string();
        assert!(msg.starts_with("bad.ron:4:"), "{msg}");
        let e = parse::<P>(Path::new("bad.ron"), "(method: \"a/b\", params: (n: 1, typo: 2))").unwrap_err();
        assert!(e.to_string().contains("typo"), "{e}");
        let e = parse::<P>(Path::new("bad.ron"), "(method: \"a/b\"").unwrap_err();
        assert!(e.to_string().starts_with("bad.ron:1:"), "{e}");
    }

    #[test]
    fn header_ignores_params() {
        let h: SceneHeader = options().from_str("(method: \"a/b\", params: (anything: [1, 2]))").unwrap();
        assert_eq!(h.method, "a/b");
    }
}

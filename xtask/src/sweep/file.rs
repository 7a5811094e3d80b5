//! Sweep files (RON): a scene, a run mode and the parameters to vary, every combination run:
//!
//! ```ron
//! (
//!     scene: "shells/drape",                                   // built-in id or a .ron path
//!     mode: Quick,                                             // Quick | Default | Full
//!     vary: [ ("shell.material.density", [0.1, 0.15, 0.2]) ],  // the grid over every listed field
//! )
//! ```
//!
//! A `.ron` scene path resolves against the sweep file's folder. Each varied path starts inside
//! the scene's `params` block (as `--set` does) and each value is one RON value, kept as written.
//! Errors name the sweep file, the line and column, and the field (`vary.0.1.2`): a path that the
//! scene does not have, a value that is not one RON value, an empty list, a repeated path.

use std::path::{Path, PathBuf};

use serde::de::IgnoredAny;
use serde::Deserialize;

use crate::error::{io_err, Error, Result};
use crate::ronpath::{self, Seg};
use crate::scene::{self, Mode, Override};

/// One varied parameter.
#[derive(Clone, Debug, PartialEq)]
pub struct Dim {
    /// The path inside the scene's `params` (`shell.material.density`).
    pub path: String,
    /// Its values, as RON text written in the sweep file.
    pub values: Vec<String>,
}

/// A parsed and checked sweep file.
#[derive(Clone, Debug)]
pub struct SweepFile {
    /// The sweep file.
    pub file: PathBuf,
    /// The scene file the tasks run (absolute).
    pub scene: PathBuf,
    /// The run mode of every task.
    pub mode: Mode,
    /// The varied parameters, outermost first.
    pub vary: Vec<Dim>,
}

#[derive(Deserialize)]
enum SweepMode {
    Quick,
    Default,
    Full,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct Raw {
    scene: String,
    #[serde(default = "default_mode")]
    mode: SweepMode,
    vary: Vec<(String, Vec<IgnoredAny>)>,
}

fn default_mode() -> SweepMode {
    SweepMode::Default
}

/// An error at `path` of the sweep file (its line and column), naming the field.
fn at(file: &Path, text: &str, path: &[Seg], msg: impl std::fmt::Display) -> Error {
    let o = ronpath::outline(text);
    let (line, col) = ronpath::find(&o, path).map(|e| ronpath::line_col(text, e.key_at)).unwrap_or((1, 1));
    Error::Scene { file: file.to_path_buf(), line, col, msg: format!("`{}`: {msg}", ronpath::path_string(path)) }
}

/// Reads and checks a sweep file.
pub fn load(file: &Path) -> Result<SweepFile> {
    let text = std::fs::read_to_string(file).map_err(io_err(file))?;
    parse(file, &text)
}

/// Parses and checks sweep text (`file` names it in errors and anchors a relative scene path).
pub fn parse(file: &Path, text: &str) -> Result<SweepFile> {
    let opts = ron::Options::default().with_default_extension(ron::extensions::Extensions::IMPLICIT_SOME);
    let raw: Raw = opts.from_str(text).map_err(|e| scene::spanned(file, text, &[], e))?;
    let o = ronpath::outline(text);
    let field = |s: &str| Seg::Field(s.into());
    let scene_path = vec![field("scene")];
    let scene = if raw.scene.ends_with(".ron") {
        let p = crate::paths::resolve_in(&crate::paths::absolute(file), Path::new(&raw.scene));
        if !p.is_file() {
            return Err(at(file, text, &scene_path, format!("no scene file {}", p.display())));
        }
        p
    } else {
        crate::registry::resolve_target(&raw.scene).map_err(|e| at(file, text, &scene_path, e))?.1
    };
    let scene_text = std::fs::read_to_string(&scene).map_err(io_err(&scene))?;
    let header = scene::load_header(&scene)?;
    if raw.vary.is_empty() {
        return Err(at(file, text, &[field("vary")], "lists no parameter: add (\"path.to.field\", [values])"));
    }
    let mut vary: Vec<Dim> = Vec::new();
    for (k, (path, values)) in raw.vary.iter().enumerate() {
        let here = vec![field("vary"), Seg::Index(k)];
        if values.is_empty() {
            return Err(at(
                file,
                text,
                &[here.clone(), vec![Seg::Index(1)]].concat(),
                format!("`{path}` has no values"),
            ));
        }
        if vary.iter().any(|d| &d.path == path) {
            return Err(at(file, text, &here, format!("`{path}` is listed twice")));
        }
        let mut texts = Vec::new();
        for j in 0..values.len() {
            let vp = [here.clone(), vec![Seg::Index(1), Seg::Index(j)]].concat();
            let e = ronpath::find(&o, &vp).ok_or_else(|| at(file, text, &vp, "cannot locate this value"))?;
            let v = text[e.value.clone()].trim().to_string();
            let ov = Override::parse(&format!("{path}={v}")).map_err(|e| at(file, text, &vp, e))?;
            texts.push(ov.value);
        }
        // The path must exist in the scene (or be addable to its parent), as `--set` requires.
        let first = [here.clone(), vec![Seg::Index(0)]].concat();
        let ov = Override { path: path.clone(), value: texts[0].clone() };
        scene::apply_overrides(&scene, &scene_text, &[ov]).map_err(|e| at(file, text, &first, e))?;
        // A field the scene does not write is added by the override; catch a misspelt name here
        // rather than in every task: it must be a field of some parameter struct of the crate.
        let mut full = vec![field("params")];
        full.extend(ronpath::parse_path(path));
        let written = ronpath::find(&ronpath::outline(&scene_text), &full).is_some();
        if let (false, Some(Seg::Field(leaf))) = (written, full.last()) {
            let krate = header.method.split('/').next().unwrap_or_default();
            if crate::params::is_field_of_crate(krate, leaf) == Some(false) {
                return Err(at(
                    file,
                    text,
                    &first,
                    format!(
                        "`{path}`: {} does not write `{leaf}` and no parameter of {krate} is called so (`cargo xtask params {}` lists them)",
                        scene.display(),
                        header.method
                    ),
                ));
            }
        }
        vary.push(Dim { path: path.clone(), values: texts });
    }
    let mode = match raw.mode {
        SweepMode::Quick => Mode::Quick,
        SweepMode::Default => Mode::Default,
        SweepMode::Full => Mode::Full,
    };
    Ok(SweepFile { file: crate::paths::absolute(file), scene, mode, vary })
}

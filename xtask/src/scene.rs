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
use std::sync::Mutex;

use serde::de::DeserializeOwned;
use serde::Deserialize;

use crate::error::{io_err, Error, Result};
use crate::ronpath::{self, Kind, Seg};

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

/// A `--set path.to.field=VALUE` override: the path starts inside the scene's `params` block
/// (`shell.material.density`, `size.0`), the value is RON text (`0.2`, `(640, 480)`,
/// `Grid(n: 12)`).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Override {
    /// Dotted path inside `params`.
    pub path: String,
    /// RON text of the new value.
    pub value: String,
}

impl Override {
    /// Parses `path=VALUE`; an error says what is wrong with the argument.
    pub fn parse(arg: &str) -> Result<Override> {
        let (path, value) =
            arg.split_once('=').ok_or_else(|| Error::Usage(format!("--set {arg}: expected path.to.field=VALUE")))?;
        let path = path.trim();
        let value = value.trim();
        let ok_path = !path.is_empty()
            && path.split('.').all(|s| !s.is_empty() && s.chars().all(|c| c.is_ascii_alphanumeric() || c == '_'));
        if !ok_path {
            return Err(Error::Usage(format!(
                "--set {arg}: '{path}' is not a field path (names and indices joined by dots, e.g. shell.material.density)"
            )));
        }
        if value.contains('\n') || !ronpath::is_single_value(value) {
            return Err(Error::Usage(format!(
                "--set {arg}: '{value}' is not one RON value (a number, \"text\", (a, b), [x, y], Name(field: v) …)"
            )));
        }
        Ok(Override { path: path.to_string(), value: value.to_string() })
    }

    fn full_path(&self) -> Vec<Seg> {
        let mut p = vec![Seg::Field("params".into())];
        p.extend(ronpath::parse_path(&self.path));
        p
    }
}

impl std::fmt::Display for Override {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "--set {}={}", self.path, self.value)
    }
}

/// Overrides in force: for one scene file (`run`) or for every scene file read (`bench`).
struct Active {
    file: Option<PathBuf>,
    overrides: Vec<Override>,
    applied: usize,
}

static ACTIVE: Mutex<Option<Active>> = Mutex::new(None);

fn same_file(a: &Path, b: &Path) -> bool {
    match (a.canonicalize(), b.canonicalize()) {
        (Ok(x), Ok(y)) => x == y,
        _ => a == b,
    }
}

/// Puts `overrides` in force for every later read of `file` (or of every scene file when `file`
/// is `None`), replacing earlier ones. An empty list clears them.
pub fn set_overrides(file: Option<&Path>, overrides: Vec<Override>) {
    let mut a = ACTIVE.lock().unwrap_or_else(|e| e.into_inner());
    *a = (!overrides.is_empty()).then(|| Active { file: file.map(Path::to_path_buf), overrides, applied: 0 });
}

/// How many scene reads the overrides in force were applied to.
pub fn overrides_applied() -> usize {
    ACTIVE.lock().unwrap_or_else(|e| e.into_inner()).as_ref().map_or(0, |a| a.applied)
}

fn overrides_for(path: &Path) -> Vec<Override> {
    let mut a = ACTIVE.lock().unwrap_or_else(|e| e.into_inner());
    match a.as_mut() {
        Some(act) if act.file.as_deref().is_none_or(|f| same_file(f, path)) => {
            act.applied += 1;
            act.overrides.clone()
        }
        _ => Vec::new(),
    }
}

/// Applies overrides to scene text: each replaces the value at its path, or adds the field to its
/// parent `( … )` when the field is not written (a field with a default). Returns the new text;
/// lines do not move (values are spliced in on the line where they go). An error names the file,
/// the line of the nearest existing parent and the override.
pub fn apply_overrides(file: &Path, text: &str, overrides: &[Override]) -> Result<String> {
    let mut text = text.to_string();
    for ov in overrides {
        let path = ov.full_path();
        let o = ronpath::outline(&text);
        if let Some(e) = ronpath::find(&o, &path) {
            text.replace_range(e.value.clone(), &ov.value);
            continue;
        }
        let parent = &path[..path.len() - 1];
        let last = &path[path.len() - 1];
        let p = ronpath::find(&o, parent);
        match (p, last) {
            (Some(e), Seg::Field(name))
                if matches!(e.kind, Kind::Paren { fields: true, .. } | Kind::Paren { empty: true, .. }) =>
            {
                let Kind::Paren { close, empty, .. } = e.kind else { unreachable!("matched just above") };
                let before = text[..close].trim_end();
                let sep = if empty || before.ends_with(',') || before.ends_with('(') { " " } else { ", " };
                text.insert_str(close, &format!("{sep}{name}: {}", ov.value));
            }
            _ => {
                // The nearest ancestor that exists, for the message.
                let (k, e) = (1..path.len())
                    .rev()
                    .find_map(|k| ronpath::find(&o, &path[..k]).map(|e| (k, e)))
                    .map(|(k, e)| (k, Some(e)))
                    .unwrap_or((0, None));
                let (line, col) = e.map(|e| ronpath::line_col(&text, e.key_at)).unwrap_or((1, 1));
                let have = display_path(&path[..k]);
                return Err(Error::Scene {
                    file: file.to_path_buf(),
                    line,
                    col,
                    msg: format!(
                        "{ov}: `{}` does not exist{}",
                        ronpath::path_string(&path[1..]),
                        if k > 0 {
                            format!(" (`{have}` here has no `{}`)", ronpath::path_string(&path[k..k + 1]))
                        } else {
                            String::new()
                        }
                    ),
                });
            }
        }
    }
    Ok(text)
}

fn read_text(path: &Path) -> Result<String> {
    std::fs::read_to_string(path).map_err(io_err(path))
}

/// Reads a scene file with the overrides in force applied: the text, and the overrides used.
pub fn read_scene_text(path: &Path) -> Result<(String, Vec<Override>)> {
    let raw = read_text(path)?;
    let ovs = overrides_for(path);
    if ovs.is_empty() {
        return Ok((raw, ovs));
    }
    Ok((apply_overrides(path, &raw, &ovs)?, ovs))
}

/// A ron error as a message a person can act on: the field it is about (path inside the file),
/// integer/number expectations in words, and the override the bad value came from.
pub fn spanned(path: &Path, text: &str, overrides: &[Override], e: ron::error::SpannedError) -> Error {
    let (line, col) = (e.span.start.line, e.span.start.col);
    let at = ronpath::offset_of(text, line, col);
    let o = ronpath::outline(text);
    let entry = ronpath::innermost(&o, at).filter(|e| !e.path.is_empty());
    let mut msg = explain(&e.code);
    // ron reads `4.5` where an integer is expected as the integer 4 followed by a stray `.5`
    // ("Expected comma"): say what is wrong with the value.
    let fraction = text.get(at..).is_some_and(|r| {
        let mut c = r.chars();
        c.next() == Some('.') && c.next().is_some_and(|d| d.is_ascii_digit())
    }) && text.get(..at).and_then(|l| l.chars().last()).is_some_and(|d| d.is_ascii_digit());
    if fraction {
        msg = "expected an integer, found a number with a fraction".into();
    }
    if let Some(e) = entry {
        msg = format!("`{}`: {msg}", display_path(&e.path));
        // A value that came from the command line: say so.
        if let Some(ov) = overrides.iter().find(|ov| {
            let p = ov.full_path();
            e.path.len() >= p.len() && e.path[..p.len()] == p[..]
        }) {
            msg = format!("{msg} (the value comes from {ov})");
        }
    }
    Error::Scene { file: path.to_path_buf(), line, col, msg }
}

/// The path as a user writes it: inside `params` without the `params.` prefix.
pub fn display_path(p: &[Seg]) -> String {
    match p.first() {
        Some(Seg::Field(f)) if f == "params" && p.len() > 1 => ronpath::path_string(&p[1..]),
        _ => ronpath::path_string(p),
    }
}

fn explain(code: &ron::Error) -> String {
    use ron::Error as E;
    let integer = |t: &str| t.starts_with('u') || t.starts_with('i') || t.contains("integer");
    match code {
        E::InvalidValueForType { expected, found } if integer(expected) => {
            format!("expected an integer ({expected}), found {found}")
        }
        E::ExpectedInteger => "expected an integer".into(),
        E::ExpectedFloat => "expected a number".into(),
        E::IntegerOutOfBounds => "integer out of range for this field".into(),
        other => other.to_string(),
    }
}

/// Parses scene text (the path is only used in messages).
#[cfg(test)]
pub fn parse<P: DeserializeOwned>(path: &Path, text: &str) -> Result<SceneFile<P>> {
    options().from_str(text).map_err(|e| spanned(path, text, &[], e))
}

/// Reads only the envelope of a scene file.
pub fn load_header(path: &Path) -> Result<SceneHeader> {
    let (text, ovs) = read_scene_text(path)?;
    options().from_str(&text).map_err(|e| spanned(path, &text, &ovs, e))
}

/// Reads a whole scene file with typed parameters (with the `--set` overrides in force).
pub fn load<P: DeserializeOwned>(path: &Path) -> Result<SceneFile<P>> {
    let (text, ovs) = read_scene_text(path)?;
    let sc: SceneFile<P> = options().from_str(&text).map_err(|e| spanned(path, &text, &ovs, e))?;
    if !sc.method.contains('/') {
        return Err(at_field(path, &text, "method", format!("method '{}' must be <crate>/<runner>", sc.method)));
    }
    if sc.description.trim().is_empty() {
        return Err(at_field(path, &text, "description", "description is empty: say in one line what the scene shows"));
    }
    Ok(sc)
}

/// An error about the top-level field `field` of a scene file, at that field's line.
pub fn at_field(path: &Path, text: &str, field: &str, msg: impl Into<String>) -> Error {
    let o = ronpath::outline(text);
    let (line, col) =
        ronpath::find(&o, &[Seg::Field(field.into())]).map(|e| ronpath::line_col(text, e.key_at)).unwrap_or((1, 1));
    Error::Scene { file: path.to_path_buf(), line, col, msg: msg.into() }
}

/// An error about a scene's content found after parsing (an out-of-range parameter): names the
/// file and the parameter; line 0 means "not tied to one line yet" — [`locate`] ties it to the
/// line of the field the message names when the run reports it.
pub fn invalid(path: &Path, msg: impl Into<String>) -> Error {
    Error::Scene { file: path.to_path_buf(), line: 0, col: 0, msg: msg.into() }
}

/// The field of `text` a validation message is about: a dotted path it names (`material.density`,
/// with or without `params.`), else the first word of the message that is the name of a field
/// under `params` (the first such field in the file). Returns its path and (line, column).
pub fn field_in_message(text: &str, msg: &str) -> Option<(Vec<Seg>, usize, usize)> {
    let o = ronpath::outline(text);
    let under_params =
        |e: &&ronpath::Entry| matches!(e.path.first(), Some(Seg::Field(f)) if f == "params") && e.path.len() > 1;
    let tokens: Vec<&str> = msg
        .split(|c: char| !(c.is_ascii_alphanumeric() || c == '_' || c == '.'))
        .map(|t| t.trim_matches('.'))
        .filter(|t| t.chars().next().is_some_and(|c| c.is_ascii_alphabetic() || c == '_'))
        .collect();
    let hit = |e: &ronpath::Entry| {
        let (l, c) = ronpath::line_col(text, e.key_at);
        (e.path.clone(), l, c)
    };
    for t in tokens.iter().filter(|t| t.contains('.')) {
        let segs = ronpath::parse_path(t);
        let mut with_params = vec![Seg::Field("params".into())];
        with_params.extend(segs.clone());
        if let Some(e) = ronpath::find(&o, &with_params).or_else(|| ronpath::find(&o, &segs)) {
            return Some(hit(e));
        }
    }
    for t in &tokens {
        let last = t.rsplit('.').next().unwrap_or(t);
        if let Some(e) = o.iter().filter(under_params).find(|e| e.path.last() == Some(&Seg::Field(last.to_string()))) {
            return Some(hit(e));
        }
    }
    None
}

/// Ties an error of a run to the line of the scene file it is about: a scene error without a
/// line, or a parameter error (its message says "parameter", "must be", "out of range",
/// "outside" or "invalid"), becomes `file:line:col: `field`: message` when the message names a
/// field of the file; the `params` block's line otherwise. Other errors are returned unchanged.
pub fn locate(file: &Path, e: Error) -> Error {
    let (msg, lineless) = match &e {
        Error::Scene { file: f, line: 0, msg, .. } if same_file(f, file) => (msg.clone(), true),
        Error::Scene { .. } | Error::Io { .. } | Error::Usage(_) => return e,
        other => (other.to_string(), false),
    };
    let lower = msg.to_lowercase();
    let about_params =
        ["parameter", "must be", "out of range", "outside", "invalid", "expected"].iter().any(|k| lower.contains(k));
    if !lineless && !about_params {
        return e;
    }
    let Ok((text, _)) = read_scene_text(file) else { return e };
    match field_in_message(&text, &msg) {
        Some((path, line, col)) => {
            let shown = display_path(&path);
            let msg = if msg.contains(&shown) { msg } else { format!("`{shown}`: {msg}") };
            Error::Scene { file: file.to_path_buf(), line, col, msg }
        }
        None if lineless => at_field(file, &text, "params", msg),
        None => e,
    }
}

/// The built-in scene directory (found at run time, [`crate::paths::scenes_dir`]); when none is
/// found, `scenes` under the current directory (so that messages name what was tried).
pub fn scenes_dir() -> PathBuf {
    crate::paths::scenes_dir().unwrap_or_else(|_| PathBuf::from("scenes"))
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

    const SCENE: &str = "// my scene\n(\n    method: \"a/b\",\n    description: \"d\",\n    params: (\n        shell: (\n            material: ( density: 0.15, name: \"cotton\" ),\n            substeps: 4,\n        ),\n        frames: (10, 60, 240),\n    ),\n)\n";

    #[derive(Debug, Deserialize)]
    #[serde(deny_unknown_fields)]
    struct Material {
        density: f64,
        name: String,
        #[serde(default)]
        friction: f64,
    }
    #[derive(Debug, Deserialize)]
    #[serde(deny_unknown_fields)]
    struct Shell {
        material: Material,
        substeps: u32,
    }
    #[derive(Debug, Deserialize)]
    #[serde(deny_unknown_fields)]
    struct Q {
        shell: Shell,
        frames: (u32, u32, u32),
    }

    fn set(args: &[&str]) -> Result<SceneFile<Q>> {
        let ovs: Vec<Override> = args.iter().map(|a| Override::parse(a).unwrap()).collect();
        let text = apply_overrides(Path::new("my.ron"), SCENE, &ovs)?;
        assert_eq!(text.lines().count(), SCENE.lines().count(), "lines never move");
        options().from_str(&text).map_err(|e| spanned(Path::new("my.ron"), &text, &ovs, e))
    }

    #[test]
    fn set_replaces_adds_and_validates_like_the_file() {
        let s = set(&["shell.material.density=0.2", "frames.1=90", "shell.material.friction=0.3"]).unwrap();
        assert_eq!(s.params.shell.material.density, 0.2);
        assert_eq!(s.params.frames, (10, 90, 240));
        assert_eq!(s.params.shell.material.friction, 0.3, "a defaulted field is added");
        assert_eq!(s.params.shell.material.name, "cotton");
        assert_eq!(s.params.shell.substeps, 4, "untouched fields keep the file's value");
        let s = set(&["shell.material=(density: 1.0, name: \"silk\")"]).unwrap();
        assert_eq!(s.params.shell.material.name, "silk");
        // A value of the wrong type is refused the way the file's would be, naming the override.
        let e = set(&["shell.substeps=4.5"]).unwrap_err().to_string();
        assert!(e.starts_with("my.ron:8:"), "{e}");
        assert!(e.contains("integer") && e.contains("--set shell.substeps=4.5"), "{e}");
        // A field that is neither written nor known.
        let e = set(&["shell.material.densty=0.2"]).unwrap_err().to_string();
        assert!(e.contains("densty"), "{e}");
        let e = set(&["shell.nope.x=1"]).unwrap_err().to_string();
        assert!(e.starts_with("my.ron:6:") && e.contains("`shell` here has no `nope`"), "{e}");
    }

    #[test]
    fn set_arguments_are_checked() {
        assert!(Override::parse("a.b=1").is_ok());
        assert!(Override::parse("a.b").unwrap_err().to_string().contains("path.to.field=VALUE"));
        assert!(Override::parse("a.b").is_err());
        assert!(Override::parse("a..b=1").is_err());
        assert!(Override::parse("a=1, 2").is_err());
        assert!(Override::parse("a=(1, 2").is_err());
        assert_eq!(Override::parse(" size = (640, 480) ").unwrap().value, "(640, 480)");
    }

    #[test]
    fn type_errors_name_the_field_and_say_integer() {
        let bad = SCENE.replace("substeps: 4,", "substeps: 4.5,");
        let e = parse::<Q>(Path::new("my.ron"), &bad).unwrap_err().to_string();
        assert!(e.starts_with("my.ron:8:"), "{e}");
        assert!(e.contains("`shell.substeps`") && e.contains("integer"), "{e}");
    }

    #[test]
    fn validation_messages_are_tied_to_the_line_of_their_field() {
        let (path, line, _) = field_in_message(SCENE, "bad parameter: density must be > 0 kg/m², got -0.15").unwrap();
        assert_eq!((display_path(&path).as_str(), line), ("shell.material.density", 7));
        let (path, line, _) = field_in_message(SCENE, "shell.substeps must be ≥ 1").unwrap();
        assert_eq!((display_path(&path).as_str(), line), ("shell.substeps", 8));
        assert!(field_in_message(SCENE, "solver diverged").is_none());
        let e = at_field(Path::new("my.ron"), SCENE, "method", "unknown method 'x/y'").to_string();
        assert!(e.starts_with("my.ron:3:"), "{e}");
        assert_eq!(invalid(Path::new("my.ron"), "boom").to_string(), "my.ron: boom", "no :0:0");
    }

    #[test]
    fn header_ignores_params() {
        let h: SceneHeader = options().from_str("(method: \"a/b\", params: (anything: [1, 2]))").unwrap();
        assert_eq!(h.method, "a/b");
    }
}

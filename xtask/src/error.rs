//! The one error type of xtask.

use std::path::PathBuf;

/// Everything a command of `cargo xtask` can fail with.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// An error from geom-core (mesh, file formats, solvers …).
    #[error(transparent)]
    Core(#[from] geom_core::Error),
    /// A scene file that cannot be read or does not describe a valid scene: `file:line:col: msg`
    /// (`file: msg` while the line is not known, `line` 0).
    #[error("{}", scene_place(file, *line, *col, msg))]
    Scene { file: PathBuf, line: usize, col: usize, msg: String },
    /// A file or directory could not be read or written.
    #[error("{path}: {source}")]
    Io { path: PathBuf, source: std::io::Error },
    /// The command line names something that does not exist.
    #[error("{0}")]
    Usage(String),
    /// A plot could not be drawn.
    #[error("plot {path}: {msg}")]
    Plot { path: PathBuf, msg: String },
    /// A scene or benchmark ran but failed (a method error, a violated invariant).
    #[error("{0}")]
    Run(String),
}

fn scene_place(file: &std::path::Path, line: usize, col: usize, msg: &str) -> String {
    if line == 0 {
        format!("{}: {msg}", file.display())
    } else {
        format!("{}:{line}:{col}: {msg}", file.display())
    }
}

/// Result alias of xtask.
pub type Result<T, E = Error> = std::result::Result<T, E>;

/// Attaches a path to an I/O error.
pub fn io_err(path: impl Into<PathBuf>) -> impl FnOnce(std::io::Error) -> Error {
    let path = path.into();
    move |source| Error::Io { path, source }
}

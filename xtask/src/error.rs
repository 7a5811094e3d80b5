//! The one error type of xtask.

use std::path::PathBuf;

/// Everything a command of `cargo xtask` can fail with.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// An error from geom-core (mesh, file formats, solvers …).
    #[error(transparent)]
    Core(#[from] geom_core::Error),
    /// A scene file that cannot be read or does not describe a valid scene.
    #[error("{file}:{line}:{col}: {msg}")]
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

/// Result alias of xtask.
pub type Result<T, E = Error> = std::result::Result<T, E>;

/// Attaches a path to an I/O error.
pub fn io_err(path: impl Into<PathBuf>) -> impl FnOnce(std::io::Error) -> Error {
    let path = path.into();
    move |source| Error::Io { path, source }
}

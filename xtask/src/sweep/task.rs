//! The state of one task's folder, read from the files a run leaves (issue 22): `summary.json`
//! written last and atomically by a run that succeeded, `FAILED` by one that did not.

use std::path::Path;

use crate::error::{io_err, Result};
use crate::run::FAILED;

/// What a task's folder says about it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TaskState {
    /// `summary.json` and no `FAILED`: done, skipped by every runner.
    Finished,
    /// `FAILED` beside whatever the run wrote.
    Failed,
    /// Files but neither `summary.json` nor `FAILED`: a run that was killed (or is running).
    Partial,
    /// No folder, or an empty one.
    Missing,
}

/// The state of the task whose folder is `dir`.
pub fn state(dir: &Path) -> TaskState {
    if dir.join(FAILED).exists() {
        TaskState::Failed
    } else if dir.join("summary.json").is_file() {
        TaskState::Finished
    } else if std::fs::read_dir(dir).map(|mut r| r.next().is_some()).unwrap_or(false) {
        TaskState::Partial
    } else {
        TaskState::Missing
    }
}

/// Removes what a failed or partial task left, so that it starts from an empty folder.
/// A finished or missing task is left alone.
pub fn clear_unfinished(dir: &Path) -> Result<bool> {
    match state(dir) {
        TaskState::Failed | TaskState::Partial => {
            std::fs::remove_dir_all(dir).map_err(io_err(dir))?;
            Ok(true)
        }
        TaskState::Finished | TaskState::Missing => Ok(false),
    }
}

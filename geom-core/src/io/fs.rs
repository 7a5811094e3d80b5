//! File access for the readers and writers: every operating-system error is re-issued with the
//! path in its message, so "No such file or directory" always says which file.
//!
//! Choice (documented in [`crate::io`]): the error stays [`Error::Io`] (its
//! [`std::io::ErrorKind`] is kept, so callers can still match on `NotFound` etc.) and only the
//! message gains the path. Parse errors of file readers get the path appended to their message by
//! [`with_path`].

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::Path;

use crate::error::{Error, Result};

/// `e` with `path` (and what was being done) prefixed to its message; the kind is kept.
pub(crate) fn io_error(path: &Path, action: &str, e: std::io::Error) -> Error {
    Error::Io(std::io::Error::new(e.kind(), format!("{action} {}: {e}", path.display())))
}

/// Reads a whole file; the error names the path.
pub(crate) fn read_file(path: &Path) -> Result<Vec<u8>> {
    std::fs::read(path).map_err(|e| io_error(path, "cannot read", e))
}

/// Adds the file path to a parse error's message (other errors pass unchanged): readers parse
/// from memory, where the path is unknown, and the file-level entry points call this.
pub(crate) fn with_path(e: Error, path: &Path) -> Error {
    match e {
        Error::Parse { format, line, msg } => {
            Error::Parse { format, line, msg: format!("{msg} (in {})", path.display()) }
        }
        other => other,
    }
}

/// The error for a mesh file that holds no mesh: it names the file and says it is empty.
pub(crate) fn empty_mesh(format: &'static str, path: &Path, what: &str) -> Error {
    Error::Parse { format, line: 0, msg: format!("the mesh is empty ({what}) (in {})", path.display()) }
}

/// Creates (truncates) `path` and hands a buffered writer to `body`; every I/O error, including
/// the final flush, names the path. Errors returned by `body` that are not I/O pass unchanged.
pub(crate) fn write_file(path: &Path, body: impl FnOnce(&mut dyn Write) -> Result<()>) -> Result<()> {
    let file = File::create(path).map_err(|e| io_error(path, "cannot create", e))?;
    let mut w = BufWriter::new(file);
    body(&mut w).map_err(|e| match e {
        Error::Io(e) => io_error(path, "cannot write", e),
        other => other,
    })?;
    w.flush().map_err(|e| io_error(path, "cannot write", e))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn missing_file_error_names_the_path_and_keeps_the_kind() {
        let p = Path::new("/definitely/not/here/mesh.obj");
        match read_file(p) {
            Err(Error::Io(e)) => {
                assert_eq!(e.kind(), std::io::ErrorKind::NotFound);
                assert!(e.to_string().contains("/definitely/not/here/mesh.obj"), "{e}");
            }
            other => panic!("expected Io error, got {other:?}"),
        }
    }

    #[test]
    fn parse_error_gains_the_path() {
        let e = Error::Parse { format: "OBJ", line: 3, msg: "bad number".into() };
        let e = with_path(e, Path::new("a/b.obj"));
        assert!(e.to_string().contains("a/b.obj"), "{e}");
        assert!(e.to_string().contains("line 3"), "{e}");
    }
}

//! The output layout of a run: `out/<crate>/<scene>/` with `summary.json` (a flat object of named
//! figures), CSV tables, frames and plots.

use std::collections::BTreeMap;
use std::fs;
use std::io::Write;
use std::path::{Path, PathBuf};

use crate::error::{io_err, Result};

/// What the runners written before `RunCtx::resolve` join a scene's relative paths to: while a
/// scene runs, the scene file's folder (issue 23: a path in a scene file resolves against that
/// file's folder); otherwise the folder holding the built-in `scenes/` and `assets/`, found at run
/// time ([`crate::paths::relative_base`]). New code uses `RunCtx::resolve`.
pub fn workspace_root() -> PathBuf {
    crate::paths::relative_base()
}

/// The default output root ([`crate::paths::default_out_root`]).
pub fn default_out_root() -> PathBuf {
    crate::paths::default_out_root()
}

/// Writes `path` atomically: the bytes go to a temporary file beside it, which is then renamed
/// over `path`, so a reader (or a resumed sweep) never sees a half-written file.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<()> {
    let name = path.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
    let tmp = path.with_file_name(format!(".{name}.tmp-{}", std::process::id()));
    let mut f = fs::File::create(&tmp).map_err(io_err(&tmp))?;
    f.write_all(bytes).map_err(io_err(&tmp))?;
    f.sync_all().map_err(io_err(&tmp))?;
    drop(f);
    fs::rename(&tmp, path).map_err(|e| {
        let _ = fs::remove_file(&tmp);
        crate::error::Error::Io { path: path.to_path_buf(), source: e }
    })
}

/// Creates a directory and its parents.
pub fn ensure_dir(dir: &Path) -> Result<()> {
    fs::create_dir_all(dir).map_err(io_err(dir))
}

/// A flat object of named figures, written as `summary.json`. Keys are stable and documented in
/// each crate's README: timings in seconds (`*_s`), errors with their metric in the name, counts.
#[derive(Clone, Debug, Default)]
pub struct Summary {
    values: BTreeMap<String, serde_json::Value>,
}

impl Summary {
    /// An empty summary.
    pub fn new() -> Self {
        Self::default()
    }

    /// Sets a number. Non-finite values are stored as `null` (JSON has no NaN) so a failure shows
    /// up instead of vanishing.
    pub fn set(&mut self, key: &str, v: f64) -> &mut Self {
        let value = serde_json::Number::from_f64(v).map(serde_json::Value::Number).unwrap_or(serde_json::Value::Null);
        self.values.insert(key.to_string(), value);
        self
    }

    /// Sets a count.
    pub fn set_count(&mut self, key: &str, v: u64) -> &mut Self {
        self.values.insert(key.to_string(), serde_json::Value::from(v));
        self
    }

    /// Sets a signed integer.
    pub fn set_int(&mut self, key: &str, v: i64) -> &mut Self {
        self.values.insert(key.to_string(), serde_json::Value::from(v));
        self
    }

    /// Sets a yes/no figure (`true` / `false`).
    pub fn set_bool(&mut self, key: &str, v: bool) -> &mut Self {
        self.values.insert(key.to_string(), serde_json::Value::from(v));
        self
    }

    /// Sets a text field (mode, units …).
    pub fn set_str(&mut self, key: &str, v: &str) -> &mut Self {
        self.values.insert(key.to_string(), serde_json::Value::from(v));
        self
    }

    /// A number previously set.
    pub fn get(&self, key: &str) -> Option<f64> {
        self.values.get(key).and_then(|v| v.as_f64())
    }

    /// Iterates over `(key, value)` in key order.
    pub fn iter(&self) -> impl Iterator<Item = (&String, &serde_json::Value)> {
        self.values.iter()
    }

    /// Writes `dir/summary.json` (pretty-printed, keys sorted) atomically ([`write_atomic`]).
    pub fn write(&self, dir: &Path) -> Result<PathBuf> {
        ensure_dir(dir)?;
        let path = dir.join("summary.json");
        let text = serde_json::to_string_pretty(&self.values).map_err(|e| crate::error::Error::Run(e.to_string()))?;
        write_atomic(&path, (text + "\n").as_bytes())?;
        Ok(path)
    }

    /// The raw JSON value of `key`.
    pub fn value(&self, key: &str) -> Option<&serde_json::Value> {
        self.values.get(key)
    }

    /// Reads a `summary.json` back.
    pub fn read(path: &Path) -> Result<Summary> {
        let text = fs::read_to_string(path).map_err(io_err(path))?;
        let values: BTreeMap<String, serde_json::Value> =
            serde_json::from_str(&text).map_err(|e| crate::error::Error::Run(format!("{}: {e}", path.display())))?;
        Ok(Summary { values })
    }
}

/// A CSV table written row by row, flushed after every row, so that a long run never loses
/// finished rows.
pub struct CsvWriter {
    path: PathBuf,
    file: fs::File,
    ncols: usize,
}

impl CsvWriter {
    /// Creates `path` and writes the header.
    pub fn create(path: &Path, header: &[&str]) -> Result<Self> {
        if let Some(dir) = path.parent() {
            ensure_dir(dir)?;
        }
        let mut file = fs::File::create(path).map_err(io_err(path))?;
        writeln!(file, "{}", header.join(",")).map_err(io_err(path))?;
        Ok(Self { path: path.to_path_buf(), file, ncols: header.len() })
    }

    /// Appends a row of cells (numbers or text); the count must match the header.
    pub fn row(&mut self, cells: &[Cell]) -> Result<()> {
        if cells.len() != self.ncols {
            return Err(crate::error::Error::Run(format!(
                "{}: row has {} cells, header has {}",
                self.path.display(),
                cells.len(),
                self.ncols
            )));
        }
        let line: Vec<String> = cells.iter().map(Cell::to_csv).collect();
        writeln!(self.file, "{}", line.join(",")).map_err(io_err(&self.path))?;
        self.file.flush().map_err(io_err(&self.path))
    }
}

/// One CSV cell.
#[derive(Clone, Debug)]
pub enum Cell {
    /// A number, written with full round-trip precision.
    Num(f64),
    /// An integer.
    Int(i64),
    /// Text (quoted if it holds a comma or quote).
    Text(String),
}

impl Cell {
    fn to_csv(&self) -> String {
        match self {
            Cell::Num(v) => format!("{v}"),
            Cell::Int(v) => format!("{v}"),
            Cell::Text(s) if s.contains([',', '"', '\n']) => format!("\"{}\"", s.replace('"', "\"\"")),
            Cell::Text(s) => s.clone(),
        }
    }
}

impl From<f64> for Cell {
    fn from(v: f64) -> Self {
        Cell::Num(v)
    }
}
impl From<usize> for Cell {
    fn from(v: usize) -> Self {
        Cell::Int(v as i64)
    }
}
impl From<&str> for Cell {
    fn from(v: &str) -> Self {
        Cell::Text(v.to_string())
    }
}
impl From<String> for Cell {
    fn from(v: String) -> Self {
        Cell::Text(v)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn summary_round_trips_and_nan_is_null() {
        let dir = std::env::temp_dir().join(format!("xtask-summary-{}", std::process::id()));
        let mut s = Summary::new();
        s.set("err_l2", 1.5e-12).set("nan_value", f64::NAN).set_count("frames", 12);
        let path = s.write(&dir).unwrap();
        let back = Summary::read(&path).unwrap();
        assert_eq!(back.get("err_l2"), Some(1.5e-12));
        assert_eq!(back.get("frames"), Some(12.0));
        assert!(back.get("nan_value").is_none());
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn atomic_writes_replace_whole_files_and_leave_no_temporary() {
        let dir = std::env::temp_dir().join(format!("xtask-atomic-{}", std::process::id()));
        let _ = fs::remove_dir_all(&dir);
        fs::create_dir_all(&dir).unwrap();
        let mut s = Summary::new();
        s.set("a", 1.0);
        s.write(&dir).unwrap();
        s.set("b", 2.0);
        s.write(&dir).unwrap();
        assert_eq!(Summary::read(&dir.join("summary.json")).unwrap().get("b"), Some(2.0));
        let names: Vec<String> =
            fs::read_dir(&dir).unwrap().flatten().map(|e| e.file_name().to_string_lossy().into_owned()).collect();
        assert_eq!(names, ["summary.json"], "no temporary file left");
        // A failed write leaves neither the target nor a temporary file.
        let e = write_atomic(&dir.join("missing/x.json"), b"{}").unwrap_err();
        assert!(e.to_string().contains("missing"), "{e}");
        assert!(write_atomic(&dir, b"{}").is_err(), "a folder cannot be replaced by a file");
        let names: Vec<String> =
            fs::read_dir(&dir).unwrap().flatten().map(|e| e.file_name().to_string_lossy().into_owned()).collect();
        assert_eq!(names, ["summary.json"]);
        fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn csv_rejects_wrong_row_width() {
        let path = std::env::temp_dir().join(format!("xtask-csv-{}.csv", std::process::id()));
        let mut w = CsvWriter::create(&path, &["a", "b"]).unwrap();
        w.row(&[1.0.into(), "x,y".into()]).unwrap();
        assert!(w.row(&[1.0.into()]).is_err());
        let text = std::fs::read_to_string(&path).unwrap();
        assert_eq!(text, "a,b\n1,\"x,y\"\n");
        std::fs::remove_file(&path).unwrap();
    }
}

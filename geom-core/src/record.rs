//! Where an experiment's outputs go while it runs: the [`Recorder`] trait.
//!
//! Method crates compute; they do not know about folders, file formats or plots. An experiment
//! hands every output to a `&mut dyn Recorder` the moment it exists — a frame of an animation, a
//! row of a table, a plot series, a note for the report, an artefact file — and the caller
//! decides what to do with it: xtask's file recorder writes `frames/NNNN.obj`, CSV tables,
//! PNG plots and `report.md` at once (so a long run never loses finished frames), the
//! [`NullRecorder`] drops everything (tests, benchmarks), and the [`MemoryRecorder`] keeps it for
//! inspection.
//!
//! ```
//! use geom_core::record::{Cell, MemoryRecorder, Recorder};
//! let mut rec = MemoryRecorder::default();
//! rec.table("steps", &["t", "energy_J"]).unwrap();
//! rec.row("steps", &[Cell::from(0.0), Cell::from(1.5)]).unwrap();
//! rec.note("converged after 3 iterations").unwrap();
//! assert_eq!(rec.tables["steps"].rows.len(), 1);
//! ```

use std::collections::BTreeMap;

use crate::error::{Error, Result};
use crate::math::Pt3;

/// One table cell.
#[derive(Clone, Debug, PartialEq)]
pub enum Cell {
    /// A number (written with round-trip precision; NaN stays NaN).
    Num(f64),
    /// An integer.
    Int(i64),
    /// A flag.
    Bool(bool),
    /// Text.
    Text(String),
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
impl From<u32> for Cell {
    fn from(v: u32) -> Self {
        Cell::Int(v as i64)
    }
}
impl From<u64> for Cell {
    fn from(v: u64) -> Self {
        Cell::Int(v as i64)
    }
}
impl From<i64> for Cell {
    fn from(v: i64) -> Self {
        Cell::Int(v)
    }
}
impl From<bool> for Cell {
    fn from(v: bool) -> Self {
        Cell::Bool(v)
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

/// A per-vertex or per-point scalar attached to a frame (strain, weight, speed …), for coloured
/// previews and PLY attributes.
#[derive(Clone, Copy, Debug)]
pub struct Attribute<'a> {
    /// Name (e.g. `"strain"`, `"pscale"`).
    pub name: &'a str,
    /// One value per vertex or point.
    pub values: &'a [f64],
}

/// One frame of an animated surface (a triangle mesh whose topology is fixed for the sequence).
#[derive(Clone, Copy, Debug)]
pub struct MeshFrame<'a> {
    /// The sequence it belongs to (`"frames"`, `"tracked"`, `"guide"` …): one folder each.
    pub sequence: &'a str,
    /// Frame number within the sequence (0, 1, …).
    pub index: usize,
    /// Simulation time (s).
    pub time: f64,
    /// Vertex positions (m).
    pub positions: &'a [Pt3],
    /// Triangles (the same for every frame of a sequence).
    pub faces: &'a [[u32; 3]],
    /// Optional per-vertex attributes.
    pub attributes: &'a [Attribute<'a>],
}

/// One frame of a point set (particles).
#[derive(Clone, Copy, Debug)]
pub struct PointFrame<'a> {
    /// The sequence it belongs to.
    pub sequence: &'a str,
    /// Frame number within the sequence.
    pub index: usize,
    /// Simulation time (s).
    pub time: f64,
    /// Point positions (m).
    pub positions: &'a [Pt3],
    /// Optional per-point attributes (e.g. `v`, `pscale`).
    pub attributes: &'a [Attribute<'a>],
}

/// Static geometry that gives a sequence its context (an obstacle, the floor, a guide at rest):
/// written once, drawn in previews.
#[derive(Clone, Debug, PartialEq)]
pub enum SceneItem {
    /// A triangle mesh (m), placed at `time`-independent positions.
    Mesh {
        /// Name (`"obstacle-0"` …).
        name: String,
        /// Vertices (m).
        positions: Vec<Pt3>,
        /// Triangles.
        faces: Vec<[u32; 3]>,
    },
    /// A horizontal ground plane at height `y` (m).
    Ground {
        /// Height (m).
        y: f64,
    },
    /// Vertices of a sequence that are prescribed (pinned or kinematic).
    Pinned {
        /// The sequence.
        sequence: String,
        /// Vertex indices.
        vertices: Vec<u32>,
    },
    /// The frame rate of the written sequences (frames per second).
    FrameRate {
        /// Frames per second.
        fps: f64,
    },
}

/// A plot series: `(x, y)` points of one named curve of one named plot.
#[derive(Clone, Debug, PartialEq)]
pub struct Series {
    /// The plot this curve belongs to (one PNG per plot, e.g. `"energy"`).
    pub plot: String,
    /// The curve's legend label.
    pub label: String,
    /// Axis labels with units, `(x, y)`.
    pub axes: (String, String),
    /// Logarithmic axes, `(x, y)`.
    pub log: (bool, bool),
    /// The points.
    pub points: Vec<(f64, f64)>,
}

/// Receives an experiment's outputs as they are computed.
///
/// Every method returns `Err` only when the output cannot be written (a full disk, a closed
/// pipe); experiments pass that error up, so a run stops instead of losing results silently.
pub trait Recorder {
    /// A frame of an animated mesh, written at once.
    fn frame(&mut self, f: &MeshFrame) -> Result<()>;
    /// A frame of a point set, written at once.
    fn points(&mut self, f: &PointFrame) -> Result<()>;
    /// Context geometry (obstacles, floor, pins, frame rate), given once before the frames.
    fn scene(&mut self, item: &SceneItem) -> Result<()>;
    /// Declares a table and its header (must come before its rows).
    fn table(&mut self, name: &str, header: &[&str]) -> Result<()>;
    /// Appends a row to a declared table; the cell count must match the header.
    fn row(&mut self, table: &str, cells: &[Cell]) -> Result<()>;
    /// A plot series (curves of one `plot` are drawn together).
    fn series(&mut self, s: &Series) -> Result<()>;
    /// A line of text for the run's report.
    fn note(&mut self, text: &str) -> Result<()>;
    /// An artefact file (`motion.bvh`, `walk.glb`, an image …) under the run's folder.
    fn file(&mut self, name: &str, bytes: &[u8]) -> Result<()>;
    /// Progress of the run's main loop (`done` of `total` units); default: ignored.
    fn progress(&mut self, _done: u64, _total: u64) {}
    /// False when outputs are discarded, so an experiment may skip work done only to record
    /// (e.g. formatting frames); figures must not depend on it.
    fn keeps_outputs(&self) -> bool {
        true
    }
}

/// Drops every output (tests, benchmarks). Tables are still checked for width, so a malformed
/// row fails the same way with every recorder.
#[derive(Debug, Default)]
pub struct NullRecorder {
    widths: BTreeMap<String, usize>,
}

fn check_row(widths: &BTreeMap<String, usize>, table: &str, cells: &[Cell]) -> Result<()> {
    match widths.get(table) {
        None => Err(Error::InvalidParameter(format!("row for undeclared table '{table}'"))),
        Some(&w) if w != cells.len() => {
            Err(Error::InvalidParameter(format!("table '{table}': row has {} cells, header has {w}", cells.len())))
        }
        Some(_) => Ok(()),
    }
}

impl Recorder for NullRecorder {
    fn frame(&mut self, _f: &MeshFrame) -> Result<()> {
        Ok(())
    }
    fn points(&mut self, _f: &PointFrame) -> Result<()> {
        Ok(())
    }
    fn scene(&mut self, _item: &SceneItem) -> Result<()> {
        Ok(())
    }
    fn table(&mut self, name: &str, header: &[&str]) -> Result<()> {
        self.widths.insert(name.to_string(), header.len());
        Ok(())
    }
    fn row(&mut self, table: &str, cells: &[Cell]) -> Result<()> {
        check_row(&self.widths, table, cells)
    }
    fn series(&mut self, _s: &Series) -> Result<()> {
        Ok(())
    }
    fn note(&mut self, _text: &str) -> Result<()> {
        Ok(())
    }
    fn file(&mut self, _name: &str, _bytes: &[u8]) -> Result<()> {
        Ok(())
    }
    fn keeps_outputs(&self) -> bool {
        false
    }
}

/// A recorded table.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Table {
    /// Column names.
    pub header: Vec<String>,
    /// Rows, in order.
    pub rows: Vec<Vec<Cell>>,
}

/// Keeps every output in memory (tests that inspect frames or tables).
#[derive(Clone, Debug, Default)]
pub struct MemoryRecorder {
    /// Frames per sequence: `(index, time, positions)`; faces of the last frame per sequence.
    pub frames: BTreeMap<String, Vec<(usize, f64, Vec<Pt3>)>>,
    /// Faces per mesh sequence.
    pub faces: BTreeMap<String, Vec<[u32; 3]>>,
    /// Point frames per sequence: `(index, time, positions)`.
    pub points: BTreeMap<String, Vec<(usize, f64, Vec<Pt3>)>>,
    /// Context items.
    pub scene: Vec<SceneItem>,
    /// Tables by name.
    pub tables: BTreeMap<String, Table>,
    /// Plot series, in order.
    pub series: Vec<Series>,
    /// Notes, in order.
    pub notes: Vec<String>,
    /// Artefact files by name.
    pub files: BTreeMap<String, Vec<u8>>,
}

impl Recorder for MemoryRecorder {
    fn frame(&mut self, f: &MeshFrame) -> Result<()> {
        self.frames.entry(f.sequence.to_string()).or_default().push((f.index, f.time, f.positions.to_vec()));
        self.faces.insert(f.sequence.to_string(), f.faces.to_vec());
        Ok(())
    }
    fn points(&mut self, f: &PointFrame) -> Result<()> {
        self.points.entry(f.sequence.to_string()).or_default().push((f.index, f.time, f.positions.to_vec()));
        Ok(())
    }
    fn scene(&mut self, item: &SceneItem) -> Result<()> {
        self.scene.push(item.clone());
        Ok(())
    }
    fn table(&mut self, name: &str, header: &[&str]) -> Result<()> {
        self.tables.insert(
            name.to_string(),
            Table { header: header.iter().map(|s| s.to_string()).collect(), rows: Vec::new() },
        );
        Ok(())
    }
    fn row(&mut self, table: &str, cells: &[Cell]) -> Result<()> {
        let widths: BTreeMap<String, usize> = self.tables.iter().map(|(k, t)| (k.clone(), t.header.len())).collect();
        check_row(&widths, table, cells)?;
        if let Some(t) = self.tables.get_mut(table) {
            t.rows.push(cells.to_vec());
        }
        Ok(())
    }
    fn series(&mut self, s: &Series) -> Result<()> {
        self.series.push(s.clone());
        Ok(())
    }
    fn note(&mut self, text: &str) -> Result<()> {
        self.notes.push(text.to_string());
        Ok(())
    }
    fn file(&mut self, name: &str, bytes: &[u8]) -> Result<()> {
        self.files.insert(name.to_string(), bytes.to_vec());
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rows_are_checked_against_their_header() {
        for rec in [&mut NullRecorder::default() as &mut dyn Recorder, &mut MemoryRecorder::default()] {
            assert!(rec.row("t", &[Cell::from(1.0)]).is_err(), "undeclared table");
            rec.table("t", &["a", "b"]).unwrap();
            assert!(rec.row("t", &[Cell::from(1.0)]).is_err(), "short row");
            rec.row("t", &[Cell::from(1.0), Cell::from("x")]).unwrap();
        }
    }

    #[test]
    fn memory_recorder_keeps_frames_in_order() {
        let mut rec = MemoryRecorder::default();
        let p = [Pt3::origin(), Pt3::new(1.0, 0.0, 0.0), Pt3::new(0.0, 1.0, 0.0)];
        for i in 0..3 {
            let f = MeshFrame {
                sequence: "frames",
                index: i,
                time: i as f64 * 0.1,
                positions: &p,
                faces: &[[0, 1, 2]],
                attributes: &[],
            };
            rec.frame(&f).unwrap();
        }
        assert_eq!(rec.frames["frames"].len(), 3);
        assert_eq!(rec.frames["frames"][2].0, 2);
        assert!(rec.keeps_outputs());
        assert!(!NullRecorder::default().keeps_outputs());
    }
}

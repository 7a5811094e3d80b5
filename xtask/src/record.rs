//! The file-writing [`Recorder`]: where a method crate's experiment outputs land in a run's
//! folder, and the one adapter ([`run_experiment`]) that loads a scene's parameters, calls the
//! experiment and turns its [`Report`] into `summary.json` and `checks.json`.
//!
//! Layout inside the run folder: mesh frames `<sequence>/NNNN.obj` and point frames
//! `<sequence>/NNNN.ply`, written the moment they are recorded; tables `<name>.csv` (flushed per
//! row); plots `<plot>.png` (drawn when the run finishes, from every series of that plot); notes
//! `report.md`; artefacts under their own names.

// The adapters of the method crates move onto `run_experiment` crate by crate (issue 21); until
// the last one has, parts of this module are unused.
#![allow(dead_code)]

use std::collections::BTreeMap;
use std::fs;
use std::io::Write;
use std::path::{Path, PathBuf};

use geom_core::experiment::{Report, Size, Value};
use geom_core::io::{obj, ply, MeshOut, Positions};
use geom_core::record::{Cell as RCell, MeshFrame, PointFrame, Recorder, SceneItem, Series as RSeries};
use serde::de::DeserializeOwned;

use crate::error::{io_err, Error, Result};
use crate::out::{ensure_dir, Cell, CsvWriter, Summary};
use crate::plot::{LinePlot, Series};
use crate::registry::RunCtx;
use crate::scene;

/// Writes an experiment's outputs into a run folder as they arrive.
pub struct FileRecorder {
    dir: PathBuf,
    tables: BTreeMap<String, CsvWriter>,
    plots: BTreeMap<String, LinePlot>,
    notes: Option<fs::File>,
    /// Context items (obstacles, floor, pins, frame rate), kept for previews.
    pub scene: Vec<SceneItem>,
    /// Mesh frames written per sequence (count).
    pub frames_written: BTreeMap<String, usize>,
}

fn core_io(path: &Path) -> impl FnOnce(std::io::Error) -> geom_core::Error + '_ {
    move |e| geom_core::Error::Io(std::io::Error::new(e.kind(), format!("{}: {e}", path.display())))
}

fn to_core(e: Error) -> geom_core::Error {
    match e {
        Error::Core(c) => c,
        Error::Io { path, source } => {
            geom_core::Error::Io(std::io::Error::new(source.kind(), format!("{}: {source}", path.display())))
        }
        other => geom_core::Error::InvalidParameter(other.to_string()),
    }
}

impl FileRecorder {
    /// A recorder writing into `dir` (created if needed).
    pub fn new(dir: &Path) -> Result<Self> {
        ensure_dir(dir)?;
        Ok(Self {
            dir: dir.to_path_buf(),
            tables: BTreeMap::new(),
            plots: BTreeMap::new(),
            notes: None,
            scene: Vec::new(),
            frames_written: BTreeMap::new(),
        })
    }

    /// The run folder.
    pub fn dir(&self) -> &Path {
        &self.dir
    }

    /// Draws the plots (one PNG per plot name) and keeps the scene items in `scene.json` (for
    /// previews and reports rebuilt later). Call once when the experiment returns.
    pub fn finish(&mut self) -> Result<()> {
        for (name, p) in &self.plots {
            p.write_png(&self.dir.join(format!("{name}.png")))?;
        }
        crate::scene_items::write(&self.dir, &self.scene)
    }
}

impl Recorder for FileRecorder {
    fn frame(&mut self, f: &MeshFrame) -> geom_core::Result<()> {
        let dir = self.dir.join(f.sequence);
        fs::create_dir_all(&dir).map_err(core_io(&dir))?;
        obj::write(geom_core::io::frame_path(&dir, f.index), &MeshOut::tri(f.positions, f.faces))?;
        *self.frames_written.entry(f.sequence.to_string()).or_default() += 1;
        Ok(())
    }

    fn points(&mut self, f: &PointFrame) -> geom_core::Result<()> {
        let dir = self.dir.join(f.sequence);
        fs::create_dir_all(&dir).map_err(core_io(&dir))?;
        let props: Vec<(&str, ply::PlyData)> =
            f.attributes.iter().map(|a| (a.name, ply::PlyData::F64(a.values))).collect();
        let path = dir.join(format!("{:04}.ply", f.index));
        ply::write_points(&path, Positions::F64(f.positions), &props, ply::Encoding::BinaryLittleEndian)
    }

    fn scene(&mut self, item: &SceneItem) -> geom_core::Result<()> {
        self.scene.push(item.clone());
        Ok(())
    }

    fn table(&mut self, name: &str, header: &[&str]) -> geom_core::Result<()> {
        let w = CsvWriter::create(&self.dir.join(format!("{name}.csv")), header).map_err(to_core)?;
        self.tables.insert(name.to_string(), w);
        Ok(())
    }

    fn row(&mut self, table: &str, cells: &[RCell]) -> geom_core::Result<()> {
        let w = self
            .tables
            .get_mut(table)
            .ok_or_else(|| geom_core::Error::InvalidParameter(format!("row for undeclared table '{table}'")))?;
        let cells: Vec<Cell> = cells
            .iter()
            .map(|c| match c {
                RCell::Num(v) => Cell::Num(*v),
                RCell::Int(v) => Cell::Int(*v),
                RCell::Bool(b) => Cell::Int(*b as i64),
                RCell::Text(s) => Cell::Text(s.clone()),
            })
            .collect();
        w.row(&cells).map_err(to_core)
    }

    fn series(&mut self, s: &RSeries) -> geom_core::Result<()> {
        let p = self
            .plots
            .entry(s.plot.clone())
            .or_insert_with(|| LinePlot::new(&s.plot, &s.axes.0, &s.axes.1).log(s.log.0, s.log.1));
        p.series.push(Series::new(s.label.clone(), s.points.clone()));
        Ok(())
    }

    fn note(&mut self, text: &str) -> geom_core::Result<()> {
        let path = self.dir.join("report.md");
        if self.notes.is_none() {
            self.notes = Some(fs::File::create(&path).map_err(core_io(&path))?);
        }
        let f = self.notes.as_mut().expect("opened just above");
        writeln!(f, "{text}").map_err(core_io(&path))
    }

    fn progress(&mut self, done: u64, total: u64) {
        crate::ui::progress(done, total);
    }

    fn file(&mut self, name: &str, bytes: &[u8]) -> geom_core::Result<()> {
        let path = self.dir.join(name);
        if let Some(parent) = path.parent() {
            fs::create_dir_all(parent).map_err(core_io(parent))?;
        }
        fs::write(&path, bytes).map_err(core_io(&path))
    }
}

impl Summary {
    /// The figures of an experiment's report as a summary (NaN → `null`, flags → true/false).
    pub fn from_report(r: &Report) -> Summary {
        let mut s = Summary::new();
        for (k, v) in &r.figures {
            match v {
                Value::Num(x) => s.set(k, *x),
                Value::Int(i) => s.set_int(k, *i),
                Value::Bool(b) => s.set_bool(k, *b),
                Value::Text(t) => s.set_str(k, t),
            };
        }
        s
    }
}

/// Writes `checks.json`: every paper check of the report (key, target, value, pass, source).
pub fn write_checks(dir: &Path, r: &Report) -> Result<()> {
    let path = dir.join("checks.json");
    let text = serde_json::to_string_pretty(&r.checks).map_err(|e| Error::Run(e.to_string()))?;
    fs::write(&path, text + "\n").map_err(io_err(&path))
}

/// The file listing the figures of `summary.json` that measure time ([`Report::timing`]: wall
/// times, rates, speed-ups, thread counts): what may differ between two runs of the same
/// parameters; every other figure is bitwise reproducible. `sweep collect` and the comparisons
/// of CI read it.
pub const TIMING_JSON: &str = "timing.json";

/// Writes `timing.json`: the keys the report marked as timing, plus the runner's own `wall_s`
/// and `preview_s`.
pub fn write_timing(dir: &Path, r: &Report) -> Result<()> {
    let mut keys: Vec<&str> = r.timing.iter().map(String::as_str).collect();
    keys.extend(["wall_s", "preview_s"]);
    keys.sort_unstable();
    keys.dedup();
    let path = dir.join(TIMING_JSON);
    let text = serde_json::to_string_pretty(&keys).map_err(|e| Error::Run(e.to_string()))?;
    fs::write(&path, text + "\n").map_err(io_err(&path))
}

/// The one adapter between a scene file and a crate's experiment: loads the `params` block as
/// `P`, runs `f` at the run's size with a [`FileRecorder`] in the run folder, draws the plots,
/// writes `checks.json` and `timing.json`, and returns the figures for `summary.json`.
pub fn run_experiment<P, E>(
    ctx: &RunCtx,
    f: impl FnOnce(&P, Size, &mut dyn Recorder) -> std::result::Result<Report, E>,
) -> Result<Summary>
where
    P: DeserializeOwned,
    Error: From<E>,
{
    let sc = scene::load::<P>(&ctx.scene_file)?;
    let mut rec = FileRecorder::new(&ctx.out_dir)?;
    let report = f(&sc.params, ctx.mode.size(), &mut rec);
    // The scene items and plots of a failed run are kept too (the frames already are).
    rec.finish()?;
    let report = report?;
    write_checks(&ctx.out_dir, &report)?;
    write_timing(&ctx.out_dir, &report)?;
    Ok(Summary::from_report(&report))
}

#[cfg(test)]
mod tests {
    use super::*;
    use geom_core::experiment::Target;
    use geom_core::math::Pt3;

    #[test]
    fn file_recorder_writes_frames_tables_plots_and_notes() {
        let dir = std::env::temp_dir().join(format!("xtask-rec-{}", std::process::id()));
        let _ = fs::remove_dir_all(&dir);
        let mut rec = FileRecorder::new(&dir).unwrap();
        let p = [Pt3::origin(), Pt3::new(1.0, 0.0, 0.0), Pt3::new(0.0, 1.0, 0.0)];
        let f =
            MeshFrame { sequence: "frames", index: 3, time: 0.1, positions: &p, faces: &[[0, 1, 2]], attributes: &[] };
        rec.frame(&f).unwrap();
        assert!(dir.join("frames/0003.obj").is_file(), "frame written at once");
        rec.table("steps", &["t", "e"]).unwrap();
        rec.row("steps", &[RCell::from(0.5), RCell::from(true)]).unwrap();
        assert!(rec.row("steps", &[RCell::from(0.5)]).is_err());
        assert!(rec.row("nope", &[]).is_err());
        rec.series(&RSeries {
            plot: "energy".into(),
            label: "E".into(),
            axes: ("t (s)".into(), "E (J)".into()),
            log: (false, false),
            points: vec![(0.0, 1.0), (1.0, 2.0)],
        })
        .unwrap();
        rec.note("hello").unwrap();
        rec.file("sub/a.bin", b"xy").unwrap();
        rec.finish().unwrap();
        assert_eq!(fs::read_to_string(dir.join("steps.csv")).unwrap(), "t,e\n0.5,1\n");
        assert!(dir.join("energy.png").is_file());
        assert_eq!(fs::read_to_string(dir.join("report.md")).unwrap(), "hello\n");
        assert_eq!(fs::read(dir.join("sub/a.bin")).unwrap(), b"xy");
        let mut r = Report::default();
        r.num("x", f64::NAN).flag("ok", true).count("n", 2).text("cfg", "a");
        r.check("x", Target::AtMost(1.0), "t");
        let s = Summary::from_report(&r);
        assert!(s.get("x").is_none(), "NaN is null");
        assert_eq!(s.get("n"), Some(2.0));
        write_checks(&dir, &r).unwrap();
        let checks = fs::read_to_string(dir.join("checks.json")).unwrap();
        assert!(checks.contains("\"pass\": false"), "{checks}");
        fs::remove_dir_all(&dir).unwrap();
    }
}

//! C4 `cloth-fit/errormap` (Bhat et al. 2003 §4.2, Fig. 3; spec §6 C4): "we compared the angle
//! map from one frame in video with several angle maps in simulation ... the error space is
//! fairly noisy, with many local minima, motivating the need for a global optimization
//! technique." E over a log-spaced (bend, stretch) grid centred on the truth, every other
//! parameter at the truth, against mismatched footage of the static test.
//!
//! ```no_run
//! # fn demo(p: &cloth_fit::experiments::errormap::Params) -> cloth_fit::Result<()> {
//! use cloth_fit::experiments::errormap::run;
//! use geom_core::experiment::Size;
//! use geom_core::record::NullRecorder;
//! let report = run(p, Size::Quick, &mut NullRecorder::default())?;
//! println!("{:?}", report.get("local_minima"));
//! # Ok(()) }
//! ```

use geom_core::experiment::{BySize, Report, Size, Target};
use geom_core::image::ImageF32;
use geom_core::record::{Cell, Recorder, Series};
use geom_core::stats::{max, min};
use serde::{Deserialize, Serialize};

use super::common::{space, truths, FitScale};
use super::static_test::static_truth;
use crate::error::Result;
use crate::forward::ShellsForward;
use crate::metrics::local_minima;
use crate::objective::{EvalStatus, Objective};
use crate::params::ParamId;
use crate::presets::{static_trial, FabricPreset};
use crate::synthetic::Condition;

/// Scene parameters (the RON `params` block).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Params {
    /// The fabric.
    pub fabric: FabricPreset,
    /// Grid points per axis (odd, so the truth is the centre).
    pub n: BySize<usize>,
    /// Half-width of the grid in decades of each parameter (log10).
    pub decades: f64,
    /// Frames of the static trial.
    pub frames: BySize<usize>,
    /// Synthetic condition (the spec: mismatched).
    pub condition: BySize<Condition>,
    /// Fit-side scale.
    pub fit: FitScale,
}

/// Runs C4.
pub fn run(p: &Params, size: Size, rec: &mut dyn Recorder) -> Result<Report> {
    let setup = p.fit.setup(size)?;
    let fwd = ShellsForward;
    let f = p.fabric;
    let truth = static_truth(f);
    let cond = p.condition.get(size);
    let n = p.n.get(size).max(3) | 1;
    let tr = truths(&fwd, &[static_trial(f, 0, p.frames.get(size).max(1))], truth, &setup, cond, p.fit.noise)?;
    let targets = [tr[0].target.clone()];
    let sp = space(&[ParamId::Bend, ParamId::Stretch], truth)?;
    let obj = Objective::new(&targets, &fwd, &sp, &setup)?;
    let c = (n / 2) as f64;
    let factor = |k: usize| 10f64.powf(p.decades * (k as f64 - c) / c);
    let mut pts = Vec::with_capacity(n * n);
    for i in 0..n {
        for j in 0..n {
            pts.push(
                truth.with(ParamId::Bend, truth.bend * factor(i)).with(ParamId::Stretch, truth.stretch * factor(j)),
            );
        }
    }
    rec.note(&format!(
        "# C4 error map\n\n{}, {n} × {n} grid over bend × stretch, ±{} decades around the truth, {}",
        f.name(),
        p.decades,
        cond.name()
    ))?;
    let recs = obj.eval_params(&pts);
    rec.progress(1, 1);
    rec.table("errormap", &["i_bend", "j_stretch", "bend", "stretch", "error", "status"])?;
    let mut grid = vec![vec![f64::NAN; n]; n];
    for (k, r) in recs.iter().enumerate() {
        let (i, j) = (k / n, k % n);
        grid[i][j] = r.error;
        rec.row(
            "errormap",
            &[
                Cell::from(i),
                Cell::from(j),
                Cell::from(r.params.bend),
                Cell::from(r.params.stretch),
                Cell::from(r.error),
                Cell::from(if r.status == EvalStatus::Ok { "ok" } else { "failed" }),
            ],
        )?;
    }
    // Image: log E, darker = lower, rows = bend (top = smallest), columns = stretch.
    let flat: Vec<f64> = grid.iter().flatten().map(|v| v.max(1e-12).ln()).collect();
    let (lo, hi) = (min(&flat), max(&flat));
    let scale = 8u32;
    let mut img = ImageF32::new(n as u32 * scale, n as u32 * scale, 0.0);
    for i in 0..n {
        for j in 0..n {
            let v = if hi > lo { ((flat[i * n + j] - lo) / (hi - lo)) as f32 } else { 0.0 };
            for y in 0..scale {
                for x in 0..scale {
                    img.set(j as u32 * scale + x, i as u32 * scale + y, v);
                }
            }
        }
    }
    rec.file("errormap.png", &crate::png_bytes::gray8(&img))?;
    let row = &grid[n / 2];
    rec.series(&Series {
        plot: "errormap_slices".into(),
        label: "E along stretch (bend at truth)".into(),
        axes: ("stretch / truth".into(), "E".into()),
        log: (true, false),
        points: (0..n).map(|j| (factor(j), row[j])).collect(),
    })?;
    rec.series(&Series {
        plot: "errormap_slices".into(),
        label: "E along bend (stretch at truth)".into(),
        axes: ("parameter / truth".into(), "E".into()),
        log: (true, false),
        points: (0..n).map(|i| (factor(i), grid[i][n / 2])).collect(),
    })?;
    let minima = local_minima(&grid);
    let (mut bi, mut bj, mut bv) = (0, 0, f64::INFINITY);
    for (i, row) in grid.iter().enumerate() {
        for (j, &v) in row.iter().enumerate() {
            if v < bv {
                (bi, bj, bv) = (i, j, v);
            }
        }
    }
    let off = (bi as i64 - (n / 2) as i64).abs().max((bj as i64 - (n / 2) as i64).abs());
    let mut r = Report::default();
    r.count("local_minima", minima.len() as u64);
    r.count("global_min_offset_cells", off as u64);
    r.flag("global_min_within_one_cell", off <= 1);
    r.num("global_min_bend_ratio", factor(bi));
    r.num("global_min_stretch_ratio", factor(bj));
    r.num("e_at_truth", grid[n / 2][n / 2]);
    r.num("e_min", bv);
    r.count("grid_n", n as u64);
    r.check(
        "global_min_within_one_cell",
        Target::IsTrue,
        "spec §6 C4: the global minimum within one grid cell of the truth",
    );
    Ok(r)
}

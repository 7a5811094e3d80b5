//! C5 `cloth-fit/confusion` (Bhat et al. 2003 §6, Figs. 12–14; spec §6 C5): "We compare each
//! of the four optimized angle maps from simulation (corresponding to the four fabrics) with the
//! four angle maps computed from video. We see that each fabric in simulation has a minimum
//! error when compared to its counterpart in reality." Rows are footage (waving trial 1,
//! mismatched truth with noise), columns are parameter sets: each fabric's true parameters
//! (default) or its fitted ones (`--full`: one waving fit per fabric).
//!
//! ```no_run
//! # fn demo(p: &cloth_fit::experiments::confusion::Params) -> cloth_fit::Result<()> {
//! use cloth_fit::experiments::confusion::run;
//! use geom_core::experiment::Size;
//! use geom_core::record::NullRecorder;
//! let report = run(p, Size::Quick, &mut NullRecorder::default())?;
//! println!("{:?}", report.get("diagonal_minimal_rows"));
//! # Ok(()) }
//! ```

use geom_core::experiment::{BySize, Report, Size, Target};
use geom_core::image::ImageF32;
use geom_core::record::{Cell, Recorder};
use serde::{Deserialize, Serialize};

use super::common::{space, truths, FitScale, SearchScale};
use crate::error::Result;
use crate::fit::{fit, DynamicInit, TrialPolicy};
use crate::forward::ShellsForward;
use crate::metrics::diagonal_minimal_rows;
use crate::objective::Objective;
use crate::params::{FabricParams, ParamId};
use crate::presets::{waving_trial, FabricPreset};
use crate::synthetic::Condition;

/// Which parameter set each column uses.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum Columns {
    /// The true parameters of each fabric (under the mismatched model and noise).
    #[default]
    Truth,
    /// Parameters fitted by the waving protocol on each fabric's footage.
    Fitted,
}

/// Scene parameters (the RON `params` block).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Params {
    /// The fabrics (rows and columns).
    pub fabrics: Vec<FabricPreset>,
    /// Parameter source of the columns.
    pub columns: BySize<Columns>,
    /// Frames of waving trial 1.
    pub frames: BySize<usize>,
    /// Synthetic condition of the footage.
    pub condition: BySize<Condition>,
    /// Seed of the random dynamic start (fitted columns).
    pub dynamic_seed: u64,
    /// Fit-side scale.
    pub fit: FitScale,
    /// Search budgets (fitted columns).
    pub search: SearchScale,
}

/// Runs C5.
pub fn run(p: &Params, size: Size, rec: &mut dyn Recorder) -> Result<Report> {
    let setup = p.fit.setup(size)?;
    let fwd = ShellsForward;
    let cond = p.condition.get(size);
    let frames = p.frames.get(size).max(2);
    let cols = p.columns.get(size);
    let n = p.fabrics.len();
    rec.note(&format!(
        "# C5 cross-comparison\n\n{n} × {n}, waving trial 1, {frames} frames, {}, columns {:?}",
        cond.name(),
        cols
    ))?;
    let mut footage = Vec::with_capacity(n);
    for &f in &p.fabrics {
        let t = truths(&fwd, &[waving_trial(f, 0, frames)], f.params(), &setup, cond, p.fit.noise)?;
        footage.push(t.into_iter().next().expect("one experiment, one truth"));
    }
    let params: Vec<FabricParams> = match cols {
        Columns::Truth => p.fabrics.iter().map(|f| f.params()).collect(),
        Columns::Fitted => {
            let mut v = Vec::with_capacity(n);
            for (k, &f) in p.fabrics.iter().enumerate() {
                let sp = space(&ParamId::ALL, f.params())?;
                let o = p.search.options(
                    size,
                    DynamicInit::Random { seed: p.dynamic_seed },
                    TrialPolicy::PerTrialThenSelect,
                    false,
                );
                let fr = fit(std::slice::from_ref(&footage[k].target), &fwd, &sp, &setup, &o, &mut |d, t| {
                    rec.progress(d, t)
                })?;
                v.push(fr.params);
            }
            v
        }
    };
    let mut m = vec![vec![0.0; n]; n];
    for (i, ft) in footage.iter().enumerate() {
        let sp = space(&ParamId::ALL, p.fabrics[i].params())?;
        let obj = Objective::new(std::slice::from_ref(&ft.target), &fwd, &sp, &setup)?;
        for (j, r) in obj.eval_params(&params).into_iter().enumerate() {
            m[i][j] = r.error;
        }
        rec.progress((i + 1) as u64, n as u64);
    }
    let mut head = vec!["footage".to_string()];
    head.extend(p.fabrics.iter().map(|f| format!("params_{}", f.name())));
    rec.table("confusion", &head.iter().map(String::as_str).collect::<Vec<_>>())?;
    let mut r = Report::default();
    for (i, row) in m.iter().enumerate() {
        let mut cells = vec![Cell::from(p.fabrics[i].name())];
        cells.extend(row.iter().map(|&v| Cell::from(v)));
        rec.row("confusion", &cells)?;
        for (j, &v) in row.iter().enumerate() {
            r.num(&format!("e_{}_{}", p.fabrics[i].name(), p.fabrics[j].name()), v);
        }
    }
    // Row-normalised image (each row divided by its maximum; darker = lower).
    let cell = 24u32;
    let mut img = ImageF32::new(n as u32 * cell, n as u32 * cell, 1.0);
    for (i, row) in m.iter().enumerate() {
        let mx = geom_core::stats::max(row);
        for (j, &v) in row.iter().enumerate() {
            let g = if mx > 0.0 { (v / mx) as f32 } else { 0.0 };
            for y in 1..cell - 1 {
                for x in 1..cell - 1 {
                    img.set(j as u32 * cell + x, i as u32 * cell + y, g);
                }
            }
        }
    }
    rec.file("confusion.png", &crate::png_bytes::gray8(&img))?;
    r.count("diagonal_minimal_rows", diagonal_minimal_rows(&m) as u64);
    r.count("fabrics", n as u64);
    r.check(
        "diagonal_minimal_rows",
        Target::Equals(n as f64),
        "paper §6 / spec §5: each fabric matches its own footage best",
    );
    Ok(r)
}

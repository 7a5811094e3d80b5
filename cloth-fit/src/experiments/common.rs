//! What the scenes share: the fit-side scale (image, model, renderer, filters) per run size,
//! search budgets, synthetic truths for a fabric, summary keys per fabric, history tables and
//! the truth-versus-fit strips.

use geom_core::experiment::{BySize, Report, Size};
use geom_core::image::ImageF32;
use geom_core::record::{Cell, Recorder};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::angle::AngleOptions;
use crate::anneal::AnnealOptions;
use crate::coarse::CoarseSearch;
use crate::error::Result;
use crate::fit::{DynamicInit, FitOptions, TrialPolicy};
use crate::fold_error::MetricOptions;
use crate::forward::{ForwardModel, Integrator, SimOptions};
use crate::noise::NoiseModel;
use crate::objective::{EvalRecord, EvalSetup, EvalStatus};
use crate::params::{FabricParams, ParamId, ParamSpace};
use crate::presets::{default_ranges, rig_spec, FabricPreset};
use crate::render::{render_intensity, RenderOptions};
use crate::setup::Experiment;
use crate::synthetic::{synthesize, Condition, SyntheticSource, TruthSequence};
use crate::variability::VariabilityOptions;

/// The fitting side of a scene per run size: image, model resolution and step, renderer,
/// filters, metric (spec §4.2–§4.5).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FitScale {
    /// Image size (px).
    pub image: BySize<(u32, u32)>,
    /// Quads per side of the fitting mesh.
    pub res: BySize<usize>,
    /// Time step of the fitting model (s).
    pub dt: BySize<f64>,
    /// Integrator of the fitting model.
    #[serde(default)]
    pub integrator: Integrator,
    /// Renderer (fit side).
    #[serde(default)]
    pub render: RenderOptions,
    /// Angle maps. `grad_threshold` is given for a 320-pixel-wide image and scaled by
    /// 320/width: a fold's change of angle per pixel grows as the pixels get larger.
    #[serde(default)]
    pub angle: AngleOptions,
    /// Frame error.
    #[serde(default)]
    pub metric: MetricOptions,
    /// Degradation of mismatched truths.
    #[serde(default)]
    pub noise: NoiseModel,
}

impl FitScale {
    /// The evaluation setup at `size`; the rig check (stripes ≥ 5 px) runs here.
    pub fn setup(&self, size: Size) -> Result<EvalSetup> {
        let (w, h) = self.image.get(size);
        let rig = rig_spec(w, h).build()?.rig;
        rig.check(&geom_core::math::Pt3::new(0.0, 0.0, -0.2), &geom_core::math::Vec3::y(), false)?;
        let model = SimOptions {
            res: self.res.get(size),
            dt: self.dt.get(size),
            integrator: self.integrator,
            collisions: Default::default(),
            render_subdivision: 0,
            implicit_drag: false,
        };
        model.validate()?;
        let angle = AngleOptions { grad_threshold: self.angle.grad_threshold * 320.0 / w as f64, ..self.angle };
        angle.validate()?;
        self.noise.validate()?;
        Ok(EvalSetup { rig, model, render: self.render, angle, metric: self.metric })
    }
}

/// Search budgets per run size.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SearchScale {
    /// Grid values per stiffness parameter (the paper: 4).
    pub coarse_values: BySize<usize>,
    /// Annealing evaluations per trial (the paper: ≈ 600).
    pub anneal_evals: BySize<usize>,
    /// Variability samples per parameter (spec: 9).
    pub variability_samples: BySize<usize>,
    /// Other annealing settings per run size (budget replaced by `anneal_evals`).
    #[serde(default = "default_anneal")]
    pub anneal: BySize<AnnealOptions>,
}

fn default_anneal() -> BySize<AnnealOptions> {
    BySize::Same(AnnealOptions::default())
}

impl SearchScale {
    /// The fit options at `size` with `dynamic_init` for the non-gridded parameters.
    pub fn options(&self, size: Size, dynamic_init: DynamicInit, trials: TrialPolicy, variability: bool) -> FitOptions {
        FitOptions {
            coarse: CoarseSearch::Grid {
                values_per_param: self.coarse_values.get(size),
                params: ParamId::STIFFNESS.to_vec(),
            },
            dynamic_init,
            anneal: AnnealOptions { max_evals: self.anneal_evals.get(size), ..self.anneal.get(size) },
            trials,
            variability: variability
                .then(|| VariabilityOptions { samples: self.variability_samples.get(size), ..Default::default() }),
        }
    }
}

/// The parameter space over the default ranges with `free` parameters and the others at `fixed`.
pub fn space(free: &[ParamId], fixed: FabricParams) -> Result<ParamSpace> {
    ParamSpace::new(default_ranges(), free.to_vec(), fixed)
}

/// Renders the truths of `experiments` for one fabric (in parallel over experiments).
pub fn truths(
    fwd: &dyn ForwardModel,
    experiments: &[Experiment],
    truth: FabricParams,
    setup: &EvalSetup,
    condition: Condition,
    noise: NoiseModel,
) -> Result<Vec<TruthSequence>> {
    let src = SyntheticSource::new(condition, truth, setup, noise);
    experiments.par_iter().map(|e| synthesize(fwd, e, &setup.rig, &src, &setup.angle)).collect()
}

/// Sets `<key>_<fabric>`.
pub fn per_fabric(r: &mut Report, key: &str, f: FabricPreset, v: f64) {
    r.num(&format!("{key}_{}", f.name()), v);
}

/// Declares the history table (one row per objective evaluation).
pub fn history_table(rec: &mut dyn Recorder, name: &str) -> Result<()> {
    let mut h = vec!["run", "index", "t_s", "wall_s", "error", "fold", "silh", "status", "cached"];
    let names: Vec<&str> = ParamId::ALL.iter().map(|p| p.name()).collect();
    h.extend(names);
    rec.table(name, &h)?;
    Ok(())
}

/// Appends evaluation records to a history table.
pub fn history_rows(rec: &mut dyn Recorder, name: &str, run: &str, recs: &[EvalRecord]) -> Result<()> {
    for r in recs {
        let mut c = vec![
            Cell::from(run),
            Cell::from(r.index),
            Cell::from(r.t_s),
            Cell::from(r.wall_s),
            Cell::from(r.error),
            Cell::from(r.fold),
            Cell::from(r.silh),
            Cell::from(match &r.status {
                EvalStatus::Ok => "ok".to_string(),
                EvalStatus::SimFailed(m) => format!("failed: {}", m.replace(',', ";")),
            }),
            Cell::from(r.cached),
        ];
        c.extend(ParamId::ALL.iter().map(|&id| Cell::from(r.params.get(id))));
        rec.row(name, &c)?;
    }
    Ok(())
}

/// A strip of frames: truth on the top row, fit on the bottom row, `picks` frames wide, with a
/// 2-pixel white gutter; as an 8-bit PNG.
pub fn strip(truth: &[ImageF32], fit: &[ImageF32], picks: &[usize]) -> Vec<u8> {
    let Some(f0) = truth.first() else { return crate::png_bytes::gray8(&ImageF32::new(1, 1, 0.0)) };
    let (w, h) = (f0.width, f0.height);
    let g = 2;
    let cols = picks.len() as u32;
    let mut img = ImageF32::new(cols * (w + g) - g, 2 * h + g, 1.0);
    for (c, &k) in picks.iter().enumerate() {
        for (row, seq) in [truth, fit].iter().enumerate() {
            let Some(src) = seq.get(k) else { continue };
            for y in 0..h {
                for x in 0..w {
                    img.set(c as u32 * (w + g) + x, row as u32 * (h + g) + y, src.at(x, y));
                }
            }
        }
    }
    crate::png_bytes::gray8(&img)
}

/// `n` evenly spaced frame indices of a sequence of `len` frames.
pub fn picks(len: usize, n: usize) -> Vec<usize> {
    if len == 0 {
        return Vec::new();
    }
    let n = n.min(len).max(1);
    (0..n).map(|i| if n == 1 { 0 } else { i * (len - 1) / (n - 1) }).collect()
}

/// Renders the fitted parameters' frames of experiment `e` with the fit setup (clean images,
/// for the strips). A failing simulation gives black frames.
pub fn fit_images(fwd: &dyn ForwardModel, p: &FabricParams, e: &Experiment, setup: &EvalSetup) -> Vec<ImageF32> {
    let faces = fwd.faces(&setup.model);
    let (w, h) = (setup.rig.camera.width, setup.rig.camera.height);
    match fwd.simulate(p, e, &setup.rig, &setup.model) {
        Ok(s) => s.frames.par_iter().map(|q| render_intensity(q, &faces, &setup.rig, &setup.render).0).collect(),
        Err(_) => vec![ImageF32::new(w, h, 0.0); e.frames],
    }
}

/// The condition names of a list.
pub fn condition_list(c: &[Condition]) -> String {
    c.iter().map(|c| c.name()).collect::<Vec<_>>().join(",")
}

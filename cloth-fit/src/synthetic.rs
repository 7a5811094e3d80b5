//! Synthetic ground truth (spec §3.11): footage rendered from a `shells` simulation with known
//! parameters, either *matched* (exactly the fitting model, renderer and camera, no noise: the
//! identifiability test, E(p*) = 0) or *mismatched* (res 24, dt/2, BDF2, supersampling 3, a
//! perturbed camera and the noise model: the realistic case that avoids the "inverse crime").

use geom_core::image::{ImageF32, Mask};
use geom_core::math::Pt3;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::angle::{angle_map, AngleFrame, AngleOptions};
use crate::error::Result;
use crate::forward::{ForwardModel, SimOptions};
use crate::noise::{degrade, NoiseModel};
use crate::objective::{EvalSetup, Target};
use crate::params::FabricParams;
use crate::presets::truth_model;
use crate::render::{render_frame_with_camera, RenderOptions};
use crate::rig::Rig;
use crate::setup::Experiment;

/// The two synthetic conditions of spec §3.11.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum Condition {
    /// The truth uses the fitting model, no noise.
    Matched,
    /// Finer, second-order truth model, supersampling 3, camera error and noise.
    #[default]
    Mismatched,
}

impl Condition {
    /// Lower-case name.
    pub fn name(self) -> &'static str {
        match self {
            Condition::Matched => "matched",
            Condition::Mismatched => "mismatched",
        }
    }
}

/// How a synthetic truth is made.
#[derive(Clone, Debug, PartialEq)]
pub struct SyntheticSource {
    /// True parameters.
    pub truth: FabricParams,
    /// Truth forward model.
    pub model: SimOptions,
    /// Truth renderer.
    pub render: RenderOptions,
    /// Degradation (with the camera error), if any.
    pub noise: Option<NoiseModel>,
}

impl SyntheticSource {
    /// The source of `condition` for parameters `truth` against the fit `setup`. Mismatched
    /// uses the truth model of spec §3.11 scaled to the fit model (res 2×, dt/2, BDF2),
    /// supersampling 3 and `noise`.
    pub fn new(condition: Condition, truth: FabricParams, setup: &EvalSetup, noise: NoiseModel) -> Self {
        match condition {
            Condition::Matched => Self { truth, model: setup.model, render: setup.render, noise: None },
            Condition::Mismatched => Self {
                truth,
                model: SimOptions { res: 2 * setup.model.res, dt: 0.5 * setup.model.dt, ..truth_model() },
                render: RenderOptions { supersample: 3, ..setup.render },
                noise: Some(noise),
            },
        }
    }
}

/// A rendered truth sequence with everything the scenes write.
#[derive(Clone, Debug)]
pub struct TruthSequence {
    /// The preprocessed target.
    pub target: Target,
    /// Footage frames (degraded when the source has noise).
    pub images: Vec<ImageF32>,
    /// Raw silhouettes.
    pub silhouettes: Vec<Mask>,
    /// Vertex positions of the truth mesh per frame.
    pub positions: Vec<Vec<Pt3>>,
    /// Triangles of the truth mesh.
    pub faces: Vec<[u32; 3]>,
    /// Whether the truth settled within the protocol's limit.
    pub settled: bool,
}

/// Renders the truth of experiment `e` (spec §3.11). A failing truth simulation is an error
/// ([`crate::FitError::Sim`]): footage must exist before any fit.
pub fn synthesize(
    forward: &dyn ForwardModel,
    e: &Experiment,
    rig: &Rig,
    src: &SyntheticSource,
    angle: &AngleOptions,
) -> Result<TruthSequence> {
    let sim = forward.simulate(&src.truth, e, rig, &src.model)?;
    let faces = forward.faces(&src.model);
    let cam = match &src.noise {
        Some(n) => {
            n.validate()?;
            n.truth_camera(&rig.camera)
        }
        None => rig.camera.clone(),
    };
    let rendered: Vec<(ImageF32, Mask, AngleFrame)> = sim
        .frames
        .par_iter()
        .enumerate()
        .map(|(k, q)| {
            let r = render_frame_with_camera(q, &faces, rig, &cam, &src.render);
            let img = match &src.noise {
                Some(n) => degrade(&r.intensity, n, k),
                None => r.intensity,
            };
            let af = angle_map(&img, &r.silhouette, angle);
            (img, r.silhouette, af)
        })
        .collect();
    let mut images = Vec::new();
    let mut silhouettes = Vec::new();
    let mut frames = Vec::new();
    for (i, s, a) in rendered {
        images.push(i);
        silhouettes.push(s);
        frames.push(a);
    }
    Ok(TruthSequence {
        target: Target { experiment: e.clone(), frames },
        images,
        silhouettes,
        positions: sim.frames,
        faces,
        settled: sim.settled,
    })
}

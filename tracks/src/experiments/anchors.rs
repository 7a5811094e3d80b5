//! Averaged versus pointwise constraints (Bergou et al. 2007 Fig. 3 and 4): the run both
//! experiments share. The same fine shell (rubber with β = 10⁻⁴ s, no gravity) follows the guide
//! once through the hats of the subdivision basis (averaged, with its untracked twin) and once
//! through anchors at the coarse vertices (pointwise, interpolating).

use geom_core::experiment::{BySize, Size};
use geom_core::linalg::Csr;
use geom_core::math::Pt3;
use geom_core::mesh::TriMesh;
use geom_core::record::Recorder;
use serde::Deserialize;
use shells::{Damping, Effects, IntegratorSettings, ShellSceneDesc};

use super::protocol::{run_pair, track_opts, PairOpts, PairOut};
use crate::error::Result;
use crate::guide::GuideAnimation;
use crate::kkt::KktMethod;
use crate::presets::{frames_for, rubber, shell_desc, Setup};
use crate::testfn::{build_test_functions, TestFunctionSpec, TestFunctions};

/// Parameters of `tracks/fig3-band` and `tracks/fig4-sphere` (the RON `params` block).
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AnchorParams {
    /// Simulated time (s) (fig4: the fast phase is 2–3 s).
    pub duration: BySize<f64>,
    /// Steps per frame.
    pub substeps: BySize<u32>,
    /// Saddle-point solver.
    pub kkt: KktMethod,
    /// Iterative refinement steps after the LDLᵀ solve.
    pub refine_steps: u32,
    /// Record mesh frames every n frames (0 = never).
    pub obj_every: usize,
    /// fig4 only: radius of the tracked material's rest sphere over the guide's rest radius
    /// (the simulation starts at the guide's radius; absent = 1, the spec's setup).
    #[serde(default)]
    pub tracked_rest_scale: Option<f64>,
}

/// Frame rate of the band and sphere guides (fps).
pub const FPS: f64 = 30.0;

/// Runs the averaged (subdivision hats, with its untracked twin; tables and sequences tagged
/// `_averaged`) and the pointwise (anchors at the coarse vertices; `_pointwise`) variants.
/// `material_rest`: the material's rest positions when they differ from `fine` (the shell then
/// starts at `fine`, pre-stretched).
#[allow(clippy::too_many_arguments)]
pub fn averaged_vs_pointwise(
    p: &AnchorParams,
    size: Size,
    avg_guide: &GuideAnimation,
    pw_guide: &GuideAnimation,
    fine: &TriMesh,
    pm: &Csr,
    material_rest: Option<Vec<Pt3>>,
    rec: &mut dyn Recorder,
) -> Result<(PairOut, PairOut)> {
    let mut mat = rubber();
    mat.damping = Damping::Rayleigh { alpha: 0.0, beta: 1e-4 };
    let make = |tf: TestFunctions, guide: &GuideAnimation| -> Setup {
        let f2 = fine.clone();
        let mat = mat.clone();
        let material_rest = material_rest.clone();
        Setup {
            guide: guide.clone(),
            prolongation: Some(pm.clone()),
            tracked_rest: fine.clone(),
            desc: Box::new(move || {
                let d = ShellSceneDesc {
                    // The guide pumps energy into the shell: shells' blow-up guard is relative to
                    // the (tiny) initial energy, so it is widened here.
                    integrator: IntegratorSettings { divergence_energy_factor: 1e12, ..IntegratorSettings::default() },
                    ..shell_desc(&f2, mat.clone(), Effects::default())
                };
                match &material_rest {
                    Some(r) => ShellSceneDesc { rest: r.clone(), initial: Some(f2.positions.clone()), ..d },
                    None => d,
                }
            }),
            tf,
            fps: FPS,
            substeps: p.substeps.get(size),
            rest_events: None,
        }
    };
    let nb = avg_guide.n_vertices() as u32;
    let anchors: Vec<u32> = (0..nb).collect();
    let avg_tf = build_test_functions(&TestFunctionSpec::SubdivisionBasis, avg_guide, fine, Some(pm))?;
    let pw_tf = build_test_functions(
        &TestFunctionSpec::Pointwise { pairs: (0..nb).map(|j| (j, j)).collect() },
        pw_guide,
        fine,
        Some(pm),
    )?;
    let frames = frames_for(p.duration.get(size), FPS);
    let mk = |tag: &str, untracked: bool| PairOpts {
        frames,
        obj_every: p.obj_every,
        untracked,
        track: track_opts(p.kkt, p.refine_steps),
        intersections: false,
        anchors: Some(anchors.clone()),
        tag: tag.to_string(),
        subsets: Vec::new(),
    };
    let avg = run_pair(&make(avg_tf, avg_guide), &mk("_averaged", true), rec)?;
    let pw = run_pair(&make(pw_tf, pw_guide), &mk("_pointwise", false), rec)?;
    Ok((avg, pw))
}

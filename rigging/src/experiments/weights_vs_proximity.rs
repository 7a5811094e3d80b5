//! `rigging/weights-vs-proximity` (spec §6.7): arms held close to the torso; torso vertices with
//! more than half their weight on an arm bone, bone heat against nearest-bone ("proximity")
//! weights ([`crate::metrics::torso_arm_weights`]). The paper's claim: heat diffusion keeps
//! weights on the bones a vertex belongs to where proximity fails.
//!
//! Outputs: table `torso_vertices` (vertex, bone-heat arm weight, proximity arm weight).
//!
//! ```no_run
//! use geom_core::experiment::{BySize, Size};
//! use geom_core::record::NullRecorder;
//! use rigging::experiments::weights_vs_proximity::{run, Params};
//! let p = Params { seed: 1002, arm_elevation_deg: Some(-78.0), target_vertices: BySize::Same(6000), tau: 0.004 };
//! let r = run(&p, Size::Quick, &mut NullRecorder::default()).unwrap();
//! assert!(r.get_f64("torso_arm_heat") <= r.get_f64("torso_arm_proximity"));
//! ```

use geom_core::experiment::{BySize, Report, Size, Target};
use geom_core::procedural::character::HumanoidParams;
use geom_core::record::Recorder;
use serde::Deserialize;

use crate::characters::test_params;
use crate::error::Result;
use crate::metrics::torso_arm_weights;
use crate::presets::humanoid_character;
use crate::{autorig, RigOptions, SkeletonTemplate};

/// Parameters (the scene file's `params` block).
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Params {
    /// Test-character seed.
    pub seed: u64,
    /// Arm elevation override (deg; negative = down).
    #[serde(default)]
    pub arm_elevation_deg: Option<f64>,
    /// Target vertex count.
    pub target_vertices: BySize<usize>,
    /// Distance-field tolerance τ (normalized units).
    pub tau: f64,
}

/// Runs the experiment. Figures: `torso_vertices`, `torso_arm_heat`, `torso_arm_proximity`
/// (counts).
pub fn run(p: &Params, size: Size, rec: &mut dyn Recorder) -> Result<Report> {
    let nv = p.target_vertices.get(size);
    let base = test_params(p.seed);
    let hp = HumanoidParams { arm_elevation_deg: p.arm_elevation_deg.unwrap_or(base.arm_elevation_deg), ..base };
    let (mesh, truth) = humanoid_character(&hp, nv)?;
    let sk = SkeletonTemplate::human();
    let o = RigOptions { tau: p.tau, ..Default::default() };
    let rig = autorig(&mesh.positions, &mesh.faces, &sk, &[], &o)?;
    let t = torso_arm_weights(&sk, &rig.mesh.positions, &rig.weights, &truth.rest, &rig.joints);
    rec.table("torso_vertices", &["vertex", "heat_arm_weight", "proximity_arm_weight"])?;
    for &(v, h, x) in &t.rows {
        rec.row("torso_vertices", &[v.into(), h.into(), x.into()])?;
    }
    let mut r = Report::default();
    r.count("torso_vertices", t.torso_vertices as u64)
        .count("torso_arm_heat", t.heat_over_half as u64)
        .count("torso_arm_proximity", t.proximity_over_half as u64);
    let prox = t.proximity_over_half as f64;
    r.check(
        "torso_arm_heat",
        Target::AtMost(prox),
        "Baran & Popović 2007 §4.1: proximity weights attach part of the torso to an arm",
    );
    Ok(r)
}

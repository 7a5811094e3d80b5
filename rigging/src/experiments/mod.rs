//! The paper's experiments (spec §6), one module each: `pub struct Params` (the `params` block of
//! the scene file `scenes/rigging/<name>.ron`) and `pub fn run(&Params, Size, &mut dyn Recorder)
//! -> Result<Report>`. Outputs (tables, meshes, notes) go to the recorder as they are computed;
//! the report holds the figures of `summary.json` and the paper checks.
//!
//! | module | scene | what |
//! |---|---|---|
//! | [`test16`] | `rigging/test16` | the 16 held-out characters, scored; failures re-run with one hint |
//! | [`timing`] | `rigging/timing` | time per stage against vertex count (paper Table 1) |
//! | [`train`] | `rigging/train` | max-margin learning of Γ (paper §3.12) |
//! | [`animate`] | `rigging/animate` | a procedural walk on a rigged character through LBS |
//! | [`heat_two_bone`] | `rigging/heat-two-bone` | weights across one joint (paper Fig. 8) |
//! | [`odd_shapes`] | `rigging/odd-shapes` | real-world defects handled or refused; a quadruped |
//! | [`weights_vs_proximity`] | `rigging/weights-vs-proximity` | arm weight on torso vertices |

pub mod animate;
pub mod heat_two_bone;
pub mod odd_shapes;
pub mod test16;
pub mod timing;
pub mod train;
pub mod weights_vs_proximity;

use geom_core::record::Cell;

use crate::rig::StageTimings;

/// The per-stage timing columns (s) of a rig, in the order normalize, distance field, medial,
/// packing, graph, discrete, refine, attach, total.
pub(crate) fn timing_cells(t: &StageTimings) -> [Cell; 9] {
    [
        t.normalize.into(),
        t.distance_field.into(),
        t.medial.into(),
        t.packing.into(),
        t.graph.into(),
        t.discrete.into(),
        t.refine.into(),
        t.attach.into(),
        t.total().into(),
    ]
}

/// The header names of [`timing_cells`].
pub(crate) const TIMING_COLUMNS: [&str; 9] =
    ["normalize", "distance_field", "medial", "packing", "graph", "discrete", "refine", "attach", "total"];

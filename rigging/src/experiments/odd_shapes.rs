//! `rigging/odd-shapes` (spec §6.6, §8): real-world defects of a character mesh, each either
//! handled (repaired, then rigged and scored) or refused with an error naming the vertices
//! ([`crate::presets::defect_cases`]); a quadruped with the quadruped template; the too-thin
//! character ([`crate::presets::too_thin_params`]), which must fail gracefully.
//!
//! Outputs: table `cases` (case, outcome, correct embedding, message), the quadruped and its
//! embedded skeleton (`quadruped.obj`, `quadruped_skel.obj`).
//!
//! ```no_run
//! use geom_core::experiment::{BySize, Size};
//! use geom_core::record::NullRecorder;
//! use rigging::experiments::odd_shapes::{run, Params};
//! let p = Params { seed: 1001, target_vertices: BySize::Same(6000), tau: 0.004, too_thin_vertices: BySize::Same(20000) };
//! let r = run(&p, Size::Quick, &mut NullRecorder::default()).unwrap();
//! println!("{:?}", r.get("holes_outcome"));
//! ```

use geom_core::collide::MeshQuery;
use geom_core::experiment::{BySize, Report, Size, Target};
use geom_core::io::{obj, MeshOut};
use geom_core::procedural::character::humanoid;
use geom_core::record::Recorder;
use serde::Deserialize;

use crate::characters::test_params;
use crate::error::{Result, RigError};
use crate::eval::score;
use crate::export::skeleton_obj;
use crate::presets::{defect_cases, humanoid_character, quadruped_character, too_thin_params, TOO_THIN_TAU};
use crate::{autorig, RigOptions, SkeletonTemplate};

/// Parameters (the scene file's `params` block).
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Params {
    /// Test-character seed (also the quadruped's).
    pub seed: u64,
    /// Target vertex count.
    pub target_vertices: BySize<usize>,
    /// Distance-field tolerance τ (normalized units).
    pub tau: f64,
    /// Target vertex count of the too-thin character (spec §3.13: it polygonizes as one
    /// component at 33k vertices; coarser grids may break its limbs apart).
    pub too_thin_vertices: BySize<usize>,
}

/// Runs the experiment. Figures per case of [`defect_cases`]: `<case>_outcome` (`handled` or
/// `refused`) and `<case>_embedded_ok` (1 if rigged and correct); `quadruped_embedded_ok`, and
/// `quadruped_mean_err_rel` with `quadruped_reason` when it rigs (else `quadruped_error`);
/// `too_thin_outcome` (text).
pub fn run(p: &Params, size: Size, rec: &mut dyn Recorder) -> Result<Report> {
    let nv = p.target_vertices.get(size);
    let sk = SkeletonTemplate::human();
    let o = RigOptions { tau: p.tau, ..Default::default() };
    let (mesh, truth) = humanoid_character(&test_params(p.seed), nv)?;
    let q = MeshQuery::new(&mesh)?;
    rec.table("cases", &["case", "outcome", "embedded_ok", "message"])?;
    let mut r = Report::default();
    for c in defect_cases(&mesh)? {
        let oc = RigOptions { keep_largest_component: c.keep_largest, ..o.clone() };
        let (outcome, ok, msg) = match autorig(&c.positions, &c.faces, &sk, &[], &oc) {
            Ok(rig) => {
                let sc = score(&sk, &rig.joints, &truth.rest, &q);
                let msg = format!(
                    "welded {} vertices; mean error {:.4} H",
                    rig.diagnostics.prep.welded_vertices, sc.mean_err_rel
                );
                ("handled", sc.ok, msg)
            }
            Err(e) => ("refused", false, e.to_string()),
        };
        r.text(&format!("{}_outcome", c.name), outcome);
        r.count(&format!("{}_embedded_ok", c.name), ok as u64);
        rec.row("cases", &[c.name.into(), outcome.into(), (ok as usize).into(), msg.into()])?;
    }
    // A quadruped with the quadruped template (qualitative).
    let (qm, qt) = quadruped_character(p.seed, nv)?;
    let qsk = SkeletonTemplate::quadruped();
    match autorig(&qm.positions, &qm.faces, &qsk, &[], &o) {
        Ok(rig) => {
            let qq = MeshQuery::new(&qm)?;
            let sc = score(&qsk, &rig.joints, &qt.rest, &qq);
            r.count("quadruped_embedded_ok", sc.ok as u64)
                .num("quadruped_mean_err_rel", sc.mean_err_rel)
                .text("quadruped_reason", &sc.reason);
            rec.file("quadruped_skel.obj", skeleton_obj(&qsk, &rig.joints).as_bytes())?;
            if rec.keeps_outputs() {
                rec.file("quadruped.obj", obj::to_string(&MeshOut::tri(&qm.positions, &qm.faces))?.as_bytes())?;
            }
        }
        Err(e) => {
            r.count("quadruped_embedded_ok", 0).text("quadruped_error", &e.to_string());
        }
    }
    // Too-thin limbs (spec §3.13: limb radius 0.012 nu rigged with τ = 0.008, i.e. 1.5τ): refused
    // with a diagnostic, never a panic.
    let thin = too_thin_params(p.seed);
    let outcome = match humanoid_character(&thin, p.too_thin_vertices.get(size)) {
        Ok((tm, _)) => {
            match autorig(&tm.positions, &tm.faces, &sk, &[], &RigOptions { tau: TOO_THIN_TAU, ..o.clone() }) {
                Ok(rig) => {
                    let tq = MeshQuery::new(&tm)?;
                    let (_, tt) = humanoid(&thin)?;
                    format!("embedded (correct: {})", score(&sk, &rig.joints, &tt.rest, &tq).ok)
                }
                Err(RigError::GraphDisconnected { components }) => {
                    format!("refused: graph has {components} components")
                }
                Err(e) => format!("refused: {e}"),
            }
        }
        Err(e) => format!("not meshed: {e}"),
    };
    r.text("too_thin_outcome", &outcome);
    r.check("duplicates_embedded_ok", Target::Equals(1.0), "spec §8: duplicate vertices are welded")
        .check("inverted_embedded_ok", Target::Equals(1.0), "spec §8: an inverted mesh is flipped, same result")
        .check("components_keep_largest_embedded_ok", Target::Equals(1.0), "spec §8: keep_largest_component")
        .check("holes_embedded_ok", Target::Equals(0.0), "spec §8: holes are refused (NotClosed)");
    Ok(r)
}

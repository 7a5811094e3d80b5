//! rigging's scenes (spec §6): thin adapters over `rigging::experiments` — the test set, stage
//! timings, learning Γ, a walk, the bone-heat figure, odd shapes and arm weight on the torso.

use geom_core::anim::skin::SkinWeights;
use geom_core::experiment::Report;
use rigging::experiments::{animate, heat_two_bone, odd_shapes, test16, timing, train, weights_vs_proximity};
use rigging::RigError;

use crate::error::{Error, Result};
use crate::out::Summary;
use crate::record::run_experiment;
use crate::registry::{RunCtx, Runner};

impl From<RigError> for Error {
    fn from(e: RigError) -> Self {
        match e {
            RigError::Core(c) => Error::Core(c),
            other => Error::Run(format!("rigging: {other}")),
        }
    }
}

/// Adds rigging's runners.
pub fn register(v: &mut Vec<Runner>) {
    v.push(Runner { method: "rigging/test16", run: |c| run_experiment(c, test16::run) });
    v.push(Runner { method: "rigging/timing", run: |c| run_experiment(c, timing::run) });
    v.push(Runner { method: "rigging/train", run: |c| run_experiment(c, train::run) });
    v.push(Runner { method: "rigging/animate", run: run_animate });
    v.push(Runner { method: "rigging/heat-two-bone", run: |c| run_experiment(c, heat_two_bone::run) });
    v.push(Runner { method: "rigging/odd-shapes", run: |c| run_experiment(c, odd_shapes::run) });
    v.push(Runner { method: "rigging/weights-vs-proximity", run: |c| run_experiment(c, weights_vs_proximity::run) });
}

fn pack4(w: &SkinWeights) -> Result<curve_skin::PackedWeights<4>> {
    let rows: Vec<Vec<(u16, f32)>> = (0..w.len())
        .map(|v| {
            let (j, x) = w.row(v);
            j.iter().copied().zip(x.iter().copied()).collect()
        })
        .collect();
    curve_skin::PackedWeights::<4>::from_sparse(&rows).map(|x| x.0).map_err(|e| Error::Run(format!("curve-skin: {e}")))
}

/// `rigging/animate`: the experiment, then the walk as glTF (`walk.gltf`, curve-skin's writer).
fn run_animate(ctx: &RunCtx) -> Result<Summary> {
    let gltf = ctx.out_dir.join("walk.gltf");
    run_experiment(ctx, |p: &animate::Params, size, rec| -> Result<Report> {
        let (mut r, a) = animate::animate(p, size, rec)?;
        let m = &a.rig.mesh;
        let pos32: Vec<[f32; 3]> = m.positions.iter().map(|p| [p.x as f32, p.y as f32, p.z as f32]).collect();
        let nrm: Vec<[f32; 3]> =
            geom_core::mesh::vertex_normals(&m.faces, &m.positions, geom_core::mesh::NormalWeight::Area)
                .iter()
                .map(|n| [n.x as f32, n.y as f32, n.z as f32])
                .collect();
        let skin_poses: Vec<curve_skin::poses::SkinPose> = a
            .poses
            .iter()
            .map(|q| curve_skin::poses::SkinPose {
                rot: q.rot.clone(),
                root_pos: q.root_pos,
                twist_hint: vec![None; q.rot.len()],
            })
            .collect();
        let w = pack4(&a.rig.weights)?;
        curve_skin::gltf::write_gltf(&gltf, &pos32, &nrm, &m.faces, &a.skeleton, &w, Some((&a.times, &skin_poses)))
            .map_err(|e| Error::Run(format!("glTF: {e}")))?;
        let bytes = std::fs::metadata(&gltf).map(|m| m.len()).unwrap_or(0);
        r.count("gltf_bytes", bytes).count("gltf_joints", a.skeleton.len() as u64);
        Ok(r)
    })
}

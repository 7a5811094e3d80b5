//! `rigging/animate` (paper §6; spec §6.4): a procedural walk ([`crate::walk::walk_cycle`]) on a
//! rigged test character, skinned by linear blend skinning with the bone-heat weights; the
//! enclosed volume per frame shows how much LBS loses.
//!
//! Outputs: table `frames` (frame, time s, volume ratio), mesh frames `frames/NNNN.obj` every
//! `obj_every` frames, the rig as `rig.ron` (joint names, joint positions, sparse weights) and
//! the walking character as binary glTF `walk.glb` (`geom_core::io::gltf`: the skinning skeleton's
//! joints, the bone-heat weights, the walk as joint rotations and root translation).
//! [`animate`] also returns the rig and the walk.
//!
//! ```no_run
//! use geom_core::experiment::{BySize, Size};
//! use geom_core::record::NullRecorder;
//! use rigging::experiments::animate::{run, Params};
//! let p = Params { seed: 1000, target_vertices: BySize::Same(6000), tau: 0.004, cycles: 2, fps: 30.0, obj_every: 6 };
//! let r = run(&p, Size::Quick, &mut NullRecorder::default()).unwrap();
//! println!("volume ratio ≥ {}", r.get_f64("volume_ratio_min"));
//! ```

use geom_core::anim::skin::{forward_kinematics, lbs, skinning_transforms, SkinSkeleton};
use geom_core::anim::Pose;
use geom_core::experiment::{BySize, Report, Size};
use geom_core::io::gltf::{skinned_glb, GltfAnimation, GltfJoint, SkinnedMesh};
use geom_core::math::Pt3;
use geom_core::record::{MeshFrame, Recorder};
use geom_core::stats;
use serde::Deserialize;

use crate::characters::test_params;
use crate::error::{Result, RigError};
use crate::presets::humanoid_character;
use crate::{autorig, Rig, RigOptions, SkeletonTemplate};

/// Parameters (the scene file's `params` block).
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Params {
    /// Test-character seed.
    pub seed: u64,
    /// Target vertex count.
    pub target_vertices: BySize<usize>,
    /// Distance-field tolerance τ (normalized units).
    pub tau: f64,
    /// Gait cycles (1.1 s each).
    pub cycles: usize,
    /// Frames per second (> 0).
    pub fps: f64,
    /// Write every n-th frame as OBJ (0 = none).
    pub obj_every: usize,
}

/// The rigged character and its walk.
pub struct WalkAnimation {
    /// The rig.
    pub rig: Rig,
    /// Its skinning skeleton ([`Rig::skin_skeleton`]).
    pub skeleton: SkinSkeleton,
    /// Frame times (s).
    pub times: Vec<f64>,
    /// Poses on `skeleton`.
    pub poses: Vec<Pose>,
}

/// Runs the experiment (see [`animate`]) and keeps the report.
pub fn run(p: &Params, size: Size, rec: &mut dyn Recorder) -> Result<Report> {
    animate(p, size, rec).map(|(r, _)| r)
}

/// Runs the experiment. Figures: `frames`, `vertices`, `volume_ratio_min`, `volume_ratio_max`
/// (enclosed volume of the skinned mesh over the rest volume, over the frames), `gltf_bytes`
/// (size of `walk.glb`), `gltf_joints`. Errors:
/// `InvalidParameter` for a non-positive frame rate.
pub fn animate(p: &Params, size: Size, rec: &mut dyn Recorder) -> Result<(Report, WalkAnimation)> {
    if !(p.fps > 0.0 && p.fps.is_finite()) {
        return Err(RigError::InvalidParameter(format!("animate: fps = {} must be positive", p.fps)));
    }
    let nv = p.target_vertices.get(size);
    let sk = SkeletonTemplate::human();
    let (mesh, _) = humanoid_character(&test_params(p.seed), nv)?;
    let o = RigOptions { tau: p.tau, ..Default::default() };
    let rig = autorig(&mesh.positions, &mesh.faces, &sk, &[], &o)?;
    let ssk = rig.skin_skeleton()?;
    let leg = (rig.joints[4] - rig.joints[6]).norm();
    let (times, poses) = crate::walk::walk_cycle(&ssk, leg, p.cycles, p.fps);
    let v0 = geom_core::mesh::signed_volume(&rig.mesh.faces, &rig.mesh.positions);
    rec.table("frames", &["frame", "time", "volume_ratio"])?;
    let mut out = vec![Pt3::origin(); rig.mesh.n_vertices()];
    let (mut vmin, mut vmax): (f64, f64) = (f64::INFINITY, 0.0);
    for (f, pose) in poses.iter().enumerate() {
        rec.progress(f as u64, poses.len() as u64);
        let posed = forward_kinematics(&ssk, pose);
        let t = skinning_transforms(&ssk, &posed);
        lbs(&rig.mesh.positions, &rig.weights, &t, &mut out);
        let vr = geom_core::mesh::signed_volume(&rig.mesh.faces, &out) / v0;
        vmin = stats::nan_min(vmin, vr);
        vmax = stats::nan_max(vmax, vr);
        rec.row("frames", &[f.into(), times[f].into(), vr.into()])?;
        if p.obj_every > 0 && f % p.obj_every == 0 {
            rec.frame(&MeshFrame {
                sequence: "frames",
                index: f,
                time: times[f],
                positions: &out,
                faces: &rig.mesh.faces,
                attributes: &[],
            })?;
        }
    }
    let ron_text = ron::to_string(&(
        rig.template.joints.iter().map(|j| j.name.clone()).collect::<Vec<_>>(),
        rig.joints.iter().map(|p| [p.x, p.y, p.z]).collect::<Vec<_>>(),
        &rig.weights.offsets,
        &rig.weights.joint,
        &rig.weights.w,
    ))
    .map_err(|e| RigError::InvalidParameter(format!("rig.ron: {e}")))?;
    rec.file("rig.ron", ron_text.as_bytes())?;
    let joints = GltfJoint::from_skin_skeleton(&ssk);
    let anim = GltfAnimation::from_skin_poses(&ssk, &times, &poses, "walk")?;
    let glb = skinned_glb(&SkinnedMesh {
        name: "character",
        positions: &rig.mesh.positions,
        faces: &rig.mesh.faces,
        joints: &joints,
        weights: &rig.weights,
        animation: Some(&anim),
    })?;
    rec.file("walk.glb", &glb)?;
    let mut r = Report::default();
    r.count("frames", poses.len() as u64)
        .count("vertices", rig.mesh.n_vertices() as u64)
        .num("volume_ratio_min", vmin)
        .num("volume_ratio_max", vmax)
        .count("gltf_bytes", glb.len() as u64)
        .count("gltf_joints", joints.len() as u64);
    Ok((r, WalkAnimation { rig, skeleton: ssk, times, poses }))
}

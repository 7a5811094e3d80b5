//! `cargo xtask retarget <clip.bvh> --rig <rig.json> [--units UNIT] [--skinning lbs|dqs]
//! [--out DIR]`: plays a BVH clip on a rig written by `cargo xtask rig`
//! (`geom_core::anim::retarget`), skins it with curve-skin (LBS and DQS), and writes the
//! retargeted clip (`retargeted.bvh`), the animated skinned character (`animated.glb`), skinned
//! OBJ frames every `--every` frames and `summary.json` with the figures.

use std::path::{Path, PathBuf};
use std::time::Instant;

use curve_skin::{Dqs, Lbs, PackedWeights, SkinSkeleton, Skinner};
use geom_core::anim::bvh::{self, BvhOptions, BvhWriteOptions};
use geom_core::anim::retarget::{retarget, RetargetOptions};
use geom_core::io::gltf::{skinned_glb, GltfAnimation, GltfJoint, SkinnedMesh};
use geom_core::io::{obj, MeshOut};
use geom_core::math::Pt3;
use rigging::export::RigFile;

use crate::cmd_rig::metres_per_unit;
use crate::error::{io_err, Error, Result};
use crate::out::Summary;

/// Command-line arguments of `retarget`.
pub struct RetargetArgs {
    /// The BVH clip.
    pub clip: PathBuf,
    /// `rig.json` of `cargo xtask rig`.
    pub rig: PathBuf,
    /// Length unit of the rig: m, cm, mm, in or auto.
    pub units: String,
    /// Skinning of the OBJ frames: lbs or dqs.
    pub skinning: String,
    /// Write every n-th skinned frame as OBJ (0 = none).
    pub every: usize,
    /// Output folder.
    pub out: PathBuf,
}

fn file_err(path: &Path, e: impl std::fmt::Display) -> Error {
    Error::Run(format!("{}: {e}", path.display()))
}

/// `cargo xtask retarget`.
pub fn run(a: &RetargetArgs) -> Result<()> {
    if !matches!(a.skinning.as_str(), "lbs" | "dqs") {
        return Err(Error::Usage(format!("--skinning {}: expected lbs or dqs", a.skinning)));
    }
    // Every input is read and checked before any long work.
    let clip = bvh::read_file(&a.clip, &BvhOptions::default()).map_err(|e| file_err(&a.clip, e))?;
    let text = std::fs::read_to_string(&a.rig).map_err(io_err(&a.rig))?;
    let rig: RigFile = serde_json::from_str(&text).map_err(|e| file_err(&a.rig, e))?;
    let o = rig.validate().map_err(|e| file_err(&a.rig, e))?;
    let s = metres_per_unit(&a.units, rig.height)?;
    let target = rig.anim_skeleton(&o, s).map_err(|e| file_err(&a.rig, e))?;
    let opts = RetargetOptions { target_height: Some(rig.height * s), ..Default::default() };
    let t0 = Instant::now();
    let r = retarget(&clip, &target, &opts)
        .map_err(|e| Error::Run(format!("{} on {}: {e}", a.clip.display(), a.rig.display())))?;
    let t_retarget = t0.elapsed().as_secs_f64();
    let m = r.metrics();
    std::fs::create_dir_all(&a.out).map_err(io_err(&a.out))?;
    let path = a.out.join("retargeted.bvh");
    std::fs::write(&path, bvh::write(&r.motion, &BvhWriteOptions::default())).map_err(io_err(&path))?;
    // Skinning: the mesh in the rig's frame and metres, bound to the joints' bone-aligned frames.
    let rest = rig.mesh_positions(&o, s);
    let faces = &rig.mesh.triangles;
    let weights = rig.skin_weights()?;
    let rows: Vec<Vec<(u16, f32)>> = (0..weights.len())
        .map(|v| {
            let (j, w) = weights.row(v);
            j.iter().copied().zip(w.iter().copied()).collect()
        })
        .collect();
    let (packed, _) = PackedWeights::<4>::from_sparse(&rows).map_err(|e| Error::Run(format!("curve-skin: {e}")))?;
    let (sk, align) = SkinSkeleton::from_skeleton(&target);
    let rest32: Vec<[f32; 3]> = rest.iter().map(|p| [p.x as f32, p.y as f32, p.z as f32]).collect();
    let skin_err = |e: curve_skin::Error| Error::Run(format!("curve-skin: {e}"));
    let mut lbs = Lbs::new(rest32.clone(), None, packed.clone()).map_err(skin_err)?;
    let mut dqs = Dqs::new(rest32, None, packed).map_err(skin_err)?;
    let v0 = geom_core::mesh::signed_volume(faces, &rest);
    let (mut vr_lbs, mut vr_dqs) = (Vec::new(), Vec::new());
    let mut out = vec![[0f32; 3]; rest.len()];
    let t0 = Instant::now();
    let dir = a.out.join(format!("frames_{}", a.skinning));
    for f in 0..r.motion.len() {
        let pose = sk.pose_from_anim(&align, &r.motion.pose(f));
        let posed = curve_skin::forward_kinematics_local(&sk, &pose.root_pos, &pose.rot);
        for (name, skinner, vr) in
            [("lbs", &mut lbs as &mut dyn Skinner, &mut vr_lbs), ("dqs", &mut dqs as &mut dyn Skinner, &mut vr_dqs)]
        {
            skinner.prepare(&sk, &posed).map_err(skin_err)?;
            skinner.deform(curve_skin::DeformOutput { positions: &mut out, normals: None });
            let p: Vec<Pt3> = out.iter().map(|x| Pt3::new(x[0] as f64, x[1] as f64, x[2] as f64)).collect();
            vr.push(geom_core::mesh::signed_volume(faces, &p) / v0);
            if name == a.skinning && a.every > 0 && f % a.every == 0 {
                geom_core::io::write_obj_frame(&dir, f, &MeshOut::tri(&p, faces))?;
            }
        }
    }
    let t_skin = t0.elapsed().as_secs_f64();
    let joints = GltfJoint::from_skeleton(&target);
    let anim = GltfAnimation::from_motion(&r.motion, "retargeted");
    let glb = skinned_glb(&SkinnedMesh {
        name: "character",
        positions: &rest,
        faces,
        joints: &joints,
        weights: &weights,
        animation: Some(&anim),
    })?;
    let path = a.out.join("animated.glb");
    std::fs::write(&path, glb).map_err(io_err(&path))?;
    if a.every == 0 {
        // Keep the rest mesh for reference even without frames.
        obj::write(a.out.join("rest.obj"), &MeshOut::tri(&rest, faces))?;
    }
    let mut sm = Summary::new();
    sm.set("retarget_foot_skate_cm_s", m.foot_skate_cm_s)
        .set("retarget_source_foot_skate_cm_s", m.source_foot_skate_cm_s)
        .set("retarget_root_path_rel_err", m.root_path_rel_err)
        .set_count("retarget_contact_flags", m.contact_flags as u64)
        .set_count("retarget_unreachable_frames", r.unreachable as u64)
        .set("height_ratio", r.height_ratio)
        .set("leg_ratio", r.leg_ratio)
        .set_count("frames", r.motion.len() as u64)
        .set("lbs_volume_ratio_min", geom_core::stats::min(&vr_lbs))
        .set("lbs_volume_ratio_max", geom_core::stats::max(&vr_lbs))
        .set("dqs_volume_ratio_min", geom_core::stats::min(&vr_dqs))
        .set("dqs_volume_ratio_max", geom_core::stats::max(&vr_dqs))
        .set("retarget_s", t_retarget)
        .set("skin_s", t_skin)
        .set("metres_per_unit", s);
    sm.write(&a.out)?;
    println!("retarget {} --rig {}: {}", a.clip.display(), a.rig.display(), a.out.display());
    crate::run::print_summary(&sm);
    Ok(())
}

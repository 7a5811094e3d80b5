//! The character stages of `pipeline/character`: load the mesh and the clip (checked before
//! any long work), rig (`rigging::character::rig_character`), retarget
//! (`geom_core::anim::retarget`) and skin (curve-skin's LBS) the body's frames.

use std::path::{Path, PathBuf};

use curve_skin::{Lbs, PackedWeights, SkinSkeleton, Skinner};
use geom_core::anim::bvh::{self, BvhOptions};
use geom_core::anim::retarget::{missing_roles, retarget, RetargetOptions, Retargeted};
use geom_core::anim::skeleton::JointRole;
use geom_core::anim::skin::SkinWeights;
use geom_core::anim::{Motion, Pose, Skeleton};
use geom_core::collide::MeshQuery;
use geom_core::experiment::{BySize, Report, Size};
use geom_core::math::{Pt3, UnitQuat};
use geom_core::mesh::TriMesh;
use geom_core::procedural::character::{build_mesh, humanoid, HumanoidParams};
use rigging::character::{rig_character, CharacterOptions};
use rigging::export::RigFile;
use rigging::orient::Orientation;
use serde::Deserialize;

use crate::cmd_rig::{metres_per_unit, read_soup, template};
use crate::error::{Error, Result};

/// Where the character mesh comes from.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub enum MeshSource {
    /// geom-core's procedural humanoid (A pose, 1.7 m) meshed to about `vertices` vertices.
    Procedural {
        /// Target vertex count.
        vertices: BySize<usize>,
    },
    /// A closed mesh file (OBJ, PLY, OFF, GLB); `units`: m, cm, mm, in or auto.
    File {
        /// Path (relative to the scene file).
        path: PathBuf,
        /// Length unit.
        units: String,
    },
}

/// The rigged character in the rig's frame (+Y up, facing +Z, metres).
pub struct Character {
    /// The rig file (what `xtask rig` writes).
    pub rig: RigFile,
    /// Its orientation (input → rig frame).
    pub orientation: Orientation,
    /// Metres per input unit.
    pub scale: f64,
    /// The body mesh (m).
    pub mesh: TriMesh,
    /// The animation skeleton of the rig.
    pub skeleton: Skeleton,
    /// The skinning weights.
    pub weights: SkinWeights,
}

fn file_err(path: &Path, e: impl std::fmt::Display) -> Error {
    Error::Run(format!("{}: {e}", path.display()))
}

/// Reads and checks a BVH clip: frame rate > 0 and the leg roles retargeting needs.
pub fn read_clip(path: &Path) -> Result<Motion> {
    let clip = bvh::read_file(path, &BvhOptions::default()).map_err(|e| file_err(path, e))?;
    if !(clip.frame_time > 0.0 && clip.frame_time.is_finite()) {
        return Err(file_err(path, format!("frame time {} s: the clip has no frame rate", clip.frame_time)));
    }
    let legs = [
        JointRole::LeftHip,
        JointRole::LeftKnee,
        JointRole::LeftAnkle,
        JointRole::RightHip,
        JointRole::RightKnee,
        JointRole::RightAnkle,
    ];
    let missing = missing_roles(&clip.skeleton, &legs);
    if !missing.is_empty() {
        return Err(file_err(path, format!("no recognisable legs: joints for {missing:?} not found by name")));
    }
    Ok(clip)
}

/// Loads the character mesh (positions in input units, triangles) and its length unit.
pub fn load_mesh(
    src: &MeshSource,
    size: Size,
    resolve: impl Fn(&Path) -> PathBuf,
) -> Result<(Vec<Pt3>, Vec<[u32; 3]>, String)> {
    match src {
        MeshSource::Procedural { vertices } => {
            let (sdf, _) = humanoid(&HumanoidParams { height: 1.7, ..Default::default() })?;
            let m = build_mesh(&sdf, vertices.get(size))?;
            Ok((m.positions, m.faces, "m".into()))
        }
        MeshSource::File { path, units } => {
            let p = resolve(path);
            let (pos, faces) = read_soup(&p)?;
            Ok((pos, faces, units.clone()))
        }
    }
}

/// Rigs the mesh with the named skeleton template (human, quadruped or a RON file).
pub fn rig(pos: &[Pt3], faces: &[[u32; 3]], units: &str, skeleton: &str, name: &Path) -> Result<Character> {
    let sk = template(skeleton)?;
    // Every bone's heat is kept (no per-bone cap of 4): the cap is applied per joint below,
    // continuously (see `cap_influences`).
    let mut co = CharacterOptions::default();
    co.rig.max_influences = 0;
    let r = rig_character(pos, faces, &sk, &co).map_err(|e| file_err(name, e))?;
    let rig = RigFile::new(&r, pos, faces)?;
    let orientation = rig.validate().map_err(|e| file_err(name, e))?;
    let scale = metres_per_unit(units, rig.height)?;
    let mesh = TriMesh::new(rig.mesh_positions(&orientation, scale), rig.mesh.triangles.clone())?;
    let skeleton = rig.anim_skeleton(&orientation, scale).map_err(|e| file_err(name, e))?;
    let weights = cap_influences(&rig.skin_weights()?, 4)?;
    Ok(Character { rig, orientation, scale, mesh, skeleton, weights })
}

/// The rig's figures: `rig_joints_outside` (joints outside the mesh), `rig_limb_extents_ok`
/// (head joint in the top 15 % of the height, feet in the bottom 10 %, hands at the lateral
/// extremes), `weights_sum_max_err` (largest |Σ_j w_ij − 1|).
pub fn rig_checks(c: &Character, r: &mut Report) -> Result<()> {
    let q = MeshQuery::new(&c.mesh)?;
    let joints: Vec<Pt3> = c.skeleton.rest_globals().iter().map(|x| Pt3::from(x.translation.vector)).collect();
    let outside = joints.iter().filter(|p| q.signed_distance(p) > 0.0).count();
    let bb = c.mesh.aabb();
    let (y0, h) = (bb.min.y, bb.size().y);
    let at = |role: JointRole| c.skeleton.role(role).map(|i| joints[i as usize]);
    let rel = |p: Option<Pt3>| p.map_or(f64::NAN, |p| (p.y - y0) / h);
    let xs: Vec<f64> = joints.iter().map(|p| p.x).collect();
    let (xmin, xmax) = (geom_core::stats::min(&xs), geom_core::stats::max(&xs));
    let hands = at(JointRole::LeftHand).is_some_and(|p| p.x >= xmax - 1e-9 * h)
        && at(JointRole::RightHand).is_some_and(|p| p.x <= xmin + 1e-9 * h);
    let ok = rel(at(JointRole::Head)) >= 0.85
        && rel(at(JointRole::LeftAnkle)) <= 0.10
        && rel(at(JointRole::RightAnkle)) <= 0.10
        && hands;
    let mut sum_err: f64 = 0.0;
    for v in 0..c.weights.len() {
        let (_, w) = c.weights.row(v);
        sum_err = geom_core::stats::nan_max(sum_err, (w.iter().map(|&x| x as f64).sum::<f64>() - 1.0).abs());
    }
    r.count("rig_joints_outside", outside as u64).flag("rig_limb_extents_ok", ok).num("weights_sum_max_err", sum_err);
    Ok(())
}

/// At most `k` influences per vertex, continuously: the (k+1)-th largest weight is subtracted
/// from the k largest (clamped at 0) and the row renormalised. A plain "keep the k largest and
/// renormalise" jumps where the k-th and (k+1)-th swap between neighbouring vertices (the whole
/// swapped weight moves from one bone to another across one edge); here the weight handed over
/// is 0 at the swap, so weights stay continuous over the surface. Measured on
/// `pipeline/jump-skirt` (default): the body's largest edge strain 16.2 with the rigging's
/// per-bone cap of 4 (a torso edge under the left armpit: 0.17 of `l_thigh` on one vertex,
/// 0.17 of `l_shoulder` on its neighbour), 0.93 with every influence kept (8 in the skinning).
pub fn cap_influences(w: &SkinWeights, k: usize) -> Result<SkinWeights> {
    let rows: Vec<Vec<(u16, f32)>> = (0..w.len())
        .map(|v| {
            let (j, x) = w.row(v);
            let mut row: Vec<(u16, f32)> = j.iter().copied().zip(x.iter().copied()).filter(|e| e.1 > 0.0).collect();
            row.sort_by(|a, b| b.1.total_cmp(&a.1).then(a.0.cmp(&b.0)));
            if row.len() > k {
                let cut = row[k].1;
                row.truncate(k);
                let top = row.clone();
                for e in &mut row {
                    e.1 -= cut;
                }
                row.retain(|e| e.1 > 0.0);
                if row.is_empty() {
                    // k + 1 equal weights: keep the first k equally.
                    row = top.iter().map(|e| (e.0, 1.0)).collect();
                }
            }
            let s: f32 = row.iter().map(|e| e.1).sum();
            row.iter().map(|&(j, x)| (j, x / s)).collect()
        })
        .collect();
    Ok(SkinWeights::from_rows(&rows)?)
}

/// Retargets the clip onto the character (root path and foot contacts kept).
pub fn retarget_clip(clip: &Motion, c: &Character, clip_path: &Path) -> Result<Retargeted> {
    let opts = RetargetOptions { target_height: Some(c.rig.height * c.scale), ..Default::default() };
    retarget(clip, &c.skeleton, &opts).map_err(|e| file_err(clip_path, e))
}

/// Linear-blend skinning of rest positions `rest` with weights `rows` on a skeleton.
pub struct Skin {
    sk: SkinSkeleton,
    align: Vec<UnitQuat>,
    lbs: Lbs<4>,
    n: usize,
}

impl Skin {
    /// Binds `rest` (m) with per-vertex `(joint, weight)` rows on `skeleton`.
    pub fn new(skeleton: &Skeleton, rest: &[Pt3], rows: &[Vec<(u16, f32)>]) -> Result<Self> {
        let skin_err = |e: curve_skin::Error| Error::Run(format!("curve-skin: {e}"));
        let (packed, _) = PackedWeights::<4>::from_sparse(rows).map_err(skin_err)?;
        let (sk, align) = SkinSkeleton::from_skeleton(skeleton);
        let rest32: Vec<[f32; 3]> = rest.iter().map(|p| [p.x as f32, p.y as f32, p.z as f32]).collect();
        let lbs = Lbs::new(rest32, None, packed).map_err(skin_err)?;
        Ok(Self { sk, align, lbs, n: rest.len() })
    }

    /// The skinned positions (m) in `pose`.
    pub fn pose(&mut self, pose: &Pose) -> Result<Vec<Pt3>> {
        let p = self.sk.pose_from_anim(&self.align, pose);
        let posed = curve_skin::forward_kinematics_local(&self.sk, &p.root_pos, &p.rot);
        self.lbs.prepare(&self.sk, &posed).map_err(|e| Error::Run(format!("curve-skin: {e}")))?;
        let mut out = vec![[0f32; 3]; self.n];
        self.lbs.deform(curve_skin::DeformOutput { positions: &mut out, normals: None });
        Ok(out.iter().map(|x| Pt3::new(x[0] as f64, x[1] as f64, x[2] as f64)).collect())
    }
}

/// Weight rows of a [`SkinWeights`].
pub fn weight_rows(w: &SkinWeights) -> Vec<Vec<(u16, f32)>> {
    (0..w.len())
        .map(|v| {
            let (j, w) = w.row(v);
            j.iter().copied().zip(w.iter().copied()).collect()
        })
        .collect()
}

/// The poses of the simulated span at `fps`: a smooth blend over `settle` s from the rest pose
/// to the clip's frame at `start` (moved horizontally onto the rest root), then the clip from
/// `start` for `seconds` s (0 = to its end), sampled at the clip's frames nearest in time.
pub fn poses(m: &Motion, rest: &Pose, start: f64, seconds: f64, settle: f64, fps: f64) -> Vec<Pose> {
    let f0 = ((start / m.frame_time).round() as usize).min(m.len() - 1);
    let mut first = m.pose(f0);
    let shift = geom_core::math::Vec3::new(rest.root_pos.x - first.root_pos.x, 0.0, rest.root_pos.z - first.root_pos.z);
    let end = if seconds > 0.0 { (start + seconds).min(m.duration()) } else { m.duration() };
    let n_settle = (settle * fps).round() as usize;
    let n_clip = ((end - start).max(0.0) * fps).floor() as usize + 1;
    first.root_pos += shift;
    let mut out = Vec::with_capacity(n_settle + n_clip);
    for k in 0..n_settle {
        let s = k as f64 / n_settle as f64;
        let w = s * s * (3.0 - 2.0 * s);
        out.push(Pose {
            root_pos: rest.root_pos.lerp(&first.root_pos, w),
            rot: rest.rot.iter().zip(&first.rot).map(|(a, b)| shortest_slerp(a, b, w)).collect(),
        });
    }
    for k in 0..n_clip {
        let f = (((start + k as f64 / fps) / m.frame_time).round() as usize).min(m.len() - 1);
        let mut p = m.pose(f);
        p.root_pos += shift;
        out.push(p);
    }
    out
}

/// Slerp along the shorter arc (q and −q are the same rotation).
fn shortest_slerp(a: &UnitQuat, b: &UnitQuat, w: f64) -> UnitQuat {
    if a.coords.dot(&b.coords) < 0.0 {
        a.slerp(&UnitQuat::new_unchecked(-b.into_inner()), w)
    } else {
        a.slerp(b, w)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two neighbouring rows whose 4th and 5th weights swap: the plain cap hands the whole
    /// swapped weight from one bone to the other, the continuous cap hands over nothing.
    #[test]
    fn the_influence_cap_is_continuous_where_ranks_swap() {
        let a = vec![(0u16, 0.4f32), (1, 0.2), (2, 0.15), (3, 0.1251), (4, 0.1249)];
        let b = vec![(0u16, 0.4f32), (1, 0.2), (2, 0.15), (3, 0.1249), (4, 0.1251)];
        let w = SkinWeights::from_rows(&[a, b]).unwrap();
        let c = cap_influences(&w, 4).unwrap();
        let dense = |v: usize| {
            let mut r = [0f32; 5];
            let (j, x) = c.row(v);
            j.iter().zip(x).for_each(|(&j, &x)| r[j as usize] += x);
            r
        };
        let (ra, rb) = (dense(0), dense(1));
        let jump: f32 = ra.iter().zip(&rb).map(|(x, y)| (x - y).abs()).sum();
        assert!(jump < 2e-3, "{ra:?} {rb:?}");
        for r in [ra, rb] {
            assert!((r.iter().sum::<f32>() - 1.0).abs() < 1e-6 && r.iter().filter(|&&x| x > 0.0).count() <= 4);
        }
        // A row with ≤ 4 influences is unchanged.
        let one = SkinWeights::from_rows(&[vec![(2u16, 0.7f32), (5, 0.3)]]).unwrap();
        assert_eq!(cap_influences(&one, 4).unwrap().row(0), one.row(0));
    }
}

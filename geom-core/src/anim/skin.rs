//! Skinning exchange types (GEOM-CORE.md §3.12 `anim::skin`, §5.7): the skinning skeleton
//! ([`SkinSkeleton`], rest frames with the x axis along each bone), forward kinematics on it, the
//! skinning transforms `T_j = posed_j · rest_world_j⁻¹`, the sparse weight format [`SkinWeights`]
//! that rigging produces and curve-skin / barnet consume, and a reference `f64` linear blend
//! skinning [`lbs`].
//!
//! Conventions: joints are in topological order (`parent[j] < j`); a joint's frame is rigid with
//! the bone from that joint to its (first) child, so "bone j" and "joint j" share transform `T_j`.
//! Poses carry local rotations relative to the rest local frames: the identity pose reproduces
//! `rest_world`.

use super::skeleton::{Pose, Skeleton};
use crate::error::{Error, Result};
use crate::math::{Iso3, Pt3, UnitQuat, Vec3};
use nalgebra::Translation3;

/// A skeleton for skinning: names, parents (topological order, `parent[j] < j`) and the world
/// frames of the joints in the bind pose. Each rest frame's x axis points along the bone to the
/// joint's first child (leaves keep their parent's orientation by convention of the builder).
#[derive(Clone, Debug, PartialEq)]
pub struct SkinSkeleton {
    /// Joint names (free text, unique by convention).
    pub names: Vec<String>,
    /// Parent joint of each joint; `None` for roots. Always `parent[j] < j`.
    pub parent: Vec<Option<usize>>,
    /// Rest (bind-pose) world frames (m, rad).
    pub rest_world: Vec<Iso3>,
}

impl SkinSkeleton {
    /// Checks sizes and the topological order. Errors: `DimensionMismatch` when the three arrays
    /// differ in length, `InvalidParameter` naming the joint whose parent is not earlier.
    pub fn validate(&self) -> Result<()> {
        let n = self.names.len();
        if self.parent.len() != n {
            return Err(Error::DimensionMismatch { what: "SkinSkeleton.parent", expected: n, got: self.parent.len() });
        }
        if self.rest_world.len() != n {
            return Err(Error::DimensionMismatch {
                what: "SkinSkeleton.rest_world",
                expected: n,
                got: self.rest_world.len(),
            });
        }
        for (j, p) in self.parent.iter().enumerate() {
            if let Some(p) = *p {
                if p >= j {
                    return Err(Error::InvalidParameter(format!(
                        "SkinSkeleton: joint {j} ('{}') has parent {p}, which is not earlier (topological order required)",
                        self.names[j]
                    )));
                }
            }
        }
        Ok(())
    }

    /// Number of joints.
    pub fn len(&self) -> usize {
        self.parent.len()
    }

    /// True when the skeleton has no joint.
    pub fn is_empty(&self) -> bool {
        self.parent.is_empty()
    }

    /// Children of every joint, in index order.
    pub fn children(&self) -> Vec<Vec<usize>> {
        let mut c = vec![Vec::new(); self.len()];
        for (j, p) in self.parent.iter().enumerate() {
            if let Some(p) = *p {
                c[p].push(j);
            }
        }
        c
    }

    /// Builds a skeleton from joint positions: each rest frame has its x axis along the bone to the
    /// first child (a leaf takes its parent's orientation, a childless root the identity). The
    /// frame is the minimal rotation taking the parent's x axis onto the bone direction, applied to
    /// the parent's frame (roots start from the world axes), so frames do not twist along a chain;
    /// an exactly reversed bone turns by π about the parent's z axis. Zero-length bones keep the
    /// parent orientation.
    pub fn from_positions(names: Vec<String>, parent: Vec<Option<usize>>, pos: &[Pt3]) -> Result<SkinSkeleton> {
        let n = names.len();
        if parent.len() != n || pos.len() != n {
            return Err(Error::DimensionMismatch {
                what: "from_positions inputs",
                expected: n,
                got: parent.len().min(pos.len()),
            });
        }
        let mut first_child = vec![None; n];
        for (j, p) in parent.iter().enumerate() {
            if let Some(p) = *p {
                if p >= j {
                    return Err(Error::InvalidParameter(format!("joint {j} has parent {p}, not earlier")));
                }
                if first_child[p].is_none() {
                    first_child[p] = Some(j);
                }
            }
        }
        let mut rot: Vec<UnitQuat> = Vec::with_capacity(n);
        for j in 0..n {
            let base = match parent[j] {
                Some(p) => rot[p],
                None => UnitQuat::identity(),
            };
            let r = match first_child[j] {
                Some(c) => {
                    let d = pos[c] - pos[j];
                    if d.norm() > 1e-12 {
                        let x = base * Vec3::x();
                        let dn = d.normalize();
                        match UnitQuat::rotation_between(&x, &dn) {
                            Some(q) => q * base,
                            // Antiparallel: turn by π about the base z axis (keeps x ⟂ z).
                            None => {
                                UnitQuat::from_axis_angle(
                                    &nalgebra::Unit::new_normalize(base * Vec3::z()),
                                    std::f64::consts::PI,
                                ) * base
                            }
                        }
                    } else {
                        base
                    }
                }
                None => base,
            };
            rot.push(r);
        }
        let rest_world = (0..n).map(|j| Iso3::from_parts(Translation3::from(pos[j].coords), rot[j])).collect();
        let s = SkinSkeleton { names, parent, rest_world };
        s.validate()?;
        Ok(s)
    }
}

impl SkinSkeleton {
    /// The skinning skeleton of an animation skeleton: joint positions of its rest pose, frames
    /// aligned with the bones by [`SkinSkeleton::from_positions`]. Returns the alignment rotations
    /// `A_j` (the rest frame orientations; the animation skeleton's rest globals have identity
    /// rotation), which [`SkinSkeleton::pose_from_anim`] uses to re-base poses.
    pub fn from_skeleton(s: &Skeleton) -> (SkinSkeleton, Vec<UnitQuat>) {
        let g = s.rest_globals();
        let pos: Vec<Pt3> = g.iter().map(|x| Pt3::from(x.translation.vector)).collect();
        let names = s.joints.iter().map(|j| j.name.clone()).collect();
        let parent = s.joints.iter().map(|j| j.parent.map(|p| p as usize)).collect();
        // A Skeleton keeps parents before children (its own validated invariant), which is all
        // from_positions checks.
        let sk = SkinSkeleton::from_positions(names, parent, &pos).expect("Skeleton parents precede children");
        let align = sk.rest_world.iter().zip(&g).map(|(w, r)| r.rotation.inverse() * w.rotation).collect();
        (sk, align)
    }

    /// Re-bases an animation pose (local rotations `R_j` in the parent's frame, BVH convention) on
    /// this skeleton's bone-aligned frames: `q_j = A_j⁻¹ R_j A_j`, same root position. Then
    /// [`forward_kinematics`] gives frames whose positions equal the animation skeleton's
    /// globals and whose orientations are `G_j · A_j`.
    pub fn pose_from_anim(&self, align: &[UnitQuat], p: &Pose) -> Pose {
        Pose { root_pos: p.root_pos, rot: p.rot.iter().zip(align).map(|(r, a)| a.inverse() * r * a).collect() }
    }
}

/// Forward kinematics of a [`Pose`] on a skinning skeleton (see [`forward_kinematics_local`]).
pub fn forward_kinematics(sk: &SkinSkeleton, pose: &Pose) -> Vec<Iso3> {
    forward_kinematics_local(sk, &pose.root_pos, &pose.rot)
}

/// World frames of a posed skeleton from local rotations and a root position: with the rest
/// local frame `L⁰_j = rest_world_p⁻¹ · rest_world_j`, the posed frame is
/// `W_j = W_p · L⁰_j · R(rot_j)`; a root `r` gets `W_r = (rest_world_r.t + (root_pos − rest_world_0.t), rest_world_r.R · R(rot_r))`,
/// so `root_pos` is the posed position of joint 0 and every root moves with it. The identity pose
/// (`rot = I`, `root_pos` = rest position of joint 0) reproduces `rest_world` exactly.
/// Non-unit quaternions are renormalised (a debug assertion flags drift > 1e-6).
///
/// Panics if `rot.len() != sk.len()` (a programming error: poses are built for their skeleton).
pub fn forward_kinematics_local(sk: &SkinSkeleton, root_pos: &Vec3, rot: &[UnitQuat]) -> Vec<Iso3> {
    let mut out = vec![Iso3::identity(); sk.len()];
    forward_kinematics_into(sk, root_pos, rot, &mut out);
    out
}

/// [`forward_kinematics_local`] into a caller-provided buffer (no allocation).
pub fn forward_kinematics_into(sk: &SkinSkeleton, root_pos: &Vec3, rot: &[UnitQuat], out: &mut [Iso3]) {
    assert_eq!(rot.len(), sk.len(), "pose has {} rotations for {} joints", rot.len(), sk.len());
    assert_eq!(out.len(), sk.len(), "output has {} frames for {} joints", out.len(), sk.len());
    if sk.is_empty() {
        return;
    }
    let shift = root_pos - sk.rest_world[0].translation.vector;
    for j in 0..sk.len() {
        let q = rot[j];
        debug_assert!((q.quaternion().norm() - 1.0).abs() < 1e-6, "non-unit quaternion at joint {j}");
        let q = UnitQuat::new_normalize(*q.quaternion());
        out[j] = match sk.parent[j] {
            Some(p) => {
                let local = sk.rest_world[p].inverse() * sk.rest_world[j];
                out[p] * local * Iso3::from_parts(Translation3::identity(), q)
            }
            None => {
                let r = sk.rest_world[j];
                Iso3::from_parts(Translation3::from(r.translation.vector + shift), r.rotation * q)
            }
        };
    }
}

/// Skinning transforms `T_j = posed_j · rest_world_j⁻¹` (GEOM-CORE.md §3.12): the rigid motion
/// that carries a point bound to joint/bone `j` from the bind pose to the pose.
pub fn skinning_transforms(sk: &SkinSkeleton, posed: &[Iso3]) -> Vec<Iso3> {
    posed.iter().zip(&sk.rest_world).map(|(w, b)| w * b.inverse()).collect()
}

/// Sparse per-vertex skin weights (compressed rows): vertex `v`'s influences are
/// `joint[offsets[v]..offsets[v+1]]` with weights `w[..]`. Rows sum to 1 (within f32 rounding),
/// weights are non-negative. This is the exchange format between rigging (producer) and the
/// skinning crates (consumers).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SkinWeights {
    /// Row offsets, `len = vertices + 1`, `offsets[0] = 0`.
    pub offsets: Vec<u32>,
    /// Joint (bone) index of each entry.
    pub joint: Vec<u16>,
    /// Weight of each entry.
    pub w: Vec<f32>,
}

impl SkinWeights {
    /// Builds the compressed rows from one `(joint, weight)` list per vertex, clamping negative
    /// weights to 0 and renormalising each row. Errors: `NonFinite` for a NaN/∞ weight,
    /// `InvalidParameter` naming the vertex whose row has zero total weight.
    pub fn from_rows(rows: &[Vec<(u16, f32)>]) -> Result<SkinWeights> {
        let mut s = SkinWeights { offsets: Vec::with_capacity(rows.len() + 1), joint: Vec::new(), w: Vec::new() };
        s.offsets.push(0);
        for (v, row) in rows.iter().enumerate() {
            let mut sum = 0.0f64;
            for &(_, w) in row {
                if !w.is_finite() {
                    return Err(Error::NonFinite("SkinWeights::from_rows weight"));
                }
                sum += w.max(0.0) as f64;
            }
            if sum <= 0.0 {
                return Err(Error::InvalidParameter(format!("skin weights: vertex {v} has zero total weight")));
            }
            for &(j, w) in row {
                if w > 0.0 {
                    s.joint.push(j);
                    s.w.push((w as f64 / sum) as f32);
                }
            }
            s.offsets.push(s.joint.len() as u32);
        }
        Ok(s)
    }

    /// Number of vertices (rows).
    pub fn len(&self) -> usize {
        self.offsets.len().saturating_sub(1)
    }

    /// True when there is no row.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The influences of vertex `v` as parallel slices `(joints, weights)`.
    pub fn row(&self, v: usize) -> (&[u16], &[f32]) {
        let (a, b) = (self.offsets[v] as usize, self.offsets[v + 1] as usize);
        (&self.joint[a..b], &self.w[a..b])
    }

    /// Keeps at most `max_k` influences per vertex (the largest; ties broken by lower joint index)
    /// and drops those below `min_w`, then renormalises each row. Returns the largest weight mass
    /// dropped from one row (before renormalisation). A row whose every weight is below `min_w`
    /// keeps its largest one, so no row becomes empty.
    pub fn prune(&mut self, max_k: usize, min_w: f32) -> f32 {
        let max_k = max_k.max(1);
        let mut offsets = Vec::with_capacity(self.offsets.len());
        let mut joint = Vec::with_capacity(self.joint.len());
        let mut w = Vec::with_capacity(self.w.len());
        offsets.push(0u32);
        let mut worst = 0.0f32;
        let mut row: Vec<(u16, f32)> = Vec::new();
        for v in 0..self.len() {
            let (js, ws) = self.row(v);
            row.clear();
            row.extend(js.iter().copied().zip(ws.iter().copied()));
            row.sort_by(|a, b| b.1.total_cmp(&a.1).then(a.0.cmp(&b.0)));
            let total: f32 = row.iter().map(|e| e.1).sum();
            let mut keep = row.len().min(max_k);
            while keep > 1 && row[keep - 1].1 < min_w {
                keep -= 1;
            }
            let kept: f32 = row[..keep].iter().map(|e| e.1).sum();
            worst = worst.max(total - kept);
            for &(j, x) in &row[..keep] {
                joint.push(j);
                w.push(if kept > 0.0 { x / kept } else { 1.0 / keep as f32 });
            }
            offsets.push(joint.len() as u32);
        }
        self.offsets = offsets;
        self.joint = joint;
        self.w = w;
        worst
    }
}

/// Reference linear blend skinning in `f64`: `out_v = Σ_j w_vj · T_j · rest_v` (Magnenat-Thalmann
/// et al. 1988; Lewis et al. 2000). Slow and simple on purpose: the fast `f32` skinners are
/// checked against it.
///
/// Panics if `out.len() != rest.len()` or a row names a joint outside `t` (caller error).
pub fn lbs(rest: &[Pt3], w: &SkinWeights, t: &[Iso3], out: &mut [Pt3]) {
    assert_eq!(out.len(), rest.len(), "lbs: output length");
    assert_eq!(w.len(), rest.len(), "lbs: weight rows");
    for (v, (x, o)) in rest.iter().zip(out.iter_mut()).enumerate() {
        let (js, ws) = w.row(v);
        let mut acc = Vec3::zeros();
        for (&j, &wj) in js.iter().zip(ws) {
            acc += (t[j as usize] * x).coords * wj as f64;
        }
        *o = Pt3::from(acc);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Unit;

    fn arm() -> SkinSkeleton {
        let pos = [Pt3::new(-1.0, 0.0, 0.0), Pt3::new(0.0, 0.0, 0.0), Pt3::new(1.0, 0.5, 0.0)];
        SkinSkeleton::from_positions(vec!["a".into(), "b".into(), "c".into()], vec![None, Some(0), Some(1)], &pos)
            .unwrap()
    }

    #[test]
    fn rest_frames_point_along_bones() {
        let s = arm();
        for j in 0..2 {
            let x = s.rest_world[j].rotation * Vec3::x();
            let d = (s.rest_world[j + 1].translation.vector - s.rest_world[j].translation.vector).normalize();
            assert!((x - d).norm() < 1e-14, "joint {j}");
        }
    }

    #[test]
    fn identity_pose_reproduces_rest_and_transforms_are_identity() {
        let s = arm();
        let rot = vec![UnitQuat::identity(); 3];
        let w = forward_kinematics_local(&s, &s.rest_world[0].translation.vector, &rot);
        for (a, b) in w.iter().zip(&s.rest_world) {
            assert!((a.to_homogeneous() - b.to_homogeneous()).abs().max() < 1e-14);
        }
        for t in skinning_transforms(&s, &w) {
            assert!((t.to_homogeneous() - Iso3::identity().to_homogeneous()).abs().max() < 1e-14);
        }
    }

    #[test]
    fn rotating_a_joint_moves_only_its_subtree_about_the_joint() {
        let s = arm();
        let mut rot = vec![UnitQuat::identity(); 3];
        rot[1] = UnitQuat::from_axis_angle(&Unit::new_normalize(Vec3::new(0.3, 0.2, 1.0)), 0.7);
        let w = forward_kinematics_local(&s, &s.rest_world[0].translation.vector, &rot);
        // Joint 1 stays in place, joint 2 keeps its distance to joint 1.
        assert!((w[1].translation.vector - s.rest_world[1].translation.vector).norm() < 1e-14);
        let d0 = (s.rest_world[2].translation.vector - s.rest_world[1].translation.vector).norm();
        let d1 = (w[2].translation.vector - w[1].translation.vector).norm();
        assert!((d0 - d1).abs() < 1e-14);
        let t = skinning_transforms(&s, &w);
        // T_1 fixes joint 1 and T_0 is the identity.
        let j1 = Pt3::from(s.rest_world[1].translation.vector);
        assert!((t[1] * j1 - j1).norm() < 1e-14);
        assert!((t[0].to_homogeneous() - Iso3::identity().to_homogeneous()).abs().max() < 1e-14);
    }

    #[test]
    fn root_position_translates_everything() {
        let s = arm();
        let rot = vec![UnitQuat::identity(); 3];
        let d = Vec3::new(0.1, -2.0, 3.0);
        let w = forward_kinematics_local(&s, &(s.rest_world[0].translation.vector + d), &rot);
        for (a, b) in w.iter().zip(&s.rest_world) {
            assert!((a.translation.vector - b.translation.vector - d).norm() < 1e-14);
        }
    }

    #[test]
    fn anim_skeleton_round_trip() {
        let s = Skeleton::standard_humanoid();
        let (sk, align) = SkinSkeleton::from_skeleton(&s);
        let mut p = s.rest_pose();
        for (j, q) in p.rot.iter_mut().enumerate() {
            *q = UnitQuat::from_axis_angle(&Unit::new_normalize(Vec3::new(1.0, j as f64, 0.5)), 0.1 * j as f64);
        }
        p.root_pos += Vec3::new(0.3, 0.1, -0.2);
        let mut g = vec![Iso3::identity(); s.joints.len()];
        s.globals(&p, &mut g);
        let w = forward_kinematics(&sk, &sk.pose_from_anim(&align, &p));
        for j in 0..g.len() {
            assert!((g[j].translation.vector - w[j].translation.vector).norm() < 1e-12, "joint {j}");
            assert!((g[j].rotation * align[j]).angle_to(&w[j].rotation) < 1e-12, "joint {j}");
        }
    }

    #[test]
    fn prune_keeps_largest_and_renormalises() {
        let mut w = SkinWeights::from_rows(&[
            vec![(0, 0.1), (1, 0.5), (2, 0.3), (3, 0.1)],
            vec![(4, 1.0)],
            vec![(0, 0.995), (1, 0.004), (2, 0.001)],
        ])
        .unwrap();
        let dropped = w.prune(2, 0.01);
        assert_eq!(w.row(0).0, &[1, 2]);
        assert!((dropped - 0.2).abs() < 1e-6, "{dropped}");
        assert_eq!(w.row(2).0, &[0]);
        for v in 0..w.len() {
            let s: f32 = w.row(v).1.iter().sum();
            assert!((s - 1.0).abs() < 1e-6);
        }
        // A row whose every weight is below min_w keeps its largest one.
        let mut tiny = SkinWeights { offsets: vec![0, 2], joint: vec![0, 1], w: vec![0.004, 0.003] };
        tiny.prune(4, 0.01);
        assert_eq!(tiny.row(0), (&[0u16][..], &[1.0f32][..]));
    }

    #[test]
    fn from_rows_rejects_nan_and_empty_rows() {
        assert!(SkinWeights::from_rows(&[vec![(0, f32::NAN)]]).is_err());
        assert!(SkinWeights::from_rows(&[vec![(0, -1.0)]]).is_err());
        let w = SkinWeights::from_rows(&[vec![(0, -1.0), (1, 2.0)]]).unwrap();
        assert_eq!(w.row(0), (&[1u16][..], &[1.0f32][..]));
    }

    #[test]
    fn lbs_with_equal_transforms_is_that_transform() {
        let rest = vec![Pt3::new(0.1, 0.2, 0.3), Pt3::new(-1.0, 2.0, 0.5)];
        let w = SkinWeights::from_rows(&[vec![(0, 0.3), (1, 0.7)], vec![(1, 1.0)]]).unwrap();
        let g = Iso3::new(Vec3::new(1.0, 2.0, 3.0), Vec3::new(0.4, -0.2, 0.9));
        let mut out = vec![Pt3::origin(); 2];
        lbs(&rest, &w, &[g, g], &mut out);
        for (o, r) in out.iter().zip(&rest) {
            assert!((o - g * r).norm() < 1e-6);
        }
    }
}

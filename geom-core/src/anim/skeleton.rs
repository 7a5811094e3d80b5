//! Joint hierarchies: [`Channel`], [`JointRole`], [`Joint`], [`Skeleton`] and the one [`Pose`]
//! type, with forward kinematics (motion-graph.md §2.1).
//!
//! Conventions: metres, +Y up, rest pose facing +Z with the character's left on +X. Joints are
//! stored in topological order (a parent before its children, `parent < index`), joint 0 is the
//! root. A joint's local transform is `T(offset + extra)·R`, its global transform
//! `G_j = G_parent·T(offset_j + extra_j)·R_j`; for the root, `G_root = T(root_pos)·R_root`, where
//! `root_pos` is the root's **world** position (the root's `offset` is its rest position; the BVH
//! reader folds the root OFFSET into `root_pos`).

use crate::error::{Error, Result};
use crate::math::{Iso3, Pt3, UnitQuat, Vec3};
use nalgebra as na;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// One BVH channel: a translation or a rotation about a coordinate axis.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
pub enum Channel {
    /// Translation along x.
    Xpos,
    /// Translation along y.
    Ypos,
    /// Translation along z.
    Zpos,
    /// Rotation about x.
    Xrot,
    /// Rotation about y.
    Yrot,
    /// Rotation about z.
    Zrot,
}

impl Channel {
    /// Whether this is a rotation channel.
    pub fn is_rotation(self) -> bool {
        matches!(self, Channel::Xrot | Channel::Yrot | Channel::Zrot)
    }

    /// The coordinate axis (0 = x, 1 = y, 2 = z).
    pub fn axis(self) -> usize {
        match self {
            Channel::Xpos | Channel::Xrot => 0,
            Channel::Ypos | Channel::Yrot => 1,
            Channel::Zpos | Channel::Zrot => 2,
        }
    }

    /// The BVH spelling (`Xposition`, `Zrotation`, …).
    pub fn bvh_name(self) -> &'static str {
        match self {
            Channel::Xpos => "Xposition",
            Channel::Ypos => "Yposition",
            Channel::Zpos => "Zposition",
            Channel::Xrot => "Xrotation",
            Channel::Yrot => "Yrotation",
            Channel::Zrot => "Zrotation",
        }
    }

    /// Parses a BVH channel name, case-insensitively (`Xposition`, `yrotation`, …).
    pub fn from_bvh_name(s: &str) -> Option<Channel> {
        const ALL: [Channel; 6] =
            [Channel::Xpos, Channel::Ypos, Channel::Zpos, Channel::Xrot, Channel::Yrot, Channel::Zrot];
        ALL.into_iter().find(|c| c.bvh_name().eq_ignore_ascii_case(s))
    }
}

/// Semantic role of a joint, used to retarget between skeletons and to find feet, hips and hands
/// (motion-graph.md §2.1). "Tip" roles are end sites.
#[allow(missing_docs)]
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
pub enum JointRole {
    Root,
    Spine,
    Chest,
    Neck,
    Head,
    LeftCollar,
    LeftShoulder,
    LeftElbow,
    LeftHand,
    RightCollar,
    RightShoulder,
    RightElbow,
    RightHand,
    LeftHip,
    LeftKnee,
    LeftAnkle,
    LeftToe,
    RightHip,
    RightKnee,
    RightAnkle,
    RightToe,
    LeftHandTip,
    RightHandTip,
    LeftToeTip,
    RightToeTip,
    HeadTop,
}

impl JointRole {
    /// All 26 roles.
    pub const ALL: [JointRole; 26] = [
        JointRole::Root,
        JointRole::Spine,
        JointRole::Chest,
        JointRole::Neck,
        JointRole::Head,
        JointRole::LeftCollar,
        JointRole::LeftShoulder,
        JointRole::LeftElbow,
        JointRole::LeftHand,
        JointRole::RightCollar,
        JointRole::RightShoulder,
        JointRole::RightElbow,
        JointRole::RightHand,
        JointRole::LeftHip,
        JointRole::LeftKnee,
        JointRole::LeftAnkle,
        JointRole::LeftToe,
        JointRole::RightHip,
        JointRole::RightKnee,
        JointRole::RightAnkle,
        JointRole::RightToe,
        JointRole::LeftHandTip,
        JointRole::RightHandTip,
        JointRole::LeftToeTip,
        JointRole::RightToeTip,
        JointRole::HeadTop,
    ];

    /// The mirrored role (left ↔ right); central roles map to themselves.
    pub fn mirror(self) -> JointRole {
        use JointRole::*;
        match self {
            LeftCollar => RightCollar,
            LeftShoulder => RightShoulder,
            LeftElbow => RightElbow,
            LeftHand => RightHand,
            RightCollar => LeftCollar,
            RightShoulder => LeftShoulder,
            RightElbow => LeftElbow,
            RightHand => LeftHand,
            LeftHip => RightHip,
            LeftKnee => RightKnee,
            LeftAnkle => RightAnkle,
            LeftToe => RightToe,
            RightHip => LeftHip,
            RightKnee => LeftKnee,
            RightAnkle => LeftAnkle,
            RightToe => LeftToe,
            LeftHandTip => RightHandTip,
            RightHandTip => LeftHandTip,
            LeftToeTip => RightToeTip,
            RightToeTip => LeftToeTip,
            r => r,
        }
    }
}

/// One joint (or end site) of a [`Skeleton`].
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Joint {
    /// Unique name.
    pub name: String,
    /// Parent index, always smaller than this joint's own index; `None` only for the root.
    pub parent: Option<u16>,
    /// Rest translation from the parent (m); for the root, its rest position.
    pub offset: Vec3,
    /// BVH channel layout, kept for round trips; empty for end sites.
    pub channels: Vec<Channel>,
    /// An end site (BVH `End Site`): a leaf marker with no channels and identity rotation.
    pub end_site: bool,
}

/// A joint hierarchy with semantic roles.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Skeleton {
    /// Skeleton (or file) name.
    pub name: String,
    /// Joints in topological order; joint 0 is the root.
    pub joints: Vec<Joint>,
    /// Role → joint index.
    pub roles: BTreeMap<JointRole, u16>,
}

/// One frame of a skeleton's motion: the root's world position (m) and every joint's **local**
/// rotation (relative to its parent; identity for end sites). The only pose type of the toolkit.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Pose {
    /// World position of the root joint (m).
    pub root_pos: Vec3,
    /// Local rotation per joint.
    pub rot: Vec<UnitQuat>,
}

/// Name normalisation for role guessing: drop a namespace prefix (`mixamorig:`, `a|b|`),
/// lowercase, drop `_`, `-`, `.` and spaces.
fn norm_name(s: &str) -> String {
    let s = s.rsplit([':', '|']).next().unwrap_or(s);
    s.chars().filter(|c| !matches!(c, '_' | '-' | '.' | ' ')).map(|c| c.to_ascii_lowercase()).collect()
}

impl Skeleton {
    /// The synthesiser's standard humanoid (motion-graph.md §3.13.1): 21 joints + 5 end sites,
    /// 1.70 m tall, T-pose facing +Z, +Y up, left on +X. The root's rest position (its offset) is
    /// `(0, 0.95, 0)`; the soles are 1 cm below the toe joints, on the ground. Rotation channels
    /// `Zrotation Xrotation Yrotation`; the root also has `X/Y/Zposition`.
    pub fn standard_humanoid() -> Skeleton {
        let mut joints: Vec<Joint> = Vec::with_capacity(26);
        let rot = vec![Channel::Zrot, Channel::Xrot, Channel::Yrot];
        let mut add = |name: &str, parent: Option<usize>, off: [f64; 3], end: bool| -> usize {
            let channels = if end {
                vec![]
            } else if parent.is_none() {
                vec![Channel::Xpos, Channel::Ypos, Channel::Zpos, Channel::Zrot, Channel::Xrot, Channel::Yrot]
            } else {
                rot.clone()
            };
            joints.push(Joint {
                name: name.to_string(),
                parent: parent.map(|p| p as u16),
                offset: Vec3::new(off[0], off[1], off[2]),
                channels,
                end_site: end,
            });
            joints.len() - 1
        };
        let hips = add("Hips", None, [0.0, 0.95, 0.0], false);
        let spine = add("Spine", Some(hips), [0.0, 0.10, 0.0], false);
        let chest = add("Chest", Some(spine), [0.0, 0.15, 0.0], false);
        let neck = add("Neck", Some(chest), [0.0, 0.22, 0.0], false);
        let head = add("Head", Some(neck), [0.0, 0.10, 0.0], false);
        add("HeadTop", Some(head), [0.0, 0.18, 0.0], true);
        for (side, sx) in [("Left", 1.0), ("Right", -1.0)] {
            let collar = add(&format!("{side}Collar"), Some(chest), [0.03 * sx, 0.18, 0.0], false);
            let arm = add(&format!("{side}Arm"), Some(collar), [0.15 * sx, 0.02, 0.0], false);
            let fore = add(&format!("{side}ForeArm"), Some(arm), [0.28 * sx, 0.0, 0.0], false);
            let hand = add(&format!("{side}Hand"), Some(fore), [0.25 * sx, 0.0, 0.0], false);
            add(&format!("{side}HandTip"), Some(hand), [0.08 * sx, 0.0, 0.0], true);
        }
        for (side, sx) in [("Left", 1.0), ("Right", -1.0)] {
            let up = add(&format!("{side}UpLeg"), Some(hips), [0.09 * sx, -0.05, 0.0], false);
            let leg = add(&format!("{side}Leg"), Some(up), [0.0, -0.42, 0.0], false);
            let foot = add(&format!("{side}Foot"), Some(leg), [0.0, -0.40, 0.0], false);
            let toe = add(&format!("{side}Toe"), Some(foot), [0.0, -0.07, 0.13], false);
            add(&format!("{side}ToeTip"), Some(toe), [0.0, 0.0, 0.07], true);
        }
        let mut s = Skeleton { name: "standard_humanoid".into(), joints, roles: BTreeMap::new() };
        s.guess_roles();
        s
    }

    /// Builds an animatable skeleton from rest joint positions (e.g. rigging output): joint 0 is
    /// the root (`parents[0] = None`), every other parent index is smaller than the joint's own;
    /// offsets are `rest[j] − rest[parent]`, the root's offset is `rest[0]`, so
    /// [`rest_globals`](Self::rest_globals) reproduces `rest` with identity rotations. Channels:
    /// the root gets `X/Y/Zposition Zrotation Xrotation Yrotation`, every other joint
    /// `Zrotation Xrotation Yrotation`; no end sites. Roles are guessed from the names.
    ///
    /// Errors: mismatched lengths ([`Error::DimensionMismatch`]), no joints, more than 65 535
    /// joints, bad parent order, duplicate names ([`Error::InvalidParameter`] naming the joint),
    /// non-finite positions ([`Error::NonFinite`]).
    pub fn from_joint_positions(names: &[String], parents: &[Option<usize>], rest: &[Pt3]) -> Result<Skeleton> {
        let n = names.len();
        if parents.len() != n {
            return Err(Error::DimensionMismatch { what: "skeleton parents", expected: n, got: parents.len() });
        }
        if rest.len() != n {
            return Err(Error::DimensionMismatch { what: "skeleton rest positions", expected: n, got: rest.len() });
        }
        if n == 0 {
            return Err(Error::InvalidParameter("a skeleton needs at least one joint".into()));
        }
        if n > u16::MAX as usize {
            return Err(Error::InvalidParameter(format!("{n} joints: at most 65535 are supported")));
        }
        let mut seen = std::collections::HashSet::new();
        let mut joints = Vec::with_capacity(n);
        for j in 0..n {
            if !seen.insert(names[j].as_str()) {
                return Err(Error::InvalidParameter(format!("duplicate joint name '{}' (joint {j})", names[j])));
            }
            if !rest[j].iter().all(|c| c.is_finite()) {
                return Err(Error::NonFinite("skeleton rest positions"));
            }
            let offset = match (j, parents[j]) {
                (0, None) => rest[0].coords,
                (0, Some(_)) => {
                    return Err(Error::InvalidParameter("joint 0 must be the root (no parent)".into()));
                }
                (_, None) => {
                    return Err(Error::InvalidParameter(format!(
                        "joint {j} ('{}') has no parent: only joint 0 may be a root",
                        names[j]
                    )));
                }
                (_, Some(p)) if p >= j => {
                    return Err(Error::InvalidParameter(format!(
                        "joint {j} ('{}') has parent {p}: parents must come before their children",
                        names[j]
                    )));
                }
                (_, Some(p)) => rest[j] - rest[p],
            };
            let channels = if j == 0 {
                vec![Channel::Xpos, Channel::Ypos, Channel::Zpos, Channel::Zrot, Channel::Xrot, Channel::Yrot]
            } else {
                vec![Channel::Zrot, Channel::Xrot, Channel::Yrot]
            };
            joints.push(Joint {
                name: names[j].clone(),
                parent: parents[j].map(|p| p as u16),
                offset,
                channels,
                end_site: false,
            });
        }
        let mut s = Skeleton { name: "skeleton".into(), joints, roles: BTreeMap::new() };
        s.guess_roles();
        Ok(s)
    }

    /// Number of joints (end sites included).
    pub fn len(&self) -> usize {
        self.joints.len()
    }

    /// Whether the skeleton has no joints.
    pub fn is_empty(&self) -> bool {
        self.joints.is_empty()
    }

    /// Index of the joint with this exact name.
    pub fn find(&self, name: &str) -> Option<u16> {
        self.joints.iter().position(|j| j.name == name).map(|i| i as u16)
    }

    /// Joint index carrying role `r`, if assigned.
    pub fn role(&self, r: JointRole) -> Option<u16> {
        self.roles.get(&r).copied()
    }

    /// Children of joint `j`, ascending.
    pub fn children(&self, j: usize) -> Vec<usize> {
        (0..self.joints.len()).filter(|&c| self.joints[c].parent.map(|p| p as usize) == Some(j)).collect()
    }

    /// Assigns roles from joint names (replacing any previous roles).
    ///
    /// Names are compared after dropping a namespace prefix (`mixamorig:`), case, `_`, `-`, `.`
    /// and spaces. The table covers the CMU/cgspeed and standard skeletons of motion-graph.md
    /// §2.1 and common exporter spellings (Mixamo, Poser `lShldr`/`lThigh`, …). Spine and chest:
    /// `LowerBack` (CMU) or `Spine` is the spine; `Chest`, `Spine2` or `Spine1` the chest. Collar
    /// vs shoulder: a `LeftShoulder` is the collar when a `LeftArm` also exists (CMU, Mixamo),
    /// otherwise it is the shoulder joint. CMU's `LHipJoint`, `Neck1`, fingers and thumbs get no
    /// role. End sites named `<parent>_End` get the tip roles (`Head_End` → `HeadTop`,
    /// `LeftToeBase_End` → `LeftToeTip`, `LeftHand_End` → `LeftHandTip`). The root role goes
    /// to `Hips`/`Pelvis`, or joint 0 if no such name exists. No joint gets two roles.
    pub fn guess_roles(&mut self) {
        self.roles.clear();
        if self.joints.is_empty() {
            return;
        }
        let names: Vec<String> = self.joints.iter().map(|j| norm_name(&j.name)).collect();
        let has = |n: &str| names.iter().any(|x| x == n);
        let mut table: Vec<(JointRole, Vec<String>)> = Vec::new();
        let s = |v: &[&str]| v.iter().map(|x| x.to_string()).collect::<Vec<_>>();
        table.push((JointRole::Root, s(&["hips", "pelvis", "hip", "root"])));
        table.push((JointRole::Spine, s(&["lowerback", "spine", "abdomen", "spine0", "torso"])));
        table.push((JointRole::Chest, s(&["chest", "upperchest", "spine2", "spine1", "chest1", "thorax"])));
        table.push((JointRole::Neck, s(&["neck", "neck1", "neckbase"])));
        table.push((JointRole::Head, s(&["head"])));
        table.push((JointRole::HeadTop, s(&["headtop", "headend", "headtopend", "headsite", "headtip"])));
        for (side, l) in [("left", "l"), ("right", "r")] {
            let arm_exists = has(&format!("{side}arm"));
            let collar_shoulder: Vec<String> =
                if arm_exists { vec![format!("{side}shoulder"), format!("{l}shoulder")] } else { vec![] };
            let mut collar =
                vec![format!("{side}collar"), format!("{l}collar"), format!("{side}clavicle"), format!("{l}clavicle")];
            collar.extend(collar_shoulder);
            let mut shoulder = vec![format!("{side}arm"), format!("{side}upperarm"), format!("{l}shldr")];
            if !arm_exists {
                shoulder.push(format!("{side}shoulder"));
                shoulder.push(format!("{l}shoulder"));
            }
            shoulder.push(format!("{l}upperarm"));
            let (collar_r, shoulder_r, elbow_r, hand_r, tip_r, hip_r, knee_r, ankle_r, toe_r, toetip_r) =
                if side == "left" {
                    use JointRole::*;
                    (
                        LeftCollar,
                        LeftShoulder,
                        LeftElbow,
                        LeftHand,
                        LeftHandTip,
                        LeftHip,
                        LeftKnee,
                        LeftAnkle,
                        LeftToe,
                        LeftToeTip,
                    )
                } else {
                    use JointRole::*;
                    (
                        RightCollar,
                        RightShoulder,
                        RightElbow,
                        RightHand,
                        RightHandTip,
                        RightHip,
                        RightKnee,
                        RightAnkle,
                        RightToe,
                        RightToeTip,
                    )
                };
            table.push((collar_r, collar));
            table.push((shoulder_r, shoulder));
            table.push((
                elbow_r,
                vec![
                    format!("{side}forearm"),
                    format!("{side}elbow"),
                    format!("{side}lowerarm"),
                    format!("{l}forearm"),
                    format!("{l}elbow"),
                    format!("{l}lowerarm"),
                ],
            ));
            table.push((
                hand_r,
                vec![format!("{side}hand"), format!("{side}wrist"), format!("{l}hand"), format!("{l}wrist")],
            ));
            table.push((
                tip_r,
                vec![
                    format!("{side}handtip"),
                    format!("{side}handend"),
                    format!("{l}handend"),
                    format!("{side}wristend"),
                ],
            ));
            table.push((
                hip_r,
                vec![
                    format!("{side}upleg"),
                    format!("{side}hip"),
                    format!("{side}thigh"),
                    format!("{side}upperleg"),
                    format!("{l}hip"),
                    format!("{l}thigh"),
                    format!("{l}upleg"),
                ],
            ));
            table.push((
                knee_r,
                vec![
                    format!("{side}leg"),
                    format!("{side}knee"),
                    format!("{side}shin"),
                    format!("{side}lowerleg"),
                    format!("{l}knee"),
                    format!("{l}shin"),
                    format!("{l}leg"),
                ],
            ));
            table.push((
                ankle_r,
                vec![format!("{side}foot"), format!("{side}ankle"), format!("{l}foot"), format!("{l}ankle")],
            ));
            table.push((
                toe_r,
                vec![
                    format!("{side}toe"),
                    format!("{side}toebase"),
                    format!("{side}toes"),
                    format!("{l}toe"),
                    format!("{l}toebase"),
                    format!("{l}toes"),
                ],
            ));
            table.push((
                toetip_r,
                vec![
                    format!("{side}toetip"),
                    format!("{side}toeend"),
                    format!("{side}toebaseend"),
                    format!("{side}toesend"),
                    format!("{l}toeend"),
                    format!("{l}toetip"),
                ],
            ));
        }
        let mut used = vec![false; self.joints.len()];
        for (role, cands) in &table {
            'c: for c in cands {
                for (j, n) in names.iter().enumerate() {
                    if n == c && !used[j] {
                        self.roles.insert(*role, j as u16);
                        used[j] = true;
                        break 'c;
                    }
                }
            }
        }
        if !self.roles.contains_key(&JointRole::Root) && !used[0] {
            self.roles.insert(JointRole::Root, 0);
        }
    }

    /// Leg length (m): the vertical drop in the rest pose from the root to the lower of the two
    /// toe joints (roles `LeftToe`/`RightToe`); without toe roles the ankles; without either, the
    /// drop to the lowest joint of the skeleton. Never negative. Used by BVH `Auto` units and to
    /// normalise speeds.
    pub fn leg_length(&self) -> f64 {
        if self.joints.is_empty() {
            return 0.0;
        }
        let g = self.rest_globals();
        let root_y = g[0].translation.y;
        let drop_to = |roles: [JointRole; 2]| -> Option<f64> {
            let ys: Vec<f64> =
                roles.iter().filter_map(|r| self.role(*r)).map(|j| g[j as usize].translation.y).collect();
            ys.into_iter().reduce(f64::min).map(|y| root_y - y)
        };
        let d = drop_to([JointRole::LeftToe, JointRole::RightToe])
            .or_else(|| drop_to([JointRole::LeftAnkle, JointRole::RightAnkle]))
            .unwrap_or_else(|| root_y - g.iter().map(|x| x.translation.y).fold(f64::INFINITY, f64::min));
        d.max(0.0)
    }

    /// The rest pose: the root at its offset (rest position), all rotations identity.
    pub fn rest_pose(&self) -> Pose {
        Pose {
            root_pos: self.joints.first().map(|j| j.offset).unwrap_or_else(Vec3::zeros),
            rot: vec![UnitQuat::identity(); self.joints.len()],
        }
    }

    /// Global (world) transforms of all joints in the rest pose.
    pub fn rest_globals(&self) -> Vec<Iso3> {
        let mut out = vec![Iso3::identity(); self.joints.len()];
        self.globals(&self.rest_pose(), &mut out);
        out
    }

    /// Forward kinematics: global transform of every joint for `pose` (see the module docs for
    /// the composition rule).
    ///
    /// # Panics
    /// If `pose.rot` or `out` does not have one entry per joint (a programming error).
    pub fn globals(&self, pose: &Pose, out: &mut [Iso3]) {
        self.globals_with_extra(pose, None, out);
    }

    /// Forward kinematics with extra per-joint translations (BVH position channels on non-root
    /// joints, added to the offsets; the root's entry is ignored).
    ///
    /// # Panics
    /// If `pose.rot`, `extra` (when given) or `out` does not have one entry per joint.
    pub fn globals_with_extra(&self, pose: &Pose, extra: Option<&[Vec3]>, out: &mut [Iso3]) {
        self.fk(&pose.root_pos, &pose.rot, extra, out);
    }

    /// Forward kinematics on borrowed data (no allocation): `root_pos` is the root's world
    /// position, `rot` the local rotations, `extra` optional per-joint translations added to the
    /// offsets (the root's entry is ignored).
    ///
    /// # Panics
    /// If `rot`, `extra` (when given) or `out` does not have one entry per joint.
    pub fn fk(&self, root_pos: &Vec3, rot: &[UnitQuat], extra: Option<&[Vec3]>, out: &mut [Iso3]) {
        let n = self.joints.len();
        assert_eq!(rot.len(), n, "{} rotations for {n} joints", rot.len());
        assert_eq!(out.len(), n, "output has {} slots for {n} joints", out.len());
        if let Some(e) = extra {
            assert_eq!(e.len(), n, "extra translations: {} for {n} joints", e.len());
        }
        for (j, joint) in self.joints.iter().enumerate() {
            out[j] = match joint.parent {
                None => Iso3::from_parts(na::Translation3::from(*root_pos), rot[j]),
                Some(p) => {
                    let mut t = joint.offset;
                    if let Some(e) = extra {
                        t += e[j];
                    }
                    out[p as usize] * Iso3::from_parts(na::Translation3::from(t), rot[j])
                }
            };
        }
    }

    /// Checks the structural invariants (root first, parents before children, unique names);
    /// returns the first violation as [`Error::InvalidParameter`].
    pub fn validate(&self) -> Result<()> {
        let mut seen = std::collections::HashSet::new();
        for (j, joint) in self.joints.iter().enumerate() {
            match (j, joint.parent) {
                (0, None) => {}
                (0, Some(_)) => return Err(Error::InvalidParameter("joint 0 must be the root".into())),
                (_, None) => {
                    return Err(Error::InvalidParameter(format!("joint {j} ('{}') has no parent", joint.name)))
                }
                (_, Some(p)) if p as usize >= j => {
                    return Err(Error::InvalidParameter(format!("joint {j} ('{}') has parent {p} ≥ {j}", joint.name)));
                }
                _ => {}
            }
            if !seen.insert(joint.name.as_str()) {
                return Err(Error::InvalidParameter(format!("duplicate joint name '{}'", joint.name)));
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn standard_humanoid_layout() {
        let s = Skeleton::standard_humanoid();
        assert_eq!(s.joints.iter().filter(|j| !j.end_site).count(), 21);
        assert_eq!(s.joints.iter().filter(|j| j.end_site).count(), 5);
        s.validate().unwrap();
        let g = s.rest_globals();
        let y: Vec<f64> = g.iter().map(|x| x.translation.y).collect();
        let top = y.iter().cloned().fold(f64::MIN, f64::max);
        let bottom = y.iter().cloned().fold(f64::MAX, f64::min);
        assert!((top - 1.70).abs() < 1e-12, "height {top}");
        assert!((bottom - 0.01).abs() < 1e-12, "toe height {bottom}");
        // Left is +X, facing +Z (toes forward).
        let lh = g[s.role(JointRole::LeftHip).unwrap() as usize].translation.x;
        let rh = g[s.role(JointRole::RightHip).unwrap() as usize].translation.x;
        assert!(lh > 0.0 && rh < 0.0);
        let toe = g[s.role(JointRole::LeftToeTip).unwrap() as usize].translation.z;
        assert!(toe > 0.1);
        // Every role is assigned, each to a distinct joint.
        assert_eq!(s.roles.len(), 26);
        let distinct: std::collections::BTreeSet<u16> = s.roles.values().copied().collect();
        assert_eq!(distinct.len(), 26);
        assert!((s.leg_length() - 0.94).abs() < 1e-12);
        assert_eq!(s.role(JointRole::LeftShoulder), s.find("LeftArm"));
        assert_eq!(s.role(JointRole::LeftCollar), s.find("LeftCollar"));
        assert_eq!(s.role(JointRole::Chest), s.find("Chest"));
    }

    #[test]
    fn cmu_and_other_names() {
        let names = [
            "Hips",
            "LHipJoint",
            "LeftUpLeg",
            "LeftLeg",
            "LeftFoot",
            "LeftToeBase",
            "LowerBack",
            "Spine",
            "Spine1",
            "Neck",
            "Neck1",
            "Head",
            "LeftShoulder",
            "LeftArm",
            "LeftForeArm",
            "LeftHand",
            "LThumb",
        ];
        let joints = names
            .iter()
            .enumerate()
            .map(|(i, n)| Joint {
                name: n.to_string(),
                parent: if i == 0 { None } else { Some(0) },
                offset: Vec3::zeros(),
                channels: vec![],
                end_site: false,
            })
            .collect();
        let mut s = Skeleton { name: "cmu".into(), joints, roles: BTreeMap::new() };
        s.guess_roles();
        let r = |role| s.role(role).map(|j| s.joints[j as usize].name.as_str());
        assert_eq!(r(JointRole::Root), Some("Hips"));
        assert_eq!(r(JointRole::Spine), Some("LowerBack"));
        assert_eq!(r(JointRole::Chest), Some("Spine1"));
        assert_eq!(r(JointRole::Neck), Some("Neck"));
        assert_eq!(r(JointRole::LeftCollar), Some("LeftShoulder"));
        assert_eq!(r(JointRole::LeftShoulder), Some("LeftArm"));
        assert_eq!(r(JointRole::LeftElbow), Some("LeftForeArm"));
        assert_eq!(r(JointRole::LeftHip), Some("LeftUpLeg"));
        assert_eq!(r(JointRole::LeftKnee), Some("LeftLeg"));
        assert_eq!(r(JointRole::LeftAnkle), Some("LeftFoot"));
        assert_eq!(r(JointRole::LeftToe), Some("LeftToeBase"));
        assert!(s
            .roles
            .values()
            .all(|&j| !["LHipJoint", "Neck1", "LThumb"].contains(&s.joints[j as usize].name.as_str())));
        // Exporters where LeftShoulder is the shoulder itself (no LeftArm), with a namespace.
        s.joints[12].name = "mixamorig:LeftShoulder".into();
        s.joints[13].name = "x".into();
        s.joints[14].name = "l_elbow".into();
        s.guess_roles();
        assert_eq!(s.role(JointRole::LeftShoulder), Some(12));
        assert_eq!(s.role(JointRole::LeftElbow), Some(14));
        assert_eq!(s.role(JointRole::LeftCollar), None);
    }

    #[test]
    fn from_joint_positions_reproduces_rest() {
        let names: Vec<String> = ["pelvis", "spine", "lthigh", "lknee"].iter().map(|s| s.to_string()).collect();
        let parents = [None, Some(0), Some(0), Some(2)];
        let rest =
            [Pt3::new(0.0, 1.0, 0.0), Pt3::new(0.0, 1.2, 0.0), Pt3::new(0.1, 0.9, 0.0), Pt3::new(0.1, 0.5, 0.05)];
        let s = Skeleton::from_joint_positions(&names, &parents, &rest).unwrap();
        let g = s.rest_globals();
        for (gi, r) in g.iter().zip(&rest) {
            assert!((gi.translation.vector - r.coords).norm() < 1e-15);
        }
        assert_eq!(s.role(JointRole::Root), Some(0));
        assert_eq!(s.role(JointRole::LeftHip), Some(2));
        assert_eq!(s.role(JointRole::LeftKnee), Some(3));
        // Errors name the problem.
        let bad = Skeleton::from_joint_positions(&names, &[None, Some(0), Some(3), Some(2)], &rest);
        assert!(matches!(bad, Err(Error::InvalidParameter(m)) if m.contains("lthigh")));
        let bad = Skeleton::from_joint_positions(&names, &parents[..3], &rest);
        assert!(matches!(bad, Err(Error::DimensionMismatch { .. })));
        let dup: Vec<String> = ["a", "a"].iter().map(|s| s.to_string()).collect();
        let bad = Skeleton::from_joint_positions(&dup, &[None, Some(0)], &rest[..2]);
        assert!(matches!(bad, Err(Error::InvalidParameter(m)) if m.contains("duplicate")));
        let nan = [Pt3::new(f64::NAN, 0.0, 0.0)];
        assert!(matches!(Skeleton::from_joint_positions(&names[..1], &[None], &nan), Err(Error::NonFinite(_))));
        assert!(Skeleton::from_joint_positions(&[], &[], &[]).is_err());
    }

    #[test]
    fn forward_kinematics_by_hand() {
        // Root at (1,0,0) rotated 90° about z; child offset (1,0,0) rotated 90° about y.
        let names: Vec<String> = ["a", "b", "c"].iter().map(|s| s.to_string()).collect();
        let rest = [Pt3::new(0.0, 0.0, 0.0), Pt3::new(1.0, 0.0, 0.0), Pt3::new(1.0, 0.0, 1.0)];
        let s = Skeleton::from_joint_positions(&names, &[None, Some(0), Some(1)], &rest).unwrap();
        let h = std::f64::consts::FRAC_PI_2;
        let pose = Pose {
            root_pos: Vec3::new(1.0, 0.0, 0.0),
            rot: vec![
                UnitQuat::from_axis_angle(&Vec3::z_axis(), h),
                UnitQuat::from_axis_angle(&Vec3::y_axis(), h),
                UnitQuat::identity(),
            ],
        };
        let mut g = vec![Iso3::identity(); 3];
        s.globals(&pose, &mut g);
        // b = root + Rz(90)·(1,0,0) = (1,1,0); c = b + Rz(90)·Ry(90)·(0,0,1) = b + Rz(90)·(1,0,0) = (1,2,0).
        assert!((g[1].translation.vector - Vec3::new(1.0, 1.0, 0.0)).norm() < 1e-15);
        assert!((g[2].translation.vector - Vec3::new(1.0, 2.0, 0.0)).norm() < 1e-15);
    }

    #[test]
    fn channel_names() {
        assert_eq!(Channel::from_bvh_name("xPOSITION"), Some(Channel::Xpos));
        assert_eq!(Channel::from_bvh_name("Zrotation"), Some(Channel::Zrot));
        assert_eq!(Channel::from_bvh_name("Wrotation"), None);
        for c in [Channel::Xpos, Channel::Yrot] {
            assert_eq!(Channel::from_bvh_name(c.bvh_name()), Some(c));
        }
        for r in JointRole::ALL {
            assert_eq!(r.mirror().mirror(), r);
        }
    }
}

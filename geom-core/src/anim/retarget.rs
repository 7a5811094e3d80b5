//! Motion retargeting by joint roles: a clip on one skeleton (a CMU BVH with 31 joints, Mixamo
//! names, the toolkit's own) played on another skeleton (a rig), with different rest poses (T
//! against A pose), bone lengths, proportions and hierarchies ([`retarget`]); foot contacts
//! detected on the source are kept planted on the target with the analytic two-bone IK of
//! [`crate::anim::ik`]; the figures that judge the result ([`RetargetMetrics`]).
//!
//! # Method
//! Per frame, the source's world joint positions give, for every pair of role joints that the
//! target connects (a target joint and its nearest descendant carrying a role the source also
//! has), a direction in world space. Every target joint gets the world rotation that turns its
//! rest bone directions onto those source directions: the best rotation in the least-squares
//! sense (Wahba's problem, solved by SVD; Markley 1988) for a joint with several such bones (the
//! pelvis, the chest), and the smallest rotation from its parent's rotated frame for a joint with
//! one (a limb joint keeps the twist of its parent). Because only directions are transferred,
//! rest poses never have to match and bone lengths stay the target's own. The target's pelvis
//! (role `Root`) follows the source's: horizontal displacement scaled by the ratio of standing
//! heights `k = h_target / h_source`, height above the floor by the ratio of leg lengths (so the
//! legs reach the floor).
//!
//! Contacts (`Motion::detect_contacts` on the source, ankle and toe points of both feet) are
//! locked on the target: during a run of contact frames the point stays where it was on the run's
//! first frame; the thigh and knee rotations are re-solved by [`two_bone`] (pole: the knee's
//! unconstrained direction), the ankle keeps the source's foot orientation, and a locked toe turns
//! the ankle towards it. Targets beyond the leg's reach are clamped by the IK (the figure then
//! shows the residual slide).
//!
//! # Figures
//! - [`foot_skate_cm_s`]: mean horizontal speed of the target's foot points over the source's
//!   contact frames (cm/s; metres in, so the target must be in metres).
//! - [`root_path_rel_err`]: `|L_target / (L_source · h_target / h_source) − 1|`, with `L` the
//!   path length of the `Root` joint and `h` the standing heights.
//!
//! ```
//! use std::sync::Arc;
//! use geom_core::anim::retarget::{retarget, RetargetOptions};
//! use geom_core::anim::{Motion, Skeleton};
//! let src = Skeleton::standard_humanoid();
//! let clip = Motion::from_poses(Arc::new(src.clone()), 1.0 / 30.0, &vec![src.rest_pose(); 10]).unwrap();
//! // A target 20 % larger: the same motion, scaled.
//! let mut big = src.clone();
//! for j in &mut big.joints { j.offset *= 1.2; }
//! let r = retarget(&clip, &big, &RetargetOptions::default()).unwrap();
//! assert_eq!(r.motion.len(), 10);
//! assert!((r.height_ratio - 1.2).abs() < 1e-9);
//! ```

use std::collections::BTreeSet;
use std::sync::Arc;

use nalgebra::Matrix3;

use super::ik::two_bone;
use super::motion::{ContactParams, FrameLabels, Motion};
use super::skeleton::{JointRole, Pose, Skeleton};
use crate::error::{Error, Result};
use crate::math::{Pt3, UnitQuat, Vec3};

/// Options of [`retarget`].
#[derive(Clone, Debug, PartialEq)]
pub struct RetargetOptions {
    /// Contact detection on the source (m, m/s; `Motion::detect_contacts`).
    pub contacts: ContactParams,
    /// Keep contacts planted with two-bone IK.
    pub foot_lock: bool,
    /// Standing height of the source (m); default [`standing_height`] of its skeleton.
    pub source_height: Option<f64>,
    /// Standing height of the target (m); default [`standing_height`] of its skeleton. A rig
    /// knows its character's height better (the mesh's extent): pass it.
    pub target_height: Option<f64>,
}

impl Default for RetargetOptions {
    fn default() -> Self {
        Self { contacts: ContactParams::default(), foot_lock: true, source_height: None, target_height: None }
    }
}

/// The result of [`retarget`].
#[derive(Clone, Debug)]
pub struct Retargeted {
    /// The motion on the target skeleton (same frame count and frame time as the source); its
    /// labels carry the source's contact flags.
    pub motion: Motion,
    /// The source clip with its detected contacts.
    pub source: Motion,
    /// `h_target / h_source`: scale of the horizontal root motion.
    pub height_ratio: f64,
    /// Target over source leg length: scale of the pelvis height above the floor.
    pub leg_ratio: f64,
    /// Source and target standing heights (m).
    pub heights: (f64, f64),
    /// Roles used: (role, source joint, target joint).
    pub mapped: Vec<(JointRole, usize, usize)>,
    /// Frames where the IK could not reach a locked point (count over both feet).
    pub unreachable: usize,
}

/// The roles a skeleton needs to be retargeted (to or from): pelvis and both legs.
pub const LEG_ROLES: [JointRole; 7] = [
    JointRole::Root,
    JointRole::LeftHip,
    JointRole::LeftKnee,
    JointRole::LeftAnkle,
    JointRole::RightHip,
    JointRole::RightKnee,
    JointRole::RightAnkle,
];

/// Standing height of a skeleton (m): the vertical extent of its rest-pose joints (end sites
/// included).
pub fn standing_height(s: &Skeleton) -> f64 {
    let g = s.rest_globals();
    let ys: Vec<f64> = g.iter().map(|x| x.translation.y).collect();
    crate::stats::max(&ys) - crate::stats::min(&ys)
}

fn check_legs(s: &Skeleton, what: &str) -> Result<()> {
    let missing: Vec<String> = LEG_ROLES.iter().filter(|r| s.role(**r).is_none()).map(|r| format!("{r:?}")).collect();
    if missing.is_empty() {
        Ok(())
    } else {
        Err(Error::InvalidParameter(format!(
            "{what} skeleton '{}' has no recognisable legs: no joint for {} (joint names are matched to roles; \
             give roles explicitly)",
            s.name,
            missing.join(", ")
        )))
    }
}

/// Best rotation taking the unit vectors `from[k]` onto `to[k]` (weights `w[k]`): Wahba's problem
/// by SVD of `B = Σ w t fᵀ`, with the reflection removed.
fn wahba(from: &[Vec3], to: &[Vec3], w: &[f64]) -> Option<UnitQuat> {
    let mut b = Matrix3::zeros();
    for k in 0..from.len() {
        b += w[k] * to[k] * from[k].transpose();
    }
    let svd = b.svd(true, true);
    let (u, vt) = (svd.u?, svd.v_t?);
    let d = (u * vt).determinant().signum();
    let r = u * Matrix3::from_diagonal(&Vec3::new(1.0, 1.0, d)) * vt;
    let q = UnitQuat::from_matrix(&r);
    q.coords.iter().all(|c| c.is_finite()).then_some(q)
}

/// Smallest rotation turning `a` onto `b` (identity for zero vectors; a half turn about any
/// perpendicular for opposite ones).
fn swing(a: &Vec3, b: &Vec3) -> UnitQuat {
    if a.norm() < 1e-12 || b.norm() < 1e-12 {
        return UnitQuat::identity();
    }
    UnitQuat::rotation_between(a, b).unwrap_or_else(|| {
        let k = if a.x.abs() < 0.9 { Vec3::x() } else { Vec3::y() };
        UnitQuat::from_axis_angle(&nalgebra::Unit::new_normalize(a.cross(&k)), std::f64::consts::PI)
    })
}

/// Per target joint: the bones to match, `(target descendant, source joint of the joint's role,
/// source joint of the descendant's role)`.
type Bones = Vec<Vec<(usize, usize, usize)>>;

fn bones(src: &Skeleton, tgt: &Skeleton) -> (Bones, Vec<(JointRole, usize, usize)>) {
    let role_of = |s: &Skeleton, j: usize| s.roles.iter().find(|(_, &v)| v as usize == j).map(|(r, _)| *r);
    let src_of = |j: usize| role_of(tgt, j).and_then(|r| src.role(r)).map(|x| x as usize);
    let n = tgt.len();
    let mut out = vec![Vec::new(); n];
    let mut mapped = Vec::new();
    for (j, out_j) in out.iter_mut().enumerate() {
        if let (Some(r), Some(s)) = (role_of(tgt, j), src_of(j)) {
            mapped.push((r, s, j));
        }
        let Some(sj) = src_of(j) else { continue };
        // Nearest mapped descendant along every child's subtree (breadth first, one per child).
        for c in tgt.children(j) {
            let mut queue = vec![c];
            while let Some(x) = queue.first().copied() {
                queue.remove(0);
                if let Some(sx) = src_of(x) {
                    out_j.push((x, sj, sx));
                    break;
                }
                queue.extend(tgt.children(x));
            }
        }
    }
    (out, mapped)
}

/// Retargets `src` onto `tgt` (see the module docs). Both skeletons need the roles of the pelvis
/// and both legs ([`LEG_ROLES`]); errors name the skeleton and the missing roles. Lengths in
/// metres; the source's contacts are detected here (its labels are replaced).
pub fn retarget(src: &Motion, tgt: &Skeleton, o: &RetargetOptions) -> Result<Retargeted> {
    check_legs(&src.skeleton, "source")?;
    check_legs(tgt, "target")?;
    tgt.validate()?;
    if src.is_empty() {
        return Err(Error::InvalidParameter("the source clip has no frames".into()));
    }
    let hs = o.source_height.unwrap_or_else(|| standing_height(&src.skeleton));
    let ht = o.target_height.unwrap_or_else(|| standing_height(tgt));
    let (ls, lt) = (src.skeleton.leg_length(), tgt.leg_length());
    for (what, v) in
        [("source height", hs), ("target height", ht), ("source leg length", ls), ("target leg length", lt)]
    {
        if !(v > 0.0 && v.is_finite()) {
            return Err(Error::InvalidParameter(format!("retarget: {what} = {v} m must be positive")));
        }
    }
    let (k, kv) = (ht / hs, lt / ls);
    let mut source = src.clone();
    source.detect_contacts(&o.contacts);
    let (bones, mapped) = bones(&src.skeleton, tgt);
    let nt = tgt.len();
    let ns = src.n_joints();
    let rest: Vec<Pt3> = tgt.rest_globals().iter().map(|g| Pt3::from(g.translation.vector)).collect();
    let role = |s: &Skeleton, r: JointRole| s.role(r).map(|x| x as usize).expect("checked by check_legs");
    let (s_root, t_root) = (role(&src.skeleton, JointRole::Root), role(tgt, JointRole::Root));
    // Source floor: the lowest foot point over the clip (ankles, toes).
    let feet_s: Vec<usize> = [JointRole::LeftAnkle, JointRole::RightAnkle, JointRole::LeftToe, JointRole::RightToe]
        .iter()
        .filter_map(|r| src.skeleton.role(*r).map(|x| x as usize))
        .collect();
    let mut ps = vec![Pt3::origin(); ns];
    let mut src_pos: Vec<Vec<Pt3>> = Vec::with_capacity(src.len());
    for f in 0..src.len() {
        src.joint_positions(f, &mut ps);
        src_pos.push(ps.clone());
    }
    let floor_s = crate::stats::min(&src_pos.iter().flat_map(|p| feet_s.iter().map(|&j| p[j].y)).collect::<Vec<_>>());
    let feet_t: Vec<usize> = [JointRole::LeftAnkle, JointRole::RightAnkle, JointRole::LeftToe, JointRole::RightToe]
        .iter()
        .filter_map(|r| tgt.role(*r).map(|x| x as usize))
        .collect();
    let floor_t = crate::stats::min(&feet_t.iter().map(|&j| rest[j].y).collect::<Vec<_>>());
    // World rotations per frame, then positions.
    let mut world_rot: Vec<Vec<UnitQuat>> = Vec::with_capacity(src.len());
    let mut root_pos: Vec<Vec3> = Vec::with_capacity(src.len());
    for p in &src_pos {
        let mut r = vec![UnitQuat::identity(); nt];
        for j in 0..nt {
            let parent = tgt.joints[j].parent.map(|x| r[x as usize]).unwrap_or_else(UnitQuat::identity);
            let b = &bones[j];
            r[j] = match b.len() {
                0 => parent,
                1 => {
                    let (d, s0, s1) = b[0];
                    swing(&(parent * (rest[d] - rest[j])), &(p[s1] - p[s0])) * parent
                }
                _ => {
                    let from: Vec<Vec3> = b.iter().map(|&(d, _, _)| (rest[d] - rest[j]).normalize()).collect();
                    let to: Vec<Vec3> = b.iter().map(|&(_, s0, s1)| (p[s1] - p[s0]).normalize()).collect();
                    let w = vec![1.0; b.len()];
                    if from.iter().chain(&to).all(|v| v.iter().all(|c| c.is_finite())) {
                        wahba(&from, &to, &w).unwrap_or(parent)
                    } else {
                        parent
                    }
                }
            };
        }
        // Pelvis target: horizontal × k, height above the floor × leg ratio.
        let sp = p[s_root];
        let want = Vec3::new(k * sp.x, floor_t + kv * (sp.y - floor_s), k * sp.z);
        let pos = fk_positions(tgt, &rest, &r, &Vec3::zeros());
        root_pos.push(want - pos[t_root].coords);
        world_rot.push(r);
    }
    let mut unreachable = 0;
    if o.foot_lock {
        for side in [Side::Left, Side::Right] {
            unreachable += lock_foot(tgt, &rest, &source.labels, side, &mut world_rot, &root_pos);
        }
    }
    // Local rotations from world rotations.
    let poses: Vec<Pose> = world_rot
        .iter()
        .zip(&root_pos)
        .map(|(r, rp)| Pose {
            root_pos: *rp,
            rot: (0..nt)
                .map(|j| match tgt.joints[j].parent {
                    Some(p) => r[p as usize].inverse() * r[j],
                    None => r[j],
                })
                .collect(),
        })
        .collect();
    let mut motion = Motion::from_poses(Arc::new(tgt.clone()), src.frame_time, &poses)?;
    motion.labels.contacts = source.labels.contacts.clone();
    motion.fix_hemispheres();
    Ok(Retargeted { motion, source, height_ratio: k, leg_ratio: kv, heights: (hs, ht), mapped, unreachable })
}

/// World joint positions from world rotations (rest rotations are the identity): the root at
/// `root_pos`, then `x_j = x_p + R_p · (rest_j − rest_p)`.
fn fk_positions(s: &Skeleton, rest: &[Pt3], r: &[UnitQuat], root_pos: &Vec3) -> Vec<Pt3> {
    let mut x = vec![Pt3::origin(); s.len()];
    for j in 0..s.len() {
        x[j] = match s.joints[j].parent {
            Some(p) => x[p as usize] + r[p as usize] * (rest[j] - rest[p as usize]),
            None => Pt3::from(*root_pos),
        };
    }
    x
}

#[derive(Clone, Copy)]
enum Side {
    Left,
    Right,
}

/// Locks one foot's contact points on the target (see the module docs); returns the number of
/// frames where a locked point was out of reach.
fn lock_foot(
    tgt: &Skeleton,
    rest: &[Pt3],
    labels: &FrameLabels,
    side: Side,
    world_rot: &mut [Vec<UnitQuat>],
    root_pos: &[Vec3],
) -> usize {
    let (hip, knee, ankle, toe, ab, tb) = match side {
        Side::Left => (
            JointRole::LeftHip,
            JointRole::LeftKnee,
            JointRole::LeftAnkle,
            JointRole::LeftToe,
            FrameLabels::L_ANKLE,
            FrameLabels::L_TOE,
        ),
        Side::Right => (
            JointRole::RightHip,
            JointRole::RightKnee,
            JointRole::RightAnkle,
            JointRole::RightToe,
            FrameLabels::R_ANKLE,
            FrameLabels::R_TOE,
        ),
    };
    let j = |r: JointRole| tgt.role(r).map(|x| x as usize);
    let (Some(h), Some(kn), Some(a)) = (j(hip), j(knee), j(ankle)) else { return 0 };
    let t = j(toe).filter(|&t| tgt.joints[t].parent.map(|p| p as usize) == Some(a));
    let (l1, l2) = ((rest[kn] - rest[h]).norm(), (rest[a] - rest[kn]).norm());
    let flag = |f: usize, bit: u8| labels.contacts.get(f).is_some_and(|c| c & bit != 0);
    let mut ankle_lock: Option<Pt3> = None;
    let mut toe_lock: Option<Pt3> = None;
    let mut miss = 0;
    for f in 0..world_rot.len() {
        let x = fk_positions(tgt, rest, &world_rot[f], &root_pos[f]);
        ankle_lock = if flag(f, ab) { Some(ankle_lock.unwrap_or(x[a])) } else { None };
        toe_lock = match t {
            Some(ti) if flag(f, tb) => Some(toe_lock.unwrap_or(x[ti])),
            _ => None,
        };
        let goal = match (ankle_lock, toe_lock, t) {
            (Some(al), _, _) => al,
            (None, Some(tl), Some(ti)) => tl - (x[ti] - x[a]),
            _ => continue,
        };
        let r = &mut world_rot[f];
        let pole = x[kn] - Pt3::from((x[h].coords + x[a].coords) * 0.5);
        let (km, am) = two_bone(&x[h], l1, l2, &goal, &pole);
        if (am - goal).norm() > 1e-6 * (l1 + l2) {
            miss += 1;
        }
        r[h] = swing(&(x[kn] - x[h]), &(km - x[h])) * r[h];
        r[kn] = swing(&(x[a] - x[kn]), &(am - km)) * r[kn];
        // Ankle keeps its world rotation (the source's foot orientation) unless the toe is locked.
        if let (Some(tl), Some(ti)) = (toe_lock, t) {
            let cur = r[a] * (rest[ti] - rest[a]);
            r[a] = swing(&cur, &(tl - am)) * r[a];
        }
    }
    miss
}

/// The set of contact points (role, flag bit) of both feet.
const CONTACT_POINTS: [(JointRole, u8); 4] = [
    (JointRole::LeftAnkle, FrameLabels::L_ANKLE),
    (JointRole::LeftToe, FrameLabels::L_TOE),
    (JointRole::RightAnkle, FrameLabels::R_ANKLE),
    (JointRole::RightToe, FrameLabels::R_TOE),
];

/// Mean horizontal speed (cm/s) of `m`'s foot points (roles of [`CONTACT_POINTS`]) over the
/// `(point, frame)` pairs where `contacts` flags the point on that frame and the previous one;
/// NaN when there is no such pair. Positions in metres.
pub fn foot_skate_cm_s(m: &Motion, contacts: &FrameLabels) -> f64 {
    let s = &m.skeleton;
    let pts: Vec<(usize, u8)> =
        CONTACT_POINTS.iter().filter_map(|(r, b)| s.role(*r).map(|j| (j as usize, *b))).collect();
    let flag = |f: usize| contacts.contacts.get(f).copied().unwrap_or(0);
    let mut prev = vec![Pt3::origin(); m.n_joints()];
    let mut cur = prev.clone();
    let (mut slide, mut pairs) = (0.0, 0usize);
    for f in 0..m.len() {
        m.joint_positions(f, &mut cur);
        if f > 0 {
            for &(j, b) in &pts {
                if flag(f) & b != 0 && flag(f - 1) & b != 0 {
                    let d = cur[j] - prev[j];
                    slide += d.x.hypot(d.z);
                    pairs += 1;
                }
            }
        }
        std::mem::swap(&mut prev, &mut cur);
    }
    if pairs == 0 {
        return f64::NAN;
    }
    100.0 * slide / (pairs as f64 * m.frame_time)
}

/// Path length (m) of the `Root`-role joint (joint 0 without one) over the clip.
pub fn root_path_length(m: &Motion) -> f64 {
    let j = m.skeleton.role(JointRole::Root).map(|x| x as usize).unwrap_or(0);
    let mut x = vec![Pt3::origin(); m.n_joints()];
    let mut last: Option<Pt3> = None;
    let mut len = 0.0;
    for f in 0..m.len() {
        m.joint_positions(f, &mut x);
        if let Some(l) = last {
            len += (x[j] - l).norm();
        }
        last = Some(x[j]);
    }
    len
}

/// `|L_target / (L_source · h_target / h_source) − 1|` (NaN when the source root does not move).
pub fn root_path_rel_err(source: &Motion, target: &Motion, h_source: f64, h_target: f64) -> f64 {
    let ls = root_path_length(source);
    if ls.is_nan() || ls <= 0.0 {
        return f64::NAN;
    }
    (root_path_length(target) / (ls * h_target / h_source) - 1.0).abs()
}

/// The figures of a retargeting.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RetargetMetrics {
    /// [`foot_skate_cm_s`] of the target on the source's contact frames (cm/s).
    pub foot_skate_cm_s: f64,
    /// The same figure of the source itself (its own sliding while flagged in contact).
    pub source_foot_skate_cm_s: f64,
    /// [`root_path_rel_err`] with the heights used for the scaling.
    pub root_path_rel_err: f64,
    /// Contact (point, frame) flags on the source.
    pub contact_flags: usize,
}

impl Retargeted {
    /// The figures of this retargeting.
    pub fn metrics(&self) -> RetargetMetrics {
        let labels = &self.source.labels;
        let contact_flags = labels.contacts.iter().map(|c| c.count_ones() as usize).sum();
        RetargetMetrics {
            foot_skate_cm_s: foot_skate_cm_s(&self.motion, labels),
            source_foot_skate_cm_s: foot_skate_cm_s(&self.source, labels),
            root_path_rel_err: root_path_rel_err(&self.source, &self.motion, self.heights.0, self.heights.1),
            contact_flags,
        }
    }
}

/// Roles of `s` that have no joint (diagnostics for error messages).
pub fn missing_roles(s: &Skeleton, roles: &[JointRole]) -> BTreeSet<JointRole> {
    roles.iter().copied().filter(|r| s.role(*r).is_none()).collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::anim::synth;

    fn walk() -> Motion {
        synth::presets::library(synth::presets::Preset::WalkTest, 1, (90, 90), 30.0, 7).remove(0)
    }

    #[test]
    fn same_skeleton_round_trip_keeps_the_pose() {
        let m = walk();
        let r = retarget(&m, &m.skeleton, &RetargetOptions { foot_lock: false, ..Default::default() }).unwrap();
        assert_eq!((r.height_ratio, r.leg_ratio), (1.0, 1.0));
        let root = m.skeleton.role(JointRole::Root).unwrap() as usize;
        let (mut a, mut b) = (vec![Pt3::origin(); m.n_joints()], vec![Pt3::origin(); m.n_joints()]);
        let mut dy = None;
        for f in (0..m.len()).step_by(7) {
            m.joint_positions(f, &mut a);
            r.motion.joint_positions(f, &mut b);
            // The pelvis follows horizontally; its height is off by one constant (the floors).
            assert!((a[root].x - b[root].x).abs() < 1e-9 && (a[root].z - b[root].z).abs() < 1e-9);
            let d = b[root].y - a[root].y;
            assert!((d - *dy.get_or_insert(d)).abs() < 1e-9);
            for j in r.mapped.iter().map(|&(_, _, t)| t) {
                let (x, y) = (a[j] - a[root], b[j] - b[root]);
                assert!((x - y).norm() < 1e-6, "frame {f} joint {}: {x} vs {y}", m.skeleton.joints[j].name);
            }
        }
        let mm = r.metrics();
        assert!(mm.root_path_rel_err < 1e-9, "{mm:?}");
    }

    #[test]
    fn scaled_a_pose_target_plants_its_feet() {
        // Target: the same humanoid 20 % smaller with arms hanging 45° down (an A pose).
        let m = walk();
        let mut t = (*m.skeleton).clone();
        for j in &mut t.joints {
            j.offset *= 0.8;
        }
        for (arm, s) in [("LeftArm", 1.0), ("RightArm", -1.0)] {
            let j = t.find(arm).unwrap() as usize;
            for c in t.children(j) {
                let l = t.joints[c].offset.norm();
                t.joints[c].offset = Vec3::new(s * l * 0.707, -l * 0.707, 0.0);
            }
        }
        let free = retarget(&m, &t, &RetargetOptions { foot_lock: false, ..Default::default() }).unwrap();
        let locked = retarget(&m, &t, &RetargetOptions::default()).unwrap();
        let (mf, ml) = (free.metrics(), locked.metrics());
        assert!(ml.contact_flags > 0);
        assert!(ml.foot_skate_cm_s <= 2.0 && ml.foot_skate_cm_s <= mf.foot_skate_cm_s, "{mf:?} {ml:?}");
        assert!(ml.root_path_rel_err <= 0.05, "{ml:?}");
        assert_eq!(locked.unreachable, 0);
        // The hands of the A-pose target follow the source's arm directions (T pose at rest).
        let mut a = vec![Pt3::origin(); m.n_joints()];
        let mut b = a.clone();
        m.joint_positions(10, &mut a);
        locked.motion.joint_positions(10, &mut b);
        let (e, h) = (
            m.skeleton.role(JointRole::LeftElbow).unwrap() as usize,
            m.skeleton.role(JointRole::LeftHand).unwrap() as usize,
        );
        let (ds, dt) = ((a[h] - a[e]).normalize(), (b[h] - b[e]).normalize());
        assert!(ds.dot(&dt) > 1.0 - 1e-9, "{ds} vs {dt}");
    }

    #[test]
    fn skeletons_without_legs_are_refused() {
        let m = walk();
        let mut t = (*m.skeleton).clone();
        t.roles.remove(&JointRole::LeftKnee);
        let e = retarget(&m, &t, &RetargetOptions::default()).unwrap_err();
        assert!(e.to_string().contains("no recognisable legs") && e.to_string().contains("LeftKnee"), "{e}");
    }
}

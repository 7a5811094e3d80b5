//! Per-frame pose of the synthesiser (motion-graph.md §3.13.2 steps 3–7, 9–11): feet from the
//! stance plan, pelvis (height limited by leg reach), trunk, arms, band-limited noise, then legs
//! (and the right arm when reaching) by analytic two-bone IK.

use super::plan::{Plan, Sample, Stance};
use super::{SynthStyle, NEEDED_ROLES};
use crate::anim::ik::two_bone;
use crate::anim::motion::FrameLabels;
use crate::anim::skeleton::{JointRole, Pose, Skeleton};
use crate::math::{axis_quat, quat_exp, smoothstep, wrap_angle, Iso3, Mat3, Planar, Pt3, UnitQuat, Vec3};
use crate::rng::Rng;
use std::f64::consts::{PI, TAU};

/// Heel rise at the end of a stance (rad): the foot pivots about the fixed toe joint.
const TOE_OFF: f64 = 25.0 * PI / 180.0;
/// Fraction of the full leg length the pelvis height allows (§3.13.2 step 4).
const REACH: f64 = 0.995;

/// Joint indices and rest geometry the synthesiser needs.
pub(super) struct Rig {
    nj: usize,
    root: usize,
    spine: usize,
    chest: usize,
    neck: usize,
    head: usize,
    collar: [usize; 2],
    shoulder: [usize; 2],
    elbow: [usize; 2],
    hand: [usize; 2],
    hip: [usize; 2],
    knee: [usize; 2],
    ankle: [usize; 2],
    toe: [usize; 2],
    /// Hip joint position relative to the root in the root's frame (rest chain).
    hip_off: [Vec3; 2],
    /// Thigh and shin bone vectors (rest offsets of the knee and ankle joints).
    thigh: [Vec3; 2],
    shin: [Vec3; 2],
    /// Ankle → toe rest offset.
    foot: [Vec3; 2],
    /// Upper arm and forearm bone vectors (rest offsets of elbow and hand).
    upper: [Vec3; 2],
    fore: [Vec3; 2],
    /// Parent index and rest offset of every joint (forward kinematics).
    parents: Vec<Option<u16>>,
    offsets: Vec<Vec3>,
    /// Rest heights of the root and of the ankle joints (m).
    root_h: f64,
    ankle_h: [f64; 2],
}

impl Rig {
    /// The rig of `s`, or `None` if a role of [`NEEDED_ROLES`] is missing.
    pub fn new(s: &Skeleton) -> Option<Rig> {
        for &r in NEEDED_ROLES {
            s.role(r)?;
        }
        let g = |r: JointRole| s.role(r).map(|j| j as usize);
        let pair = |l: JointRole, r: JointRole| -> Option<[usize; 2]> { Some([g(l)?, g(r)?]) };
        let rest = s.rest_globals();
        let root = g(JointRole::Root)?;
        let hip = pair(JointRole::LeftHip, JointRole::RightHip)?;
        let knee = pair(JointRole::LeftKnee, JointRole::RightKnee)?;
        let ankle = pair(JointRole::LeftAnkle, JointRole::RightAnkle)?;
        let toe = pair(JointRole::LeftToe, JointRole::RightToe)?;
        let elbow = pair(JointRole::LeftElbow, JointRole::RightElbow)?;
        let hand = pair(JointRole::LeftHand, JointRole::RightHand)?;
        let shoulder = pair(JointRole::LeftShoulder, JointRole::RightShoulder)?;
        let pos = |j: usize| rest[j].translation.vector;
        Some(Rig {
            nj: s.joints.len(),
            root,
            spine: g(JointRole::Spine)?,
            chest: g(JointRole::Chest)?,
            neck: g(JointRole::Neck)?,
            head: g(JointRole::Head)?,
            collar: pair(JointRole::LeftCollar, JointRole::RightCollar)?,
            shoulder,
            elbow,
            hand,
            hip,
            knee,
            ankle,
            toe,
            hip_off: hip.map(|h| pos(h) - pos(root)),
            thigh: [0, 1].map(|i| pos(knee[i]) - pos(hip[i])),
            shin: [0, 1].map(|i| pos(ankle[i]) - pos(knee[i])),
            foot: [0, 1].map(|i| pos(toe[i]) - pos(ankle[i])),
            upper: [0, 1].map(|i| pos(elbow[i]) - pos(shoulder[i])),
            fore: [0, 1].map(|i| pos(hand[i]) - pos(elbow[i])),
            parents: s.joints.iter().map(|j| j.parent).collect(),
            offsets: s.joints.iter().map(|j| j.offset).collect(),
            root_h: pos(root).y,
            ankle_h: ankle.map(|a| pos(a).y),
        })
    }
}

impl Rig {
    /// Forward kinematics with the root at `root_pos` (world) and local rotations `rot`.
    fn fk(&self, root_pos: &Vec3, rot: &[UnitQuat], out: &mut [Iso3]) {
        for j in 0..self.nj {
            out[j] = match self.parents[j] {
                Some(p) => out[p as usize] * Iso3::from_parts(nalgebra::Translation3::from(self.offsets[j]), rot[j]),
                None => Iso3::from_parts(nalgebra::Translation3::from(*root_pos), rot[j]),
            };
        }
    }

    /// World rotation of the parent of joint `j` (identity for the root).
    fn parent_rot(&self, g: &[Iso3], j: usize) -> UnitQuat {
        self.parents[j].map_or_else(UnitQuat::identity, |p| g[p as usize].rotation)
    }
}

/// Band-limited rotational noise (§3.13.2 step 11): per joint and axis a sum of three sinusoids
/// with frequencies in [0.2, 2] Hz, random phases, amplitude `a = rms·√(2/3)` (so the sum has the
/// requested RMS).
pub(super) struct Noise {
    /// Per joint × axis × 3: (amplitude rad, angular frequency rad/s, phase).
    terms: Vec<[(f64, f64, f64); 3]>,
}

impl Noise {
    pub fn new(nj: usize, rms_deg: f64, seed: u64) -> Noise {
        let rms = if rms_deg.is_finite() { rms_deg.abs().to_radians() } else { 0.0 };
        let a = rms * (2.0f64 / 3.0).sqrt();
        let mut rng = Rng::stream(seed, 0x0015E);
        let terms = (0..nj * 3).map(|_| [0; 3].map(|_| (a, TAU * rng.range(0.2, 2.0), TAU * rng.f64()))).collect();
        Noise { terms }
    }

    /// Noise rotation of joint `j` at time `t`, scaled by `w`.
    fn rot(&self, j: usize, t: f64, w: f64) -> UnitQuat {
        let mut v = Vec3::zeros();
        for ax in 0..3 {
            if let Some(ts) = self.terms.get(j * 3 + ax) {
                v[ax] = ts.iter().map(|(a, om, ph)| a * (om * t + ph).sin()).sum::<f64>() * w;
            }
        }
        quat_exp(&v)
    }
}

/// A foot's pose at one time.
struct FootPose {
    ankle: Vec3,
    yaw: f64,
    pitch: f64,
    /// (ankle fixed, toe fixed).
    contact: (bool, bool),
    /// How strongly this foot limits the pelvis height: 1 in stance and near lift-off/touch-down,
    /// falling to 0 in mid-swing (a far swing target must not pull the pelvis down).
    limit: f64,
}

/// Ankle of a stance's foot pivoted by `alpha` about its fixed toe.
fn pivot_ankle(rig: &Rig, side: usize, st: &Stance, alpha: f64) -> Vec3 {
    let ry = axis_quat(1, st.yaw);
    let ankle_flat = Vec3::new(st.x, rig.ankle_h[side], st.z);
    let toe = ankle_flat + ry * rig.foot[side];
    if alpha == 0.0 {
        return ankle_flat;
    }
    toe - (ry * axis_quat(0, alpha)) * rig.foot[side]
}

fn foot_pose(rig: &Rig, plan: &Plan, side: usize, t: f64) -> FootPose {
    let sts = &plan.feet[side];
    // First stance ending at or after t.
    let i = sts.partition_point(|s| s.t1 < t);
    if let Some(st) = sts.get(i) {
        if st.t0 <= t {
            let to = st.toe_off();
            let start = st.t1 - to;
            let alpha = if to > 0.0 && t > start { TOE_OFF * smoothstep(start, st.t1, t) } else { 0.0 };
            return FootPose {
                ankle: pivot_ankle(rig, side, st, alpha),
                yaw: st.yaw,
                pitch: alpha,
                contact: (alpha == 0.0, true),
                limit: 1.0,
            };
        }
    }
    // Swing between stance i − 1 (ended) and stance i (not started).
    match (i.checked_sub(1).and_then(|k| sts.get(k)), sts.get(i)) {
        (Some(a), Some(b)) => {
            let a_end = if a.toe_off() > 0.0 { TOE_OFF } else { 0.0 };
            let lift = pivot_ankle(rig, side, a, a_end);
            let land = pivot_ankle(rig, side, b, 0.0);
            let u = ((t - a.t1) / (b.t0 - a.t1)).clamp(0.0, 1.0);
            let s = smoothstep(0.0, 1.0, u);
            // Horizontal progress leaves at the mean swing speed and lands softly:
            // h(u) = u + u² − u³ (h(0) = 0, h(1) = 1, h'(0) = 1, h'(1) = 0).
            let hz = u + u * u - u * u * u;
            let bump = (PI * u).sin();
            let mut ankle = lift + (land - lift) * hz;
            ankle.y = lift.y + (land.y - lift.y) * s;
            ankle.y += b.clear * bump;
            FootPose {
                ankle,
                yaw: a.yaw + wrap_angle(b.yaw - a.yaw) * hz,
                pitch: a_end * (1.0 - s) - 10f64.to_radians() * bump,
                contact: (false, false),
                limit: 1.0 - smoothstep(0.0, 0.2, u) * (1.0 - smoothstep(0.8, 1.0, u)),
            }
        }
        (Some(a), None) => {
            let a_end = if a.toe_off() > 0.0 { TOE_OFF } else { 0.0 };
            FootPose {
                ankle: pivot_ankle(rig, side, a, a_end),
                yaw: a.yaw,
                pitch: a_end,
                contact: (false, false),
                limit: 1.0,
            }
        }
        (None, Some(b)) => FootPose {
            ankle: pivot_ankle(rig, side, b, 0.0),
            yaw: b.yaw,
            pitch: 0.0,
            contact: (false, false),
            limit: 1.0,
        },
        (None, None) => FootPose {
            ankle: Vec3::new(0.0, rig.ankle_h[side], 0.0),
            yaw: 0.0,
            pitch: 0.0,
            contact: (false, false),
            limit: 1.0,
        },
    }
}

/// Rotation mapping the rest bone direction `b` to `d` and the rest forward axis +Z (made
/// orthogonal to `b`) to `fwd` (made orthogonal to `d`): a bone frame with controlled twist.
fn aim(b: &Vec3, d: &Vec3, fwd: &Vec3) -> UnitQuat {
    let basis = |a: &Vec3, f: &Vec3| -> Mat3 {
        let e1 = a.normalize();
        let mut e2 = f - e1 * f.dot(&e1);
        if e2.norm() < 1e-9 {
            e2 = e1.cross(&Vec3::x());
            if e2.norm() < 1e-9 {
                e2 = e1.cross(&Vec3::y());
            }
        }
        let e2 = e2.normalize();
        let e3 = e1.cross(&e2);
        Mat3::from_columns(&[e1, e2, e3])
    };
    let r = basis(d, fwd) * basis(b, &Vec3::z()).transpose();
    UnitQuat::from_matrix(&r)
}

/// Soft minimum `−k ln Σ exp(−x_i/k)` (≤ the minimum, smooth).
fn soft_min(xs: &[f64], k: f64) -> f64 {
    let m = xs.iter().copied().fold(f64::INFINITY, f64::min);
    m - k * xs.iter().map(|x| (-(x - m) / k).exp()).sum::<f64>().ln()
}

/// The pose, contact bits and label bits of time `t`.
pub(super) fn frame(rig: &Rig, plan: &Plan, style: &SynthStyle, noise: &Noise, t: f64) -> (Pose, u8, u64) {
    let s: Sample = plan.at(t);
    let (arm_f, bounce_f, _) = style.effective();
    let feet = [foot_pose(rig, plan, 0, t), foot_pose(rig, plan, 1, t)];
    let ph = TAU * s.phase;
    let walk = 1.0 - s.run;
    let deg = PI / 180.0;

    // Pelvis.
    let yaw_osc = (3.0 + 2.0 * s.v) * deg * ph.sin() * s.gait;
    let roll = 3.0 * deg * ph.sin() * s.gait * (1.0 - 0.5 * s.run);
    let r_root = axis_quat(1, s.psi + yaw_osc) * axis_quat(2, roll) * noise.rot(rig.root, t, 0.3);
    let left = Vec3::new(s.psi.cos(), 0.0, -s.psi.sin());
    let sway = 0.03 * ph.sin() * s.gait * walk;
    let base = Vec3::new(s.x, 0.0, s.z) + left * sway;
    let bob = (0.025 + 0.025 * s.run) * bounce_f * (2.0 * ph).cos() * s.gait;
    let h_nom = rig.root_h - 0.02 - walk * 0.02 * s.v.min(2.0) - s.run * 0.06 + bob + s.dy;
    let h = if s.airborne {
        h_nom
    } else {
        let mut cands = vec![h_nom];
        for (side, fp) in feet.iter().enumerate() {
            let hip0 = base + r_root * rig.hip_off[side];
            let a = fp.ankle;
            let l = REACH * (rig.thigh[side].norm() + rig.shin[side].norm());
            let dxz = (hip0.x - a.x).hypot(hip0.z - a.z).min(0.98 * l);
            // A swing foot's limit is relaxed by up to 1 m in mid-swing.
            cands.push(a.y + (l * l - dxz * dxz).sqrt() - hip0.y + (1.0 - fp.limit));
        }
        soft_min(&cands, 0.015)
    };
    let root_pos = base + Vec3::new(0.0, h, 0.0);

    let mut rot = vec![UnitQuat::identity(); rig.nj];
    rot[rig.root] = r_root;
    // Trunk: lean split over spine and chest, counter-rotation, head stabilised.
    let lean = style.lean_deg.clamp(-30.0, 45.0) * deg + 3.0 * deg * s.v.min(6.0) + s.lean;
    rot[rig.spine] = axis_quat(0, 0.5 * lean) * axis_quat(1, -0.3 * yaw_osc);
    rot[rig.chest] = axis_quat(0, 0.5 * lean) * axis_quat(1, -0.3 * yaw_osc);
    rot[rig.neck] = axis_quat(0, -0.4 * (lean - s.lean));
    rot[rig.head] = axis_quat(1, -0.4 * yaw_osc) * axis_quat(0, -0.2 * (lean - s.lean));
    // Arms: lowered 75°, swing opposite to the same-side leg, elbow 20° (walk) … 90° (run).
    let amp = (10.0 + 12.0 * s.v.min(6.0)) * deg * arm_f * s.gait;
    let elbow = (20.0 + 70.0 * s.run) * deg;
    for side in 0..2 {
        let sg = if side == 0 { 1.0 } else { -1.0 };
        let swing = -sg * amp * ph.cos();
        rot[rig.shoulder[side]] = axis_quat(0, -swing) * axis_quat(2, -sg * 75.0 * deg);
        rot[rig.elbow[side]] = axis_quat(1, -sg * elbow);
    }
    if s.wave > 0.0 {
        let sh = axis_quat(2, 45.0 * deg) * axis_quat(1, -20.0 * deg);
        let fa = axis_quat(2, (60.0 + 25.0 * (TAU * 2.0 * t).sin()) * deg);
        rot[rig.shoulder[1]] = rot[rig.shoulder[1]].slerp(&sh, s.wave);
        rot[rig.elbow[1]] = rot[rig.elbow[1]].slerp(&fa, s.wave);
    }
    // Noise on every free DOF of the upper body.
    for j in [rig.spine, rig.chest, rig.neck, rig.head] {
        rot[j] *= noise.rot(j, t, 1.0);
    }
    for side in 0..2 {
        for j in [rig.collar[side], rig.shoulder[side], rig.elbow[side], rig.hand[side]] {
            rot[j] *= noise.rot(j, t, 1.0);
        }
    }

    // Forward kinematics of the upper body and hips (legs still at rest).
    let mut g = vec![Iso3::identity(); rig.nj];
    rig.fk(&root_pos, &rot, &mut g);

    // Right hand to a target (reach: 1.5–1.9 m high ahead; pick-up: the floor 0.35 m ahead).
    let w_ik = s.reach.max(s.pickup);
    if w_ik > 0.0 {
        let side = 1;
        let body = Planar::new(s.x, s.z, s.psi);
        let target = if s.pickup >= s.reach {
            body.apply_point(Vec3::new(-0.15, 0.06, 0.35))
        } else {
            body.apply_point(Vec3::new(-0.2, s.reach_h, 0.45))
        };
        let sh = g[rig.shoulder[side]].translation.vector;
        let el = g[rig.elbow[side]].translation.vector;
        let hd = g[rig.hand[side]].translation.vector;
        let goal = hd + (target - hd) * w_ik;
        let (l1, l2) = (rig.upper[side].norm(), rig.fore[side].norm());
        let (m, e) = two_bone(&Pt3::from(sh), l1, l2, &Pt3::from(goal), &(el - 0.5 * (sh + hd)));
        let r_up = g[rig.shoulder[side]].rotation;
        let r_fo = g[rig.elbow[side]].rotation;
        let r_up_new = UnitQuat::rotation_between(&(r_up * rig.upper[side]), &(m.coords - sh))
            .unwrap_or_else(UnitQuat::identity)
            * r_up;
        let r_fo_new =
            UnitQuat::rotation_between(&(r_fo * rig.fore[side]), &(e - m)).unwrap_or_else(UnitQuat::identity) * r_fo;
        let parent = g[rig.collar[side]].rotation;
        rot[rig.shoulder[side]] = parent.inverse() * r_up_new;
        rot[rig.elbow[side]] = r_up_new.inverse() * r_fo_new;
    }

    // Legs by two-bone IK to the ankle targets; knee towards the foot's forward direction.
    let mut contacts = 0u8;
    for (side, fp) in feet.iter().enumerate() {
        let hip_g = &g[rig.hip[side]];
        let parent_rot = rig.parent_rot(&g, rig.hip[side]);
        let hip = hip_g.translation.vector;
        let ry = axis_quat(1, fp.yaw);
        let fwd = ry * Vec3::z();
        let (l1, l2) = (rig.thigh[side].norm(), rig.shin[side].norm());
        // Knee flexion at most 145°: a target closer to the hip than the chord of a 35° interior
        // angle is pushed out along the hip → target ray (only swing feet get that close).
        let d_min = (l1 * l1 + l2 * l2 - 2.0 * l1 * l2 * 35f64.to_radians().cos()).max(0.0).sqrt();
        let mut target = fp.ankle;
        let reach = target - hip;
        if reach.norm() < d_min {
            target = hip + reach.try_normalize(1e-12).unwrap_or(-Vec3::y()) * d_min;
        }
        let (knee, ank) = two_bone(&Pt3::from(hip), l1, l2, &Pt3::from(target), &fwd);
        let r_thigh = aim(&rig.thigh[side], &(knee.coords - hip), &fwd);
        let r_shin = aim(&rig.shin[side], &(ank - knee), &fwd);
        let r_foot = ry * axis_quat(0, fp.pitch);
        rot[rig.hip[side]] = parent_rot.inverse() * r_thigh;
        rot[rig.knee[side]] = r_thigh.inverse() * r_shin;
        rot[rig.ankle[side]] = r_shin.inverse() * r_foot;
        rot[rig.toe[side]] = r_foot.inverse() * ry;
        let (a, to) = fp.contact;
        let (ba, bt) = if side == 0 {
            (FrameLabels::L_ANKLE, FrameLabels::L_TOE)
        } else {
            (FrameLabels::R_ANKLE, FrameLabels::R_TOE)
        };
        if a {
            contacts |= ba;
        }
        if to {
            contacts |= bt;
        }
    }
    (Pose { root_pos, rot }, contacts, s.labels)
}

//! Assembly (§3.9), smoothing at cuts (§3.10), exact body constraints (§3.11) and metrics
//! (§3.12).

use crate::graph::{FrameRef, MotionGraph};
use crate::path::{place, Path, Piece};
use crate::problem::{BodyConstraint, HardConstraint, Problem};
use geom_core::anim::metrics::{
    foot_skate, splice_discontinuity, within_clip_jump_distribution, JumpDistribution, JumpStats, SkateStats,
};
use geom_core::anim::{FrameLabels, JointRole, Motion};
use geom_core::math::{axis_quat, quat_exp, quat_log, wrap_angle, Planar, Pt3, Vec3};

/// An assembled motion with its piece table.
#[derive(Clone, Debug)]
pub struct Assembled {
    /// The motion (world coordinates; labels and contacts carried from the source frames).
    pub motion: Motion,
    /// Pieces (clip, frames, output time, placement).
    pub pieces: Vec<Piece>,
    /// Output index of the first frame of every piece after the first.
    pub cuts: Vec<usize>,
    /// Source database frame of every output frame.
    pub source: Vec<FrameRef>,
}

/// Copies the pieces of `path` placed from `start` (§3.9): local rotations unchanged, the root
/// moved by the piece placement `W`. `None` if the path is invalid.
pub fn assemble(g: &MotionGraph, path: &Path, start: Planar, min_piece: u32) -> Option<Assembled> {
    let pieces = place(g, path, &start, min_piece)?;
    let skel = g.db.skeleton.clone();
    let nj = skel.joints.len();
    let total: usize = pieces.iter().map(|p| (p.last - p.first + 1) as usize).sum();
    let mut root_pos = Vec::with_capacity(total);
    let mut rot = Vec::with_capacity(total * nj);
    let mut labels = FrameLabels {
        names: g.db.labels.clone(),
        bits: Vec::with_capacity(total),
        contacts: Vec::with_capacity(total),
    };
    let mut cuts = Vec::new();
    let mut source = Vec::with_capacity(total);
    let root = skel.role(geom_core::anim::JointRole::Root).unwrap_or(0) as usize;
    for (k, p) in pieces.iter().enumerate() {
        if k > 0 {
            cuts.push(root_pos.len());
        }
        let clip = &g.db.clips[p.clip as usize];
        let ry = axis_quat(1, p.w.yaw);
        for f in p.first..=p.last {
            let f = f as usize;
            root_pos.push(p.w.apply_point(clip.root_pos[f]));
            let r = clip.frame_rot(f);
            for (j, q) in r.iter().enumerate() {
                rot.push(if j == root { ry * q } else { *q });
            }
            labels.bits.push(clip.labels.bits.get(f).copied().unwrap_or(0));
            labels.contacts.push(clip.labels.contacts.get(f).copied().unwrap_or(0));
            source.push(FrameRef { clip: p.clip, frame: f as u32 });
        }
    }
    let extra = g.db.clips[0].extra_trans.as_ref().map(|_| {
        let mut e = Vec::with_capacity(total * nj);
        for p in &pieces {
            let clip = &g.db.clips[p.clip as usize];
            for f in p.first..=p.last {
                e.extend_from_slice(clip.frame_extra(f as usize).unwrap_or(&vec![Vec3::zeros(); nj]));
            }
        }
        e
    });
    let mut motion = Motion::new(skel, 1.0 / g.db.rate_hz, root_pos, rot, extra).ok()?;
    motion.labels = labels;
    motion.fix_hemispheres();
    Some(Assembled { motion, pieces, cuts, source })
}

/// Smoothing kernel `s(u) = 1 − 3u² + 2u³` (C¹ at `u = 1`, `s(0) = 1`).
pub fn kernel(u: f64) -> f64 {
    let u = u.clamp(0.0, 1.0);
    1.0 - 3.0 * u * u + 2.0 * u * u * u
}

/// Spreads every cut's jump over ±`window` frames (§3.10): for each joint's local rotation
/// (the root's world rotation) and the root height, the jump minus the expected one-frame change,
/// `δ = log(q_a⁻¹q_b) − ½[log(q_{a−1}⁻¹q_a) + log(q_b⁻¹q_{b+1})]`, is split half/half:
/// frames `a − d` get `q·exp(+½ s(d/W_l) δ)`, frames `b + d` get `q·exp(−½ s(d/W_r) δ)`, with the
/// windows clamped to the adjacent pieces. Displacements are computed on the unsmoothed signal
/// and summed. Planar position and heading are continuous by placement and are not touched.
pub fn smooth(a: &mut Assembled, window: u32) {
    if window == 0 || a.cuts.is_empty() {
        return;
    }
    let m = &a.motion;
    let n = m.len();
    let nj = m.n_joints();
    let mut drot = vec![Vec3::zeros(); n * nj];
    let mut dy = vec![0.0; n];
    let bounds: Vec<usize> = std::iter::once(0).chain(a.cuts.iter().copied()).chain(std::iter::once(n)).collect();
    for (ci, &b) in a.cuts.iter().enumerate() {
        let ai = b - 1;
        let left_len = b - bounds[ci];
        let right_len = bounds[ci + 2] - b;
        let wl = (window as usize).min(left_len);
        let wr = (window as usize).min(right_len);
        for j in 0..nj {
            let q = |f: usize| m.rot[f * nj + j];
            let jump = quat_log(&(q(ai).inverse() * q(b)));
            let before = if ai >= 1 { quat_log(&(q(ai - 1).inverse() * q(ai))) } else { Vec3::zeros() };
            let after = if b + 1 < n { quat_log(&(q(b).inverse() * q(b + 1))) } else { Vec3::zeros() };
            let delta = jump - 0.5 * (before + after);
            for d in 0..wl {
                drot[(ai - d) * nj + j] += 0.5 * kernel(d as f64 / wl as f64) * delta;
            }
            for d in 0..wr {
                drot[(b + d) * nj + j] -= 0.5 * kernel(d as f64 / wr as f64) * delta;
            }
        }
        let y = |f: usize| m.root_pos[f].y;
        let before = if ai >= 1 { y(ai) - y(ai - 1) } else { 0.0 };
        let after = if b + 1 < n { y(b + 1) - y(b) } else { 0.0 };
        let delta = (y(b) - y(ai)) - 0.5 * (before + after);
        for d in 0..wl {
            dy[ai - d] += 0.5 * kernel(d as f64 / wl as f64) * delta;
        }
        for d in 0..wr {
            dy[b + d] -= 0.5 * kernel(d as f64 / wr as f64) * delta;
        }
    }
    let m = &mut a.motion;
    for f in 0..n {
        m.root_pos[f].y += dy[f];
        for j in 0..nj {
            let v = drot[f * nj + j];
            if v != Vec3::zeros() {
                m.rot[f * nj + j] *= quat_exp(&v);
            }
        }
    }
}

/// Cancels the foot sliding that cuts and smoothing introduce (ours, beyond the paper; no IK):
/// whenever foot points carry a contact flag on a frame and the previous one, the root is moved
/// horizontally by minus their mean horizontal displacement, and the accumulated offset is kept
/// for the following frames. A stance foot then stays where it was planted (exactly when one
/// point, or points sliding alike, are held; double support with different slides keeps their
/// difference); between contacts the body moves as assembled. Only the root translation
/// changes (local rotations, heights and headings are untouched), so the pose is the same and the
/// torso path drifts by the removed sliding, which the body-constraint correction of §3.11 then
/// takes back — [`enforce_body`] puts its ramp into frames with few held contacts.
/// Returns the total horizontal offset applied at the last frame (m).
pub fn fix_contacts(a: &mut Assembled) -> f64 {
    let m = &mut a.motion;
    let n = m.len();
    let s = &m.skeleton;
    let pts: Vec<(u8, usize)> = [
        (FrameLabels::L_ANKLE, JointRole::LeftAnkle),
        (FrameLabels::L_TOE, JointRole::LeftToe),
        (FrameLabels::R_ANKLE, JointRole::RightAnkle),
        (FrameLabels::R_TOE, JointRole::RightToe),
    ]
    .into_iter()
    .filter_map(|(bit, r)| s.role(r).map(|j| (bit, j as usize)))
    .collect();
    if n < 2 || pts.is_empty() {
        return 0.0;
    }
    let nj = m.n_joints();
    let mut prev = vec![Pt3::origin(); nj];
    let mut cur = vec![Pt3::origin(); nj];
    m.joint_positions(0, &mut prev);
    let flag = |m: &Motion, f: usize| m.labels.contacts.get(f).copied().unwrap_or(0);
    let mut off = Vec3::zeros();
    for f in 1..n {
        m.joint_positions(f, &mut cur);
        let held = flag(m, f) & flag(m, f - 1);
        let mut slide = Vec3::zeros();
        let mut k = 0;
        for &(bit, j) in &pts {
            if held & bit != 0 {
                let d = cur[j] - prev[j];
                slide += Vec3::new(d.x, 0.0, d.z);
                k += 1;
            }
        }
        if k > 0 {
            off -= slide / k as f64;
        }
        std::mem::swap(&mut prev, &mut cur);
        m.root_pos[f] += off;
    }
    off.norm()
}

/// Per held contact point, how much less a frame takes of the §3.11 ramp than a frame without
/// contacts: frame weight `1/(1 + CONTACT_RAMP_WEIGHT·k)`.
const CONTACT_RAMP_WEIGHT: f64 = 100.0;

/// Meets body constraints exactly (§3.11): for consecutive constraints `t_p < t_c`, the
/// trajectory from `t_p` on is rotated about the torso position at `t_p` by `λΔyaw` and moved by
/// `λΔ`, where `Δyaw` and `Δ` make the torso frame at `t_c` equal to the target and `λ` rises
/// from 0 at `t_p` to 1 at `t_c`. The paper's ramp is uniform; here `λ` accumulates per-frame
/// weights `1/(1 + 100k)` (k = foot points in contact on that and the previous frame), which moves
/// the correction into flight and single-support frames and so reduces foot skate (our choice;
/// uniform when no contacts are flagged). Processed in time order; the time-0 constraint is met by placement.
/// Constraints beyond the motion are applied at its last frame. The time-0 constraint (met by
/// placement before smoothing) is made exact by one rigid planar motion of the whole trajectory.
pub fn enforce_body(a: &mut Assembled, body: &[BodyConstraint]) {
    let n = a.motion.len();
    if n == 0 {
        return;
    }
    let mut bs: Vec<BodyConstraint> = body.to_vec();
    bs.sort_by_key(|b| b.time);
    let root = a.motion.skeleton.role(geom_core::anim::JointRole::Root).unwrap_or(0) as usize;
    let nj = a.motion.n_joints();
    // Time 0: met by placement up to the smoothing of a short first piece; a rigid motion of the
    // whole trajectory makes it exact.
    if let Some(b) = bs.iter().find(|b| b.time == 0) {
        let m = &mut a.motion;
        let cur = m.torso_frame(0);
        let dyaw = b.yaw.map_or(0.0, |y| wrap_angle(y - cur.yaw));
        let r = Planar::new(0.0, 0.0, dyaw);
        let rq = axis_quat(1, dyaw);
        for t in 0..n {
            let p = m.root_pos[t];
            let d = r.apply_dir(Vec3::new(p.x - cur.x, 0.0, p.z - cur.z));
            m.root_pos[t] = Vec3::new(b.x + d.x, p.y, b.z + d.z);
            m.rot[t * nj + root] = rq * m.rot[t * nj + root];
        }
    }
    let mut tp = 0usize;
    for b in &bs {
        let tc = (b.time as usize).min(n - 1);
        if tc == 0 || tc <= tp {
            continue;
        }
        let m = &mut a.motion;
        let o = m.root_pos[tp];
        let cur = m.torso_frame(tc);
        let dyaw = b.yaw.map_or(0.0, |y| wrap_angle(y - cur.yaw));
        let rot = Planar::new(0.0, 0.0, dyaw);
        let pc = Vec3::new(cur.x - o.x, 0.0, cur.z - o.z);
        let rotated = rot.apply_dir(pc);
        let delta = Vec3::new(b.x - (o.x + rotated.x), 0.0, b.z - (o.z + rotated.z));
        // λ(t): cumulative per-frame weights, so the correction goes where few foot points are
        // in contact (w = 1/(1 + 100 k), k = contact points held from the previous frame); with
        // no contact information this is the uniform ramp of the paper.
        let held = |t: usize| -> u32 {
            let c = m.labels.contacts.get(t).copied().unwrap_or(0);
            let c0 = m.labels.contacts.get(t.wrapping_sub(1)).copied().unwrap_or(0);
            (c & c0).count_ones()
        };
        let w: Vec<f64> = (tp + 1..=tc).map(|t| 1.0 / (1.0 + CONTACT_RAMP_WEIGHT * held(t) as f64)).collect();
        let total: f64 = w.iter().sum();
        let mut cum = 0.0;
        let mut lams = Vec::with_capacity(tc - tp);
        for wi in &w {
            cum += wi;
            lams.push(cum / total);
        }
        for t in tp..n {
            let lam = if t == tp {
                0.0
            } else if t >= tc {
                1.0
            } else {
                lams[t - tp - 1]
            };
            if lam == 0.0 {
                continue;
            }
            let r = Planar::new(0.0, 0.0, lam * dyaw);
            let p = m.root_pos[t];
            let d = r.apply_dir(Vec3::new(p.x - o.x, 0.0, p.z - o.z));
            m.root_pos[t] = Vec3::new(o.x + d.x + lam * delta.x, p.y, o.z + d.z + lam * delta.z);
            m.rot[t * nj + root] = axis_quat(1, lam * dyaw) * m.rot[t * nj + root];
        }
        tp = tc;
    }
}

/// Reference statistics of the database (within-clip jumps, source skate).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ClipStats {
    /// Within-clip `J_v`/`J_a` distribution.
    pub jumps: JumpDistribution,
    /// Foot skate of the source clips (summed over clips, rate per second of source).
    pub skate: SkateStats,
}

impl ClipStats {
    /// Statistics of every clip of the graph's database.
    pub fn of(g: &MotionGraph) -> ClipStats {
        let jumps = within_clip_jump_distribution(&g.db.clips);
        let mut slide = 0.0;
        let mut dur = 0.0;
        let mut frames = 0;
        let mut max: f64 = 0.0;
        for c in &g.db.clips {
            let s = foot_skate(c, &c.labels);
            slide += s.slide_m;
            dur += c.duration();
            frames += s.contact_frames;
            max = max.max(s.max_speed_cm_s);
        }
        let skate = SkateStats {
            rate_cm_s: if dur > 0.0 { 100.0 * slide / dur } else { 0.0 },
            mean_mm: if frames > 0 { 1000.0 * slide / frames as f64 } else { 0.0 },
            max_speed_cm_s: max,
            contact_frames: frames,
            slide_m: slide,
        };
        ClipStats { jumps, skate }
    }
}

/// Measured quality of an assembled motion (§3.12).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Metrics {
    /// Body constraint position errors (m).
    pub body_pos: Vec<f64>,
    /// Body constraint heading errors (deg; 0 if unconstrained).
    pub body_yaw_deg: Vec<f64>,
    /// Joint constraint errors (m).
    pub joint: Vec<f64>,
    /// `|F − F*|` (frames).
    pub length_err: u32,
    /// Every hard constraint met exactly.
    pub hard_met: bool,
    /// Number of hard constraints met.
    pub hard_count_met: usize,
    /// Pieces.
    pub pieces: usize,
    /// Jumps at the cuts.
    pub cut_jumps: Vec<JumpStats>,
    /// Foot skate with contacts carried from the source frames.
    pub skate: SkateStats,
}

/// Measures `a` against `pb` (§3.12).
pub fn evaluate(g: &MotionGraph, a: &Assembled, pb: &Problem) -> Metrics {
    let m = &a.motion;
    let n = m.len();
    let mut out = Metrics { pieces: a.pieces.len(), ..Default::default() };
    if n == 0 {
        return out;
    }
    out.length_err = (n as i64 - pb.target_length() as i64).unsigned_abs() as u32;
    for b in &pb.body {
        let t = (b.time as usize).min(n - 1);
        let tf = m.torso_frame(t);
        out.body_pos.push((tf.x - b.x).hypot(tf.z - b.z));
        out.body_yaw_deg.push(b.yaw.map_or(0.0, |y| wrap_angle(tf.yaw - y).abs().to_degrees()));
    }
    let nj = m.n_joints();
    let mut p = vec![Pt3::origin(); nj];
    for j in &pb.joints {
        let t = (j.time as usize).min(n - 1);
        m.joint_positions(t, &mut p);
        out.joint.push((p[j.joint as usize].coords - j.pos).norm());
    }
    out.hard_met = true;
    for h in &pb.hard {
        let t = h.time() as usize;
        let ok = t < n
            && match h {
                HardConstraint::Frame { frame, .. } => a.source[t] == *frame,
                HardConstraint::Label { label, .. } => {
                    g.db.label_bit(label).is_some_and(|bit| m.labels.bits[t] & bit != 0)
                }
            };
        if ok {
            out.hard_count_met += 1;
        } else {
            out.hard_met = false;
        }
    }
    out.cut_jumps = splice_discontinuity(m, &a.cuts);
    out.skate = foot_skate(m, &m.labels);
    out
}

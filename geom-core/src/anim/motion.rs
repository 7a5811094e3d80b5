//! Motion clips: [`Motion`] (per-frame root position and local joint rotations on a shared
//! [`Skeleton`]) and per-frame labels [`FrameLabels`] (motion-graph.md §2.1, §3.1).

use super::skeleton::{JointRole, Pose, Skeleton};
use crate::error::{Error, Result};
use crate::math::{fix_hemisphere, heading, slerp, wrap_angle, Iso3, Planar, Pt3, UnitQuat, Vec3};
use serde::{Deserialize, Serialize};
use std::f64::consts::FRAC_PI_2;
use std::sync::Arc;

/// Per-frame labels: a bitset of label ids (index into `names`, at most 64) and foot-contact
/// flags ([`FrameLabels::L_ANKLE`] …). All vectors have one entry per frame (or are empty when a
/// clip carries no labels).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct FrameLabels {
    /// Label names; bit `i` of `bits[f]` means frame `f` carries `names[i]`.
    pub names: Vec<String>,
    /// Label bitset per frame.
    pub bits: Vec<u64>,
    /// Contact flags per frame (bit 0 left ankle, 1 left toe, 2 right ankle, 3 right toe).
    pub contacts: Vec<u8>,
}

impl FrameLabels {
    /// Contact bit: left ankle on the ground.
    pub const L_ANKLE: u8 = 1;
    /// Contact bit: left toe on the ground.
    pub const L_TOE: u8 = 2;
    /// Contact bit: right ankle on the ground.
    pub const R_ANKLE: u8 = 4;
    /// Contact bit: right toe on the ground.
    pub const R_TOE: u8 = 8;

    /// No labels and no contacts on `frames` frames.
    pub fn new(frames: usize) -> Self {
        Self { names: Vec::new(), bits: vec![0; frames], contacts: vec![0; frames] }
    }

    /// Id of a label name.
    pub fn id(&self, name: &str) -> Option<usize> {
        self.names.iter().position(|n| n == name)
    }

    /// Id of `name`, adding it if new. Error if 64 labels already exist.
    pub fn add(&mut self, name: &str) -> Result<usize> {
        if let Some(i) = self.id(name) {
            return Ok(i);
        }
        if self.names.len() >= 64 {
            return Err(Error::InvalidParameter(format!("label '{name}': at most 64 labels per clip")));
        }
        self.names.push(name.to_string());
        Ok(self.names.len() - 1)
    }

    /// Whether frame `f` carries label `id` (false for frames or ids out of range).
    pub fn has(&self, f: usize, id: usize) -> bool {
        id < 64 && self.bits.get(f).is_some_and(|b| b >> id & 1 == 1)
    }

    /// Sets or clears label `id` on frame `f` (ignored out of range).
    pub fn set(&mut self, f: usize, id: usize, on: bool) {
        if let (Some(b), true) = (self.bits.get_mut(f), id < 64) {
            if on {
                *b |= 1 << id;
            } else {
                *b &= !(1 << id);
            }
        }
    }

    /// Labels of the given source frames, in order (missing entries read as 0).
    fn select(&self, frames: impl Iterator<Item = usize>) -> FrameLabels {
        let mut out = FrameLabels { names: self.names.clone(), bits: Vec::new(), contacts: Vec::new() };
        for f in frames {
            out.bits.push(self.bits.get(f).copied().unwrap_or(0));
            out.contacts.push(self.contacts.get(f).copied().unwrap_or(0));
        }
        out
    }
}

/// Thresholds of [`Motion::detect_contacts`] (motion-graph.md §3.1 step 3, §4).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct ContactParams {
    /// Height above the point's floor level below which it may be in contact (m); default 0.03.
    pub height: f64,
    /// Horizontal speed below which it may be in contact (m/s); default 0.4.
    pub speed: f64,
    /// Percentile of the point's height over the clip taken as its floor level; default 5.
    pub floor_percentile: f64,
    /// Gaps of at most this many frames between contact frames are filled; default 2.
    pub fill_gap: usize,
}

impl Default for ContactParams {
    fn default() -> Self {
        Self { height: 0.03, speed: 0.4, floor_percentile: 5.0, fill_gap: 2 }
    }
}

/// A motion clip on one skeleton: `len()` frames sampled every `frame_time` seconds.
///
/// `rot` holds the local joint rotations, frames × joints row-major (`rot[f·J + j]`);
/// `root_pos[f]` is the root's world position (m); `extra_trans` (frames × joints, only when a
/// non-root joint has BVH position channels) adds to joint offsets. See [`Skeleton`] for the
/// forward-kinematics convention.
#[derive(Clone, Debug, PartialEq)]
pub struct Motion {
    /// The shared skeleton.
    pub skeleton: Arc<Skeleton>,
    /// Seconds between frames.
    pub frame_time: f64,
    /// Root world position per frame (m).
    pub root_pos: Vec<Vec3>,
    /// Per-frame labels and contacts.
    pub labels: FrameLabels,
    /// Local rotations, frames × joints, row-major.
    pub rot: Vec<UnitQuat>,
    /// Extra per-joint translations (m), frames × joints, or `None`.
    pub extra_trans: Option<Vec<Vec3>>,
}

impl Motion {
    /// A clip from its parts, checking sizes (`rot` and `extra_trans` must hold
    /// `root_pos.len() × joints` entries) and that `frame_time` is positive and finite.
    /// Labels start empty.
    pub fn new(
        skeleton: Arc<Skeleton>,
        frame_time: f64,
        root_pos: Vec<Vec3>,
        rot: Vec<UnitQuat>,
        extra_trans: Option<Vec<Vec3>>,
    ) -> Result<Motion> {
        if !(frame_time > 0.0 && frame_time.is_finite()) {
            return Err(Error::InvalidParameter(format!("frame time {frame_time} s must be positive")));
        }
        let n = root_pos.len() * skeleton.joints.len();
        if rot.len() != n {
            return Err(Error::DimensionMismatch { what: "motion rotations", expected: n, got: rot.len() });
        }
        if let Some(e) = &extra_trans {
            if e.len() != n {
                return Err(Error::DimensionMismatch { what: "motion extra translations", expected: n, got: e.len() });
            }
        }
        let labels = FrameLabels::new(root_pos.len());
        Ok(Motion { skeleton, frame_time, root_pos, labels, rot, extra_trans })
    }

    /// A clip from a sequence of poses (each with one rotation per joint).
    pub fn from_poses(skeleton: Arc<Skeleton>, frame_time: f64, poses: &[Pose]) -> Result<Motion> {
        let nj = skeleton.joints.len();
        let mut rot = Vec::with_capacity(poses.len() * nj);
        for p in poses {
            if p.rot.len() != nj {
                return Err(Error::DimensionMismatch { what: "pose rotations", expected: nj, got: p.rot.len() });
            }
            rot.extend_from_slice(&p.rot);
        }
        Motion::new(skeleton, frame_time, poses.iter().map(|p| p.root_pos).collect(), rot, None)
    }

    /// Number of frames.
    pub fn len(&self) -> usize {
        self.root_pos.len()
    }

    /// Whether the clip has no frames.
    pub fn is_empty(&self) -> bool {
        self.root_pos.is_empty()
    }

    /// Joints per frame.
    pub fn n_joints(&self) -> usize {
        self.skeleton.joints.len()
    }

    /// Time from the first to the last frame, `(len − 1)·frame_time` (s); 0 for ≤ 1 frame.
    pub fn duration(&self) -> f64 {
        self.len().saturating_sub(1) as f64 * self.frame_time
    }

    /// Local rotations of frame `f`.
    ///
    /// # Panics
    /// If `f ≥ len()`.
    pub fn frame_rot(&self, f: usize) -> &[UnitQuat] {
        let nj = self.n_joints();
        &self.rot[f * nj..(f + 1) * nj]
    }

    /// Extra translations of frame `f`, if the clip has any.
    pub fn frame_extra(&self, f: usize) -> Option<&[Vec3]> {
        let nj = self.n_joints();
        self.extra_trans.as_ref().map(|e| &e[f * nj..(f + 1) * nj])
    }

    /// The pose of frame `f` (extra translations are not part of a [`Pose`]).
    ///
    /// # Panics
    /// If `f ≥ len()`.
    pub fn pose(&self, f: usize) -> Pose {
        Pose { root_pos: self.root_pos[f], rot: self.frame_rot(f).to_vec() }
    }

    /// Forward kinematics of frame `f` into `out` (one transform per joint).
    ///
    /// # Panics
    /// If `f ≥ len()` or `out.len()` is not the joint count.
    pub fn globals(&self, f: usize, out: &mut [Iso3]) {
        self.skeleton.fk(&self.root_pos[f], self.frame_rot(f), self.frame_extra(f), out);
    }

    /// World joint positions of frame `f` (m).
    ///
    /// # Panics
    /// If `f ≥ len()` or `out.len()` is not the joint count.
    pub fn joint_positions(&self, f: usize, out: &mut [Pt3]) {
        assert_eq!(out.len(), self.n_joints(), "output has {} slots for {} joints", out.len(), self.n_joints());
        let mut g = vec![Iso3::identity(); self.n_joints()];
        self.globals(f, &mut g);
        for (o, gi) in out.iter_mut().zip(&g) {
            *o = Pt3::from(gi.translation.vector);
        }
    }

    /// Heading (rad) of frame `f` by motion-graph.md §3.1 step 4, or `None` if both the pelvis and
    /// the root forward axis are too close to vertical.
    fn raw_heading(&self, f: usize) -> Option<f64> {
        let s = &self.skeleton;
        let mut g = vec![Iso3::identity(); self.n_joints()];
        self.globals(f, &mut g);
        if let (Some(l), Some(r)) = (s.role(JointRole::LeftHip), s.role(JointRole::RightHip)) {
            let lat = g[l as usize].translation.vector - g[r as usize].translation.vector;
            let n = lat.norm();
            if n > 0.0 && lat.x.hypot(lat.z) >= 0.3 * n {
                return Some(wrap_angle(heading(&lat) - FRAC_PI_2));
            }
        }
        let fwd = g[0].rotation * Vec3::z();
        if fwd.x.hypot(fwd.z) >= 0.3 {
            return Some(heading(&fwd));
        }
        None
    }

    /// Torso (ground) frame of frame `f` (motion-graph.md §3.1 step 4): origin = root position
    /// projected to y = 0; heading from the pelvis lateral axis `l = p(LeftHip) − p(RightHip)`,
    /// `yaw = atan2(l.x, l.z) − π/2`; if `l`'s xz part is shorter than `0.3·|l|` (lying on the
    /// side) the root's forward axis `R_root·(0,0,1)`; if that is also steeper (xz part < 0.3),
    /// the heading of the nearest earlier frame that has one (0 if none). Yaw in `(−π, π]`;
    /// [`torso_frames`](Self::torso_frames) gives the unwrapped sequence.
    ///
    /// # Panics
    /// If `f ≥ len()`.
    pub fn torso_frame(&self, f: usize) -> Planar {
        let p = self.root_pos[f];
        let yaw = (0..=f).rev().find_map(|k| self.raw_heading(k)).unwrap_or(0.0);
        Planar { x: p.x, z: p.z, yaw }
    }

    /// Torso frames of all frames with the yaw unwrapped in time (consecutive yaws differ by at
    /// most π), a frame without a heading keeping the previous one.
    pub fn torso_frames(&self) -> Vec<Planar> {
        let raw: Vec<Option<f64>> = (0..self.len()).map(|f| self.raw_heading(f)).collect();
        // Frames before the first valid heading take that heading.
        let mut prev = raw.iter().flatten().next().copied().unwrap_or(0.0);
        raw.iter()
            .zip(&self.root_pos)
            .map(|(h, p)| {
                if let Some(y) = h {
                    prev += wrap_angle(y - prev);
                }
                Planar { x: p.x, z: p.z, yaw: prev }
            })
            .collect()
    }

    /// Interpolated pose and extra translations at fractional frame index `u ∈ [0, len − 1]`
    /// (clamped): slerp of local rotations, lerp of positions.
    fn sample_into(&self, u: f64, root: &mut Vec<Vec3>, rot: &mut Vec<UnitQuat>, extra: &mut Option<Vec<Vec3>>) {
        let n = self.len();
        let nj = self.n_joints();
        let u = if u.is_finite() { u.clamp(0.0, (n - 1) as f64) } else { 0.0 };
        let i = (u.floor() as usize).min(n.saturating_sub(2));
        let s = if n == 1 { 0.0 } else { u - i as f64 };
        let i1 = (i + 1).min(n - 1);
        root.push(self.root_pos[i].lerp(&self.root_pos[i1], s));
        for j in 0..nj {
            rot.push(slerp(&self.rot[i * nj + j], &self.rot[i1 * nj + j], s));
        }
        if let (Some(out), Some(src)) = (extra.as_mut(), self.extra_trans.as_ref()) {
            for j in 0..nj {
                out.push(src[i * nj + j].lerp(&src[i1 * nj + j], s));
            }
        }
    }

    /// Pose at time `t` seconds from the first frame (clamped to the clip), interpolated as in
    /// [`resample`](Self::resample). Error if the clip is empty.
    pub fn pose_at(&self, t: f64) -> Result<Pose> {
        if self.is_empty() {
            return Err(Error::InvalidParameter("pose_at on an empty motion".into()));
        }
        let (mut root, mut rot, mut extra) = (Vec::new(), Vec::new(), None);
        self.sample_into(t / self.frame_time, &mut root, &mut rot, &mut extra);
        Ok(Pose { root_pos: root[0], rot })
    }

    /// Builds a clip from samples at fractional source frame indices `us`.
    fn resampled(&self, us: &[f64], frame_time: f64) -> Motion {
        let nj = self.n_joints();
        let mut root = Vec::with_capacity(us.len());
        let mut rot = Vec::with_capacity(us.len() * nj);
        let mut extra = self.extra_trans.as_ref().map(|_| Vec::with_capacity(us.len() * nj));
        if !self.is_empty() {
            for &u in us {
                self.sample_into(u, &mut root, &mut rot, &mut extra);
            }
        }
        let n = self.len();
        let labels = self.labels.select(us.iter().map(|&u| (u.round().max(0.0) as usize).min(n.saturating_sub(1))));
        let mut m =
            Motion { skeleton: self.skeleton.clone(), frame_time, root_pos: root, labels, rot, extra_trans: extra };
        if self.is_empty() {
            m.labels = FrameLabels { names: self.labels.names.clone(), ..FrameLabels::default() };
        }
        m
    }

    /// The clip resampled at a new frame time (s): samples at times `k·dt`, `k = 0 … K` with
    /// `K = ⌊duration/dt⌋` (a 1e-9 relative tolerance absorbs rounding), so the first frame is
    /// kept exactly and the last one too when the duration is a multiple of `dt` (otherwise the
    /// clip ends up to one new frame early). Rotations by slerp (shortest arc), root and extra
    /// translations by lerp, labels and contacts from the nearest source frame
    /// (motion-graph.md §3.1 step 1). Error unless `dt` is positive and finite.
    pub fn resample(&self, dt: f64) -> Result<Motion> {
        if !(dt > 0.0 && dt.is_finite()) {
            return Err(Error::InvalidParameter(format!("resample: new frame time {dt} s must be positive")));
        }
        if self.is_empty() {
            return Ok(self.resampled(&[], dt));
        }
        let k_max = (self.duration() / dt * (1.0 + 1e-9)).floor() as usize;
        let us: Vec<f64> =
            (0..=k_max).map(|k| (k as f64 * dt / self.frame_time).min((self.len() - 1) as f64)).collect();
        Ok(self.resampled(&us, dt))
    }

    /// Frames `[a, b)` as a new clip (indices clamped to the clip; `a ≥ b` gives an empty clip).
    pub fn slice(&self, a: usize, b: usize) -> Motion {
        let n = self.len();
        let b = b.min(n);
        let a = a.min(b);
        let nj = self.n_joints();
        Motion {
            skeleton: self.skeleton.clone(),
            frame_time: self.frame_time,
            root_pos: self.root_pos[a..b].to_vec(),
            labels: self.labels.select(a..b),
            rot: self.rot[a * nj..b * nj].to_vec(),
            extra_trans: self.extra_trans.as_ref().map(|e| e[a * nj..b * nj].to_vec()),
        }
    }

    /// Uniform time stretch to `n_out` frames with the same first and last frame (frame `k` samples
    /// source index `k·(len−1)/(n_out−1)`), keeping `frame_time`: the motion plays slower or faster.
    /// `n_out = 1` gives the first frame; `n_out = 0` or an empty clip an empty clip.
    pub fn time_stretch(&self, n_out: usize) -> Motion {
        let n = self.len();
        let us: Vec<f64> = if n == 0 || n_out == 0 {
            vec![]
        } else if n_out == 1 {
            vec![0.0]
        } else {
            let r = (n - 1) as f64 / (n_out - 1) as f64;
            (0..n_out).map(|k| if k + 1 == n_out { (n - 1) as f64 } else { k as f64 * r }).collect()
        };
        self.resampled(&us, self.frame_time)
    }

    /// Sets the contact flags of every frame from the foot points' motion (motion-graph.md §3.1
    /// step 3): a foot point (ankle, toe) is in contact when its height is below
    /// `h_floor + p.height` and its horizontal speed (central differences, one-sided at the ends)
    /// below `p.speed`, where `h_floor` is the clip's `p.floor_percentile`-th percentile height of
    /// that point; runs of at most `p.fill_gap` non-contact frames between contacts are filled.
    /// Points whose role is missing get no flags. Replaces any previous flags.
    pub fn detect_contacts(&mut self, p: &ContactParams) {
        let n = self.len();
        self.labels.contacts = vec![0; n];
        if n == 0 {
            return;
        }
        let s = self.skeleton.clone();
        let pts = [
            (FrameLabels::L_ANKLE, s.role(JointRole::LeftAnkle)),
            (FrameLabels::L_TOE, s.role(JointRole::LeftToe)),
            (FrameLabels::R_ANKLE, s.role(JointRole::RightAnkle)),
            (FrameLabels::R_TOE, s.role(JointRole::RightToe)),
        ];
        let nj = self.n_joints();
        let mut all = vec![Pt3::origin(); n * nj];
        for f in 0..n {
            self.joint_positions(f, &mut all[f * nj..(f + 1) * nj]);
        }
        for (bit, j) in pts {
            let Some(j) = j else { continue };
            let j = j as usize;
            let y: Vec<f64> = (0..n).map(|f| all[f * nj + j].y).collect();
            let mut sorted = y.clone();
            sorted.sort_by(f64::total_cmp);
            let q = (p.floor_percentile.clamp(0.0, 100.0) / 100.0 * (n - 1) as f64).round() as usize;
            let floor = sorted[q.min(n - 1)];
            let mut on: Vec<bool> = (0..n)
                .map(|f| {
                    let (a, b) = (f.saturating_sub(1), (f + 1).min(n - 1));
                    let d = all[b * nj + j] - all[a * nj + j];
                    let speed = if b > a { d.x.hypot(d.z) / ((b - a) as f64 * self.frame_time) } else { 0.0 };
                    y[f] < floor + p.height && speed < p.speed
                })
                .collect();
            // Fill short gaps between contact runs.
            let mut f = 0;
            while f < n {
                if !on[f] {
                    let start = f;
                    while f < n && !on[f] {
                        f += 1;
                    }
                    if start > 0 && f < n && f - start <= p.fill_gap {
                        on[start..f].iter_mut().for_each(|x| *x = true);
                    }
                } else {
                    f += 1;
                }
            }
            for (c, o) in self.labels.contacts.iter_mut().zip(on) {
                if o {
                    *c |= bit;
                }
            }
        }
    }

    /// Makes every joint's quaternion sequence continuous in sign: `q_f·q_{f−1} ≥ 0` for every
    /// frame (and `w ≥ 0` on frame 0). Rotations are unchanged.
    pub fn fix_hemispheres(&mut self) {
        let nj = self.n_joints();
        let n = self.len();
        for j in 0..nj {
            if n == 0 {
                break;
            }
            if self.rot[j].w < 0.0 {
                self.rot[j] = UnitQuat::new_unchecked(-self.rot[j].into_inner());
            }
            for f in 1..n {
                let prev = self.rot[(f - 1) * nj + j];
                fix_hemisphere(&prev, &mut self.rot[f * nj + j]);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::axis_quat;

    /// Standard humanoid turning about +Y at constant angular velocity `w` (rad/s), root moving
    /// along +X at 1 m/s, left knee bending at 0.5·w.
    fn spinning(n: usize, dt: f64, w: f64) -> Motion {
        let s = Arc::new(Skeleton::standard_humanoid());
        let knee = s.role(JointRole::LeftKnee).unwrap() as usize;
        let poses: Vec<Pose> = (0..n)
            .map(|f| {
                let t = f as f64 * dt;
                let mut p = s.rest_pose();
                p.root_pos += Vec3::new(t, 0.0, 0.0);
                p.rot[0] = axis_quat(1, w * t);
                p.rot[knee] = axis_quat(0, 0.5 * w * t);
                p
            })
            .collect();
        Motion::from_poses(s, dt, &poses).unwrap()
    }

    #[test]
    fn resample_120_to_30_is_exact_for_constant_angular_velocity() {
        let m = spinning(121, 1.0 / 120.0, 2.0);
        let r = m.resample(1.0 / 30.0).unwrap();
        assert_eq!(r.len(), 31);
        let knee = m.skeleton.role(JointRole::LeftKnee).unwrap() as usize;
        for k in 0..r.len() {
            let t = k as f64 / 30.0;
            assert!(r.frame_rot(k)[0].angle_to(&axis_quat(1, 2.0 * t)) <= 1e-9);
            assert!(r.frame_rot(k)[knee].angle_to(&axis_quat(0, t)) <= 1e-9);
            assert!((r.root_pos[k].x - t).abs() < 1e-12);
        }
        // Endpoints preserved (the duration, 1 s, is a multiple of 1/30 s).
        assert_eq!(r.pose(0), m.pose(0));
        let last = r.pose(r.len() - 1);
        let want = m.pose(m.len() - 1);
        assert!((last.root_pos - want.root_pos).norm() < 1e-12);
        for (a, b) in last.rot.iter().zip(&want.rot) {
            assert!(a.angle_to(b) < 1e-12);
        }
        assert!((r.duration() - m.duration()).abs() < 1e-12);
        assert!(m.resample(0.0).is_err());
        assert!(m.resample(f64::NAN).is_err());
    }

    #[test]
    fn resample_frame_count_of_non_multiple_duration() {
        // 2752 frames at 120 Hz → 688 frames at 30 Hz (motion-graph.md §6.1).
        let m = spinning(2752, 1.0 / 120.0, 0.1);
        assert_eq!(m.resample(1.0 / 30.0).unwrap().len(), 688);
        let m = spinning(4511, 1.0 / 120.0, 0.1);
        assert_eq!(m.resample(1.0 / 30.0).unwrap().len(), 1128);
    }

    #[test]
    fn slice_and_time_stretch() {
        let m = spinning(50, 0.01, 1.0);
        let s = m.slice(10, 20);
        assert_eq!(s.len(), 10);
        assert_eq!(s.pose(0), m.pose(10));
        assert_eq!(m.slice(40, 100).len(), 10);
        assert_eq!(m.slice(30, 20).len(), 0);
        let t = m.time_stretch(99);
        assert_eq!(t.len(), 99);
        assert_eq!(t.pose(0), m.pose(0));
        assert_eq!(t.pose(98), m.pose(49));
        // Frame 2 of the stretch is source frame 1.
        assert!((t.root_pos[2] - m.root_pos[1]).norm() < 1e-15);
        assert_eq!(m.time_stretch(1).len(), 1);
        assert!(m.time_stretch(0).is_empty());
        assert_eq!(m.slice(0, 0).time_stretch(5).len(), 0);
    }

    #[test]
    fn hemispheres_are_fixed() {
        let mut m = spinning(10, 0.1, 1.0);
        let nj = m.n_joints();
        for f in (1..10).step_by(2) {
            let q = m.rot[f * nj];
            m.rot[f * nj] = UnitQuat::new_unchecked(-q.into_inner());
        }
        let before = m.clone();
        m.fix_hemispheres();
        for f in 1..10 {
            assert!(m.rot[f * nj].coords.dot(&m.rot[(f - 1) * nj].coords) >= 0.0);
            assert!(m.rot[f * nj].angle_to(&before.rot[f * nj]) < 1e-15);
        }
    }

    #[test]
    fn torso_frame_heading() {
        let m = spinning(100, 0.05, 1.0);
        for f in [0, 10, 50, 99] {
            let p = m.torso_frame(f);
            let t = f as f64 * 0.05;
            assert!(wrap_angle(p.yaw - t).abs() < 1e-12, "frame {f}: {} vs {t}", p.yaw);
            assert_eq!((p.x, p.z), (m.root_pos[f].x, m.root_pos[f].z));
        }
        // Unwrapped: 99 frames × 0.05 rad/frame = 4.95 rad, beyond π.
        let all = m.torso_frames();
        assert!((all[99].yaw - 4.95).abs() < 1e-12, "{}", all[99].yaw);
        // Lying on the side: the pelvis axis is vertical, the forward axis decides.
        let s = m.skeleton.clone();
        let mut p = s.rest_pose();
        p.rot[0] = axis_quat(1, 0.4) * axis_quat(2, FRAC_PI_2);
        let lying = Motion::from_poses(s, 0.1, &[p]).unwrap();
        assert!((lying.torso_frame(0).yaw - 0.4).abs() < 1e-12);
    }

    #[test]
    fn labels_follow_frames() {
        let mut m = spinning(20, 0.1, 1.0);
        let jump = m.labels.add("jump").unwrap();
        m.labels.set(5, jump, true);
        m.labels.contacts[6] = FrameLabels::L_TOE;
        let s = m.slice(5, 7);
        assert!(s.labels.has(0, jump) && !s.labels.has(1, jump));
        assert_eq!(s.labels.contacts[1], FrameLabels::L_TOE);
        m.labels.set(5, jump, false);
        assert!(!m.labels.has(5, jump));
        assert!(!m.labels.has(500, jump));
        let r = m.resample(0.2).unwrap();
        assert_eq!(r.labels.bits.len(), r.len());
        assert_eq!(r.labels.names, vec!["jump".to_string()]);
    }

    #[test]
    fn construction_checks_sizes() {
        let s = Arc::new(Skeleton::standard_humanoid());
        let bad = Motion::new(s.clone(), 0.1, vec![Vec3::zeros()], vec![UnitQuat::identity(); 3], None);
        assert!(matches!(bad, Err(Error::DimensionMismatch { .. })));
        let bad = Motion::new(s.clone(), 0.0, vec![], vec![], None);
        assert!(matches!(bad, Err(Error::InvalidParameter(_))));
        let ok = Motion::new(s, 0.1, vec![], vec![], None).unwrap();
        assert!(ok.is_empty());
        assert_eq!(ok.duration(), 0.0);
        assert!(ok.pose_at(0.0).is_err());
    }
}

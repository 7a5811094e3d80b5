//! Per-frame features and the frame-to-frame cost (motion-graph.md §3.1 steps 4–6, §3.2;
//! paper's Appendix A, matrices reconstructed).
//!
//! For frame `f`, in its own torso frame: `A(f) = [p_1 … p_n | v_T | ω_T]` (joint positions,
//! root linear and angular velocity) and `B(f) = [ṗ_1 … ṗ_n | a_T | α_T]` (joint velocities,
//! root linear and angular acceleration). The cost
//! `C(f, g) = Σ_k M_k ‖A_k(f) − A_k(g)‖²/O_k² + Σ_k T_k ‖B_k(f) − B_k(g)‖²/L_k²`
//! is a squared Euclidean distance between scaled feature vectors `φ(f) ∈ R^{6(n+2)}`.
//! Normalizers `O`, `L` are group-wise RMS deviations over the database (one for all joint
//! positions, one for all joint velocities, one each for the four root quantities).

use crate::db::Database;
use geom_core::anim::JointRole;
use geom_core::math::{axis_quat, quat_log, Planar, Pt3, UnitQuat, Vec3};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// Per-joint weights `(M_k, T_k)` of the cost (§3.2).
#[derive(Clone, Debug, PartialEq, Default, Serialize, Deserialize)]
pub enum JointWeights {
    /// Ankle and toe 2; knee, hip, root, spine, chest, neck, head 1; collar, shoulder, elbow 0.7;
    /// hand 0.5; both torso columns 1.
    #[default]
    Default,
    /// Explicit `(role, position weight, velocity weight)`; unlisted feature joints get 1.
    Explicit(Vec<(JointRole, f64, f64)>),
}

fn default_weight(r: JointRole) -> f64 {
    use JointRole::*;
    match r {
        LeftAnkle | RightAnkle | LeftToe | RightToe => 2.0,
        LeftCollar | RightCollar | LeftShoulder | RightShoulder | LeftElbow | RightElbow => 0.7,
        LeftHand | RightHand => 0.5,
        _ => 1.0,
    }
}

/// Features of every database frame (global frame index = `offsets[clip] + frame`).
#[derive(Clone, Debug)]
pub struct FeatureTable {
    /// First global frame of each clip, plus the total at the end.
    pub offsets: Vec<usize>,
    /// Torso frame `T(s_i)` of every frame (clip coordinates, yaw unwrapped within a clip).
    pub torso: Vec<Planar>,
    /// Torso-frame positions of **all** joints, frames × joints (f32, for joint constraints).
    pub local_pos: Vec<[f32; 3]>,
    /// Joints per frame in `local_pos`.
    pub n_joints: usize,
    /// Feature joints (indices into the skeleton).
    pub feature_joints: Vec<usize>,
    /// Scaled features φ, frames × `dim` (f64).
    pub phi: Vec<f64>,
    /// Feature dimension `6(n + 2)`.
    pub dim: usize,
    /// Normalizers `[O_pos, O_v, O_ω, L_vel, L_a, L_α]`.
    pub norms: [f64; 6],
}

/// Extended per-clip kinematics (with one frame of the neighbouring fragments at both ends).
struct Kin {
    /// Indices into the arrays below of frame `k` is `k + 1`; `has_prev`, `has_next` say whether
    /// slots 0 and n+1 hold real frames.
    world: Vec<Vec<Pt3>>,
    root_rot: Vec<UnitQuat>,
    torso: Vec<Planar>,
    has_prev: bool,
    has_next: bool,
}

fn kin(db: &Database, c: usize) -> Kin {
    let m = &db.clips[c];
    let nj = m.n_joints();
    let n = m.len();
    let root = db.skeleton.role(JointRole::Root).unwrap_or(0) as usize;
    let torso_c = m.torso_frames();
    let frame = |mm: &geom_core::anim::Motion, f: usize| -> (Vec<Pt3>, UnitQuat) {
        let mut g = vec![geom_core::math::Iso3::identity(); nj];
        mm.globals(f, &mut g);
        (g.iter().map(|x| Pt3::from(x.translation.vector)).collect(), g[root].rotation)
    };
    let mut world = Vec::with_capacity(n + 2);
    let mut root_rot = Vec::with_capacity(n + 2);
    let mut torso = Vec::with_capacity(n + 2);
    let prev = db.prev[c].map(|p| &db.clips[p as usize]).filter(|p| p.len() >= 2);
    let next = db.next[c].map(|p| &db.clips[p as usize]).filter(|p| p.len() >= 2);
    match prev {
        Some(p) => {
            let (w, r) = frame(p, p.len() - 2);
            let tp = p.torso_frame(p.len() - 2);
            let mut t = tp;
            t.yaw = torso_c[0].yaw + geom_core::math::wrap_angle(tp.yaw - torso_c[0].yaw);
            world.push(w);
            root_rot.push(r);
            torso.push(t);
        }
        None => {
            let (w, r) = frame(m, 0);
            world.push(w);
            root_rot.push(r);
            torso.push(torso_c[0]);
        }
    }
    for (f, t) in torso_c.iter().enumerate() {
        let (w, r) = frame(m, f);
        world.push(w);
        root_rot.push(r);
        torso.push(*t);
    }
    match next {
        Some(q) => {
            let (w, r) = frame(q, 1);
            let tq = q.torso_frame(1);
            let mut t = tq;
            t.yaw = torso_c[n - 1].yaw + geom_core::math::wrap_angle(tq.yaw - torso_c[n - 1].yaw);
            world.push(w);
            root_rot.push(r);
            torso.push(t);
        }
        None => {
            let (w, r) = frame(m, n - 1);
            world.push(w);
            root_rot.push(r);
            torso.push(torso_c[n - 1]);
        }
    }
    Kin { world, root_rot, torso, has_prev: prev.is_some(), has_next: next.is_some() }
}

/// Raw (unscaled) feature groups of one clip: per frame, joint positions P (feature joints),
/// v_T, ω_T, ṗ, a_T, α_T, all in the frame's torso frame.
struct Raw {
    p: Vec<Vec3>,
    v: Vec<Vec3>,
    w: Vec<Vec3>,
    pd: Vec<Vec3>,
    a: Vec<Vec3>,
    al: Vec<Vec3>,
    local_all: Vec<[f32; 3]>,
    torso: Vec<Planar>,
}

fn raw(db: &Database, c: usize, fj: &[usize]) -> Raw {
    let k = kin(db, c);
    let n = db.clips[c].len();
    let nj = db.clips[c].n_joints();
    let dt = 1.0 / db.rate_hz;
    let root = db.skeleton.role(JointRole::Root).unwrap_or(0) as usize;
    let lo = if k.has_prev { 0 } else { 1 };
    let hi = if k.has_next { n + 1 } else { n };
    // Torso-frame positions of all joints in every extended slot.
    let local: Vec<Vec<Vec3>> = (0..n + 2)
        .map(|s| {
            let inv = k.torso[s].inverse();
            k.world[s].iter().map(|p| inv.apply_point(p.coords)).collect()
        })
        .collect();
    let mut r = Raw {
        p: Vec::new(),
        v: Vec::new(),
        w: Vec::new(),
        pd: Vec::new(),
        a: Vec::new(),
        al: Vec::new(),
        local_all: Vec::with_capacity(n * nj),
        torso: k.torso[1..=n].to_vec(),
    };
    for f in 0..n {
        let s = f + 1;
        let (sa, sb) = ((s - 1).max(lo), (s + 1).min(hi));
        let span = (sb - sa) as f64 * dt;
        let to_torso = axis_quat(1, -k.torso[s].yaw);
        for &j in fj {
            r.p.push(local[s][j]);
            r.pd.push(if span > 0.0 { (local[sb][j] - local[sa][j]) / span } else { Vec3::zeros() });
        }
        for q in &local[s] {
            r.local_all.push([q.x as f32, q.y as f32, q.z as f32]);
        }
        let x = |i: usize| k.world[i][root].coords;
        let v = if span > 0.0 { (x(sb) - x(sa)) / span } else { Vec3::zeros() };
        r.v.push(to_torso * v);
        let om = if span > 0.0 { quat_log(&(k.root_rot[sb] * k.root_rot[sa].inverse())) / span } else { Vec3::zeros() };
        r.w.push(to_torso * om);
        // Second differences need both neighbours; at a true end use the adjacent interior frame.
        let c2 = if s > lo && s < hi {
            s
        } else if s <= lo {
            (s + 1).min(hi.saturating_sub(1)).max(lo + 1)
        } else {
            (s - 1).max(lo + 1)
        };
        let (a, al) = if c2 > lo && c2 < n + 1 && c2 < hi {
            let acc = (x(c2 + 1) - 2.0 * x(c2) + x(c2 - 1)) / (dt * dt);
            let w1 = quat_log(&(k.root_rot[c2 + 1] * k.root_rot[c2].inverse()));
            let w0 = quat_log(&(k.root_rot[c2] * k.root_rot[c2 - 1].inverse()));
            (acc, (w1 - w0) / (dt * dt))
        } else {
            (Vec3::zeros(), Vec3::zeros())
        };
        r.a.push(to_torso * a);
        r.al.push(to_torso * al);
    }
    r
}

fn rms_dev(xs: &[Vec3], groups: usize) -> f64 {
    if xs.is_empty() {
        return 1.0;
    }
    // Mean per group member (xs is frames × groups, row-major).
    let mut mean = vec![Vec3::zeros(); groups];
    for (i, x) in xs.iter().enumerate() {
        mean[i % groups] += x;
    }
    let nf = (xs.len() / groups) as f64;
    for m in mean.iter_mut() {
        *m /= nf;
    }
    let ss: f64 = xs.iter().enumerate().map(|(i, x)| (x - mean[i % groups]).norm_squared()).sum();
    let r = (ss / xs.len() as f64).sqrt();
    if r > 1e-12 && r.is_finite() {
        r
    } else {
        1.0
    }
}

impl FeatureTable {
    /// Features of every frame of `db` (parallel over clips, deterministic).
    pub fn build(db: &Database, weights: &JointWeights) -> FeatureTable {
        let s = &db.skeleton;
        let root = s.role(JointRole::Root).unwrap_or(0) as usize;
        let mut fj: Vec<(usize, f64)> = Vec::new();
        for (r, &j) in &s.roles {
            let j = j as usize;
            let joint = &s.joints[j];
            if joint.end_site || (j != root && joint.offset.norm() < 1e-9) {
                continue;
            }
            let w = match weights {
                JointWeights::Default => default_weight(*r),
                JointWeights::Explicit(list) => list.iter().find(|(rr, _, _)| rr == r).map_or(1.0, |x| x.1),
            };
            fj.push((j, w));
        }
        fj.sort_by_key(|x| x.0);
        fj.dedup_by_key(|x| x.0);
        let vel_w: Vec<f64> = fj
            .iter()
            .map(|(j, w)| match weights {
                JointWeights::Default => *w,
                JointWeights::Explicit(list) => {
                    list.iter().find(|(r, _, _)| s.role(*r) == Some(*j as u16)).map_or(1.0, |x| x.2)
                }
            })
            .collect();
        let joints: Vec<usize> = fj.iter().map(|x| x.0).collect();
        let raws: Vec<Raw> = (0..db.clips.len()).into_par_iter().map(|c| raw(db, c, &joints)).collect();
        let nf = joints.len();
        let cat = |get: &dyn Fn(&Raw) -> &Vec<Vec3>| -> Vec<Vec3> {
            raws.iter().flat_map(|r| get(r).iter().copied()).collect()
        };
        let o_pos = rms_dev(&cat(&|r| &r.p), nf.max(1));
        let o_v = rms_dev(&cat(&|r| &r.v), 1);
        let o_w = rms_dev(&cat(&|r| &r.w), 1);
        let l_vel = rms_dev(&cat(&|r| &r.pd), nf.max(1));
        let l_a = rms_dev(&cat(&|r| &r.a), 1);
        let l_al = rms_dev(&cat(&|r| &r.al), 1);
        let dim = 6 * (nf + 2);
        let mut offsets = vec![0usize];
        let mut phi = Vec::new();
        let mut torso = Vec::new();
        let mut local_pos = Vec::new();
        for r in &raws {
            let n = r.torso.len();
            offsets.push(offsets.last().copied().unwrap_or(0) + n);
            for f in 0..n {
                let push = |phi: &mut Vec<f64>, v: &Vec3, s: f64| phi.extend_from_slice(&[v.x * s, v.y * s, v.z * s]);
                for (k, (_, w)) in fj.iter().enumerate() {
                    push(&mut phi, &r.p[f * nf + k], w.sqrt() / o_pos);
                }
                push(&mut phi, &r.v[f], 1.0 / o_v);
                push(&mut phi, &r.w[f], 1.0 / o_w);
                for (k, w) in vel_w.iter().enumerate() {
                    push(&mut phi, &r.pd[f * nf + k], w.sqrt() / l_vel);
                }
                push(&mut phi, &r.a[f], 1.0 / l_a);
                push(&mut phi, &r.al[f], 1.0 / l_al);
            }
            torso.extend_from_slice(&r.torso);
            local_pos.extend_from_slice(&r.local_all);
        }
        FeatureTable {
            offsets,
            torso,
            local_pos,
            n_joints: db.skeleton.joints.len(),
            feature_joints: joints,
            phi,
            dim,
            norms: [o_pos, o_v, o_w, l_vel, l_a, l_al],
        }
    }

    /// Global index of `(clip, frame)`.
    pub fn global(&self, clip: u32, frame: u32) -> usize {
        self.offsets[clip as usize] + frame as usize
    }

    /// Number of frames.
    pub fn frames(&self) -> usize {
        *self.offsets.last().unwrap_or(&0)
    }

    /// Feature vector of global frame `g`.
    pub fn phi(&self, g: usize) -> &[f64] {
        &self.phi[g * self.dim..(g + 1) * self.dim]
    }

    /// Exact f64 cost `C(f, g)` between global frames (§3.2).
    pub fn cost(&self, f: usize, g: usize) -> f64 {
        self.phi(f).iter().zip(self.phi(g)).map(|(a, b)| (a - b) * (a - b)).sum()
    }

    /// Torso frame of `(clip, frame)` in clip coordinates.
    pub fn torso(&self, clip: u32, frame: u32) -> Planar {
        self.torso[self.global(clip, frame)]
    }

    /// Torso-frame position of joint `j` at `(clip, frame)`.
    pub fn local(&self, clip: u32, frame: u32, j: usize) -> Vec3 {
        let p = self.local_pos[self.global(clip, frame) * self.n_joints + j];
        Vec3::new(p[0] as f64, p[1] as f64, p[2] as f64)
    }
}

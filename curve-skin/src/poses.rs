//! Poses for the test characters: world-axis joint rotations converted to the local rotations of
//! `forward_kinematics_local`, the humanoid test poses of spec §6.3, and a simple procedural walk
//! cycle (the issue allows one while `geom_core::anim::synth` is absent).

use geom_core::anim::skin::{forward_kinematics_local, SkinSkeleton};
use geom_core::math::{Iso3, UnitQuat, Vec3};
use nalgebra::Unit;
use std::f64::consts::PI;

use crate::procedural::HUMANOID_JOINTS;

/// A pose of a [`SkinSkeleton`]: local rotations (relative to the rest local frames), the root
/// position, and optional authored twist angles per joint (rad) for curve skinning.
#[derive(Clone, Debug, PartialEq)]
pub struct SkinPose {
    /// Local rotation per joint.
    pub rot: Vec<UnitQuat>,
    /// Position of joint 0 (m).
    pub root_pos: Vec3,
    /// Authored twist per joint (rad).
    pub twist_hint: Vec<Option<f64>>,
}

impl SkinPose {
    /// The bind pose.
    pub fn rest(sk: &SkinSkeleton) -> SkinPose {
        SkinPose {
            rot: vec![UnitQuat::identity(); sk.len()],
            root_pos: sk.rest_world.first().map(|f| f.translation.vector).unwrap_or_default(),
            twist_hint: vec![None; sk.len()],
        }
    }

    /// Sets joint `j` to rotate by the world-axis rotation `g` relative to its parent's motion
    /// (`q_j = R⁰_j⁻¹ g R⁰_j`): in the bind pose, `g` is what the joint's subtree does.
    pub fn set_world(&mut self, sk: &SkinSkeleton, j: usize, g: UnitQuat) {
        let r0 = sk.rest_world[j].rotation;
        self.rot[j] = r0.inverse() * g * r0;
    }

    /// Posed world frames.
    pub fn globals(&self, sk: &SkinSkeleton) -> Vec<Iso3> {
        forward_kinematics_local(sk, &self.root_pos, &self.rot)
    }
}

/// Rotation about a world axis by `deg` degrees.
pub fn axis_deg(axis: Vec3, deg: f64) -> UnitQuat {
    UnitQuat::from_axis_angle(&Unit::new_normalize(axis), deg.to_radians())
}

fn idx(name: &str) -> usize {
    // The names are the constant table; a miss is a programming error caught by the tests.
    HUMANOID_JOINTS.iter().position(|n| *n == name).expect("humanoid joint name")
}

/// The named humanoid test poses of spec §6.3.
pub fn humanoid_pose(sk: &SkinSkeleton, name: &str) -> Option<SkinPose> {
    let mut p = SkinPose::rest(sk);
    let x = Vec3::x();
    let y = Vec3::y();
    let z = Vec3::z();
    match name {
        "rest" => {}
        "elbows_90" | "elbows_135" => {
            let a = if name == "elbows_90" { 90.0 } else { 135.0 };
            p.set_world(sk, idx("l_elbow"), axis_deg(y, -a));
            p.set_world(sk, idx("r_elbow"), axis_deg(y, a));
        }
        "twist_90" | "twist_180" => {
            let a: f64 = if name == "twist_90" { 90.0 } else { 180.0 };
            p.set_world(sk, idx("l_elbow"), axis_deg(x, a));
            p.set_world(sk, idx("r_elbow"), axis_deg(x, -a));
            p.twist_hint[idx("l_elbow")] = Some(a.to_radians());
            p.twist_hint[idx("r_elbow")] = Some(a.to_radians());
        }
        "squat" => {
            for s in ["l", "r"] {
                p.set_world(sk, idx(&format!("{s}_hip")), axis_deg(x, -100.0));
                p.set_world(sk, idx(&format!("{s}_knee")), axis_deg(x, 120.0));
                p.set_world(sk, idx(&format!("{s}_ankle")), axis_deg(x, -20.0));
            }
            p.root_pos.y -= 0.35;
        }
        "shoulder_raise_150" => {
            // Abduction 150° from arms-down = 60° above the T-pose.
            p.set_world(sk, idx("l_shoulder"), axis_deg(z, 60.0));
            p.set_world(sk, idx("r_shoulder"), axis_deg(z, -60.0));
        }
        _ => return None,
    }
    Some(p)
}

/// Names accepted by [`humanoid_pose`] (besides "rest").
pub const HUMANOID_POSES: [&str; 6] =
    ["elbows_90", "elbows_135", "twist_90", "twist_180", "squat", "shoulder_raise_150"];

/// A procedural walk cycle at time `t` (s): period 1.1 s, 1.3 m/s forward (+z), hip flexion
/// ±25°, knee flexion up to 55°, arms lowered 75° and swinging ±20° in counter-phase, elbows
/// flexed 15–35°, pelvis yaw ±5° and bob 2 cm.
pub fn walk_pose(sk: &SkinSkeleton, t: f64) -> SkinPose {
    let mut p = SkinPose::rest(sk);
    let phi = 2.0 * PI * t / 1.1;
    let x = Vec3::x();
    let y = Vec3::y();
    let z = Vec3::z();
    for (side, ph) in [("l", 0.0), ("r", PI)] {
        let f = phi + ph;
        p.set_world(sk, idx(&format!("{side}_hip")), axis_deg(x, -25.0 * f.sin()));
        let knee = 5.0 + 50.0 * (0.5 - 0.5 * (f + 0.9).cos()).powi(2);
        p.set_world(sk, idx(&format!("{side}_knee")), axis_deg(x, knee));
        p.set_world(sk, idx(&format!("{side}_ankle")), axis_deg(x, -10.0 * (f - 0.5).sin()));
        let (down, sgn) = if side == "l" { (-75.0, 1.0) } else { (75.0, -1.0) };
        let swing = axis_deg(x, 20.0 * (f + PI).sin());
        p.set_world(sk, idx(&format!("{side}_shoulder")), swing * axis_deg(z, down));
        let elbow = 25.0 + 10.0 * (f + PI).sin();
        p.set_world(sk, idx(&format!("{side}_elbow")), axis_deg(y, -sgn * elbow));
    }
    p.set_world(sk, idx("pelvis"), axis_deg(y, 5.0 * phi.sin()));
    p.set_world(sk, idx("chest"), axis_deg(y, -7.0 * phi.sin()));
    p.root_pos += Vec3::new(0.0, 0.02 * (2.0 * phi).cos() - 0.02, 1.3 * t);
    p
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::procedural::humanoid_skeleton;

    #[test]
    fn every_named_pose_exists_and_keeps_bone_lengths() {
        let sk = humanoid_skeleton().unwrap();
        for name in HUMANOID_POSES.iter().chain(["rest"].iter()) {
            let p = humanoid_pose(&sk, name).unwrap();
            let g = p.globals(&sk);
            for j in 0..sk.len() {
                if let Some(par) = sk.parent[j] {
                    let l0 = (sk.rest_world[j].translation.vector - sk.rest_world[par].translation.vector).norm();
                    let l1 = (g[j].translation.vector - g[par].translation.vector).norm();
                    assert!((l0 - l1).abs() < 1e-12, "{name}: joint {j}");
                }
            }
        }
        assert!(humanoid_pose(&sk, "nope").is_none());
    }

    #[test]
    fn elbow_pose_bends_the_forearm_by_the_angle() {
        let sk = humanoid_skeleton().unwrap();
        let p = humanoid_pose(&sk, "elbows_90").unwrap();
        let g = p.globals(&sk);
        let (e, w, s) = (idx("l_elbow"), idx("l_wrist"), idx("l_shoulder"));
        let u = (g[w].translation.vector - g[e].translation.vector).normalize();
        let v = (g[e].translation.vector - g[s].translation.vector).normalize();
        assert!((u.dot(&v)).abs() < 1e-12);
        // Forward (+z).
        assert!(u.z > 0.99);
    }

    #[test]
    fn walk_feet_stay_near_the_ground() {
        let sk = humanoid_skeleton().unwrap();
        for i in 0..22 {
            let g = walk_pose(&sk, i as f64 * 0.05).globals(&sk);
            let low = g[idx("l_ankle")].translation.y.min(g[idx("r_ankle")].translation.y);
            assert!(low > 0.0 && low < 0.2, "{low}");
        }
    }
}

//! A simple procedural walk cycle for a rigged biped (spec §3.14): sinusoidal hip, knee,
//! shoulder and elbow angles about the lateral (x) axis, a small vertical bob and constant
//! forward speed. Joints are mapped by the template's joint names (the bone ending at
//! `l_knee` is the left thigh, and so on), so any template using the human names walks.
//! Used until `geom_core::anim::synth` lands in this tree.

use geom_core::anim::skin::SkinSkeleton;
use geom_core::anim::Pose;
use geom_core::math::{UnitQuat, Vec3};
use nalgebra::Unit;

/// Walk poses for `sk` (a [`crate::Rig::skin_skeleton`]): `frames` poses at `fps` covering
/// `cycles` gait cycles of period 1.1 s; `leg_length` (same units as the skeleton) sets the
/// stride. Returns (times in s, poses).
pub fn walk_cycle(sk: &SkinSkeleton, leg_length: f64, cycles: usize, fps: f64) -> (Vec<f64>, Vec<Pose>) {
    let period = 1.1;
    let frames = ((cycles as f64 * period * fps).round() as usize).max(2);
    let x = Unit::new_normalize(Vec3::x());
    let find = |n: &str| sk.names.iter().position(|s| s == n);
    // (bone name, amplitude rad, phase rad, offset rad): rotation about +x = swing backwards.
    let spec: [(&str, f64, f64, f64); 8] = [
        ("l_knee", 0.45, 0.0, 0.0),
        ("r_knee", 0.45, std::f64::consts::PI, 0.0),
        ("l_ankle", 0.35, -1.2, 0.35),
        ("r_ankle", 0.35, std::f64::consts::PI - 1.2, 0.35),
        ("l_elbow", 0.35, std::f64::consts::PI, 0.0),
        ("r_elbow", 0.35, 0.0, 0.0),
        ("l_hand", 0.15, std::f64::consts::PI, -0.3),
        ("r_hand", 0.15, 0.0, -0.3),
    ];
    let stride = 2.0 * leg_length * 0.45f64.sin();
    let rest0 = sk.rest_world[0].translation.vector;
    let mut times = Vec::with_capacity(frames);
    let mut poses = Vec::with_capacity(frames);
    for f in 0..frames {
        let t = f as f64 / fps;
        let phi = 2.0 * std::f64::consts::PI * t / period;
        let mut rot = vec![UnitQuat::identity(); sk.len()];
        for (name, amp, phase, off) in spec {
            if let Some(j) = find(name) {
                let theta = off + amp * (phi + phase).sin();
                let r = sk.rest_world[j].rotation;
                rot[j] = r.inverse() * UnitQuat::from_axis_angle(&x, -theta) * r;
            }
        }
        let bob = 0.02 * leg_length * (2.0 * phi).cos();
        let root_pos = rest0 + Vec3::new(0.0, bob, stride * t / period * 2.0);
        times.push(t);
        poses.push(Pose { root_pos, rot });
    }
    (times, poses)
}

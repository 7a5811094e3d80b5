//! Rotation and kinematics tests (motion-graph.md §7.1 tests 1, 6): Euler orders against explicit
//! matrix products, quaternion → Euler → quaternion round trips, gimbal lock, resampling at
//! constant angular velocity, two-bone IK.

use geom_core::anim::ik::two_bone;
use geom_core::anim::{JointRole, Motion, Pose, Skeleton};
use geom_core::math::{euler_to_quat, quat_exp, quat_to_euler, Mat3, Pt3, RotOrder, UnitQuat, Vec3};
use geom_core::rng::Rng;
use std::f64::consts::{FRAC_PI_2, PI};
use std::sync::Arc;

fn rot(axis: usize, a: f64) -> Mat3 {
    let (s, c) = a.sin_cos();
    match axis {
        0 => Mat3::new(1.0, 0.0, 0.0, 0.0, c, -s, 0.0, s, c),
        1 => Mat3::new(c, 0.0, s, 0.0, 1.0, 0.0, -s, 0.0, c),
        _ => Mat3::new(c, -s, 0.0, s, c, 0.0, 0.0, 0.0, 1.0),
    }
}

#[test]
fn euler_to_quat_equals_the_explicit_matrix_product() {
    let mut rng = Rng::new(1);
    for o in RotOrder::ALL {
        let [a1, a2, a3] = o.axes();
        for _ in 0..1000 {
            let t = [rng.range(-PI, PI), rng.range(-PI, PI), rng.range(-PI, PI)];
            let r1 = euler_to_quat(o, t).to_rotation_matrix().into_inner();
            let r2 = rot(a1, t[0]) * rot(a2, t[1]) * rot(a3, t[2]);
            assert!((r1 - r2).norm() <= 1e-12, "{o:?} {t:?}: {}", (r1 - r2).norm());
        }
    }
}

#[test]
fn quat_euler_quat_round_trip_away_from_gimbal_lock() {
    let mut rng = Rng::new(2);
    for o in RotOrder::ALL {
        for _ in 0..1000 {
            let q = quat_exp(&(rng.unit_vec3() * rng.range(0.0, PI)));
            let e = quat_to_euler(o, &q);
            // Skip the immediate neighbourhood of the lock (tested separately below).
            if (e[1].abs() - FRAC_PI_2).abs() < 1e-6 {
                continue;
            }
            assert!(e[1].abs() <= FRAC_PI_2 && e[0].abs() <= PI && e[2].abs() <= PI);
            let back = euler_to_quat(o, e);
            assert!(back.angle_to(&q) <= 1e-10, "{o:?}: {}", back.angle_to(&q));
            // Euler → quat → Euler reproduces the angles (canonical range, not at the lock).
            let e2 = quat_to_euler(o, &back);
            for k in 0..3 {
                assert!((e2[k] - e[k]).abs() < 1e-9, "{o:?} {e:?} {e2:?}");
            }
        }
    }
}

#[test]
fn gimbal_lock_and_its_neighbourhood() {
    let mut rng = Rng::new(3);
    for o in RotOrder::ALL {
        for _ in 0..200 {
            let mid = if rng.f64() < 0.5 { FRAC_PI_2 } else { -FRAC_PI_2 };
            let t = [rng.range(-PI, PI), mid, rng.range(-PI, PI)];
            let q = euler_to_quat(o, t);
            let e = quat_to_euler(o, &q);
            assert_eq!(e[2], 0.0, "{o:?}: third angle must be zero at gimbal lock");
            assert!(euler_to_quat(o, e).angle_to(&q) <= 1e-10, "{o:?}");
            // Near the lock (1e-7 … 1e-13 away) recomposition stays accurate.
            for d in [1e-7, 1e-10, 1e-13] {
                let t = [t[0], mid - mid.signum() * d, t[2]];
                let q = euler_to_quat(o, t);
                let back = euler_to_quat(o, quat_to_euler(o, &q));
                assert!(back.angle_to(&q) <= 1e-10, "{o:?} d = {d}: {}", back.angle_to(&q));
            }
        }
    }
}

#[test]
fn resampling_constant_angular_velocity_is_exact() {
    // Every joint spins at its own constant angular velocity about its own axis; 120 → 30 Hz.
    let s = Arc::new(Skeleton::standard_humanoid());
    let nj = s.joints.len();
    let mut rng = Rng::new(4);
    let axes: Vec<Vec3> = (0..nj).map(|_| rng.unit_vec3()).collect();
    let rates: Vec<f64> = (0..nj).map(|_| rng.range(-6.0, 6.0)).collect();
    let at = |t: f64| Pose {
        root_pos: Vec3::new(0.0, 0.95, 1.3 * t),
        rot: (0..nj)
            .map(|j| UnitQuat::from_axis_angle(&nalgebra::Unit::new_normalize(axes[j]), rates[j] * t))
            .collect(),
    };
    let poses: Vec<Pose> = (0..241).map(|f| at(f as f64 / 120.0)).collect();
    let mut m = Motion::from_poses(s, 1.0 / 120.0, &poses).unwrap();
    m.fix_hemispheres();
    let r = m.resample(1.0 / 30.0).unwrap();
    assert_eq!(r.len(), 61);
    for k in 0..r.len() {
        let want = at(k as f64 / 30.0);
        for j in 0..nj {
            assert!(r.frame_rot(k)[j].angle_to(&want.rot[j]) <= 1e-9, "frame {k} joint {j}");
        }
        assert!((r.root_pos[k] - want.root_pos).norm() <= 1e-12);
    }
    // A non-integer ratio (120 → 50 Hz) still samples the exact rotations.
    let r = m.resample(1.0 / 50.0).unwrap();
    for k in 0..r.len() {
        let want = at(k as f64 / 50.0);
        for j in 0..nj {
            assert!(r.frame_rot(k)[j].angle_to(&want.rot[j]) <= 1e-9);
        }
    }
}

#[test]
fn two_bone_ik_places_the_standard_leg() {
    let s = Skeleton::standard_humanoid();
    let g = s.rest_globals();
    let hip = Pt3::from(g[s.role(JointRole::LeftHip).unwrap() as usize].translation.vector);
    let mut rng = Rng::new(5);
    for _ in 0..1000 {
        let target = hip + rng.unit_vec3() * rng.range(0.05, 0.9);
        let (knee, ankle) = two_bone(&hip, 0.42, 0.40, &target, &Vec3::z());
        assert!(((knee - hip).norm() - 0.42).abs() < 1e-12);
        assert!(((ankle - knee).norm() - 0.40).abs() < 1e-12);
        let d = (target - hip).norm();
        if (0.02..=0.82).contains(&d) {
            assert!((ankle - target).norm() < 1e-12);
        } else {
            // Clamped onto the ray towards the target.
            let dir = (ankle - hip).normalize();
            assert!((dir - (target - hip).normalize()).norm() < 1e-12);
        }
    }
}

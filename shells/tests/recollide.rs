//! `ShellSim::recollide` (requested by tracks): replacing the end-of-step velocities reruns the
//! collision pass from q_k and keeps the state collision-free.

mod common;

use common::{cloth, desc, sheet};
use geom_core::math::{Pt3, Vec3};
use shells::{
    CollisionSettings, Damping, IntegratorKind, Obstacle, ObstacleShape, ShellError, ShellSim, VertexConstraint,
};

/// Without collision effects, recollide sets q = q_k + h·v for free vertices and leaves pinned
/// ones bitwise in place; bad calls are typed errors that leave the state unchanged.
#[test]
fn replaces_velocities_and_positions() {
    let (p, f) = sheet(5, 0.4, 0.5);
    let mut d = desc(p.clone(), f.clone(), cloth(Damping::None));
    d.constraints.push(VertexConstraint::Pinned(vec![0]));
    let mut sim = ShellSim::new(d).unwrap();
    assert!(matches!(sim.recollide(&vec![Vec3::zeros(); p.len()]), Err(ShellError::BadParameter(_))));
    let h = 1.0 / 120.0;
    sim.step(h).unwrap();
    let before = sim.state().clone();
    assert!(matches!(sim.recollide(&[Vec3::zeros()]), Err(ShellError::BadParameter(_))));
    let mut bad = vec![Vec3::zeros(); p.len()];
    bad[3].x = f64::NAN;
    assert!(matches!(sim.recollide(&bad), Err(ShellError::NonFinite(_))));
    assert_eq!(sim.state().q, before.q);
    let v_new: Vec<Vec3> = (0..p.len()).map(|i| Vec3::new(0.01 * i as f64, 0.02, -0.01)).collect();
    sim.recollide(&v_new).unwrap();
    // q_k is the rest sheet: the first step started from rest with no forces.
    for i in 0..p.len() {
        if i == 0 {
            assert_eq!(sim.state().q[0], before.q[0]);
            assert_eq!(sim.state().v[0], before.v[0]);
        } else {
            assert_eq!(sim.state().v[i], v_new[i]);
            assert!((sim.state().q[i] - (p[i] + h * v_new[i])).norm() < 1e-15);
        }
    }
    assert_eq!(sim.state().t, before.t);
    // BDF2 is refused.
    let mut d2 = desc(p, f, cloth(Damping::None));
    d2.integrator.kind = IntegratorKind::Bdf2;
    let mut sim2 = ShellSim::new(d2).unwrap();
    sim2.step(h).unwrap();
    assert!(matches!(sim2.recollide(&sim2.state().v.clone()), Err(ShellError::BadParameter(_))));
}

/// Velocities that would drive the sheet through a ground plane are filtered: after recollide
/// every vertex stays above the plane.
#[test]
fn filters_through_the_collision_pass() {
    let (p, f) = sheet(5, 0.4, 0.01);
    let mut d = desc(p.clone(), f, cloth(Damping::None));
    d.effects.collision = Some(CollisionSettings { thickness: 0.004, ..Default::default() });
    d.effects.obstacles =
        vec![Obstacle { shape: ObstacleShape::Plane { normal: Vec3::y(), offset: 0.0 }, friction: 0.5, motion: None }];
    let mut sim = ShellSim::new(d).unwrap();
    let h = 1.0 / 60.0;
    sim.step(h).unwrap();
    let down = vec![Vec3::new(0.0, -3.0, 0.0); p.len()];
    sim.recollide(&down).unwrap();
    let ymin = sim.state().q.iter().map(|q: &Pt3| q.y).fold(f64::INFINITY, f64::min);
    assert!(ymin > 0.0, "went through the plane: {ymin}");
    assert!(sim.state().v.iter().all(|v| v.y > -3.0), "velocities were filtered");
}

/// A start state with a zero gap (a sheet lying exactly on the floor) is refused with an error
/// that names the first offending pair and its gap, before any state change (README, "Contact
/// (issue 20)": no silent push-out).
#[test]
fn a_zero_gap_start_names_the_pair() {
    let (p, f) = sheet(4, 0.3, 0.0);
    let mut d = desc(p.clone(), f, cloth(Damping::None));
    d.effects.collision = Some(CollisionSettings { thickness: 0.004, ..Default::default() });
    d.effects.obstacles =
        vec![Obstacle { shape: ObstacleShape::Plane { normal: Vec3::y(), offset: 0.0 }, friction: 0.5, motion: None }];
    let mut sim = ShellSim::new(d).unwrap();
    match sim.step(1.0 / 60.0) {
        Err(ShellError::Diverged { reason, .. }) => {
            assert!(reason.contains("16 contact pair(s) have no gap"), "{reason}");
            assert!(reason.contains("cloth vertex 0 against obstacle 0 (plane), gap 0.000e0 m"), "{reason}");
        }
        other => panic!("expected a zero-gap error, got {other:?}"),
    }
    assert_eq!(sim.state().q, p, "the state is unchanged");
    assert_eq!(sim.state().t, 0.0);
}

//! The IPC contact model (module `contact`) on small cases with known answers.

mod common;

use geom_core::math::{Pt3, Vec3};
use shells::{CollisionSettings, Damping, Effects, Obstacle, ObstacleShape, ShellSceneDesc, ShellSim};

fn drop_onto(obstacle: ObstacleShape, height: f64, speed: f64, steps: usize) -> (ShellSim, f64) {
    let n: u32 = std::env::var("N").ok().and_then(|s| s.parse().ok()).unwrap_or(3);
    let size: f64 = std::env::var("S").ok().and_then(|s| s.parse().ok()).unwrap_or(0.1);
    let (p, f) = common::sheet(n, size, height);
    let mut d = common::desc(p.clone(), f, common::cloth(Damping::None));
    d.initial_velocity = Some(vec![Vec3::new(0.0, -speed, 0.0); p.len()]);
    d.effects = Effects {
        gravity: Some(Vec3::new(0.0, -9.81, 0.0)),
        obstacles: vec![Obstacle { shape: obstacle.clone(), friction: 0.0, motion: None }],
        collision: Some(CollisionSettings { thickness: 0.004, ..Default::default() }),
        ..Default::default()
    };
    let desc: ShellSceneDesc = d;
    let mut sim = ShellSim::new(desc).unwrap();
    let mut worst = f64::INFINITY;
    for k in 0..steps {
        let st = sim.step(1.0 / 120.0).unwrap_or_else(|e| panic!("step {k}: {e}"));
        worst = worst.min(st.contact.min_gap);
    }
    (sim, worst)
}

#[test]
fn a_sheet_dropped_on_a_sphere_rests_on_it() {
    let r = 0.25;
    let (sim, min_gap) = drop_onto(ShellShape::sphere(r), r + 0.01, 2.0, 60);
    for q in &sim.state().q {
        assert!((q.coords).norm() > r, "vertex inside the sphere: {q:?}");
    }
    assert!(min_gap > 1e-4, "gap collapsed: {min_gap}");
}

struct ShellShape;
impl ShellShape {
    fn sphere(r: f64) -> ObstacleShape {
        ObstacleShape::Sphere { center: Pt3::origin(), radius: r }
    }
}

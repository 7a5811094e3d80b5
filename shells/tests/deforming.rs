//! Deforming-mesh obstacles (module `contact::deforming`): cloth on a box that rises, bulges and
//! slides, with the IPC contact invariants (no penetration, no intersection, no NaN) and
//! friction relative to the moving surface.

mod common;

use geom_core::math::Pt3;
use geom_core::procedural::{box_surface, Diagonals};
use geom_core::query::tri_tri_intersect;
use shells::{CollisionSettings, Damping, DeformingMesh, Effects, ShellSim};

const H: f64 = 1.0 / 120.0;

/// A 0.4 m box (top at y = 0) whose frames at 120 fps follow `f(t, rest vertex)`.
fn box_frames(steps: usize, f: impl Fn(f64, &Pt3) -> Pt3) -> (Vec<[u32; 3]>, Vec<Vec<Pt3>>) {
    let m =
        box_surface(Pt3::new(-0.2, -0.3, -0.2), Pt3::new(0.2, 0.0, 0.2), [4, 3, 4], Diagonals::Alternating).unwrap();
    let frames = (0..=steps).map(|k| m.positions.iter().map(|p| f(k as f64 * H, p)).collect()).collect();
    (m.faces.clone(), frames)
}

/// A 0.3 m sheet of 7 × 7 vertices 5 mm above the box top, with IPC contact (d̂ = 2 mm).
fn sheet_sim(friction: f64) -> ShellSim {
    let (p, f) = common::sheet(7, 0.3, 0.005);
    let mut d = common::desc(p, f, common::cloth(Damping::None));
    d.effects = Effects {
        gravity: Some(common::g()),
        collision: Some(CollisionSettings { thickness: 0.002, friction, ..Default::default() }),
        ..Default::default()
    };
    ShellSim::new(d).unwrap()
}

/// Count of cloth–body triangle pairs that intersect.
fn crossings(sim: &ShellSim, body: &DeformingMesh, t: f64) -> usize {
    let q = &sim.state().q;
    let b = body.positions(t);
    let mut n = 0;
    for ct in &sim.mesh().tris {
        let a = ct.map(|i| q[i as usize]);
        for bt in body.tris() {
            n += tri_tri_intersect(&a, &bt.map(|i| b[i as usize])) as usize;
        }
    }
    n
}

/// Runs `steps` steps and returns the worst penetration (m) and intersection count seen.
fn run(sim: &mut ShellSim, body: &DeformingMesh, steps: usize) -> (f64, usize) {
    let (mut pen, mut cross) = (0.0f64, 0usize);
    for k in 0..steps {
        sim.step(H).unwrap_or_else(|e| panic!("step {k}: {e}"));
        let t = sim.state().t;
        assert!(sim.state().q.iter().all(|p| p.iter().all(|c| c.is_finite())), "NaN at step {k}");
        pen = pen.max(body.max_penetration(t, &sim.state().q).unwrap());
        cross = cross.max(crossings(sim, body, t));
    }
    (pen, cross)
}

#[test]
fn a_sheet_rides_a_rising_bulging_box_without_penetrating() {
    let steps = 48;
    // Rises at 0.6 m/s while its top bulges upward by up to 2 cm at the centre.
    let (tris, frames) = box_frames(steps, |t, p| {
        let bulge = if p.y > -1e-9 { 0.02 * (t / 0.4).min(1.0) * (1.0 - (p.x / 0.2).powi(2)) } else { 0.0 };
        Pt3::new(p.x, p.y + 0.6 * t + bulge, p.z)
    });
    let body = DeformingMesh::new(tris, frames, 0.0, 120.0, 0.3).unwrap();
    let mut sim = sheet_sim(0.3);
    sim.add_deforming_obstacle(body.clone()).unwrap();
    let (pen, cross) = run(&mut sim, &body, steps);
    assert!(pen <= 1e-3, "penetration {pen} m");
    assert_eq!(cross, 0, "cloth–body intersections");
    // Carried up with the box: the centre vertex sits on the top (rise 0.24 m + bulge 2 cm).
    let centre = sim.state().q[24];
    assert!(centre.y > 0.6 * steps as f64 * H + 0.02 - 1e-4 && centre.y < 0.6 * steps as f64 * H + 0.05, "{centre:?}");
}

#[test]
fn friction_drags_the_sheet_with_a_sliding_box() {
    let steps = 48;
    // Slides along +x at 0.5 m/s (a rigid motion given as frames).
    let (tris, frames) = box_frames(steps, |t, p| Pt3::new(p.x + 0.5 * t, p.y, p.z));
    let body = DeformingMesh::new(tris.clone(), frames.clone(), 0.0, 120.0, 0.8).unwrap();
    let drift = |mu: f64| {
        let body = DeformingMesh::new(tris.clone(), frames.clone(), 0.0, 120.0, mu).unwrap();
        let mut sim = sheet_sim(0.3);
        sim.add_deforming_obstacle(body.clone()).unwrap();
        let (pen, cross) = run(&mut sim, &body, steps);
        assert!(pen <= 1e-3 && cross == 0, "μ = {mu}: penetration {pen} m, {cross} intersections");
        sim.state().q.iter().map(|p| p.x).sum::<f64>() / sim.state().q.len() as f64
    };
    let slide = 0.5 * steps as f64 * H;
    let (with, without) = (drift(body.friction), drift(0.0));
    // μ = 0.8 sticks (g μ = 7.8 m/s² ≫ the box's start-up): the sheet follows; μ = 0 leaves it.
    assert!(with > 0.8 * slide, "with friction the sheet moved {with} m of {slide} m");
    assert!(without.abs() < 0.1 * slide, "without friction the sheet moved {without} m");
}

#[test]
fn bad_deforming_obstacles_are_refused() {
    let (tris, frames) = box_frames(2, |_, p| *p);
    // Open mesh.
    assert!(DeformingMesh::new(tris[1..].to_vec(), frames.clone(), 0.0, 120.0, 0.3).is_err());
    // Zero frame rate, no frame, frames of different sizes.
    assert!(DeformingMesh::new(tris.clone(), frames.clone(), 0.0, 0.0, 0.3).is_err());
    assert!(DeformingMesh::new(tris.clone(), vec![], 0.0, 120.0, 0.3).is_err());
    let mut short = frames.clone();
    short[1].pop();
    assert!(DeformingMesh::new(tris.clone(), short, 0.0, 120.0, 0.3).is_err());
    // A cloth starting inside the body.
    let (tris2, inside) = box_frames(2, |_, p| Pt3::new(p.x, p.y + 0.1, p.z));
    let body = DeformingMesh::new(tris2, inside, 0.0, 120.0, 0.3).unwrap();
    let e = sheet_sim(0.3).add_deforming_obstacle(body).unwrap_err().to_string();
    assert!(e.contains("inside"), "{e}");
    // Without IPC contact.
    let (p, f) = common::sheet(3, 0.3, 0.005);
    let mut sim = ShellSim::new(common::desc(p, f, common::cloth(Damping::None))).unwrap();
    let body = DeformingMesh::new(tris, frames, 0.0, 120.0, 0.3).unwrap();
    assert!(sim.add_deforming_obstacle(body).is_err());
}

//! The hard-case table of shells.md §8 as a stress suite: every case either gives a clear typed
//! error before any work or runs without NaN and without panicking.

mod common;

use common::{cloth, desc, g, sheet};
use geom_core::math::{Pt3, Vec3};
use shells::{
    CollisionSettings, Damping, HessianMode, IntegratorKind, MembraneLaw, ShellError, ShellSim, ShellState,
    VertexConstraint, WarpSource,
};

fn finite(sim: &ShellSim) -> bool {
    sim.state().q.iter().all(|q| q.iter().all(|c| c.is_finite()))
        && sim.state().v.iter().all(|v| v.iter().all(|c| c.is_finite()))
}

#[test]
fn degenerate_and_non_manifold_rejected() {
    let p = vec![Pt3::new(0.0, 0.0, 0.0), Pt3::new(1.0, 0.0, 0.0), Pt3::new(2.0, 0.0, 0.0), Pt3::new(0.0, 1.0, 0.0)];
    let e = ShellSim::new(desc(p.clone(), vec![[0, 1, 2]], cloth(Damping::None))).err().unwrap();
    assert!(matches!(e, ShellError::DegenerateTriangle(0)), "{e}");
    let mut p5 = p.clone();
    p5.push(Pt3::new(0.5, 0.5, 1.0));
    let fan = vec![[0, 1, 3], [1, 0, 4], [0, 1, 2]];
    let p6 = vec![p5[0], p5[1], Pt3::new(0.5, -1.0, 0.0), p5[3], p5[4]];
    let e = ShellSim::new(desc(p6, fan, cloth(Damping::None))).err().unwrap();
    assert!(matches!(e, ShellError::NonManifoldEdge(0, 1)), "{e}");
}

#[test]
fn bad_parameters_rejected_before_work() {
    let (p, f) = sheet(3, 1.0, 0.0);
    let mut m = cloth(Damping::None);
    m.density = -1.0;
    assert!(matches!(ShellSim::new(desc(p.clone(), f.clone(), m)), Err(ShellError::BadParameter(_))));
    let mut m = cloth(Damping::None);
    m.bending = f64::NAN;
    assert!(matches!(ShellSim::new(desc(p.clone(), f.clone(), m)), Err(ShellError::NonFinite(_))));
    let mut bad = p.clone();
    bad[1].y = f64::INFINITY;
    assert!(matches!(ShellSim::new(desc(bad, f.clone(), cloth(Damping::None))), Err(ShellError::NonFinite(_))));
    let mut d = desc(p.clone(), f.clone(), cloth(Damping::None));
    d.initial_velocity = Some(vec![Vec3::new(f64::NAN, 0.0, 0.0); p.len()]);
    assert!(matches!(ShellSim::new(d), Err(ShellError::NonFinite(_))));
    let mut sim = ShellSim::new(desc(p.clone(), f.clone(), cloth(Damping::None))).unwrap();
    assert!(matches!(sim.step(0.0), Err(ShellError::BadParameter(_))));
    assert!(matches!(sim.step(-1.0), Err(ShellError::BadParameter(_))));
    assert!(matches!(sim.step(f64::NAN), Err(ShellError::NonFinite(_))));
    assert_eq!(sim.steps_taken(), 0);
    // Orthotropic warp parallel to the normal of the (XZ) sheet.
    let mut m = cloth(Damping::None);
    m.membrane = MembraneLaw::Orthotropic {
        k_stretch_u: 100.0,
        k_stretch_v: 100.0,
        k_shear: 10.0,
        k_couple: 5.0,
        warp: WarpSource::Direction(Vec3::y()),
    };
    assert!(matches!(ShellSim::new(desc(p, f, m)), Err(ShellError::BadParameter(_))));
}

#[test]
fn empty_and_single_triangle() {
    let mut sim = ShellSim::new(desc(Vec::new(), Vec::new(), cloth(Damping::None))).unwrap();
    sim.step(0.01).unwrap();
    assert!((sim.state().t - 0.01).abs() < 1e-15);
    let p = vec![Pt3::new(0.0, 0.0, 0.0), Pt3::new(1.0, 0.0, 0.0), Pt3::new(0.0, 1.0, 0.0)];
    let mut d = desc(p, vec![[0, 1, 2]], cloth(Damping::None));
    d.effects.gravity = Some(g());
    let mut sim = ShellSim::new(d).unwrap();
    assert_eq!(sim.mesh().hinges.len(), 0);
    for _ in 0..10 {
        sim.step(0.01).unwrap();
    }
    assert!(finite(&sim));
}

#[test]
fn all_pinned_only_advances_time() {
    let (p, f) = sheet(3, 1.0, 0.0);
    let mut d = desc(p.clone(), f, cloth(Damping::None));
    d.effects.gravity = Some(g());
    d.constraints = vec![VertexConstraint::Pinned((0..9).collect())];
    let mut sim = ShellSim::new(d).unwrap();
    sim.step(0.1).unwrap();
    assert_eq!(sim.state().q, p);
    assert!((sim.state().t - 0.1).abs() < 1e-15);
}

#[test]
fn sliver_folded_collapsed_and_inverted_stay_finite() {
    // A sliver triangle (min angle < 1°) in the rest mesh.
    let p = vec![Pt3::new(0.0, 0.0, 0.0), Pt3::new(1.0, 0.0, 0.0), Pt3::new(0.5, 0.005, 0.0), Pt3::new(0.5, -1.0, 0.0)];
    let d = desc(p.clone(), vec![[0, 1, 2], [1, 0, 3]], cloth(Damping::None));
    let mut sim = ShellSim::new(d).unwrap();
    assert_eq!(sim.mesh().n_slivers, 1);
    // Fold flat onto itself (θ → π), collapse a triangle and invert another.
    let mut q = p.clone();
    q[3] = Pt3::new(0.5, 1.0, 1e-9); // w2 folded over w1's side
    q[2] = Pt3::new(0.5, 0.0, 0.0); // collapsed onto the edge
    sim.set_state(ShellState { t: 0.0, q: q.clone(), v: vec![Vec3::zeros(); 4] }).unwrap();
    for _ in 0..5 {
        let st = sim.step(0.01).unwrap();
        assert!(finite(&sim));
        let _ = st.skipped_hinges;
    }
    let (p, f) = sheet(4, 0.3, 0.0);
    let mut inv = p.clone();
    inv.swap(5, 10); // inverts the triangles around the two interior vertices
    let mut d = desc(p, f, cloth(Damping::None));
    d.initial = Some(inv);
    let mut sim = ShellSim::new(d).unwrap();
    for _ in 0..20 {
        sim.step(1.0 / 60.0).unwrap();
    }
    assert!(finite(&sim));
}

#[test]
fn extreme_stiffness_ratios() {
    let (p, f) = sheet(5, 0.5, 0.0);
    for (yt, kb) in [(1e6, 1e-9), (1.0, 0.0)] {
        let mut m = cloth(Damping::None);
        m.membrane = MembraneLaw::Isotropic { young_thickness: yt, poisson: 0.3, compression_softening: None };
        m.bending = kb;
        let mut d = desc(p.clone(), f.clone(), m);
        d.effects.gravity = Some(g());
        d.constraints = vec![VertexConstraint::Pinned(vec![0, 4])];
        let mut sim = ShellSim::new(d).unwrap();
        for _ in 0..30 {
            let st = sim.step(1.0 / 30.0).unwrap();
            assert_eq!(st.regularization_shift, 0.0);
        }
        assert!(finite(&sim));
    }
}

#[test]
fn large_step_cheap_is_bounded() {
    let (p, f) = sheet(9, 1.0, 0.0);
    let mut d = desc(p, f, cloth(Damping::Rayleigh { alpha: 0.0, beta: 1e-4 }));
    d.effects.gravity = Some(g());
    d.constraints = vec![VertexConstraint::Pinned(vec![72, 80])];
    let mut sim = ShellSim::new(d).unwrap();
    let mut emax: f64 = 0.0;
    for _ in 0..60 {
        sim.step(1.0 / 30.0).unwrap();
        let e = sim.energies();
        emax = emax.max(e.kinetic + e.membrane + e.bending);
    }
    // Bounded by the potential energy released by a fall of the sheet's size.
    let m: f64 = sim.mesh().mass.iter().sum();
    assert!(emax < m * 9.81 * 2.0, "{emax}");
}

#[test]
fn full_hessian_under_compression_never_nan() {
    let (p, f) = sheet(6, 0.5, 0.0);
    let q0: Vec<Pt3> = p.iter().map(|q| Pt3::new(0.6 * q.x, q.y + 0.01 * (30.0 * q.x).sin(), 0.6 * q.z)).collect();
    let mut d = desc(p, f, cloth(Damping::None));
    d.initial = Some(q0);
    d.integrator.hessian = HessianMode::Full;
    d.integrator.newton_iters = 3;
    d.integrator.line_search = true;
    let mut sim = ShellSim::new(d).unwrap();
    for _ in 0..10 {
        match sim.step(1.0 / 30.0) {
            Ok(_) => assert!(finite(&sim)),
            Err(ShellError::FactorizationFailed) | Err(ShellError::Diverged { .. }) => break,
            Err(e) => panic!("{e}"),
        }
    }
}

#[test]
fn coincident_contacts_and_parallel_edges() {
    // Two stacked sheets exactly coincident in x/z, 1 mm apart, falling onto each other.
    let (p, f) = sheet(4, 0.3, 0.0);
    let n = p.len() as u32;
    let mut pos = p.clone();
    pos.extend(p.iter().map(|q| q + Vec3::new(0.0, 0.001, 0.0)));
    let mut faces = f.clone();
    faces.extend(f.iter().map(|t| t.map(|i| i + n)));
    let mut d = desc(pos.clone(), faces.clone(), cloth(Damping::None));
    let mut v = vec![Vec3::zeros(); pos.len()];
    for vi in v.iter_mut().skip(n as usize) {
        *vi = Vec3::new(0.0, -1.0, 0.0);
    }
    d.initial_velocity = Some(v);
    d.effects.self_collision = true;
    d.effects.collision = Some(CollisionSettings { thickness: 0.002, ..Default::default() });
    let mut sim = ShellSim::new(d).unwrap();
    for _ in 0..20 {
        sim.step(1.0 / 120.0).unwrap();
        assert!(finite(&sim));
        assert_eq!(shells::collision::count_self_intersections(&sim.state().q, &faces), 0);
    }
}

#[test]
fn bdf2_restarts_after_set_state() {
    let (p, f) = sheet(4, 0.3, 0.0);
    let mut d = desc(p, f, cloth(Damping::None));
    d.effects.gravity = Some(g());
    d.integrator.kind = IntegratorKind::Bdf2;
    let mut sim = ShellSim::new(d).unwrap();
    for _ in 0..3 {
        sim.step(0.01).unwrap();
    }
    let s = sim.state().clone();
    sim.set_state(ShellState { t: s.t, q: s.q.clone(), v: vec![Vec3::zeros(); s.v.len()] }).unwrap();
    sim.step(0.01).unwrap();
    // A restart from rest with backward Euler: v = h g exactly for a free-falling flat sheet.
    assert!(sim.state().v.iter().all(|v| (v - 0.01 * g()).norm() < 1e-9));
    let bad = ShellState { t: 0.0, q: vec![Pt3::new(f64::NAN, 0.0, 0.0); s.q.len()], v: s.v.clone() };
    assert!(matches!(sim.set_state(bad), Err(ShellError::NonFinite(_))));
}

//! Spec §8 hard cases at small size: each gives a clear error or a correct result, never NaN or a
//! panic. H-SLIVER, H-ESCAPE, H-EMPTY / H-DROPLET-8, H-DROPLET-1 (exact parabola), H-EMPTY-SCENE,
//! H-FULL-BOX, H-CFL (fixed step 5× too large), H-NONFINITE (scene rejects NaN), H-SOLVER-FAIL.

use flip_tet::bcc::TetMesh;
use flip_tet::error::{MeshError, SimError, SolverKind};
use flip_tet::scene::{DtPolicy, Scene, Shape};
use flip_tet::sim::FlipTetSim;
use geom_core::math::{Pt3, Vec3};

fn base(liquid: &str, extra: &str) -> Scene {
    let text = format!(
        r#"(
        domain: (min: (0.0, 0.0, 0.0), max: (1.0, 1.0, 1.0)),
        resolution: (coarsest: 4, finest: 8),
        duration: 0.2, fps: 50.0,
        liquid: [{liquid}],
        {extra}
    )"#
    );
    ron::from_str(&text).unwrap()
}

fn assert_finite(sim: &FlipTetSim) {
    let p = sim.particles();
    assert!(p.x.iter().all(|x| x.coords.iter().all(|c| c.is_finite())));
    assert!(p.v.iter().all(|v| v.iter().all(|c| c.is_finite())));
}

#[test]
fn h_sliver_rejected_and_near_sliver_kept_symmetric() {
    let mut m = TetMesh {
        nodes: vec![
            Pt3::new(0.0, 0.0, 0.0),
            Pt3::new(1.0, 0.0, 0.0),
            Pt3::new(0.0, 1.0, 0.0),
            Pt3::new(0.3, 0.3, 1e-15),
        ],
        tets: vec![[0, 1, 2, 3]],
        ..Default::default()
    };
    assert!(matches!(m.compute_geometry(1.0), Err(MeshError::DegenerateTet { tet: 0, .. })));
    // Volume 1e-9 h³: accepted, the local stiffness is a Gram matrix (symmetric, PSD).
    m.nodes[3].z = 6e-9;
    m.compute_geometry(1.0).unwrap();
    let k = flip_tet::ops::local_stiffness(&m, 0);
    for (i, row) in k.iter().enumerate() {
        for (j, v) in row.iter().enumerate() {
            assert_eq!(*v, k[j][i]);
        }
        assert!(row[i] >= 0.0);
    }
}

#[test]
fn h_escape_particles_clamped_inside() {
    let mut sim = FlipTetSim::new(&base("Box(min: (0.4, 0.0, 0.4), max: (0.6, 0.2, 0.6))", "")).unwrap();
    let n = sim.particles().len();
    for (i, v) in sim.particles_mut().v.iter_mut().enumerate() {
        *v = Vec3::new(if i % 2 == 0 { 20.0 } else { -20.0 }, 0.0, 0.0);
    }
    for _ in 0..5 {
        sim.step().unwrap();
    }
    assert_finite(&sim);
    assert_eq!(sim.particles().len(), n, "none lost through closed walls");
    for (x, r) in sim.particles().x.iter().zip(&sim.particles().r) {
        assert!(x.x >= r - 1e-12 && x.x <= 1.0 - r + 1e-12);
    }
}

#[test]
fn h_escape_open_face_deletes_and_counts() {
    let mut sim =
        FlipTetSim::new(&base("Box(min: (0.0, 0.0, 0.0), max: (0.25, 0.25, 1.0))", "open_faces: [NegX],")).unwrap();
    let v0 = sim.particles().total_volume();
    for v in sim.particles_mut().v.iter_mut() {
        *v = Vec3::new(-20.0, 0.0, 0.0);
    }
    let mut deleted = 0;
    for _ in 0..5 {
        deleted += sim.step().unwrap().n_deleted;
    }
    assert!(deleted > 0);
    let left = sim.particles().total_volume() + sim.deleted_volume;
    assert!((left - v0).abs() <= 1e-12 * v0);
}

#[test]
fn h_droplet_1_exact_parabola() {
    let mut s = base("Sphere(center: (0.5, 0.8, 0.5), radius: 0.01)", "");
    s.liquid.clear();
    s.flip.dt_policy = DtPolicy::Fixed(0.01);
    let mut sim = FlipTetSim::new(&s).unwrap();
    assert_eq!(sim.particles().len(), 0);
    let x0 = Pt3::new(0.5, 0.8, 0.5);
    let v0 = Vec3::new(0.1, 0.0, 0.0);
    sim.particles_mut().push(x0, v0, 0.03, 0.0);
    let dt = 0.01;
    for n in 1..=10u32 {
        let st = sim.step().unwrap();
        assert_eq!(st.n_ballistic, 1);
        assert_eq!(st.n_dofs, 0, "no liquid node");
        let nf = f64::from(n);
        // Leapfrog (the default time integration): half kick first, so the positions lie on the
        // exact parabola x0 + v0 t + g t²/2 (symplectic Euler from synchronised velocities would
        // lead it by g t Δt/2).
        let t = nf * dt;
        let want = x0 + v0 * t + Vec3::new(0.0, -9.81, 0.0) * (t * t / 2.0);
        assert!((sim.particles().x[0] - want).norm() < 1e-12, "step {n}");
    }
}

#[test]
fn h_droplet_8_cluster_falls_with_g() {
    // Eight particles inside one coarse cube away from the walls (node averages are free-slip at
    // wall nodes, so a cluster within one cell of a wall is slowed): no liquid node, falls with g.
    let mut s = base("Sphere(center: (0.5, 0.8, 0.5), radius: 0.01)", "");
    s.liquid.clear();
    s.resolution.finest = 4;
    s.flip.dt_policy = DtPolicy::Fixed(0.005);
    s.particles.position_correction = false;
    let mut sim = FlipTetSim::new(&s).unwrap();
    for c in 0..8 {
        let o = Vec3::new((c & 1) as f64, ((c >> 1) & 1) as f64, ((c >> 2) & 1) as f64) * 0.02;
        sim.particles_mut().push(Pt3::new(0.54, 0.64, 0.54) + o, Vec3::zeros(), 0.01, 0.0);
    }
    for _ in 0..10 {
        sim.step().unwrap();
    }
    assert_finite(&sim);
    // Leapfrog velocities live at half steps: v(t − Δt/2) = −g (t − Δt/2).
    let t = sim.time() - 0.5 * 0.005;
    for v in &sim.particles().v {
        assert!((v.y + 9.81 * t).abs() <= 0.01 * 9.81 * t, "vy {} vs {}", v.y, -9.81 * t);
    }
}

#[test]
fn h_empty_scene_steps_are_noops() {
    let mut s = base("Sphere(center: (0.5, 0.8, 0.5), radius: 0.01)", "");
    s.liquid.clear();
    let mut sim = FlipTetSim::new(&s).unwrap();
    let st = sim.step().unwrap();
    assert_eq!(st.n_particles, 0);
    assert_eq!(st.n_dofs, 0);
    assert_eq!(st.kinetic_energy, 0.0);
    assert!(sim.surface().is_none_or(|m| m.faces.is_empty()), "surface has no faces");
}

#[test]
fn h_full_box_stays_at_rest() {
    let mut sim = FlipTetSim::new(&base("Box(min: (0.0, 0.0, 0.0), max: (1.0, 1.0, 1.0))", "")).unwrap();
    for _ in 0..3 {
        let st = sim.step().unwrap();
        assert!(st.max_speed < 1e-9, "max speed {}", st.max_speed);
    }
}

#[test]
fn h_cfl_fixed_step_substeps_no_nan() {
    let mut s = base("Box(min: (0.0, 0.0, 0.0), max: (0.3, 0.6, 1.0))", "");
    s.flip.dt_policy = DtPolicy::Fixed(0.04);
    s.fps = 5.0;
    s.initial_velocity = [4.0, 0.0, 0.0];
    let mut sim = FlipTetSim::new(&s).unwrap();
    let mut subs = 0;
    for _ in 0..5 {
        subs += sim.step().unwrap().cfl_substeps;
    }
    assert!(subs > 0);
    assert_finite(&sim);
    for (x, r) in sim.particles().x.iter().zip(&sim.particles().r) {
        for a in 0..3 {
            assert!(x[a] >= r - 1e-12 && x[a] <= 1.0 - r + 1e-12);
        }
    }
}

#[test]
fn h_nonfinite_scene_rejected() {
    let mut s = base("Box(min: (0.0, 0.0, 0.0), max: (0.3, 0.6, 1.0))", "");
    s.liquid.push(Shape::Sphere { center: [f64::NAN, 0.0, 0.0], radius: 0.1 });
    assert!(matches!(FlipTetSim::new(&s), Err(SimError::InvalidScene(_))));
    let mut s = base("Box(min: (0.0, 0.0, 0.0), max: (0.3, 0.6, 1.0))", "");
    s.domain.max[1] = 0.7;
    assert!(matches!(FlipTetSim::new(&s), Err(SimError::Mesh(MeshError::DomainNotMultipleOfRoot { axis: 1, .. }))));
}

#[test]
fn h_solver_fail_reports_iterations() {
    let mut s = base("Box(min: (0.0, 0.0, 0.0), max: (0.3, 0.6, 1.0))", "");
    s.pressure.solver = SolverKind::PcgJacobi;
    s.pressure.max_iters = 1;
    s.pressure.tol = 1e-12;
    let mut sim = FlipTetSim::new(&s).unwrap();
    match sim.step() {
        Err(SimError::SolverFailed { kind: SolverKind::PcgJacobi, iters, residual }) => {
            assert_eq!(iters, 1);
            assert!(residual.is_finite());
        }
        other => panic!("expected SolverFailed, got {other:?}"),
    }
}

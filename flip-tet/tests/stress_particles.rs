//! Spec §8 hard cases about the particles, at small size (each a correct result or a clear error,
//! never NaN or a panic): H-COINCIDENT (two particles at one point), H-BUDGET (the particle budget
//! stops splitting, or is an error when the scene asks for it), H-ALL-BALLISTIC (a sparse spray:
//! no pressure solve, the mesh stays coarsest, every particle falls freely).

use flip_tet::error::SimError;
use flip_tet::scene::{DtPolicy, Scene};
use flip_tet::sim::FlipTetSim;
use geom_core::math::{Pt3, Vec3};

/// Unit box, 4 → 8 cells per side (two levels, so split/merge is active), a shallow pool.
fn pool(extra: &str) -> Scene {
    let text = format!(
        r#"(
        domain: (min: (0.0, 0.0, 0.0), max: (1.0, 1.0, 1.0)),
        resolution: (coarsest: 4, finest: 8),
        duration: 0.2, fps: 50.0,
        liquid: [Box(min: (0.0, 0.0, 0.0), max: (1.0, 0.3, 1.0))],
        {extra}
    )"#
    );
    ron::from_str(&text).expect("test scene parses")
}

fn assert_finite_inside(sim: &FlipTetSim) {
    let p = sim.particles();
    for (x, (v, r)) in p.x.iter().zip(p.v.iter().zip(&p.r)) {
        assert!(x.coords.iter().chain(v.iter()).all(|c| c.is_finite()), "non-finite particle {x:?} {v:?}");
        for a in 0..3 {
            assert!(x[a] >= r - 1e-12 && x[a] <= 1.0 - r + 1e-12, "particle {x:?} (r {r}) outside the box");
        }
    }
}

#[test]
fn h_coincident_particles_stay_finite_and_separate() {
    let mut sim = FlipTetSim::new(&pool("")).expect("valid scene");
    let r = sim.particles().r[0];
    // Two pairs of exactly coincident particles: one deep in the pool, one at the free surface.
    for x in [Pt3::new(0.43, 0.12, 0.57), Pt3::new(0.61, 0.3 - r, 0.38)] {
        sim.particles_mut().push(x, Vec3::zeros(), r, -r);
        sim.particles_mut().push(x, Vec3::zeros(), r, -r);
    }
    let n = sim.particles().len();
    for _ in 0..5 {
        let st = sim.step().expect("step with coincident particles");
        assert!(st.max_speed.is_finite() && st.kinetic_energy.is_finite());
    }
    assert_finite_inside(&sim);
    let p = sim.particles();
    // The position correction pushes coincident particles apart along a hashed direction, so no
    // pair of the four injected ones (the last four) may still share a point.
    let added = &p.x[p.len() - 4..];
    assert_eq!(p.len(), n, "no particle lost or created (split/merge is volume neutral here)");
    assert!((added[0] - added[1]).norm() > 0.0 && (added[2] - added[3]).norm() > 0.0, "{added:?}");
    let surface = sim.surface().expect("pool has a surface");
    assert!(surface.positions.iter().all(|q| q.coords.iter().all(|c| c.is_finite())));
}

/// A pool with one oversized particle that the next remesh must split several times.
fn pool_with_big_particle(max_extra: usize, is_error: bool) -> FlipTetSim {
    let mut s = pool("");
    s.flip.remesh_interval = 1;
    let mut sim = FlipTetSim::new(&s).expect("valid scene");
    let r = sim.particles().r.iter().cloned().fold(0.0, f64::max);
    sim.particles_mut().push(Pt3::new(0.5, 0.1, 0.5), Vec3::zeros(), 4.0 * r, -4.0 * r);
    let n = sim.particles().len();
    let mut s = sim.scene().clone();
    s.particles.max_particles = n + max_extra;
    s.particles.budget_is_error = is_error;
    // Rebuild with the budget: the same pool plus the same big particle (sampling is
    // deterministic from the scene seed).
    let mut sim = FlipTetSim::new(&s).expect("valid scene");
    sim.particles_mut().push(Pt3::new(0.5, 0.1, 0.5), Vec3::zeros(), 4.0 * r, -4.0 * r);
    assert_eq!(sim.particles().len(), n);
    sim
}

#[test]
fn h_budget_stops_splitting_and_the_run_continues() {
    // Without a budget the big particle (radius 4× the largest sampled one, 64× its volume)
    // splits into many: the budget of 3 extra particles must stop that.
    let mut free = pool_with_big_particle(1_000_000, false);
    let n0 = free.particles().len();
    // The first remesh is at step 1 (step 0 runs on the initial mesh).
    let split_free: usize = (0..2).map(|_| free.step().expect("step").n_split).sum();
    assert!(split_free > 3, "the oversized particle splits without a budget ({split_free} splits)");
    assert!(free.particles().len() > n0 + 3);

    let mut sim = pool_with_big_particle(3, false);
    let limit = sim.scene().particles.max_particles;
    let mut hit_steps = Vec::new();
    for k in 0..4 {
        let st = sim.step().expect("splitting stops, the run goes on");
        assert!(st.max_speed.is_finite());
        if st.budget_hit {
            hit_steps.push(k);
        }
    }
    // The first remesh (step 1) meets the budget and reports it in its StepStats.
    assert_eq!(hit_steps.first(), Some(&1), "budget reported at the first remesh: {hit_steps:?}");
    assert!(sim.particles().len() <= limit, "{} particles > budget {limit}", sim.particles().len());
    assert_finite_inside(&sim);
}

#[test]
fn h_budget_as_error_names_the_limit() {
    let mut sim = pool_with_big_particle(3, true);
    let limit = sim.scene().particles.max_particles;
    sim.step().expect("step 0 runs on the initial mesh, no remesh");
    match sim.step() {
        Err(SimError::ParticleBudgetExceeded { limit: l }) => assert_eq!(l, limit),
        other => panic!("expected ParticleBudgetExceeded at the first remesh, got {other:?}"),
    }
}

#[test]
fn h_all_ballistic_spray_falls_freely_on_the_coarsest_mesh() {
    let mut s = pool("");
    s.liquid.clear();
    s.flip.dt_policy = DtPolicy::Fixed(0.005);
    s.flip.remesh_interval = 1;
    let mut sim = FlipTetSim::new(&s).expect("empty scene is valid");
    let coarsest_tets = sim.mesh().tets.len();
    // A sparse spray: 27 drops 0.2 m apart (isolation radius 6 r = 0.06 m), moving in all
    // directions, well away from the walls for the 10 steps below.
    let r = 0.01;
    let mut x0 = Vec::new();
    let mut v0 = Vec::new();
    for i in 0..3 {
        for j in 0..3 {
            for k in 0..3 {
                let x = Pt3::new(0.3 + 0.2 * i as f64, 0.5 + 0.2 * j as f64, 0.3 + 0.2 * k as f64);
                let v = Vec3::new(0.3 * (i as f64 - 1.0), 0.5, 0.3 * (k as f64 - 1.0));
                sim.particles_mut().push(x, v, r, 0.0);
                x0.push(x);
                v0.push(v);
            }
        }
    }
    let g = Vec3::new(0.0, -9.81, 0.0);
    let dt = 0.005;
    for n in 1..=10u32 {
        let st = sim.step().expect("ballistic step");
        assert_eq!(st.n_ballistic, 27, "step {n}: every drop is isolated");
        assert_eq!(st.n_dofs, 0, "step {n}: no liquid node, no pressure solve");
        assert_eq!(sim.mesh().tets.len(), coarsest_tets, "step {n}: the mesh stays coarsest");
        let nf = f64::from(n);
        for (p, (x, v)) in x0.iter().zip(&v0).enumerate() {
            // Leapfrog free fall (half kick first): the velocity at the half step,
            // v = v₀ + (n − ½) g Δt, and the exact parabola x_n = x₀ + v₀ t + g t²/2, t = n Δt.
            let want_v = v + g * ((nf - 0.5) * dt);
            let want_x = x + v * (nf * dt) + g * (dt * dt * nf * nf / 2.0);
            // 1e-12 m: a few roundings of O(1) positions over ten steps.
            assert!((sim.particles().v[p] - want_v).norm() < 1e-12, "step {n} drop {p} velocity");
            assert!((sim.particles().x[p] - want_x).norm() < 1e-12, "step {n} drop {p} position");
        }
    }
}

//! Criterion benches of the element kernels and the assembled step (shells.md §9): energy +
//! gradient + Hessian per hinge and per triangle, and one full implicit step (assembly included)
//! of the 1617-vertex (49 × 33) flag without collisions. Divide by the element counts printed in
//! the bench names for the time per element.

use criterion::{criterion_group, criterion_main, Criterion};
use geom_core::math::{Pt3, Vec3};
use geom_core::procedural::{grid, Diagonals, GridSpec, Plane};
use shells::kernels::bending::bending_eval;
use shells::kernels::membrane::{membrane_eval, Membrane, TriRest};
use shells::{Effects, HessianMode, Hinge, IntegratorSettings, Material, ShellSceneDesc, ShellSim, VertexConstraint};
use std::hint::black_box;

fn hinge_kernel(c: &mut Criterion) {
    let x = [Pt3::new(0.0, 0.0, 0.0), Pt3::new(1.0, 0.1, 0.0), Pt3::new(0.4, 0.9, 0.3), Pt3::new(0.6, -0.8, 0.2)];
    let h = Hinge { v: [0, 1, 2, 3], rest_theta: 0.1, weight: 3.0, stiffness: 1e-5, edge_len: 1.0, area_sum: 1.0 };
    for mode in [HessianMode::ProjectedCheap, HessianMode::ProjectedEigen, HessianMode::Full] {
        c.bench_function(&format!("hinge_kernel/{mode:?}"), |b| {
            b.iter(|| bending_eval(black_box(&h), black_box(&x), mode, true))
        });
    }
}

fn membrane_kernel(c: &mut Criterion) {
    let x0 = [Pt3::new(0.0, 0.0, 0.0), Pt3::new(1.0, 0.0, 0.0), Pt3::new(0.3, 0.9, 0.0)];
    let t = TriRest::new(&x0, None).expect("non-degenerate triangle");
    let x = [Pt3::new(0.0, 0.01, 0.0), Pt3::new(0.95, 0.0, 0.05), Pt3::new(0.3, 0.92, -0.02)];
    let laws = [
        ("isotropic", Membrane::isotropic(2000.0, 0.3)),
        ("softened", Membrane::Softened { mu: 800.0, lambda: 300.0, s: 0.1 }),
    ];
    for (name, law) in laws {
        for mode in [HessianMode::ProjectedCheap, HessianMode::ProjectedEigen] {
            c.bench_function(&format!("membrane_kernel/{name}/{mode:?}"), |b| {
                b.iter(|| membrane_eval(black_box(&t), black_box(&law), black_box(&x), mode, Some((1e-4, 1e-4))))
            });
        }
    }
}

fn flag_step(c: &mut Criterion) {
    let g = grid(&GridSpec {
        quads: [48, 32],
        size: [1.2, 0.8],
        plane: Plane::XY,
        diagonals: Diagonals::Alternating,
        center: Pt3::origin(),
    })
    .expect("valid grid");
    let n = g.positions.len();
    let effects = Effects { gravity: Some(Vec3::new(0.0, -9.81, 0.0)), ..Default::default() };
    let desc = ShellSceneDesc {
        rest: g.positions.clone(),
        faces: g.faces.clone(),
        uv: None,
        initial: None,
        initial_velocity: None,
        material: Material::cotton(),
        effects,
        constraints: vec![VertexConstraint::Pinned((0..33).map(|j| j * 49).collect())],
        integrator: IntegratorSettings::default(),
        t0: 0.0,
    };
    let mut sim = ShellSim::new(desc).expect("valid scene");
    let label = format!("step_flag_{n}v_{}t_{}h", g.faces.len(), sim.mesh().hinges.len());
    c.bench_function(&label, |b| b.iter(|| sim.step(1.0 / 120.0).expect("stable step")));
}

criterion_group!(benches, hinge_kernel, membrane_kernel, flag_step);
criterion_main!(benches);

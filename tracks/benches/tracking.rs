//! Criterion benches of tracks.md §9 on the 3038-vertex Xavier character (spec §6.4):
//!
//! - `pg_mass_build_3038`: the Petrov–Galerkin mass matrix 𝓜 (eq. 5).
//! - `constraints_build_hat_bag`: C, C̄ and the eq. 8 normalisation for the subdivision-hat basis
//!   of the bag (88 hats on 1297 vertices: the hats need a subdivision hierarchy, which Xavier
//!   does not have); `constraints_build_cluster_280`: the same for Xavier's 280 clusters.
//! - `kkt_factor_{method}_{K}`: one constrained velocity solve of a captured Xavier step (KKT
//!   values, numeric factorisation, solve and refinement — what tracking costs per step; the
//!   symbolic analysis is done once before timing, as in a run) for K ∈ {4, 88, 280, 1024} regions
//!   and the exact methods ConstraintLast, Interleaved, AmdRegularized and Schur, beside
//!   `kkt_factor_untracked_llt`, the plain LLᵀ solve of the same system.
//! - `cluster_xavier_200`: animation-aware variational clustering, 200 regions, F = 32.
//! - `lowpass_apply`: the low-pass filter L_τ of the deviation metric (§3.8) for K = 280.
//!
//! Run with `cargo bench -p tracks` (release). The system is captured from the second step of the
//! scene's cloth (gravity, ground contact off: the solve does not depend on collisions).

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use geom_core::math::Vec3;
use geom_core::mesh::subdivide_linear;
use shells::VelocitySolve;
use std::hint::black_box;
use tracks::metrics::LowPass;
use tracks::procedural::{bag_guide, xavier, xavier_guide, xavier_sim, Xavier};
use tracks::{
    build_test_functions, cluster, pg_mass_matrix, CapturedSystem, ClusterOptions, GuideAnimation, KktMethod,
    TestFunctionSpec, TestFunctions, TrackOptions, TrackingConstraints, TrackingSolver,
};

/// Xavier's test functions with `k` animation-aware clusters (μ = 0.98, F = 32, seed 7).
fn clusters(guide: &GuideAnimation, x: &Xavier, k: usize) -> TestFunctions {
    let opts = ClusterOptions { regions: k, mu: 0.98, frames: 32, seed: 7, ..ClusterOptions::default() };
    build_test_functions(&TestFunctionSpec::Clustered(opts), guide, &x.mesh, None).expect("clustering")
}

fn pg_mass(c: &mut Criterion) {
    let x = xavier().expect("xavier");
    c.bench_function("pg_mass_build_3038", |b| b.iter(|| pg_mass_matrix(black_box(&x.mesh))));
}

fn constraints_build(c: &mut Criterion) {
    let bag = bag_guide(2.0, tracks::procedural::BAG_B1_GAIN).expect("bag guide");
    let (fine, p) = subdivide_linear(&bag.rest, 2);
    let hats = build_test_functions(&TestFunctionSpec::SubdivisionBasis, &bag, &fine, Some(&p)).expect("hats");
    let name = format!("constraints_build_hat_bag_{}", hats.len());
    c.bench_function(&name, |b| b.iter(|| TrackingConstraints::build(&bag.rest, black_box(&fine), &hats)));

    let x = xavier().expect("xavier");
    let guide = xavier_guide(&x, 2.0).expect("xavier guide");
    let tf = clusters(&guide, &x, 280);
    c.bench_function("constraints_build_cluster_280", |b| {
        b.iter(|| TrackingConstraints::build(&x.mesh, black_box(&x.mesh), &tf))
    });
}

fn kkt_factor(c: &mut Criterion) {
    let x = xavier().expect("xavier");
    let guide = xavier_guide(&x, 2.0).expect("xavier guide");
    let mut sim = xavier_sim(&x, &guide).expect("the Xavier cloth is a valid shell scene");
    sim.step(1.0 / 120.0).expect("first step");
    let sys = CapturedSystem::capture_step(&mut sim, 1.0 / 120.0).expect("captured step");
    let mut g = c.benchmark_group("kkt_factor");
    g.sample_size(20);
    {
        // The untracked solve of the same system: the baseline of the overhead.
        let mut llt = geom_core::linalg::SparseLlt::from_symbolic(&sim.llt_symbolic());
        g.bench_function("untracked_llt", |b| {
            b.iter(|| {
                llt.factor(&sys.a).expect("SPD system");
                let mut x = sys.b.clone();
                llt.solve_in_place(&mut x).expect("solve");
                x
            })
        });
    }
    let methods = [
        ("constraint_last", KktMethod::ConstraintLastLdlt),
        ("interleaved", KktMethod::InterleavedLdlt),
        ("amd_regularized", KktMethod::AmdRegularizedLdlt { delta: 1e-8 }),
        ("schur", KktMethod::Schur),
    ];
    for k in [4usize, 88, 280, 1024] {
        let tf = clusters(&guide, &x, k);
        let cons = TrackingConstraints::build(&x.mesh, &x.mesh, &tf).expect("constraints");
        for (name, method) in methods {
            let opts = TrackOptions { kkt: method, ..TrackOptions::default() };
            let mut solver = TrackingSolver::new(
                cons.clone(),
                guide.clone(),
                &opts,
                sim.fill_reducing_perm().to_vec(),
                sim.llt_symbolic(),
            );
            // The symbolic analysis happens once per run: keep it out of the timing.
            solver.solve(&sys.system()).expect("KKT solve");
            g.bench_with_input(BenchmarkId::new(name, k), &k, |b, _| {
                b.iter(|| solver.solve(black_box(&sys.system())).expect("KKT solve"))
            });
        }
    }
    g.finish();
}

fn cluster_xavier(c: &mut Criterion) {
    let x = xavier().expect("xavier");
    let guide = xavier_guide(&x, 2.0).expect("xavier guide");
    let opts = ClusterOptions { regions: 200, mu: 0.98, frames: 32, seed: 7, ..ClusterOptions::default() };
    let mut g = c.benchmark_group("cluster");
    g.sample_size(10);
    g.bench_function("cluster_xavier_200", |b| b.iter(|| cluster(&guide, black_box(&opts), None).expect("clustering")));
    g.finish();
}

fn lowpass(c: &mut Criterion) {
    let x = xavier().expect("xavier");
    let lp = LowPass::new(&x.mesh, LowPass::tau_for(&x.mesh, 280)).expect("low-pass filter");
    let d: Vec<Vec3> = x.mesh.positions.iter().map(|p| Vec3::new(p.y.sin(), p.x * p.z, p.z.cos()) * 0.01).collect();
    c.bench_function("lowpass_apply", |b| b.iter(|| lp.apply(black_box(&d)).expect("filter")));
}

criterion_group!(benches, pg_mass, constraints_build, kkt_factor, cluster_xavier, lowpass);
criterion_main!(benches);

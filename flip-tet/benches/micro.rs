//! Criterion micro-benchmarks of flip-tet (spec §9, last paragraph): the kernels of one adaptive
//! FLIP step measured on realistic, deterministic inputs, single-thread and two-thread.
//!
//! Inputs (each built once, and only when a benchmark that needs it is selected):
//! - **dam break** (spec S2 geometry, `scenes/flip-tet/dam-break.ron`): column `a × 2a` in the
//!   `(64/13) a × (32/13) a × (8/13) a` box, coarsest 8, finest 64, surface band 3 + depth floor
//!   0.25, advanced [`DAM_STEPS`] steps from rest so that the column is collapsing. It supplies the
//!   octree demands, the graded octree and mesh, the particles, the node level set and the
//!   P2G/extrapolated tet velocities.
//! - **tank** (pressure solves): unit cube, uniform BCC mesh of `n³` cubes, liquid below
//!   `y = 0.79` (planar `φ`, second-order ghost fluid), `u* = −g Δt ŷ` plus a seeded random
//!   perturbation uniform in ±0.05 m/s per component and tet, so that the right-hand side is
//!   broadband rather than hydrostatic. `n` = 18 / 31 / 50 gives ≈ 10 k / 50 k / 200 k DOFs.
//!
//! Threads: each benchmark id ends in `t1` or `t2`, the size of the rayon pool
//! (`ThreadPoolBuilder::num_threads`) the kernel runs in via `pool.install`. Kernels that are
//! serial in the library (octree build, assembly, marching tets, the direct solve with
//! `faer::Par::Seq`) are measured with `t1` only: a second thread cannot change them.
//!
//! `split_merge` runs the simulator's own pass ([`flip_tet::split_merge::split_merge`]) on a copy
//! of the particles; [`g2p_advect`] calls the simulator's G2P and advection kernels.
//!
//! Run: `cargo bench -p flip-tet --bench micro` (≈ 4 min of measurement on the project's 2-core
//! machine); filter with a substring, e.g. `-- solve_mic`.

use std::hint::black_box;
use std::time::Duration;

use criterion::measurement::WallTime;
use criterion::{BatchSize, BenchmarkGroup, Criterion, SamplingMode, Throughput};
use flip_tet::advect::{advect, g2p, AdvectMesh, TetField};
use flip_tet::bcc::{tetrahedralize, TetMesh};
use flip_tet::error::SolverKind;
use flip_tet::octree::{build_octree, Octree, OctreeSpec, SizeDemand};
use flip_tet::particles::{apply_walls, Particles};
use flip_tet::pressure::{assemble_pressure, PressureParams, PressureSolver, PressureSystem};
use flip_tet::scene::{Scene, TimeIntegration};
use flip_tet::sim::FlipTetSim;
use flip_tet::sizing::{Sizing, SizingContext, C_H};
use flip_tet::split_merge::{split_merge, OldLevelSet};
use flip_tet::surface::{level_set_on_nodes_sign_inside, marching_tets, LevelSetSampler, Walls};
use flip_tet::transfer::{extrapolate, node_average, particles_to_tets};
use geom_core::math::{Pt3, Vec3};
use geom_core::rng::Rng;
use geom_core::NONE;
use rayon::prelude::*;

/// Thread counts of the rayon pools the parallel kernels run in.
const THREADS: [usize; 2] = [1, 2];

/// Steps the dam break is advanced from rest before its state is captured.
const DAM_STEPS: usize = 6;

/// Step size of the benchmarked transfers and of the tank's `u*` (s): the dam break's `dt_max`.
const DT: f64 = 0.005;

/// The S2 dam break at coarsest 8, finest 64 (the geometry of `scenes/flip-tet/dam-break.ron`).
const DAM_SCENE: &str = r#"(
    name: "dam_break_bench",
    domain: (min: (0.0, 0.0, 0.0), max: (0.2813538461538462, 0.1406769230769231, 0.03516923076923077)),
    resolution: (coarsest: 8, finest: 64),
    duration: 0.19, fps: 100.0, seed: 7,
    liquid: [Box(min: (0.0, 0.0, 0.0), max: (0.05715, 0.1143, 0.03516923076923077))],
    sizing: (depth_floor: Some(0.25), surface_band: Some(3.0)),
)"#;

/// A rayon pool of `t` threads.
fn pool(t: usize) -> rayon::ThreadPool {
    // Invariant: building a pool with a positive thread count only fails when the OS refuses
    // to spawn threads, which a benchmark cannot recover from.
    rayon::ThreadPoolBuilder::new().num_threads(t).build().expect("rayon pool")
}

/// State of the collapsing dam break, the input of every kernel except the solves.
struct DamBreak {
    /// The scene (transfer, surface and FLIP parameters, walls).
    scene: Scene,
    /// Graded octree of the current mesh.
    octree: Octree,
    /// Graded BCC mesh with geometry.
    mesh: TetMesh,
    /// Particles with their tet hints and stored `φ_p`.
    parts: Particles,
    /// Node level set of the last step (m).
    phi: Vec<f64>,
    /// Cube size of each tet's level (m).
    h_tet: Vec<f64>,
    /// One size demand per non-ballistic particle, as the remesh computes them (spec §3.12).
    demands: Vec<SizeDemand>,
    /// P2G velocities extrapolated over the mesh (`u_old` of a step, m/s).
    u_old: Vec<Vec3>,
    /// Nodal averages of `u_old` (free slip at the walls).
    nodal_old: Vec<Vec3>,
    /// `u_old + g Δt`, the stand-in for the projected `u_new` (m/s).
    u_new: Vec<Vec3>,
    /// Nodal averages of `u_new`.
    nodal_new: Vec<Vec3>,
    /// FLIP increment `u_new − u_old` (m/s).
    du: Vec<Vec3>,
    /// Nodal averages of `du`.
    nodal_du: Vec<Vec3>,
}

/// Size demands of the particles (the remesh rule of `FlipTetSim`, spec §3.12: radius from the
/// sizing function clamped to `[h_min, h_root] / C_H`, rounded down to a level, padded by two
/// cubes or the distance travelled in one remesh interval).
fn particle_demands(scene: &Scene, spec: &OctreeSpec, parts: &Particles) -> Vec<SizeDemand> {
    // Invariant: the scene passed `FlipTetSim::new`, which validates the sizing parameters.
    let sizing = Sizing::from_params(&scene.sizing).expect("valid sizing");
    let ctx = SizingContext::new(spec.h_min(), spec.h_root);
    let (r_min, r_max) = (spec.h_min() / C_H, spec.h_root / C_H);
    (0..parts.len())
        .filter(|&i| !parts.is_ballistic(i))
        .map(|i| {
            let s = sizing.radius_at_phi(&parts.x[i], Some(parts.phi[i]), &ctx).clamp(r_min, r_max);
            let level = spec.level_for_size(C_H * s);
            let pad = (2.0 * spec.h(level)).max(f64::from(scene.flip.remesh_interval) * DT * parts.v[i].norm());
            SizeDemand { center: parts.x[i], pad, level }
        })
        .collect()
}

/// Builds the dam-break fixture (a few seconds; its sizes are printed to stderr).
fn build_dam_break() -> DamBreak {
    // Invariant: the scene text is a constant that parses and validates (same as the S2 file).
    let scene: Scene = ron::from_str(DAM_SCENE).expect("dam-break scene parses");
    let mut sim = FlipTetSim::new(&scene).expect("dam-break scene is valid");
    for _ in 0..DAM_STEPS {
        sim.step().expect("dam-break step");
    }
    let spec = *sim.spec();
    let mesh = sim.mesh().clone();
    let parts = sim.particles().clone();
    let h_tet: Vec<f64> = mesh.tet_level.iter().map(|&l| spec.h(l)).collect();
    let demands = particle_demands(&scene, &spec, &parts);
    let p2g = particles_to_tets(&mesh, &h_tet, &parts, &scene.transfer);
    let (mut u_old, mut valid) = (p2g.u, p2g.valid);
    extrapolate(&mesh, &mut u_old, &mut valid, scene.flip.cfl.ceil() as u32 + 2);
    let g = scene.g();
    let u_new: Vec<Vec3> = u_old.iter().map(|u| u + g * DT).collect();
    let du: Vec<Vec3> = u_new.iter().zip(&u_old).map(|(a, b)| a - b).collect();
    let walls = 0x3f;
    let fx = DamBreak {
        nodal_old: node_average(&mesh, &u_old, walls),
        nodal_new: node_average(&mesh, &u_new, walls),
        nodal_du: node_average(&mesh, &du, walls),
        scene,
        octree: sim.octree().clone(),
        phi: sim.phi().to_vec(),
        mesh,
        parts,
        h_tet,
        demands,
        u_old,
        u_new,
        du,
    };
    eprintln!(
        "dam break after {DAM_STEPS} steps (t = {:.4} s): {} particles, {} leaves, {} nodes, {} tets, {} demands",
        sim.time(),
        fx.parts.len(),
        fx.octree.leaves.len(),
        fx.mesh.n_nodes(),
        fx.mesh.n_tets(),
        fx.demands.len()
    );
    fx
}

/// Uniform BCC tank of `n³` cubes in the unit cube, liquid below `y = 0.79`, and its assembled
/// pressure system (see the module docs).
struct Tank {
    /// Cubes per axis.
    n: u32,
    /// The assembled system.
    sys: PressureSystem,
}

/// Builds the tank pressure system for `n` cubes per axis.
fn build_tank(n: u32) -> Tank {
    // Invariant: a unit cube with coarsest = finest = n is a valid one-level spec.
    let spec = OctreeSpec::new(Pt3::origin(), Pt3::new(1.0, 1.0, 1.0), n, n).expect("unit-cube spec");
    let mesh = tetrahedralize(&Octree::uniform(spec, 0)).expect("uniform octree tetrahedralizes");
    let phi: Vec<f64> = mesh.nodes.iter().map(|x| x.y - 0.79).collect();
    let mut rng = Rng::new(2013);
    let u_star: Vec<Vec3> = (0..mesh.n_tets())
        .map(|_| {
            Vec3::new(0.0, -9.81 * DT, 0.0)
                + Vec3::new(rng.range(-1.0, 1.0), rng.range(-1.0, 1.0), rng.range(-1.0, 1.0)) * 0.05
        })
        .collect();
    let sys = assemble_pressure(&mesh, &phi, &u_star, spec.h_min(), &PressureParams::default());
    eprintln!(
        "tank n = {n}: {} nodes, {} tets, {} DOFs, {} matrix non-zeros",
        mesh.n_nodes(),
        mesh.n_tets(),
        sys.rhs.len(),
        sys.matrix.val.len()
    );
    Tank { n, sys }
}

/// The tank sizes: (label, cubes per axis), giving 11 283, 52 601 and 211 840 DOFs.
const TANKS: [(&str, u32); 3] = [("10k", 18), ("50k", 31), ("200k", 50)];

/// Which benchmarks the command line selects, so that fixtures (the 200 k tank takes seconds and
/// a few hundred MB) are only built when a benchmark needing them runs. Mirrors criterion's
/// positional `FILTER` (a regex; plain strings match as substrings): a filter with regex
/// metacharacters selects everything here and criterion does the exact filtering.
struct Selection {
    filters: Vec<String>,
}

impl Selection {
    /// Parses the positional arguments of criterion's command line.
    fn from_args() -> Self {
        const WITH_VALUE: [&str; 17] = [
            "-c",
            "--color",
            "-s",
            "--save-baseline",
            "-b",
            "--baseline",
            "--baseline-lenient",
            "--format",
            "--profile-time",
            "--load-baseline",
            "--sample-size",
            "--warm-up-time",
            "--measurement-time",
            "--nresamples",
            "--noise-threshold",
            "--confidence-level",
            "--significance-level",
        ];
        const WITH_VALUE_2: [&str; 2] = ["--plotting-backend", "--output-format"];
        let mut filters = Vec::new();
        let mut args = std::env::args().skip(1);
        while let Some(a) = args.next() {
            if a.starts_with('-') {
                if !a.contains('=') && (WITH_VALUE.contains(&a.as_str()) || WITH_VALUE_2.contains(&a.as_str())) {
                    args.next();
                }
            } else {
                filters.push(a);
            }
        }
        Self { filters }
    }

    /// Whether criterion may select one of the benchmark ids `{name}/{input}/t1` or `…/t2`.
    fn wants(&self, name: &str, input: &str) -> bool {
        let ids = THREADS.map(|t| format!("{name}/{input}/t{t}"));
        self.filters.is_empty()
            || self.filters.iter().any(|f| {
                f.chars().any(|ch| "\\.^$*+?()[]{}|".contains(ch)) || ids.iter().any(|id| id.contains(f.as_str()))
            })
    }
}

/// Group settings: `samples` samples of equal iteration count (flat sampling: several kernels
/// take 0.1–6 s per call, too long for criterion's linear ramp) within about `secs` seconds of
/// measurement after 0.5 s of warm-up.
fn group<'a>(c: &'a mut Criterion, name: &str, samples: usize, secs: f64) -> BenchmarkGroup<'a, WallTime> {
    let mut g = c.benchmark_group(name);
    g.sampling_mode(SamplingMode::Flat)
        .sample_size(samples)
        .warm_up_time(Duration::from_millis(500))
        .measurement_time(Duration::from_secs_f64(secs));
    g
}

/// `octree_build`: [`build_octree`] (recursive refinement from the demands + strong 2:1 balance;
/// serial, `t1` only) from the dam break's particle demands. Throughput: demands (one per
/// non-ballistic particle), i.e. demands/s.
fn bench_octree_build(c: &mut Criterion, fx: &DamBreak) {
    let mut g = group(c, "octree_build", 20, 3.0);
    g.throughput(Throughput::Elements(fx.demands.len() as u64));
    let spec = fx.octree.spec;
    g.bench_function("dam64/t1", |b| pool(1).install(|| b.iter(|| black_box(build_octree(spec, &fx.demands)))));
    g.finish();
}

/// The dam-break demands with every level shifted by `shift` (clamped to the spec's levels):
/// `+1` asks for cubes half the size everywhere (splits), `−1` for twice the size (merges).
fn shifted_demands(fx: &DamBreak, shift: i32) -> Vec<SizeDemand> {
    let top = i32::from(fx.octree.spec.levels) - 1;
    fx.demands.iter().map(|d| SizeDemand { level: (i32::from(d.level) + shift).clamp(0, top) as u8, ..*d }).collect()
}

/// `split_merge`: [`split_merge`] (split passes, merge passes with a k-d tree of the particles,
/// surface snap against the old level set; serial, `t1` only) of the dam-break particles against
/// three new octrees: `remesh` (the octree of the current demands, what the next remesh builds:
/// few changes), `refine` (every demand one level finer: splits) and `coarsen` (one level
/// coarser: merges). The particle copy is made outside the timed routine. Throughput: particles
/// in, i.e. particles/s.
fn bench_split_merge(c: &mut Criterion, fx: &DamBreak) {
    let spec = fx.octree.spec;
    let old = OldLevelSet { mesh: &fx.mesh, octree: &fx.octree, phi: &fx.phi };
    let pp = &fx.scene.particles;
    let cases = [("remesh", 0), ("refine", 1), ("coarsen", -1)];
    let mut g = group(c, "split_merge", 20, 3.0);
    g.throughput(Throughput::Elements(fx.parts.len() as u64));
    for (name, shift) in cases {
        let oct = build_octree(spec, &shifted_demands(fx, shift));
        // Invariant: the bench scene's particle budget is the default (far above these counts).
        let counts = split_merge(&mut fx.parts.clone(), &oct, pp, &mut Rng::new(1), &old).expect("within budget");
        eprintln!(
            "split_merge {name}: {} particles, {} splits, {} merges",
            fx.parts.len(),
            counts.split,
            counts.merged
        );
        g.bench_function(format!("dam64_{name}/t1"), |b| {
            pool(1).install(|| {
                b.iter_batched_ref(
                    || (fx.parts.clone(), Rng::new(1)),
                    |(p, rng)| black_box(split_merge(p, &oct, pp, rng, &old).expect("within budget")),
                    BatchSize::LargeInput,
                )
            })
        });
    }
    g.finish();
}

/// `tetrahedralize`: graded BCC tetrahedralisation of the dam-break octree including
/// `compute_geometry` (volumes, gradients, face neighbours, node rings; the per-tet and per-node
/// parts run in parallel). Throughput: tets, i.e. tets/s.
fn bench_tetrahedralize(c: &mut Criterion, fx: &DamBreak) {
    let mut g = group(c, "tetrahedralize", 10, 3.0);
    g.throughput(Throughput::Elements(fx.mesh.n_tets() as u64));
    for t in THREADS {
        g.bench_function(format!("dam64/t{t}"), |b| {
            pool(t).install(|| b.iter(|| black_box(tetrahedralize(&fx.octree).expect("valid octree"))))
        });
    }
    g.finish();
}

/// `assemble`: [`assemble_pressure`] (liquid classification, stiffness, second-order ghost terms
/// with the `k_t` rule, null-space check; serial, `t1` only) on the dam-break mesh and level
/// set with `u* = u_old + g Δt`. Throughput: rows (pressure DOFs), i.e. rows/s.
fn bench_assemble(c: &mut Criterion, fx: &DamBreak) {
    let h_min = fx.octree.spec.h_min();
    let p = PressureParams::default();
    let rows = assemble_pressure(&fx.mesh, &fx.phi, &fx.u_new, h_min, &p).rhs.len();
    eprintln!("assemble: {rows} rows");
    let mut g = group(c, "assemble", 20, 3.0);
    g.throughput(Throughput::Elements(rows as u64));
    g.bench_function("dam64/t1", |b| {
        pool(1).install(|| b.iter(|| black_box(assemble_pressure(&fx.mesh, &fx.phi, &fx.u_new, h_min, &p))))
    });
    g.finish();
}

/// `p2g`: [`particles_to_tets`] (bounding-box tree of the particles, kernel-weighted gather per
/// tet in parallel, coverage) on the dam break. Throughput: particles, i.e. particles/s (µs per
/// particle is its inverse).
fn bench_p2g(c: &mut Criterion, fx: &DamBreak) {
    let mut g = group(c, "p2g", 20, 3.0);
    g.throughput(Throughput::Elements(fx.parts.len() as u64));
    for t in THREADS {
        g.bench_function(format!("dam64/t{t}"), |b| {
            pool(t)
                .install(|| b.iter(|| black_box(particles_to_tets(&fx.mesh, &fx.h_tet, &fx.parts, &fx.scene.transfer))))
        });
    }
    g.finish();
}

/// G2P and advection of one step with the simulator's own kernels (`flip_tet::advect::{g2p,
/// advect}`, `FlipTetSim::step` stages 9–10): the PIC/FLIP blend of the sub-tet interpolated
/// `u_new` and `Δu` (spec §3.7), then RK2 through `u_new` (the default leapfrog drift; the
/// time-centred field `(1 − s) u_old + s u_new` when the scene asks for `TimeCentred`) with CFL
/// substeps `ceil(|v| Δt / (h/2))` and a tet walk per velocity sample (spec §3.8), box walls, and
/// the final relocation walk. Ballistic particles fly free (kick `g Δt`). Returns the substeps
/// beyond one.
fn g2p_advect(fx: &DamBreak, parts: &mut Particles) -> u32 {
    let (mesh, oct) = (&fx.mesh, &fx.octree);
    let r_min = oct.spec.h_min() / C_H;
    let new = TetField { tet: &fx.u_new, nodal: &fx.nodal_new };
    g2p(mesh, parts, new, TetField { tet: &fx.du, nodal: &fx.nodal_du }, r_min, &fx.scene.flip);
    let grid = AdvectMesh { mesh, octree: oct, h_tet: &fx.h_tet };
    let centred = fx.scene.flip.time_integration == TimeIntegration::TimeCentred;
    let old = centred.then_some(TetField { tet: &fx.u_old, nodal: &fx.nodal_old });
    let subs: u32 = advect(&grid, parts, new, old, fx.scene.g() * DT, DT).iter().sum();
    apply_walls(parts, &fx.scene.min(), &fx.scene.max(), &[false; 6]);
    parts.tet.par_iter_mut().zip(parts.x.par_iter()).for_each(|(t, x)| {
        *t = mesh.walk(oct, *t, x).map_or(NONE, |(tt, _)| tt);
    });
    subs
}

/// `g2p_advect`: [`g2p_advect`] on a fresh copy of the dam-break particles (the copy is made
/// outside the timed routine). Throughput: particles, i.e. particles/s.
fn bench_g2p_advect(c: &mut Criterion, fx: &DamBreak) {
    let subs = g2p_advect(fx, &mut fx.parts.clone());
    eprintln!("g2p_advect: {} particles, {subs} extra CFL substeps", fx.parts.len());
    let mut g = group(c, "g2p_advect", 20, 3.0);
    g.throughput(Throughput::Elements(fx.parts.len() as u64));
    for t in THREADS {
        g.bench_function(format!("dam64/t{t}"), |b| {
            pool(t).install(|| {
                b.iter_batched_ref(|| fx.parts.clone(), |p| black_box(g2p_advect(fx, p)), BatchSize::LargeInput)
            })
        });
    }
    g.finish();
}

/// `hull_levelset`: the simulator's node level set [`level_set_on_nodes_sign_inside`] (triplet
/// hulls of the near-surface particles, sphere union elsewhere, mirrored particles at the six
/// closed walls, exact values only where the redistancing needs them, then the interior
/// redistancing of the band; spec §3.11.3) on the dam break. Throughput: band nodes (nodes with
/// `|φ| <` their band `max(3 h, 6 r_max)`), i.e. band nodes/s.
fn bench_hull_levelset(c: &mut Criterion, fx: &DamBreak) {
    let walls = Walls { min: fx.scene.min(), max: fx.scene.max(), mirror: [true; 6], node_in_solid: None };
    let sampler = LevelSetSampler::new(&fx.parts, &fx.scene.surface, &walls);
    let band = (0..fx.mesh.n_nodes()).filter(|&i| fx.phi[i].abs() < sampler.band(fx.mesh.node_h[i])).count();
    eprintln!("hull_levelset: {band} band nodes of {} nodes, {} sources", fx.mesh.n_nodes(), sampler.n_sources());
    let mut g = group(c, "hull_levelset", 10, 3.0);
    g.throughput(Throughput::Elements(band as u64));
    for t in THREADS {
        g.bench_function(format!("dam64/t{t}"), |b| {
            pool(t).install(|| {
                b.iter(|| black_box(level_set_on_nodes_sign_inside(&fx.mesh, &fx.parts, &fx.scene.surface, &walls)))
            })
        });
    }
    g.finish();
}

/// `marching_tets`: [`marching_tets`] (crossing test, edge snapping, triangle extraction with
/// shared edge vertices; serial, `t1` only) of the dam break's node level set. Throughput: tets
/// scanned, i.e. tets/s.
fn bench_marching_tets(c: &mut Criterion, fx: &DamBreak) {
    let tri = marching_tets(&fx.mesh, &fx.phi).expect("finite level set");
    eprintln!("marching_tets: {} triangles from {} tets", tri.faces.len(), fx.mesh.n_tets());
    let mut g = group(c, "marching_tets", 20, 3.0);
    g.throughput(Throughput::Elements(fx.mesh.n_tets() as u64));
    g.bench_function("dam64/t1", |b| {
        pool(1).install(|| b.iter(|| black_box(marching_tets(&fx.mesh, &fx.phi).expect("finite level set"))))
    });
    g.finish();
}

/// `solve_{direct,mic,jacobi}`: [`PressureSolver::solve`] on the tank systems, cold start, the
/// default tolerance `‖b − Aq‖ ≤ 1e−6 ‖b‖`. `direct` is faer's sparse Cholesky with AMD ordering
/// including the symbolic analysis (a fresh solver: the cost of the first solve after the
/// pattern changes), `Par::Seq` in the library, so `t1` only; `mic` is MIC(0)-PCG (factor 0.97,
/// serial triangular solves, parallel products); `jacobi` is Jacobi-PCG. Throughput: DOFs.
///
/// `solve_direct/200k` is left out: one factorisation took 85 s with 4.7e8 factor non-zeros
/// (≈ 3.7 GB) on the project machine, so ten samples would take a quarter of an hour — far past
/// the threshold (`direct_max_dofs` = 30 000) above which `Auto` uses PCG anyway.
fn bench_solves(c: &mut Criterion, sel: &Selection) {
    let kinds = [
        ("solve_direct", SolverKind::DirectCholesky),
        ("solve_mic", SolverKind::PcgIc0),
        ("solve_jacobi", SolverKind::PcgJacobi),
    ];
    for (label, n) in TANKS {
        if !kinds.iter().any(|(k, _)| sel.wants(k, label)) {
            continue;
        }
        let tank = build_tank(n);
        for (name, kind) in kinds {
            if (name, label) == ("solve_direct", "200k") || !sel.wants(name, label) {
                continue;
            }
            let p = PressureParams { solver: kind, ..Default::default() };
            let mut probe = PressureSolver::default();
            let t0 = std::time::Instant::now();
            let (_, rep) = probe.solve(&tank.sys, &p, None).expect("tank system solves");
            let probe_s = t0.elapsed().as_secs_f64();
            eprintln!(
                "{name}/{label} (n = {}): {} iterations, residual {:.2e}, factor nnz {}, probe {:.3} s",
                tank.n, rep.iters, rep.rel_residual, rep.factor_nnz, probe_s
            );
            // Ten samples of one solve each: criterion runs `ceil(target / 10 / warm-up mean)`
            // solves per sample, so a target of half the probe's ten solves keeps that at one
            // (criterion then warns that the samples overrun the target; harmless).
            let mut g = group(c, name, 10, (5.0 * probe_s).max(3.0));
            g.throughput(Throughput::Elements(tank.sys.rhs.len() as u64));
            let threads: &[usize] = if kind == SolverKind::DirectCholesky { &[1] } else { &THREADS };
            for &t in threads {
                g.bench_function(format!("{label}/t{t}"), |b| {
                    pool(t).install(|| {
                        b.iter(|| {
                            let mut s = PressureSolver::default();
                            black_box(s.solve(&tank.sys, &p, None).expect("tank system solves"))
                        })
                    })
                });
            }
            g.finish();
        }
    }
}

/// Runs the groups in the order of a step's stages, then the solves by size.
fn main() {
    let mut c = Criterion::default().configure_from_args();
    let sel = Selection::from_args();
    let dam_groups = [
        "octree_build",
        "split_merge",
        "tetrahedralize",
        "assemble",
        "p2g",
        "g2p_advect",
        "hull_levelset",
        "marching_tets",
    ];
    if dam_groups.iter().any(|g| sel.wants(g, "dam64")) {
        let fx = &build_dam_break();
        bench_octree_build(&mut c, fx);
        bench_split_merge(&mut c, fx);
        bench_tetrahedralize(&mut c, fx);
        bench_assemble(&mut c, fx);
        bench_p2g(&mut c, fx);
        bench_g2p_advect(&mut c, fx);
        bench_hull_levelset(&mut c, fx);
        bench_marching_tets(&mut c, fx);
    }
    bench_solves(&mut c, &sel);
    c.final_summary();
}

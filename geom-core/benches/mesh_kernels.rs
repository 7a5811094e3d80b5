//! Mesh kernel benchmarks on a 100 × 100-vertex grid (10 000 vertices, 19 602 triangles):
//! cotan stiffness assembly, face normals, topology build and one level of linear subdivision.
//! Small sample counts keep `cargo bench` short.

use std::hint::black_box;
use std::time::Duration;

use criterion::{criterion_group, criterion_main, Criterion};
use geom_core::math::Vec3;
use geom_core::mesh::{cotan_stiffness, face_normals, subdivide_linear, Topology};
use geom_core::procedural::{grid, GridSpec};

fn kernels(c: &mut Criterion) {
    let g = grid(&GridSpec { quads: [99, 99], ..Default::default() }).expect("valid grid spec");
    // Bend the sheet so the normals and cotangents are not all identical.
    let p = g.positions.iter().map(|q| q + Vec3::new(0.0, 0.0, 0.1 * (3.0 * q.x).sin() * (2.0 * q.y).cos())).collect();
    let m = g.with_positions(p).expect("same vertex count");
    let mut grp = c.benchmark_group("mesh_kernels_10k");
    grp.sample_size(10).warm_up_time(Duration::from_millis(300)).measurement_time(Duration::from_secs(1));
    grp.bench_function("cotan_stiffness", |b| {
        b.iter(|| cotan_stiffness(black_box(&m.faces), black_box(&m.positions), None))
    });
    grp.bench_function("face_normals", |b| b.iter(|| face_normals(black_box(&m.faces), black_box(&m.positions))));
    grp.bench_function("topology_build", |b| b.iter(|| Topology::new(m.positions.len(), black_box(&m.faces))));
    grp.bench_function("subdivide_linear_1", |b| b.iter(|| subdivide_linear(black_box(&m), 1)));
    grp.finish();
}

criterion_group!(benches, kernels);
criterion_main!(benches);

//! Criterion micro-benchmarks (spec §9): closed-form alignment, one DP on a short walk with and
//! without beam, clustering of a walk database.

use criterion::{criterion_group, criterion_main, Criterion};
use geom_core::math::{Planar, Vec3};
use perf_control::data::walk_take;
use perf_control::{align, interpret, ClusterBy, ClusterDistance, ClusterOptions, DpParams, MappingDb, Representative};
use std::hint::black_box;

fn bench(c: &mut Criterion) {
    // 6 frames × 4 points.
    let a: Vec<Vec3> =
        (0..24).map(|i| Vec3::new((i as f64 * 0.37).sin(), 0.1 * i as f64, (i as f64 * 0.91).cos())).collect();
    let g = Planar::new(0.3, -1.2, 0.7);
    let x: Vec<Vec3> = a.iter().map(|p| g.apply_point(*p) + Vec3::new(0.01, 0.0, -0.02)).collect();
    let w = [1.0; 4];
    c.bench_function("align_closed_form_6x4", |b| b.iter(|| align(black_box(&x), black_box(&a), &w)));

    let db = MappingDb::from_takes(vec![walk_take(11, 40.0, 30.0)], 10.0).expect("walk database");
    let x = walk_take(101, 20.0, 30.0).control.downsample(3);
    let mut p = DpParams::default();
    let mut g = c.benchmark_group("dp");
    g.sample_size(10);
    g.bench_function("dp_full_walk_20s_exact", |b| b.iter(|| interpret(&db, black_box(&x), &p).expect("dp")));
    p.beam = Some(0.3);
    g.bench_function("dp_full_walk_20s_beam", |b| b.iter(|| interpret(&db, black_box(&x), &p).expect("dp")));
    let o = ClusterOptions {
        by: ClusterBy::TargetSize(40),
        distance: ClusterDistance::ControlAndTarget,
        stretch_limit_s: 0.2,
        representative: Representative::Random,
        seed: 1,
    };
    g.bench_function("cluster_walk_db", |b| {
        b.iter(|| {
            let mut d = db.clone();
            d.cluster(&o).expect("cluster")
        })
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);

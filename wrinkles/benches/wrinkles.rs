//! Criterion group `wrinkles` (spec §9): precomputation at two tolerances, per-frame modulation
//! per mode at T ≈ 1000 and 10 000, smoothing (average vs LSQ), displaced mesh at L = 4, 8, 16.

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use geom_core::math::Pt3;
use geom_core::procedural::{grid, Diagonals, GridSpec, Plane};
use wrinkles::*;

fn sheet(quads: u32) -> RestMesh {
    let m = grid(&GridSpec {
        quads: [quads, quads],
        size: [0.5, 0.5],
        plane: Plane::XY,
        diagonals: Diagonals::Alternating,
        center: Pt3::new(0.25, 0.25, 0.0),
    })
    .expect("grid");
    RestMesh::from_trimesh(&m).expect("uv")
}

fn pattern() -> WrinklePattern {
    WrinklePattern::new(
        &PatternSource::Procedural(Procedural::Folds {
            wavelength_uv: 0.08,
            angle_deg: 0.0,
            spread_deg: 8.0,
            count: 4,
            irregularity: 0.3,
            seed: 7,
        }),
        PatternOptions { normalization: Normalization::TargetRestSlope(0.5), ..Default::default() },
    )
    .expect("pattern")
}

fn gather(mesh: &RestMesh) -> Vec<Pt3> {
    mesh.positions.iter().map(|p| Pt3::new(0.25 + (p.x - 0.25) * (1.0 - 0.8 * p.y), p.y, 0.0)).collect()
}

fn bench(c: &mut Criterion) {
    let mut g = c.benchmark_group("wrinkles");
    g.sample_size(10);
    let pats = [pattern()];
    // T = 2·22² = 968 ≈ 1000 and 2·71² = 10 082 ≈ 10 000.
    let small = sheet(22);
    for tol in [1e-3, 1e-4] {
        let o = PrecomputeOptions { tolerance: tol, ..Default::default() };
        g.bench_with_input(BenchmarkId::new("precompute/T1000", tol), &o, |b, o| {
            b.iter(|| precompute(&small, &pats, o).expect("precompute"))
        });
    }
    for (name, quads) in [("T1000", 22u32), ("T10000", 71)] {
        let mesh = sheet(quads);
        let rig = precompute(&mesh, &pats, &PrecomputeOptions::default()).expect("precompute");
        let def = gather(&mesh);
        for (mname, mode) in [
            ("linearized", ModulationMode::Linearized { strain: StrainMeasure::Green }),
            ("exact_flat", ModulationMode::ExactFlatRest),
        ] {
            let mut a =
                WrinkleAnimator::new(rig.clone(), ModulationOptions { mode, ..Default::default() }).expect("animator");
            g.bench_function(BenchmarkId::new(format!("modulate/{mname}"), name), |b| {
                b.iter(|| a.frame(&def).expect("frame"))
            });
        }
        let mean_c4 = rig.coeffs.iter().map(|c| c.c4).sum::<f64>() / rig.coeffs.len() as f64;
        for (sname, sm) in [
            ("average", Smoothing::VertexAverage { weights: VertexWeights::Area }),
            ("lsq", Smoothing::AreaConsistent { mu: 1e-3 * mean_c4 }),
        ] {
            let o = ModulationOptions {
                mode: ModulationMode::Linearized { strain: StrainMeasure::Green },
                smoothing: sm,
                ..Default::default()
            };
            let mut a = WrinkleAnimator::new(rig.clone(), o).expect("animator");
            g.bench_function(BenchmarkId::new(format!("smooth/{sname}"), mesh.positions.len()), |b| {
                b.iter(|| a.frame(&def).expect("frame"))
            });
        }
        if name == "T1000" {
            let mut a = WrinkleAnimator::new(rig.clone(), ModulationOptions::default()).expect("animator");
            let fm = a.frame(&def).expect("frame");
            for l in [4u32, 8, 16] {
                g.bench_function(BenchmarkId::new("displaced_mesh", l), |b| {
                    b.iter(|| a.displaced_mesh(&def, &fm, l).expect("mesh"))
                });
            }
        }
    }
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);

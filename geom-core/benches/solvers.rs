//! Criterion benchmarks of the sparse solver facade on a 2-D grid Laplacian + mass with
//! 256 × 256 = 65 536 unknowns (surface-like sparsity, as a cloth Hessian's scalar block):
//! symbolic analysis, numeric factorisation (the per-step cost of shells), solve, and IC(0)-PCG.
//! The accuracy-versus-time sweep over mesh sizes is `cargo xtask bench geom-core`.

use criterion::{criterion_group, criterion_main, Criterion};
use geom_core::linalg::{pcg, CgOptions, Csr, Ic0, Jacobi, Ordering, SparseLlt, Triplets};
use std::hint::black_box;

const SIDE: usize = 256;

/// 5-point Laplacian of a `side × side` grid with free boundary, plus `mass · I`.
fn grid_laplacian(side: usize, mass: f64) -> Csr {
    let n = side * side;
    let id = |i: usize, j: usize| (j * side + i) as u32;
    let mut t = Triplets::with_capacity(n, n, 5 * n);
    for j in 0..side {
        for i in 0..side {
            let mut deg = 0.0;
            for (di, dj) in [(-1i64, 0i64), (1, 0), (0, -1), (0, 1)] {
                let (a, b) = (i as i64 + di, j as i64 + dj);
                if a >= 0 && b >= 0 && (a as usize) < side && (b as usize) < side {
                    t.push(id(i, j), id(a as usize, b as usize), -1.0);
                    deg += 1.0;
                }
            }
            t.push(id(i, j), id(i, j), deg + mass);
        }
    }
    Csr::from_triplets(&t)
}

fn rhs(n: usize) -> Vec<f64> {
    (0..n).map(|i| ((i * 7919) % 1000) as f64 / 500.0 - 1.0).collect()
}

fn solvers(c: &mut Criterion) {
    let a = grid_laplacian(SIDE, 1e-2);
    let n = a.nrows;
    let csc = a.to_csc_lower();
    let b = rhs(n);
    let mut f = SparseLlt::analyze(&csc, Ordering::Amd).expect("SPD grid Laplacian");
    f.factor(&csc).expect("SPD grid Laplacian");

    let mut g = c.benchmark_group("llt_grid_65k");
    g.sample_size(10);
    g.bench_function("analyze_amd", |bench| {
        bench.iter(|| SparseLlt::analyze(black_box(&csc), Ordering::Amd).expect("analysis"))
    });
    g.bench_function("factor_numeric", |bench| bench.iter(|| f.factor(black_box(&csc)).expect("factor")));
    g.bench_function("solve", |bench| {
        bench.iter(|| {
            let mut x = b.clone();
            f.solve_in_place(black_box(&mut x)).expect("solve");
            x
        })
    });
    g.finish();

    let mut g = c.benchmark_group("pcg_grid_65k_tol1e-8");
    g.sample_size(10);
    let opts = CgOptions { tol: 1e-8, max_iters: 5000, history: false };
    let jac = Jacobi::new(&a).expect("positive diagonal");
    g.bench_function("jacobi", |bench| {
        bench.iter(|| {
            let mut x = vec![0.0; n];
            pcg(&a, black_box(&b), &mut x, &jac, &opts).expect("valid input")
        })
    });
    g.bench_function("ic0_setup_and_solve", |bench| {
        bench.iter(|| {
            let m = Ic0::new(&a, None).expect("IC(0)");
            let mut x = vec![0.0; n];
            pcg(&a, black_box(&b), &mut x, &m, &opts).expect("valid input")
        })
    });
    g.finish();
}

criterion_group!(benches, solvers);
criterion_main!(benches);

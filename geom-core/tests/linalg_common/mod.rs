//! Test matrices for the `linalg_*` integration tests, built from finite-difference stencils so
//! the solver tests do not depend on the mesh module.
#![allow(dead_code)]

use geom_core::linalg::{Csr, Triplets};

/// 5-point Laplacian on an `nx × ny` grid plus `mass · I`. With `dirichlet`, every node has
/// diagonal 4 (missing neighbours are fixed zero values: SPD); otherwise the diagonal is the
/// node's neighbour count (free boundary: singular when `mass = 0`, constants in the kernel).
pub fn laplacian_2d(nx: usize, ny: usize, mass: f64, dirichlet: bool) -> Csr {
    let id = |i: usize, j: usize| (j * nx + i) as u32;
    let mut t = Triplets::with_capacity(nx * ny, nx * ny, 5 * nx * ny);
    for j in 0..ny {
        for i in 0..nx {
            let mut nb = Vec::new();
            if i > 0 {
                nb.push(id(i - 1, j));
            }
            if i + 1 < nx {
                nb.push(id(i + 1, j));
            }
            if j > 0 {
                nb.push(id(i, j - 1));
            }
            if j + 1 < ny {
                nb.push(id(i, j + 1));
            }
            let d = if dirichlet { 4.0 } else { nb.len() as f64 };
            t.push(id(i, j), id(i, j), d + mass);
            for k in nb {
                t.push(id(i, j), k, -1.0);
            }
        }
    }
    Csr::from_triplets(&t)
}

/// 7-point Dirichlet Poisson matrix on an `n × n × n` grid (diagonal 6, off-diagonals −1).
pub fn poisson_3d(n: usize) -> Csr {
    let id = |i: usize, j: usize, k: usize| ((k * n + j) * n + i) as u32;
    let mut t = Triplets::with_capacity(n * n * n, n * n * n, 7 * n * n * n);
    for k in 0..n {
        for j in 0..n {
            for i in 0..n {
                let me = id(i, j, k);
                t.push(me, me, 6.0);
                if i > 0 {
                    t.push(me, id(i - 1, j, k), -1.0);
                }
                if i + 1 < n {
                    t.push(me, id(i + 1, j, k), -1.0);
                }
                if j > 0 {
                    t.push(me, id(i, j - 1, k), -1.0);
                }
                if j + 1 < n {
                    t.push(me, id(i, j + 1, k), -1.0);
                }
                if k > 0 {
                    t.push(me, id(i, j, k - 1), -1.0);
                }
                if k + 1 < n {
                    t.push(me, id(i, j, k + 1), -1.0);
                }
            }
        }
    }
    Csr::from_triplets(&t)
}

/// Constraint rows: row `r` ties unknowns `r·stride` and `r·stride + 1` with weights
/// `(1, −0.5)` plus a third unknown `(r·stride + 7) mod n` with weight 0.25 (independent rows).
pub fn constraints(m: usize, n: usize, stride: usize) -> Csr {
    let mut t = Triplets::new(m, n);
    for r in 0..m {
        let a = r * stride;
        t.push(r as u32, a as u32, 1.0);
        t.push(r as u32, (a + 1) as u32, -0.5);
        t.push(r as u32, ((a + 7) % n) as u32, 0.25);
    }
    Csr::from_triplets(&t)
}

/// The saddle-point matrix `[A Cᵀ; C 0]` (full storage, explicit zero diagonal on the dual
/// block so the LDLᵀ pattern has every diagonal).
pub fn kkt(a: &Csr, c: &Csr) -> Csr {
    let (n, m) = (a.nrows, c.nrows);
    let mut t = Triplets::new(n + m, n + m);
    for i in 0..n {
        let (cols, vals) = a.row(i);
        for (&j, &v) in cols.iter().zip(vals) {
            t.push(i as u32, j, v);
        }
    }
    for r in 0..m {
        let (cols, vals) = c.row(r);
        for (&j, &v) in cols.iter().zip(vals) {
            t.push((n + r) as u32, j, v);
            t.push(j, (n + r) as u32, v);
        }
        t.push((n + r) as u32, (n + r) as u32, 0.0);
    }
    Csr::from_triplets(&t)
}

/// A deterministic pseudo-random vector in [−1, 1) (SplitMix64-style hash of the index).
pub fn test_vector(n: usize, seed: u64) -> Vec<f64> {
    (0..n)
        .map(|i| {
            let mut z = (i as u64).wrapping_add(seed.wrapping_mul(0x9E37_79B9_7F4A_7C15));
            z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
            z ^= z >> 31;
            (z >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
        })
        .collect()
}

/// Runs `f` in a Rayon pool with `threads` threads.
pub fn with_threads<T: Send>(threads: usize, f: impl FnOnce() -> T + Send) -> T {
    rayon::ThreadPoolBuilder::new().num_threads(threads).build().expect("thread pool").install(f)
}

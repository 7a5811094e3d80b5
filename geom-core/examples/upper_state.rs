//! Measures what a dirty upper vector-register state costs scalar code, and that
//! `geom_core::linalg::dense::matmul` leaves it clean (see `geom_core::linalg::zero_upper`).
//!
//! `cargo run --release -p geom-core --example upper_state`
//!
//! Prints the wall time of one scalar `f64` loop (legacy-SSE code, as everything in this workspace
//! is compiled for baseline x86-64) before any product, after faer's raw `matmul`, after
//! `zero_upper`, and after geom-core's `dense::matmul`; the ratios are to the first time.

use geom_core::faer::{Accum, Mat, Par};
use geom_core::linalg::dense;
use std::hint::black_box;
use std::time::Instant;

/// A dependent chain of scalar multiply-adds, square roots and sines (≈ 0.2 s at full speed).
fn scalar_loop() -> f64 {
    let n = black_box(20_000_000usize);
    let (mut acc, mut x) = (0.0f64, 1.0001f64);
    for i in 0..n {
        x = x * 1.000_000_1 + (i as f64).sqrt() * 1e-9;
        acc += x.sin();
    }
    acc
}

fn timed() -> f64 {
    let t0 = Instant::now();
    black_box(scalar_loop());
    t0.elapsed().as_secs_f64()
}

fn main() {
    let a = Mat::<f64>::from_fn(64, 12, |i, j| (i + j) as f64);
    let b = Mat::<f64>::from_fn(12, 64, |i, j| (i * j) as f64);
    let mut c = Mat::<f64>::zeros(64, 64);
    timed();
    let base = timed();
    println!("scalar loop, clean state:               {base:.3} s");
    geom_core::faer::linalg::matmul::matmul(c.as_mut(), Accum::Replace, a.as_ref(), b.as_ref(), 1.0, Par::Seq);
    let raw = timed();
    println!("after faer's raw matmul:                {raw:.3} s  ({:.1}x)", raw / base);
    geom_core::linalg::zero_upper();
    let cleared = timed();
    println!("after zero_upper:                       {cleared:.3} s  ({:.1}x)", cleared / base);
    dense::matmul(c.as_mut(), Accum::Replace, a.as_ref(), b.as_ref(), 1.0, Par::Seq);
    let wrapped = timed();
    println!("after geom_core::linalg::dense::matmul: {wrapped:.3} s  ({:.1}x)", wrapped / base);
    println!("(c[1,1] = {})", c[(1, 1)]);
}

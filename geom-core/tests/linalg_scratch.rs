mod linalg_common;
use geom_core::linalg::*;
use linalg_common::*;
use std::time::Instant;

#[test]
fn scratch() {
    let a = laplacian_2d(447, 447, 0.01, false);
    let n = a.nrows;
    let x = test_vector(n, 1);
    let mut y = vec![0.0; n];
    let t = Instant::now(); for _ in 0..100 { a.mul_vec_par(&x, &mut y); } println!("mul_vec_par {:.3} ms", t.elapsed().as_secs_f64()*10.0);
    let t = Instant::now(); for _ in 0..100 { a.mul_vec(&x, &mut y); } println!("mul_vec {:.3} ms", t.elapsed().as_secs_f64()*10.0);
    let ic = Ic0::new(&a, None).unwrap();
    let t = Instant::now(); for _ in 0..100 { ic.apply(&x, &mut y); } println!("ic0 apply {:.3} ms", t.elapsed().as_secs_f64()*10.0);
    let mut s = 0.0;
    let t = Instant::now(); for _ in 0..100 { s += dot(&x, &y); } println!("dot {:.3} ms {s}", t.elapsed().as_secs_f64()*10.0);
    let b = test_vector(n, 2);
    let mut z = vec![0.0; n];
    let t = Instant::now();
    let r = pcg(&a, &b, &mut z, &ic, &CgOptions { tol: 1e-8, max_iters: 10000, history: false }).unwrap();
    println!("pcg {} its {:.3} ms/it", r.iters, t.elapsed().as_secs_f64()*1e3 / r.iters as f64);
}

//! Orderings of the constrained (KKT) solve on one captured step of the Xavier character
//! (3038 vertices, K animation-aware clusters; spec §6.4), beside the untracked LLᵀ of A:
//! scalar AMD on the KKT pattern, AMD on vertices and regions ([`Ordering::AmdBlocks`], what
//! `AmdRegularizedLdlt` uses) and constraint-last. Prints best-of-7 factor + solve times, the
//! factor's stored entries, the unrefined residuals of the δ-shifted solve and its distance to
//! the refined one, then the whole `TrackingSolver` solve with 0 and 1 refinement steps.
//!
//! `cargo run --release -p tracks --example kkt_orderings -- [K = 280] [δ = 1e-8]`
use faer::sparse::{SparseColMat, SymbolicSparseColMat};
use geom_core::linalg::{Csc, Ordering, Regularization, SparseLdlt, SparseLlt};
use geom_core::NONE;
use shells::VelocitySolve;
use std::time::Instant;
use tracks::procedural::{xavier, xavier_guide, xavier_sim};
use tracks::{build_test_functions, CapturedSystem, ClusterOptions, TestFunctionSpec, TrackingConstraints};

fn time<F: FnMut()>(mut f: F) -> f64 {
    let mut best = f64::INFINITY;
    for _ in 0..7 {
        let t = Instant::now();
        f();
        best = best.min(t.elapsed().as_secs_f64());
    }
    best * 1e3
}

fn main() {
    let k: usize = std::env::args().nth(1).and_then(|s| s.parse().ok()).unwrap_or(280);
    let delta_rel: f64 = std::env::args().nth(2).and_then(|s| s.parse().ok()).unwrap_or(1e-8);
    let x = xavier().expect("xavier");
    let guide = xavier_guide(&x, 2.0).expect("guide");
    let mut sim = xavier_sim(&x, &guide).expect("the Xavier cloth is a valid shell scene");
    sim.step(1.0 / 120.0).expect("step");
    let sys = CapturedSystem::capture_step(&mut sim, 1.0 / 120.0).expect("captured step");
    let opts = ClusterOptions { regions: k, mu: 0.98, frames: 32, seed: 7, ..ClusterOptions::default() };
    let tf = build_test_functions(&TestFunctionSpec::Clustered(opts), &guide, &x.mesh, None).expect("tf");
    let cons = TrackingConstraints::build(&x.mesh, &x.mesh, &tf).expect("cons");
    {
        let isys = sys.system();
        for refine in [0u32, 1] {
            let opts = tracks::TrackOptions {
                kkt: tracks::KktMethod::AmdRegularizedLdlt { delta: 1e-8 },
                refine_steps: refine,
                ..Default::default()
            };
            let mut solver = tracks::TrackingSolver::new(
                cons.clone(),
                guide.clone(),
                &opts,
                sim.fill_reducing_perm().to_vec(),
                sim.llt_symbolic(),
            );
            solver.solve(&isys).expect("solve");
            let t = time(|| {
                solver.solve(&isys).expect("solve");
            });
            println!("TrackingSolver AmdRegularized refine {refine}: {t:.2} ms (t_kkt {:.2})", solver.last.t_kkt * 1e3);
        }
    }
    let n = sys.a.nrows();
    let nv = n / 3;
    let m = 3 * cons.len();
    let mut cft: Vec<Vec<(u32, f64)>> = vec![Vec::new(); nv];
    for i in 0..cons.len() {
        let (c, v) = cons.c.row(i);
        for (&l, &w) in c.iter().zip(v) {
            let f = sys.dofs.free_index[l as usize];
            if f != NONE {
                cft[f as usize].push((i as u32, w));
            }
        }
    }
    let rowlen: Vec<usize> = (0..cons.len()).map(|i| cons.c.row(i).0.len()).collect();
    println!(
        "n = {n}, m = {m}, nnz(A lower) = {}, mean support = {:.1}",
        sys.a.val().len(),
        rowlen.iter().sum::<usize>() as f64 / rowlen.len() as f64
    );
    // KKT (lower triangle), (2,2) = -delta.
    let sa = sys.a.symbolic();
    let mut col_ptr = vec![0usize];
    let mut row_idx = Vec::new();
    let mut val = Vec::new();
    let av = sys.a.val();
    let max_diag = av.iter().fold(0.0f64, |a, x| a.max(x.abs()));
    for j in 0..n {
        for kk in sa.col_range(j) {
            row_idx.push(sa.row_idx()[kk]);
            val.push(av[kk]);
        }
        for &(i, w) in &cft[j / 3] {
            row_idx.push(n + 3 * i as usize + j % 3);
            val.push(w);
        }
        col_ptr.push(row_idx.len());
    }
    for r in 0..m {
        row_idx.push(n + r);
        val.push(-delta_rel * max_diag);
        col_ptr.push(row_idx.len());
    }
    let kkt: Csc = SparseColMat::new(SymbolicSparseColMat::new_checked(n + m, n + m, col_ptr, None, row_idx), val);
    let mut rhs = sys.b.clone();
    rhs.extend((0..m).map(|i| 1e-3 * ((i as f64 * 0.7).sin())));
    // the exact KKT (no shift) for residuals
    let mut exact = kkt.clone();
    {
        let starts: Vec<usize> = (n..n + m).map(|j| exact.symbolic().col_range(j).start).collect();
        let v = exact.val_mut();
        for p in starts {
            v[p] = 0.0;
        }
    }

    let mut llt = SparseLlt::from_symbolic(&sim.llt_symbolic());
    let t = time(|| {
        llt.factor(&sys.a).expect("f");
        let mut y = sys.b.clone();
        llt.solve_in_place(&mut y).expect("s");
    });
    println!("untracked LLT:          {t:7.2} ms  nnz(L) {}", llt.nnz_l());
    {
        let mut l = SparseLdlt::analyze(&sys.a, Ordering::Custom(sim.fill_reducing_perm().to_vec())).expect("a");
        let reg = Regularization::default();
        let t = time(|| {
            l.factor(&sys.a, &reg).expect("f");
        });
        println!("LDLT of A (same perm):  {t:7.2} ms  nnz(L) {}", l.nnz_l());
    }
    let run = |name: &str, ord: Ordering| {
        let ta = Instant::now();
        let mut l = SparseLdlt::analyze(&kkt, ord).expect("analyze");
        let t_an = ta.elapsed().as_secs_f64() * 1e3;
        let mut reg = Regularization::kkt(n, m);
        reg.eps = 1e-13 * max_diag;
        reg.delta = delta_rel * max_diag;
        let mut x = vec![0.0; n + m];
        let t = time(|| {
            l.factor(&kkt, &reg).expect("f");
            x.copy_from_slice(&rhs);
            l.solve_in_place(&mut x).expect("s");
        });
        let mut y = vec![0.0; n + m];
        geom_core::linalg::sym_mul_vec(&exact, &x, &mut y);
        let rc = (n..n + m).map(|i| (y[i] - rhs[i]).abs()).fold(0.0f64, f64::max);
        let ra = (0..n).map(|i| (y[i] - rhs[i]).abs()).fold(0.0f64, f64::max);
        let bn = rhs.iter().fold(0.0f64, |a, x| a.max(x.abs()));
        let res1 = l.solve_refined(&exact, &rhs, &mut y, 1).expect("r");
        let dx = (0..n).map(|i| (y[i] - x[i]).abs()).fold(0.0f64, f64::max)
            / y[..n].iter().fold(0.0f64, |a, x| a.max(x.abs()));
        println!("{name:24}{t:7.2} ms  nnz(L) {}  (analysis {t_an:.1} ms) unrefined: max|r_c| {rc:.2e} max|r_a| {ra:.2e} (|b| {bn:.1e}); refined res {res1:.1e}, rel dx {dx:.1e}", l.nnz_l());
    };
    run("KKT scalar AMD", Ordering::Amd);
    // AMD on vertices (DOFs 3v..3v+3) and regions (multipliers n + 3r..n + 3r + 3).
    let blocks = (0..n as u32).map(|j| j / 3).chain((0..m as u32).map(|r| nv as u32 + r / 3)).collect();
    run("KKT AMD on vertex/region blocks", Ordering::AmdBlocks(blocks));
    let mut cl = sim.fill_reducing_perm().to_vec();
    cl.extend(n..n + m);
    run("KKT constraint last", Ordering::Custom(cl));
}

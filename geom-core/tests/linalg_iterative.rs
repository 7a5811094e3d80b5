//! Preconditioned conjugate gradients: Jacobi, IC(0) and MIC(0) on a 3-D Poisson problem,
//! stopping rule, warm start, edge cases and thread-count determinism.

mod linalg_common;

use geom_core::linalg::{pcg, CgOptions, Csr, Ic0, Identity, Jacobi, Preconditioner, Triplets};
use geom_core::Error;
use linalg_common::{laplacian_2d, poisson_3d, test_vector, with_threads};

fn true_rel_residual(a: &Csr, x: &[f64], b: &[f64]) -> f64 {
    let mut r = vec![0.0; b.len()];
    a.mul_vec(x, &mut r);
    let num: f64 = r.iter().zip(b).map(|(ri, bi)| (bi - ri).powi(2)).sum::<f64>().sqrt();
    num / b.iter().map(|v| v * v).sum::<f64>().sqrt()
}

fn run(a: &Csr, b: &[f64], m: &dyn Preconditioner, tol: f64) -> (Vec<f64>, geom_core::linalg::CgReport) {
    let mut x = vec![0.0; b.len()];
    let rep = pcg(a, b, &mut x, m, &CgOptions { tol, max_iters: 2000, history: true }).expect("valid input");
    (x, rep)
}

#[test]
fn preconditioners_converge_on_3d_poisson_and_ic0_beats_jacobi() {
    // 20³ = 8000 unknowns, 7-point Dirichlet Poisson: κ ≈ 180, CG needs O(√κ·log(1/tol)).
    let a = poisson_3d(20);
    let b = test_vector(a.nrows, 1);
    let tol = 1e-8;
    let jac = Jacobi::new(&a).expect("positive diagonal");
    let ic = Ic0::new(&a, None).expect("IC(0)");
    let mic = Ic0::new(&a, Some(0.97)).expect("MIC(0)");
    let mut iters = Vec::new();
    for (name, m) in [("none", &Identity as &dyn Preconditioner), ("jacobi", &jac), ("ic0", &ic), ("mic0", &mic)] {
        let (x, rep) = run(&a, &b, m, tol);
        assert!(rep.converged && !rep.breakdown, "{name}: {rep:?}");
        assert!(rep.rel_residual <= tol, "{name}: reported residual {:e}", rep.rel_residual);
        // The reported residual is the true one.
        assert!((true_rel_residual(&a, &x, &b) - rep.rel_residual).abs() <= 1e-12);
        assert_eq!(rep.history.len(), rep.iters + 1);
        assert_eq!(rep.history[0], 1.0, "zero warm start: initial relative residual 1");
        iters.push((name, rep.iters));
    }
    let it = |n: &str| iters.iter().find(|(k, _)| *k == n).map(|p| p.1).expect("ran");
    assert!(it("ic0") < it("jacobi"), "{iters:?}");
    assert!(it("mic0") < it("jacobi"), "{iters:?}");
    // No pivot of this M-matrix needs the σ safety rule.
    assert_eq!(ic.replaced_pivots(), 0);
}

#[test]
fn ic0_is_exact_when_there_is_no_fill() {
    // A tridiagonal matrix has no fill, so IC(0) = the exact Cholesky and PCG takes one step.
    let n = 50;
    let mut t = Triplets::new(n, n);
    for i in 0..n {
        t.push(i as u32, i as u32, 2.5);
        if i > 0 {
            t.push(i as u32, (i - 1) as u32, -1.0);
            t.push((i - 1) as u32, i as u32, -1.0);
        }
    }
    let a = Csr::from_triplets(&t);
    let b = test_vector(n, 2);
    let (_, rep) = run(&a, &b, &Ic0::new(&a, None).expect("IC(0)"), 1e-12);
    assert!(rep.converged);
    assert_eq!(rep.iters, 1);
}

#[test]
fn mic0_preserves_row_sums() {
    // With ω = 1 the dropped fill goes to the diagonal: (L Lᵀ) 1 = A 1. Check through the
    // preconditioner: M⁻¹ (A 1) = 1 up to rounding (1e-12 for this well-scaled grid).
    let a = laplacian_2d(9, 7, 0.5, false);
    let n = a.nrows;
    let ones = vec![1.0; n];
    let mut a1 = vec![0.0; n];
    a.mul_vec(&ones, &mut a1);
    let mut z = vec![0.0; n];
    Ic0::new(&a, Some(1.0)).expect("MIC(0)").apply(&a1, &mut z);
    for zi in z {
        assert!((zi - 1.0).abs() <= 1e-12, "{zi}");
    }
    // Plain IC(0) does not preserve them (the 5-point stencil creates dropped fill).
    let mut z0 = vec![0.0; n];
    Ic0::new(&a, None).expect("IC(0)").apply(&a1, &mut z0);
    assert!(z0.iter().any(|zi| (zi - 1.0).abs() > 1e-6));
}

#[test]
fn warm_start_and_zero_rhs() {
    let a = poisson_3d(8);
    let n = a.nrows;
    let b = test_vector(n, 3);
    let jac = Jacobi::new(&a).expect("Jacobi");
    let (x, cold) = run(&a, &b, &jac, 1e-10);
    // Starting from the solution: converged without iterating.
    let mut xw = x.clone();
    let rep = pcg(&a, &b, &mut xw, &jac, &CgOptions { tol: 1e-10, max_iters: 100, history: false }).expect("ok");
    assert!(rep.converged);
    assert_eq!(rep.iters, 0);
    assert!(cold.iters > 10);
    // b = 0: x = 0 immediately, whatever the warm start.
    let mut x0 = vec![3.0; n];
    let rep = pcg(&a, &vec![0.0; n], &mut x0, &jac, &CgOptions::default()).expect("ok");
    assert!(rep.converged && rep.iters == 0 && rep.rel_residual == 0.0);
    assert!(x0.iter().all(|&v| v == 0.0));
}

#[test]
fn iteration_cap_is_reported_not_an_error() {
    let a = poisson_3d(12);
    let b = test_vector(a.nrows, 4);
    let mut x = vec![0.0; a.nrows];
    let rep = pcg(&a, &b, &mut x, &Identity, &CgOptions { tol: 1e-12, max_iters: 5, history: false }).expect("ok");
    assert!(!rep.converged && !rep.breakdown);
    assert_eq!(rep.iters, 5);
    assert!(rep.rel_residual > 1e-12 && rep.rel_residual < 1.0);
    assert!(x.iter().all(|v| v.is_finite()));
}

#[test]
fn invalid_input_is_an_error_and_indefinite_breaks_down() {
    let a = poisson_3d(5);
    let n = a.nrows;
    let b = test_vector(n, 5);
    let o = CgOptions::default();
    let mut x = vec![0.0; n];
    let mut bad_b = b.clone();
    bad_b[3] = f64::NAN;
    assert!(matches!(pcg(&a, &bad_b, &mut x, &Identity, &o), Err(Error::NonFinite(_))));
    let mut bad_x = vec![0.0; n];
    bad_x[0] = f64::INFINITY;
    assert!(matches!(pcg(&a, &b, &mut bad_x, &Identity, &o), Err(Error::NonFinite(_))));
    let mut bad_a = a.clone();
    bad_a.val[10] = f64::NAN;
    assert!(matches!(pcg(&bad_a, &b, &mut x, &Identity, &o), Err(Error::NonFinite(_))));
    assert!(matches!(Jacobi::new(&bad_a), Err(Error::NonFinite(_))));
    assert!(matches!(pcg(&a, &b[..n - 1], &mut x, &Identity, &o), Err(Error::DimensionMismatch { .. })));
    let zero_tol = CgOptions { tol: 0.0, ..CgOptions::default() };
    assert!(matches!(pcg(&a, &b, &mut x, &Identity, &zero_tol), Err(Error::InvalidParameter(_))));
    assert!(matches!(Ic0::new(&a, Some(1.5)), Err(Error::InvalidParameter(_))));
    // −A is negative definite: the first pᵀAp < 0 stops CG with a breakdown, x stays finite.
    let neg = a.add(&a, -1.0, 0.0);
    let mut xn = vec![0.0; n];
    let rep = pcg(&neg, &b, &mut xn, &Identity, &o).expect("valid input");
    assert!(rep.breakdown && !rep.converged);
    assert!(xn.iter().all(|v| v.is_finite()));
    // A non-positive diagonal is rejected by the preconditioners, naming the row.
    assert!(matches!(Jacobi::new(&neg), Err(Error::NotPositiveDefinite { column: 0 })));
    assert!(matches!(Ic0::new(&neg, None), Err(Error::NotPositiveDefinite { column: 0 })));
}

#[test]
fn pcg_is_bitwise_deterministic_across_thread_counts() {
    let a = poisson_3d(22);
    let b = test_vector(a.nrows, 6);
    let solve = |t: usize| {
        with_threads(t, || {
            let m = Jacobi::new(&a).expect("Jacobi");
            let (x, rep) = run(&a, &b, &m, 1e-9);
            (x.iter().map(|v| v.to_bits()).collect::<Vec<_>>(), rep.iters)
        })
    };
    assert_eq!(solve(1), solve(2));
}

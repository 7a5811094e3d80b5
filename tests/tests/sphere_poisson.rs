//! Cross-module integration: procedural icosphere → cotangent Laplacian and consistent mass →
//! sparse Cholesky → a Laplace–Beltrami eigenfunction, checked against the analytic answer, with
//! its convergence order under refinement; then the mesh goes through OBJ and back unchanged.
//!
//! On the unit sphere the coordinate function z is an eigenfunction of −Δ with eigenvalue 2
//! (degree-1 spherical harmonic), so the solution of (−Δ + 1) u = 3 z is u = z. Discretised with
//! the PSD cotangent stiffness L and the P1 mass M: (L + M) u = 3 M z. The error comes from the
//! polyhedral approximation of the sphere and the P1 discretisation, both O(h²).

use geom_core::io::{obj, MeshOut};
use geom_core::linalg::{rel_residual, Ordering, SparseLlt};
use geom_core::mesh::{cotan_stiffness, mass_p1};
use geom_core::procedural::icosphere;

/// Max-norm error of the discrete solution at icosphere level `level`, and the relative residual
/// of the direct solve.
fn eigen_error(level: u32) -> (f64, f64) {
    let m = icosphere(1.0, level).expect("icosphere of valid parameters");
    let n = m.positions.len();
    let l = cotan_stiffness(&m.faces, &m.positions, None);
    let mass = mass_p1(&m.faces, &m.positions);
    let a = l.add(&mass, 1.0, 1.0);
    let z: Vec<f64> = m.positions.iter().map(|p| p.z).collect();
    let mut b = vec![0.0; n];
    mass.mul_vec(&z, &mut b);
    b.iter_mut().for_each(|v| *v *= 3.0);
    let csc = a.to_csc_lower();
    let mut llt = SparseLlt::analyze(&csc, Ordering::Amd).expect("symbolic analysis");
    llt.factor(&csc).expect("SPD system");
    let mut u = b.clone();
    llt.solve_in_place(&mut u).expect("solve");
    let res = rel_residual(&csc, &u, &b);
    let err = u.iter().zip(&z).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
    (err, res)
}

#[test]
fn laplace_beltrami_eigenfunction_converges_at_second_order() {
    let errs: Vec<(f64, f64)> = (2..=4).map(eigen_error).collect();
    for (err, res) in &errs {
        // Direct solve: residual at round-off level (tolerance of the issue: 1e-10).
        assert!(*res < 1e-10, "relative residual {res:e}");
        assert!(err.is_finite());
    }
    // Each level halves h; second-order convergence divides the error by ~4. Accept ≥ 3 (order
    // ≥ 1.58) to allow for the pre-asymptotic irregularity of the icosphere's triangles.
    for w in errs.windows(2) {
        let ratio = w[0].0 / w[1].0;
        assert!(ratio > 3.0, "error ratio {ratio} between levels (errors {:e} → {:e})", w[0].0, w[1].0);
    }
    assert!(errs[2].0 < 5e-3, "level-4 error {:e}", errs[2].0);
}

#[test]
fn icosphere_survives_obj_round_trip_bit_for_bit() {
    let m = icosphere(0.37, 2).unwrap();
    let path = std::env::temp_dir().join(format!("sphere-roundtrip-{}.obj", std::process::id()));
    obj::write(&path, &MeshOut::tri(&m.positions, &m.faces)).unwrap();
    let back = obj::read_tri(&path).unwrap();
    std::fs::remove_file(&path).unwrap();
    assert_eq!(back.faces, m.faces);
    assert_eq!(back.positions, m.positions, "shortest round-trip text must give identical f64");
}

//! The constrained solve on a system whose sparsity pattern changes between calls (IPC contact
//! couplings grow A's pattern between Newton iterations; `VelocitySolve::accepts_pattern_changes`).

use faer::sparse::{SparseColMat, SymbolicSparseColMat};
use geom_core::linalg::Csc;
use geom_core::math::Vec3;
use geom_core::mesh::subdivide_linear;
use geom_core::procedural::{grid, GridSpec, Plane};
use shells::{Effects, ImplicitSystem, IntegratorSettings, Material, ShellSceneDesc, ShellSim, VelocitySolve};
use std::sync::Arc;
use tracks::{
    build_test_functions, CapturedSystem, GuideAnimation, KktMethod, TestFunctionSpec, TrackOptions,
    TrackingConstraints, TrackingSolver,
};

/// `a` (lower triangle, CSC) with explicit zero entries added at the lower-triangle positions
/// `extra` (row ≥ column, not already stored): the same matrix, a different pattern.
fn with_zeros(a: &Csc, extra: &[(usize, usize)]) -> Csc {
    let s = a.symbolic();
    let n = a.nrows();
    let (mut col_ptr, mut row_idx, mut val) = (vec![0usize], Vec::new(), Vec::new());
    for j in 0..n {
        let mut col: Vec<(usize, f64)> = s.col_range(j).map(|k| (s.row_idx()[k], a.val()[k])).collect();
        for &(i, jj) in extra {
            if jj == j {
                assert!(i >= j && col.iter().all(|e| e.0 != i), "({i}, {j}) must be a new lower entry");
                col.push((i, 0.0));
            }
        }
        col.sort_by_key(|e| e.0);
        row_idx.extend(col.iter().map(|e| e.0));
        val.extend(col.iter().map(|e| e.1));
        col_ptr.push(row_idx.len());
    }
    SparseColMat::new(SymbolicSparseColMat::new_checked(n, n, col_ptr, None, row_idx), val)
}

/// A lower-triangle position (row > column) in column `j` that `a` does not store.
fn missing_below(a: &Csc, j: usize) -> (usize, usize) {
    let s = a.symbolic();
    let stored: Vec<usize> = s.col_range(j).map(|k| s.row_idx()[k]).collect();
    let i = (j + 1..a.nrows()).rev().find(|i| !stored.contains(i)).expect("a free position below the diagonal");
    (i, j)
}

/// Every method that says it accepts pattern changes gives, on the same matrix stored with
/// three different patterns — two of them with the same number of entries, so a cache keyed on
/// the entry count alone would scatter A's values into the wrong KKT positions —, the Δv of the
/// original pattern to 1e-12 relative; Schur (which reuses the mesh pattern's symbolic LLᵀ)
/// says it does not.
#[test]
fn solves_follow_the_pattern() {
    let c = grid(&GridSpec { quads: [3, 2], size: [0.6, 0.4], plane: Plane::XZ, ..GridSpec::default() }).expect("grid");
    let (fine, p) = subdivide_linear(&c, 2);
    let rest = c.positions.clone();
    let guide = GuideAnimation::procedural(
        c.clone(),
        Arc::new(move |t: f64| {
            rest.iter().map(|q| q + Vec3::new(0.0, 0.1 * (3.0 * t + 4.0 * q.x).sin(), 0.0)).collect()
        }),
        10.0,
    )
    .expect("guide");
    let tf = build_test_functions(&TestFunctionSpec::SubdivisionBasis, &guide, &fine, Some(&p)).expect("tf");
    let cons = TrackingConstraints::build(&c, &fine, &tf).expect("constraints");
    let mut sim = ShellSim::new(ShellSceneDesc {
        rest: fine.positions.clone(),
        faces: fine.faces.clone(),
        uv: None,
        initial: None,
        initial_velocity: None,
        material: Material::cotton(),
        effects: Effects { gravity: Some(Vec3::new(0.0, -9.81, 0.0)), ..Effects::default() },
        constraints: vec![],
        integrator: IntegratorSettings::default(),
        t0: 0.0,
    })
    .expect("sheet");
    let cap = CapturedSystem::capture_step(&mut sim, 1.0 / 120.0).expect("capture");
    let base = cap.system();
    let n = base.a.nrows();
    let a1 = with_zeros(base.a, &[missing_below(base.a, 0)]);
    let a2 = with_zeros(base.a, &[missing_below(base.a, n / 2)]);
    assert_eq!(a1.val().len(), a2.val().len(), "same entry count, different patterns");
    assert_ne!(a1.symbolic().row_idx(), a2.symbolic().row_idx());
    let accepting = [
        KktMethod::ConstraintLastLdlt,
        KktMethod::InterleavedLdlt,
        KktMethod::AmdRegularizedLdlt { delta: 1e-8 },
        KktMethod::AugmentedLagrangian { alpha: 1e6 },
    ];
    for m in accepting {
        let opts = TrackOptions { kkt: m, ..TrackOptions::default() };
        let mut s = TrackingSolver::new(
            cons.clone(),
            guide.clone(),
            &opts,
            sim.fill_reducing_perm().to_vec(),
            sim.llt_symbolic(),
        );
        assert!(s.accepts_pattern_changes(), "{m:?}");
        let want = s.solve(&base).expect("solve");
        let scale = want.iter().fold(0.0f64, |a, x| a.max(x.abs()));
        assert!(scale > 0.0);
        for (name, a) in [("a1", &a1), ("a2", &a2), ("a", base.a)] {
            let got = s.solve(&ImplicitSystem { a, ..cap.system() }).expect("solve");
            let d = got.iter().zip(&want).fold(0.0f64, |acc, (x, y)| acc.max((x - y).abs()));
            assert!(d <= 1e-12 * scale, "{m:?} on {name}: Δv differs by {d:e} (scale {scale:e})");
        }
        assert!(s.constraint_violation().is_finite());
    }
    let opts = TrackOptions { kkt: KktMethod::Schur, ..TrackOptions::default() };
    let s = TrackingSolver::new(cons, guide, &opts, sim.fill_reducing_perm().to_vec(), sim.llt_symbolic());
    assert!(!s.accepts_pattern_changes());
}

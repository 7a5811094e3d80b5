//! Spec §7 "Operators and pressure" convergence tests: T-POISSON-CONV (Dirichlet Poisson on graded
//! meshes), T-GHOST-CONV (spherical free surface with the second-order ghost fluid) and
//! T-NO-LOCKING (a divergence-free field is barely changed by the projection in a closed box).
//!
//! All three go through the library's own projection path — `assemble_pressure` (liquid
//! classification, stiffness `K`, ghost terms, right-hand side `D u*`), `PressureSolver::solve` and
//! `apply_pressure` (`u ← u* − G̃ q`) — rather than a system assembled here, so that every operator
//! the simulator uses is what converges. A source term is produced the way the simulator produces
//! one: the intermediate velocity is a gradient field `u* = ∇p_exact` sampled at tet centroids, so
//! `(D u*)_i = Σ_t V_t ∇λ_i·u*_t ≈ ∫ ∇λ_i·∇p = ∫ λ_i (−Δp)` for every node `i` whose hat function
//! vanishes on the boundary of the liquid (Green's formula): the pressure solve is then the
//! Galerkin P1 discretisation of `−Δp = f` with a load perturbed only by the second-order
//! midpoint-rule error of the centroid sampling, and `G q` is the discrete gradient of `p`.
//!
//! Errors are measured against the exact solution; observed orders are
//! `log(e_coarse / e_fine) / log(h_coarse / h_fine)` between consecutive resolutions, and every
//! consecutive pair must meet the bound (not just the end points). The measured numbers quoted in
//! the doc comments are from the dev/test profile on the reference machine (they are deterministic
//! up to the solver's round-off).

use flip_tet::bcc::{tetrahedralize, TetMesh};
use flip_tet::octree::{build_octree, Octree, OctreeSpec, SizeDemand};
use flip_tet::ops::{divergence, local_stiffness};
use flip_tet::pressure::{
    apply_pressure, assemble_pressure, tet_pressures, PressureParams, PressureSolver, PressureSystem,
};
use geom_core::math::{Pt3, Vec3};
use geom_core::NONE;
use std::f64::consts::PI;

/// Symmetric 4-point tetrahedron rule of degree 2 (barycentric `(a, b, b, b)` and permutations,
/// weights `V/4`). Used for the L2 and gradient error integrals: the integrands `(p − p_h)²` and
/// `|∇p − ∇p_h|²` are smooth inside each tet, and the rule's own error is a smooth O(h⁴) term
/// against `‖p − p_h‖² = O(h⁴)` and O(h³) against `‖∇(p − p_h)‖² = O(h²)`, so it shifts the
/// constants slightly but not the observed orders.
const QUAD_A: f64 = 0.585_410_196_624_968_5;
/// See [`QUAD_A`].
const QUAD_B: f64 = 0.138_196_601_125_010_5;

/// The four barycentric points of the degree-2 rule.
fn quad_points() -> [[f64; 4]; 4] {
    std::array::from_fn(|k| std::array::from_fn(|a| if a == k { QUAD_A } else { QUAD_B }))
}

/// Point of tet `t` with barycentric coordinates `l`.
fn tet_point(m: &TetMesh, t: usize, l: &[f64; 4]) -> Pt3 {
    let tv = m.tets[t];
    Pt3::from((0..4).fold(Vec3::zeros(), |acc, a| acc + m.nodes[tv[a] as usize].coords * l[a]))
}

/// Observed orders between consecutive resolutions.
fn observed_orders(err: &[f64], h: &[f64]) -> Vec<f64> {
    (1..err.len()).map(|i| (err[i - 1] / err[i]).ln() / (h[i - 1] / h[i]).ln()).collect()
}

/// Errors in scientific notation for assertion messages.
fn sci(v: &[f64]) -> String {
    v.iter().map(|x| format!("{x:.3e}")).collect::<Vec<_>>().join(", ")
}

/// Assembles, solves and applies the projection; asserts that the solve converged to `max_res`
/// relative residual. Returns the system, the DOF pressures and the projected velocities.
fn project(
    m: &TetMesh,
    phi: &[f64],
    ustar: &[Vec3],
    h_min: f64,
    prm: &PressureParams,
    max_res: f64,
) -> (PressureSystem, Vec<f64>, Vec<Vec3>) {
    let sys = assemble_pressure(m, phi, ustar, h_min, prm);
    let (q, rep) = PressureSolver::default().solve(&sys, prm, None).expect("SPD pressure system solves");
    assert!(rep.rel_residual <= max_res, "solver {:?}: relative residual {:.2e}", rep.kind, rep.rel_residual);
    let mut u = ustar.to_vec();
    apply_pressure(m, &sys, &q, &mut u);
    (sys, q, u)
}

/// Exact solution of T-POISSON-CONV, `p = sin(πx) sin(πy) sin(πz)`.
fn poisson_p(x: &Pt3) -> f64 {
    (PI * x.x).sin() * (PI * x.y).sin() * (PI * x.z).sin()
}

/// Gradient of [`poisson_p`].
fn poisson_grad(x: &Pt3) -> Vec3 {
    let (sx, sy, sz) = ((PI * x.x).sin(), (PI * x.y).sin(), (PI * x.z).sin());
    let (cx, cy, cz) = ((PI * x.x).cos(), (PI * x.y).cos(), (PI * x.z).cos());
    PI * Vec3::new(cx * sy * sz, sx * cy * sz, sx * sy * cz)
}

/// T-POISSON-CONV (spec §7): Dirichlet Poisson `−Δp = f = 3π² p` with
/// `p = sin(πx) sin(πy) sin(πz)` on graded BCC meshes of the unit cube.
///
/// Meshes: root grid `n³` with `n = 8, 16, 32` and two levels, the finest level (`h = 1/(2n)`)
/// demanded in the ball of radius 0.25 around `(0.35, 0.4, 0.45)` plus the 2:1 balance band, so the
/// mesh has regular, bisected and (obtuse) transition tets; the test checks that transition tets
/// with positive stiffness couplings are present. The family is refined uniformly (every cube
/// halves), so `h = 1/n` measures it. The spec does not fix the resolutions; the third (116 066
/// nodes, 0.65 M tets, PCG-MIC(0) at `tol = 1e−10`) is the largest that keeps the test near 3 s in
/// the test profile.
///
/// Dirichlet data: `φ = −dist(x, ∂Ω)`, which is 0 on boundary nodes, so they are air (`φ = 0`
/// counts as air, spec §3.4) and their ghost values are `s_g · (…) = 0` (`λ = 1`), i.e. exactly
/// the homogeneous Dirichlet condition that `p` satisfies; the test asserts every ghost value is
/// 0, no boundary node is a DOF, and nothing is pinned. Source: `u* = ∇p` at centroids (module
/// docs); the test checks that the assembled right-hand side is `ops::divergence(u*)` on the DOFs.
///
/// Measured: L2 error 4.11e−3, 1.03e−3, 2.59e−4 (orders 1.99, 2.00); gradient L2 error 2.29e−1,
/// 1.17e−1, 5.90e−2 (orders 0.97, 0.99). Bounds: the spec's, L2 order ≥ 1.8 and gradient order
/// ≥ 0.9 for both consecutive pairs (P1 Galerkin theory gives 2 and 1 on shape-regular meshes). A
/// coarser family (`n = 4, 8, 16`) is still pre-asymptotic (L2 1.88, gradient 0.87 on the first
/// pair), which is why it starts at `n = 8`.
#[test]
fn t_poisson_conv_graded() {
    let (mut e_l2, mut e_grad, mut hs) = (Vec::new(), Vec::new(), Vec::new());
    for n in [8u32, 16, 32] {
        let spec = OctreeSpec::new(Pt3::origin(), Pt3::new(1.0, 1.0, 1.0), n, 2 * n).expect("valid resolution");
        let demand = [SizeDemand { center: Pt3::new(0.35, 0.4, 0.45), pad: 0.25, level: spec.levels - 1 }];
        let oct = build_octree(spec, &demand);
        let m = tetrahedralize(&oct).expect("balanced octree tetrahedralises");
        // The mesh really is graded: transition tets with a positive (obtuse) coupling exist.
        let obtuse = (0..m.tets.len())
            .filter(|&t| m.is_transition(t, &oct.spec))
            .filter(|&t| {
                let k = local_stiffness(&m, t);
                (0..4).any(|i| (0..4).any(|j| i != j && k[i][j] > 1e-12 * k[i][i]))
            })
            .count();
        assert!(obtuse > 0, "n = {n}: no obtuse transition tet, the mesh is not graded");

        let phi: Vec<f64> =
            m.nodes.iter().map(|x| -(x.x.min(1.0 - x.x).min(x.y).min(1.0 - x.y).min(x.z).min(1.0 - x.z))).collect();
        let ustar: Vec<Vec3> = m.centroid.iter().map(poisson_grad).collect();
        let prm = PressureParams { tol: 1e-10, ..Default::default() };
        let (sys, q, u) = project(&m, &phi, &ustar, oct.spec.h_min(), &prm, 1e-9);

        assert!(sys.pinned.is_empty(), "Dirichlet problem must not be pinned");
        let div = divergence(&m, &ustar);
        let bmax = sys.rhs.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        for (i, &d) in sys.dof_of_node.iter().enumerate() {
            if m.node_boundary[i] != 0 {
                assert_eq!(d, NONE, "boundary node {i} must be a Dirichlet (air) node");
            } else {
                assert_ne!(d, NONE, "interior node {i} must be a DOF");
                assert!((sys.rhs[d as usize] - div[i]).abs() <= 1e-12 * bmax, "rhs of node {i} is not D u*");
            }
        }
        let mut qn = vec![0.0; m.nodes.len()];
        for (d, &i) in sys.node_of_dof.iter().enumerate() {
            qn[i as usize] = q[d];
        }
        let (mut l2, mut h1) = (0.0, 0.0);
        for t in 0..m.tets.len() {
            // Ghost values at the boundary nodes are exactly the Dirichlet value 0.
            let qh = tet_pressures(&m, &sys, &q, t);
            for (&node, &value) in m.tets[t].iter().zip(&qh) {
                if sys.dof_of_node[node as usize] == NONE {
                    assert!(value == 0.0, "tet {t}: ghost value {value} at a Dirichlet node");
                }
            }
            let grad_h = ustar[t] - u[t];
            for l in quad_points() {
                let x = tet_point(&m, t, &l);
                let ph: f64 = (0..4).map(|a| l[a] * qn[m.tets[t][a] as usize]).sum();
                l2 += 0.25 * m.volume[t] * (ph - poisson_p(&x)).powi(2);
                h1 += 0.25 * m.volume[t] * (grad_h - poisson_grad(&x)).norm_squared();
            }
        }
        e_l2.push(l2.sqrt());
        e_grad.push(h1.sqrt());
        hs.push(1.0 / f64::from(n));
    }
    let (o_l2, o_grad) = (observed_orders(&e_l2, &hs), observed_orders(&e_grad, &hs));
    for (k, (&a, &b)) in o_l2.iter().zip(&o_grad).enumerate() {
        assert!(a >= 1.8, "L2 order {a:.3} (pair {k}); errors {}", sci(&e_l2));
        assert!(b >= 0.9, "gradient order {b:.3} (pair {k}); errors {}", sci(&e_grad));
    }
}

/// T-GHOST-CONV (spec §7): spherical free surface. `Δp = 6` inside the sphere of radius
/// `R = 0.28` around the off-centre point `c = (0.5123, 0.4783, 0.5071)`, `p = 0` on it:
/// `p = |x − c|² − R²`. Uniform BCC with `h = 1/16, 1/32, 1/64` (the spec's N = 16, 32, 64) on the
/// box `[0.1875, 0.8125]³` (10, 20, 40 cubes per axis) rather than the unit cube, to keep the finest
/// mesh at 0.14 M nodes: the liquid touches no wall (every wall node is air, `φ ≥ 0.01`) and a
/// liquid row never sees a wall term, so the box size does not enter the discrete problem for the
/// liquid nodes. `u* = ∇p = 2(x − c)` at centroids (exact tet average: ∇p is linear). Solver
/// tolerance 1e−12 (direct for the two coarse meshes, PCG-MIC(0) on 48 220 DOFs).
///
/// Measured nodal errors over the liquid nodes:
/// - second order, default `min_interface_fraction = 0.01` and `surface_snap = 0.01`: RMS
///   2.98e−4, 7.36e−5, 1.82e−5 (orders 2.02, 2.01); max 4.24e−4, 1.11e−4, 3.47e−5 (orders 1.94,
///   1.67). As the spec's remark says, the clamp `λ ≥ 0.01` (and the snap of nodes within 0.01 h)
///   leaves an O(h) error on nodes within 0.01 h of the sphere, which the max norm sees once such
///   a node exists (here at N = 64; the spec measured 0.97 there on its sphere; 1.28 before the
///   session-9 snap), so the max-norm order is not asserted for this variant.
/// - second order, `min_interface_fraction = surface_snap = 1e−6`: RMS 3.00e−4, 7.38e−5, 1.84e−5
///   (orders 2.02, 2.00); max 4.21e−4, 1.10e−4, 2.84e−5 (orders 1.94, 1.95).
/// - first order (`second_order: false`): max 1.46e−2, 7.56e−3, 3.91e−3 (orders 0.95, 0.95); RMS
///   orders 0.97, 1.07.
///
/// Bounds: RMS order ≥ 1.8 for both second-order variants and max order ≥ 1.8 with `λ_min = 1e−6`
/// (spec); first order "≈ 1" is asserted as a max-norm order in [0.8, 1.2] (the `p = 0` placement
/// error is `|∇p|` times a node-to-interface distance that is ≤ h but varies with how the sphere
/// cuts the lattice, hence the band), and the first-order max error at N = 64 must be at least 10×
/// the second-order one (measured 88×), so the two variants are really different schemes. Uniform
/// BCC tets are regular, so no tet may fall back (`n_k_reduced = 0`, spec T-K-RULE).
#[test]
fn t_ghost_conv_sphere() {
    let c = Pt3::new(0.5123, 0.4783, 0.5071);
    let r = 0.28;
    let exact = |x: &Pt3| (x - c).norm_squared() - r * r;
    // (second_order, min_interface_fraction)
    let variants = [(true, 0.01), (true, 1e-6), (false, 0.01)];
    let mut rms = vec![Vec::new(); variants.len()];
    let mut max = vec![Vec::new(); variants.len()];
    let mut hs = Vec::new();
    for n in [16u32, 32, 64] {
        let cells = n * 10 / 16;
        let lo = Pt3::new(0.1875, 0.1875, 0.1875);
        let hi = Pt3::new(0.8125, 0.8125, 0.8125);
        let spec = OctreeSpec::new(lo, hi, cells, cells).expect("valid resolution");
        let h = spec.h_min();
        assert!((h - 1.0 / f64::from(n)).abs() <= 1e-15);
        let m = tetrahedralize(&Octree::uniform(spec, 0)).expect("uniform octree tetrahedralises");
        let phi: Vec<f64> = m.nodes.iter().map(|x| (x - c).norm() - r).collect();
        for (i, &b) in m.node_boundary.iter().enumerate() {
            assert!(b == 0 || phi[i] >= 0.01, "wall node {i} is liquid or too close to the sphere");
        }
        let ustar: Vec<Vec3> = m.centroid.iter().map(|x| 2.0 * (x - c)).collect();
        for (v, &(second_order, lambda_min)) in variants.iter().enumerate() {
            // The surface snap follows the clamp (`surface_snap = λ_min`, as the defaults pair
            // them): a 0.01 h snap with λ_min = 1e−6 would put back the O(0.01 h) placement error
            // the small clamp removes (max-norm order 1.67 measured).
            let prm = PressureParams {
                second_order,
                min_interface_fraction: lambda_min,
                surface_snap: lambda_min,
                tol: 1e-12,
                ..Default::default()
            };
            let (sys, q, _) = project(&m, &phi, &ustar, h, &prm, 1e-11);
            assert!(sys.pinned.is_empty() && sys.n_ghost_tets > 0);
            assert_eq!(sys.n_k_reduced, 0, "regular BCC tets must keep k = 1");
            let (mut s2, mut emax) = (0.0f64, 0.0f64);
            for (d, &i) in sys.node_of_dof.iter().enumerate() {
                let e = q[d] - exact(&m.nodes[i as usize]);
                s2 += e * e;
                emax = emax.max(e.abs());
            }
            rms[v].push((s2 / q.len() as f64).sqrt());
            max[v].push(emax);
        }
        hs.push(h);
    }
    for v in 0..2 {
        for (k, &o) in observed_orders(&rms[v], &hs).iter().enumerate() {
            assert!(o >= 1.8, "{:?}: RMS order {o:.3} (pair {k}); errors {}", variants[v], sci(&rms[v]));
        }
    }
    for (k, &o) in observed_orders(&max[1], &hs).iter().enumerate() {
        assert!(o >= 1.8, "λ_min = 1e−6: max-norm order {o:.3} (pair {k}); errors {}", sci(&max[1]));
    }
    for (k, &o) in observed_orders(&max[2], &hs).iter().enumerate() {
        assert!((0.8..=1.2).contains(&o), "first order: max-norm order {o:.3} (pair {k}); errors {}", sci(&max[2]));
    }
    assert!(max[2][2] >= 10.0 * max[0][2], "first {:.3e} vs second order {:.3e} at N = 64", max[2][2], max[0][2]);
}

/// Divergence-free rotational field of T-NO-LOCKING: `u = (−∂ψ/∂y, ∂ψ/∂x, 0)` with
/// `ψ = sin²(πx) sin²(πy)`; its normal component vanishes on every wall of the unit cube.
fn stream_velocity(x: &Pt3) -> Vec3 {
    let (sx, sy) = ((PI * x.x).sin(), (PI * x.y).sin());
    let (s2x, s2y) = ((2.0 * PI * x.x).sin(), (2.0 * PI * x.y).sin());
    Vec3::new(-PI * sx * sx * s2y, PI * s2x * sy * sy, 0.0)
}

/// T-NO-LOCKING (spec §7): closed unit box entirely filled with liquid (`φ = −1` at every node, no
/// free surface, one pinned DOF for the null space), `u*` = the divergence-free rotational field of
/// [`stream_velocity`] at the tet centroids, uniform BCC `N = 8, 16, 32` (the spec fixes only 16³).
/// Measured: the relative change `‖u − u*‖_W / ‖u*‖_W` (volume-weighted L2 over all tets) under the
/// projection.
///
/// Measured: 2.26e−3, 6.14e−4, 1.59e−4 (orders 1.88, 1.95): the change is O(h²), better than the
/// spec's O(h) requirement, and 0.06 % at 16³ against the spec's 10 %. Bounds: the spec's, order
/// ≥ 0.8 for both consecutive pairs and relative change ≤ 0.10 at 16³. A locking discretisation
/// (too few velocity DOFs per pressure constraint) would remove an O(1) part of the field and fail
/// both. Because a projection that did nothing would pass trivially, the test also checks that the
/// result is discretely divergence-free, `‖D u‖₂ ≤ 1e−8 ‖D u*‖₂` (solver tolerance 1e−10; `D u` is
/// the residual `b − A q` on the DOF rows, and the pinned row is minus the sum of the others since
/// the weak divergence of any field sums to 0 over a closed box), and that `D u*` is not already 0.
#[test]
fn t_no_locking_closed_box() {
    let (mut rel, mut hs) = (Vec::new(), Vec::new());
    for n in [8u32, 16, 32] {
        let spec = OctreeSpec::new(Pt3::origin(), Pt3::new(1.0, 1.0, 1.0), n, n).expect("valid resolution");
        let m = tetrahedralize(&Octree::uniform(spec, 0)).expect("uniform octree tetrahedralises");
        let phi = vec![-1.0; m.nodes.len()];
        let ustar: Vec<Vec3> = m.centroid.iter().map(stream_velocity).collect();
        let prm = PressureParams { tol: 1e-10, ..Default::default() };
        let (sys, _, u) = project(&m, &phi, &ustar, spec.h_min(), &prm, 1e-9);
        assert_eq!(sys.pinned.len(), 1, "closed box: exactly one pinned DOF");
        let norm = |v: &[f64]| v.iter().map(|x| x * x).sum::<f64>().sqrt();
        let (div_star, div_new) = (norm(&divergence(&m, &ustar)), norm(&divergence(&m, &u)));
        assert!(div_star > 0.0 && div_new <= 1e-8 * div_star, "N = {n}: |D u| {div_new:.3e} vs |D u*| {div_star:.3e}");
        let (mut change, mut total) = (0.0, 0.0);
        for ((v, a), b) in m.volume.iter().zip(&u).zip(&ustar) {
            change += v * (a - b).norm_squared();
            total += v * b.norm_squared();
        }
        rel.push((change / total).sqrt());
        hs.push(1.0 / f64::from(n));
    }
    assert!(rel[1] <= 0.10, "relative change {:.3e} at 16³", rel[1]);
    for (k, &o) in observed_orders(&rel, &hs).iter().enumerate() {
        assert!(o >= 0.8, "order {o:.3} (pair {k}); relative changes {}", sci(&rel));
    }
}

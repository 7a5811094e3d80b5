//! Spec §7: analytic solutions (7.1), the paper's properties (7.2), the character coupling (7.3),
//! solver paths (7.4), the nonlinear reference (7.5) and the mass–spring claim (7.6).

use barnet::analytic::{self, NetCase};
use barnet::assemble::d_from_branch_node;
use barnet::deformer::{BarNetDeformer, DeformerConfig, Drivers, FrameOutput, LoadSpec};
use barnet::net::{Bar, BarNet};
use barnet::{FdmOptions, FdmSolver, SolverPath};
use geom_core::math::{Iso3, Pt3, Vec3};
use geom_core::rng::Rng;

fn solve_case(c: &NetCase, o: &FdmOptions) -> (FdmSolver, Vec<Pt3>) {
    let s = FdmSolver::new(&c.net, o).unwrap();
    let (loads, fixed) = c.split();
    let x = s.solve(&loads, &fixed).unwrap();
    (s, x)
}

fn max_diff(a: &[Pt3], b: &[Pt3]) -> f64 {
    a.iter().zip(b).map(|(p, q)| (p - q).norm()).fold(0.0, f64::max)
}

fn max_norm(a: &[Vec3]) -> f64 {
    a.iter().map(|v| v.norm()).fold(0.0, f64::max)
}

// ---------------------------------------------------------------------------------------------
// 7.1 analytic

/// 7.1 a: one free node joined to k fixed nodes: x = (p + Σ q_j x_j) / Σ q_j.
#[test]
fn single_free_node_exact() {
    let mut rng = Rng::new(7);
    for k in 1..6 {
        let n = k + 1;
        let bars: Vec<Bar> = (1..n).map(|j| Bar { a: 0, b: j as u32, q: rng.range(0.1, 3.0), group: None }).collect();
        let mut fixed = vec![true; n];
        fixed[0] = false;
        let net = BarNet { n_nodes: n, bars: bars.clone(), fixed };
        let xf: Vec<Pt3> =
            (1..n).map(|_| Pt3::new(rng.range(-1.0, 1.0), rng.range(-1.0, 1.0), rng.range(-1.0, 1.0))).collect();
        let p = Vec3::new(0.3, -0.2, 0.7);
        let s = FdmSolver::new(&net, &FdmOptions::default()).unwrap();
        assert_eq!(s.path(), SolverPath::Dense);
        let x = s.solve(&[p], &xf).unwrap()[0];
        let qs: f64 = bars.iter().map(|b| b.q).sum();
        let num = bars.iter().zip(&xf).fold(p, |acc, (b, xj)| acc + xj.coords * b.q);
        let exact = num / qs;
        let err = (x.coords - exact).norm() / exact.norm();
        assert!(err < 1e-14, "k = {k}: relative error {err}");
    }
}

/// 7.1 b: the loaded cable is exact at the nodes (a discrete parabola).
#[test]
fn loaded_cable_is_a_discrete_parabola() {
    for n in [1usize, 2, 3, 7, 10, 64, 65, 100, 1000] {
        let c = analytic::cable(n, 2.0, 0.5);
        let (_, x) = solve_case(&c, &FdmOptions::default());
        let err = analytic::max_rel_err(&x, c.exact.as_ref().unwrap(), 1);
        let tol = if n <= 100 { 1e-12 } else { 1e-9 };
        assert!(err <= tol, "n = {n}: cable relative error {err:e} > {tol:e}");
    }
}

/// 7.1 c: the membrane converges with O(h²): error ratios in [3.6, 4.4] for N = 8→17→35→71.
#[test]
fn membrane_converges_quadratically() {
    let errs: Vec<f64> = [8usize, 17, 35, 71]
        .iter()
        .map(|&n| {
            let c = analytic::membrane(n, 1.5);
            let (_, x) = solve_case(&c, &FdmOptions::default());
            analytic::max_abs_err(&x, c.exact.as_ref().unwrap(), 2)
        })
        .collect();
    for w in errs.windows(2) {
        let r = w[0] / w[1];
        assert!((3.6..=4.4).contains(&r), "error ratio {r} (errors {errs:?})");
    }
}

/// 7.1 d: manufactured solution on random 3-D nets.
#[test]
fn manufactured_random_nets() {
    let mut rng = Rng::new(11);
    for &(n, extra) in &[(10usize, 5usize), (60, 40), (150, 200)] {
        let c = analytic::random_net(&mut rng, n, extra, 0.2, 0.1, 10.0);
        let s = FdmSolver::new(&c.net, &FdmOptions::default()).unwrap();
        let xs: Vec<Pt3> = s.free_nodes().iter().map(|_| Pt3::new(rng.f64(), rng.f64(), rng.f64())).collect();
        let (_, fixed) = c.split();
        let p = s.rest_loads(&xs, &fixed).unwrap();
        let x = s.solve(&p, &fixed).unwrap();
        let err = max_diff(&x, &xs) / xs.iter().map(|p| p.coords.norm()).fold(0.0, f64::max);
        assert!(err < 1e-10, "n = {n}: manufactured error {err}");
    }
}

// ---------------------------------------------------------------------------------------------
// 7.2 properties

/// 7.2 a: D from direct assembly equals Cᵀ Q C; D symmetric; Cholesky succeeds. 7.2 g: row sums.
#[test]
fn direct_assembly_equals_branch_node_products() {
    let mut rng = Rng::new(3);
    let c = analytic::random_net(&mut rng, 120, 150, 0.25, 0.01, 100.0);
    let s = FdmSolver::new(&c.net, &FdmOptions::default()).unwrap();
    let (d, df) = d_from_branch_node(&c.net);
    let a = s.assembly();
    let scale = a.d.max_abs();
    let diff = a.d.add(&d, 1.0, -1.0).max_abs();
    assert!(diff <= 1e-15 * scale, "D differs by {diff}");
    assert!(a.d_f.add(&df, 1.0, -1.0).max_abs() <= 1e-15 * scale);
    assert!(a.d.is_symmetric(0.0));
    assert_eq!(s.path(), SolverPath::Sparse);
    // 7.2 g: D·1 + D_f·1 = 0.
    let mut r1 = vec![0.0; a.n];
    let mut r2 = vec![0.0; a.n];
    a.d.mul_vec(&vec![1.0; a.n], &mut r1);
    a.d_f.mul_vec(&vec![1.0; a.n_fixed], &mut r2);
    let worst = r1.iter().zip(&r2).map(|(x, y)| (x + y).abs()).fold(0.0, f64::max);
    assert!(worst <= 1e-14 * scale, "row sums {worst}");
}

fn grid_case(seed: u64) -> NetCase {
    // An irregular 12×12 grid net with random diagonals and random q; border fixed.
    let mut rng = Rng::new(seed);
    let mut c = analytic::grid_net(10, 1.0);
    for b in &mut c.net.bars {
        b.q = rng.range(0.5, 2.0);
    }
    let s = 12u32;
    for i in 1..s - 2 {
        for j in 1..s - 2 {
            if rng.chance(0.3) {
                c.net.bars.push(Bar { a: i * s + j, b: (i + 1) * s + j + 1, q: rng.range(0.5, 2.0), group: None });
            }
        }
    }
    for v in 0..c.net.n_nodes {
        c.positions[v].z = rng.range(-0.05, 0.05);
        c.loads[v] = Vec3::new(rng.range(-1.0, 1.0), rng.range(-1.0, 1.0), rng.range(-1.0, 1.0)) * 0.01;
    }
    c
}

/// 7.2 b, c, d, f: independence, superposition, stiffness scaling, joint scaling.
#[test]
fn paper_properties_hold_exactly() {
    let c = grid_case(5);
    let s = FdmSolver::new(&c.net, &FdmOptions::default()).unwrap();
    let (p, fixed) = c.split();
    let zero = vec![Vec3::zeros(); p.len()];
    let x0 = s.solve(&zero, &fixed).unwrap();
    let x = s.solve(&p, &fixed).unwrap();
    // b: an x-only load change leaves y and z bitwise unchanged.
    let px: Vec<Vec3> = p.iter().map(|v| v + Vec3::new(0.3, 0.0, 0.0)).collect();
    let xx = s.solve(&px, &fixed).unwrap();
    for (a, b) in xx.iter().zip(&x) {
        assert_eq!(a.y, b.y);
        assert_eq!(a.z, b.z);
    }
    // c: superposition.
    let p2: Vec<Vec3> =
        p.iter().enumerate().map(|(i, _)| Vec3::new((i as f64).sin(), 0.5, -(i as f64).cos()) * 0.01).collect();
    let p12: Vec<Vec3> = p.iter().zip(&p2).map(|(a, b)| a + b).collect();
    let x2 = s.solve(&p2, &fixed).unwrap();
    let x12 = s.solve(&p12, &fixed).unwrap();
    let d = |a: &[Pt3]| -> Vec<Vec3> { a.iter().zip(&x0).map(|(u, v)| u - v).collect() };
    let (d1, d2, d12) = (d(&x), d(&x2), d(&x12));
    let sup: Vec<Vec3> = d12.iter().zip(d1.iter().zip(&d2)).map(|(a, (b, c))| a - b - c).collect();
    assert!(max_norm(&sup) <= 1e-12 * max_norm(&d12), "superposition {}", max_norm(&sup) / max_norm(&d12));
    // d: q → αq scales load-induced displacements by 1/α.
    let alpha = 3.7;
    let mut net2 = c.net.clone();
    net2.scale_q(alpha).unwrap();
    let s2 = FdmSolver::new(&net2, &FdmOptions::default()).unwrap();
    let xa = s2.solve(&p, &fixed).unwrap();
    let xa0 = s2.solve(&zero, &fixed).unwrap();
    let err: f64 = xa.iter().zip(&xa0).zip(&d1).map(|((a, b), dd)| ((a - b) * alpha - dd).norm()).fold(0.0, f64::max);
    assert!(err <= 1e-12 * max_norm(&d1), "stiffness scaling {}", err / max_norm(&d1));
    // f: scaling q and loads together leaves the shape unchanged.
    let pa: Vec<Vec3> = p.iter().map(|v| v * alpha).collect();
    let xs = s2.solve(&pa, &fixed).unwrap();
    let scale = x.iter().map(|v| v.coords.norm()).fold(0.0, f64::max);
    assert!(max_diff(&xs, &x) <= 1e-13 * scale, "joint scaling {}", max_diff(&xs, &x) / scale);
}

/// 7.2 e: changing one bar's q moves ≥ 99 % of the free nodes of its component.
#[test]
fn stiffness_change_has_a_global_effect() {
    let c = grid_case(9);
    let s = FdmSolver::new(&c.net, &FdmOptions::default()).unwrap();
    let (p, fixed) = c.split();
    let x = s.solve(&p, &fixed).unwrap();
    let x0 = s.solve(&vec![Vec3::zeros(); p.len()], &fixed).unwrap();
    let disp = max_diff(&x, &x0);
    // A bar between two interior free nodes near the centre.
    let j = c.net.bars.iter().position(|b| b.a == 5 * 12 + 5 && b.b == 5 * 12 + 6).unwrap();
    let mut q = c.net.q();
    q[j] *= 1.5;
    let mut s2 = FdmSolver::new(&c.net, &FdmOptions::default()).unwrap();
    s2.update_q(&q).unwrap();
    let x2 = s2.solve(&p, &fixed).unwrap();
    let moved = x.iter().zip(&x2).filter(|(a, b)| (*a - *b).norm() > 1e-12 * disp).count();
    assert!(moved as f64 >= 0.99 * x.len() as f64, "{moved} of {} free nodes moved", x.len());
}

// ---------------------------------------------------------------------------------------------
// 7.3 coupling

fn arm_config(loads: Vec<LoadSpec>, q: f64) -> DeformerConfig {
    DeformerConfig { loads, q, ..barnet::presets::biceps_arm() }
}

fn biceps_load() -> LoadSpec {
    barnet::presets::biceps_bulge()
}

/// 7.3 a, b: rest pose reproduced; rigid motion ⇒ rigid, with and without channels.
#[test]
fn rest_pose_and_rigid_motion() {
    let mut d = BarNetDeformer::new(&arm_config(vec![biceps_load()], 1.0)).unwrap();
    let drivers = Drivers { joint_angles: vec![0.0; 3], time: 0.0 };
    let mut out = FrameOutput::default();
    let rest_pose = d.arm_pose(0.0, &Iso3::identity()).unwrap();
    d.deform_with(&rest_pose, &drivers, Some(&[0.0]), &mut out).unwrap();
    let rest = d.control_rest().positions.clone();
    let e = max_diff(&out.control, &rest);
    assert!(e < 1e-12, "rest reproduction {e}");
    assert!(out.residual <= 1e-12);
    let g = Iso3::new(Vec3::new(0.2, -0.4, 1.0), Vec3::new(0.3, 1.1, -0.6));
    let rigid = d.arm_pose(0.0, &g).unwrap();
    d.deform_with(&rigid, &drivers, Some(&[0.0]), &mut out).unwrap();
    let moved: Vec<Pt3> = rest.iter().map(|p| g * p).collect();
    assert!(max_diff(&out.control, &moved) < 1e-12);
    // With a channel, the loaded shape moves rigidly too.
    d.deform_with(&rest_pose, &drivers, Some(&[0.8]), &mut out).unwrap();
    let loaded = out.control.clone();
    assert!(max_diff(&loaded, &rest) > 1e-3, "the channel should bulge the biceps");
    d.deform_with(&rigid, &drivers, Some(&[0.8]), &mut out).unwrap();
    let moved: Vec<Pt3> = loaded.iter().map(|p| g * p).collect();
    assert!(max_diff(&out.control, &moved) < 1e-12);
}

/// 7.2 d on the arm: lower q, larger bulge.
#[test]
fn lower_q_gives_a_larger_bulge() {
    let bulge = |q: f64| {
        let mut d = BarNetDeformer::new(&arm_config(vec![biceps_load()], q)).unwrap();
        let pose = d.arm_pose(2.0, &Iso3::identity()).unwrap();
        let mut out = FrameOutput::default();
        d.deform(&pose, &Drivers { joint_angles: vec![0.0, 2.0, 0.0], time: 0.0 }, &mut out).unwrap();
        assert!(out.residual <= 1e-12);
        max_diff(&out.control, &out.lbs)
    };
    let (b2, b1, b05) = (bulge(2.0), bulge(1.0), bulge(0.5));
    assert!(b2 < b1 && b1 < b05, "bulges {b2} {b1} {b05}");
    assert!((b1 / b2 - 2.0).abs() < 1e-9 && (b05 / b1 - 2.0).abs() < 1e-9, "1/q scaling: {} {}", b1 / b2, b05 / b1);
}

// ---------------------------------------------------------------------------------------------
// 7.4 solver paths

/// 7.4 a: dense and sparse paths agree; 7.4 b: update_q equals a fresh factorisation.
#[test]
fn dense_sparse_agree_and_update_q_is_fresh() {
    let mut rng = Rng::new(21);
    for &n in &[1usize, 2, 5, 30, 90, 200] {
        let c = analytic::random_net(&mut rng, n + n / 4 + 1, n, 0.2, 0.1, 10.0);
        let dense = FdmOptions { dense_threshold: usize::MAX, ..Default::default() };
        let sparse = FdmOptions { dense_threshold: 0, ..Default::default() };
        let (sd, xd) = solve_case(&c, &dense);
        let (ss, xs) = solve_case(&c, &sparse);
        if sd.free_nodes().is_empty() {
            continue;
        }
        assert_eq!(sd.path(), SolverPath::Dense);
        assert_eq!(ss.path(), SolverPath::Sparse);
        let scale = xd.iter().map(|p| p.coords.norm()).fold(0.0, f64::max);
        assert!(max_diff(&xd, &xs) <= 1e-12 * scale, "n = {n}: dense vs sparse {}", max_diff(&xd, &xs) / scale);
        // 7.4 b
        let q: Vec<f64> = c.net.q().iter().map(|q| q * rng.range(0.5, 2.0)).collect();
        let mut upd = FdmSolver::new(&c.net, &sparse).unwrap();
        upd.update_q(&q).unwrap();
        let mut net2 = c.net.clone();
        for (b, &qq) in net2.bars.iter_mut().zip(&q) {
            b.q = qq;
        }
        let fresh = FdmSolver::new(&net2, &sparse).unwrap();
        let (p, f) = c.split();
        let (xu, xf) = (upd.solve(&p, &f).unwrap(), fresh.solve(&p, &f).unwrap());
        let scale = xf.iter().map(|p| p.coords.norm()).fold(0.0, f64::max);
        assert!(max_diff(&xu, &xf) <= 1e-14 * scale, "n = {n}: update_q vs fresh {}", max_diff(&xu, &xf) / scale);
    }
}

/// 7.4 c: iterative refinement on a q-ratio-1e8 net brings the componentwise backward error to
/// rounding level.
#[test]
fn refinement_on_ill_conditioned_net() {
    let mut rng = Rng::new(33);
    let mut c = analytic::grid_net(20, 1.0);
    for b in &mut c.net.bars {
        b.q = if rng.chance(0.5) { 1e4 } else { 1e-4 };
    }
    for v in 0..c.net.n_nodes {
        c.loads[v] = Vec3::new(rng.range(-1.0, 1.0), rng.range(-1.0, 1.0), rng.range(-1.0, 1.0));
    }
    let o = FdmOptions { refine_steps: 3, ..Default::default() };
    let s = FdmSolver::new(&c.net, &o).unwrap();
    let (p, f) = c.split();
    let x = s.solve(&p, &f).unwrap();
    let be = s.backward_error(&x, &p, &f).unwrap();
    assert!(be < 1e-15, "componentwise backward error {be:e}");
}

mod properties {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(24))]
        /// On any random anchored net: the shape-holding loads of any positions reproduce those
        /// positions (manufactured solution), and superposition holds.
        #[test]
        fn random_nets_reproduce_and_superpose(seed in any::<u64>(), n in 2usize..40, extra in 0usize..60) {
            let mut rng = geom_core::rng::Rng::new(seed);
            let c = analytic::random_net(&mut rng, n, extra, 0.3, 0.05, 20.0);
            let s = FdmSolver::new(&c.net, &FdmOptions::default()).unwrap();
            let (p, fixed) = c.split();
            let xs: Vec<Pt3> = s.free_nodes().iter().map(|&v| c.positions[v as usize]).collect();
            let p0 = s.rest_loads(&xs, &fixed).unwrap();
            let x = s.solve(&p0, &fixed).unwrap();
            prop_assert!(max_diff(&x, &xs) <= 1e-10);
            let zero = vec![Vec3::zeros(); p.len()];
            let x0 = s.solve(&zero, &fixed).unwrap();
            let x1 = s.solve(&p, &fixed).unwrap();
            let p2: Vec<Vec3> = p.iter().map(|v| v + v).collect();
            let x2 = s.solve(&p2, &fixed).unwrap();
            let err = x2.iter().zip(&x1).zip(&x0).map(|((a, b), o)| ((a - o) - (b - o) * 2.0).norm()).fold(0.0, f64::max);
            let scale = x1.iter().zip(&x0).map(|(a, o)| (a - o).norm()).fold(0.0, f64::max);
            prop_assert!(err <= 1e-12 * scale.max(1e-300));
        }
    }
}

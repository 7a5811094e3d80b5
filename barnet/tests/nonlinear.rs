//! Spec §7.5 (nonlinear reference) and §7.6 (the paper's claim about mass–spring nets).

use barnet::analytic;
use barnet::arm::{Arm, ArmSpec};
use barnet::net::BarNet;
use barnet::nonlinear::{form_find_nonlinear, Elastic, NewtonOptions, NonlinearModel};
use barnet::{FdmOptions, FdmSolver};
use geom_core::math::{Pt3, Vec3};

/// The 12-free-node arm net with its rest positions split by kind.
fn arm_net() -> (BarNet, Vec<Pt3>, Vec<Pt3>, Vec<f64>) {
    let arm = Arm::new(&ArmSpec::default()).unwrap();
    let free_list = arm.named("biceps_triceps_12").unwrap();
    let mut free = vec![false; arm.mesh.positions.len()];
    for v in free_list {
        free[v as usize] = true;
    }
    let net = BarNet::from_mesh_edges(&arm.mesh, &free, 1.0).unwrap();
    let (fr, fx, _) = net.index_maps();
    let xf: Vec<Pt3> = fr.iter().map(|&v| arm.mesh.positions[v as usize]).collect();
    let xs: Vec<Pt3> = fx.iter().map(|&v| arm.mesh.positions[v as usize]).collect();
    let len =
        net.bars.iter().map(|b| (arm.mesh.positions[b.a as usize] - arm.mesh.positions[b.b as usize]).norm()).collect();
    (net, xf, xs, len)
}

/// 7.5 a: Schek's nonlinear FDM reaches q_j l_j = s_j and equilibrium.
#[test]
fn prescribed_forces_fixed_point() {
    let mut c = analytic::grid_net(5, 1.0);
    for v in 0..c.net.n_nodes {
        if !c.net.fixed[v] {
            c.loads[v] = Vec3::new(0.0, 0.0, 0.01);
        }
    }
    let (loads, fixed) = c.split();
    let (fr, _, _) = c.net.index_maps();
    let x0: Vec<Pt3> = fr.iter().map(|&v| c.positions[v as usize]).collect();
    let s = vec![1.0; c.net.bars.len()];
    let r = form_find_nonlinear(
        &c.net,
        &NonlinearModel::PrescribedForces { s: s.clone() },
        &loads,
        &fixed,
        &x0,
        &NewtonOptions::default(),
    )
    .unwrap();
    assert!(r.converged, "history {:?}", r.history);
    // q_j l_j = s_j at the converged shape, and the linear FDM with those q is in equilibrium.
    let (_, _, index) = c.net.index_maps();
    let pos = |v: u32| {
        if c.net.fixed[v as usize] {
            fixed[index[v as usize] as usize]
        } else {
            r.x[index[v as usize] as usize]
        }
    };
    let mut net = c.net.clone();
    for b in &mut net.bars {
        let l = (pos(b.a) - pos(b.b)).norm();
        b.q = 1.0 / l;
    }
    for b in &net.bars {
        let l = (pos(b.a) - pos(b.b)).norm();
        assert!((b.q * l - 1.0).abs() < 1e-10);
    }
    let solver = FdmSolver::new(&net, &FdmOptions::default()).unwrap();
    let res = solver.residual(&r.x, &loads, &fixed).unwrap();
    assert!(res < 1e-10, "equilibrium residual {res}");
    // 7.5 d: linear convergence with a roughly constant contraction ratio < 1.
    let h = &r.history;
    let ratios: Vec<f64> = h.windows(2).skip(2).take(5).map(|w| w[1] / w[0]).collect();
    assert!(ratios.iter().all(|&q| q < 1.0), "contraction ratios {ratios:?}");
}

/// 7.5 b: gradient and Hessian against central differences; quadratic Newton tail.
#[test]
fn elastic_bars_derivatives_and_newton() {
    let (net, xf, xs, len) = arm_net();
    let k = vec![1.0; net.bars.len()];
    let l0: Vec<f64> = len.iter().map(|l| 0.9 * l).collect();
    let loads: Vec<Vec3> = (0..xf.len()).map(|i| Vec3::new((i as f64).sin(), (i as f64).cos(), 0.5) * 0.003).collect();
    let el = Elastic::new(&net, &k, &l0, &loads, &xs, &xf);
    let x: Vec<Pt3> =
        xf.iter().enumerate().map(|(i, p)| p + Vec3::new(0.001 * (i as f64).cos(), 0.002, -0.001)).collect();
    let g = el.gradient(&x);
    let (h, _) = el.hessian(&x);
    let eps = 1e-6;
    for i in 0..x.len() {
        for c in 0..3 {
            let (mut xp, mut xm) = (x.clone(), x.clone());
            xp[i][c] += eps;
            xm[i][c] -= eps;
            let fd = (el.energy(&xp) - el.energy(&xm)) / (2.0 * eps);
            assert!((fd - g[i][c]).abs() <= 1e-6 * g[i][c].abs().max(1e-3), "grad ({i},{c}): {fd} vs {}", g[i][c]);
            let (gp, gm) = (el.gradient(&xp), el.gradient(&xm));
            for j in 0..x.len() {
                for d in 0..3 {
                    let fd = (gp[j][d] - gm[j][d]) / (2.0 * eps);
                    let an = h.get(3 * j + d, 3 * i + c);
                    assert!((fd - an).abs() <= 1e-6 * an.abs().max(1e-2), "H[{j},{d};{i},{c}]: {fd} vs {an}");
                }
            }
        }
    }
    // Newton: converged, few iterations, quadratic tail.
    let model = NonlinearModel::ElasticBars { k: k.clone(), rest_len: l0.clone() };
    let r = form_find_nonlinear(&net, &model, &loads, &xs, &xf, &NewtonOptions::default()).unwrap();
    assert!(r.converged && r.iterations <= 15, "iterations {} history {:?}", r.iterations, r.history);
    let h = &r.history;
    let n = h.len();
    assert!(n >= 3);
    for w in h[n.saturating_sub(4)..].windows(2) {
        if w[0] > 1e-9 {
            assert!(w[1] / (w[0] * w[0]) < 1e4, "not quadratic: {h:?}");
        }
    }
}

/// 7.5 c: zero load and L0 = rest lengths ⇒ the rest state in 0 iterations.
#[test]
fn elastic_rest_state_is_returned_unchanged() {
    let (net, xf, xs, len) = arm_net();
    let model = NonlinearModel::ElasticBars { k: vec![2.0; net.bars.len()], rest_len: len };
    let loads = vec![Vec3::zeros(); xf.len()];
    let r = form_find_nonlinear(&net, &model, &loads, &xs, &xf, &NewtonOptions::default()).unwrap();
    assert!(r.converged);
    assert_eq!(r.iterations, 0);
    assert_eq!(r.x, xf);
}

/// 7.6: on the arm net, an elastic-bar ("mass–spring") model breaks superposition and x/y/z
/// independence by more than 1 % for displacements of about 10 % of the edge length, while the
/// FDM keeps them to 1e-12.
#[test]
fn mass_spring_violates_the_paper_properties() {
    let (net, xf, xs, len) = arm_net();
    let k = vec![1.0; net.bars.len()];
    let l0: Vec<f64> = len.iter().map(|l| 0.9 * l).collect();
    // Shape-holding loads of the prestressed rest state: P0 = internal forces at rest.
    let no_load = vec![Vec3::zeros(); xf.len()];
    let el0 = Elastic::new(&net, &k, &l0, &no_load, &xs, &xf);
    let p0: Vec<Vec3> = el0.gradient(&xf);
    let edge = len.iter().sum::<f64>() / len.len() as f64;
    let model = NonlinearModel::ElasticBars { k: k.clone(), rest_len: l0.clone() };
    let solve_el = |extra: &[Vec3]| -> Vec<Pt3> {
        let p: Vec<Vec3> = p0.iter().zip(extra).map(|(a, b)| a + b).collect();
        let r = form_find_nonlinear(&net, &model, &p, &xs, &xf, &NewtonOptions::default()).unwrap();
        assert!(r.converged);
        r.x
    };
    // FDM with q = k (1 − L0/l) = 0.1: the same rest equilibrium.
    let mut fnet = net.clone();
    for b in &mut fnet.bars {
        b.q = 0.1;
    }
    let fdm = FdmSolver::new(&fnet, &FdmOptions::default()).unwrap();
    let solve_fdm = |extra: &[Vec3]| -> Vec<Pt3> {
        let p: Vec<Vec3> = p0.iter().zip(extra).map(|(a, b)| a + b).collect();
        fdm.solve(&p, &xs).unwrap()
    };
    let n = xf.len();
    // Load patterns: p1 pushes the first node along +y, p2 pulls the last one along x.
    let mag = 0.1 * edge * 0.1 * 6.0;
    let mut p1 = vec![Vec3::zeros(); n];
    p1[0] = Vec3::new(0.0, mag, 0.0);
    let mut p2 = vec![Vec3::zeros(); n];
    p2[0] = Vec3::new(mag, 0.0, 0.0);
    let p12: Vec<Vec3> = p1.iter().zip(&p2).map(|(a, b)| a + b).collect();
    let zero = vec![Vec3::zeros(); n];
    let check = |solve: &dyn Fn(&[Vec3]) -> Vec<Pt3>| -> (f64, f64, f64) {
        let x0 = solve(&zero);
        let (x1, x2, x12) = (solve(&p1), solve(&p2), solve(&p12));
        let d = |a: &[Pt3]| -> Vec<Vec3> { a.iter().zip(&x0).map(|(u, v)| u - v).collect() };
        let (d1, d2, d12) = (d(&x1), d(&x2), d(&x12));
        let mx = |v: &[Vec3]| v.iter().map(|u| u.norm()).fold(0.0, f64::max);
        let sup: Vec<Vec3> = d12.iter().zip(d1.iter().zip(&d2)).map(|(a, (b, c))| a - b - c).collect();
        // Independence: p2 has only an x component; its y and z response relative to its size.
        let cross = d2.iter().map(|u| u.y.abs().max(u.z.abs())).fold(0.0, f64::max);
        (mx(&sup) / mx(&d12), cross / mx(&d2), mx(&d12) / edge)
    };
    let (sup_el, ind_el, disp_el) = check(&solve_el);
    let (sup_fdm, ind_fdm, _) = check(&solve_fdm);
    eprintln!("7.6: displacement/edge {disp_el:.3}, superposition {sup_el:.3e}, independence {ind_el:.3e}");
    assert!(disp_el > 0.03 && disp_el < 0.5, "displacement / edge = {disp_el}");
    assert!(sup_el > 0.01, "elastic superposition error only {sup_el}");
    assert!(ind_el > 0.01, "elastic independence error only {ind_el}");
    assert!(sup_fdm < 1e-12, "FDM superposition {sup_fdm}");
    assert_eq!(ind_fdm, 0.0, "FDM x/y/z independence");
}

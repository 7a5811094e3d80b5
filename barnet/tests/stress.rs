//! Spec §8: hard cases that must stay numerically stable, each with its expected behaviour.

use barnet::analytic;
use barnet::deformer::{
    BarNetDeformer, DeformerConfig, DirLocal, DriverSpec, Drivers, FineSpec, FrameOutput, LoadSpec, NodeSet,
};
use barnet::net::{Bar, BarNet};
use barnet::nonlinear::{form_find_nonlinear, NewtonOptions, NonlinearModel};
use barnet::subdiv::Scheme;
use barnet::{BarNetError, FdmOptions, FdmSolver, SolverPath};
use geom_core::math::{Iso3, Pt3, Vec3};
use geom_core::rng::Rng;

fn chain(qs: &[f64]) -> BarNet {
    let n = qs.len() + 1;
    let bars = qs.iter().enumerate().map(|(i, &q)| Bar { a: i as u32, b: i as u32 + 1, q, group: None }).collect();
    let mut fixed = vec![false; n];
    fixed[0] = true;
    fixed[n - 1] = true;
    BarNet { n_nodes: n, bars, fixed }
}

fn ends() -> Vec<Pt3> {
    vec![Pt3::new(0.0, 0.0, 0.0), Pt3::new(3.0, 0.0, 0.0)]
}

#[test]
fn free_component_without_fixed_node() {
    let mut net = chain(&[1.0, 1.0, 1.0]);
    net.n_nodes += 3;
    net.fixed.extend([false, false, false]);
    net.bars.push(Bar { a: 4, b: 5, q: 1.0, group: None });
    net.bars.push(Bar { a: 5, b: 6, q: 2.0, group: None });
    match FdmSolver::new(&net, &FdmOptions::default()) {
        Err(BarNetError::Unanchored { nodes }) => assert_eq!(nodes, vec![4, 5, 6]),
        other => panic!("expected Unanchored, got {other:?}"),
    }
}

#[test]
fn zero_q_bars_are_ignored() {
    // A zero-q bar parallel to a live one changes nothing.
    let mut net = chain(&[1.0, 2.0, 1.0]);
    let s = FdmSolver::new(&net, &FdmOptions::default()).unwrap();
    let p = vec![Vec3::new(0.0, 1.0, 0.0); 2];
    let x = s.solve(&p, &ends()).unwrap();
    net.bars.push(Bar { a: 1, b: 2, q: 0.0, group: None });
    let s2 = FdmSolver::new(&net, &FdmOptions::default()).unwrap();
    assert_eq!(s2.report().zero_q_bars, 1);
    assert_eq!(s2.solve(&p, &ends()).unwrap(), x);
}

#[test]
fn compression_bars_indefinite_and_singular() {
    // D = [[1+q, −q], [−q, 1+q]] has eigenvalues 1 and 1 + 2q.
    let net = chain(&[1.0, -0.8, 1.0]);
    let s = FdmSolver::new(&net, &FdmOptions::default()).unwrap();
    assert!(s.is_indefinite());
    assert_eq!(s.path(), SolverPath::Ldlt);
    let p = vec![Vec3::new(0.1, 1.0, 0.0), Vec3::new(0.0, -0.5, 0.2)];
    let x = s.solve(&p, &ends()).unwrap();
    assert!(s.residual(&x, &p, &ends()).unwrap() < 1e-14);
    assert!(matches!(FdmSolver::new(&chain(&[1.0, -0.5, 1.0]), &FdmOptions::default()), Err(BarNetError::Singular(_))));
    // Larger nets take the sparse path first.
    let mut c = analytic::grid_net(10, 1.0);
    c.net.bars[40].q = -0.2;
    let s = FdmSolver::new(&c.net, &FdmOptions::default()).unwrap();
    let (l, f) = c.split();
    let x = s.solve(&l, &f).unwrap();
    assert!(s.residual(&x, &l, &f).unwrap() < 1e-12);
}

#[test]
fn huge_stiffness_ratios() {
    let mut rng = Rng::new(4);
    let mut c = analytic::grid_net(15, 1.0);
    for b in &mut c.net.bars {
        b.q = 10f64.powf(rng.range(-8.0, 8.0));
    }
    for v in 0..c.net.n_nodes {
        c.loads[v] = Vec3::new(rng.range(-1.0, 1.0), rng.range(-1.0, 1.0), rng.range(-1.0, 1.0));
    }
    let s = FdmSolver::new(&c.net, &FdmOptions::default()).unwrap();
    let (l, f) = c.split();
    let x = s.solve(&l, &f).unwrap();
    assert!(x.iter().all(|p| p.coords.iter().all(|v| v.is_finite())));
    let be = s.backward_error(&x, &l, &f).unwrap();
    assert!(be < 1e-14, "componentwise backward error {be:e}");
}

#[test]
fn duplicate_bars_merge_by_summing_q() {
    let mut net = chain(&[1.0, 0.5, 1.0]);
    net.bars.push(Bar { a: 1, b: 2, q: 1.5, group: None });
    let s = FdmSolver::new(&net, &FdmOptions::default()).unwrap();
    assert_eq!(s.report().duplicates, vec![(1, 3)]);
    let merged = FdmSolver::new(&chain(&[1.0, 2.0, 1.0]), &FdmOptions::default()).unwrap();
    let p = vec![Vec3::new(0.0, 1.0, 0.0), Vec3::new(0.0, 0.0, 1.0)];
    let (a, b) = (s.solve(&p, &ends()).unwrap(), merged.solve(&p, &ends()).unwrap());
    assert!(a.iter().zip(&b).all(|(x, y)| (x - y).norm() < 1e-15));
}

#[test]
fn self_loop_is_an_error() {
    let mut net = chain(&[1.0, 1.0]);
    net.bars.push(Bar { a: 1, b: 1, q: 1.0, group: None });
    assert!(matches!(FdmSolver::new(&net, &FdmOptions::default()), Err(BarNetError::SelfLoop { bar: 2, node: 1 })));
}

#[test]
fn coincident_nodes_and_zero_length_bars() {
    // Linear FDM: lengths unused, fixed ends at the same point.
    let net = chain(&[1.0, 1.0, 1.0]);
    let s = FdmSolver::new(&net, &FdmOptions::default()).unwrap();
    let same = vec![Pt3::origin(); 2];
    let x = s.solve(&[Vec3::zeros(), Vec3::zeros()], &same).unwrap();
    assert_eq!(x, vec![Pt3::origin(); 2]);
    // Nonlinear: the 1/l guard is used and reported, and the result stays finite.
    let x0 = vec![Pt3::origin(), Pt3::new(2.0, 0.0, 0.0)];
    let model = NonlinearModel::ElasticBars { k: vec![1.0; 3], rest_len: vec![0.5; 3] };
    let r = form_find_nonlinear(&net, &model, &[Vec3::zeros(), Vec3::zeros()], &ends(), &x0, &NewtonOptions::default())
        .unwrap();
    assert!(r.guarded_bars >= 1);
    assert!(r.x.iter().all(|p| p.coords.iter().all(|v| v.is_finite())));
}

#[test]
fn no_free_nodes_is_a_no_op() {
    let net = BarNet { n_nodes: 2, bars: vec![Bar { a: 0, b: 1, q: 1.0, group: None }], fixed: vec![true, true] };
    let s = FdmSolver::new(&net, &FdmOptions::default()).unwrap();
    assert_eq!(s.path(), SolverPath::Empty);
    assert!(s.solve(&[], &ends()).unwrap().is_empty());
}

#[test]
fn huge_loads_respond_linearly() {
    let c = analytic::membrane(6, 1.0);
    let s = FdmSolver::new(&c.net, &FdmOptions::default()).unwrap();
    let (l, f) = c.split();
    let big: Vec<Vec3> = l.iter().map(|v| v * 1e12).collect();
    let (x, xb) = (s.solve(&l, &f).unwrap(), s.solve(&big, &f).unwrap());
    let x0 = s.solve(&vec![Vec3::zeros(); l.len()], &f).unwrap();
    let err = x.iter().zip(&xb).zip(&x0).map(|((a, b), o)| ((b - o) - (a - o) * 1e12).norm()).fold(0.0, f64::max);
    let scale = xb.iter().map(|p| p.coords.norm()).fold(0.0, f64::max);
    assert!(err <= 1e-12 * scale, "{err} vs {scale}");
}

#[test]
fn non_finite_inputs_are_typed_errors() {
    let net = chain(&[1.0, 1.0, 1.0]);
    let s = FdmSolver::new(&net, &FdmOptions::default()).unwrap();
    let bad = vec![Vec3::new(f64::NAN, 0.0, 0.0), Vec3::zeros()];
    assert!(matches!(s.solve(&bad, &ends()), Err(BarNetError::NonFinite { .. })));
    let badp = vec![Pt3::new(0.0, f64::INFINITY, 0.0), Pt3::origin()];
    assert!(matches!(s.solve(&[Vec3::zeros(); 2], &badp), Err(BarNetError::NonFinite { .. })));
    let mut s = s;
    assert!(matches!(s.update_q(&[1.0, f64::NAN, 1.0]), Err(BarNetError::NonFinite { .. })));
    assert!(matches!(s.update_q(&[1.0, 1.0]), Err(BarNetError::DimensionMismatch { .. })));
    let mut net2 = chain(&[1.0, 1.0]);
    net2.bars[0].q = f64::NAN;
    assert!(matches!(FdmSolver::new(&net2, &FdmOptions::default()), Err(BarNetError::NonFinite { .. })));
}

#[test]
fn folded_control_mesh_stays_solvable() {
    let cfg = DeformerConfig {
        arm: Default::default(),
        ramp_half_width: 0.04,
        free: NodeSet::Named("elbow_24".into()),
        q: 1.0,
        groups: vec![],
        loads: vec![LoadSpec {
            name: "elbow".into(),
            nodes: NodeSet::Named("elbow_ring".into()),
            dir_local: DirLocal::Radial,
            driver: DriverSpec::JointAngle { joint: "elbow".into() },
            curve: vec![(0.0, 0.0), (3.0, 1.0)],
            scale: 0.02,
        }],
        stiffness: vec![],
        fine: FineSpec::Wrap { levels: 1, k_tris: 1 },
        max_disp: Some(0.05),
    };
    let mut d = BarNetDeformer::new(&cfg).unwrap();
    let mut out = FrameOutput::default();
    for deg in [150.0f64, 170.0, 179.0] {
        let a = deg.to_radians();
        let pose = d.arm_pose(a, &Iso3::identity()).unwrap();
        d.deform(&pose, &Drivers { joint_angles: vec![0.0, a, 0.0], time: 0.0 }, &mut out).unwrap();
        assert!(out.residual <= 1e-12, "{deg}°: residual {}", out.residual);
        assert!(out.fine.iter().all(|p| p.iter().all(|v| v.is_finite())));
        for (c, l) in out.control.iter().zip(&out.lbs) {
            assert!((c - l).norm() <= 0.05 + 1e-12);
        }
    }
    // Bad configuration names are errors, not panics.
    let mut bad = cfg.clone();
    bad.free = NodeSet::Named("nope".into());
    assert!(BarNetDeformer::new(&bad).is_err());
    let mut bad = cfg;
    bad.loads[0].nodes = NodeSet::List(vec![0]);
    assert!(matches!(BarNetDeformer::new(&bad), Err(BarNetError::InvalidParameter(_))));
    let _ = Scheme::Loop;
}

#[test]
fn nonlinear_divergence_returns_best_iterate() {
    let c = analytic::membrane(4, 1.0);
    let (l, f) = c.split();
    let (fr, _, _) = c.net.index_maps();
    let x0: Vec<Pt3> = fr.iter().map(|&v| c.positions[v as usize]).collect();
    let big: Vec<Vec3> = l.iter().map(|v| v * 1e3).collect();
    let model = NonlinearModel::ElasticBars { k: vec![1.0; c.net.bars.len()], rest_len: vec![0.1; c.net.bars.len()] };
    let o = NewtonOptions { max_iter: 2, ..Default::default() };
    let r = form_find_nonlinear(&c.net, &model, &big, &f, &x0, &o).unwrap();
    assert!(!r.converged);
    assert_eq!(r.iterations, 2);
    assert!(r.x.iter().all(|p| p.coords.iter().all(|v| v.is_finite())));
}

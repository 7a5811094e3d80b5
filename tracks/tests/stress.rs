//! Hard cases of spec §8: each must end in a typed error or a finite, reported result.

use geom_core::linalg::{Csr, Triplets};
use geom_core::math::{Pt3, Vec3};
use geom_core::mesh::{subdivide_linear, TriMesh};
use geom_core::procedural::{grid, GridSpec, Plane};
use shells::{Damping, Effects, IntegratorSettings, Material, ShellSceneDesc, ShellSim, VertexConstraint};
use std::sync::Arc;
use tracks::{
    build_test_functions, cluster, ClusterOptions, GuideAnimation, KktMethod, RegionSel, TestFunctionSpec,
    TestFunctions, TestKind, TimeInterp, TrackError, TrackOptions, Tracker, TrackingConstraints,
};

fn sheet(q: [u32; 2]) -> TriMesh {
    grid(&GridSpec { quads: q, size: [0.6, 0.4], plane: Plane::XZ, ..GridSpec::default() }).expect("grid")
}

fn sim_of(m: &TriMesh, pins: Vec<u32>) -> ShellSim {
    let mut mat = Material::cotton();
    mat.damping = Damping::Rayleigh { alpha: 0.0, beta: 1e-4 };
    ShellSim::new(ShellSceneDesc {
        rest: m.positions.clone(),
        faces: m.faces.clone(),
        uv: None,
        initial: None,
        initial_velocity: None,
        material: mat,
        effects: Effects { gravity: Some(Vec3::new(0.0, -9.81, 0.0)), ..Effects::default() },
        constraints: if pins.is_empty() { vec![] } else { vec![VertexConstraint::Pinned(pins)] },
        integrator: IntegratorSettings::default(),
        t0: 0.0,
    })
    .expect("sim")
}

fn moving(c: &TriMesh, f: impl Fn(f64, &Pt3) -> Pt3 + Send + Sync + 'static, dur: f64) -> GuideAnimation {
    let rest = c.positions.clone();
    GuideAnimation::procedural(c.clone(), Arc::new(move |t| rest.iter().map(|p| f(t, p)).collect()), dur)
        .expect("guide")
}

fn hats(g: &GuideAnimation, fine: &TriMesh, p: &Csr) -> TestFunctions {
    build_test_functions(&TestFunctionSpec::SubdivisionBasis, g, fine, Some(p)).expect("tf")
}

/// Guide frames with a different vertex count or NaN are rejected at load.
#[test]
fn bad_guide_frames() {
    let c = sheet([2, 2]);
    let bad = vec![c.positions.clone(), c.positions[..4].to_vec()];
    assert!(matches!(
        GuideAnimation::from_frames(c.clone(), bad, 30.0, TimeInterp::CatmullRom),
        Err(TrackError::TopologyMismatch { .. })
    ));
    let mut nan = c.positions.clone();
    nan[3].y = f64::INFINITY;
    assert!(matches!(
        GuideAnimation::from_frames(c, vec![nan], 30.0, TimeInterp::CatmullRom),
        Err(TrackError::NonFinite(_))
    ));
}

/// Guide time past the last frame: the last frame is held and the step flags it.
#[test]
fn guide_past_end_is_held_and_flagged() {
    let c = sheet([2, 2]);
    let frames = vec![c.positions.clone(), c.positions.iter().map(|p| p + Vec3::new(0.0, 0.01, 0.0)).collect()];
    let g = GuideAnimation::from_frames(c.clone(), frames, 30.0, TimeInterp::CatmullRom).expect("guide");
    let (fine, p) = subdivide_linear(&c, 1);
    let mut tr = Tracker::new(sim_of(&fine, vec![]), g.clone(), hats(&g, &fine, &p), Some(p), TrackOptions::default())
        .expect("tracker");
    let mut held = false;
    for _ in 0..4 {
        let s = tr.step(1.0 / 60.0).expect("step");
        held |= s.guide_held;
        assert!(s.residual_pre_collision <= 1e-10);
    }
    assert!(held);
}

/// A zero test function (empty row) is `ZeroIntegral(i)`.
#[test]
fn zero_integral() {
    let c = sheet([2, 2]);
    let mut t = Triplets::new(2, c.n_vertices());
    t.push(0, 0, 1.0);
    let s = Csr::from_triplets(&t);
    let tf = TestFunctions { s_bar: s.clone(), s, kind: TestKind::Weak };
    assert!(matches!(TrackingConstraints::build(&c, &c, &tf), Err(TrackError::ZeroIntegral(1))));
    // A region selecting nothing is caught when the test functions are built.
    let g = moving(&c, |_, p| *p, 1.0);
    let nothing = RegionSel::RestBox { min: (5.0, 5.0, 5.0), max: (6.0, 6.0, 6.0) };
    let spec = TestFunctionSpec::Painted { guide: vec![nothing.clone()], tracked: vec![nothing] };
    assert!(matches!(build_test_functions(&spec, &g, &c, None), Err(TrackError::ZeroIntegral(0))));
}

/// Linearly dependent rows (A, B and A ∪ B as explicit indicator rows), and more constraints
/// than free DOFs, are `RankDeficient`.
#[test]
fn dependent_and_too_many_constraints() {
    let c = sheet([3, 2]);
    let g = moving(&c, |_, p| *p, 1.0);
    let n = c.n_vertices();
    let left: Vec<u32> = (0..n as u32).filter(|&v| c.positions[v as usize].x < 0.0).collect();
    let right: Vec<u32> = (0..n as u32).filter(|&v| c.positions[v as usize].x >= 0.0).collect();
    let mut t = Triplets::new(3, n);
    left.iter().for_each(|&v| t.push(0, v, 1.0));
    right.iter().for_each(|&v| t.push(1, v, 1.0));
    (0..n as u32).for_each(|v| t.push(2, v, 1.0));
    let s = Csr::from_triplets(&t);
    let tf = TestFunctions { s_bar: s.clone(), s, kind: TestKind::Weak };
    match Tracker::new(sim_of(&c, vec![]), g.clone(), tf, None, TrackOptions::default()) {
        Err(TrackError::RankDeficient(rows)) => assert_eq!(rows, vec![0, 1, 2]),
        other => panic!("expected RankDeficient, got {:?}", other.err()),
    }
    // n + 1 pointwise rows on n vertices (one duplicated anchor).
    let mut pairs: Vec<(u32, u32)> = (0..n as u32).map(|v| (v, v)).collect();
    pairs.push((0, 0));
    let tf = build_test_functions(&TestFunctionSpec::Pointwise { pairs }, &g, &c, None).expect("tf");
    assert!(matches!(
        Tracker::new(sim_of(&c, vec![]), g, tf, None, TrackOptions::default()),
        Err(TrackError::RankDeficient(_))
    ));
}

/// Pointwise anchors on pinned vertices with a moving guide: `InfeasibleConstraint`.
#[test]
fn pointwise_on_pinned() {
    let c = sheet([2, 2]);
    let g = moving(&c, |t, p| p + Vec3::new(0.0, 0.1 * t, 0.0), 1.0);
    let tf =
        build_test_functions(&TestFunctionSpec::Pointwise { pairs: vec![(0, 0), (4, 4)] }, &g, &c, None).expect("tf");
    assert!(matches!(
        Tracker::new(sim_of(&c, vec![0]), g, tf, None, TrackOptions::default()),
        Err(TrackError::InfeasibleConstraint(0))
    ));
}

/// More clusters than vertices can carry: empty vertex regions are merged and K reported; a
/// disconnected guide gets at least one region per component.
#[test]
fn clusters_degenerate() {
    let c = sheet([3, 2]);
    let g = moving(&c, |t, p| p + Vec3::new(0.0, 0.05 * (t + p.x).sin(), 0.0), 1.0);
    let all = c.n_faces();
    let res =
        cluster(&g, &ClusterOptions { regions: all, frames: 4, ..ClusterOptions::default() }, None).expect("cluster");
    assert!(res.regions <= c.n_vertices() && res.regions > 0);
    assert!(res.vertex_labels.iter().all(|&l| (l as usize) < res.regions));
    // Two disjoint sheets, one region requested: one per component.
    let mut p = c.positions.clone();
    p.extend(c.positions.iter().map(|x| x + Vec3::new(5.0, 0.0, 0.0)));
    let nv = c.n_vertices() as u32;
    let mut f = c.faces.clone();
    f.extend(c.faces.iter().map(|t| t.map(|v| v + nv)));
    let two = TriMesh::new(p, f).expect("two sheets");
    let g2 = GuideAnimation::from_frames(two.clone(), vec![two.positions.clone()], 30.0, TimeInterp::CatmullRom)
        .expect("guide");
    let res = cluster(&g2, &ClusterOptions { regions: 1, frames: 1, ..ClusterOptions::default() }, None).expect("c");
    assert_eq!(res.regions, 2);
    assert!(matches!(
        cluster(&g2, &ClusterOptions { regions: 0, ..ClusterOptions::default() }, None),
        Err(TrackError::BadParameter(_))
    ));
}

/// A teleporting guide (1 m jump at 0.1 s): the solve stays finite, the constraint force reports
/// the jump; correction_fraction 0.5 halves the first response.
#[test]
fn guide_teleport() {
    let c = sheet([2, 2]);
    let (fine, p) = subdivide_linear(&c, 1);
    let g = moving(&c, |t, x| if t > 0.1 { x + Vec3::new(1.0, 0.0, 0.0) } else { *x }, 1.0);
    let mut forces = Vec::new();
    for frac in [1.0, 0.5] {
        let opts = TrackOptions { correction_fraction: frac, ..TrackOptions::default() };
        let mut tr = Tracker::new(sim_of(&fine, vec![]), g.clone(), hats(&g, &fine, &p), Some(p.clone()), opts)
            .expect("tracker");
        let mut fmax = 0.0f64;
        for _ in 0..12 {
            let s = tr.step(1.0 / 60.0).expect("finite step");
            fmax = fmax.max(s.max_constraint_force);
            assert!(tr.sim.state().q.iter().all(|q| q.iter().all(|x| x.is_finite())));
        }
        forces.push(fmax);
    }
    assert!(forces[0] > 1.0, "the jump shows as a large constraint force: {forces:?}");
    assert!(forces[1] < forces[0], "{forces:?}");
}

/// A non-isometrically stretching guide (×1.5 in x over 1 s): tracked follows exactly, no blow-up.
#[test]
fn guide_stretching() {
    let c = sheet([2, 2]);
    let (fine, p) = subdivide_linear(&c, 2);
    let g = moving(&c, |t, x| Pt3::new(x.x * (1.0 + 0.5 * t.min(1.0)), x.y, x.z), 2.0);
    let mut tr = Tracker::new(sim_of(&fine, vec![]), g.clone(), hats(&g, &fine, &p), Some(p), TrackOptions::default())
        .expect("tracker");
    for _ in 0..60 {
        let s = tr.step(1.0 / 60.0).expect("step");
        assert!(s.residual_pre_collision <= 1e-10 * g.scale());
    }
}

/// Penalty with a huge stiffness: either a typed factorisation error or a finite result, never NaN.
#[test]
fn penalty_huge() {
    let c = sheet([2, 2]);
    let (fine, p) = subdivide_linear(&c, 1);
    let g = moving(&c, |t, x| x + Vec3::new(0.0, 0.1 * t, 0.0), 1.0);
    let opts = TrackOptions { kkt: KktMethod::Penalty { stiffness: 1e18 }, ..TrackOptions::default() };
    let mut tr = Tracker::new(sim_of(&fine, vec![]), g.clone(), hats(&g, &fine, &p), Some(p), opts).expect("tracker");
    for _ in 0..5 {
        match tr.step(1.0 / 60.0) {
            Ok(_) => assert!(tr.sim.state().q.iter().all(|q| q.iter().all(|x| x.is_finite()))),
            Err(TrackError::Shell(_)) => return,
            Err(e) => panic!("unexpected error {e}"),
        }
    }
}

/// One large step per frame keeps the residual at solver precision (1e-9·L).
#[test]
fn large_time_step() {
    let c = sheet([2, 2]);
    let (fine, p) = subdivide_linear(&c, 2);
    let g = moving(&c, |t, x| x + Vec3::new(0.0, 0.3 * (4.0 * t + 3.0 * x.x).sin(), 0.0), 3.0);
    let mut tr = Tracker::new(sim_of(&fine, vec![]), g.clone(), hats(&g, &fine, &p), Some(p), TrackOptions::default())
        .expect("tracker");
    for _ in 0..20 {
        let s = tr.step(1.0 / 24.0).expect("step");
        assert!(s.residual_pre_collision <= 1e-9 * g.scale());
    }
}

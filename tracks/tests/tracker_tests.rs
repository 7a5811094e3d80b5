//! Tracked-step tests of spec §7 (7, 8, 11, 12, 15, 17, 19) on small sheets.

use geom_core::linalg::Csr;
use geom_core::math::{Pt3, Vec3};
use geom_core::mesh::{subdivide_linear, TriMesh};
use geom_core::procedural::{grid, GridSpec, Plane};
use shells::{Damping, Effects, IntegratorSettings, Material, ShellSceneDesc, ShellSim, VertexConstraint};
use std::sync::Arc;
use tracks::{
    build_test_functions, GuideAnimation, KktMethod, RegionSel, TestFunctionSpec, TrackError, TrackOptions, Tracker,
};

fn coarse() -> TriMesh {
    grid(&GridSpec { quads: [3, 2], size: [0.6, 0.4], plane: Plane::XZ, ..GridSpec::default() }).expect("grid")
}

fn sim_of(m: &TriMesh, gravity: bool, alpha: f64, pins: Vec<u32>, v0: Vec3) -> ShellSim {
    let effects = Effects { gravity: gravity.then(|| Vec3::new(0.0, -9.81, 0.0)), ..Effects::default() };
    sim_with(m, effects, alpha, pins, v0)
}

/// Cotton with Rayleigh damping (α, β = 1e-4) on mesh `m` with the given effects.
fn sim_with(m: &TriMesh, effects: Effects, alpha: f64, pins: Vec<u32>, v0: Vec3) -> ShellSim {
    let mut mat = Material::cotton();
    mat.damping = Damping::Rayleigh { alpha, beta: 1e-4 };
    ShellSim::new(ShellSceneDesc {
        rest: m.positions.clone(),
        faces: m.faces.clone(),
        uv: None,
        initial: None,
        initial_velocity: Some(vec![v0; m.n_vertices()]),
        material: mat,
        effects,
        constraints: if pins.is_empty() { vec![] } else { vec![VertexConstraint::Pinned(pins)] },
        integrator: IntegratorSettings::default(),
        t0: 0.0,
    })
    .expect("valid sim")
}

/// Guide: the coarse grid waving (procedural).
fn waving_guide(c: &TriMesh) -> GuideAnimation {
    let rest = c.positions.clone();
    GuideAnimation::procedural(
        c.clone(),
        Arc::new(move |t: f64| {
            rest.iter().map(|p| p + Vec3::new(0.0, 0.1 * (3.0 * t + 4.0 * p.x).sin(), 0.0)).collect()
        }),
        10.0,
    )
    .expect("guide")
}

fn tracker(method: KktMethod, levels: u32) -> (Tracker, f64) {
    tracker_with(TrackOptions { kkt: method, ..TrackOptions::default() }, levels, gravity_only())
}

fn gravity_only() -> Effects {
    Effects { gravity: Some(Vec3::new(0.0, -9.81, 0.0)), ..Effects::default() }
}

/// The waving coarse grid tracked by its `levels`-times subdivided copy (subdivision hats, at
/// rest, no damping but β = 1e-4) with `effects` and `opts`; returns it and the guide scale L.
fn tracker_with(opts: TrackOptions, levels: u32, effects: Effects) -> (Tracker, f64) {
    let c = coarse();
    let (fine, p) = subdivide_linear(&c, levels);
    let g = waving_guide(&c);
    let tf = build_test_functions(&TestFunctionSpec::SubdivisionBasis, &g, &fine, Some(&p)).expect("tf");
    let sim = sim_with(&fine, effects, 0.0, vec![], Vec3::zeros());
    let l = g.scale();
    (Tracker::new(sim, g, tf, Some(p), opts).expect("tracker"), l)
}

/// The methods that solve the KKT system exactly (to rounding).
const EXACT_METHODS: [KktMethod; 5] = [
    KktMethod::ConstraintLastLdlt,
    KktMethod::InterleavedLdlt,
    KktMethod::AmdRegularizedLdlt { delta: 1e-8 },
    KktMethod::Schur,
    KktMethod::AugmentedLagrangian { alpha: 1e6 },
];

/// §7.8 (collisions off): r_pre = r_post ≤ 1e-10·L at every step for every exact method.
#[test]
fn residual_every_step() {
    for m in EXACT_METHODS {
        let (mut tr, l) = tracker(m, 2);
        assert!(tr.residual_now() <= 1e-12 * l, "initial state consistent");
        for _ in 0..60 {
            let s = tr.step(1.0 / 120.0).expect("step");
            assert!(s.residual_pre_collision <= 1e-10 * l, "{m:?}: r_pre {}", s.residual_pre_collision);
            assert!(s.residual_post_collision <= 1e-10 * l, "{m:?}: r_post {}", s.residual_post_collision);
        }
    }
}

/// §7.7: the exact methods agree on the step (Δv via the resulting state) to 1e-10 relative.
#[test]
fn kkt_methods_agree() {
    let mut states = Vec::new();
    for m in EXACT_METHODS {
        let (mut tr, _) = tracker(m, 2);
        for _ in 0..5 {
            tr.step(1.0 / 60.0).expect("step");
        }
        states.push(tr.sim.state().v.clone());
    }
    let scale = states[0].iter().map(|v| v.norm()).fold(0.0, f64::max);
    for s in &states[1..] {
        let d = s.iter().zip(&states[0]).map(|(a, b)| (a - b).norm()).fold(0.0, f64::max);
        assert!(d <= 1e-10 * scale, "methods differ by {d} (scale {scale})");
    }
}

/// §7.11: no gravity, no damping, guide = rest translating at constant velocity, tracked starts
/// on it with that velocity: the output is the same translation (1e-10·L).
#[test]
fn translation_exact() {
    let c = coarse();
    let (fine, p) = subdivide_linear(&c, 1);
    let vel = Vec3::new(0.3, -0.2, 0.1);
    let rest = c.positions.clone();
    let g = GuideAnimation::procedural(c.clone(), Arc::new(move |t| rest.iter().map(|x| x + t * vel).collect()), 5.0)
        .expect("guide");
    let tf = build_test_functions(&TestFunctionSpec::SubdivisionBasis, &g, &fine, Some(&p)).expect("tf");
    let sim = sim_of(&fine, false, 0.0, vec![], vel);
    let l = g.scale();
    let mut tr = Tracker::new(sim, g, tf, Some(p), TrackOptions::default()).expect("tracker");
    let h = 1.0 / 30.0;
    for _ in 0..30 {
        tr.step(h).expect("step");
    }
    let t = tr.sim.state().t;
    for (q, x) in tr.sim.state().q.iter().zip(&fine.positions) {
        assert!((q - (x + t * vel)).norm() <= 1e-10 * l);
    }
}

/// §7.12: after the projection g₀ = 0 and ġ₀ = 0 (1e-12), and the correction is M-orthogonal to
/// null(C_f): it lies in the range of W C_fᵀ, checked as M·Δq = C_fᵀ y (the residual of the least
/// squares fit of MΔq by C_fᵀ columns is ~0).
#[test]
fn initial_projection() {
    let c = coarse();
    let (fine, p) = subdivide_linear(&c, 1);
    let g = waving_guide(&c);
    let tf = build_test_functions(&TestFunctionSpec::SubdivisionBasis, &g, &fine, Some(&p)).expect("tf");
    // Start away from the guide: the tracked rest shifted and at rest.
    let sim = sim_of(&fine, true, 0.0, vec![], Vec3::new(0.5, 0.0, 0.0));
    let l = g.scale();
    let mut tr = Tracker::new(sim, g.clone(), tf, Some(p), TrackOptions::default()).expect("tracker");
    assert!(tr.residual_now() <= 1e-12 * l.max(1.0));
    let cons = tr.constraints().expect("K > 0").clone();
    let v: Vec<Pt3> = tr.sim.state().v.iter().map(|v| Pt3::from(*v)).collect();
    let mut vb = vec![Vec3::zeros(); g.n_vertices()];
    g.sample_velocity(0.0, &mut vb);
    let vbp: Vec<Pt3> = vb.iter().map(|v| Pt3::from(*v)).collect();
    assert!(cons.max_residual(&vbp, &v) <= 1e-12 * 1.0f64.max(vb.iter().map(|x| x.norm()).fold(0.0, f64::max)));
    // Velocity correction Δv = v − 0.5 x̂ must be W Cᵀ y: Δv_l m_l = Σ_i C_il y_i. Check that
    // M Δv is orthogonal to the null space of C, via: the component of MΔv outside range(Cᵀ) is
    // zero. Solve the normal equations (C Cᵀ) y = C (MΔv) and compare.
    let mass = &tr.sim.mesh().mass;
    let n = mass.len();
    for d in 0..3 {
        let mdv: Vec<f64> =
            (0..n).map(|l| mass[l] * (tr.sim.state().v[l][d] - if d == 0 { 0.5 } else { 0.0 })).collect();
        let k = cons.len();
        let ones = vec![1.0; n];
        let gm = cons.gram(&ones);
        let mut cm = vec![0.0; k];
        cons.c.mul_vec(&mdv, &mut cm);
        let f = cons.check_rank(&ones).expect("full rank");
        f.solve(&mut cm);
        let mut fit = vec![0.0; n];
        cons.c.tr_mul_vec(&cm, &mut fit);
        let err = mdv.iter().zip(&fit).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
        let sc = mdv.iter().map(|a| a.abs()).fold(0.0, f64::max).max(1e-30);
        assert!(err <= 1e-10 * sc, "coordinate {d}: {err} vs {sc}");
        let _ = gm;
    }
}

/// §7.19: with K = 0 the tracker produces bitwise the states of `ShellSim::step`.
#[test]
fn untracked_equivalence() {
    let c = coarse();
    let (fine, _) = subdivide_linear(&c, 1);
    let g = waving_guide(&c);
    let empty = tracks::TestFunctions {
        s_bar: Csr { nrows: 0, ncols: c.n_vertices(), row_ptr: vec![0], col: vec![], val: vec![] },
        s: Csr { nrows: 0, ncols: fine.n_vertices(), row_ptr: vec![0], col: vec![], val: vec![] },
        kind: tracks::TestKind::Weak,
    };
    let mut tr =
        Tracker::new(sim_of(&fine, true, 0.1, vec![0, 1], Vec3::zeros()), g, empty, None, TrackOptions::default())
            .expect("tracker");
    assert!(tr.solver.is_none());
    let mut plain = sim_of(&fine, true, 0.1, vec![0, 1], Vec3::zeros());
    for _ in 0..20 {
        tr.step(1.0 / 60.0).expect("step");
        plain.step(1.0 / 60.0).expect("step");
    }
    assert_eq!(tr.sim.state(), plain.state());
}

/// §7.15: a duplicated region ⇒ RankDeficient([i, j]); a region on pinned vertices with non-zero
/// residual ⇒ InfeasibleConstraint(i); with zero residual ⇒ dropped + warning.
#[test]
fn rank_checks() {
    let c = coarse();
    let g = waving_guide(&c);
    let left = RegionSel::RestBox { min: (-1.0, -1.0, -1.0), max: (-0.05, 1.0, 1.0) };
    let right = RegionSel::RestBox { min: (0.05, -1.0, -1.0), max: (1.0, 1.0, 1.0) };
    let dup = TestFunctionSpec::Painted {
        guide: vec![left.clone(), right.clone(), left.clone()],
        tracked: vec![left.clone(), right.clone(), left.clone()],
    };
    let tf = build_test_functions(&dup, &g, &c, None).expect("tf");
    match Tracker::new(sim_of(&c, true, 0.0, vec![], Vec3::zeros()), g.clone(), tf, None, TrackOptions::default()) {
        Err(TrackError::RankDeficient(rows)) => assert_eq!(rows, vec![0, 2]),
        other => panic!("expected RankDeficient, got {:?}", other.err()),
    }
    // Region = the left column (x = −0.3); the consistent mass spreads its support one ring, so
    // the two left columns are pinned to make the support fully pinned.
    let col = RegionSel::RestBox { min: (-0.31, -1.0, -1.0), max: (-0.29, 1.0, 1.0) };
    let pins: Vec<u32> = (0..c.n_vertices() as u32).filter(|&v| c.positions[v as usize].x < -0.05).collect();
    let spec = TestFunctionSpec::Painted { guide: vec![col.clone(), right.clone()], tracked: vec![col, right] };
    let tf = build_test_functions(&spec, &g, &c, None).expect("tf");
    // The waving guide moves the pinned column: infeasible.
    match Tracker::new(sim_of(&c, true, 0.0, pins.clone(), Vec3::zeros()), g, tf.clone(), None, TrackOptions::default())
    {
        Err(TrackError::InfeasibleConstraint(0)) => {}
        other => panic!("expected InfeasibleConstraint(0), got {:?}", other.err()),
    }
    // A static guide satisfies it: dropped with a warning.
    let still = GuideAnimation::procedural(
        c.clone(),
        Arc::new({
            let r = c.positions.clone();
            move |_| r.clone()
        }),
        1.0,
    )
    .expect("guide");
    let tr = Tracker::new(sim_of(&c, true, 0.0, pins, Vec3::zeros()), still, tf, None, TrackOptions::default())
        .expect("dropped row");
    assert_eq!(tr.dropped_rows, vec![0]);
    assert_eq!(tr.warnings.len(), 1);
    assert_eq!(tr.constraints().expect("one row left").len(), 1);
}

/// §7.17: residual of `Penalty` vs k_p ∈ {1e3 … 1e7} falls like 1/k_p (log–log slope −1 ± 0.2).
#[test]
fn penalty_scaling() {
    let mut pts = Vec::new();
    for e in 3..=7 {
        let kp = 10f64.powi(e);
        let (mut tr, _) = tracker(KktMethod::Penalty { stiffness: kp }, 1);
        let mut worst = 0.0f64;
        for _ in 0..10 {
            let s = tr.step(1.0 / 60.0).expect("step");
            worst = worst.max(s.residual_pre_collision);
        }
        pts.push((kp.log10(), worst.log10()));
    }
    let n = pts.len() as f64;
    let (mx, my) = (pts.iter().map(|p| p.0).sum::<f64>() / n, pts.iter().map(|p| p.1).sum::<f64>() / n);
    let slope =
        pts.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum::<f64>() / pts.iter().map(|p| (p.0 - mx).powi(2)).sum::<f64>();
    assert!((slope + 1.0).abs() <= 0.2, "slope {slope}, points {pts:?}");
}

/// Guard: newton_iters > 1 is rejected (only the first Newton solve is constrained).
#[test]
fn newton_iters_rejected() {
    let c = coarse();
    let g = waving_guide(&c);
    let mut sim = sim_of(&c, true, 0.0, vec![], Vec3::zeros());
    sim.settings_mut().newton_iters = 3;
    let tf = build_test_functions(&TestFunctionSpec::SubdivisionBasis, &g, &c, Some(&Csr::identity(c.n_vertices())))
        .expect("tf");
    assert!(matches!(Tracker::new(sim, g, tf, None, TrackOptions::default()), Err(TrackError::BadParameter(_))));
}

/// §7.9 (reduced to a 35-vertex sheet to keep the suite fast): 2000 steps, the residual of the
/// last 100 steps stays ≤ 1e-10·L — each step corrects the full violation, nothing accumulates.
#[test]
fn no_drift() {
    let c = coarse();
    let (fine, p) = subdivide_linear(&c, 1);
    let g = waving_guide(&c);
    let l = g.scale();
    let tf = build_test_functions(&TestFunctionSpec::SubdivisionBasis, &g, &fine, Some(&p)).expect("tf");
    let mut tr = Tracker::new(sim_of(&fine, true, 0.0, vec![], Vec3::zeros()), g, tf, Some(p), TrackOptions::default())
        .expect("tracker");
    let mut worst = 0.0f64;
    for k in 0..2000 {
        let s = tr.step(1.0 / 240.0).expect("step");
        if k >= 1900 {
            worst = worst.max(s.residual_post_collision);
        }
    }
    assert!(worst <= 1e-10 * l, "drift {worst}");
}

/// §7.10: a physically consistent guide (an untracked run of the same mesh, sampled at the step
/// times) needs no constraint force: the tracked run reproduces it (1e-8·L) with μ ≈ 0.
#[test]
fn physical_guide_is_free() {
    let c = coarse();
    let (fine, _) = subdivide_linear(&c, 1);
    let h = 1.0 / 120.0;
    let mut plain = sim_of(&fine, true, 0.0, vec![], Vec3::zeros());
    let mut frames = vec![plain.state().q.clone()];
    for _ in 0..100 {
        plain.step(h).expect("step");
        frames.push(plain.state().q.clone());
    }
    let g = GuideAnimation::from_frames(fine.clone(), frames.clone(), 1.0 / h, tracks::TimeInterp::CatmullRom)
        .expect("guide");
    let l = g.scale();
    let o = tracks::ClusterOptions { regions: 6, frames: 4, ..tracks::ClusterOptions::default() };
    let tf = build_test_functions(&TestFunctionSpec::Clustered(o), &g, &fine, None).expect("tf");
    // The states coincide at t = 0; the projection would match the Catmull–Rom end tangent instead.
    let opts = TrackOptions { project_initial_state: false, ..TrackOptions::default() };
    let mut tr = Tracker::new(sim_of(&fine, true, 0.0, vec![], Vec3::zeros()), g, tf, None, opts).expect("tracker");
    for f in frames.iter().skip(1) {
        let s = tr.step(h).expect("step");
        assert!(s.max_constraint_force <= 1e-6, "force {}", s.max_constraint_force);
        let d = tr.sim.state().q.iter().zip(f).map(|(a, b)| (a - b).norm()).fold(0.0, f64::max);
        assert!(d <= 1e-8 * l, "deviation {d}");
    }
}

/// `TrackOptions::compare`: every alternative solves the same systems as the main method, is
/// timed, and agrees with it (1e-9 relative on Δv; the factorisations differ in rounding only).
#[test]
fn compare_methods_on_identical_systems() {
    let compare = vec![KktMethod::InterleavedLdlt, KktMethod::Schur, KktMethod::AmdRegularizedLdlt { delta: 1e-8 }];
    let opts = TrackOptions { compare: compare.clone(), ..TrackOptions::default() };
    let (mut tr, _) = tracker_with(opts, 2, gravity_only());
    for _ in 0..3 {
        let s = tr.step(1.0 / 60.0).expect("step");
        assert_eq!(s.compare.len(), compare.len());
        for (m, c) in compare.iter().zip(&s.compare) {
            assert!(c.t_solve > 0.0 && c.nnz_l > 0, "{m:?} timed");
            assert!(c.rel_diff <= 1e-9, "{m:?} differs by {}", c.rel_diff);
        }
    }
}

/// AmdRegularizedLdlt without refinement: the (2,2) shift −δI perturbs the solve by O(δ·μ); the
/// shift is warm-started with the previous step's multipliers, so from the second step on the
/// error is O(δ·(μ − μ_prev)). Checked against the exact ConstraintLastLdlt on the same steps:
/// the constraint residual stays ≤ 1e-10·L, the warm-started steps' residual is far below the
/// first (cold) step's, and the states agree to 1e-6 relative (δ = 1e-8 relative to max diag A).
#[test]
fn unrefined_shift_is_warm_started() {
    let run = |m: KktMethod| {
        let opts = TrackOptions { kkt: m, refine_steps: 0, ..TrackOptions::default() };
        let (mut tr, l) = tracker_with(opts, 2, gravity_only());
        let r: Vec<f64> = (0..20).map(|_| tr.step(1.0 / 120.0).expect("step").residual_pre_collision).collect();
        (r, tr.sim.state().v.clone(), l)
    };
    let (r_amd, v_amd, l) = run(KktMethod::AmdRegularizedLdlt { delta: 1e-8 });
    let (_, v_exact, _) = run(KktMethod::ConstraintLastLdlt);
    let worst_warm = r_amd[2..].iter().copied().fold(0.0, f64::max);
    // Measured: cold 6.7e-12, warm ≤ 1.2e-12 (L = 0.74); without the warm start every step's
    // residual is δ·μ, of the cold step's size or larger as the waving guide loads the cloth.
    assert!(worst_warm <= 0.5 * r_amd[0], "warm-started {worst_warm:e} vs cold {:e}", r_amd[0]);
    assert!(r_amd.iter().all(|&r| r <= 1e-10 * l), "residuals {r_amd:?}");
    let scale = v_exact.iter().map(|v| v.norm()).fold(0.0, f64::max);
    let d = v_amd.iter().zip(&v_exact).map(|(a, b)| (a - b).norm()).fold(0.0, f64::max);
    assert!(d <= 1e-6 * scale, "unrefined AMD differs from the exact solve by {d} (scale {scale})");
}

/// AmdRegularizedLdlt with a coarse shift (δ = 1e-6) and `refine_steps: 0`: the warm-started
/// solve misses the constraints by more than `SHIFT_RESIDUAL_TOL`·L, so the solver adds
/// refinement steps by itself (up to `MAX_SHIFT_REFINE_STEPS`); r_pre stays ≤ 1e-10·L.
#[test]
fn shift_residual_test_adds_refinement() {
    let opts =
        TrackOptions { kkt: KktMethod::AmdRegularizedLdlt { delta: 1e-6 }, refine_steps: 0, ..TrackOptions::default() };
    let (mut tr, l) = tracker_with(opts, 2, gravity_only());
    let mut refined = 0;
    for _ in 0..20 {
        let s = tr.step(1.0 / 120.0).expect("step");
        assert!(s.residual_pre_collision <= 1e-10 * l, "r_pre {:e} (L = {l})", s.residual_pre_collision);
        refined += usize::from(s.kkt_refine_steps > 0);
    }
    assert!(refined > 0, "the coarse shift never triggered a refinement");
}

/// §3.7 step 5 (`reproject_after_collisions`) on the waving sheet (the guide dips to y ≈ −0.093 m)
/// over a ground plane, with both contact models.
///
/// Bridson's velocity filter runs after the constrained solve: (a) floor at −0.095 m, initial
/// state projected: contact only grazes the tracked sheet at the start, the constraints stay
/// feasible, and the reprojection removes most of what the collision pass left (measured over
/// 120 steps: mean r_post 2.2e-6 → 7.6e-7 m); (b) floor at −0.05 m, flat start: the guide asks
/// for positions inside the floor — an infeasible conflict — and the residual stays
/// (1.12e-2 → 1.11e-2 m): the correction is undone by the rerun pass instead of pushing the
/// cloth through.
///
/// IPC puts the barrier inside the constrained Newton solve, so (a) the feasible case leaves no
/// residual for the reprojection to remove (r_post at solver precision), and (b) in the
/// infeasible case the barrier wins: the residual stays large and no vertex goes below the floor.
/// Either way collision-freedom keeps priority.
#[test]
fn reprojection_after_collisions() {
    use shells::{CollisionSettings, ContactMethod, Obstacle, ObstacleShape};
    let run = |method: ContactMethod, floor: f64, project: bool, reproject: bool| {
        let plane =
            Obstacle { shape: ObstacleShape::Plane { normal: Vec3::y(), offset: floor }, friction: 0.5, motion: None };
        let effects = Effects {
            gravity: Some(Vec3::new(0.0, -9.81, 0.0)),
            obstacles: vec![plane],
            collision: Some(CollisionSettings { method, ..Default::default() }),
            ..Effects::default()
        };
        let opts = TrackOptions {
            reproject_after_collisions: reproject,
            project_initial_state: project,
            ..TrackOptions::default()
        };
        let (mut tr, l) = tracker_with(opts, 2, effects);
        let (mut first, mut last, mut ran) = (0.0, 0.0, 0);
        for _ in 0..120 {
            let s = tr.step(1.0 / 120.0).expect("step");
            first += s.residual_post_first_pass;
            last += s.residual_post_collision;
            ran += usize::from(s.reprojected);
            let low = tr.sim.state().q.iter().map(|q| q.y).fold(f64::INFINITY, f64::min);
            assert!(
                low >= floor - 1e-9,
                "{method:?}: vertex at y = {low} below the floor {floor} at t = {}",
                tr.sim.state().t
            );
        }
        (first / 120.0, last / 120.0, ran, l)
    };
    // Option off: nothing runs, both residuals are the same number.
    let (first, last, ran, _) = run(ContactMethod::Bridson, -0.095, true, false);
    assert_eq!((ran, first), (0, last));
    // Bridson (a) feasible: the reprojection removes at least half of the post-collision residual.
    let (first, last, ran, _) = run(ContactMethod::Bridson, -0.095, true, true);
    assert!(ran > 0 && first > 1e-7, "contact must disturb the tracking (ran {ran}, r {first:e})");
    assert!(last < 0.5 * first, "feasible: mean r_post {last:e} vs first pass {first:e}");
    // Bridson (b) infeasible: collisions win; the residual is not made worse.
    let (first, last, ran, _) = run(ContactMethod::Bridson, -0.05, false, true);
    assert!(ran > 0 && first > 1e-3, "the floor must conflict with the guide (r {first:e})");
    assert!(last <= 1.01 * first, "infeasible: mean r_post {last:e} vs first pass {first:e}");
    // IPC (a) feasible: constraints and contact are solved together.
    let (first, last, _, l) = run(ContactMethod::Ipc, -0.095, true, true);
    assert!(first <= 1e-9 * l && last <= 1e-9 * l, "IPC feasible: mean r {first:e}, {last:e} (L = {l})");
    // IPC (b) infeasible: the barrier wins, the conflict stays visible in the residual.
    let (first, last, _, _) = run(ContactMethod::Ipc, -0.05, false, true);
    assert!(first > 1e-3 && last <= 1.01 * first, "IPC infeasible: mean r {first:e} → {last:e}");
}

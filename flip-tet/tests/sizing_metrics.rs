//! Sizing metrics and their combination (spec §3.12, §7): one test per metric plus the combination
//! rule and the level quantisation.

use flip_tet::bcc::tetrahedralize;
use flip_tet::octree::{Octree, OctreeSpec};
use flip_tet::sizing::{
    level_for_radius, CameraPath, Sizing, SizingContext, SizingParams, SurfaceCurvature, UserBox, VisibilityParams, C_H,
};
use flip_tet::surface::{marching_tets, vertex_curvature};
use flip_tet::transfer::w_smooth;
use geom_core::math::Pt3;
use geom_core::mesh::TriMesh;

/// h_min = 1/64, h_root = 1/8 → r_min = 1/256, r_max = 1/32.
fn ctx() -> SizingContext<'static> {
    SizingContext::new(1.0 / 64.0, 1.0 / 8.0)
}

fn sizing(p: SizingParams) -> Sizing {
    Sizing::from_params(&p).expect("valid parameters")
}

fn none() -> SizingParams {
    SizingParams { depth_floor: None, ..SizingParams::default() }
}

#[test]
fn nothing_switched_on_means_finest_everywhere() {
    // No metric, no floor: the liquid asks for the finest size (a uniform simulation).
    let s = sizing(none());
    assert!(s.metrics.is_empty());
    let c = ctx();
    assert_eq!(s.radius_at(&Pt3::new(0.3, 0.2, 0.1), &c), c.r_min);
    // A metric that is on but has no opinion: no demand.
    let s = sizing(SizingParams { turbulence: Some(0.05), ..none() });
    assert_eq!(s.radius_at(&Pt3::new(0.3, 0.2, 0.1), &c), f64::INFINITY);
}

#[test]
fn depth_floor_grows_linearly_with_depth() {
    let s = sizing(SizingParams::default()); // depth_floor 0.25 only
    let phi = |x: &Pt3| x.y - 0.5;
    let mut c = ctx();
    c.phi = Some(&phi);
    let (rmin, rmax) = (c.r_min, c.r_max);
    let depth = 0.05;
    let r = s.radius_at(&Pt3::new(0.0, 0.5 - depth, 0.0), &c);
    assert!((r - (rmin + 0.25 * depth)).abs() <= 1e-15, "{r}");
    // Deep enough the clamp to r_max applies.
    assert_eq!(s.radius_at(&Pt3::new(0.0, -1.0, 0.0), &c), rmax);
    // Above the surface D = r_min.
    assert_eq!(s.radius_at(&Pt3::new(0.0, 0.7, 0.0), &c), rmin);
    // With a curvature metric on and silent, the floor alone asks for nothing.
    let s = sizing(SizingParams { turbulence: Some(0.05), ..SizingParams::default() });
    assert_eq!(s.radius_at(&Pt3::new(0.0, 0.3, 0.0), &c), f64::INFINITY);
}

#[test]
fn surface_band_overrides_the_depth_floor() {
    let s = sizing(SizingParams { surface_band: Some(3.0), ..SizingParams::default() });
    let c = ctx();
    let h = c.h_min;
    assert_eq!(s.radius_at_phi(&Pt3::origin(), Some(-2.9 * h), &c), c.r_min);
    // Below the band the depth floor grades: D = r_min + 0.25 · depth.
    let r = s.radius_at_phi(&Pt3::origin(), Some(-3.1 * h), &c);
    assert!((r - (c.r_min + 0.25 * 3.1 * h)).abs() <= 1e-15, "{r}");
    // With a metric on and silent, outside the band there is no demand; inside, r_min wins.
    let s = sizing(SizingParams { surface_band: Some(3.0), turbulence: Some(0.05), ..SizingParams::default() });
    assert_eq!(s.radius_at_phi(&Pt3::origin(), Some(-3.1 * h), &c), f64::INFINITY);
    assert_eq!(s.radius_at_phi(&Pt3::origin(), Some(-2.9 * h), &c), c.r_min);
}

#[test]
fn liquid_curvature_uses_the_nearest_surface_vertex() {
    // Sphere of radius R = 0.25: κ = 2/R = 8, radius demand 0.8 / 8 = 0.1 → clamped to r_max.
    // With coefficient 0.1: 0.1 / 8 = 0.0125 inside [r_min, r_max].
    let mesh = tri_sphere(0.25);
    let kappa = vertex_curvature(&mesh, 1e9);
    let curv = SurfaceCurvature::new(&mesh, kappa);
    let s = sizing(SizingParams { liquid_curvature: Some(0.1), ..none() });
    assert!(s.needs_surface());
    let mut c = ctx();
    c.surface = Some(&curv);
    // Per-vertex curvature on a marching-tets mesh is noisy (see surface tests): check the median
    // over 64 query points around the sphere within 10 %, every one within 50 %.
    let mut rs: Vec<f64> = (0..64)
        .map(|i| {
            let y = 1.0 - 2.0 * (i as f64 + 0.5) / 64.0;
            let a = i as f64 * 2.399_963_229_728_653;
            let q = (1.0 - y * y).sqrt();
            s.radius_at(&(Pt3::new(0.5, 0.5, 0.5) + geom_core::math::Vec3::new(q * a.cos(), y, q * a.sin()) * 0.26), &c)
        })
        .collect();
    assert!(rs.iter().all(|r| (r - 0.0125).abs() <= 0.5 * 0.0125), "{rs:?}");
    rs.sort_by(|a, b| a.total_cmp(b));
    let median = rs[rs.len() / 2];
    assert!((median - 0.0125).abs() <= 0.1 * 0.0125, "median {median}");
    // Without a surface in the context: no opinion.
    assert_eq!(s.radius_at(&Pt3::origin(), &ctx()), f64::INFINITY);
}

#[test]
fn solid_curvature_fades_with_distance() {
    // Sphere obstacle R = 0.1: |∇²φ| = 2/|x − c| outside. W_smooth(d, r_max).
    let sdf = |x: &Pt3| (x - Pt3::new(0.5, 0.5, 0.5)).norm() - 0.1;
    let s = sizing(SizingParams { solid_curvature: Some(1.6), ..none() });
    let mut c = ctx();
    c.solid_sdf = Some(&sdf);
    let d = 0.01;
    let x = Pt3::new(0.5 + 0.1 + d, 0.5, 0.5);
    let expect = 1.6 / (w_smooth(d, c.r_max) * 2.0 / (0.1 + d));
    let r = s.radius_at(&x, &c);
    // FD Laplacian with step h_min/4 on a sphere SDF: relative error O((h/R)²) ≈ 1e-3.
    assert!((r - expect.clamp(c.r_min, c.r_max)).abs() <= 2e-3 * expect, "{r} vs {expect}");
    // Beyond r_max from the solid: no demand.
    assert_eq!(s.radius_at(&Pt3::new(0.5 + 0.1 + 1.01 * c.r_max, 0.5, 0.5), &c), f64::INFINITY);
    // Flat solid (half-space): zero curvature, no demand.
    let plane = |x: &Pt3| x.y - 0.2;
    c.solid_sdf = Some(&plane);
    assert_eq!(s.radius_at(&Pt3::new(0.3, 0.21, 0.3), &c), f64::INFINITY);
}

#[test]
fn turbulence_is_inverse_to_vorticity() {
    let s = sizing(SizingParams { turbulence: Some(0.05), ..none() });
    let w = |x: &Pt3| 10.0 * x.x;
    let mut c = ctx();
    c.u_ref = 2.0;
    c.vorticity = Some(&w);
    let r = s.radius_at(&Pt3::new(0.5, 0.0, 0.0), &c);
    // c_T U_ref / |ω| = 0.05 · 2 / 5 = 0.02 (ε = 1e-9 changes it by 4e-12).
    assert!((r - 0.02).abs() <= 1e-10, "{r}");
    // |ω| = 2.5 → 0.04 > r_max: clamped.
    assert_eq!(s.radius_at(&Pt3::new(0.25, 0.0, 0.0), &c), c.r_max);
    // |ω| = 8 → 0.0125.
    assert!((s.radius_at(&Pt3::new(0.8, 0.0, 0.0), &c) - 0.0125).abs() <= 1e-10);
    // Small vorticity: large radius, clamped to r_max.
    assert_eq!(s.radius_at(&Pt3::new(1e-6, 0.0, 0.0), &c), c.r_max);
}

#[test]
fn visibility_coarsens_outside_the_frustum() {
    let vis = VisibilityParams {
        path: CameraPath::Fixed { position: (0.5, 0.5, 3.0), look_at: (0.5, 0.5, 0.0) },
        fov_y_deg: 20.0,
        aspect: 1.0,
        near: 0.01,
        far: 100.0,
        margin_r_max: 2.0,
    };
    let p = SizingParams {
        visibility: Some(vis),
        user: Some(vec![UserBox { min: (-5.0, -5.0, -5.0), max: (5.0, 5.0, 5.0), radius: 0.005 }]),
        ..none()
    };
    let s = sizing(p);
    let c = ctx();
    assert_eq!(s.radius_at(&Pt3::new(0.5, 0.5, 0.0), &c), 0.005);
    assert_eq!(s.radius_at(&Pt3::new(3.0, 0.5, 0.0), &c), c.r_max);
}

#[test]
fn user_boxes_take_the_smallest_radius() {
    let p = SizingParams {
        user: Some(vec![
            UserBox { min: (0.0, 0.0, 0.0), max: (1.0, 1.0, 1.0), radius: 0.02 },
            UserBox { min: (0.4, 0.4, 0.4), max: (0.6, 0.6, 0.6), radius: 0.01 },
        ]),
        ..none()
    };
    let s = sizing(p);
    let c = ctx();
    assert_eq!(s.radius_at(&Pt3::new(0.5, 0.5, 0.5), &c), 0.01);
    assert_eq!(s.radius_at(&Pt3::new(0.1, 0.5, 0.5), &c), 0.02);
    assert_eq!(s.radius_at(&Pt3::new(1.5, 0.5, 0.5), &c), f64::INFINITY);
}

#[test]
fn quantisation_rounds_the_cube_size_down() {
    let h_root = 1.0 / 8.0;
    // r = h_root / (c_h 2^l) lands exactly on level l.
    for l in 0..5u8 {
        let r = h_root / (C_H * 2f64.powi(l as i32));
        assert_eq!(level_for_radius(r, h_root, 6), l);
        // Slightly smaller radius: next finer level.
        assert_eq!(level_for_radius(r * 0.99, h_root, 6), (l + 1).min(6));
        // Slightly larger radius: same level.
        assert_eq!(level_for_radius(r * 1.01, h_root, 6), l);
    }
    assert_eq!(level_for_radius(f64::INFINITY, h_root, 6), 0);
    assert_eq!(level_for_radius(1e-12, h_root, 3), 3);
    assert!(Sizing::temporal_limit(0.5, 0.1) == 0.2);
}

#[test]
fn invalid_parameters_are_rejected() {
    for p in [
        SizingParams { liquid_curvature: Some(-1.0), ..none() },
        SizingParams { depth_floor: Some(f64::NAN), ..none() },
        SizingParams {
            user: Some(vec![UserBox { min: (0.0, 0.0, 0.0), max: (1.0, 1.0, 1.0), radius: 0.0 }]),
            ..none()
        },
    ] {
        assert!(Sizing::from_params(&p).is_err());
    }
}

/// Closed marching-tets sphere of radius `r` about (0.5, 0.5, 0.5) on a uniform 32³ BCC mesh.
fn tri_sphere(r: f64) -> TriMesh {
    let spec = OctreeSpec::new(Pt3::origin(), Pt3::new(1.0, 1.0, 1.0), 32, 32).expect("unit box");
    let mesh = tetrahedralize(&Octree::uniform(spec, 0)).expect("uniform mesh");
    let phi: Vec<f64> = mesh.nodes.iter().map(|p| (p - Pt3::new(0.5, 0.5, 0.5)).norm() - r).collect();
    marching_tets(&mesh, &phi).expect("sphere")
}

/// Obstacle metrics are sampled on a grid over the domain (spec §3.12), not only at particles:
/// with `solid_curvature` on, the initial mesh is graded around the edges of a box obstacle that
/// no liquid touches (the FD Laplacian of the box SDF peaks along its edges), and is the
/// coarsest level there with the metric off. The liquid sits in the opposite corner.
#[test]
fn obstacle_metric_grades_the_mesh_before_the_liquid_arrives() {
    let scene = |metric: &str| -> flip_tet::scene::Scene {
        ron::from_str(&format!(
            r#"(domain: (min: (0.0, 0.0, 0.0), max: (1.0, 1.0, 1.0)),
            resolution: (coarsest: 4, finest: 32), duration: 1.0, fps: 30.0,
            liquid: [Box(min: (0.0, 0.0, 0.0), max: (0.2, 0.2, 0.2))],
            obstacles: [Box(min: (0.5, 0.4, 0.5), max: (0.9, 0.6, 0.9))],
            sizing: (depth_floor: None, {metric}))"#
        ))
        .expect("scene parses")
    };
    // A point just outside the middle of the top front edge of the obstacle.
    let edge = Pt3::new(0.7, 0.6 + 0.004, 0.5 - 0.004);
    let level_at = |s: &flip_tet::scene::Scene| {
        let sim = flip_tet::sim::FlipTetSim::new(s).expect("valid scene");
        let o = sim.octree();
        o.leaves[o.leaf_at(&edge) as usize].level
    };
    let on = level_at(&scene("solid_curvature: Some(1.6)"));
    let off = level_at(&scene("solid_curvature: None"));
    assert_eq!(off, 0, "no metric: the coarsest level away from the liquid");
    assert!(on >= 2, "solid curvature grades the box edge: level {on}");
}

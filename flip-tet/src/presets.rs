//! The setups of the paper's and the spec's experiments (spec §6 S1–S10): each function returns
//! the experiment's parameters exactly as the scene file `scenes/flip-tet/<name>.ron` holds them
//! (a test compares the two), and the scene transformations the variants use.

use geom_core::experiment::BySize;

use crate::error::{Result, SimError};
use crate::experiments::probes::Probes;
use crate::experiments::{
    adaptivity_payoff, dam_break, drop_pool, fvm_vs_nodal, holes_plate, open_splash, rest_pool, standing_wave,
    surface_mixed_radii,
};
use crate::scene::{Scene, Shape};
use crate::sizing::SizingParams;
use crate::sizing::{CameraPath, VisibilityParams};
use crate::surface::{SurfaceMethod, SurfaceParams};

/// S1b lattice shift in units of the particle spacing `2r` (spec §6 S1b: the flat surface then
/// lies `0.37 · 2r = 0.185 h` above a node plane, strictly between two planes `h/2` apart).
pub const S1B_OFFSET: f64 = 0.37;
/// Liquid depth of the second standing wave (m; spec §6 S3 "repeat with `H = 0.25`").
pub const SHALLOW_DEPTH: f64 = 0.25;
/// PCG tolerance of the S1 PCG run (relative residual; spec §6 S1).
pub const PCG_TOL: f64 = 1e-8;
/// Martin & Moyce's column width `a = 2¼ in` (m).
pub const MM_COLUMN_A: f64 = 0.05715;

fn sizes<T>(quick: T, default: T, full: T) -> BySize<T> {
    BySize::Modes(quick, default, full)
}

fn bx(min: [f64; 3], max: [f64; 3]) -> Shape {
    Shape::Box { min, max }
}

/// The S1b scene: `base` on a uniform mesh at `finest` with the lattice shifted up by
/// `0.37 · 2r`, and its intended surface height (m): the liquid box top plus the shift.
///
/// The shift also opens a gap of `0.185 h` between the floor and the bottom particles' spheres;
/// the level set mirrors every particle within `2 l r` of a closed wall across it (spec
/// §3.11.3), so the hull between a bottom particle and its mirror image covers the gap.
pub fn s1b_scene(base: &Scene, finest: u32) -> Result<(Scene, f64)> {
    let top = match base.liquid.first() {
        Some(Shape::Box { max, .. }) => max[1],
        _ => return Err(SimError::InvalidScene("rest-pool: the first liquid shape must be the pool Box".into())),
    };
    let mut s = base.clone();
    s.resolution.finest = finest;
    s.resolution.coarsest = finest;
    s.particles.lattice_offset = [0.0, S1B_OFFSET, 0.0];
    // Uniform mesh: h_min = longest domain side / finest, r = h_min / 4, spacing 2r = h_min / 2.
    let longest = (0..3).map(|a| s.domain.max[a] - s.domain.min[a]).fold(0.0, f64::max);
    let h = longest / f64::from(finest);
    Ok((s, top + S1B_OFFSET * h / 2.0))
}

/// `scene` with its cosine surface's mean moved to `depth` above the floor.
pub fn with_depth(scene: &Scene, depth: f64) -> Result<Scene> {
    let mut s = scene.clone();
    match s.liquid.first_mut() {
        Some(Shape::CosineSurface { mean, .. }) => *mean = s.domain.min[1] + depth,
        _ => return Err(SimError::InvalidScene("standing-wave: the liquid must be a CosineSurface".into())),
    }
    Ok(s)
}

/// S1 rest pool: a 1 × 0.5 × 0.25 m box half full, depth-graded, direct solver, 1/120 s steps.
pub fn rest_pool() -> rest_pool::Params {
    let mut scene = Scene::new(([0.0; 3], [1.0, 0.5, 0.25]), (8, 32), vec![bx([0.0; 3], [1.0, 0.25, 0.25])]);
    scene.name = "rest_pool".into();
    scene.fps = 120.0;
    scene.sizing = SizingParams { depth_floor: Some(0.25), surface_band: Some(3.0), ..Default::default() };
    scene.flip.dt_max = 0.008333333333333333;
    scene.pressure.solver = crate::error::SolverKind::DirectCholesky;
    rest_pool::Params {
        scene,
        finest: sizes(16, 32, 64),
        duration: sizes(0.3333333333333333, 1.6666666666666667, 1.6666666666666667),
        obj_every: 20,
        ply_every: 0,
        hires_every: 0,
        variants: rest_pool::Variants {
            offset_surface: true,
            pcg: true,
            first_order: true,
            jitter: true,
            jitter_steps: BySize::Same(400),
            jitter_finest: None,
            finest: Some(sizes(16, 16, 32)),
        },
        probes: Probes {
            heights: vec![(0.5, 0.125)],
            pressures: vec![[0.5, 0.1, 0.125], [0.25, 0.2, 0.0625]],
            obstacle_forces: false,
        },
    }
}

/// S2 Martin & Moyce dam break: column `a × 2a` (`a = 2¼ in`) in a `(64/13) a × (32/13) a ×
/// (8/13) a` tank (README "Deviations": `a` and `2a` whole multiples of the finest spacing).
pub fn dam_break() -> dam_break::Params {
    let a = MM_COLUMN_A;
    let (lx, ly, lz) = (0.2813538461538462, 0.1406769230769231, 0.03516923076923077);
    let mut scene = Scene::new(([0.0; 3], [lx, ly, lz]), (8, 64), vec![bx([0.0; 3], [a, 0.1143, lz])]);
    scene.name = "dam_break_mm".into();
    scene.fps = 100.0;
    scene.seed = 7;
    scene.sizing = SizingParams { depth_floor: Some(0.25), surface_band: Some(3.0), ..Default::default() };
    dam_break::Params {
        scene,
        finest: sizes(32, 64, 128),
        duration: sizes(0.19, 0.19, 0.19),
        obj_every: 2,
        ply_every: 0,
        hires_every: 0,
        resolution_study: Some(BySize::Modes(vec![], vec![], vec![16, 32, 64])),
    }
}

/// S3 standing wave: tank `L = 1` m, depth `H = 0.5` m, `η = H + A cos(π x/L)`, `A = 0.02` m.
pub fn standing_wave() -> standing_wave::Params {
    let wave = Shape::CosineSurface { mean: 0.5, amplitude: 0.02, length: 1.0, x0: 0.0 };
    let mut scene = Scene::new(([0.0; 3], [1.0, 0.75, 0.125]), (8, 32), vec![wave]);
    scene.name = "standing_wave".into();
    scene.fps = 60.0;
    scene.sizing = SizingParams { depth_floor: Some(0.25), surface_band: Some(3.0), ..Default::default() };
    scene.particles.column_top_on_surface = true;
    scene.flip.dt_max = 0.008333333333333333;
    standing_wave::Params {
        scene,
        finest: sizes(16, 32, 64),
        duration: sizes(1.8, 3.6, 3.6),
        obj_every: 6,
        ply_every: 0,
        hires_every: 0,
        variants: standing_wave::Variants {
            first_order: true,
            shallow: true,
            uniform: true,
            finest: Some(sizes(16, 16, 32)),
        },
    }
}

/// The drop-pool geometry (S4, S10): a ball `R = 0.12` m at 1 m/s over a 0.3 m pool in a 1 m box,
/// curvature + turbulence + depth sizing.
fn drop_scene(name: &str) -> Scene {
    let mut scene = Scene::new(([0.0; 3], [1.0; 3]), (8, 32), vec![bx([0.0; 3], [1.0, 0.3, 1.0])]);
    scene.name = name.into();
    scene.fps = 30.0;
    scene.seed = 3;
    scene.moving_liquid = vec![(Shape::Sphere { center: [0.5, 0.65, 0.5], radius: 0.12 }, [0.0, -1.0, 0.0])];
    scene.sizing = SizingParams {
        liquid_curvature: Some(0.8),
        turbulence: Some(0.05),
        depth_floor: Some(0.25),
        ..Default::default()
    };
    scene
}

/// S4 drop into a pool.
pub fn drop_pool() -> drop_pool::Params {
    drop_pool::Params {
        scene: drop_scene("drop_pool"),
        finest: sizes(16, 32, 64),
        duration: sizes(0.25, 0.6, 1.5),
        obj_every: 2,
        ply_every: 0,
        hires_every: 0,
    }
}

/// S7 holes plate: a 0.8 × 0.4 × 0.8 m block over a 0.1 m plate with a 3 × 3 grid of holes of
/// radius 0.07 m, solid-curvature sizing.
pub fn holes_plate() -> holes_plate::Params {
    let c = [0.3, 0.6, 0.8999999999999999];
    let mut holes = Vec::new();
    for x in c {
        for z in c {
            holes.push(Shape::Cylinder { a: [x, 0.5, z], b: [x, 0.8, z], radius: 0.07 });
        }
    }
    let plate = Shape::Subtract { base: Box::new(bx([0.0, 0.6, 0.0], [1.2, 0.7, 1.2])), holes };
    let mut scene = Scene::new(([0.0; 3], [1.2, 1.6, 1.2]), (8, 32), vec![bx([0.2, 0.9, 0.2], [1.0, 1.3, 1.0])]);
    scene.name = "holes_plate".into();
    scene.fps = 30.0;
    scene.seed = 5;
    scene.obstacles = vec![plate];
    scene.sizing = SizingParams {
        solid_curvature: Some(1.6),
        solid_proximity: Some(2.0),
        depth_floor: Some(0.25),
        ..Default::default()
    };
    holes_plate::Params {
        scene,
        finest: sizes(16, 32, 64),
        duration: sizes(0.3, 0.8, 0.8),
        obj_every: 2,
        ply_every: 0,
        hires_every: 0,
        uniform_comparison: Some(BySize::Modes(false, false, true)),
    }
}

/// S10 adaptivity payoff: the drop-pool geometry, adaptive vs uniform.
pub fn adaptivity_payoff() -> adaptivity_payoff::Params {
    adaptivity_payoff::Params {
        scene: drop_scene("adaptivity_payoff"),
        finest: sizes(16, 32, 64),
        duration: sizes(0.15, 0.5, 0.5),
        obj_every: 0,
        sizes: sizes(vec![16], vec![16, 32], vec![64]),
    }
}

/// S8 flat surfaces from mixed radii.
pub fn surface_mixed_radii() -> surface_mixed_radii::Params {
    surface_mixed_radii::Params {
        r: 0.01,
        plane_y: 0.2037,
        domain_min: (0.0, 0.0, 0.0),
        domain_max: (1.28, 0.32, 0.32),
        coarsest: 4,
        finest: sizes(128, 256, 256),
        patch: (0.02, 0.98, 0.02, 0.26),
        edge_margin: 1.25,
        blob_center: (1.15, 0.15, 0.16),
        blob_radius: 0.1,
        blob_particles: 300,
        seed: 7,
        surface: SurfaceParams {
            hull_l: 2.0,
            interior_k: 0.75,
            near_surface_band: 3.0,
            neighbours: 10,
            smoothing_iterations: 2,
            output_extra_levels: 1,
            method: SurfaceMethod::Hulls,
        },
    }
}

/// S9 nodal vs circumcentric FVM projection.
pub fn fvm_vs_nodal() -> fvm_vs_nodal::Params {
    fvm_vs_nodal::Params {
        domain_min: (0.0, 0.0, 0.0),
        domain_max: (1.0, 0.5, 0.25),
        coarsest: 4,
        finest: sizes(32, 32, 64),
        depth: 0.2578125,
        dt: 0.008333333333333333,
        sizing: SizingParams { depth_floor: Some(0.25), surface_band: Some(3.0), ..Default::default() },
        tol: 1e-8,
        eps_fvm: 0.1,
    }
}

/// S5 open splash: a sphere dropped at 2 m/s near one corner of a 4 × 1 × 4 m pool.
pub fn open_splash() -> open_splash::Params {
    let mut scene = Scene::new(([0.0; 3], [4.0, 1.0, 4.0]), (8, 64), vec![bx([0.0; 3], [4.0, 0.3, 4.0])]);
    scene.name = "open_splash".into();
    scene.duration = 0.4;
    scene.fps = 20.0;
    scene.seed = 5;
    scene.moving_liquid = vec![(Shape::Sphere { center: [0.8, 0.55, 0.8], radius: 0.15 }, [0.0, -2.0, 0.0])];
    scene.sizing = SizingParams { liquid_curvature: Some(0.8), depth_floor: Some(0.25), ..Default::default() };
    open_splash::Params { scene, finest: sizes(32, 64, 128), duration: sizes(0.1, 0.4, 1.0), obj_every: 2 }
}

/// S6 corridor: liquid released at one end of a U-shaped corridor under a moving camera.
pub fn corridor_camera() -> open_splash::Params {
    let mut scene = Scene::new(([0.0; 3], [2.0, 0.5, 2.0]), (8, 64), vec![bx([0.0; 3], [0.5, 0.3, 0.5])]);
    scene.name = "corridor_camera".into();
    scene.duration = 1.0;
    scene.fps = 20.0;
    scene.seed = 3;
    scene.obstacles = vec![bx([0.5, 0.0, 0.0], [1.5, 0.5, 1.5])];
    // Issue 26: a camera that first looks down the far leg of the U (the released liquid is out
    // of view), then pulls back over 0.5–0.7 s to see the whole corridor.
    let path = CameraPath::Keyframes(vec![
        (0.0, (1.75, 1.5, 2.6), (1.75, 0.0, 0.6)),
        (0.5, (1.75, 1.5, 2.6), (1.75, 0.0, 0.6)),
        (0.7, (1.0, 2.5, 3.5), (1.0, 0.0, 1.0)),
    ]);
    let vis = VisibilityParams { path, fov_y_deg: 50.0, aspect: 1.0, near: 0.05, far: 20.0, margin_r_max: 2.0 };
    scene.sizing = SizingParams { depth_floor: Some(0.25), visibility: Some(vis), ..Default::default() };
    open_splash::Params { scene, finest: sizes(32, 32, 64), duration: sizes(0.25, 1.0, 1.0), obj_every: 0 }
}

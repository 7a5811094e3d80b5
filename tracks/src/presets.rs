//! The paper's materials and scene setups (Bergou et al. 2007, §5; spec §6): the guide, the fine
//! mesh, the test functions and the fine shell of the flag (§5.1), the twisting box (§5.2), the
//! backflipping bag (§5.3) and the Xavier character stand-in (§5.4).
//!
//! The seed only names its materials (rubber, vinyl, cotton …); the values here are ours.
//! `shells` has no presets module (it has `Material::cotton()`), so the materials tracks needs
//! stay here: [`rubber`], [`vinyl`] and [`silk`] (the shells spec's preset table).
//!
//! ```
//! use tracks::presets::{box_setup, ShellOptions};
//! let s = box_setup(&ShellOptions { substeps: 4, self_collision: false, ..ShellOptions::default() }).unwrap();
//! assert_eq!((s.guide.n_vertices(), s.tracked_rest.n_vertices(), s.tf.len()), (8, 1538, 8));
//! ```

use std::sync::Arc;
use std::time::Instant;

use geom_core::linalg::Csr;
use geom_core::math::{Pt3, Vec3};
use geom_core::mesh::{subdivide_linear, TriMesh};
use shells::{
    CollisionSettings, ContactMethod, Damping, Effects, IntegratorSettings, Material, MembraneLaw, Obstacle,
    ObstacleShape, ShellSceneDesc, ShellSim, VertexConstraint, Wind,
};

use crate::cluster::ClusterOptions;
use crate::error::Result;
use crate::guide::{GuideAnimation, TimeInterp};
use crate::metrics::{centroid, mean_speed, stuck_on_branch};
use crate::procedural::{bag_guide, box_guide, flag_coarse, Xavier, BAG_B1_GAIN};
use crate::rest_events::RestEvents;
use crate::testfn::{build_test_functions, RegionSel, TestFunctionSpec, TestFunctions};

// ---------------------------------------------------------------------------------------------
// materials (ours; the seed names the materials only)

/// Isotropic St Venant–Kirchhoff shell: areal density ρ_s (kg/m²), Young's modulus × thickness
/// Yt (N/m), Poisson ratio ν, bending stiffness k_B (J) and Rayleigh stiffness damping β (s).
pub fn iso_material(density: f64, young_thickness: f64, poisson: f64, bending: f64, beta: f64) -> Material {
    Material {
        density,
        membrane: MembraneLaw::Isotropic { young_thickness, poisson, compression_softening: None },
        bending,
        damping: Damping::Rayleigh { alpha: 0.0, beta },
        plasticity: None,
    }
}

/// Rubber (box, Fig. 3/4 stand-ins, cellophane): ρ_s 0.5 kg/m², Yt 2·10⁴ N/m, ν 0.4, k_B 2·10⁻⁴ J,
/// β 10⁻³ s.
pub fn rubber() -> Material {
    iso_material(0.5, 2.0e4, 0.4, 2e-4, 1e-3)
}

/// Vinyl (bag): ρ_s 0.3 kg/m², Yt 5000 N/m, ν 0.35, k_B 5·10⁻⁵ J, β 5·10⁻³ s.
pub fn vinyl() -> Material {
    iso_material(0.3, 5.0e3, 0.35, 5e-5, 5e-3)
}

/// Silk (undamped, flowy; the shells spec §4 preset table): ρ_s 0.08 kg/m², Yt 800 N/m, ν 0.3,
/// k_B 10⁻⁶ J, α = β = 0.
pub fn silk() -> Material {
    iso_material(0.08, 800.0, 0.3, 1e-6, 0.0)
}

// ---------------------------------------------------------------------------------------------
// the fine shell

/// How the fine shell of a setup runs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShellOptions {
    /// Implicit Euler steps per guide frame.
    pub substeps: u32,
    /// Cloth–cloth collisions on/off (obstacles always collide).
    pub self_collision: bool,
    /// The contact model (IPC by default; `Bridson` is the seed's velocity filter).
    pub contact: ContactMethod,
}

impl Default for ShellOptions {
    fn default() -> Self {
        Self { substeps: 4, self_collision: true, contact: ContactMethod::default() }
    }
}

/// Collision settings of a scene with `self_collision` and/or obstacles (`None` without either).
pub fn collision(self_collision: bool, obstacles: bool, contact: ContactMethod) -> Option<CollisionSettings> {
    (self_collision || obstacles).then(|| CollisionSettings { method: contact, ..CollisionSettings::default() })
}

/// Gravity (−9.81 m/s² along y), the given obstacles and (optionally) self-collision; no wind.
pub fn gravity_effects(self_collision: bool, obstacles: Vec<Obstacle>, contact: ContactMethod) -> Effects {
    let any_obstacle = !obstacles.is_empty();
    Effects {
        gravity: Some(Vec3::new(0.0, -9.81, 0.0)),
        obstacles,
        self_collision,
        collision: collision(self_collision, any_obstacle, contact),
        ..Effects::default()
    }
}

/// A scene of `mesh` at rest with `material` and `effects`, no constraints, default integrator;
/// callers override fields with struct-update syntax.
pub fn shell_desc(mesh: &TriMesh, material: Material, effects: Effects) -> ShellSceneDesc {
    ShellSceneDesc {
        rest: mesh.positions.clone(),
        faces: mesh.faces.clone(),
        uv: None,
        initial: None,
        initial_velocity: None,
        material,
        effects,
        constraints: vec![],
        integrator: IntegratorSettings::default(),
        t0: 0.0,
    }
}

/// The ground plane y = 0 with Coulomb friction μ.
pub fn ground(friction: f64) -> Obstacle {
    ground_at(friction, 0.0)
}

/// The ground plane y = `height` (m) with the given friction.
pub fn ground_at(friction: f64, height: f64) -> Obstacle {
    Obstacle { shape: ObstacleShape::Plane { normal: Vec3::y(), offset: height }, friction, motion: None }
}

/// Height (m) of the ground under a cloth whose lowest vertex rests on y = 0 (the bag, Xavier):
/// one IPC contact distance d̂ ([`shells::contact::contact_distance`] of the mesh's mean edge)
/// plus 1 mm below it, so that the guide's lowest vertices stand just outside the barrier's
/// reach. Closer, the barrier pushes the feet up while their tracking constraints hold them at
/// the guide's y = 0: measured with the ground 1 mm below Xavier's feet (d̂ = 5.9 mm), the
/// constraint force grew by 2–4 N every step (2.2 → 27.7 N in 8 steps) and the edge strain
/// reached 0.27; at y = 0 the first step fails (IPC needs a positive gap at the start).
pub fn ground_below(mesh: &TriMesh) -> f64 {
    let (edges, p) = (mesh.topology().edges(), &mesh.positions);
    let mean =
        edges.iter().map(|&[a, b]| (p[b as usize] - p[a as usize]).norm()).sum::<f64>() / edges.len().max(1) as f64;
    -(shells::contact::contact_distance(0.0, mean) + 1e-3)
}

// ---------------------------------------------------------------------------------------------
// a setup

/// Everything needed to run one scene tracked and untracked.
pub struct Setup {
    /// The guide animation.
    pub guide: GuideAnimation,
    /// Prolongation P (guide → tracked) when the meshes are subdivision-related.
    pub prolongation: Option<Csr>,
    /// The tracked (fine) rest mesh.
    pub tracked_rest: TriMesh,
    /// Builds the fine shell's description (the tracked and the untracked run get one each).
    pub desc: Box<dyn Fn() -> ShellSceneDesc + Send + Sync>,
    /// The test functions.
    pub tf: TestFunctions,
    /// Guide frames per second.
    pub fps: f64,
    /// Steps per frame.
    pub substeps: u32,
    /// Scheduled rest-angle changes applied to the tracked and the untracked run alike
    /// (Xavier's CrinkleRest / RestoreRest, spec §6.4); `None` for the other scenes.
    pub rest_events: Option<Arc<RestEvents>>,
}

impl Setup {
    /// The same setup with `edit` applied to every shell description it builds (a material,
    /// rest-shape or wind variant).
    pub fn edited(self, edit: Box<dyn Fn(&mut ShellSceneDesc) + Send + Sync>) -> Setup {
        let desc = self.desc;
        Setup {
            desc: Box::new(move || {
                let mut d = desc();
                edit(&mut d);
                d
            }),
            ..self
        }
    }

    /// Step size h = 1 / (fps · substeps) (s).
    pub fn h(&self) -> f64 {
        1.0 / (self.fps * self.substeps as f64)
    }
}

/// Whole frames of `duration` s at `fps` (at least one).
pub fn frames_for(duration: f64, fps: f64) -> usize {
    (duration * fps).round().max(1.0) as usize
}

// ---------------------------------------------------------------------------------------------
// flag (§5.1)

/// Frame rate of the flag previews and guide (fps).
pub const FLAG_FPS: f64 = 30.0;

/// The branch: a capsule of radius 3 cm along z at (x, y) = (2.0, 1.2) m, friction 0.8.
pub fn flag_branch() -> Obstacle {
    Obstacle {
        shape: ObstacleShape::Capsule { a: Pt3::new(2.0, 1.2, -1.0), b: Pt3::new(2.0, 1.2, 1.0), radius: 0.03 },
        friction: 0.8,
        motion: None,
    }
}

/// Gravity, the branch and a steady 1.5 m/s wind along +x.
pub fn flag_effects(self_collision: bool, contact: ContactMethod) -> Effects {
    Effects {
        wind: Some(Wind::steady(Vec3::new(1.5, 0.0, 0.0))),
        ..gravity_effects(self_collision, vec![flag_branch()], contact)
    }
}

/// Initial velocity: (v_x, v_y, 0) m/s plus a spin of 1.5 rad/s about z through the flag centre.
pub fn flag_velocity(p: &[Pt3], vx: f64, vy: f64) -> Vec<Vec3> {
    let c = Vec3::new(0.0, 2.0, 0.0);
    let w = Vec3::new(0.0, 0.0, 1.5);
    p.iter().map(|x| Vec3::new(vx, vy, 0.0) + w.cross(&(x.coords - c))).collect()
}

/// A cotton flag of mesh `m` thrown with (v_x, v_y) m/s.
pub fn flag_desc(m: &TriMesh, vx: f64, vy: f64, self_collision: bool, contact: ContactMethod) -> ShellSceneDesc {
    ShellSceneDesc {
        initial_velocity: Some(flag_velocity(&m.positions, vx, vy)),
        ..shell_desc(m, Material::cotton(), flag_effects(self_collision, contact))
    }
}

/// The four painted regions of the flag: its quadrants in (u, v).
pub fn quadrants() -> Vec<RegionSel> {
    let q = |u: (f64, f64), v: (f64, f64)| RegionSel::Uv { u, v };
    vec![q((0.0, 0.6), (0.0, 0.4)), q((0.6, 1.2), (0.0, 0.4)), q((0.0, 0.6), (0.4, 0.8)), q((0.6, 1.2), (0.4, 0.8))]
}

/// The outcome of the flag's preview design loop.
pub struct FlagDesign {
    /// The chosen preview, as the guide.
    pub guide: GuideAnimation,
    /// Its throw velocity (v_x, v_y) (m/s).
    pub velocity: (f64, f64),
    /// Per preview of the velocity grid: stuck on the branch at the end.
    pub stuck_flags: Vec<bool>,
    /// Wall time of the loop (s).
    pub preview_s: f64,
}

/// One coarse preview: its frames (positions per frame) and its throw velocity (v_x, v_y) (m/s).
type PreviewRun = (Vec<Vec<Pt3>>, (f64, f64));

/// The coarse preview design loop (§5.1): the 35-vertex flag thrown with each of 20 velocities
/// (v_x ∈ {1.6 … 2.8}, v_y ∈ {0.5 … 2.0} m/s) for `duration` s; the first preview that ends
/// stuck on the branch ([`stuck_on_branch`]) is the guide, else the last design (2.8, 2.0).
pub fn flag_design(duration: f64, contact: ContactMethod) -> Result<FlagDesign> {
    let coarse = flag_coarse()?;
    let t0 = Instant::now();
    let mut flags = Vec::new();
    // The chosen preview's frames and its throw velocity (m/s).
    let mut chosen: Option<PreviewRun> = None;
    let nf = frames_for(duration, FLAG_FPS);
    for &vx in &[1.6, 1.9, 2.2, 2.5, 2.8] {
        for &vy in &[0.5, 1.0, 1.5, 2.0] {
            let mut sim = ShellSim::new(flag_desc(&coarse, vx, vy, false, contact))?;
            let mut frames = vec![sim.state().q.clone()];
            let (mut cs, mut vs) = (Vec::new(), Vec::new());
            for _ in 0..nf {
                sim.step(1.0 / FLAG_FPS)?;
                frames.push(sim.state().q.clone());
                cs.push(centroid(&sim.state().q));
                vs.push(mean_speed(&sim.state().v));
            }
            let s = stuck_on_branch(&cs, &vs, FLAG_FPS);
            flags.push(s);
            if s && chosen.is_none() {
                chosen = Some((frames, (vx, vy)));
            }
        }
    }
    let (frames, v) = match chosen {
        Some(c) => c,
        None => {
            // No preview got stuck: keep the last design (reported as stuck_preview = 0).
            let mut sim = ShellSim::new(flag_desc(&coarse, 2.8, 2.0, false, contact))?;
            let mut frames = vec![sim.state().q.clone()];
            for _ in 0..nf {
                sim.step(1.0 / FLAG_FPS)?;
                frames.push(sim.state().q.clone());
            }
            (frames, (2.8, 2.0))
        }
    };
    let guide = GuideAnimation::from_frames(coarse, frames, FLAG_FPS, TimeInterp::CatmullRom)?;
    Ok(FlagDesign { guide, velocity: v, stuck_flags: flags, preview_s: t0.elapsed().as_secs_f64() })
}

/// The 1617-vertex flag (the preview subdivided 3 times) tracking the design's guide through
/// its quadrants painted on the guide (`PaintedOnGuide`).
pub fn flag_setup(d: &FlagDesign, o: &ShellOptions) -> Result<Setup> {
    let (fine, p) = subdivide_linear(&d.guide.rest, 3);
    let spec = TestFunctionSpec::PaintedOnGuide { guide: quadrants() };
    let tf = build_test_functions(&spec, &d.guide, &fine, Some(&p))?;
    let (vx, vy) = d.velocity;
    let f2 = fine.clone();
    let (sc, contact) = (o.self_collision, o.contact);
    Ok(Setup {
        guide: d.guide.clone(),
        prolongation: Some(p),
        tracked_rest: fine,
        desc: Box::new(move || flag_desc(&f2, vx, vy, sc, contact)),
        tf,
        fps: FLAG_FPS,
        substeps: o.substeps,
        rest_events: None,
    })
}

// ---------------------------------------------------------------------------------------------
// box (§5.2)

/// Duration of the box guide clip (s): twist, hold, untwist, abrupt stop at 4.5 s.
pub const BOX_DURATION: f64 = 6.0;

/// The twisting rubber box: 8 → 1538 vertices (4 subdivisions), 8 subdivision hats, the bottom
/// face pinned, gravity, no obstacle.
pub fn box_setup(o: &ShellOptions) -> Result<Setup> {
    let guide = box_guide(BOX_DURATION)?;
    let (fine, p) = subdivide_linear(&guide.rest, 4);
    let tf = build_test_functions(&TestFunctionSpec::SubdivisionBasis, &guide, &fine, Some(&p))?;
    let pins: Vec<u32> =
        (0..fine.n_vertices() as u32).filter(|&v| fine.positions[v as usize].y.abs() < 1e-12).collect();
    let f2 = fine.clone();
    let (sc, contact) = (o.self_collision, o.contact);
    Ok(Setup {
        guide,
        prolongation: Some(p),
        tracked_rest: fine,
        desc: Box::new(move || ShellSceneDesc {
            constraints: vec![VertexConstraint::Pinned(pins.clone())],
            ..shell_desc(&f2, rubber(), gravity_effects(sc, vec![], contact))
        }),
        tf,
        fps: 30.0,
        substeps: o.substeps,
        rest_events: None,
    })
}

// ---------------------------------------------------------------------------------------------
// bag (§5.3)

/// Side vertices of the bag's fine rest mesh: those projected onto the cylinder of radius 0.2 m
/// (the bottom disc is planar already).
pub fn bag_side(q: &Pt3) -> bool {
    q.y > 1e-9 || (q.x * q.x + q.z * q.z).sqrt() > 0.19
}

/// The backflipping vinyl bag: 88 → 1297 vertices (2 subdivisions, side projected back onto the
/// smooth cylinder), 88 hats, the self-intersecting rig as guide (B1 gain [`BAG_B1_GAIN`]),
/// ground with friction 0.5.
pub fn bag_setup(o: &ShellOptions) -> Result<Setup> {
    let guide = bag_guide(3.0, BAG_B1_GAIN)?;
    let (fine, p) = subdivide_linear(&guide.rest, 2);
    let tf = build_test_functions(&TestFunctionSpec::SubdivisionBasis, &guide, &fine, Some(&p))?;
    let mut rest = fine;
    for q in rest.positions.iter_mut() {
        if bag_side(q) {
            let r = (q.x * q.x + q.z * q.z).sqrt();
            q.x *= 0.2 / r;
            q.z *= 0.2 / r;
        }
    }
    let r2 = rest.clone();
    let gy = ground_below(&rest);
    let (sc, contact) = (o.self_collision, o.contact);
    Ok(Setup {
        guide,
        prolongation: Some(p),
        tracked_rest: rest,
        desc: Box::new(move || shell_desc(&r2, vinyl(), gravity_effects(sc, vec![ground_at(0.5, gy)], contact))),
        tf,
        fps: 30.0,
        substeps: o.substeps,
        rest_events: None,
    })
}

// ---------------------------------------------------------------------------------------------
// Xavier (§5.4)

/// Duration of the Xavier guide clip (s): walk, headwind 4–7 s, electrocution, shake-off.
pub const XAVIER_DURATION: f64 = 10.0;

/// Feet: leg limbs (2, 3) with membership > 0.5 and radial coordinate s > 0.85.
pub fn xavier_feet(x: &Xavier) -> Vec<u32> {
    (0..x.mesh.n_vertices() as u32)
        .filter(|&v| {
            let m = x.membership[v as usize];
            (m[2] > 0.5 || m[3] > 0.5) && x.s[v as usize] > 0.85
        })
        .collect()
}

/// Gravity, ground (friction 0.5) and a gusty 12 m/s headwind along −z switched on over 4–7 s.
/// The ground is at `ground_y` (m; [`ground_below`] of the mesh).
pub fn xavier_effects(self_collision: bool, contact: ContactMethod, ground_y: f64) -> Effects {
    let mut wind = Wind::steady(Vec3::new(0.0, 0.0, -12.0));
    wind.turbulence = 0.5;
    wind.seed = 7;
    wind.schedule = vec![(3.99, 0.0), (4.0, 1.0), (7.0, 1.0), (7.01, 0.0)];
    Effects { wind: Some(wind), ..gravity_effects(self_collision, vec![ground_at(0.5, ground_y)], contact) }
}

/// Xavier's cloth (the 3038-vertex mesh itself) tracking `guide` through `tf`, starting on the
/// guide's first frame, with the CrinkleRest / RestoreRest events (±4 mm normal noise, seed 7;
/// they act from 7 s on).
pub fn xavier_setup(x: &Xavier, guide: &GuideAnimation, tf: TestFunctions, o: &ShellOptions) -> Setup {
    let mesh = x.mesh.clone();
    let gy = ground_below(&mesh);
    let g0 = {
        let mut p = vec![Pt3::origin(); guide.n_vertices()];
        guide.sample(0.0, &mut p);
        p
    };
    let (sc, contact) = (o.self_collision, o.contact);
    let desc = move || ShellSceneDesc {
        initial: Some(g0.clone()),
        ..shell_desc(&mesh, crate::procedural::xavier_material(), xavier_effects(sc, contact, gy))
    };
    // (An invalid description fails again, with its error, when the runs are built.)
    let rest_events = ShellSim::new(desc()).ok().map(|sim| Arc::new(RestEvents::xavier(&sim, &x.mesh, 0.004, 7)));
    Setup {
        guide: guide.clone(),
        prolongation: None,
        tracked_rest: x.mesh.clone(),
        desc: Box::new(desc),
        tf,
        fps: 30.0,
        substeps: o.substeps,
        rest_events,
    }
}

/// Xavier's test functions: `body` animation-aware regions (μ = 0.98, F = 32, seed 7) refined by
/// `feet` regions on the feet (the paper's 200 + 80); returns them and the time taken (s).
pub fn xavier_tf(x: &Xavier, guide: &GuideAnimation, body: usize, feet: usize) -> Result<(TestFunctions, f64)> {
    let t0 = Instant::now();
    let base = ClusterOptions { regions: body, mu: 0.98, frames: 32, seed: 7, ..ClusterOptions::default() };
    let spec =
        TestFunctionSpec::ClusteredWithRefinement { base, refine: vec![(RegionSel::Vertices(xavier_feet(x)), feet)] };
    let tf = build_test_functions(&spec, guide, &x.mesh, None)?;
    Ok((tf, t0.elapsed().as_secs_f64()))
}

/// Uniform animation-aware clustering of Xavier with `regions` regions (μ = 0.98, F = 32, seed
/// 7; Fig. 6); returns the test functions and the time taken (s).
pub fn xavier_uniform_tf(x: &Xavier, guide: &GuideAnimation, regions: usize) -> Result<(TestFunctions, f64)> {
    let t0 = Instant::now();
    let o = ClusterOptions { regions, mu: 0.98, frames: 32, seed: 7, ..ClusterOptions::default() };
    let tf = build_test_functions(&TestFunctionSpec::Clustered(o), guide, &x.mesh, None)?;
    Ok((tf, t0.elapsed().as_secs_f64()))
}

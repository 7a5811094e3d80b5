//! The `shells` cloth simulations that drive the wrinkle scenes on real cloth (spec §6 W2 with
//! the `shells` driver, W3 `sleeve`, W4 `vs-fine`): the gathered curtain and the sleeve, built
//! directly as `shells` scene descriptions (the curtain's gathered top edge is a per-vertex
//! kinematic path, which a rigid `KinematicPath` cannot express), stepped frame by frame with the
//! simulation's CPU and wall time measured and the physical-sanity invariants of the contact
//! issue (edge strain and compression, obstacle penetration, exact self-intersections, NaN)
//! watched after every step.
//!
//! Material coordinates are the rest mesh's UVs in metres: the curtain's (u, v) ∈ [0, W] × [0, H]
//! with v up (the top edge is v = H); the sleeve's (u, v) ∈ [0, 2πr] × [0, L] with v along the
//! axis from the bottom ring (per-corner UVs, so the seam has u = 2πr on its far side).
//!
//! ```no_run
//! use wrinkles::experiments::cloth::{Cloth, ClothModel, Curtain};
//! let model: ClothModel = ron::from_str(
//!     "(material: (density: 0.15, membrane: Isotropic(young_thickness: 1000.0, poisson: 0.3), bending: 2e-6),
//!       integrator: (fps: 30.0, substeps: 8))",
//! )
//! .unwrap();
//! let c = Curtain { width: 0.5, height: 0.5, gathered_width: 0.3, gather_s: 1.0, gravity: 9.81, noise_m: 1e-4, seed: 1 };
//! let mut cloth = Cloth::curtain(&c, 12, &model).unwrap();
//! let (_wall, _cpu) = cloth.advance_frame().unwrap();
//! assert_eq!(cloth.stats.steps, 8);
//! ```

use geom_core::experiment::Report;
use geom_core::math::{Pt2, Pt3, UnitQuat, Vec3};
use geom_core::mesh::Uv;
use geom_core::procedural::{grid, Diagonals, GridSpec, Plane};
use geom_core::rng::Rng;
use serde::Deserialize;
use shells::metrics::Sanity;
use shells::scene::SceneIntegrator;
use shells::{CollisionSettings, Effects, Material, Obstacle, ShellSceneDesc, ShellSim, VertexConstraint};

use crate::error::{Result, WrinkleError};
use crate::frames::RestMesh;
use geom_core::clock::process_cpu_s as process_cpu_seconds;

fn driver(e: impl std::fmt::Display) -> WrinkleError {
    WrinkleError::Driver(e.to_string())
}

/// How a cloth is simulated: material, time stepping, contact (a scene file's `fine` / `coarse`
/// block).
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ClothModel {
    /// The `shells` material (membrane law, bending k_B = B/6 in J, damping).
    pub material: Material,
    /// Frames per second, steps per frame, Newton iterations.
    #[serde(default)]
    pub integrator: SceneIntegrator,
    /// Contact handling (`None`: no collision code; the exact self-intersection count is still
    /// measured on every frame).
    #[serde(default)]
    pub collision: Option<CollisionSettings>,
    /// Cloth–cloth contact (needs `collision`).
    #[serde(default)]
    pub self_collision: bool,
}

/// The gathered curtain of spec §6 W4 (a): a `width × height` sheet hanging in the XY plane
/// under gravity −y, its top edge pinned and gathered about x = 0 from `width` to
/// `gathered_width` over `gather_s` seconds (smoothstep), held after.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Curtain {
    /// Sheet width W (m).
    pub width: f64,
    /// Sheet height H (m).
    pub height: f64,
    /// Width of the gathered top edge (m).
    pub gathered_width: f64,
    /// Gather duration (s).
    pub gather_s: f64,
    /// |g| (m/s²).
    pub gravity: f64,
    /// Out-of-plane noise of the initial positions (m, uniform in ±noise), which breaks the
    /// symmetry of the flat sheet so that it can buckle.
    pub noise_m: f64,
    /// Seed of the noise.
    pub seed: u64,
}

/// The sleeve of spec §6 W3: an open tube of radius r and length L along +y (bottom ring at
/// y = 0) around a static capsule arm; the top ring is pinned, the bottom ring (the cuff) rises
/// by `rise_frac·L` over `rise_s` (smoothstep), holds for `hold_s`, then twists by
/// `twist_deg·sin(2π τ)`, τ ∈ [0, 1] over `twist_s` (+ then −).
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Sleeve {
    /// Tube radius r (m).
    pub radius: f64,
    /// Tube length L (m).
    pub length: f64,
    /// Rise of the bottom ring as a fraction of L.
    pub rise_frac: f64,
    /// Rise duration (s).
    pub rise_s: f64,
    /// Hold after the rise (s).
    pub hold_s: f64,
    /// Twist amplitude (degrees).
    pub twist_deg: f64,
    /// Twist duration (s; 0 = no twist).
    pub twist_s: f64,
    /// Radius of the capsule arm on the tube's axis (m; 0 = no arm).
    pub arm_radius: f64,
    /// Out-of-surface noise of the initial positions (m).
    pub noise_m: f64,
    /// Seed of the noise.
    pub seed: u64,
}

/// `3s² − 2s³` of `t/t1` clamped to [0, 1] (1 when `t1 ≤ 0`).
pub fn smoothstep(t: f64, t1: f64) -> f64 {
    if t1 <= 0.0 {
        return 1.0;
    }
    let s = (t / t1).clamp(0.0, 1.0);
    s * s * (3.0 - 2.0 * s)
}

impl Sleeve {
    /// Cuff rise (m) and twist angle (rad) at time t.
    pub fn cuff(&self, t: f64) -> (f64, f64) {
        let rise = self.rise_frac * self.length * smoothstep(t, self.rise_s);
        let t1 = self.rise_s + self.hold_s;
        let tw = if self.twist_s > 0.0 && t > t1 {
            let tau = ((t - t1) / self.twist_s).min(1.0);
            self.twist_deg.to_radians() * (2.0 * std::f64::consts::PI * tau).sin()
        } else {
            0.0
        };
        (rise, tw)
    }
}

/// Counters of a cloth run.
#[derive(Clone, Debug, Default)]
pub struct ClothStats {
    /// Steps taken.
    pub steps: u64,
    /// Failed steps (0 or 1: a failure stops the run).
    pub nan_steps: u64,
    /// The error that stopped the run.
    pub error: Option<String>,
    /// Largest exact self-intersection count over the frames counted.
    pub max_intersections: u64,
    /// Newton iterations over all steps.
    pub newton_iters: u64,
    /// CPU seconds of the steps (all threads).
    pub sim_cpu_s: f64,
    /// Wall seconds of the steps.
    pub sim_wall_s: f64,
}

/// A running cloth simulation with its material-space rest mesh.
pub struct Cloth {
    /// The simulation.
    pub sim: ShellSim,
    /// Sanity monitor (every step).
    pub sanity: Sanity,
    /// The rest mesh for the wrinkle rig (UV = material coordinates, m).
    pub rest: RestMesh,
    /// Grid vertex counts (nx, ny) of the curtain (vertex (i, j) is `j·nx + i`).
    pub grid: Option<(usize, usize)>,
    /// Step size (s).
    pub h: f64,
    /// Steps per frame.
    pub substeps: u32,
    /// Frames per second.
    pub fps: f64,
    /// Counters.
    pub stats: ClothStats,
}

fn check_model(m: &ClothModel) -> Result<()> {
    m.material.validate().map_err(driver)?;
    let it = &m.integrator;
    if !(it.fps > 0.0 && it.fps.is_finite()) || it.substeps == 0 {
        return Err(WrinkleError::InvalidOption(format!(
            "integrator: fps must be > 0 and substeps ≥ 1, got {} and {}",
            it.fps, it.substeps
        )));
    }
    Ok(())
}

impl Cloth {
    /// The curtain at `quads × quads` (spec's "48²" = 48 quads per side).
    pub fn curtain(c: &Curtain, quads: u32, m: &ClothModel) -> Result<Self> {
        check_model(m)?;
        if !(c.width > 0.0 && c.height > 0.0 && c.gathered_width > 0.0 && c.gather_s >= 0.0 && c.noise_m >= 0.0)
            || quads < 2
        {
            return Err(WrinkleError::InvalidOption(format!(
                "curtain: width, height, gathered_width must be > 0, gather_s and noise_m ≥ 0, quads ≥ 2 \
                 (got {}, {}, {}, {}, {}, {quads})",
                c.width, c.height, c.gathered_width, c.gather_s, c.noise_m
            )));
        }
        let g = grid(&GridSpec {
            quads: [quads, quads],
            size: [c.width, c.height],
            plane: Plane::XY,
            diagonals: Diagonals::Alternating,
            center: Pt3::new(0.0, 0.5 * c.height, 0.0),
        })?;
        let n = (quads + 1) as usize;
        let top: Vec<u32> = ((n - 1) * n..n * n).map(|i| i as u32).collect();
        let mut rng = Rng::new(c.seed);
        let initial: Vec<Pt3> = g
            .positions
            .iter()
            .enumerate()
            .map(|(i, p)| if i >= (n - 1) * n { *p } else { p + Vec3::z() * rng.range(-c.noise_m, c.noise_m) })
            .collect();
        let rest_top: Vec<Pt3> = g.positions.clone();
        let (shrink, ts) = (1.0 - c.gathered_width / c.width, c.gather_s);
        let path: shells::KinematicFn = Box::new(move |t, i| {
            let p = rest_top[i as usize];
            Pt3::new(p.x * (1.0 - shrink * smoothstep(t, ts)), p.y, p.z)
        });
        let desc = ShellSceneDesc {
            rest: g.positions.clone(),
            faces: g.faces.clone(),
            uv: g.uv.clone(),
            initial: Some(initial),
            initial_velocity: None,
            material: m.material.clone(),
            effects: effects(m, Some(Vec3::new(0.0, -c.gravity, 0.0)), Vec::new()),
            constraints: vec![VertexConstraint::Kinematic(top, path)],
            integrator: m.integrator.settings(),
            t0: 0.0,
        };
        let rest = RestMesh::from_trimesh(&g)?;
        Self::start(desc, rest, Some((n, n)), m)
    }

    /// The W2 sheet of the four-stage demonstration (spec §6 W2) on the wrinkle rest mesh itself
    /// (same vertices and faces, so positions pass straight to the animator): no gravity, the
    /// vertices at y = `side` (the top edge) pinned, the two bottom corners (y = 0, x = 0 and
    /// x = `side`) displaced by `corner(t)` (m).
    pub fn four_stage_sheet(
        mesh: &RestMesh,
        side: f64,
        corner: impl Fn(f64) -> geom_core::math::Vec2 + Send + Sync + 'static,
        m: &ClothModel,
    ) -> Result<Self> {
        check_model(m)?;
        let tol = 1e-9 * side;
        let p = &mesh.positions;
        let top: Vec<u32> = (0..p.len() as u32).filter(|&i| (p[i as usize].y - side).abs() <= tol).collect();
        let corners: Vec<u32> = (0..p.len() as u32)
            .filter(|&i| {
                let q = p[i as usize];
                q.y.abs() <= tol && (q.x.abs() <= tol || (q.x - side).abs() <= tol)
            })
            .collect();
        if top.is_empty() || corners.len() != 2 {
            return Err(WrinkleError::InvalidOption(format!(
                "four-stage sheet: expected a top edge at y = {side} and two bottom corners, found {} and {}",
                top.len(),
                corners.len()
            )));
        }
        let rest_c = p.clone();
        let path: shells::KinematicFn = Box::new(move |t, i| {
            let d = corner(t);
            rest_c[i as usize] + Vec3::new(d.x, d.y, 0.0)
        });
        let desc = ShellSceneDesc {
            rest: p.clone(),
            faces: mesh.faces.clone(),
            uv: Some(mesh.uvs.clone()),
            initial: None,
            initial_velocity: None,
            material: m.material.clone(),
            effects: effects(m, None, Vec::new()),
            constraints: vec![VertexConstraint::Pinned(top), VertexConstraint::Kinematic(corners, path)],
            integrator: m.integrator.settings(),
            t0: 0.0,
        };
        Self::start(desc, mesh.clone(), None, m)
    }

    /// The sleeve with `around` vertices per ring and `rings` rings (spec's 16 × 12 quads =
    /// `around` 16, `rings` 13).
    pub fn sleeve(s: &Sleeve, around: u32, rings: u32, m: &ClothModel) -> Result<Self> {
        check_model(m)?;
        if !(s.radius > 0.0 && s.length > 0.0 && s.rise_s >= 0.0 && s.hold_s >= 0.0 && s.twist_s >= 0.0)
            || !(s.arm_radius >= 0.0 && s.arm_radius < s.radius && s.noise_m >= 0.0)
            || around < 3
            || rings < 2
        {
            return Err(WrinkleError::InvalidOption(format!(
                "sleeve: radius, length > 0, durations ≥ 0, 0 ≤ arm_radius < radius, around ≥ 3, rings ≥ 2 \
                 (got r {}, L {}, arm {}, {around} × {rings})",
                s.radius, s.length, s.arm_radius
            )));
        }
        let t = geom_core::procedural::tube(&geom_core::procedural::TubeSpec {
            radius: s.radius,
            length: s.length,
            around,
            along: rings - 1,
            start: Pt3::origin(),
            axis: Vec3::y(),
            caps: geom_core::procedural::Caps::Open,
        })?;
        let (tm, _) = t.triangulate_fan()?;
        // Per-corner UVs without the seam jump: a corner at u = 0 of a face that also touches
        // the last column takes u = 2πr.
        let circ = 2.0 * std::f64::consts::PI * s.radius;
        let uvv = |i: u32| -> Pt2 {
            let (k, r) = (i % around, i / around);
            Pt2::new(circ * k as f64 / around as f64, s.length * r as f64 / (rings - 1) as f64)
        };
        let uv: Vec<[Pt2; 3]> = tm
            .faces
            .iter()
            .map(|f| {
                let wraps = f.iter().any(|&i| i % around == around - 1);
                f.map(|i| {
                    let p = uvv(i);
                    if wraps && i % around == 0 {
                        Pt2::new(circ, p.y)
                    } else {
                        p
                    }
                })
            })
            .collect();
        let n = tm.positions.len() as u32;
        let bottom: Vec<u32> = (0..around).collect();
        let top: Vec<u32> = (n - around..n).collect();
        let mut rng = Rng::new(s.seed);
        let initial: Vec<Pt3> = tm
            .positions
            .iter()
            .enumerate()
            .map(|(i, p)| {
                let r = (i as u32) / around;
                if r == 0 || r == rings - 1 {
                    return *p;
                }
                let radial = Vec3::new(p.x, 0.0, p.z).normalize();
                p + radial * rng.range(-s.noise_m, s.noise_m)
            })
            .collect();
        let rest_b: Vec<Pt3> = tm.positions.clone();
        let sl = s.clone();
        let path: shells::KinematicFn = Box::new(move |t, i| {
            let (rise, tw) = sl.cuff(t);
            let p = rest_b[i as usize];
            UnitQuat::from_axis_angle(&Vec3::y_axis(), tw) * p + Vec3::new(0.0, rise, 0.0)
        });
        let mut obstacles = Vec::new();
        if s.arm_radius > 0.0 {
            obstacles.push(Obstacle {
                shape: shells::ObstacleShape::Capsule {
                    a: Pt3::new(0.0, -0.5 * s.length, 0.0),
                    b: Pt3::new(0.0, 1.5 * s.length, 0.0),
                    radius: s.arm_radius,
                },
                friction: m.collision.as_ref().map_or(0.0, |c| c.friction),
                motion: None,
            });
        }
        let desc = ShellSceneDesc {
            rest: tm.positions.clone(),
            faces: tm.faces.clone(),
            uv: Some(Uv::PerCorner(uv.clone())),
            initial: Some(initial),
            initial_velocity: None,
            material: m.material.clone(),
            effects: effects(m, None, obstacles),
            constraints: vec![VertexConstraint::Pinned(top), VertexConstraint::Kinematic(bottom, path)],
            integrator: m.integrator.settings(),
            t0: 0.0,
        };
        let rest = RestMesh::new(tm.positions.clone(), tm.faces.clone(), Uv::PerCorner(uv))?;
        Self::start(desc, rest, None, m)
    }

    fn start(desc: ShellSceneDesc, rest: RestMesh, grid: Option<(usize, usize)>, m: &ClothModel) -> Result<Self> {
        let obstacles = desc.effects.obstacles.clone();
        let sim = ShellSim::new(desc).map_err(driver)?;
        let sanity = Sanity::new(&sim.mesh().rest, &sim.mesh().edges, obstacles, None);
        let it = &m.integrator;
        Ok(Self {
            sim,
            sanity,
            rest,
            grid,
            h: it.h(),
            substeps: it.substeps,
            fps: it.fps,
            stats: ClothStats::default(),
        })
    }

    /// Current positions (m).
    pub fn positions(&self) -> &[Pt3] {
        &self.sim.state().q
    }

    /// Current time (s).
    pub fn time(&self) -> f64 {
        self.sim.state().t
    }

    /// One frame (`substeps` steps); returns its (wall, CPU) seconds, steps only (the sanity
    /// monitor runs after each step, outside the timed region). A failed step stops the run:
    /// the error is kept in `stats` and returned.
    pub fn advance_frame(&mut self) -> Result<(f64, f64)> {
        let (mut wall, mut cpu) = (0.0, 0.0);
        for _ in 0..self.substeps {
            let (c0, w0) = (process_cpu_seconds(), std::time::Instant::now());
            let r = self.sim.step(self.h);
            let (w, c) = (w0.elapsed().as_secs_f64(), process_cpu_seconds() - c0);
            match r {
                Ok(st) => {
                    self.stats.steps += 1;
                    self.stats.newton_iters += st.newton_iters as u64;
                    wall += w;
                    cpu += c;
                    let s = self.sim.state();
                    self.sanity.observe(&s.q, s.t, None);
                }
                Err(e) => {
                    self.stats.nan_steps += 1;
                    self.stats.error = Some(e.to_string());
                    return Err(driver(e));
                }
            }
        }
        self.stats.sim_wall_s += wall;
        self.stats.sim_cpu_s += cpu;
        Ok((wall, cpu))
    }

    /// Counts the exact self-intersections of the current frame (kept as a maximum).
    pub fn count_intersections(&mut self) -> u64 {
        let k = shells::collision::count_self_intersections(&self.sim.state().q, &self.sim.mesh().tris) as u64;
        self.stats.max_intersections = self.stats.max_intersections.max(k);
        k
    }

    /// The sanity figures with keys prefixed by `prefix`: `max_edge_strain`,
    /// `max_edge_compression`, `max_obstacle_penetration_m`, `max_intersections`, `nan_steps`,
    /// `steps`, `newton_iters_mean`, `vertices`, and the timings `sim_cpu_s`, `sim_wall_s`.
    pub fn figures(&self, r: &mut Report, prefix: &str) {
        let k = |s: &str| format!("{prefix}{s}");
        let s = &self.sanity;
        r.num(&k("max_edge_strain"), s.max_edge_strain);
        r.num(&k("max_edge_compression"), s.max_edge_compression);
        r.num(&k("max_obstacle_penetration_m"), s.max_obstacle_penetration_m);
        r.count(&k("max_intersections"), self.stats.max_intersections);
        r.count(&k("nan_steps"), self.stats.nan_steps);
        r.count(&k("steps"), self.stats.steps);
        r.num(&k("newton_iters_mean"), self.stats.newton_iters as f64 / self.stats.steps.max(1) as f64);
        r.count(&k("vertices"), self.sim.state().q.len() as u64);
        r.timing(&k("sim_cpu_s"), self.stats.sim_cpu_s);
        r.timing(&k("sim_wall_s"), self.stats.sim_wall_s);
    }
}

fn effects(m: &ClothModel, gravity: Option<Vec3>, obstacles: Vec<Obstacle>) -> Effects {
    Effects {
        gravity,
        wind: None,
        obstacles,
        self_collision: m.self_collision,
        collision: m.collision.clone(),
        custom: Vec::new(),
    }
}

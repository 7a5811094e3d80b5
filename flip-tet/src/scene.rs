//! Scene description (spec §2, §4): domain, resolution, liquid and obstacle shapes (analytic
//! SDFs), effect switches and parameters. Deserialised from RON with unknown fields rejected;
//! [`Scene::validate`] names the offending field.

use geom_core::math::{Pt3, Vec3};
use serde::{Deserialize, Serialize};

use crate::error::{Result, SimError};
use crate::pressure::PressureParams;
use crate::sizing::SizingParams;
use crate::surface::SurfaceParams;
use crate::transfer::TransferParams;

/// Axis-aligned domain box (m).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DomainBox {
    /// Minimum corner.
    pub min: [f64; 3],
    /// Maximum corner.
    pub max: [f64; 3],
}

/// Resolution: cubes along the longest axis at the coarsest and the finest level (spec §4).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Resolution {
    /// Coarsest (root) cubes along the longest axis.
    pub coarsest: u32,
    /// Finest cubes along the longest axis (`coarsest · 2^k`).
    pub finest: u32,
}

/// Analytic shapes for liquid regions and obstacles (negative SDF inside).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum Shape {
    /// Axis-aligned box.
    Box {
        /// Minimum corner (m).
        min: [f64; 3],
        /// Maximum corner (m).
        max: [f64; 3],
    },
    /// Ball.
    Sphere {
        /// Centre (m).
        center: [f64; 3],
        /// Radius (m).
        radius: f64,
    },
    /// Capped cylinder between two points.
    Cylinder {
        /// Axis start (m).
        a: [f64; 3],
        /// Axis end (m).
        b: [f64; 3],
        /// Radius (m).
        radius: f64,
    },
    /// Liquid below the surface `y = mean + amplitude · cos(π (x − x0) / length)` (standing wave).
    CosineSurface {
        /// Mean height (m).
        mean: f64,
        /// Amplitude (m).
        amplitude: f64,
        /// Tank length `L` (m); the mode is `cos(π x / L)`.
        length: f64,
        /// Tank start `x0` (m).
        x0: f64,
    },
    /// `base` minus the union of `holes` (CSG difference).
    Subtract {
        /// Base shape.
        base: Box<Shape>,
        /// Removed shapes.
        holes: Vec<Shape>,
    },
    /// A closed triangle mesh read from `path` (OBJ, PLY, OFF; a relative path resolves against
    /// the scene file's folder, [`Scene::resolve_paths`]), for obstacles only (top level of
    /// `obstacles` or of a moving obstacle's `shape`). Its signed distance is geom-core's
    /// `MeshQuery::signed_distance`, evaluated through [`crate::obstacle::Obstacles`], which
    /// loads the file; [`Shape::sdf`] itself knows no mesh and returns +∞.
    Mesh {
        /// Mesh file.
        path: String,
    },
}

fn p3(a: &[f64; 3]) -> Pt3 {
    Pt3::new(a[0], a[1], a[2])
}

impl Shape {
    /// Signed distance (m; exact for box, sphere, cylinder; a bound for the cosine surface and CSG).
    pub fn sdf(&self, x: &Pt3) -> f64 {
        match self {
            Shape::Box { min, max } => {
                let c = (p3(min).coords + p3(max).coords) / 2.0;
                let h = (p3(max) - p3(min)) / 2.0;
                let q = (x.coords - c).abs() - h;
                let outside = q.map(|v| v.max(0.0)).norm();
                outside + q.max().min(0.0)
            }
            Shape::Sphere { center, radius } => (x - p3(center)).norm() - radius,
            Shape::Cylinder { a, b, radius } => geom_core::iso::sdf::cylinder(x, &p3(a), &p3(b), *radius),
            Shape::CosineSurface { mean, amplitude, length, x0 } => {
                let eta = mean + amplitude * (std::f64::consts::PI * (x.x - x0) / length).cos();
                x.y - eta
            }
            Shape::Subtract { base, holes } => {
                let mut d = base.sdf(x);
                for h in holes {
                    d = d.max(-h.sdf(x));
                }
                d
            }
            Shape::Mesh { .. } => f64::INFINITY,
        }
    }

    /// Whether the shape is or contains a `Mesh`.
    pub fn has_mesh(&self) -> bool {
        match self {
            Shape::Mesh { .. } => true,
            Shape::Subtract { base, holes } => base.has_mesh() || holes.iter().any(Shape::has_mesh),
            _ => false,
        }
    }

    fn finite(&self) -> bool {
        match self {
            Shape::Box { min, max } => min.iter().chain(max).all(|v| v.is_finite()),
            Shape::Sphere { center, radius } => {
                center.iter().all(|v| v.is_finite()) && radius.is_finite() && *radius > 0.0
            }
            Shape::Cylinder { a, b, radius } => a.iter().chain(b).all(|v| v.is_finite()) && *radius > 0.0,
            Shape::CosineSurface { mean, amplitude, length, x0 } => {
                [mean, amplitude, length, x0].iter().all(|v| v.is_finite()) && *length > 0.0
            }
            Shape::Subtract { base, holes } => base.finite() && holes.iter().all(Shape::finite),
            Shape::Mesh { path } => !path.is_empty(),
        }
    }
}

/// Union SDF of a list of shapes (+∞ for an empty list).
pub fn union_sdf(shapes: &[Shape], x: &Pt3) -> f64 {
    shapes.iter().map(|s| s.sdf(x)).fold(f64::INFINITY, f64::min)
}

/// A face of the domain box (open faces let particles leave).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum BoxFace {
    /// x = min.
    NegX,
    /// x = max.
    PosX,
    /// y = min.
    NegY,
    /// y = max.
    PosY,
    /// z = min.
    NegZ,
    /// z = max.
    PosZ,
}

/// Particle options (spec §4 `particles`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ParticleParams {
    /// Initial jitter as a fraction of the particle spacing.
    pub sampling_jitter: f64,
    /// Ballistic particles on/off.
    pub ballistic: bool,
    /// Isolation radius / r (paper: 6).
    pub ballistic_factor: f64,
    /// Position correction on/off.
    pub position_correction: bool,
    /// Overlap relief per step γ.
    pub correction_gamma: f64,
    /// Tangential-correction band / r (paper: 6).
    pub surface_band_factor: f64,
    /// Split/merge at remesh on/off (forced off when the mesh is uniform).
    pub split_merge: bool,
    /// Split hysteresis σ_s.
    pub split_ratio: f64,
    /// Merge hysteresis σ_m.
    pub merge_ratio: f64,
    /// Snap-to-surface distance / r for new particles (paper: 1.25).
    pub snap_factor: f64,
    /// Particle budget.
    pub max_particles: usize,
    /// Exceeding the budget is an error (else splitting stops).
    pub budget_is_error: bool,
    /// Standing-wave sampling: in each column the top particle is placed at `η(x) − r`.
    pub column_top_on_surface: bool,
    /// Shift of the initial particle lattice, per axis, in units of the particle spacing `2r`
    /// (spec §6 S1b: `(0, 0.37, 0)` moves a flat pool surface strictly between BCC node planes).
    /// Which lattice points are kept, and their `φ_p`, are decided at the unshifted point, so the
    /// whole sampled liquid is translated by `offset · 2r` (the shape's surface moves with it;
    /// a translation keeps every signed distance). Default `[0, 0, 0]`: the unshifted lattice.
    pub lattice_offset: [f64; 3],
}

impl Default for ParticleParams {
    fn default() -> Self {
        Self {
            sampling_jitter: 0.0,
            ballistic: true,
            ballistic_factor: 6.0,
            position_correction: true,
            correction_gamma: 0.5,
            surface_band_factor: 6.0,
            split_merge: true,
            split_ratio: 1.5,
            merge_ratio: 1.0 / 1.5,
            snap_factor: 1.25,
            max_particles: 5_000_000,
            budget_is_error: false,
            column_top_on_surface: false,
            lattice_offset: [0.0; 3],
        }
    }
}

/// Time-step policy (spec §3.13).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize, Default)]
pub enum DtPolicy {
    /// CFL-limited adaptive step.
    #[default]
    Adaptive,
    /// Fixed step (s); advection substeps handle CFL violations.
    Fixed(f64),
}

/// FLIP options (spec §4 `flip`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct FlipParams {
    /// PIC fraction at the finest radius α₀.
    pub pic_base: f64,
    /// Size compensation exponent e.
    pub pic_radius_exponent: f64,
    /// Minimum PIC fraction.
    pub pic_floor: f64,
    /// Steps between mesh rebuilds.
    pub remesh_interval: u32,
    /// CFL number w.r.t. the local tet size.
    pub cfl: f64,
    /// Largest step (s).
    pub dt_max: f64,
    /// Smallest step (s).
    pub dt_min: f64,
    /// Step policy.
    pub dt_policy: DtPolicy,
    /// Time integration of the particle velocities and positions (ours, see README
    /// "Deviations"); default [`TimeIntegration::Leapfrog`].
    pub time_integration: TimeIntegration,
}

/// How a step advances velocities ("kick": gravity, then the pressure projection, then G2P) and
/// positions ("drift": advection through the grid field). All three use one projection per step.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum TimeIntegration {
    /// Kick–drift leapfrog: the particle velocities live at half steps. Gravity acts over
    /// `(Δt_prev + Δt) / 2` (`Δt / 2` in the first step: the half kick that starts the scheme),
    /// then the particles drift with the projected field `u_new`. Second order in time (exact
    /// for constant acceleration) and symplectic: an oscillation (a sloshing mode) keeps its
    /// energy, where `TimeCentred` gains about `π ω Δt / 2` of amplitude per period.
    #[default]
    Leapfrog,
    /// Gravity over `Δt`, drift through the linear-in-time field `(1 − s) u_old + s u_new`
    /// (`s` the fraction of the step; sessions 5–9 default). Exact for constant acceleration
    /// but not symplectic: its one-step map of a harmonic oscillator has determinant
    /// `1 + (ω Δt)² / 2`, so standing waves grow.
    TimeCentred,
    /// Gravity over `Δt`, drift with `u_new` (symplectic Euler from synchronised velocities):
    /// energy-stable, but a particle accelerating at `A` from the start runs ahead of its path by
    /// `A t Δt / 2` (first order).
    EndOfStep,
}

impl Default for FlipParams {
    fn default() -> Self {
        Self {
            pic_base: 0.03,
            pic_radius_exponent: 2.0,
            pic_floor: 0.005,
            remesh_interval: 10,
            cfl: 1.0,
            dt_max: 0.005,
            dt_min: 1e-6,
            dt_policy: DtPolicy::Adaptive,
            time_integration: TimeIntegration::Leapfrog,
        }
    }
}

fn default_gravity() -> [f64; 3] {
    [0.0, -9.81, 0.0]
}

/// A complete scene (spec §2). All fields but `domain`, `resolution` and `liquid` have defaults.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Scene {
    /// Name (informational).
    #[serde(default)]
    pub name: String,
    /// Domain box.
    pub domain: DomainBox,
    /// Resolution.
    pub resolution: Resolution,
    /// Simulated duration (s).
    #[serde(default = "one")]
    pub duration: f64,
    /// Frames per second (frame boundaries are landed on exactly).
    #[serde(default = "fps")]
    pub fps: f64,
    /// RNG seed (jitter, split placement, tie breaks).
    #[serde(default)]
    pub seed: u64,
    /// Gravity (m/s²).
    #[serde(default = "default_gravity")]
    pub gravity: [f64; 3],
    /// Liquid regions (union).
    pub liquid: Vec<Shape>,
    /// Initial velocity of the liquid (m/s).
    #[serde(default)]
    pub initial_velocity: [f64; 3],
    /// Liquid regions with their own initial velocity (e.g. a falling drop), `(shape, velocity)`.
    #[serde(default)]
    pub moving_liquid: Vec<(Shape, [f64; 3])>,
    /// Static obstacles (union).
    #[serde(default)]
    pub obstacles: Vec<Shape>,
    /// Obstacles moving on rigid paths (issue 26; [`crate::obstacle`]).
    #[serde(default)]
    pub moving_obstacles: Vec<crate::obstacle::MovingObstacle>,
    /// Inflow emitters (issue 26; [`crate::inflow`]).
    #[serde(default)]
    pub emitters: Vec<crate::inflow::Emitter>,
    /// Outflow regions: particles whose centre enters one are deleted (issue 26).
    #[serde(default)]
    pub outflow: Vec<Shape>,
    /// Box faces through which particles may leave.
    #[serde(default)]
    pub open_faces: Vec<BoxFace>,
    /// Extra strong-balance layers (gentler grading).
    #[serde(default)]
    pub extra_grading_layers: u32,
    /// Sizing function (ft-aux's `SizingParams`).
    #[serde(default)]
    pub sizing: SizingParams,
    /// Particle options.
    #[serde(default)]
    pub particles: ParticleParams,
    /// FLIP options.
    #[serde(default)]
    pub flip: FlipParams,
    /// Pressure options.
    #[serde(default)]
    pub pressure: PressureParams,
    /// Transfer options.
    #[serde(default)]
    pub transfer: TransferParams,
    /// Surface reconstruction (ft-aux's `SurfaceParams`).
    #[serde(default)]
    pub surface: SurfaceParams,
}

fn one() -> f64 {
    1.0
}
fn fps() -> f64 {
    60.0
}

impl Scene {
    /// A scene over `domain` (min, max corners, m) at `resolution` (coarsest, finest cubes along
    /// the longest axis) holding `liquid`, every other field at its default (the values a scene
    /// file gets when it leaves them out).
    pub fn new(domain: ([f64; 3], [f64; 3]), resolution: (u32, u32), liquid: Vec<Shape>) -> Self {
        Self {
            name: String::new(),
            domain: DomainBox { min: domain.0, max: domain.1 },
            resolution: Resolution { coarsest: resolution.0, finest: resolution.1 },
            duration: one(),
            fps: fps(),
            seed: 0,
            gravity: default_gravity(),
            liquid,
            initial_velocity: [0.0; 3],
            moving_liquid: Vec::new(),
            obstacles: Vec::new(),
            moving_obstacles: Vec::new(),
            emitters: Vec::new(),
            outflow: Vec::new(),
            open_faces: Vec::new(),
            extra_grading_layers: 0,
            sizing: SizingParams::default(),
            particles: ParticleParams::default(),
            flip: FlipParams::default(),
            pressure: PressureParams::default(),
            transfer: TransferParams::default(),
            surface: SurfaceParams::default(),
        }
    }

    /// Domain minimum corner.
    pub fn min(&self) -> Pt3 {
        p3(&self.domain.min)
    }

    /// Domain maximum corner.
    pub fn max(&self) -> Pt3 {
        p3(&self.domain.max)
    }

    /// Gravity vector.
    pub fn g(&self) -> Vec3 {
        Vec3::new(self.gravity[0], self.gravity[1], self.gravity[2])
    }

    /// Checks every numeric field (finite, in range); the error names the field.
    pub fn validate(&self) -> Result<()> {
        let bad = |m: &str| Err(SimError::InvalidScene(m.to_string()));
        if !self.domain.min.iter().chain(&self.domain.max).all(|v| v.is_finite()) {
            return bad("domain: non-finite corner");
        }
        if (0..3).any(|a| self.domain.max[a] <= self.domain.min[a]) {
            return bad("domain: max must exceed min on every axis");
        }
        if !(self.duration.is_finite() && self.duration >= 0.0 && self.fps.is_finite() && self.fps > 0.0) {
            return bad("duration/fps: must be finite, duration ≥ 0, fps > 0");
        }
        if !self.gravity.iter().chain(&self.initial_velocity).all(|v| v.is_finite()) {
            return bad("gravity/initial_velocity: non-finite");
        }
        if !self.liquid.iter().chain(&self.obstacles).chain(&self.outflow).all(Shape::finite)
            || !self.moving_liquid.iter().all(|(s, v)| s.finite() && v.iter().all(|x| x.is_finite()))
        {
            return bad("liquid/obstacles/outflow: non-finite or non-positive shape parameter");
        }
        if self.liquid.iter().chain(self.moving_liquid.iter().map(|(s, _)| s)).chain(&self.outflow).any(Shape::has_mesh)
        {
            return bad("liquid/moving_liquid/outflow: Mesh shapes are allowed only as obstacles");
        }
        for (k, s) in self.obstacles.iter().enumerate() {
            if let Shape::Subtract { .. } = s {
                if s.has_mesh() {
                    return Err(SimError::InvalidScene(format!("obstacles[{k}]: a Mesh cannot be part of a Subtract")));
                }
            }
        }
        for (k, m) in self.moving_obstacles.iter().enumerate() {
            if !m.shape.finite() || (matches!(m.shape, Shape::Subtract { .. }) && m.shape.has_mesh()) {
                return Err(SimError::InvalidScene(format!(
                    "moving_obstacles[{k}].shape: non-finite parameter or a Mesh inside a Subtract"
                )));
            }
            m.path.validate().map_err(|e| SimError::InvalidScene(format!("moving_obstacles[{k}].path: {e}")))?;
        }
        for (k, e) in self.emitters.iter().enumerate() {
            e.validate(&format!("emitters[{k}]")).map_err(SimError::InvalidScene)?;
        }
        let f = &self.flip;
        if !(f.cfl > 0.0 && f.cfl.is_finite() && f.dt_max > 0.0 && f.dt_min > 0.0 && f.dt_min <= f.dt_max) {
            return bad("flip: cfl > 0, 0 < dt_min ≤ dt_max required");
        }
        if f.remesh_interval == 0 {
            return bad("flip.remesh_interval must be ≥ 1");
        }
        if let DtPolicy::Fixed(dt) = f.dt_policy {
            if !(dt > 0.0 && dt.is_finite()) {
                return bad("flip.dt_policy: Fixed(dt) needs dt > 0");
            }
        }
        if ![f.pic_base, f.pic_floor, f.pic_radius_exponent].iter().all(|v| v.is_finite() && *v >= 0.0) {
            return bad("flip: pic_base, pic_floor, pic_radius_exponent must be finite and ≥ 0");
        }
        let p = &self.pressure;
        if !(p.tol > 0.0
            && p.tol.is_finite()
            && p.ghost_tolerance >= 0.0
            && p.min_interface_fraction > 0.0
            && p.min_interface_fraction < 1.0
            && (0.0..0.5).contains(&p.surface_snap))
        {
            return bad("pressure: tol > 0, ghost_tolerance ≥ 0, 0 < min_interface_fraction < 1, 0 ≤ surface_snap < 0.5 required");
        }
        let q = &self.particles;
        if !(q.ballistic_factor > 0.0 && q.split_ratio > 1.0 && q.merge_ratio < 1.0 && q.merge_ratio > 0.0) {
            return bad("particles: ballistic_factor > 0, split_ratio > 1, 0 < merge_ratio < 1 required");
        }
        if !(q.sampling_jitter.is_finite() && (0.0..0.5).contains(&q.sampling_jitter)) {
            return bad("particles.sampling_jitter must lie in [0, 0.5)");
        }
        if !q.lattice_offset.iter().all(|v| v.is_finite() && v.abs() < 1.0) {
            return bad("particles.lattice_offset components must be finite and lie in (−1, 1)");
        }
        let t = &self.transfer;
        if !(t.support > 0.0 && t.omega_valid > 0.0 && t.omega_blend >= t.omega_valid) {
            return bad("transfer: support > 0, 0 < omega_valid ≤ omega_blend required");
        }
        self.sizing.validate().map_err(|e| SimError::InvalidScene(e.to_string()))?;
        self.surface.validate().map_err(|e| SimError::InvalidScene(e.to_string()))?;
        Ok(())
    }

    /// Liquid SDF at `x` (union of `liquid` and `moving_liquid`).
    pub fn liquid_sdf(&self, x: &Pt3) -> f64 {
        union_sdf(&self.liquid, x).min(self.moving_liquid.iter().map(|(s, _)| s.sdf(x)).fold(f64::INFINITY, f64::min))
    }

    /// Initial stored particle level set (spec §3.11.3 "at t = 0, φ_p comes from the analytic
    /// liquid SDF"): the liquid SDF with box faces that lie on the domain boundary pushed outward,
    /// so a closed wall is not mistaken for a free surface (otherwise the interior radii shrink
    /// next to walls and the hull level set gets holes there).
    pub fn initial_phi(&self, x: &Pt3) -> f64 {
        let ext: f64 = (0..3).map(|a| self.domain.max[a] - self.domain.min[a]).fold(0.0, f64::max);
        let widen = |s: &Shape| -> Shape {
            match s {
                Shape::Box { min, max } => {
                    let (mut lo, mut hi) = (*min, *max);
                    for a in 0..3 {
                        if (lo[a] - self.domain.min[a]).abs() <= 1e-9 * ext {
                            lo[a] -= ext;
                        }
                        if (hi[a] - self.domain.max[a]).abs() <= 1e-9 * ext {
                            hi[a] += ext;
                        }
                    }
                    Shape::Box { min: lo, max: hi }
                }
                other => other.clone(),
            }
        };
        let a = self.liquid.iter().map(|s| widen(s).sdf(x)).fold(f64::INFINITY, f64::min);
        a.min(self.moving_liquid.iter().map(|(s, _)| widen(s).sdf(x)).fold(f64::INFINITY, f64::min))
    }

    /// Initial velocity at a liquid point `x`.
    pub fn velocity_at(&self, x: &Pt3) -> Vec3 {
        for (s, v) in &self.moving_liquid {
            if s.sdf(x) < 0.0 {
                return Vec3::new(v[0], v[1], v[2]);
            }
        }
        Vec3::new(self.initial_velocity[0], self.initial_velocity[1], self.initial_velocity[2])
    }

    /// SDF of the static analytic obstacles (+∞ without; `Mesh` obstacles and moving obstacles
    /// are not included: the simulator evaluates every obstacle through
    /// [`crate::obstacle::Obstacles`]).
    pub fn solid_sdf(&self, x: &Pt3) -> f64 {
        union_sdf(&self.obstacles, x)
    }

    /// Whether the scene has any obstacle (static, mesh or moving).
    pub fn has_obstacles(&self) -> bool {
        !self.obstacles.is_empty() || !self.moving_obstacles.is_empty()
    }

    /// Makes every relative `Mesh` path absolute against `dir` (the scene file's folder).
    pub fn resolve_paths(&mut self, dir: &std::path::Path) {
        let fix = |s: &mut Shape| {
            if let Shape::Mesh { path } = s {
                if std::path::Path::new(path.as_str()).is_relative() {
                    *path = dir.join(path.as_str()).to_string_lossy().into_owned();
                }
            }
        };
        self.obstacles.iter_mut().for_each(fix);
        self.moving_obstacles.iter_mut().for_each(|m| fix(&mut m.shape));
    }
}

//! Optional effects (shells.md §2 "effects", §3.5, §10). Each is evaluated only if present:
//! `gravity: None` costs nothing, `wind: None` skips the wind pass, `collision: None` builds no
//! collision structure at all, an empty `custom` list evaluates nothing.

use crate::error::{Error, Result};
use geom_core::math::{Mat3, Pt3, Vec3};
use serde::{Deserialize, Serialize};
use std::sync::Arc;

/// Everything optional a scene can ask for.
#[derive(Clone, Default)]
pub struct Effects {
    /// Gravitational acceleration (m/s²); `None` = no gravity.
    pub gravity: Option<Vec3>,
    /// Aerodynamic drag and lift in a gusty wind field.
    pub wind: Option<Wind>,
    /// Rigid obstacles (need `collision` to act).
    pub obstacles: Vec<Obstacle>,
    /// Cloth–cloth collisions (need `collision`).
    pub self_collision: bool,
    /// Collision settings; `None` = no collision code runs.
    pub collision: Option<CollisionSettings>,
    /// User force hooks; empty = nothing evaluated.
    pub custom: Vec<Arc<dyn ExternalForce>>,
}

impl std::fmt::Debug for Effects {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Effects")
            .field("gravity", &self.gravity)
            .field("wind", &self.wind)
            .field("obstacles", &self.obstacles)
            .field("self_collision", &self.self_collision)
            .field("collision", &self.collision)
            .field("custom", &self.custom.len())
            .finish()
    }
}

impl Effects {
    /// Validates every parameter (finite, ranges).
    pub fn validate(&self) -> Result<()> {
        if let Some(g) = self.gravity {
            if g.iter().any(|x| !x.is_finite()) {
                return Err(Error::NonFinite("gravity"));
            }
        }
        if let Some(w) = &self.wind {
            w.validate()?;
        }
        if let Some(c) = &self.collision {
            c.validate()?;
        }
        for o in &self.obstacles {
            o.validate()?;
        }
        Ok(())
    }
}

/// 3×3 blocks `(row vertex, column vertex, block)` added by an [`ExternalForce`]'s Jacobian.
#[derive(Clone, Debug, Default)]
pub struct BlockTriplets {
    /// The blocks; repeated keys are summed.
    pub blocks: Vec<(u32, u32, Mat3)>,
}

impl BlockTriplets {
    /// Adds a block.
    pub fn push(&mut self, i: u32, j: u32, m: Mat3) {
        self.blocks.push((i, j, m));
    }
}

/// User force hook (cloth-fit drag models, scripted forces). Forces are added at the Newton
/// linearisation point. Jacobians are optional; the contribution −h·J_v − h²·J_x they add to
/// the system matrix must be symmetric (give both (i, j) and (j, i)) and should be PSD. Blocks
/// must lie in the fixed sparse pattern: vertex-diagonal, or two vertices sharing a triangle;
/// others give `BadParameter` at the step.
pub trait ExternalForce: Send + Sync {
    /// Adds forces (N) at time `t` (s) for positions `q` and velocities `v` into `f`.
    fn add_forces(&self, t: f64, q: &[Pt3], v: &[Vec3], f: &mut [Vec3]);
    /// Adds ∂f/∂q into `jx` and ∂f/∂v into `jv` (optional).
    fn add_jacobians(&self, _t: f64, _q: &[Pt3], _v: &[Vec3], _jx: &mut BlockTriplets, _jv: &mut BlockTriplets) {}
}

/// Wind with quadratic normal drag, weak tangential drag and a seeded gust field (§3.5).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Wind {
    /// Base wind velocity (m/s).
    pub base: Vec3,
    /// Gain schedule (t in s, gain) interpolated linearly, held outside; empty = gain 1.
    #[serde(default)]
    pub schedule: Vec<(f64, f64)>,
    /// Normal drag coefficient C_n.
    #[serde(default = "d_cn")]
    pub drag_normal: f64,
    /// Tangential drag coefficient C_t.
    #[serde(default = "d_ct")]
    pub drag_tangent: f64,
    /// Air density ρ_air (kg/m³).
    #[serde(default = "d_rho")]
    pub air_density: f64,
    /// Turbulence amplitude a (relative).
    #[serde(default = "d_turb")]
    pub turbulence: f64,
    /// Gust wavelength λ (m).
    #[serde(default = "d_wl")]
    pub turb_wavelength: f64,
    /// Gust angular frequency ω (rad/s).
    #[serde(default = "d_wf")]
    pub turb_freq: f64,
    /// Seed of the gust directions and phases.
    #[serde(default)]
    pub seed: u64,
}

fn d_cn() -> f64 {
    1.0
}
fn d_ct() -> f64 {
    0.05
}
fn d_rho() -> f64 {
    1.2
}
fn d_turb() -> f64 {
    0.3
}
fn d_wl() -> f64 {
    1.0
}
fn d_wf() -> f64 {
    6.0
}

impl Wind {
    /// A steady wind with the default coefficients and no turbulence.
    pub fn steady(base: Vec3) -> Self {
        Self {
            base,
            schedule: Vec::new(),
            drag_normal: d_cn(),
            drag_tangent: d_ct(),
            air_density: d_rho(),
            turbulence: 0.0,
            turb_wavelength: d_wl(),
            turb_freq: d_wf(),
            seed: 0,
        }
    }

    fn validate(&self) -> Result<()> {
        let all = [
            self.drag_normal,
            self.drag_tangent,
            self.air_density,
            self.turbulence,
            self.turb_wavelength,
            self.turb_freq,
        ];
        if all.iter().chain(self.base.iter()).any(|x| !x.is_finite())
            || self.schedule.iter().any(|(t, g)| !t.is_finite() || !g.is_finite())
        {
            return Err(Error::NonFinite("wind parameters"));
        }
        if self.drag_normal < 0.0 || self.drag_tangent < 0.0 || self.air_density < 0.0 || self.turb_wavelength <= 0.0 {
            return Err(Error::BadParameter(format!(
                "wind: drag coefficients and air density must be ≥ 0 and the wavelength > 0, got {all:?}"
            )));
        }
        Ok(())
    }
}

/// Rigid obstacle shape.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum ObstacleShape {
    /// Half-space {x : n̂·x ≤ offset} is solid; the cloth stays on the side n̂·x ≥ offset.
    Plane {
        /// Outward normal (normalised on use).
        normal: Vec3,
        /// n̂·x of the surface (m).
        offset: f64,
    },
    /// Capsule around the segment a–b (m).
    Capsule {
        /// First end.
        a: Pt3,
        /// Second end.
        b: Pt3,
        /// Radius (m).
        radius: f64,
    },
    /// Ball (m).
    Sphere {
        /// Centre.
        center: Pt3,
        /// Radius (m).
        radius: f64,
    },
    /// Closed triangle mesh (outward faces).
    Mesh {
        /// Vertices (m).
        verts: Vec<Pt3>,
        /// Triangles.
        tris: Vec<[u32; 3]>,
    },
}

pub use geom_core::kinematic::KinematicPath;

/// A rigid (static or kinematic) obstacle.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Obstacle {
    /// Shape in its rest placement.
    pub shape: ObstacleShape,
    /// Cloth–obstacle Coulomb friction μ.
    #[serde(default = "d_ofric")]
    pub friction: f64,
    /// Rigid motion; `None` = static.
    #[serde(default)]
    pub motion: Option<KinematicPath>,
}

fn d_ofric() -> f64 {
    0.5
}

impl Obstacle {
    fn validate(&self) -> Result<()> {
        let bad = |s: String| Err(Error::BadParameter(s));
        if !self.friction.is_finite() || self.friction < 0.0 {
            return bad(format!("obstacle friction must be finite and ≥ 0, got {}", self.friction));
        }
        match &self.shape {
            ObstacleShape::Plane { normal, offset } => {
                if !(normal.norm() > 0.0) || !offset.is_finite() || normal.iter().any(|x| !x.is_finite()) {
                    return bad(format!("plane needs a finite non-zero normal, got {normal:?}"));
                }
            }
            ObstacleShape::Capsule { radius, a, b } => {
                if !(*radius > 0.0) || !radius.is_finite() || a.iter().chain(b.iter()).any(|x| !x.is_finite()) {
                    return bad(format!("capsule needs finite ends and radius > 0, got {radius}"));
                }
            }
            ObstacleShape::Sphere { radius, center } => {
                if !(*radius > 0.0) || !radius.is_finite() || center.iter().any(|x| !x.is_finite()) {
                    return bad(format!("sphere needs a finite centre and radius > 0, got {radius}"));
                }
            }
            ObstacleShape::Mesh { verts, tris } => {
                if tris.is_empty() {
                    return bad("obstacle mesh has no triangles".into());
                }
                if verts.iter().any(|p| p.iter().any(|x| !x.is_finite())) {
                    return Err(Error::NonFinite("obstacle mesh vertices"));
                }
                if tris.iter().flatten().any(|&v| v as usize >= verts.len()) {
                    return bad("obstacle mesh has an out-of-range index".into());
                }
            }
        }
        if let Some(m) = &self.motion {
            m.validate().map_err(|e| Error::BadParameter(format!("obstacle motion: {e}")))?;
        }
        Ok(())
    }
}

/// The contact model.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum ContactMethod {
    /// Incremental Potential Contact (Li et al. 2020, 2021): barrier energies inside the implicit
    /// Newton solve with a CCD-clamped line search — intersection-free by construction and
    /// energy-stable (module `contact`). The default.
    #[default]
    Ipc,
    /// The seed's velocity filter (Bridson, Fedkiw, Anderson 2002): proximity impulses, CCD,
    /// rigid impact zones and freezing after the linear solve (module `collision`).
    Bridson,
}

/// Collision settings (§3.9, §4).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CollisionSettings {
    /// The contact model (default IPC).
    #[serde(default)]
    pub method: ContactMethod,
    /// Contact distance (m): IPC's barrier activation distance d̂, Bridson's proximity
    /// thickness h_c; ≤ 0 means the default clamp(0.1·mean edge, 1 mm, 1 cm).
    #[serde(default)]
    pub thickness: f64,
    /// Cloth–cloth Coulomb friction μ.
    #[serde(default = "d_fric")]
    pub friction: f64,
    /// Repulsion spring k_rep (N/m); `None` = membrane stiffness.
    #[serde(default)]
    pub repulsion_stiffness: Option<f64>,
    /// Continuous collision detection on/off (off = proximity-only preview).
    #[serde(default = "d_true")]
    pub ccd: bool,
    /// Inelastic CCD passes before impact zones.
    #[serde(default = "d_passes")]
    pub ccd_passes: u32,
    /// Impact-zone iterations.
    #[serde(default = "d_zones")]
    pub impact_zone_iters: u32,
    /// Target separation speed as a fraction of h_c per step.
    #[serde(default = "d_sep")]
    pub separation_speed_frac: f64,
    /// IPC barrier stiffness κ (N/m); `None` = 100·m̄·max(|g|, 1 m/s²)/d̂ (m̄ the mean vertex
    /// mass), doubled during the run while gaps fall below 1 % of d̂.
    #[serde(default)]
    pub barrier_stiffness: Option<f64>,
    /// IPC friction's static-to-sliding transition speed ε_v (m/s).
    #[serde(default = "d_epsv")]
    pub friction_eps_v: f64,
    /// IPC Newton tolerance on the largest velocity update ‖Δv‖∞ (m/s).
    #[serde(default = "d_ntol")]
    pub newton_tol: f64,
    /// IPC Newton iteration cap per step (the step is taken, and counted, if it is reached).
    #[serde(default = "d_nmax")]
    pub max_newton_iters: u32,
}

fn d_epsv() -> f64 {
    1e-3
}
fn d_ntol() -> f64 {
    1e-2
}
fn d_nmax() -> u32 {
    20
}

fn d_fric() -> f64 {
    0.3
}
fn d_true() -> bool {
    true
}
fn d_passes() -> u32 {
    5
}
fn d_zones() -> u32 {
    100
}
fn d_sep() -> f64 {
    0.1
}

impl Default for CollisionSettings {
    fn default() -> Self {
        Self {
            method: ContactMethod::Ipc,
            thickness: 0.0,
            friction: d_fric(),
            repulsion_stiffness: None,
            ccd: true,
            ccd_passes: d_passes(),
            impact_zone_iters: d_zones(),
            separation_speed_frac: d_sep(),
            barrier_stiffness: None,
            friction_eps_v: d_epsv(),
            newton_tol: d_ntol(),
            max_newton_iters: d_nmax(),
        }
    }
}

impl CollisionSettings {
    fn validate(&self) -> Result<()> {
        if !self.thickness.is_finite() || !self.friction.is_finite() || !self.separation_speed_frac.is_finite() {
            return Err(Error::NonFinite("collision settings"));
        }
        if self.friction < 0.0 || !(0.0..=1.0).contains(&self.separation_speed_frac) {
            return Err(Error::BadParameter(format!(
                "collision: friction ≥ 0 and separation_speed_frac in [0, 1] expected, got {} and {}",
                self.friction, self.separation_speed_frac
            )));
        }
        if let Some(k) = self.barrier_stiffness {
            if !(k > 0.0) || !k.is_finite() {
                return Err(Error::BadParameter(format!("barrier_stiffness must be finite and > 0, got {k}")));
            }
        }
        if !(self.friction_eps_v > 0.0) || !self.friction_eps_v.is_finite() {
            return Err(Error::BadParameter(format!(
                "friction_eps_v must be finite and > 0 m/s, got {}",
                self.friction_eps_v
            )));
        }
        if !(self.newton_tol > 0.0) || !self.newton_tol.is_finite() {
            return Err(Error::BadParameter(format!("newton_tol must be finite and > 0 m/s, got {}", self.newton_tol)));
        }
        if self.max_newton_iters == 0 {
            return Err(Error::BadParameter("max_newton_iters must be ≥ 1".into()));
        }
        if let Some(k) = self.repulsion_stiffness {
            if !(k >= 0.0) || !k.is_finite() {
                return Err(Error::BadParameter(format!("repulsion_stiffness must be finite and ≥ 0, got {k}")));
            }
        }
        Ok(())
    }
}

//! Sizing functions (spec §3.12): the metrics (liquid-surface curvature, solid proximity and
//! curvature, turbulence, user boxes, visibility from a camera, depth floor, surface band), their
//! combination and the quantisation of the desired radius to octree levels.
//!
//! Combination (spec §3.12, §12 G6):
//! `S(x) = clamp( min( B(x), max( D(x), V(x, min(κ_liquid, κ_solid, T, S_user)(x)) ) ), r_min, r_max )`.
//! Each metric is opt-in: a `None` in [`SizingParams`] is not instantiated and costs nothing.

mod camera;
mod metrics;

use geom_core::math::Pt3;
use serde::{Deserialize, Serialize};

pub use camera::{CameraPath, Frustum, Keyframe, VisibilityParams};
pub use metrics::{
    fd_laplacian, LiquidCurvature, SolidCurvature, SurfaceCurvature, Turbulence, UserBox, UserBoxes, TURBULENCE_EPS,
};

/// Cube edge over particle radius, `c_h = 4` (a cube holds 2×2×2 particles of radius h/4; §12 G9).
pub const C_H: f64 = 4.0;

/// Scene-file sizing parameters (spec §2 `sizing: (...)`, defaults of spec §4).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SizingParams {
    /// `κ_liquid` coefficient (paper 0.8); `None` = off.
    pub liquid_curvature: Option<f64>,
    /// `κ_solid` coefficient (paper 1.6); `None` = off.
    pub solid_curvature: Option<f64>,
    /// Turbulence coefficient `c_T` (0.05); `None` = off.
    pub turbulence: Option<f64>,
    /// Camera visibility; `None` = off.
    pub visibility: Option<VisibilityParams>,
    /// Depth floor `γ_d`: radius growth per metre of depth (default `Some(0.25)`).
    pub depth_floor: Option<f64>,
    /// Surface band width in finest cubes (`B = r_min` within it); `None` = off.
    pub surface_band: Option<f64>,
    /// Solid-proximity band width in finest cubes (ours, issue 26): liquid within this distance of
    /// an obstacle (`solid SDF < w h_min`) asks for `r_min`, overriding the depth floor like the
    /// surface band. The spec's solid-curvature metric leaves flat obstacle faces coarse, where
    /// liquid converging into holes then runs on coarse cells (S7); `None` = off.
    pub solid_proximity: Option<f64>,
    /// User boxes with radii; `None` = off.
    pub user: Option<Vec<UserBox>>,
    /// Temporal smoothing (spec §3.12, optional): at a remesh a particle's demanded radius is
    /// limited to twice the radius of the leaf it sits in, `S ← min(S, 2 S_prev)`, so that
    /// resolution is thrown away at most one level per remesh. Off by default.
    pub temporal_smoothing: bool,
}

impl Default for SizingParams {
    fn default() -> Self {
        Self {
            liquid_curvature: None,
            solid_curvature: None,
            turbulence: None,
            visibility: None,
            depth_floor: Some(0.25),
            surface_band: None,
            solid_proximity: None,
            user: None,
            temporal_smoothing: false,
        }
    }
}

impl SizingParams {
    /// Checks ranges (coefficients finite and > 0, depth floor ≥ 0, band > 0, user radii > 0,
    /// camera); the error names the field.
    pub fn validate(&self) -> geom_core::Result<()> {
        let bad = |w: &str| Err(geom_core::Error::InvalidParameter(format!("sizing.{w}")));
        let pos = |v: Option<f64>| v.is_none_or(|c| c > 0.0 && c.is_finite());
        if !pos(self.liquid_curvature) {
            return bad("liquid_curvature must be finite and > 0");
        }
        if !pos(self.solid_curvature) {
            return bad("solid_curvature must be finite and > 0");
        }
        if !pos(self.turbulence) {
            return bad("turbulence must be finite and > 0");
        }
        if !pos(self.surface_band) {
            return bad("surface_band must be finite and > 0");
        }
        if !pos(self.solid_proximity) {
            return bad("solid_proximity must be finite and > 0");
        }
        if !self.depth_floor.is_none_or(|g| g >= 0.0 && g.is_finite()) {
            return bad("depth_floor must be finite and >= 0");
        }
        if let Some(u) = &self.user {
            if u.iter().any(|b| !(b.radius > 0.0 && b.radius.is_finite())) {
                return bad("user: every box radius must be finite and > 0");
            }
        }
        if let Some(v) = &self.visibility {
            v.validate()?;
        }
        Ok(())
    }
}

/// What the metrics may look at when evaluated (spec §3.12). Fields a metric needs but finds
/// `None` make it return "no opinion" (`+∞`).
#[derive(Clone, Copy)]
pub struct SizingContext<'a> {
    /// Smallest admissible radius `h_min / c_h` (m).
    pub r_min: f64,
    /// Largest admissible radius `h_root / c_h` (m).
    pub r_max: f64,
    /// Finest cube edge (m).
    pub h_min: f64,
    /// Simulation time (s), for the camera path.
    pub time: f64,
    /// Reference speed `U_ref = √(g H_ref)` of the turbulence metric (m/s).
    pub u_ref: f64,
    /// Liquid level set at a point (m, negative inside).
    pub phi: Option<&'a (dyn Fn(&Pt3) -> f64 + Sync)>,
    /// Curvature of the current liquid surface.
    pub surface: Option<&'a SurfaceCurvature>,
    /// Vorticity magnitude `|ω|` at a point (1/s).
    pub vorticity: Option<&'a (dyn Fn(&Pt3) -> f64 + Sync)>,
    /// Signed distance to the obstacles (m, negative inside a solid).
    pub solid_sdf: Option<&'a (dyn Fn(&Pt3) -> f64 + Sync)>,
}

impl<'a> SizingContext<'a> {
    /// A context with only the radius bounds and `h_min` set (`r_min = h_min / c_h`,
    /// `r_max = h_root / c_h`); fill the optional fields as needed.
    pub fn new(h_min: f64, h_root: f64) -> Self {
        Self {
            r_min: h_min / C_H,
            r_max: h_root / C_H,
            h_min,
            time: 0.0,
            u_ref: 1.0,
            phi: None,
            surface: None,
            vorticity: None,
            solid_sdf: None,
        }
    }
}

/// One sizing metric: desired particle radius at `x` (m), `+∞` = no demand (spec §2).
pub trait SizingMetric: Sync + Send {
    /// Desired radius at `x` (m) or `+∞`.
    fn radius_at(&self, x: &Pt3, ctx: &SizingContext) -> f64;
    /// Short name (for statistics and plots).
    fn name(&self) -> &'static str;
    /// Whether the metric describes the obstacles (a function of position alone): such metrics
    /// are also sampled on a grid over the domain (spec §3.12: "obstacle metrics add demands
    /// sampled on a coarse grid of points"), so the mesh is graded around obstacles before the
    /// liquid reaches them. Default `false`.
    fn is_obstacle_metric(&self) -> bool {
        false
    }
}

/// The combined sizing function of a scene (spec §2, §3.12).
pub struct Sizing {
    /// Metrics combined by `min` (liquid curvature, solid curvature, turbulence, user, and any
    /// metric pushed from code).
    pub metrics: Vec<Box<dyn SizingMetric>>,
    /// Camera visibility `V(x, y)`.
    pub visibility: Option<VisibilityParams>,
    /// Depth floor `γ_d`.
    pub depth_floor: Option<f64>,
    /// Surface band width in finest cubes.
    pub surface_band: Option<f64>,
    /// Solid-proximity band width in finest cubes ([`SizingParams::solid_proximity`]).
    pub solid_proximity: Option<f64>,
}

impl std::fmt::Debug for Sizing {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Sizing")
            .field("metrics", &self.metrics.iter().map(|m| m.name()).collect::<Vec<_>>())
            .field("visibility", &self.visibility)
            .field("depth_floor", &self.depth_floor)
            .field("surface_band", &self.surface_band)
            .finish()
    }
}

impl Sizing {
    /// Instantiates exactly the metrics switched on in `p` (validated first).
    pub fn from_params(p: &SizingParams) -> geom_core::Result<Self> {
        p.validate()?;
        let mut metrics: Vec<Box<dyn SizingMetric>> = Vec::new();
        if let Some(c) = p.liquid_curvature {
            metrics.push(Box::new(LiquidCurvature { coeff: c }));
        }
        if let Some(c) = p.solid_curvature {
            metrics.push(Box::new(SolidCurvature { coeff: c }));
        }
        if let Some(c) = p.turbulence {
            metrics.push(Box::new(Turbulence { coeff: c }));
        }
        if let Some(b) = &p.user {
            metrics.push(Box::new(UserBoxes { boxes: b.clone() }));
        }
        Ok(Self {
            metrics,
            visibility: p.visibility.clone(),
            depth_floor: p.depth_floor,
            surface_band: p.surface_band,
            solid_proximity: p.solid_proximity,
        })
    }

    /// Whether an obstacle metric ([`SizingMetric::is_obstacle_metric`]) is on.
    pub fn has_obstacle_metric(&self) -> bool {
        self.metrics.iter().any(|m| m.is_obstacle_metric())
    }

    /// The smallest radius the obstacle metrics ask for at `x` (m), `+∞` when none has an opinion
    /// (neither the depth floor, the band nor the visibility apply: they describe the liquid and
    /// the camera, not the obstacle).
    pub fn obstacle_radius_at(&self, x: &Pt3, ctx: &SizingContext) -> f64 {
        self.metrics
            .iter()
            .filter(|m| m.is_obstacle_metric())
            .map(|m| m.radius_at(x, ctx))
            .fold(f64::INFINITY, f64::min)
    }

    /// Whether any term needs the level set (depth floor or surface band).
    pub fn needs_phi(&self) -> bool {
        self.depth_floor.is_some() || self.surface_band.is_some()
    }

    /// Whether the liquid-curvature metric is on (the caller must then extract the surface and
    /// supply [`SizingContext::surface`]).
    pub fn needs_surface(&self) -> bool {
        self.metrics.iter().any(|m| m.name() == "liquid_curvature")
    }

    /// Desired particle radius at `x` (m), `+∞` = no demand; φ from `ctx.phi` when needed.
    pub fn radius_at(&self, x: &Pt3, ctx: &SizingContext) -> f64 {
        let phi = if self.needs_phi() { ctx.phi.map(|f| f(x)) } else { None };
        self.radius_at_phi(x, phi, ctx)
    }

    /// [`Sizing::radius_at`] with the level-set value at `x` supplied directly (e.g. a particle's
    /// stored `φ_p`): `S = clamp(min(B, max(D, V(min(metrics)))), r_min, r_max)`, or `+∞` when the
    /// combination has no finite demand (the octree then keeps the coarsest level).
    ///
    /// `min(metrics)` over an empty metric list is `r_min` (ours, spec §12 G6 leaves it open): the
    /// depth floor and visibility only make sense relative to a default of "finest", as in S1a
    /// (band + depth floor grade a pool) and S6 (visibility alone).
    pub fn radius_at_phi(&self, x: &Pt3, phi: Option<f64>, ctx: &SizingContext) -> f64 {
        // With no min-combined metric switched on, the liquid asks for the finest size (a uniform
        // simulation); the depth floor, band and visibility then grade it (spec S1a, S6). With
        // metrics on, "no opinion" from all of them means no demand (+∞).
        let m = if self.metrics.is_empty() {
            ctx.r_min
        } else {
            self.metrics.iter().map(|m| m.radius_at(x, ctx)).fold(f64::INFINITY, f64::min)
        };
        let v = match &self.visibility {
            Some(vis) => {
                if vis.frustum(ctx.time).contains(x, vis.margin_r_max * ctx.r_max) {
                    m
                } else {
                    ctx.r_max
                }
            }
            None => m,
        };
        let d = match (self.depth_floor, phi) {
            (Some(g), Some(p)) => ctx.r_min + g * (-p).max(0.0),
            _ => 0.0,
        };
        let b = match (self.surface_band, phi) {
            (Some(w), Some(p)) if p > -w * ctx.h_min => ctx.r_min,
            _ => f64::INFINITY,
        };
        let near_solid = match (self.solid_proximity, ctx.solid_sdf) {
            (Some(w), Some(f)) if f(x) < w * ctx.h_min => ctx.r_min,
            _ => f64::INFINITY,
        };
        let s = b.min(near_solid).min(d.max(v));
        if s.is_finite() {
            s.clamp(ctx.r_min, ctx.r_max)
        } else {
            f64::INFINITY
        }
    }

    /// Temporal smoothing `S ← min(S, 2 S_prev)` (spec §3.12): resolution is thrown away at most
    /// by a factor 2 in radius per remesh.
    pub fn temporal_limit(s: f64, s_prev: f64) -> f64 {
        s.min(2.0 * s_prev)
    }
}

/// Octree level for a desired radius `s` (m): the target cube size `c_h s` rounded *down* to a
/// level size `h_root / 2^ℓ`, i.e. `ℓ = ⌈log2(h_root / (c_h s))⌉`, clamped to `[0, max_level]`
/// (spec §3.2). `s = +∞` (no demand) gives level 0.
pub fn level_for_radius(s: f64, h_root: f64, max_level: u8) -> u8 {
    if s.is_nan() || s <= 0.0 {
        return max_level;
    }
    if !s.is_finite() {
        return 0;
    }
    let ratio = h_root / (C_H * s);
    if ratio <= 1.0 {
        return 0;
    }
    // Exact powers of two land on their level: guard the ceil against log2 round-off.
    let mut l = ratio.log2().ceil().max(0.0) as u32;
    if l > 0 && h_root / 2f64.powi(l as i32 - 1) <= C_H * s {
        l -= 1;
    }
    l.min(max_level as u32) as u8
}

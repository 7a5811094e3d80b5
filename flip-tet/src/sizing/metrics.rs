//! The individual sizing metrics of spec §3.12. Each returns a desired particle radius (m), or
//! `+∞` when it has no opinion at `x`.

use geom_core::math::{Pt3, Vec3};
use geom_core::mesh::TriMesh;
use geom_core::spatial::KdTree;
use serde::{Deserialize, Serialize};

use super::{SizingContext, SizingMetric};
use crate::transfer::w_smooth;

/// Curvature of the liquid surface mesh, looked up at the nearest surface vertex (spec §3.12
/// "extrapolated to the particle through a nearest-vertex query").
#[derive(Clone, Debug)]
pub struct SurfaceCurvature {
    tree: KdTree,
    kappa: Vec<f64>,
}

impl SurfaceCurvature {
    /// From a (smoothed) surface mesh and its per-vertex curvature `κ_v` (1/m, e.g. from
    /// [`crate::surface::vertex_curvature`]). Panics if `kappa.len() != mesh.n_vertices()`.
    pub fn new(mesh: &TriMesh, kappa: Vec<f64>) -> Self {
        assert_eq!(kappa.len(), mesh.n_vertices(), "SurfaceCurvature: one curvature per vertex");
        Self { tree: KdTree::build(&mesh.positions), kappa }
    }

    /// Curvature at the surface vertex nearest to `x`; `None` for an empty surface.
    pub fn at(&self, x: &Pt3) -> Option<f64> {
        self.tree.nearest(x).map(|(i, _)| self.kappa[i as usize])
    }
}

/// `κ_liquid(x) = c / κ(x)` (paper: c = 0.8), `κ` the curvature of the nearest surface vertex.
#[derive(Clone, Copy, Debug)]
pub struct LiquidCurvature {
    /// Coefficient `c`.
    pub coeff: f64,
}

impl SizingMetric for LiquidCurvature {
    fn radius_at(&self, x: &Pt3, ctx: &SizingContext) -> f64 {
        match ctx.surface.and_then(|s| s.at(x)) {
            Some(k) if k > 0.0 => self.coeff / k,
            _ => f64::INFINITY,
        }
    }
    fn name(&self) -> &'static str {
        "liquid_curvature"
    }
}

/// Seven-point finite-difference Laplacian of `f` at `x` with step `eps` (`O(eps²)` error).
pub fn fd_laplacian(f: &(dyn Fn(&Pt3) -> f64 + Sync), x: &Pt3, eps: f64) -> f64 {
    let f0 = f(x);
    let mut s = 0.0;
    for k in 0..3 {
        let mut e = Vec3::zeros();
        e[k] = eps;
        s += f(&(x + e)) + f(&(x - e)) - 2.0 * f0;
    }
    s / (eps * eps)
}

/// `κ_solid(x) = c / (W_smooth(d_solid(x), r_max) · κ_s(x))` (paper: c = 1.6; §12 G7; `W_smooth` is
/// [`crate::transfer::w_smooth`], spec §5 P10), with
/// `κ_s = |∇²φ_s|` of the obstacle SDF by finite differences (step `h_min / 4`).
#[derive(Clone, Copy, Debug)]
pub struct SolidCurvature {
    /// Coefficient `c`.
    pub coeff: f64,
}

impl SizingMetric for SolidCurvature {
    fn radius_at(&self, x: &Pt3, ctx: &SizingContext) -> f64 {
        let Some(sdf) = ctx.solid_sdf else { return f64::INFINITY };
        let d = sdf(x);
        let w = w_smooth(d, ctx.r_max);
        if w.is_nan() || w <= 0.0 {
            return f64::INFINITY;
        }
        let k = fd_laplacian(sdf, x, 0.25 * ctx.h_min).abs();
        if k > 0.0 {
            self.coeff / (w * k)
        } else {
            f64::INFINITY
        }
    }
    fn name(&self) -> &'static str {
        "solid_curvature"
    }
    fn is_obstacle_metric(&self) -> bool {
        true
    }
}

/// Vorticity floor `ε` of the turbulence metric (1/s).
pub const TURBULENCE_EPS: f64 = 1e-9;

/// `T(x) = c_T U_ref / (|ω(x)| + ε)` (spec §3.12, reconstructed), `U_ref = √(g H_ref)`.
#[derive(Clone, Copy, Debug)]
pub struct Turbulence {
    /// Coefficient `c_T` (spec default 0.05).
    pub coeff: f64,
}

impl SizingMetric for Turbulence {
    fn radius_at(&self, x: &Pt3, ctx: &SizingContext) -> f64 {
        match ctx.vorticity {
            Some(w) => self.coeff * ctx.u_ref / (w(x).abs() + TURBULENCE_EPS),
            None => f64::INFINITY,
        }
    }
    fn name(&self) -> &'static str {
        "turbulence"
    }
}

/// An axis-aligned box asking for particle radius `radius` inside it (spec §3.12 user field).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct UserBox {
    /// Box minimum corner (m).
    pub min: (f64, f64, f64),
    /// Box maximum corner (m).
    pub max: (f64, f64, f64),
    /// Requested particle radius inside the box (m).
    pub radius: f64,
}

/// The user field: the smallest radius among the boxes containing `x`.
#[derive(Clone, Debug)]
pub struct UserBoxes {
    /// The boxes.
    pub boxes: Vec<UserBox>,
}

impl SizingMetric for UserBoxes {
    fn radius_at(&self, x: &Pt3, _ctx: &SizingContext) -> f64 {
        self.boxes
            .iter()
            .filter(|b| {
                (b.min.0..=b.max.0).contains(&x.x)
                    && (b.min.1..=b.max.1).contains(&x.y)
                    && (b.min.2..=b.max.2).contains(&x.z)
            })
            .map(|b| b.radius)
            .fold(f64::INFINITY, f64::min)
    }
    fn name(&self) -> &'static str {
        "user"
    }
}

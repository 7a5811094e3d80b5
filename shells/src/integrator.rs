//! Integrator settings, per-step statistics and the hook through which `tracks` replaces the
//! velocity solve (shells.md §2, §3.7).

use crate::error::Result;
use crate::kernels::psd::HessianMode;
use geom_core::linalg::Csc;
use geom_core::math::{Pt3, Vec3};
use serde::{Deserialize, Serialize};

/// Time integrator.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum IntegratorKind {
    /// Linearly implicit backward Euler (seed §4.3; default).
    #[default]
    BackwardEuler,
    /// Second-order BDF (reconstructed, §3.7), restarted with one backward-Euler step.
    Bdf2,
}

/// Integrator settings (§4).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct IntegratorSettings {
    /// Backward Euler or BDF2.
    #[serde(default)]
    pub kind: IntegratorKind,
    /// Newton iterations per step (1 = the seed's single linearised step).
    #[serde(default = "one")]
    pub newton_iters: u32,
    /// Hessian projection mode.
    #[serde(default)]
    pub hessian: HessianMode,
    /// Backtracking on the incremental potential (only used when `newton_iters > 1`).
    #[serde(default)]
    pub line_search: bool,
    /// Fixed-order reductions (bitwise reproducible for any thread count). The assembly is always
    /// deterministic in this implementation; the flag is kept for API stability.
    #[serde(default = "yes")]
    pub deterministic: bool,
    /// Energy blow-up factor for [`crate::Error::Diverged`].
    #[serde(default = "div")]
    pub divergence_energy_factor: f64,
}

fn one() -> u32 {
    1
}
fn yes() -> bool {
    true
}
fn div() -> f64 {
    1e6
}

impl Default for IntegratorSettings {
    fn default() -> Self {
        Self {
            kind: IntegratorKind::BackwardEuler,
            newton_iters: 1,
            hessian: HessianMode::ProjectedCheap,
            line_search: false,
            deterministic: true,
            divergence_energy_factor: 1e6,
        }
    }
}

/// What one step did and how long each phase took (s). Disabled phases report zero.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct StepStats {
    /// Element evaluation + sparse assembly (s).
    pub t_assembly: f64,
    /// Numeric Cholesky factorisation (s).
    pub t_factor: f64,
    /// Triangular solves (s).
    pub t_solve: f64,
    /// Collision processing (s); 0 when collisions are off.
    pub t_collision: f64,
    /// Relative residual ‖AΔv − b‖/‖b‖ of the last linear solve.
    pub lin_residual: f64,
    /// Proximity pairs handled.
    pub n_proximity: u32,
    /// CCD hits resolved.
    pub n_ccd: u32,
    /// Rigid impact zones formed.
    pub n_impact_zones: u32,
    /// Largest impact zone (vertices).
    pub max_zone_size: u32,
    /// Vertices frozen at q_k because impact zones did not converge (reported, not an error).
    pub n_frozen: u32,
    /// Hinges that yielded plastically.
    pub plastic_events: u32,
    /// Hinges whose hardened stiffness hit the clamp.
    pub stiffness_clamped: u32,
    /// Diagonal shift τ used to make the system factorable (0 = none).
    pub regularization_shift: f64,
    /// Hinges skipped because a triangle collapsed (§8).
    pub skipped_hinges: u32,
    /// Deformed triangles with zero area.
    pub collapsed_triangles: u32,
    /// Newton iterations performed.
    pub newton_iters: u32,
    /// Line-search halvings.
    pub line_search_halvings: u32,
    /// What the IPC contact model did (zero with the Bridson filter or without collisions).
    pub contact: crate::contact::ContactStats,
}

/// Free / pinned / kinematic classification of the vertices and the free-DOF numbering.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct DofMap {
    /// Free index of each vertex, or `geom_core::NONE` for a constrained vertex.
    pub free_index: Vec<u32>,
    /// Free vertices in free-index order.
    pub free_vertices: Vec<u32>,
    /// Pinned vertices (sorted).
    pub pinned: Vec<u32>,
    /// Kinematic vertices (sorted).
    pub kinematic: Vec<u32>,
}

impl DofMap {
    /// Number of free vertices (the system has 3× this many unknowns).
    pub fn n_free(&self) -> usize {
        self.free_vertices.len()
    }
}

/// The linearised implicit system of one step on the free DOFs (§2). Conventions of this
/// implementation: constrained (pinned/kinematic) vertices already hold their prescribed
/// velocities in the Newton starting guess, so their Δv is zero and no free×kinematic coupling
/// enters the right-hand side.
pub struct ImplicitSystem<'a> {
    /// Lower triangle of A, (3 n_free)².
    pub a: &'a Csc,
    /// Right-hand side b.
    pub b: &'a [f64],
    /// Predicted positions q_base + h_eff v⁰ (all vertices).
    pub q_pred: &'a [Pt3],
    /// Starting velocities v⁰ (all vertices; constrained ones prescribed).
    pub v0: &'a [Vec3],
    /// Effective step: h for backward Euler, 2h/3 for BDF2; q_end = q_pred + h_eff·Δv.
    pub h_eff: f64,
    /// The free/constrained map.
    pub dofs: &'a DofMap,
    /// Step size (s).
    pub h: f64,
    /// Time at the end of the step (s).
    pub t_next: f64,
}

/// A replacement for the sparse Cholesky velocity solve (used by `tracks`).
pub trait VelocitySolve {
    /// Returns Δv for the free DOFs (length 3 n_free).
    fn solve(&mut self, sys: &ImplicitSystem) -> Result<Vec<f64>>;

    /// The term this solver adds to the IPC line search's merit function at end-of-step
    /// positions `q` (all vertices), in the units of the incremental potential Φ (J). A solver
    /// that imposes equality constraints C v = r returns an exact penalty ρ·Σᵢ‖cᵢ(q)‖ with ρ
    /// above its multipliers' norm, so that its constrained Newton direction is a descent
    /// direction of Φ + merit (Nocedal & Wright, *Numerical Optimization*, §18.3, eq. 18.36):
    /// without it a constraint that pulls uphill in Φ makes every line search fail. The
    /// default, for unconstrained solves, is 0.
    fn merit(&mut self, _q: &[Pt3]) -> f64 {
        0.0
    }

    /// Largest constraint violation the last [`solve`](Self::solve) had to restore, as a
    /// velocity (m/s): max over constraint rows of ‖rᵢ‖ in C Δv = r. The IPC Newton loop stops
    /// on its decrement test only when this is within `newton_tol` (a feasible iterate), so a
    /// step that still pulls the cloth onto its constraints keeps iterating. 0 (the default)
    /// for unconstrained solves.
    fn constraint_violation(&self) -> f64 {
        0.0
    }

    /// Whether [`solve`](Self::solve) accepts a system whose sparsity pattern changes between
    /// calls (IPC contact couplings grow it, `ShellSim`'s pattern growth). A solver that keeps
    /// a symbolic analysis of the mesh's own pattern returns false (the default); IPC then
    /// lumps contact couplings onto the diagonal blocks for it, which costs Newton iterations.
    fn accepts_pattern_changes(&self) -> bool {
        false
    }
}

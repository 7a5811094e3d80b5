//! # shells — discrete thin-shell simulator
//!
//! Triangle-mesh thin shells and cloth (shells.md): Discrete Shells hinge bending (Grinspun et al.
//! 2003), constant-strain-triangle St. Venant–Kirchhoff membranes (isotropic, orthotropic,
//! compression-softened), lumped masses, gravity, damping, wind, user forces, pinned and
//! kinematic vertices, the bending plasticity of TRACKS (Bergou et al. 2007, §4.4), a linearly
//! implicit backward-Euler step (one Newton step, as in the seed §4.3) or BDF2 with the sparse
//! Cholesky of geom-core, and collisions after Bridson, Fedkiw & Anderson 2002.
//!
//! Units are SI (m, kg, s), angles in radians, y is up in the scenes.
//!
//! The scenes of `cargo xtask run shells/<scene>` are public experiments here
//! ([`experiments`]), with the materials and setups they use ([`presets`]), the figures they
//! report ([`metrics`]) and the analytic solutions they are compared with ([`reference`]).

// `!(x > 0.0)` is used on purpose throughout: it rejects NaN together with the invalid range.
#![allow(clippy::neg_cmp_op_on_partial_ord)]
// Element kernels index small fixed blocks (vertex a, b; row r, column c) exactly as the
// formulas of the spec do; iterator rewrites would obscure them.
#![allow(clippy::needless_range_loop)]

mod assembly;
pub mod calib;
pub mod collision;
pub mod contact;
pub mod effects;
pub mod error;
pub mod experiments;
pub mod garment;
pub mod integrator;
pub mod kernels;
pub mod loads;
pub mod material;
pub mod mesh;
pub mod metrics;
pub mod obstacle_mesh;
pub mod presets;
pub mod reference;
pub mod scene;
pub mod sim;
pub mod wind;

pub use contact::deforming::DeformingMesh;
pub use contact::ContactStats;
pub use effects::{
    BlockTriplets, CollisionSettings, ContactMethod, Effects, ExternalForce, KinematicPath, Obstacle, ObstacleShape,
    Wind,
};
pub use error::{Error, Result, ShellError};
pub use integrator::{DofMap, ImplicitSystem, IntegratorKind, IntegratorSettings, StepStats, VelocitySolve};
pub use kernels::bending::{bending_element, Hinge};
pub use kernels::hinge::{hinge_angle, hinge_angle_grad, hinge_angle_hessian};
pub use kernels::membrane::{membrane_element, Membrane, TriRest};
pub use kernels::plastic::plastic_update;
pub use kernels::psd::HessianMode;
pub use material::{Damping, Material, MembraneLaw, PlasticRule, Plasticity, WarpSource};
pub use mesh::ShellMesh;
pub use sim::{EnergyBreakdown, KinematicFn, ShellSceneDesc, ShellSim, ShellState, VertexConstraint};

/// Continuous collision detection primitives (shells.md §2 `ccd`).
pub mod ccd {
    pub use crate::collision::ccd::{coplanarity_cubic, cubic_roots_unit, edge_edge, vertex_triangle};
}

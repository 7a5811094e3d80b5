//! The crate's error types (spec §2): [`SimError`] for the simulator and scene loading,
//! [`MeshError`] for octree / tetrahedralisation failures.

use thiserror::Error;

/// Failures of the octree and tetrahedral mesh construction (spec §2, §3.2).
#[derive(Debug, Error, Clone, PartialEq)]
pub enum MeshError {
    /// The domain box is not an integer number of root cubes in every axis.
    #[error("domain extent {extent} m along axis {axis} is not a multiple of the root cube {h_root} m")]
    DomainNotMultipleOfRoot {
        /// Axis index (0 = x).
        axis: usize,
        /// Extent of the box along that axis (m).
        extent: f64,
        /// Root cube edge (m).
        h_root: f64,
    },
    /// More levels than the lattice supports (finest / coarsest must be a power of two ≤ 2^12).
    #[error("too many octree levels: {0}")]
    TooManyLevels(u8),
    /// A tet of (near-)zero volume.
    #[error("degenerate tet {tet}: volume {volume}")]
    DegenerateTet {
        /// Tet index.
        tet: u32,
        /// Its volume (m³).
        volume: f64,
    },
    /// The tiling is not conforming (a face was not matched).
    #[error("non-conforming mesh: {faces} unmatched faces")]
    NonConforming {
        /// Number of faces that were not matched.
        faces: usize,
    },
    /// Invalid resolution or domain parameters.
    #[error("invalid mesh parameter: {0}")]
    InvalidParameter(String),
}

/// Which linear solver produced a result (spec §3.6).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
pub enum SolverKind {
    /// Choose by DOF count: direct below `direct_max_dofs`, MIC(0)-PCG above, Jacobi on breakdown.
    #[default]
    Auto,
    /// Sparse Cholesky (faer through geom-core).
    DirectCholesky,
    /// CG preconditioned with modified incomplete Cholesky MIC(0).
    PcgIc0,
    /// CG preconditioned with the diagonal.
    PcgJacobi,
    /// No solve was needed (no DOFs).
    None,
}

/// Simulator errors (spec §2).
#[derive(Debug, Error)]
pub enum SimError {
    /// The scene description is invalid (names the field and the problem).
    #[error("invalid scene: {0}")]
    InvalidScene(String),
    /// A non-finite value appeared in the named phase.
    #[error("non-finite value in {what} at step {step}")]
    NonFinite {
        /// Phase name.
        what: &'static str,
        /// Step counter.
        step: u64,
    },
    /// Mesh construction failed.
    #[error("mesh: {0}")]
    Mesh(#[from] MeshError),
    /// The pressure solver did not converge.
    #[error("pressure solver {kind:?} failed after {iters} iterations (relative residual {residual})")]
    SolverFailed {
        /// Solver that failed last.
        kind: SolverKind,
        /// Iterations performed.
        iters: usize,
        /// Final relative residual.
        residual: f64,
    },
    /// The particle budget was exceeded and the scene asked for a hard error.
    #[error("particle budget {limit} exceeded")]
    ParticleBudgetExceeded {
        /// The budget.
        limit: usize,
    },
    /// Error from geom-core (linear algebra, marching tetrahedra, I/O).
    #[error(transparent)]
    Core(#[from] geom_core::Error),
}

/// Result alias of the crate.
pub type Result<T> = std::result::Result<T, SimError>;

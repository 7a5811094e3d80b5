//! The crate's error type: every user-input problem and every numerical failure of a step is a
//! typed value, never a panic (shells.md §2 `ShellError`, §8).

/// Errors of the shell simulator.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// A rest triangle has (near) zero area: area < 1e-12·L² (L the bounding-box diagonal).
    #[error("degenerate rest triangle {0} (area below 1e-12·L²)")]
    DegenerateTriangle(u32),
    /// An edge is shared by more than two triangles, or the orientation cannot be made consistent.
    #[error("non-manifold edge ({0}, {1})")]
    NonManifoldEdge(u32, u32),
    /// A NaN or infinite value in user input or in the state; names the quantity.
    #[error("non-finite value in {0}")]
    NonFinite(&'static str),
    /// A parameter outside its valid range; the message names it and its value.
    #[error("bad parameter: {0}")]
    BadParameter(String),
    /// The sparse Cholesky factorisation failed even after the diagonal-shift retries (§3.8).
    #[error("factorisation failed after diagonal-shift retries")]
    FactorizationFailed,
    /// Collisions could not be resolved (count of still-colliding impact zones).
    #[error("{0} impact zones could not be resolved")]
    CollisionUnresolved(u32),
    /// A step produced non-finite values or an energy blow-up; frames already written stay valid.
    #[error("simulation diverged at step {step}: {reason}")]
    Diverged {
        /// Index of the failing step (0-based, counted since construction).
        step: u64,
        /// What was detected.
        reason: String,
    },
    /// A scene's run stopped at a failed step (`message`: that step's error); the frames
    /// recorded before it stay recorded.
    #[error("{scene} failed after {steps} steps (frames kept): {message}")]
    RunFailed {
        /// The scene.
        scene: String,
        /// Steps completed.
        steps: u64,
        /// The failed step's error.
        message: String,
    },
    /// An error of the geometry core (mesh validation, solver, I/O).
    #[error(transparent)]
    Core(#[from] geom_core::Error),
}

/// The spec's name for [`Error`] (shells.md §2).
pub type ShellError = Error;

/// Result alias of this crate.
pub type Result<T> = std::result::Result<T, Error>;

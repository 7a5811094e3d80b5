//! The crate's error type.

/// Everything that can go wrong with user input to the skinners.
#[derive(Debug, thiserror::Error)]
pub enum SkinError {
    /// A geom-core error (I/O, invalid parameter, dimension mismatch …).
    #[error(transparent)]
    Core(#[from] geom_core::Error),
    /// The skeleton has no joint.
    #[error("the skeleton has no joint")]
    EmptySkeleton,
    /// A bone transform given to dual-quaternion skinning has scale or shear (‖RᵀR − I‖ > 1e-6)
    /// and `allow_scale` is off (spec §3.3).
    #[error(
        "bone {bone}: transform is not rigid (‖RᵀR − I‖ = {deviation:.3e}); dual-quaternion skinning needs allow_scale"
    )]
    NonRigidForDqs {
        /// The offending bone.
        bone: usize,
        /// ‖RᵀR − I‖ (max norm).
        deviation: f64,
    },
    /// A weight row is unusable (NaN weight, zero total weight, bone index out of range).
    #[error("weights, vertex {vertex}: {msg}")]
    BadWeights {
        /// The vertex (row).
        vertex: usize,
        /// What is wrong.
        msg: String,
    },
    /// Array sizes disagree.
    #[error("{what}: expected {expected}, got {got}")]
    Size {
        /// Which array.
        what: &'static str,
        /// Expected length.
        expected: usize,
        /// Actual length.
        got: usize,
    },
    /// A parameter is out of its range.
    #[error("invalid parameter: {0}")]
    Param(String),
}

/// Shorthand result type.
pub type Result<T> = std::result::Result<T, SkinError>;

/// The error type under the name the method-crate convention uses.
pub type Error = SkinError;

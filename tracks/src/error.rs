//! The crate's error type (spec §2 `TrackError`): every bad input and every numerical failure of
//! the tracked step is a typed value naming what and where.

/// Errors of the tracking layer.
#[derive(Debug, thiserror::Error)]
pub enum TrackError {
    /// An error of the underlying shell simulator (including factorisation failures).
    #[error(transparent)]
    Shell(#[from] shells::Error),
    /// An error of the geometry core (mesh validation, linear algebra, I/O).
    #[error(transparent)]
    Core(#[from] geom_core::Error),
    /// Guide frames (or guide and tracked meshes) disagree in vertex count or topology.
    #[error("topology mismatch: {what} (expected {expected}, got {got})")]
    TopologyMismatch {
        /// What was compared.
        what: &'static str,
        /// Expected count.
        expected: usize,
        /// Count found.
        got: usize,
    },
    /// Test function `i` has (near) zero integral over the guide (spec §3.2).
    #[error("test function {0} has (near) zero integral")]
    ZeroIntegral(usize),
    /// The listed constraint rows are linearly dependent on earlier rows (duplicated or
    /// redundant regions; spec §3.2 rank check).
    #[error("rank-deficient constraints: rows {0:?} depend on other rows")]
    RankDeficient(Vec<usize>),
    /// Constraint `i` acts only on pinned vertices and the guide violates it.
    #[error("constraint {0} acts only on pinned/kinematic vertices and cannot be satisfied")]
    InfeasibleConstraint(usize),
    /// A NaN or infinite value in the named input.
    #[error("non-finite value in {0}")]
    NonFinite(&'static str),
    /// A parameter outside its valid range; the message names it and its value.
    #[error("bad parameter: {0}")]
    BadParameter(String),
    /// The guide was sampled past its last frame (held; reported, spec §3.4).
    #[error("guide time {0} s is out of range")]
    GuideTimeOutOfRange(f64),
}

/// Result alias of this crate.
pub type Result<T> = std::result::Result<T, TrackError>;

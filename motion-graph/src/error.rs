//! The crate's error type: database, graph and search errors (motion-graph.md §2.4, §8), plus
//! wrapped geom-core errors. No user input panics.

use thiserror::Error;

/// Errors of the motion-graph crate.
#[derive(Debug, Error)]
pub enum Error {
    /// geom-core error (BVH parsing, mesh building, …).
    #[error(transparent)]
    Core(#[from] geom_core::Error),
    /// A motion file could not be read.
    #[error("{path}: {source}")]
    File {
        /// The file.
        path: String,
        /// What went wrong.
        source: geom_core::Error,
    },
    /// The database has no usable clip (none given, or every clip shorter than 3 frames).
    #[error("empty database: {0}")]
    EmptyDatabase(String),
    /// Two sources use different skeletons.
    #[error("skeleton mismatch in clip {clip}: {what}")]
    SkeletonMismatch {
        /// Index of the offending source clip.
        clip: usize,
        /// The first difference (joint name, parent, offset).
        what: String,
    },
    /// The graph would hold more edges than the memory guard allows.
    #[error("too many edges: about {estimated} estimated, cap {cap}")]
    TooManyEdges {
        /// Estimated edge count.
        estimated: usize,
        /// The cap.
        cap: usize,
    },
    /// A parameter is out of its valid range.
    #[error("invalid parameter: {0}")]
    InvalidParameter(String),
    /// No body constraint at time 0 (needed to place the motion).
    #[error("no body constraint at time 0: the first body constraint places the motion")]
    NoStartConstraint,
    /// A constraint lies beyond ten times the requested length.
    #[error("constraint at frame {time} is out of range (requested length {length})")]
    ConstraintOutOfRange {
        /// Constraint time (frames).
        time: u32,
        /// Requested length (frames).
        length: u32,
    },
    /// Two hard constraints at one time ask for different things.
    #[error("conflicting hard constraints at frame {time}")]
    ConflictingHard {
        /// Output frame.
        time: u32,
    },
    /// No seed path meets the hard constraints (e.g. they lie in different graph components).
    #[error("no seed path after {tries} tries: {reason}")]
    NoSeedPath {
        /// Attempts made.
        tries: usize,
        /// Why (last failure).
        reason: String,
    },
    /// A label named by a constraint exists in no clip.
    #[error("unknown label '{0}'")]
    UnknownLabel(String),
    /// A joint named by a constraint is not in the skeleton.
    #[error("unknown joint '{0}'")]
    UnknownJoint(String),
}

/// Result alias.
pub type Result<T> = std::result::Result<T, Error>;

//! The crate's error type (spec §2, §8).

/// Everything a user's input can break in the wrinkle pipeline.
#[derive(Debug, thiserror::Error)]
pub enum WrinkleError {
    /// A geom-core error (PNG I/O, sparse factorisation …).
    #[error(transparent)]
    Core(#[from] geom_core::Error),
    /// A per-frame position array does not match the rest mesh's vertex count.
    #[error("topology mismatch: the rest mesh has {expected} vertices, the frame has {got}")]
    TopologyMismatch {
        /// Vertex count of the rest mesh.
        expected: usize,
        /// Vertex count of the frame.
        got: usize,
    },
    /// The rest mesh carries no texture coordinates (patterns are mapped through UVs).
    #[error("the rest mesh has no UVs: wrinkle patterns are mapped through texture coordinates")]
    MissingUv,
    /// A rest or deformed position has a NaN or infinite coordinate.
    #[error("vertex {vertex}: non-finite position")]
    NonFinitePosition {
        /// The offending vertex.
        vertex: usize,
    },
    /// A face index is out of range or repeated within a face.
    #[error("face {face}: bad vertex index {index} (mesh has {n_vertices} vertices)")]
    BadFace {
        /// The offending face.
        face: usize,
        /// The offending index.
        index: u32,
        /// Vertex count.
        n_vertices: usize,
    },
    /// A pattern image could not be read.
    #[error("pattern image: {0}")]
    PatternIo(String),
    /// An option or parameter is out of range (the message names it and its value).
    #[error("invalid option: {0}")]
    InvalidOption(String),
    /// The cloth simulation driving a scene (`shells`, feature `shells`) failed; the message
    /// names the simulator's error.
    #[error("cloth simulation: {0}")]
    Driver(String),
    /// The area-consistent smoothing system is singular (μ = 0 and a vertex touches no valid
    /// triangle, or an isolated vertex); raised at construction, never mid-animation (spec §3.9).
    #[error("area-consistent smoothing system is singular (pattern {pattern}, vertex {vertex}): raise mu or remove isolated vertices")]
    SingularSmoothingSystem {
        /// The pattern whose system is singular.
        pattern: usize,
        /// A vertex with a zero row (`usize::MAX` when the factorisation failed elsewhere).
        vertex: usize,
    },
}

/// Shorthand result type.
pub type Result<T> = std::result::Result<T, WrinkleError>;

/// The error type under the name the method-crate convention uses.
pub type Error = WrinkleError;

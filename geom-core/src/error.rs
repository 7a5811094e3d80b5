//! The one error type of geom-core (GEOM-CORE.md §4).
//!
//! Every variant names the offending element (face, vertex, line, column) so that a user can find
//! the problem in their input. Method crates wrap it as `Core(#[from] geom_core::Error)` or map the
//! variants onto the names their spec uses.

/// Result alias used throughout geom-core.
pub type Result<T, E = Error> = std::result::Result<T, E>;

/// Everything that can go wrong in geom-core.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// A face refers to a vertex index that does not exist (or repeats a vertex).
    #[error("face {face} refers to vertex {vertex}, which is out of range or repeated in the face")]
    IndexOutOfRange { face: u32, vertex: u32 },
    /// A vertex with a NaN or infinite coordinate.
    #[error("vertex {vertex} has a non-finite coordinate")]
    NonFiniteVertex { vertex: u32 },
    /// A face whose area is (numerically) zero.
    #[error("face {face} is degenerate (zero area)")]
    DegenerateFace { face: u32 },
    /// A vertex whose incident faces do not form a single fan.
    #[error("vertex {vertex} is non-manifold (its faces do not form one fan)")]
    NonManifoldVertex { vertex: u32 },
    /// An edge shared by more than two faces (or twice in the same direction).
    #[error("edge ({a}, {b}) is non-manifold: shared by faces {faces:?}")]
    NonManifoldEdge { a: u32, b: u32, faces: Vec<u32> },
    /// Two neighbouring faces traverse their shared edge in the same direction and the surface
    /// could not be re-oriented (non-orientable, e.g. a Möbius strip).
    #[error("faces {face} and {neighbour} have inconsistent orientation and the surface is not orientable")]
    InconsistentOrientation { face: u32, neighbour: u32 },
    /// A closed surface was required.
    #[error("the mesh is not closed: {boundary_edges} boundary edges")]
    NotClosed { boundary_edges: usize },
    /// Two meshes (or a mesh and a data array) that must share topology do not.
    #[error("topology mismatch: expected {expected}, got {got}")]
    TopologyMismatch { expected: usize, got: usize },
    /// An array has the wrong length.
    #[error("dimension mismatch in {what}: expected {expected}, got {got}")]
    DimensionMismatch { what: &'static str, expected: usize, got: usize },
    /// Cholesky met a non-positive pivot.
    #[error("matrix is not positive definite (pivot at column {column})")]
    NotPositiveDefinite { column: usize },
    /// Any other factorisation failure (singular matrix, symbolic failure), with faer's message.
    #[error("factorisation failed: {0}")]
    Factorization(String),
    /// An iterative solver stopped before its tolerance.
    #[error("iterative solver did not converge: {iters} iterations, relative residual {rel_residual:e}")]
    NotConverged { iters: usize, rel_residual: f64 },
    /// A NaN or infinity where finite numbers are required; the string says where.
    #[error("non-finite value in {0}")]
    NonFinite(&'static str),
    /// A text or binary file could not be parsed; `line` is 1-based (0 when not line-based, e.g. a
    /// binary PLY body, where `msg` gives the byte offset or element index).
    #[error("{format} parse error at line {line}: {msg}")]
    Parse { format: &'static str, line: usize, msg: String },
    /// PNG encoding or decoding failed.
    #[error("image error: {0}")]
    Image(String),
    /// An operating-system I/O error.
    #[error("I/O error: {0}")]
    Io(#[from] std::io::Error),
    /// A malformed BVH motion file.
    #[error("BVH error: {0}")]
    Bvh(#[from] BvhError),
    /// An out-of-range or inconsistent parameter; the string says which and why.
    #[error("invalid parameter: {0}")]
    InvalidParameter(String),
    /// An error found while reading a file, with the file's path (the inner error says what is
    /// wrong and where inside the file).
    #[error("{}: {source}", path.display())]
    InFile {
        /// The file.
        path: std::path::PathBuf,
        /// What is wrong with it.
        source: Box<Error>,
    },
}

/// The specific ways a BVH file can be malformed (motion-graph.md §2.2, §7.1). Each carries the
/// 1-based line where the problem was found.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum BvhError {
    /// Fewer frame rows (or numbers) than the `Frames:` line declares (strict mode).
    #[error("line {line}: truncated motion: {declared} frames declared, {found} found")]
    Truncated { line: usize, declared: usize, found: usize },
    /// `{` and `}` do not match.
    #[error("line {line}: unbalanced braces")]
    UnbalancedBraces { line: usize },
    /// `Frame Time:` missing, non-numeric, zero or negative.
    #[error("line {line}: bad frame time: {text}")]
    BadFrameTime { line: usize, text: String },
    /// A token that should be a number is not (or is not finite).
    #[error("line {line}: bad number '{text}'")]
    BadNumber { line: usize, text: String },
    /// A joint's rotation channels repeat an axis (e.g. `Xrotation Xrotation Zrotation`).
    #[error("line {line}: joint '{joint}' repeats a rotation axis")]
    RepeatedAxis { line: usize, joint: String },
    /// A keyword that has no place here.
    #[error("line {line}: unknown or misplaced keyword '{keyword}'")]
    UnknownKeyword { line: usize, keyword: String },
    /// Two joints with the same name.
    #[error("line {line}: duplicate joint name '{name}'")]
    DuplicateJoint { line: usize, name: String },
    /// A `CHANNELS n` line whose count does not match the names that follow (or an unknown name).
    #[error("line {line}: channel count or name mismatch: {msg}")]
    ChannelCount { line: usize, msg: String },
    /// The file declares zero frames, or has no MOTION section.
    #[error("line {line}: no frames")]
    NoFrames { line: usize },
}

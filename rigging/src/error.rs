//! The crate's error type (rigging spec §2.1 `RigError`, §8 hard cases).

/// Everything that can go wrong while rigging; input problems name what and where.
#[derive(Debug, thiserror::Error)]
pub enum RigError {
    /// The mesh has no triangles.
    #[error("the mesh has no triangles")]
    EmptyMesh,
    /// The mesh has a boundary (holes).
    #[error("the mesh is not closed: {boundary_edges} boundary edges, e.g. at vertices {example:?}")]
    NotClosed {
        /// Number of boundary edges.
        boundary_edges: usize,
        /// The first few boundary edges (vertex pairs, input indices after welding).
        example: Vec<[u32; 2]>,
    },
    /// Some edges are shared by more than two triangles.
    #[error("{edges} non-manifold edges (more than two faces), e.g. between vertices {example:?}")]
    NonManifold {
        /// Number of non-manifold edges.
        edges: usize,
        /// The first few such edges (vertex pairs).
        example: Vec<[u32; 2]>,
    },
    /// The mesh has several connected components.
    #[error("the mesh has {components} connected components (set keep_largest_component to rig the largest)")]
    NotConnected {
        /// Number of components.
        components: usize,
    },
    /// Degenerate geometry (zero volume, collapsed mesh …).
    #[error("degenerate input: {0}")]
    Degenerate(String),
    /// A skeleton template is malformed.
    #[error("invalid skeleton: {0}")]
    InvalidSkeleton(String),
    /// The sphere graph is disconnected and no embedding exists.
    #[error("the sphere graph has {components} components and no embedding was found (thin limbs?)")]
    GraphDisconnected {
        /// Number of components.
        components: usize,
    },
    /// The discrete search found no embedding below the rejection bound.
    #[error(
        "no skeleton embedding passes the penalty bound after {expanded} expanded partial embeddings (best partial: {best_partial:?})"
    )]
    NoEmbedding {
        /// Graph vertices of the deepest partial embedding seen, if any.
        best_partial: Option<Vec<u32>>,
        /// Partial embeddings the search expanded before giving up.
        expanded: usize,
    },
    /// The bone-heat solve failed.
    #[error("bone heat solve failed: {0}")]
    SolverFailed(String),
    /// Non-finite numbers in the named input.
    #[error("non-finite values in {0}")]
    NonFinite(&'static str),
    /// A parameter is out of range.
    #[error("invalid parameter: {0}")]
    InvalidParameter(String),
    /// Reading or parsing a file.
    #[error("{path}: {msg}")]
    File {
        /// File path.
        path: String,
        /// What went wrong.
        msg: String,
    },
    /// An error from geom-core.
    #[error(transparent)]
    Core(#[from] geom_core::Error),
}

/// Result alias of the crate.
pub type Result<T> = std::result::Result<T, RigError>;

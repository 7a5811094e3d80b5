//! [`BarNetError`]: the one error type of the crate (spec §8 names its variants).

/// Everything a bar-net operation can fail with. Every variant names what and where.
#[derive(Debug, thiserror::Error)]
pub enum BarNetError {
    /// An error from geom-core (mesh, files, sparse solvers).
    #[error(transparent)]
    Core(#[from] geom_core::Error),
    /// Free nodes forming a connected part (through bars with `q ≠ 0`) without any fixed node:
    /// `D` is singular (spec §3.2, §8). Found by union–find before any factorisation.
    #[error("bar-net: {} free node(s) belong to a part with no fixed node (e.g. nodes {:?}); fix at least one node of that part", nodes.len(), &nodes[..nodes.len().min(8)])]
    Unanchored {
        /// Every free node of every unanchored part, ascending.
        nodes: Vec<u32>,
    },
    /// The equilibrium matrix is singular although every part is anchored (possible only with
    /// negative, compression force densities, spec §8).
    #[error("bar-net: the equilibrium matrix D is singular ({0})")]
    Singular(String),
    /// A bar joins a node to itself.
    #[error("bar-net: bar {bar} is a self-loop on node {node}")]
    SelfLoop {
        /// Bar index.
        bar: usize,
        /// The node.
        node: u32,
    },
    /// A bar names a node that does not exist.
    #[error("bar-net: bar {bar} names node {node}, but the net has {n_nodes} nodes")]
    NodeOutOfRange {
        /// Bar index (or `usize::MAX` when the index came from a node list).
        bar: usize,
        /// The bad node index.
        node: u32,
        /// Number of nodes.
        n_nodes: usize,
    },
    /// A NaN or infinite value in an input (loads, positions, force densities).
    #[error("bar-net: non-finite value in {what} at index {index}")]
    NonFinite {
        /// Which input.
        what: &'static str,
        /// First offending entry.
        index: usize,
    },
    /// An input slice of the wrong length.
    #[error("bar-net: {what} has length {got}, expected {expected}")]
    DimensionMismatch {
        /// Which input.
        what: &'static str,
        /// Expected length.
        expected: usize,
        /// Given length.
        got: usize,
    },
    /// A parameter outside its valid range, or an unknown name.
    #[error("bar-net: invalid parameter: {0}")]
    InvalidParameter(String),
    /// A frame whose equilibrium residual exceeds the bound an experiment asserts (spec §7.3 e).
    #[error("{what}: equilibrium residual {residual:e} exceeds {bound:e} (spec 7.3 e)")]
    Residual {
        /// The experiment.
        what: &'static str,
        /// The relative residual ‖D x − (P − D_f x_f)‖ / ‖P − D_f x_f‖.
        residual: f64,
        /// The bound.
        bound: f64,
    },
}

/// Result alias of the crate.
pub type Result<T, E = BarNetError> = std::result::Result<T, E>;

/// Returns `NonFinite { what, index }` for the first non-finite entry of `v`.
pub(crate) fn check_finite(what: &'static str, v: &[f64]) -> Result<()> {
    match v.iter().position(|x| !x.is_finite()) {
        Some(index) => Err(BarNetError::NonFinite { what, index }),
        None => Ok(()),
    }
}

/// Returns `DimensionMismatch` unless `got == expected`.
pub(crate) fn check_len(what: &'static str, expected: usize, got: usize) -> Result<()> {
    if expected == got {
        Ok(())
    } else {
        Err(BarNetError::DimensionMismatch { what, expected, got })
    }
}

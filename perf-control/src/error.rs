//! The crate's error type (spec §2 "Errors", §8 hard cases).

/// Everything that can go wrong with user input; never a panic, never a NaN result.
#[derive(Debug, thiserror::Error)]
pub enum PcError {
    /// A geom-core error (motion construction …).
    #[error(transparent)]
    Core(#[from] geom_core::Error),
    /// The database has no instance (no take, or every segment was dropped as too short).
    #[error("the database is empty: {0}")]
    EmptyDatabase(String),
    /// The input control has fewer than 2 frames.
    #[error("input too short: {frames} frame(s), at least 2 needed")]
    InputTooShort {
        /// Frames in the input.
        frames: usize,
    },
    /// A NaN or infinite coordinate.
    #[error("non-finite value in {what} at frame {frame}, point {point}")]
    NonFinite {
        /// Which signal (input control, take `i` control …).
        what: String,
        /// Frame index.
        frame: usize,
        /// Point index within the frame.
        point: usize,
    },
    /// No chain satisfies the constraints (exact tiling impossible without partial ends, or the
    /// forced segments exclude every cell).
    #[error("no interpretation: {0}")]
    NoInterpretation(String),
    /// Sample rates disagree.
    #[error("rate mismatch: {what} is sampled at {got} Hz, {expected} Hz expected")]
    RateMismatch {
        /// Which signal.
        what: String,
        /// Expected rate (Hz).
        expected: f64,
        /// Actual rate (Hz).
        got: f64,
    },
    /// Point counts per frame disagree.
    #[error("point-count mismatch: {what} has {got} points per frame, {expected} expected")]
    PointCountMismatch {
        /// Which signal.
        what: String,
        /// Expected points per frame.
        expected: usize,
        /// Actual points per frame.
        got: usize,
    },
    /// A parameter outside its valid range.
    #[error("bad parameter {name}: {msg}")]
    BadParameter {
        /// Parameter name.
        name: &'static str,
        /// What is wrong.
        msg: String,
    },
}

/// Result alias of the crate.
pub type Result<T> = std::result::Result<T, PcError>;

/// Error unless every coordinate of `data` (frames × `k` points) is finite.
pub(crate) fn check_finite(what: &str, data: &[geom_core::math::Vec3], k: usize) -> Result<()> {
    for (i, p) in data.iter().enumerate() {
        if !(p.x.is_finite() && p.y.is_finite() && p.z.is_finite()) {
            return Err(PcError::NonFinite { what: what.to_string(), frame: i / k.max(1), point: i % k.max(1) });
        }
    }
    Ok(())
}

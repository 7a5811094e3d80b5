//! The crate's typed errors: every problem with user input (footage, calibration, corner
//! tracks, scene parameters) is a [`FitError`] raised *before* any objective evaluation; a
//! failing forward simulation is a [`SimError`], which the objective turns into a finite penalty
//! (spec §3.7) rather than an error.

use std::path::PathBuf;

/// Why a forward simulation failed. The objective records it as `SimFailed` and returns the
/// finite failure penalty; the search continues.
#[derive(Debug, Clone, thiserror::Error)]
pub enum SimError {
    /// `shells` rejected the setup (a parameter out of its valid range).
    #[error("simulation setup rejected: {0}")]
    Setup(String),
    /// `shells` reported a divergence, a factorisation failure or non-finite values at `t` (s).
    #[error("simulation failed at t = {t:.4} s: {reason}")]
    Diverged {
        /// Simulation time of the failing step (s).
        t: f64,
        /// What `shells` detected.
        reason: String,
    },
    /// The cloth left the plausible region (a vertex farther than the bound from the rig).
    #[error("simulation left the scene at t = {t:.4} s (vertex {vertex} at {distance:.3} m)")]
    Escaped {
        /// Simulation time (s).
        t: f64,
        /// Offending vertex.
        vertex: usize,
        /// Its distance from the swatch's top edge midpoint (m).
        distance: f64,
    },
}

/// Errors of the fitting pipeline (spec §2, §8): all raised before any evaluation.
#[derive(Debug, thiserror::Error)]
pub enum FitError {
    /// A file could not be read or decoded (corrupt or truncated PNG, missing file …); names it.
    #[error("{path}: {msg}")]
    Io {
        /// The file.
        path: PathBuf,
        /// What went wrong.
        msg: String,
    },
    /// A frame's size differs from the calibrated camera's.
    #[error("{what}: image is {got:?} pixels, the camera expects {expected:?}")]
    ImageSizeMismatch {
        /// The frame (file name or "frame k").
        what: String,
        /// Camera size (width, height).
        expected: (u32, u32),
        /// Frame size (width, height).
        got: (u32, u32),
    },
    /// Frame counts (or other per-frame lists) of two sequences disagree.
    #[error("sequence mismatch in {what}: expected {expected}, got {got}")]
    SequenceMismatch {
        /// What was compared.
        what: String,
        /// Expected count.
        expected: usize,
        /// Actual count.
        got: usize,
    },
    /// Too few or (nearly) coplanar calibration markers (DLT needs ≥ 6 non-coplanar points).
    #[error("degenerate calibration: {0}")]
    DegenerateCalibration(String),
    /// The projected stripes are too fine in the image (aliasing below 5 px per period).
    #[error("stripes under-resolved: predicted period {period_px:.2} px in the image, need ≥ {min_px} px (set allow_fine_stripes to override)")]
    StripesUnderResolved {
        /// Predicted stripe period in the camera image (px).
        period_px: f64,
        /// The minimum accepted (px).
        min_px: f64,
    },
    /// Every coarse-search point failed to simulate.
    #[error("no valid start: all {count} coarse-search points failed ({first_reason})")]
    NoValidStart {
        /// Number of failed points.
        count: usize,
        /// The first failure's reason.
        first_reason: String,
        /// Every failure reason, in grid order.
        reasons: Vec<String>,
    },
    /// A CSV file with a bad line.
    #[error("{path}:{line}: {msg}")]
    Csv {
        /// The file.
        path: PathBuf,
        /// 1-based line number (0: the whole file).
        line: usize,
        /// What is wrong.
        msg: String,
    },
    /// A RON file (rig, calibration) that does not parse.
    #[error("{path}:{line}:{col}: {msg}")]
    Parse {
        /// The file.
        path: PathBuf,
        /// Line (1-based).
        line: usize,
        /// Column (1-based).
        col: usize,
        /// The parser's message.
        msg: String,
    },
    /// A parameter outside its valid range; the message names it and its value.
    #[error("bad parameter: {0}")]
    BadParameter(String),
    /// The forward model failed where a failure cannot be turned into a penalty (the truth
    /// sequence of a synthetic target).
    #[error("forward simulation: {0}")]
    Sim(#[from] SimError),
    /// An error of geom-core (camera setup, image buffers, recorder output).
    #[error(transparent)]
    Core(#[from] geom_core::Error),
}

/// Result alias of this crate.
pub type Result<T, E = FitError> = std::result::Result<T, E>;

//! # cloth-fit — cloth simulation parameters estimated from video
//!
//! Bhat, Twigg, Hodgins, Khosla, Popović, Seitz: *Estimating Cloth Simulation Parameters from
//! Video*, SCA 2003. A fabric swatch is filmed in two calibration experiments (hanging from two
//! corners, and waved by one corner) under projected horizontal stripes. Steerable filters turn
//! each frame into an angle map of stripe orientation, flat on planar cloth and varying across
//! folds; simulation and footage are compared by the squared angle differences at fold pixels
//! plus a silhouette mismatch (eqs. 5–9). A coarse exhaustive search and continuous simulated
//! annealing (Metropolis + downhill simplex) find the cloth parameters; a perturbation analysis
//! reports how well each is determined.
//!
//! There is no real footage here: synthetic truths rendered from `shells` simulations with
//! known parameters (optionally degraded) replace it, and the real-footage path (PNG frames,
//! DLT calibration, corner tracks) is exercised by writing a synthetic capture to disk.
//!
//! Units are SI; pixel coordinates follow OpenCV (centre of the top-left pixel at (0, 0), y
//! down); angles in radians unless a name says `_deg`.

// `!(x > 0.0)` rejects NaN together with the invalid range, on purpose.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

pub mod angle;
pub mod anneal;
pub mod camera;
pub mod coarse;
pub mod dlt;
pub mod drag;
pub mod error;
pub mod experiments;
pub mod fit;
pub mod fold_error;
pub mod footage;
pub mod forward;
pub mod metrics;
pub mod morphology;
pub mod noise;
pub mod objective;
pub mod params;
pub mod png_bytes;
pub mod presets;
pub mod reference;
pub mod render;
pub mod rig;
pub mod setup;
pub mod steerable;
pub mod synthetic;
pub mod trajectory;
pub mod variability;

pub use error::{FitError, Result, SimError};

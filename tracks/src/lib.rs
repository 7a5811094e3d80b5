//! # tracks — weak-form tracking of a coarse guide animation
//!
//! TRACKS (Bergou, Mathur, Wardetzky, Grinspun, "TRACKS: Toward Directable Thin Shells", ACM
//! TOG 26(3), SIGGRAPH 2007). A fine `shells` simulation is constrained so that weighted averages
//! of its positions (test functions φ_i) equal the corresponding averages of a coarse guide
//! animation (eq. 1–8); the constraints enter the implicit Euler step as Lagrange multipliers
//! (§4.3), so detail finer than the test functions stays physical while the coarse motion
//! follows the guide.
//!
//! Modules: [`guide`] (guide trajectories), [`testfn`] and [`cluster`] (test-function designs),
//! [`constraints`] (𝓜, C̄, C, eq. 8, rank), [`kkt`] (the saddle-point solvers) and [`augmented`] (the augmented-Lagrangian one), [`tracker`] (the
//! constrained step, initial projection, residuals), [`metrics`] (deviation, wavelength, tug
//! index, …), [`procedural`] (the guides of the paper's scenes), [`rest_events`] (scheduled rest-angle
//! changes) and [`capture`] (one step's system kept for benchmarks); [`presets`] (the paper's
//! materials and scene setups) and [`experiments`] (every figure and table of the paper as a
//! callable experiment, the lockstep tracked/untracked run protocol).

#![allow(clippy::neg_cmp_op_on_partial_ord)]
#![allow(clippy::needless_range_loop)]

pub mod augmented;
pub mod capture;
pub mod cluster;
pub mod constraints;
pub mod error;
pub mod experiments;
pub mod guide;
pub mod kkt;
pub mod metrics;
pub mod presets;
pub mod procedural;
pub mod rest_events;
pub mod testfn;
pub mod tracker;
pub mod usd_guide;

pub use capture::CapturedSystem;
pub use cluster::{cluster, ClusterInit, ClusterMetric, ClusterOptions, Clustering};
pub use constraints::{pg_mass_matrix, GramFactor, TrackingConstraints};
pub use error::{Result, TrackError};
pub use guide::{GuideAnimation, ProceduralFn, TimeInterp};
pub use kkt::{CompareStats, KktMethod, KktStats, TrackingSolver};
pub use rest_events::RestEvents;
pub use testfn::{build_test_functions, RegionSel, TestFunctionSpec, TestFunctions, TestKind};
pub use tracker::{TrackOptions, TrackStepStats, Tracker};

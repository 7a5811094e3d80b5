//! # perf-control
//!
//! Example-based mapping from a control motion to a target motion (Eugene Hsu, Sommer Gentry,
//! Jovan Popović, *Example-Based Control of Human Motion*, SCA 2004): a new control input (hips
//! floor trajectory, mouse path) is explained as a chain of database control segments, each
//! rigidly moved on the floor and uniformly time-stretched; a dynamic program (paper eqs. 6–7)
//! picks the chain balancing how well each segment explains its stretch of the input against how
//! continuously the corresponding target segments join; the chosen targets, placed the same way
//! and blended at the seams, form the output.
//!
//! Modules: [`track`] (point-cloud motion, stretch, downsampling), [`align`] (closed-form planar
//! alignment), [`db`] (takes, instances, database), [`reduce`] (complete-linkage reduction),
//! [`cell`] (one DP cell), [`dp`] (the DP, beam, forced segments), [`refine`] (upsampling
//! refinement), [`output`] (target construction, post-processing, skeletal output), [`control`]
//! (control builders), [`eval`] (metrics, walk and dance), [`data`] (procedural walks, mouse paths
//! and the partner-dance duet), [`dance`] (the dance grammar), [`handhold`] (handhold propagation
//! and closing, §3.11), [`stream`] (fixed-lag streaming DP, §13),
//! [`pipeline`] (the end-to-end call [`drive`]), [`presets`] (the paper's databases) and
//! [`experiments`] (the paper's experiments, callable without xtask).
//!
//! Conventions: metres, seconds, Y up, planar transforms = geom-core's [`geom_core::math::Planar`];
//! frames at the working rate unless stated; shared boundary samples between consecutive
//! segments (`t_i = t_{i−1} + d_i`, `t_L = T − 1`).

pub mod align;
pub mod cell;
pub mod control;
pub mod dance;
pub mod data;
pub mod db;
pub mod dp;
pub mod error;
pub mod eval;
pub mod experiments;
pub mod handhold;
pub mod output;
pub mod pipeline;
pub mod presets;
pub mod reduce;
pub mod refine;
pub mod stream;
pub mod track;

pub use align::{align, Alignment};
pub use control::{end_effectors, hips_control, path_control};
pub use db::{Instance, MappingDb, SegmentLabel, Side, Take};
pub use dp::{interpret, score_chain, Chosen, DpParams, DpStats, Forced, Interpretation};
pub use error::{PcError, Result};
pub use eval::{tracking_error, TrackingStats};
pub use output::{
    achieved_control, placed_motions, placed_segments, postprocess_segments, propagate, target_motion, target_points,
    Signal,
};
pub use pipeline::{drive, drive_points, Driven, DrivenPoints};
pub use presets::PreparedDb;
pub use reduce::{ClusterBy, ClusterDistance, ClusterOptions, ClusterReport, Representative};
pub use refine::refine;
pub use track::PointTrack;

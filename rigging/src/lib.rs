//! # rigging
//!
//! Automatic rigging of a static character mesh (Baran and Popović, *Automatic Rigging and
//! Animation of 3D Characters*, SIGGRAPH 2007 — the Pinocchio system): a generic skeleton
//! template is embedded in the character (adaptive distance field → approximate medial surface →
//! sphere packing → graph → discrete penalty minimisation by best-first branch and bound →
//! continuous refinement), then every surface vertex is attached to the bones by bone-heat
//! diffusion (one sparse Cholesky factorisation, one back-substitution per bone).
//!
//! Coordinates: +Y up, characters face +Z, their left is +X. Internally everything runs on the
//! normalized mesh (largest bounding-box extent 0.9, centred in the unit cube, spec §3.0); results
//! are mapped back to the input coordinates.

// Negated comparisons (`!(x > 0.0)`) are deliberate: they reject NaN together with the bad range.
// Index loops over joints/coordinates mirror the paper's subscripts.
#![allow(clippy::neg_cmp_op_on_partial_ord, clippy::needless_range_loop)]

pub mod df;
pub mod error;
pub mod prep;
pub mod template;

pub use df::{DfStats, DistanceField};
pub use error::{Result, RigError};
pub use prep::{normalize, prepare, PrepReport};
pub use template::{ReducedSkeleton, SkeletonTemplate, TemplateJoint};
pub mod embed;
pub mod graph;
pub mod medial;
pub mod options;
pub use embed::{DiscreteEmbedding, Hint};
pub use graph::EmbedGraph;
pub use medial::Sphere;
pub use options::{RigOptions, GAMMA_PUBLISHED};
pub mod characters;
pub mod eval;
pub mod heat;
pub mod refine;
pub mod rig;
pub use rig::{autorig, prepare_embedding, Embedding, Rig, RigDiagnostics, StageTimings};
pub mod character;
pub mod experiments;
pub mod export;
pub mod learn;
pub mod metrics;
pub mod orient;
pub mod presets;
pub mod preview;
pub mod walk;

//! Motion graphs: synthesis by randomized search over a hierarchy of motion graphs
//! (Okan Arikan and D. A. Forsyth, "Interactive Motion Generation from Examples", SIGGRAPH 2002;
//! spec `motion-graph.md`).
//!
//! Pipeline: [`Database`] (resample to one rate, fragment, contacts and labels) →
//! [`MotionGraph::build`] (torso-frame features, frame-to-frame cost §3.2, edges below a
//! threshold τ §3.3, hierarchy of graphs by edge clustering §3.4) → [`Search`] (randomized search
//! over paths §3.5–3.8 for a [`Problem`] of soft and hard constraints) → [`assemble`], [`smooth`]
//! (±W frames around each cut, §3.10) and [`enforce_body`] (exact body constraints, §3.11) →
//! [`evaluate`] (§3.12 metrics). [`experiments::search`] runs a whole scene (MG-1 … MG-8) and
//! [`metrics`] turns its results into the figures of `summary.json`.
//!
//! Conventions: metres, seconds, radians inside (degrees in scene files); +Y up, characters
//! face +Z; frames at the database rate (default 30 Hz).

pub mod assemble;
pub mod db;
pub mod error;
pub(crate) mod eval;
pub mod experiments;
pub mod features;
pub mod graph;
pub mod guided;
pub mod kmeans;
pub mod metrics;
pub mod path;
pub mod problem;
pub mod rigid;
pub mod search;

pub use assemble::{assemble, enforce_body, evaluate, fix_contacts, kernel, smooth, Assembled, ClipStats, Metrics};
pub use db::{Database, DbParams};
pub use error::{Error, Result};
pub use features::{FeatureTable, JointWeights};
pub use graph::{EdgeId, EdgeNode, FrameRef, GraphParams, GraphStats, MotionGraph};
pub use guided::GuidedParams;
pub use path::{Path, ScoreParts, Scored};
pub use problem::{
    random_mg1, BodyConstraint, Disc, HardConstraint, JointConstraint, Problem, StyleConstraint, Weights,
};
pub use rigid::Rigid2;
pub use search::{Search, SearchParams, StepReport, Tolerance};

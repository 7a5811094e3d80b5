//! Per-crate adapters (issue 21): each loads a scene's `params` block, calls the crate's
//! experiment with a file recorder ([`crate::record::run_experiment`]) and returns the figures
//! of `summary.json`. Each module's `register` adds its runners.

pub mod flip_tet;
pub mod motion_graph;
pub mod rigging;
pub mod shells;

//! Thin per-crate adapters onto [`crate::record::run_experiment`] (issue 21): each module maps
//! scene methods to a method crate's `experiments::<scene>::run` and converts its error type.

pub mod cloth_fit;

//! Per-crate adapters (issue 21): each loads a scene's parameters, calls the crate's experiment
//! with a file-writing recorder (`crate::record::run_experiment`) and returns the figures of
//! `summary.json`. Experiments, setups and metrics live in the method crates.

pub mod rigging;

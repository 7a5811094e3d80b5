//! Per-crate adapters: each loads a scene file's `params` as the crate's own experiment
//! parameters, runs the crate's experiment with the file-writing recorder and returns the
//! figures for `summary.json` (issue 21).

pub mod shells;

//! Per-crate adapters (issue 21): each module registers its crate's scene methods, each a call
//! of the crate's experiment through [`crate::record::run_experiment`], and converts the
//! crate's error type into [`crate::error::Error`].

pub mod tracks;

//! Scene runners, one module per crate. Each module's `register` adds its runners.

pub mod barnet;
pub mod curve_skin;
pub mod geom_core;
pub mod perf_control;
pub mod tracks;
pub mod tracks_variants;
pub mod wrinkles;

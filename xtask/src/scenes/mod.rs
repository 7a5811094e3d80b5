//! Scene runners, one module per crate. Each module's `register` adds its runners.

pub mod barnet;
pub mod curve_skin;
pub mod flip_tet;
pub mod flip_tet_adaptive;
pub mod flip_tet_holes;
pub mod flip_tet_snapshots;
pub mod flip_tet_variants;
pub mod geom_core;
pub mod motion_graph;
pub mod perf_control;
pub mod rigging;
pub mod tracks;
pub mod tracks_variants;
pub mod wrinkles;

//! Scene runners, one module per crate. Each module's `register` adds its runners.

pub mod geom_core;
pub mod curve_skin; // TEMP-CURVESKIN
pub mod shells; // TEMP-SHELLS

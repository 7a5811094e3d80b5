//! Scene runners, one module per crate. Each module's `register` adds its runners.

pub mod tracks;
pub mod tracks_variants;

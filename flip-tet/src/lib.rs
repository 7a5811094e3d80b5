//! Highly adaptive FLIP liquids on graded tetrahedral (BCC) meshes, after Ando, Thürey and Wojtan,
//! *Highly Adaptive Liquid Simulations on Tetrahedral Meshes*, SIGGRAPH 2013.
//!
//! See `README.md` and `shared/specs/flip-tet.md` for the method and the module map (spec §2).

pub mod advect;
pub mod bcc;
pub mod error;
pub mod experiments;
#[cfg(feature = "fvm-baseline")]
pub mod fvm_baseline;
pub mod inflow;
pub mod metrics;
pub mod obstacle;
pub mod octree;
pub mod ops;
pub mod particles;
pub mod presets;
pub mod pressure;
pub mod reference;
pub mod scene;
pub mod sim;
pub mod sizing;
pub mod split_merge;
pub mod surface;
pub mod transfer;

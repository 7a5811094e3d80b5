//! # geom-core
//!
//! The base crate every method crate of the toolkit builds on (see `GEOM-CORE.md` in the design
//! notes): index-based half-edge triangle meshes and their geometry, mesh I/O, procedural
//! generators, sparse linear algebra over faer, spatial queries, the parry boundary, skeletons and
//! motion clips, and a small software rasteriser.
//!
//! Conventions: `f64`, SI units, right-handed; positions are [`math::Pt3`], solvers take flat
//! `[x0, y0, z0, x1, …]` slices ([`linalg::flat`]); indices are `u32` with [`NONE`] as "no element".

#[cfg(feature = "anim")]
pub mod anim;
pub mod clock;
pub mod cluster;
#[cfg(feature = "parry")]
pub mod collide;
pub mod error;
pub mod experiment;
pub mod experiments;
pub mod graph;
pub mod image;
pub mod io;
pub mod iso;
pub mod kinematic;
pub mod linalg;
pub mod math;
pub mod mesh;
pub mod procedural;
pub mod query;
pub mod raster;
pub mod record;
pub mod rng;
pub mod spatial;
pub mod stats;

pub use error::{BvhError, Error, Result};
pub use faer;
pub use nalgebra;

/// The "no element" index (a boundary half-edge's missing twin, a background pixel's face …).
pub const NONE: u32 = u32::MAX;

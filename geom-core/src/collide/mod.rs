//! The parry boundary (GEOM-CORE.md §3.10, feature `parry`): the only module that imports
//! `parry3d-f64`. Other crates describe obstacles with [`Shape`] and [`Placed`], query closed
//! meshes through [`MeshQuery`], and never see parry or glam types except through
//! [`convert`].
//!
//! Which shape uses what:
//! - [`Shape::HalfSpace`] and [`Shape::Ball`]: closed forms for every query (no parry call).
//! - [`Shape::Capsule`]: closed-form point projection, segment contacts and separated triangle
//!   contacts; ray casts and penetrating triangle contacts (EPA) through parry.
//! - [`Shape::Cuboid`]: parry for every query.
//! - [`Shape::Mesh`]: [`MeshQuery`] (a parry `TriMesh` with pseudo-normals).
//!
//! Signed distances are negative inside; contact normals point from the shape towards the other
//! object; ray hits are times `t` along `o + t d` (in units of `|d|`).

pub mod convert;
mod mesh_query;
mod placed;

pub use mesh_query::{Closest, MeshQuery};
pub use placed::{Contact, Placed, Projection, Shape};

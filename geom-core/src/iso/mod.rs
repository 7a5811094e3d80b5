//! Implicit surfaces (GEOM-CORE.md §3.11): analytic signed distance primitives with smooth
//! union ([`sdf`]), marching tetrahedra over an arbitrary tetrahedral grid ([`marching_tets`]),
//! and the regular-grid polygonizer ([`polygonize`], [`polygonize_to_count`]) used to mesh the
//! procedural characters of [`crate::procedural::character`].
//!
//! Sign convention everywhere: a field value `< 0` is inside, `> 0` outside; output triangles
//! face outward (towards increasing field values).

mod marching;
mod polygonize;
pub mod sdf;

pub use marching::marching_tets;
pub use polygonize::{polygonize, polygonize_to_count, PolygonizeOptions};

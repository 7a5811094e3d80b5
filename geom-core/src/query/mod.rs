//! Geometric queries (GEOM-CORE.md §3.9): exact orientation predicates, an exact
//! triangle–triangle intersection test, mesh self-intersection detection and closest-point
//! computations between points, segments and triangles.
//!
//! The predicates are Shewchuk's adaptive-precision ones (the `robust` crate), and every
//! yes/no answer built on them here is exact for the given `f64` coordinates: no tolerance,
//! degenerate configurations (coplanar, collinear, touching) are decided correctly.

mod closest;
mod predicates;
mod self_intersect;
mod tri_tri;

pub use closest::{closest_point_segment, closest_point_triangle, closest_points_segments};
pub use predicates::{orient2d, orient3d};
pub use self_intersect::{count_self_intersections, self_intersecting_pairs};
pub use tri_tri::{segment_triangle_intersect, tri_tri_intersect};

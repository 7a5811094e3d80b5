//! Triangle meshes: [`TriMesh`] with its half-edge [`Topology`], plain polygon meshes
//! ([`PolyMesh`]), per-element geometry, discrete operators, subdivision, smoothing, welding and
//! repair (GEOM-CORE.md §3.4).
//!
//! Conventions: faces are counter-clockwise seen from the front (outward for closed meshes);
//! geometry functions are free functions over `(faces, positions)` so they work for any
//! deformed positions sharing the faces, generic over [`crate::math::AsPt3`].

mod geometry;
mod hash;
mod hinge;
mod operators;
mod poly;
mod repair;
mod smooth;
mod subdivide;
mod topology;
mod tri;
mod weld;

pub use geometry::{face_areas, face_normals, signed_volume, signed_volume_capped, vertex_normals, NormalWeight};
pub use hinge::{hinge_angle, hinge_angle_checked, hinge_angles, HINGE_COLLAPSE_REL};
pub use operators::{cotan_stiffness, mass_barycentric, mass_p1, mass_voronoi, mean_curvature_normal, COT_SIN_FLOOR};
pub use poly::PolyMesh;
pub use repair::{RepairOptions, RepairReport};
pub use smooth::{taubin_smooth, SmoothWeight};
pub use subdivide::subdivide_linear;
pub use topology::{EdgeId, FaceId, HalfEdgeId, Topology, VertexId};
pub use tri::{bbox_of, TriMesh, Uv, DEGENERATE_REL_AREA};
pub use weld::weld;

//! Spatial acceleration structures (GEOM-CORE.md §3.8): axis-aligned boxes ([`Aabb`]), a bounding
//! volume hierarchy over boxes ([`AabbTree`]: overlap queries, self-pairs, refit) and a k-d tree
//! over points ([`KdTree`]: nearest, k-nearest, radius search).
//!
//! Everything here is our own code (no parry types) and deterministic: the same input gives the
//! same tree and the same callback order on every run and thread count, so that broad phases feed
//! reproducible narrow phases.

mod aabb;
mod aabb_tree;
mod kdtree;

pub use aabb::Aabb;
pub use aabb_tree::AabbTree;
pub use kdtree::KdTree;

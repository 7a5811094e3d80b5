//! A small software rasteriser (GEOM-CORE.md §3.15): pinhole [`Camera`]s, a
//! perspective-correct G-buffer rasteriser ([`rasterize`]), a texture-space rasteriser
//! ([`rasterize_uv`]), and the images built from a [`GBuffer`]: coverage, silhouette, depth,
//! normals and Lambert shading, written as PNG by [`render_views`].
//!
//! Conventions (OpenCV, CF §3.3): a pixel's continuous coordinates are `(PX̃)₀/(PX̃)₂,
//! (PX̃)₁/(PX̃)₂`, the centre of the top-left pixel is `(0, 0)`, `x` grows right and `y` down; the
//! depth of a point is `w = (PX̃)₂`, positive in front of the camera (metres for a camera built
//! by [`Camera::look_at`] or [`Camera::from_krt`] with `K₃₃ = 1`).
//!
//! Rasterisation follows the classic edge-function formulation (Pineda 1988) with the
//! Direct3D/OpenGL top-left fill rule, so that triangles sharing an edge never cover a sample
//! twice nor leave a gap; triangles are clipped against the near plane `w = near_w` in
//! homogeneous coordinates before projection; barycentrics are perspective-correct; the
//! z-buffer keeps the smallest `w` (ties: the lower face index). Work is split into horizontal
//! bands processed in parallel, each visiting its triangles in face order, so the result is
//! bitwise independent of the thread count.

mod camera;
mod gbuffer;
mod rasterize;
mod views;

pub use camera::Camera;
pub use gbuffer::{GBuffer, NormalSpace};
pub use rasterize::{rasterize, rasterize_uv, RasterOptions};
pub use views::{lambert_preview, render_images, render_views, RenderedViews, ViewImages, AMBIENT};

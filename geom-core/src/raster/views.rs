//! Preview renders: Lambert shading and the four standard views (depth, normals, silhouette,
//! shaded) written as PNG.

use std::path::{Path, PathBuf};

use super::camera::Camera;
use super::gbuffer::{GBuffer, NormalSpace};
use super::rasterize::{rasterize, RasterOptions};
use crate::error::Result;
use crate::image::{write_png_gray16, write_png_gray8, write_png_mask, write_png_rgb8, ImageF32, ImageRgbF32, Mask};
use crate::math::{Pt3, Vec3};

/// Ambient term of [`lambert_preview`]: shading is `AMBIENT + (1 − AMBIENT) · max(0, n · l)`, so
/// surfaces turned away from the light stay visible against the black background.
pub const AMBIENT: f32 = 0.15;

/// Flat-shaded, two-sided Lambert image of the mesh `(p, faces)` seen by `c`, in `[0, 1]`,
/// background 0.
///
/// `light` is the direction *towards* the light (world, any length); each face uses its unit
/// normal turned towards the camera, shade `AMBIENT + (1 − AMBIENT) · max(0, n · l̂)`, box-filtered
/// over the `o.supersample²` samples. A zero `light` means a headlight: `l̂` points from the face
/// towards the camera centre.
pub fn lambert_preview(c: &Camera, p: &[Pt3], faces: &[[u32; 3]], light: &Vec3, o: &RasterOptions) -> ImageF32 {
    lambert_resolve(&rasterize(c, p, faces, o), c, p, faces, light)
}

/// The shading of [`lambert_preview`] on an existing G-buffer.
fn lambert_resolve(gb: &GBuffer, c: &Camera, p: &[Pt3], faces: &[[u32; 3]], light: &Vec3) -> ImageF32 {
    let l = light.try_normalize(0.0);
    let eye = c.center();
    let shade: Vec<f32> = faces
        .iter()
        .map(|f| {
            if f.iter().any(|&v| v as usize >= p.len()) {
                return 0.0;
            }
            let [a, b, d] = f.map(|v| p[v as usize]);
            let mut n = (b - a).cross(&(d - a)).try_normalize(0.0).unwrap_or_else(Vec3::zeros);
            if !c.is_front_facing(&a, &b, &d) {
                n = -n;
            }
            let centroid = Pt3::from((a.coords + b.coords + d.coords) / 3.0);
            let dir = match (l, eye) {
                (Some(l), _) => l,
                (None, Some(e)) => (e - centroid).try_normalize(0.0).unwrap_or_else(Vec3::zeros),
                (None, None) => -c.view_rotation().row(2).transpose(),
            };
            AMBIENT + (1.0 - AMBIENT) * n.dot(&dir).max(0.0) as f32
        })
        .collect();
    gb.resolve(|f, _| shade.get(f as usize).copied().unwrap_or(0.0), 0.0)
}

/// Paths and metadata of the images written by [`render_views`].
#[derive(Clone, Debug, PartialEq)]
pub struct RenderedViews {
    /// 16-bit depth PNG: `value / 65535 · depth_max` is the nearest depth `w`; 0 = background.
    pub depth: PathBuf,
    /// 8-bit RGB camera-space normals (smooth), `(n + 1)/2`, background black.
    pub normal: PathBuf,
    /// 8-bit silhouette mask (pixel coverage above one half).
    pub silhouette: PathBuf,
    /// 8-bit Lambert preview ([`lambert_preview`]).
    pub shaded: PathBuf,
    /// Largest depth in the image (the depth PNG's full scale), 0 if nothing is visible.
    pub depth_max: f64,
}

/// The four standard views of a mesh, in memory ([`render_images`]).
#[derive(Clone, Debug, PartialEq)]
pub struct ViewImages {
    /// Nearest depth `w` per pixel (0 = background).
    pub depth: ImageF32,
    /// Camera-space smooth normals, `(n + 1)/2` per channel, background black.
    pub normal: ImageRgbF32,
    /// Pixels whose coverage exceeds one half.
    pub silhouette: Mask,
    /// Lambert preview ([`lambert_preview`]).
    pub shaded: ImageF32,
    /// Largest depth in the image, 0 if nothing is visible, NaN if a depth is NaN.
    pub depth_max: f64,
}

impl ViewImages {
    /// The scale that maps depth to the 16-bit PNG's full range (`65535 / depth_max`; 0 when
    /// nothing is visible).
    pub fn depth_scale(&self) -> f64 {
        if self.depth_max > 0.0 {
            65535.0 / self.depth_max
        } else {
            0.0
        }
    }
}

/// Renders the mesh `(p, faces)` with camera `c` into the four standard views (one
/// rasterisation serves all four).
pub fn render_images(c: &Camera, p: &[Pt3], faces: &[[u32; 3]], light: &Vec3, o: &RasterOptions) -> ViewImages {
    let gb = rasterize(c, p, faces, o);
    let depth: ImageF32 = gb.depth();
    // NaN-propagating maximum: a NaN depth (NaN positions) must not read as a valid image.
    let depth_max =
        depth.data.iter().copied().fold(0.0f32, |m, v| if m.is_nan() || v.is_nan() { f32::NAN } else { m.max(v) })
            as f64;
    ViewImages {
        normal: gb.normals(c, p, faces, NormalSpace::Camera, true),
        silhouette: gb.silhouette(0.5),
        shaded: lambert_resolve(&gb, c, p, faces, light),
        depth,
        depth_max,
    }
}

/// Renders the mesh `(p, faces)` with camera `c` ([`render_images`]) and writes four PNGs into
/// `dir` (created if missing): `{stem}_depth.png`, `{stem}_normal.png`, `{stem}_silhouette.png`
/// and `{stem}_shaded.png`. Errors: file system and PNG encoding failures (naming the file).
pub fn render_views(
    c: &Camera,
    p: &[Pt3],
    faces: &[[u32; 3]],
    light: &Vec3,
    o: &RasterOptions,
    dir: &Path,
    stem: &str,
) -> Result<RenderedViews> {
    std::fs::create_dir_all(dir)?;
    let v = render_images(c, p, faces, light, o);
    let out = RenderedViews {
        depth: dir.join(format!("{stem}_depth.png")),
        normal: dir.join(format!("{stem}_normal.png")),
        silhouette: dir.join(format!("{stem}_silhouette.png")),
        shaded: dir.join(format!("{stem}_shaded.png")),
        depth_max: v.depth_max,
    };
    write_png_gray16(&out.depth, &v.depth, v.depth_scale())?;
    write_png_rgb8(&out.normal, &v.normal)?;
    write_png_mask(&out.silhouette, &v.silhouette)?;
    write_png_gray8(&out.shaded, &v.shaded)?;
    Ok(out)
}

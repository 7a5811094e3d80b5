//! The software rasteriser end to end: depth, normal, silhouette and shaded images of each mesh,
//! seen from a camera placed relative to its bounding box.
//!
//! Outputs: `<name>_depth.png` (16-bit, full scale = the largest depth), `<name>_normal.png`,
//! `<name>_silhouette.png`, `<name>_shaded.png`. Figures: `<name>_triangles`,
//! `<name>_silhouette_px`, `<name>_depth_max_m` (NaN if a depth is NaN), `image_width`,
//! `image_height`, and the timings `<name>_render_s`, `render_total_s`.
//!
//! ```
//! use geom_core::experiment::Size;
//! use geom_core::experiments::render::{run, Params};
//! use geom_core::experiments::MeshSource;
//! use geom_core::record::NullRecorder;
//! let p = Params {
//!     size: [64, 48],
//!     quick_size: [32, 24],
//!     supersample: 1,
//!     fov_y_deg: 40.0,
//!     eye_offset: [0.6, 0.45, 1.0],
//!     light: [0.4, 1.0, 0.6],
//!     meshes: vec![("ball".into(), MeshSource::Icosphere { radius: 1.0, level: 1 })],
//!     root: Default::default(),
//! };
//! let r = run(&p, Size::Quick, &mut NullRecorder::default()).unwrap();
//! assert!(r.get_f64("ball_silhouette_px") > 0.0);
//! ```

use std::path::PathBuf;
use std::time::Instant;

use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};
use crate::experiment::{Report, Size, Target};
use crate::image::{encode_png_gray16, encode_png_gray8, encode_png_mask, encode_png_rgb8};
use crate::math::{Pt3, Vec3};
use crate::raster::{render_images, Camera, RasterOptions};
use crate::record::Recorder;

use super::MeshSource;

/// The scene's `params` block.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Params {
    /// Image width and height in pixels (default size; full size doubles them).
    pub size: [u32; 2],
    /// Image size of the quick and tiny runs.
    pub quick_size: [u32; 2],
    /// Supersampling per axis.
    pub supersample: u32,
    /// Vertical field of view (degrees).
    pub fov_y_deg: f64,
    /// Camera position relative to the mesh's bounding-box centre, in bounding-box diagonals.
    pub eye_offset: [f64; 3],
    /// Direction towards the light.
    pub light: [f64; 3],
    /// The meshes, each rendered into `<name>_{depth,normal,silhouette,shaded}.png`.
    pub meshes: Vec<(String, MeshSource)>,
    /// Folder relative mesh files are read from (not part of the scene file: the caller sets it).
    #[serde(skip)]
    pub root: PathBuf,
}

/// Renders every mesh; see the module docs.
pub fn run(p: &Params, size: Size, rec: &mut dyn Recorder) -> Result<Report> {
    let [w, h] = size.pick(p.quick_size, p.size, [p.size[0] * 2, p.size[1] * 2]);
    if w == 0 || h == 0 || p.supersample == 0 || !(1.0..179.0).contains(&p.fov_y_deg) {
        return Err(Error::InvalidParameter(
            "render: size and supersample must be ≥ 1 and fov_y_deg in [1, 179)".into(),
        ));
    }
    let mut s = Report::default();
    let opts = RasterOptions { supersample: p.supersample, ..RasterOptions::default() };
    let light = Vec3::new(p.light[0], p.light[1], p.light[2]);
    let mut total_s = 0.0;
    for (i, (name, src)) in p.meshes.iter().enumerate() {
        rec.progress(i as u64, p.meshes.len() as u64);
        let m = src.build(&p.root)?;
        let (lo, hi) = m.bbox().ok_or_else(|| Error::InvalidParameter(format!("render: mesh '{name}' is empty")))?;
        let center = Pt3::from((lo.coords + hi.coords) * 0.5);
        let diag = (hi - lo).norm().max(1e-12);
        let eye = center + Vec3::new(p.eye_offset[0], p.eye_offset[1], p.eye_offset[2]) * diag;
        let cam = Camera::look_at(&eye, &center, &Vec3::y(), p.fov_y_deg, w, h)?;
        let t0 = Instant::now();
        let v = render_images(&cam, &m.positions, &m.faces, &light, &opts);
        if rec.keeps_outputs() {
            rec.file(&format!("{name}_depth.png"), &encode_png_gray16(&v.depth, v.depth_scale())?)?;
            rec.file(&format!("{name}_normal.png"), &encode_png_rgb8(&v.normal)?)?;
            rec.file(&format!("{name}_silhouette.png"), &encode_png_mask(&v.silhouette)?)?;
            rec.file(&format!("{name}_shaded.png"), &encode_png_gray8(&v.shaded)?)?;
        }
        let dt = t0.elapsed().as_secs_f64();
        total_s += dt;
        s.count(&format!("{name}_triangles"), m.faces.len() as u64);
        s.count(&format!("{name}_silhouette_px"), v.silhouette.count() as u64);
        s.num(&format!("{name}_depth_max_m"), v.depth_max);
        s.timing(&format!("{name}_render_s"), dt);
        s.check(&format!("{name}_silhouette_px"), Target::Above(0.0), "the mesh is in view");
    }
    s.timing("render_total_s", total_s);
    s.count("image_width", w as u64);
    s.count("image_height", h as u64);
    Ok(s)
}

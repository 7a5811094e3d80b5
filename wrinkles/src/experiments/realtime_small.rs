//! W6 (spec §6): the paper's real-time claim on a small sheet. A 98-triangle sheet under a
//! prescribed travelling wave; frames per second of modulation plus a level-L displaced mesh,
//! and of modulation plus a bump-mapped software preview.
//!
//! Outputs: `preview.png` (8-bit, last frame) and `last_frame.obj`. Figures: `triangles`,
//! `frames`, `displaced_vertices`, `last_displaced_area_m2`, and the timings `ms_modulation`,
//! `ms_displaced_mesh`, `ms_bump_preview`, `fps_modulation_plus_mesh`,
//! `fps_modulation_plus_preview` with `profile`.
//!
//! ```no_run
//! use wrinkles::experiments::realtime_small::{run, Params};
//! use geom_core::experiment::Size;
//! use geom_core::record::NullRecorder;
//! let p: Params = ron::from_str(
//!     "(size: 0.3, quads: 7, level: 8, frames: 10, preview: (320, 240), wavelength: 0.03, slope: 0.6)",
//! )
//! .unwrap();
//! let r = run(&p, Size::Quick, &mut NullRecorder::default()).unwrap();
//! assert_eq!(r.get_f64("triangles"), 98.0);
//! ```

use std::time::Instant;

use geom_core::experiment::{BySize, Report, Size};
use geom_core::image::encode_png_gray8;
use geom_core::io::{obj, MeshOut};
use geom_core::math::{Pt3, Vec3};
use geom_core::raster::{rasterize, Camera, RasterOptions};
use geom_core::record::Recorder;
use serde::Deserialize;

use crate::animator::{ModulationOptions, WrinkleAnimator};
use crate::coeffs::{precompute, PrecomputeOptions};
use crate::displaced::Refinement;
use crate::error::{Result, WrinkleError};
use crate::presets::{sheet, sinusoid, travelling_wave};

/// The scene's `params` block.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Params {
    /// Sheet side (m).
    pub size: f64,
    /// Quads per side (7 → 98 triangles).
    pub quads: u32,
    /// Displaced-mesh level.
    pub level: u32,
    /// Frames.
    pub frames: BySize<usize>,
    /// Preview resolution (pixels).
    pub preview: [u32; 2],
    /// Pattern wavelength (UV m).
    pub wavelength: f64,
    /// Pattern rest slope.
    pub slope: f64,
}

/// Runs the animation; see the module docs.
pub fn run(p: &Params, size: Size, rec: &mut dyn Recorder) -> Result<Report> {
    let frames = p.frames.get(size).max(1);
    if p.size.is_nan() || p.size <= 0.0 || p.quads == 0 || p.level == 0 || p.preview.contains(&0) {
        return Err(WrinkleError::InvalidOption("size, quads, level and preview must be positive".into()));
    }
    let mesh = sheet(p.quads, p.size)?;
    let pats = vec![sinusoid(p.wavelength, 0.0, p.slope)?, sinusoid(p.wavelength, 90.0, p.slope)?];
    let rig = precompute(&mesh, &pats, &PrecomputeOptions::default())?;
    let mut a = WrinkleAnimator::new(rig.clone(), ModulationOptions::default())?;
    let refine = Refinement::new(mesh.positions.len(), &mesh.faces, &rig.edges, p.level);
    let c = p.size * 0.5;
    let eye = Pt3::new(c, -0.6 * p.size, 1.2 * p.size);
    let cam = Camera::look_at(&eye, &Pt3::new(c, c, 0.0), &Vec3::z(), 40.0, p.preview[0], p.preview[1])?;
    let light = Vec3::new(0.3, -0.5, 1.0).normalize();
    let (mut t_mod, mut t_mesh, mut t_prev) = (0.0, 0.0, 0.0);
    let mut last_area = 0.0;
    for k in 0..frames {
        rec.progress(k as u64, frames as u64);
        let def = travelling_wave(&mesh, p.size, k as f64 / 30.0);
        let t0 = Instant::now();
        let fm = a.frame(&def)?;
        let t1 = Instant::now();
        let dm = a.displaced_on(&refine, &def, &fm);
        let t2 = Instant::now();
        // Bump-mapped preview of the coarse mesh: per-sample shading with the bump normal.
        let gb = rasterize(&cam, &def, &mesh.faces, &RasterOptions::default());
        let img = gb.resolve(
            |f, b| {
                let n = a.bump_normal(&def, &fm, f as usize, [b[0] as f64, b[1] as f64, b[2] as f64]);
                (n.dot(&light).abs() * 0.9 + 0.1) as f32
            },
            0.0,
        );
        let t3 = Instant::now();
        t_mod += (t1 - t0).as_secs_f64();
        t_mesh += (t2 - t1).as_secs_f64();
        t_prev += (t3 - t2).as_secs_f64();
        if k == frames - 1 {
            last_area = dm.area();
            if rec.keeps_outputs() {
                rec.file("preview.png", &encode_png_gray8(&img)?)?;
                let text = obj::to_string(&MeshOut::tri(&dm.positions, &dm.faces).with_uv(&dm.uv))?;
                rec.file("last_frame.obj", text.as_bytes())?;
            }
        }
    }
    let n = frames as f64;
    let mut r = Report::default();
    r.text("profile", if cfg!(debug_assertions) { "debug" } else { "release" });
    r.count("triangles", mesh.faces.len() as u64);
    r.count("frames", frames as u64);
    r.count("displaced_vertices", refine.n_vertices as u64);
    r.timing("ms_modulation", 1e3 * t_mod / n);
    r.timing("ms_displaced_mesh", 1e3 * t_mesh / n);
    r.timing("ms_bump_preview", 1e3 * t_prev / n);
    r.timing("fps_modulation_plus_mesh", n / (t_mod + t_mesh));
    r.timing("fps_modulation_plus_preview", n / (t_mod + t_prev));
    r.num("last_displaced_area_m2", last_area);
    Ok(r)
}

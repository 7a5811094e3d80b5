//! W5 (spec §6): precomputation time against triangle count and tolerance. The procedural
//! folds rendered into an image and read back through the B-spline image path, on sheets of
//! constant triangle size (22 quads per 0.5 m), so the paper's per-triangle cost model predicts
//! a time linear in T.
//!
//! Outputs: table `metrics` (tolerance, triangles, seconds, quadrature points per triangle,
//! unconverged triangles), plot `precompute_vs_T`. Figures: `image_side`,
//! `paper_s_per_1000_tri` (300 s), and the timings `loglog_slope_tol<τ>` (fitted exponent of
//! time against T), `s_per_1000_tri_tol<τ>` (at the largest T) with `profile`.
//!
//! ```no_run
//! use wrinkles::experiments::precompute_cost::{run, Params};
//! use geom_core::experiment::Size;
//! use geom_core::record::NullRecorder;
//! let p: Params =
//!     ron::from_str("(quads: [7, 14], tolerances: [1.0e-3], image: 64, wavelength: 0.04, slope: 0.5)").unwrap();
//! let r = run(&p, Size::Quick, &mut NullRecorder::default()).unwrap();
//! assert!(r.get_f64("s_per_1000_tri_tol1e-3") > 0.0);
//! ```

use std::time::Instant;

use geom_core::experiment::{BySize, Report, Size};
use geom_core::image::ImageF32;
use geom_core::math::Pt2;
use geom_core::record::{Recorder, Series};
use geom_core::stats;
use serde::Deserialize;

use crate::coeffs::{precompute, CoeffStatus, PrecomputeOptions};
use crate::error::{Result, WrinkleError};
use crate::pattern::{Normalization, PatternOptions, PatternSource, UvTransform, WrinklePattern};
use crate::presets::{folds_source, sheet};

/// The scene's `params` block.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Params {
    /// Quads per side of the sheets (T = 2·q²).
    pub quads: BySize<Vec<u32>>,
    /// Quadrature tolerances.
    pub tolerances: BySize<Vec<f64>>,
    /// Image side (texels).
    pub image: BySize<u32>,
    /// Fold wavelength in texture units ([0, 1] spans the image).
    pub wavelength: f64,
    /// Rest slope.
    pub slope: f64,
}

/// Runs the sweep; see the module docs.
pub fn run(p: &Params, size: Size, rec: &mut dyn Recorder) -> Result<Report> {
    let (quads, tols, n) = (p.quads.get(size), p.tolerances.get(size), p.image.get(size));
    if quads.is_empty()
        || tols.is_empty()
        || n == 0
        || quads.contains(&0)
        || p.wavelength.is_nan()
        || p.wavelength <= 0.0
    {
        return Err(WrinkleError::InvalidOption(
            "quads, tolerances, image and wavelength must be non-empty/positive".into(),
        ));
    }
    // Render the procedural folds into an n × n image (texel centres), then use the spline path.
    let folds = WrinklePattern::new(&folds_source(p.wavelength, 0.0, 7), PatternOptions::default())?;
    let mut img = ImageF32::new(n, n, 0.0);
    for y in 0..n {
        for x in 0..n {
            let uv = Pt2::new((x as f64 + 0.5) / n as f64, (y as f64 + 0.5) / n as f64);
            img.set(x, y, (0.5 + 0.5 * folds.eval(&uv)) as f32);
        }
    }
    let l = 0.5;
    let pat = WrinklePattern::new(
        &PatternSource::Image(img),
        PatternOptions {
            normalization: Normalization::TargetRestSlope(p.slope),
            blur_texels: 1.0,
            uv_transform: UvTransform { scale: [1.0 / l, 1.0 / l], ..Default::default() },
            ..Default::default()
        },
    )?;
    rec.table("metrics", &["tolerance", "triangles", "seconds", "points_per_triangle", "unconverged"])?;
    let mut r = Report::default();
    r.text("profile", if cfg!(debug_assertions) { "debug" } else { "release" });
    r.count("image_side", n as u64);
    for (ti, &tol) in tols.iter().enumerate() {
        let mut pts = Vec::new();
        for (qi, &q) in quads.iter().enumerate() {
            rec.progress((ti * quads.len() + qi) as u64, (tols.len() * quads.len()) as u64);
            // Constant triangle size (22 quads per 0.5 m; the image repeats every 0.5 m): the
            // paper's per-triangle cost model, so the time should be linear in T.
            let mesh = sheet(q, l * q as f64 / 22.0)?;
            let t0 = Instant::now();
            let opts = PrecomputeOptions { tolerance: tol, ..Default::default() };
            let rig = precompute(&mesh, std::slice::from_ref(&pat), &opts)?;
            let secs = t0.elapsed().as_secs_f64();
            let nt = mesh.faces.len();
            let ppt = rig.coeffs.iter().map(|c| c.n_points).sum::<usize>() as f64 / nt as f64;
            let unconv = rig.coeffs.iter().filter(|c| c.status == CoeffStatus::Unconverged).count();
            rec.row("metrics", &[tol.into(), nt.into(), secs.into(), ppt.into(), unconv.into()])?;
            pts.push((nt as f64, secs));
        }
        if pts.len() >= 2 {
            r.timing(&format!("loglog_slope_tol{tol:e}"), stats::loglog_fit(&pts).1);
        }
        if let Some(&(t, s)) = pts.last() {
            r.timing(&format!("s_per_1000_tri_tol{tol:e}"), 1000.0 * s / t);
        }
        rec.series(&Series {
            plot: "precompute_vs_T".into(),
            label: format!("tol {tol:e}"),
            axes: ("triangles".into(), "seconds".into()),
            log: (true, true),
            points: pts,
        })?;
    }
    r.num("paper_s_per_1000_tri", 300.0);
    Ok(r)
}

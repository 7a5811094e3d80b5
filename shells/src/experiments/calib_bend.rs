//! `shells/calib-bend` (shells.md §6 scene 2): an equilateral patch wrapped statically onto a
//! cylinder and a sphere; its interior bending-energy density against 3k_B/R² and 4k_B/R²
//! ([`reference::CYLINDER_DENSITY`], [`reference::SPHERE_DENSITY`]; Grinspun et al. 2003) for
//! several edge lengths ℓ and two lattice orientations.
//!
//! Figures: `cylinder_rel_err`, `sphere_rel_err` (the worse orientation at ℓ = `report_ell`,
//! dimensionless), `report_ell_m`. Table `calib` (one row per ℓ and orientation), plot `calib`
//! (worst error against ℓ).
//!
//! ```
//! use geom_core::experiment::Size;
//! use geom_core::record::NullRecorder;
//! use shells::experiments::calib_bend::{run, Params};
//! let p = Params { patch: 0.2, ells: vec![0.02], cylinder_radius: 0.5, sphere_radius: 2.5, report_ell: 0.02 };
//! let r = run(&p, Size::Quick, &mut NullRecorder::default()).unwrap();
//! assert!(r.get("cylinder_rel_err").and_then(|v| v.as_f64()).unwrap() < 0.01);
//! ```

use geom_core::experiment::{Report, Size, Target};
use geom_core::record::{Cell, Recorder, Series};
use geom_core::stats::nan_max;
use serde::Deserialize;

use crate::calib;
use crate::error::{Error, Result};
use crate::reference;

/// Parameters (the scene file's `params` block).
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Params {
    /// Patch size (m).
    pub patch: f64,
    /// Edge lengths ℓ (m), each in (0, patch/4].
    pub ells: Vec<f64>,
    /// Cylinder radius (m).
    pub cylinder_radius: f64,
    /// Sphere radius (m); the patch must stay ≤ 0.2 R (no wrap onto a sphere is isometric).
    pub sphere_radius: f64,
    /// ℓ at which the figures are read (m).
    pub report_ell: f64,
}

/// Runs the calibration (the same at every size: it is static and takes well under a second).
pub fn run(p: &Params, _size: Size, rec: &mut dyn Recorder) -> Result<Report> {
    if p.ells.iter().any(|&l| !(l > 0.0) || l > p.patch / 4.0) || !(p.cylinder_radius > 0.0) || !(p.sphere_radius > 0.0)
    {
        return Err(Error::BadParameter("ells must be in (0, patch/4], radii > 0".into()));
    }
    rec.table(
        "calib",
        &["ell_m", "orientation", "cylinder_ratio", "cylinder_rel_err", "sphere_ratio", "sphere_rel_err"],
    )?;
    let (mut cyl_err, mut sph_err) = (0.0f64, 0.0f64);
    let (mut cyl_series, mut sph_series) = (Vec::new(), Vec::new());
    let mut rows = String::new();
    for &ell in &p.ells {
        let (mut wc, mut ws) = (0.0f64, 0.0f64);
        for rotated in [false, true] {
            let c = calib::measure(p.patch, ell, rotated, p.cylinder_radius, false)?;
            let sp = calib::measure(p.patch, ell, rotated, p.sphere_radius, true)?;
            let orientation = if rotated { "rows-along-y" } else { "rows-along-x" };
            rec.row(
                "calib",
                &[
                    Cell::Num(ell),
                    Cell::Text(orientation.into()),
                    Cell::Num(c.ratio),
                    Cell::Num(c.rel_err),
                    Cell::Num(sp.ratio),
                    Cell::Num(sp.rel_err),
                ],
            )?;
            rows += &format!("| {ell} | {} | {:.4} | {:.4} |\n", orientation.replace('-', " "), c.ratio, sp.ratio);
            wc = nan_max(wc, c.rel_err);
            ws = nan_max(ws, sp.rel_err);
        }
        cyl_series.push((ell, wc));
        sph_series.push((ell, ws));
        if (ell - p.report_ell).abs() <= 1e-12 * p.report_ell {
            cyl_err = wc;
            sph_err = ws;
        }
    }
    let axes = ("edge length ℓ (m)".to_string(), "relative error".to_string());
    for (label, points) in [("cylinder vs 3k_B/R²", cyl_series), ("sphere vs 4k_B/R²", sph_series)] {
        rec.series(&Series {
            plot: "calib".into(),
            label: label.into(),
            axes: axes.clone(),
            log: (true, true),
            points,
        })?;
    }
    rec.note(&format!(
        "### shells/calib-bend\n\nInterior bending-energy density of an equilateral patch divided by k_B/R² \
         (ideal: {} on the cylinder R = {} m, {} on the sphere R = {} m; spec §3.2).\n\n\
         | ℓ (m) | lattice | cylinder | sphere |\n|---|---|---|---|\n{rows}\n\
         Worst of the two orientations at ℓ = {}: cylinder {:.2e}, sphere {:.2e} (Must hold ≤ 0.01).\n",
        reference::CYLINDER_DENSITY,
        p.cylinder_radius,
        reference::SPHERE_DENSITY,
        p.sphere_radius,
        p.report_ell,
        cyl_err,
        sph_err
    ))?;
    let mut r = Report::default();
    r.num("cylinder_rel_err", cyl_err).num("sphere_rel_err", sph_err).num("report_ell_m", p.report_ell);
    let src = "shells.md §6.2 (Discrete Shells calibration, Grinspun et al. 2003)";
    r.check("cylinder_rel_err", Target::AtMost(0.01), src);
    r.check("sphere_rel_err", Target::AtMost(0.01), src);
    Ok(r)
}

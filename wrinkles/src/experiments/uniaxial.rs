//! W1 (spec §6): the analytic area check. A sinusoid on a square (two triangles, optionally a
//! grid) under prescribed uniform deformations — uniaxial compression/stretch `c` and pure
//! shear `b` — for every modulation mode, rest slope and pattern angle; the exact flat-rest
//! mode against the 1-D buckled-strip amplitude ([`crate::reference::strip_amplitude`]), and the
//! linearised mode's residual order.
//!
//! Outputs: tables `metrics` (one row per mesh, slope, angle, load, mode) and `linear_order`;
//! plots `h_vs_c`, `area_err_vs_c`, `lin_err_vs_delta`; OBJ files `c_<c>.obj` of the displaced
//! exact-flat surface. Figures: `exact_flat_max_area_residual`,
//! `exact_flat_max_amplitude_rel_err_vs_1d`, `exact_flat_nonzero_h_under_stretch`,
//! `linear_residual_slope_min`, `linear_residual_slope_max`, `strip_amp_over_lambda_c<c>`,
//! `pass` (1 when every W1 criterion holds), `seconds` (timing).
//!
//! ```no_run
//! use wrinkles::experiments::uniaxial::{run, Params};
//! use geom_core::experiment::Size;
//! use geom_core::record::NullRecorder;
//! let p: Params = ron::from_str(
//!     "(size: 0.1, periods: 8.0, slopes: [1.0], angles_deg: [0.0], grid_quads: 0,
//!       c_range: (1.2, 0.6), c_steps: 5, shear_max: 0.3, shear_steps: 3, tolerance: 1.0e-6,
//!       max_slope: 1.5, obj_at_c: [], obj_level: 8)",
//! )
//! .unwrap();
//! let r = run(&p, Size::Quick, &mut NullRecorder::default()).unwrap();
//! assert!(r.get_f64("exact_flat_max_area_residual") <= 1e-9);
//! ```

use std::time::Instant;

use geom_core::experiment::{BySize, Report, Size, Target};
use geom_core::io::{obj, MeshOut};
use geom_core::math::Mat2;
use geom_core::record::{Cell, Recorder, Series};
use geom_core::stats::{self, nan_max};
use serde::Deserialize;

use crate::animator::{HMax, ModulationOptions, WrinkleAnimator};
use crate::coeffs::{precompute, PrecomputeOptions};
use crate::error::{Result, WrinkleError};
use crate::metrics::uniaxial_frame;
use crate::modulation::{wrinkled_area, ModulationMode, StrainMeasure};
use crate::presets::{sheet, sinusoid, two_triangle_square, uniform};
use crate::reference::strip_amplitude;
use crate::smoothing::Smoothing;

/// The scene's `params` block.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Params {
    /// Square side (m).
    pub size: f64,
    /// Periods across the square.
    pub periods: f64,
    /// Rest slopes compared.
    pub slopes: BySize<Vec<f64>>,
    /// Pattern rotations (degrees).
    pub angles_deg: BySize<Vec<f64>>,
    /// Grid quads per side of the second mesh (0 = skip it).
    pub grid_quads: BySize<u32>,
    /// c sweep `(from, to)`.
    pub c_range: (f64, f64),
    /// c steps.
    pub c_steps: BySize<usize>,
    /// Pure shear b ∈ [−shear_max, shear_max].
    pub shear_max: f64,
    /// Shear steps.
    pub shear_steps: BySize<usize>,
    /// Precomputation tolerance (spec: ≤ 1e-6, all gradient samples kept, for the 1e-5
    /// amplitude check).
    pub tolerance: BySize<f64>,
    /// Cap on the wrinkled slope (h_max = max_slope / s).
    pub max_slope: f64,
    /// c values with OBJ output.
    pub obj_at_c: Vec<f64>,
    /// Displaced-mesh level of the OBJ output.
    pub obj_level: u32,
}

/// The five modulation modes with their figure names.
pub const MODES: [(&str, ModulationMode); 5] = [
    ("lin_green", ModulationMode::Linearized { strain: StrainMeasure::Green }),
    ("lin_abd", ModulationMode::Linearized { strain: StrainMeasure::PaperAbd }),
    ("exact_wrinkled", ModulationMode::ExactWrinkledRest),
    ("exact_flat", ModulationMode::ExactFlatRest),
    ("principal", ModulationMode::PrincipalLength),
];

fn series(plot: &str, label: String, axes: (&str, &str), log: (bool, bool), points: Vec<(f64, f64)>) -> Series {
    Series { plot: plot.into(), label, axes: (axes.0.into(), axes.1.into()), log, points }
}

/// The linearised mode's area residual at `F = diag(1 − δ, 1)`, δ = 0.05·2^−j (j < 5): the
/// `(δ, residual)` points of triangle 0, pattern 0 (spec T5, W1).
fn linear_order_points(a: &mut WrinkleAnimator, mesh: &crate::RestMesh) -> Result<Vec<(f64, f64)>> {
    let mut pts = Vec::new();
    for j in 0..5 {
        let d = 0.05 * 0.5f64.powi(j);
        let f = Mat2::new(1.0 - d, 0.0, 0.0, 1.0);
        let fm = a.frame(&uniform(mesh, &f))?;
        let cf = a.rig().coeff(0, 0);
        let cc = f.transpose() * f;
        let r = (wrinkled_area(&cf.grad_samples, &cc, fm.tri_h[0]) - cf.area_wrinkled).abs() / cf.area_wrinkled;
        pts.push((d, r));
    }
    Ok(pts)
}

/// Runs every variant; see the module docs.
pub fn run(p: &Params, size: Size, rec: &mut dyn Recorder) -> Result<Report> {
    let steps = p.c_steps.get(size).max(2);
    let sh_steps = p.shear_steps.get(size).max(2);
    let (slopes, angles, tolerance) = (p.slopes.get(size), p.angles_deg.get(size), p.tolerance.get(size));
    if !(p.size > 0.0 && p.periods > 0.0 && tolerance > 0.0 && p.max_slope > 0.0)
        || slopes.is_empty()
        || slopes.iter().any(|s| s.is_nan() || *s <= 0.0)
    {
        return Err(WrinkleError::InvalidOption(
            "size, periods, tolerance, max_slope and slopes must be positive (at least one slope)".into(),
        ));
    }
    let lambda = p.size / p.periods;
    let pre = PrecomputeOptions { tolerance, max_depth: 9, gradient_bins: 0, gradient_samples: true };
    let gq = p.grid_quads.get(size);
    let mut meshes = vec![("square2", two_triangle_square(p.size)?)];
    if gq > 0 {
        meshes.push(("grid", sheet(gq, p.size)?));
    }
    rec.table(
        "metrics",
        &[
            "mesh",
            "slope",
            "angle_deg",
            "load",
            "param",
            "mode",
            "h_mean",
            "amplitude_m",
            "area_residual",
            "clipped",
            "analytic_amp_over_lambda",
        ],
    )?;
    rec.table("linear_order", &["slope", "angle_deg", "fitted_order", "res_d0.05", "res_d0.003125"])?;
    let t0 = Instant::now();
    let (mut flat_res_max, mut amp_err_max, mut stretch_violations) = (0.0f64, 0.0f64, 0usize);
    let mut lin_slopes = Vec::new();
    let total = (meshes.len() * slopes.len() * angles.len()) as u64;
    let mut done = 0;
    for (mesh_name, mesh) in &meshes {
        for &s in &slopes {
            for &ang in &angles {
                rec.progress(done, total);
                done += 1;
                let rig = precompute(mesh, &[sinusoid(lambda, ang, s)?], &pre)?;
                let eta = rig.eta[0];
                for (mode_name, mode) in MODES {
                    let o = ModulationOptions {
                        mode,
                        smoothing: Smoothing::PerTriangle,
                        h_max: HMax::Auto { max_slope: p.max_slope },
                        ..Default::default()
                    };
                    let mut a = WrinkleAnimator::new(rig.clone(), o)?;
                    let (mut hv, mut rv) = (Vec::new(), Vec::new());
                    let row = |rec: &mut dyn Recorder,
                               load: &str,
                               param: f64,
                               fr: &crate::metrics::UniaxialFrame,
                               an: f64| {
                        rec.row(
                            "metrics",
                            &[
                                Cell::Text(mesh_name.to_string()),
                                s.into(),
                                ang.into(),
                                load.into(),
                                param.into(),
                                mode_name.into(),
                                fr.h_mean.into(),
                                (fr.h_mean * eta).into(),
                                fr.area_residual.into(),
                                fr.clipped.into(),
                                an.into(),
                            ],
                        )
                    };
                    for k in 0..steps {
                        let c = p.c_range.0 + (p.c_range.1 - p.c_range.0) * k as f64 / (steps - 1) as f64;
                        let fr = uniaxial_frame(&mut a, &uniform(mesh, &Mat2::new(c, 0.0, 0.0, 1.0)))?;
                        let analytic = if ang == 0.0 { strip_amplitude(c) } else { f64::NAN };
                        if mode_name == "exact_flat" {
                            flat_res_max = nan_max(flat_res_max, fr.area_residual);
                            if c >= 1.0 && (fr.h_min != 0.0 || fr.h_mean != 0.0) {
                                stretch_violations += 1;
                            }
                            if ang == 0.0 && fr.clipped == 0 && c < 1.0 {
                                amp_err_max =
                                    nan_max(amp_err_max, (fr.h_mean * eta / lambda - analytic).abs() / analytic);
                            }
                        }
                        hv.push((c, fr.h_mean));
                        rv.push((c, fr.area_residual.max(1e-17)));
                        row(rec, "uniaxial", c, &fr, analytic)?;
                    }
                    for k in 0..sh_steps {
                        let b = -p.shear_max + 2.0 * p.shear_max * k as f64 / (sh_steps - 1) as f64;
                        let fr = uniaxial_frame(&mut a, &uniform(mesh, &Mat2::new(1.0, b, 0.0, 1.0)))?;
                        if mode_name == "exact_flat" {
                            flat_res_max = nan_max(flat_res_max, fr.area_residual);
                        }
                        row(rec, "shear", b, &fr, f64::NAN)?;
                    }
                    if *mesh_name == "square2" && ang == 0.0 {
                        let label = format!("{mode_name} s={s}");
                        rec.series(&series("h_vs_c", label.clone(), ("c", "h"), (false, false), hv))?;
                        if !mode_name.starts_with("lin") {
                            rec.series(&series("area_err_vs_c", label, ("c", "|A - A*|/A*"), (false, true), rv))?;
                        }
                    }
                    // Linear-mode residual order (Green), δ ≤ 0.05.
                    if mode_name == "lin_green" && *mesh_name == "square2" {
                        let pts = linear_order_points(&mut a, mesh)?;
                        let logp: Vec<(f64, f64)> = pts.iter().map(|(d, r)| (d.ln(), r.ln())).collect();
                        let sl = stats::linear_fit(&logp).1;
                        rec.row("linear_order", &[s.into(), ang.into(), sl.into(), pts[0].1.into(), pts[4].1.into()])?;
                        lin_slopes.push(sl);
                        let label = format!("s={s} angle={ang}");
                        rec.series(&series("lin_err_vs_delta", label, ("delta", "|A - A*|/A*"), (true, true), pts))?;
                    }
                }
                // OBJs of the exact flat mode, axis-aligned, on the two-triangle square.
                if *mesh_name == "square2" && ang == 0.0 && s == slopes[slopes.len() - 1] && rec.keeps_outputs() {
                    let o = ModulationOptions {
                        mode: ModulationMode::ExactFlatRest,
                        smoothing: Smoothing::PerTriangle,
                        ..Default::default()
                    };
                    let mut a = WrinkleAnimator::new(rig.clone(), o)?;
                    for &c in &p.obj_at_c {
                        let def = uniform(mesh, &Mat2::new(c, 0.0, 0.0, 1.0));
                        let fm = a.frame(&def)?;
                        let dm = a.displaced_mesh(&def, &fm, p.obj_level)?;
                        let text = obj::to_string(&MeshOut::tri(&dm.positions, &dm.faces).with_uv(&dm.uv))?;
                        rec.file(&format!("c_{:.2}.obj", c), text.as_bytes())?;
                    }
                }
            }
        }
    }
    let (slope_min, slope_max) = (stats::min(&lin_slopes), stats::max(&lin_slopes));
    let mut r = Report::default();
    r.num("exact_flat_max_area_residual", flat_res_max);
    r.num("exact_flat_max_amplitude_rel_err_vs_1d", amp_err_max);
    r.count("exact_flat_nonzero_h_under_stretch", stretch_violations as u64);
    r.num("linear_residual_slope_min", slope_min);
    r.num("linear_residual_slope_max", slope_max);
    for c in [0.95, 0.9, 0.8, 0.7] {
        r.num(&format!("strip_amp_over_lambda_c{:.2}", c), strip_amplitude(c));
    }
    let pass = flat_res_max <= 1e-9
        && amp_err_max <= 1e-5
        && stretch_violations == 0
        && (slope_min - 2.0).abs() <= 0.1
        && (slope_max - 2.0).abs() <= 0.1;
    r.count("pass", pass as u64);
    r.timing("seconds", t0.elapsed().as_secs_f64());
    r.check("exact_flat_max_area_residual", Target::AtMost(1e-9), "spec W1: exact flat mode restores the area");
    r.check("exact_flat_max_amplitude_rel_err_vs_1d", Target::AtMost(1e-5), "spec W1: 1-D strip amplitude to 1e-5");
    r.check("exact_flat_nonzero_h_under_stretch", Target::Equals(0.0), "spec W1: no wrinkles under stretch");
    r.check("linear_residual_slope_min", Target::Within(1.9, 2.1), "spec T5: second-order linearisation");
    r.check("linear_residual_slope_max", Target::Within(1.9, 2.1), "spec T5: second-order linearisation");
    Ok(r)
}

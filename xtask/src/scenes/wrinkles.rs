//! wrinkles' scenes (spec §6): wrinkle patterns modulated by per-triangle area conservation.
//!
//! - `wrinkles/uniaxial` ([`run_uniaxial`], spec W1): analytic area check with prescribed
//!   deformations (uniaxial c = 1.2 … 0.6, pattern rotated 0/30/90°, pure shear), every mode.
//! - `wrinkles/four-stage` ([`run_four_stage`], spec W2): the paper's Fig. 7–11 demonstration with
//!   two orthogonal fold patterns; the coarse sheet is driven by a prescribed smooth shear field
//!   (not `shells`, see the crate README), MF/weights per frame, popping index n = 4 vs n = ∞.
//! - `wrinkles/precompute-cost` ([`run_precompute_cost`], spec W5): precomputation time against
//!   triangle count and tolerance with a `Folds` pattern rendered to an image (spline path).
//! - `wrinkles/realtime-small` ([`run_realtime`], spec W6): 98-triangle sheet, prescribed
//!   animation; fps of modulation + level-8 displaced mesh, and of a 320×240 bump-mapped preview.

use std::path::Path;
use std::time::Instant;

use geom_core::image::write_png_gray16;
use geom_core::io::{obj, MeshOut};
use geom_core::math::{Mat2, Pt2, Pt3, Vec2, Vec3};
use geom_core::mesh::Uv;
use geom_core::procedural::{grid, Diagonals, GridSpec, Plane};
use geom_core::raster::{rasterize, Camera, RasterOptions};
use serde::Deserialize;
use wrinkles::displaced::Refinement;
use wrinkles::modulation::wrinkled_area;
use wrinkles::{
    precompute, AreaCheck, BlendOptions, HMax, ModulationMode, ModulationOptions, Normalization, PatternOptions,
    PatternSource, PrecomputeOptions, Procedural, RestMesh, Smoothing, StrainMeasure, VertexWeights, WrinkleAnimator,
    WrinklePattern, WrinkleRig,
};

use crate::error::{Error, Result};
use crate::out::{Cell, CsvWriter, Summary};
use crate::plot::{LinePlot, Series};
use crate::registry::{RunCtx, Runner};
use crate::scene;

/// Adds wrinkles' runners.
pub fn register(v: &mut Vec<Runner>) {
    v.push(Runner { method: "wrinkles/uniaxial", run: run_uniaxial });
    v.push(Runner { method: "wrinkles/four-stage", run: run_four_stage });
    v.push(Runner { method: "wrinkles/realtime-small", run: run_realtime });
    v.push(Runner { method: "wrinkles/precompute-cost", run: run_precompute_cost });
}

fn wr<T>(r: wrinkles::Result<T>) -> Result<T> {
    r.map_err(|e| Error::Run(format!("wrinkles: {e}")))
}

/// An `n × n` grid of side `l` in the XY plane from the origin, UV = (x, y) (m).
fn sheet(n: u32, l: f64, diagonals: Diagonals) -> Result<RestMesh> {
    let m = grid(&GridSpec {
        quads: [n, n],
        size: [l, l],
        plane: Plane::XY,
        diagonals,
        center: Pt3::new(0.5 * l, 0.5 * l, 0.0),
    })?;
    wr(RestMesh::from_trimesh(&m))
}

/// A square of side `l` made of two triangles whose edge 0 is axis-aligned (the W1 fixture).
fn two_triangles(l: f64) -> Result<RestMesh> {
    let p = vec![Pt3::new(0.0, 0.0, 0.0), Pt3::new(l, 0.0, 0.0), Pt3::new(l, l, 0.0), Pt3::new(0.0, l, 0.0)];
    let uv = Uv::PerVertex(p.iter().map(|p| Pt2::new(p.x, p.y)).collect());
    wr(RestMesh::new(p, vec![[0, 1, 2], [2, 3, 0]], uv))
}

fn sinusoid(lambda: f64, angle_deg: f64, slope: f64) -> Result<WrinklePattern> {
    wr(WrinklePattern::new(
        &PatternSource::Procedural(Procedural::Sinusoid { wavelength_uv: lambda, angle_deg, phase: 0.0 }),
        PatternOptions { normalization: Normalization::TargetRestSlope(slope), ..Default::default() },
    ))
}

fn deform(mesh: &RestMesh, f: &Mat2) -> Vec<Pt3> {
    mesh.positions
        .iter()
        .map(|p| {
            let q = f * Vec2::new(p.x, p.y);
            Pt3::new(q.x, q.y, p.z)
        })
        .collect()
}

fn write_obj(dir: &Path, name: &str, m: &wrinkles::displaced::DisplacedMesh) -> Result<()> {
    crate::out::ensure_dir(dir)?;
    obj::write(dir.join(name), &MeshOut::tri(&m.positions, &m.faces).with_uv(&m.uv))?;
    Ok(())
}

/// The 1-D buckled-strip amplitude ratio A/λ at compression c (flat rest, arc length kept):
/// mean_θ √(c² + (2πA/λ)² cos²θ) = 1 by bisection, 4096-point periodic midpoint rule.
fn strip_amplitude(c: f64) -> f64 {
    let n = 4096;
    let mean = |k: f64| {
        (0..n)
            .map(|i| (c * c + k * k * (std::f64::consts::TAU * (i as f64 + 0.5) / n as f64).cos().powi(2)).sqrt())
            .sum::<f64>()
            / n as f64
    };
    if c >= 1.0 {
        return 0.0;
    }
    let (mut lo, mut hi) = (0.0, 20.0);
    for _ in 0..200 {
        let m = 0.5 * (lo + hi);
        if mean(m) < 1.0 {
            lo = m
        } else {
            hi = m
        }
    }
    0.5 * (lo + hi) / std::f64::consts::TAU
}

fn slope_fit(pts: &[(f64, f64)]) -> f64 {
    let n = pts.len() as f64;
    let (mx, my) = (pts.iter().map(|p| p.0).sum::<f64>() / n, pts.iter().map(|p| p.1).sum::<f64>() / n);
    pts.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum::<f64>() / pts.iter().map(|p| (p.0 - mx).powi(2)).sum::<f64>()
}

// ---------------------------------------------------------------------------------------------
// W1 uniaxial

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct UniaxialParams {
    /// Square side (m).
    size: f64,
    /// Periods across the square.
    periods: f64,
    /// Rest slopes compared.
    slopes: Vec<f64>,
    /// Pattern rotations (degrees).
    angles_deg: Vec<f64>,
    /// Grid quads per side of the second mesh [quick, default, full] (0 = skip it).
    grid_quads: [u32; 3],
    /// c sweep [from, to] and [quick, default, full] step counts.
    c_range: [f64; 2],
    c_steps: [usize; 3],
    /// Pure shear b ∈ [−b_max, b_max], [quick, default, full] steps.
    shear_max: f64,
    shear_steps: [usize; 3],
    /// Precomputation (spec: tolerance ≤ 1e-6, gradient_bins 0 for the 1e-5 amplitude check).
    tolerance: f64,
    /// Cap on the wrinkled slope (h_max = max_slope / s).
    max_slope: f64,
    /// c values with OBJ output, and the displaced-mesh level.
    obj_at_c: Vec<f64>,
    obj_level: u32,
}

const MODES: [(&str, ModulationMode); 5] = [
    ("lin_green", ModulationMode::Linearized { strain: StrainMeasure::Green }),
    ("lin_abd", ModulationMode::Linearized { strain: StrainMeasure::PaperAbd }),
    ("exact_wrinkled", ModulationMode::ExactWrinkledRest),
    ("exact_flat", ModulationMode::ExactFlatRest),
    ("principal", ModulationMode::PrincipalLength),
];

/// Per-frame figures of one deformation: mean h over unclipped triangles, max area residual
/// over unclipped compressed triangles (where a root exists), clipped count, min h.
fn measure(a: &mut WrinkleAnimator, def: &[Pt3]) -> Result<(f64, f64, usize, f64)> {
    let fm = wr(a.frame(def))?;
    let rep = wr(a.area_report(def, &fm, AreaCheck::PerTriangle))?;
    let hm = a.h_max()[0];
    let (mut hs, mut res, mut n, mut clipped) = (0.0, 0.0f64, 0usize, 0usize);
    for (t, h) in fm.tri_h.iter().enumerate() {
        if *h >= hm {
            clipped += 1;
            continue;
        }
        hs += h;
        n += 1;
        if *h == 0.0 && rep.area[t] >= rep.target[t] {
            continue; // stretched: no wrinkle can restore the area (h = 0 is the answer)
        }
        res = res.max((rep.area[t] - rep.target[t]).abs() / rep.target[t]);
    }
    let mean_h = if n > 0 { hs / n as f64 } else { hm };
    let h_min = fm.tri_h.iter().copied().fold(f64::INFINITY, f64::min);
    Ok((mean_h, res, clipped, h_min))
}

/// W1: analytic area check (spec §6 W1).
pub fn run_uniaxial(ctx: &RunCtx) -> Result<Summary> {
    let p: UniaxialParams = scene::load(&ctx.scene_file)?.params;
    let steps = ctx.mode.pick(p.c_steps[0], p.c_steps[1], p.c_steps[2]).max(2);
    let sh_steps = ctx.mode.pick(p.shear_steps[0], p.shear_steps[1], p.shear_steps[2]).max(2);
    if p.size <= 0.0
        || p.periods <= 0.0
        || p.tolerance <= 0.0
        || p.max_slope <= 0.0
        || p.slopes.iter().any(|s| *s <= 0.0)
    {
        return Err(scene::invalid(&ctx.scene_file, "size, periods, tolerance, max_slope and slopes must be positive"));
    }
    let lambda = p.size / p.periods;
    let pre = PrecomputeOptions { tolerance: p.tolerance, max_depth: 9, gradient_bins: 0, gradient_samples: true };
    let gq = ctx.mode.pick(p.grid_quads[0], p.grid_quads[1], p.grid_quads[2]);
    let mut meshes = vec![("square2", two_triangles(p.size)?)];
    if gq > 0 {
        meshes.push(("grid", sheet(gq, p.size, Diagonals::Alternating)?));
    }
    let mut csv = CsvWriter::create(
        &ctx.out_dir.join("metrics.csv"),
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
    let mut sum = Summary::new();
    sum.set_str("mode", ctx.mode.name());
    let t0 = Instant::now();
    let (mut flat_res_max, mut amp_err_max, mut stretch_violations) = (0.0f64, 0.0f64, 0usize);
    let mut h_plot: Vec<Series> = Vec::new();
    let mut res_plot: Vec<Series> = Vec::new();
    let mut lin_slopes = Vec::new();
    let mut lin_csv = CsvWriter::create(
        &ctx.out_dir.join("linear_order.csv"),
        &["slope", "angle_deg", "fitted_order", "res_d0.05", "res_d0.003125"],
    )?;
    let mut lin_plot: Vec<Series> = Vec::new();
    for (mesh_name, mesh) in &meshes {
        for &s in &p.slopes {
            for &ang in &p.angles_deg {
                let rig = wr(precompute(mesh, &[sinusoid(lambda, ang, s)?], &pre))?;
                let eta = rig.eta[0];
                for (mode_name, mode) in MODES {
                    let o = ModulationOptions {
                        mode,
                        smoothing: Smoothing::PerTriangle,
                        h_max: HMax::Auto { max_slope: p.max_slope },
                        ..Default::default()
                    };
                    let mut a = wr(WrinkleAnimator::new(rig.clone(), o))?;
                    let mut hv = Vec::new();
                    let mut rv = Vec::new();
                    for k in 0..steps {
                        let c = p.c_range[0] + (p.c_range[1] - p.c_range[0]) * k as f64 / (steps - 1) as f64;
                        let def = deform(mesh, &Mat2::new(c, 0.0, 0.0, 1.0));
                        let (h, res, clipped, h_min) = measure(&mut a, &def)?;
                        let analytic = if ang == 0.0 { strip_amplitude(c) } else { f64::NAN };
                        if mode_name == "exact_flat" {
                            flat_res_max = flat_res_max.max(res);
                            if c >= 1.0 && (h_min != 0.0 || h != 0.0) {
                                stretch_violations += 1;
                            }
                            if ang == 0.0 && clipped == 0 && c < 1.0 {
                                amp_err_max = amp_err_max.max((h * eta / lambda - analytic).abs() / analytic);
                            }
                        }
                        hv.push((c, h));
                        rv.push((c, res.max(1e-17)));
                        csv.row(&[
                            Cell::Text(mesh_name.to_string()),
                            s.into(),
                            ang.into(),
                            Cell::Text("uniaxial".into()),
                            c.into(),
                            Cell::Text(mode_name.into()),
                            h.into(),
                            (h * eta).into(),
                            res.into(),
                            clipped.into(),
                            analytic.into(),
                        ])?;
                    }
                    for k in 0..sh_steps {
                        let b = -p.shear_max + 2.0 * p.shear_max * k as f64 / (sh_steps - 1) as f64;
                        let def = deform(mesh, &Mat2::new(1.0, b, 0.0, 1.0));
                        let (h, res, clipped, _) = measure(&mut a, &def)?;
                        if mode_name == "exact_flat" {
                            flat_res_max = flat_res_max.max(res);
                        }
                        csv.row(&[
                            Cell::Text(mesh_name.to_string()),
                            s.into(),
                            ang.into(),
                            Cell::Text("shear".into()),
                            b.into(),
                            Cell::Text(mode_name.into()),
                            h.into(),
                            (h * eta).into(),
                            res.into(),
                            clipped.into(),
                            f64::NAN.into(),
                        ])?;
                    }
                    if *mesh_name == "square2" && ang == 0.0 {
                        h_plot.push(Series::new(format!("{mode_name} s={s}"), hv));
                        if !mode_name.starts_with("lin") {
                            res_plot.push(Series::new(format!("{mode_name} s={s}"), rv));
                        }
                    }
                    // Linear-mode residual order (Green), δ ≤ 0.05.
                    if mode_name == "lin_green" && *mesh_name == "square2" {
                        let mut pts = Vec::new();
                        for j in 0..5 {
                            let d = 0.05 * 0.5f64.powi(j);
                            let f = Mat2::new(1.0 - d, 0.0, 0.0, 1.0);
                            let def = deform(mesh, &f);
                            let fm = wr(a.frame(&def))?;
                            let cf = rig.coeff(0, 0);
                            let cc = f.transpose() * f;
                            let r = (wrinkled_area(&cf.grad_samples, &cc, fm.tri_h[0]) - cf.area_wrinkled).abs()
                                / cf.area_wrinkled;
                            pts.push((d, r));
                        }
                        let logp: Vec<(f64, f64)> = pts.iter().map(|(d, r)| (d.ln(), r.ln())).collect();
                        let sl = slope_fit(&logp);
                        lin_csv.row(&[s.into(), ang.into(), sl.into(), pts[0].1.into(), pts[4].1.into()])?;
                        lin_slopes.push(sl);
                        lin_plot.push(Series::new(format!("s={s} angle={ang}"), pts));
                    }
                }
                // OBJs of the exact flat mode, axis-aligned, on the two-triangle square.
                if *mesh_name == "square2" && ang == 0.0 && s == p.slopes[p.slopes.len() - 1] {
                    let o = ModulationOptions {
                        mode: ModulationMode::ExactFlatRest,
                        smoothing: Smoothing::PerTriangle,
                        ..Default::default()
                    };
                    let mut a = wr(WrinkleAnimator::new(rig.clone(), o))?;
                    for &c in &p.obj_at_c {
                        let def = deform(mesh, &Mat2::new(c, 0.0, 0.0, 1.0));
                        let fm = wr(a.frame(&def))?;
                        let dm = wr(a.displaced_mesh(&def, &fm, p.obj_level))?;
                        write_obj(&ctx.out_dir, &format!("c_{:.2}.obj", c), &dm)?;
                    }
                }
            }
        }
    }
    let mut plot = LinePlot::new("W1: modulation factor vs compression (axis-aligned, 2 triangles)", "c", "h");
    for s in h_plot {
        plot = plot.with(s);
    }
    plot.write_png(&ctx.out_dir.join("h_vs_c.png"))?;
    let mut plot =
        LinePlot::new("W1: exact-mode area residual (unclipped triangles)", "c", "|A - A*|/A*").log(false, true);
    for s in res_plot {
        plot = plot.with(s);
    }
    plot.write_png(&ctx.out_dir.join("area_err_vs_c.png"))?;
    let mut plot = LinePlot::new("W1: linear-mode area residual (slope 2)", "delta", "|A - A*|/A*").log(true, true);
    for s in lin_plot {
        plot = plot.with(s);
    }
    plot.write_png(&ctx.out_dir.join("lin_err_vs_delta.png"))?;
    let slope_min = lin_slopes.iter().copied().fold(f64::INFINITY, f64::min);
    let slope_max = lin_slopes.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    sum.set("exact_flat_max_area_residual", flat_res_max);
    sum.set("exact_flat_max_amplitude_rel_err_vs_1d", amp_err_max);
    sum.set_count("exact_flat_nonzero_h_under_stretch", stretch_violations as u64);
    sum.set("linear_residual_slope_min", slope_min);
    sum.set("linear_residual_slope_max", slope_max);
    for (c, want) in [(0.95, 0.0707189), (0.9, 0.0993299), (0.8, 0.1383959), (0.7, 0.1667054)] {
        sum.set(&format!("strip_amp_over_lambda_c{:.2}", c), strip_amplitude(c));
        let _ = want;
    }
    let pass = flat_res_max <= 1e-9
        && amp_err_max <= 1e-5
        && stretch_violations == 0
        && (slope_min - 2.0).abs() <= 0.1
        && (slope_max - 2.0).abs() <= 0.1;
    sum.set_count("pass", pass as u64);
    sum.set("seconds", t0.elapsed().as_secs_f64());
    Ok(sum)
}

// ---------------------------------------------------------------------------------------------
// W2 four-stage

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct FourStageParams {
    /// Sheet side (m) and quads per side.
    size: f64,
    quads: u32,
    /// Bottom-corner displacement (x, y) in stages 2 (−x) and 4 (+x) (m).
    corner: [f64; 2],
    /// Stage length (s), fraction of each stage used by the smoothstep transition, fps.
    stage_seconds: f64,
    transition: f64,
    fps: f64,
    /// Fold patterns: wavelength (UV m), directions (deg), rest slope.
    wavelength: f64,
    angles_deg: [f64; 2],
    slope: f64,
    blend_variance: f64,
    blend_power: f64,
    /// Rest point whose triangle is reported.
    marked: [f64; 2],
    /// Displaced-mesh level and OBJ/modmap stride [quick, default, full].
    obj_level: u32,
    obj_every: [usize; 3],
    modmap_every: usize,
    modmap_size: u32,
}

fn smooth01(x: f64) -> f64 {
    let x = x.clamp(0.0, 1.0);
    x * x * (3.0 - 2.0 * x)
}

/// The prescribed corner displacement at time t (4 stages).
fn corner_disp(p: &FourStageParams, t: f64) -> Vec2 {
    let st = (t / p.stage_seconds).floor() as i64;
    let u = smooth01((t / p.stage_seconds - st as f64) / p.transition);
    let left = Vec2::new(-p.corner[0].abs(), p.corner[1]);
    let right = Vec2::new(p.corner[0].abs(), p.corner[1]);
    match st {
        0 => Vec2::zeros(),
        1 => left * u,
        2 => left * (1.0 - u),
        _ => right * u,
    }
}

/// Top edge fixed, bottom edge carried by the corners: u(x, y) = (1 − y/L)²·d (smooth shear).
fn sheared(mesh: &RestMesh, l: f64, d: Vec2) -> Vec<Pt3> {
    mesh.positions
        .iter()
        .map(|p| {
            let w = (1.0 - p.y / l).powi(2);
            Pt3::new(p.x + w * d.x, p.y + w * d.y, p.z)
        })
        .collect()
}

fn popping(prev: &Option<Vec<f64>>, d: &[f64], dmax: f64) -> f64 {
    match prev {
        Some(p) if dmax > 0.0 => p.iter().zip(d).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max) / dmax,
        _ => 0.0,
    }
}

/// W2: two orthogonal fold patterns under a four-stage corner pull (spec §6 W2).
pub fn run_four_stage(ctx: &RunCtx) -> Result<Summary> {
    let p: FourStageParams = scene::load(&ctx.scene_file)?.params;
    if p.size <= 0.0
        || p.quads == 0
        || p.fps <= 0.0
        || p.stage_seconds <= 0.0
        || !(p.transition > 0.0 && p.transition <= 1.0)
    {
        return Err(scene::invalid(
            &ctx.scene_file,
            "size, quads, fps, stage_seconds must be positive; transition in (0, 1]",
        ));
    }
    let mesh = sheet(p.quads, p.size, Diagonals::Alternating)?;
    let pats: Vec<WrinklePattern> = p
        .angles_deg
        .iter()
        .enumerate()
        .map(|(k, &a)| {
            wr(WrinklePattern::new(
                &PatternSource::Procedural(Procedural::Folds {
                    wavelength_uv: p.wavelength,
                    angle_deg: a,
                    spread_deg: 8.0,
                    count: 4,
                    irregularity: 0.3,
                    seed: 7 + k as u64,
                }),
                PatternOptions { normalization: Normalization::TargetRestSlope(p.slope), ..Default::default() },
            ))
        })
        .collect::<Result<_>>()?;
    let t_pre = Instant::now();
    let rig: WrinkleRig = wr(precompute(&mesh, &pats, &PrecomputeOptions::default()))?;
    let t_pre = t_pre.elapsed().as_secs_f64();
    let lin = ModulationMode::Linearized { strain: StrainMeasure::Green };
    let blend = BlendOptions { variance: p.blend_variance, power: p.blend_power };
    let base = ModulationOptions {
        mode: lin,
        blend,
        smoothing: Smoothing::VertexAverage { weights: VertexWeights::Area },
        ..Default::default()
    };
    let mut a4 = wr(WrinkleAnimator::new(rig.clone(), base.clone()))?;
    let mut ainf = wr(WrinkleAnimator::new(
        rig.clone(),
        ModulationOptions { blend: BlendOptions { power: f64::INFINITY, ..blend }, ..base.clone() },
    ))?;
    let mut apl =
        wr(WrinkleAnimator::new(rig.clone(), ModulationOptions { mode: ModulationMode::PrincipalLength, ..base }))?;
    // Marked triangle: the one containing the rest point.
    let mp = Vec2::new(p.marked[0], p.marked[1]);
    let marked = mesh
        .faces
        .iter()
        .position(|f| {
            let q = |k: usize| Vec2::new(mesh.positions[f[k] as usize].x, mesh.positions[f[k] as usize].y);
            let cr = |a: Vec2, b: Vec2, c: Vec2| (b - a).perp(&(c - a));
            let (a, b, c) = (q(0), q(1), q(2));
            let s = cr(a, b, c).signum();
            cr(a, b, mp) * s >= 0.0 && cr(b, c, mp) * s >= 0.0 && cr(c, a, mp) * s >= 0.0
        })
        .ok_or_else(|| scene::invalid(&ctx.scene_file, "marked point is outside the sheet"))?;
    let n_frames = (4.0 * p.stage_seconds * p.fps).round() as usize;
    let obj_every = ctx.mode.pick(p.obj_every[0], p.obj_every[1], p.obj_every[2]).max(1);
    let refine = Refinement::new(mesh.positions.len(), &mesh.faces, &rig.edges, p.obj_level.max(1));
    // Probe points for the popping index: the level-4 lattice of every triangle.
    let probes: Vec<(usize, [f64; 3])> = (0..mesh.faces.len())
        .flat_map(|t| {
            (0..=4u32).flat_map(move |j| {
                (0..=(4 - j)).map(move |i| (t, [(4 - i - j) as f64 / 4.0, i as f64 / 4.0, j as f64 / 4.0]))
            })
        })
        .collect();
    let mut csv = CsvWriter::create(
        &ctx.out_dir.join("metrics.csv"),
        &[
            "frame",
            "t",
            "mf1",
            "mf2",
            "w1",
            "w2",
            "h_principal1",
            "h_principal2",
            "pop_n",
            "pop_inf",
            "ms_modulate",
            "ms_mesh",
        ],
    )?;
    let (mut prev4, mut prevf) = (None, None);
    let (mut s_mf1, mut s_mf2, mut s_w1, mut s_w2) = (vec![], vec![], vec![], vec![]);
    let mut stage1_dev: f64 = 0.0;
    let mut end3_dev = 0.0;
    let (mut mid2, mut mid4) = ((0.0, 0.0, 0.0, 0.0), (0.0, 0.0, 0.0, 0.0));
    let (mut pop4_max, mut popinf_max) = (0.0f64, 0.0f64);
    let (mut ms_mod, mut ms_mesh) = (0.0, 0.0);
    for k in 0..n_frames {
        let t = k as f64 / p.fps;
        let def = sheared(&mesh, p.size, corner_disp(&p, t));
        let t0 = Instant::now();
        let fm = wr(a4.frame(&def))?;
        let dt_mod = t0.elapsed().as_secs_f64();
        let fi = wr(ainf.frame(&def))?;
        let fpl = wr(apl.frame(&def))?;
        let (mf1, mf2) = (fm.tri_mf_lin[2 * marked], fm.tri_mf_lin[2 * marked + 1]);
        let (w1, w2) = (fm.tri_weight[2 * marked], fm.tri_weight[2 * marked + 1]);
        let d4: Vec<f64> = probes.iter().map(|(t, b)| a4.displacement(&fm, *t, *b)).collect();
        let di: Vec<f64> = probes.iter().map(|(t, b)| ainf.displacement(&fi, *t, *b)).collect();
        let dmax = d4.iter().chain(&di).fold(0.0f64, |m, v| m.max(v.abs()));
        let (pn, pi) = (popping(&prev4, &d4, dmax), popping(&prevf, &di, dmax));
        pop4_max = pop4_max.max(pn);
        popinf_max = popinf_max.max(pi);
        prev4 = Some(d4);
        prevf = Some(di);
        let stage = (t / p.stage_seconds).floor() as usize;
        if stage == 0 {
            stage1_dev = stage1_dev.max(fm.tri_mf_lin.iter().fold(0.0f64, |m, v| m.max((v - 1.0).abs())));
        }
        if stage == 2 {
            end3_dev = (mf1 - 1.0).abs().max((mf2 - 1.0).abs());
        }
        let frac = t / p.stage_seconds - stage as f64;
        if (frac - 0.5).abs() < 0.5 / (p.fps * p.stage_seconds) + 1e-12 {
            if stage == 1 {
                mid2 = (mf1, mf2, w1, w2);
            } else if stage == 3 {
                mid4 = (mf1, mf2, w1, w2);
            }
        }
        let mut dt_mesh = 0.0;
        if k % obj_every == 0 {
            let t1 = Instant::now();
            let dm = a4.displaced_on(&refine, &def, &fm);
            dt_mesh = t1.elapsed().as_secs_f64();
            write_obj(&ctx.out_dir.join("frames"), &format!("frame_{k:04}.obj"), &dm)?;
        }
        if p.modmap_every > 0 && k % p.modmap_every == 0 {
            for i in 0..2 {
                let img = wr(a4.bake_modulation_map(&fm, i, p.modmap_size, p.modmap_size))?;
                let hm = a4.h_max()[i].max(1e-12);
                write_png_gray16(ctx.out_dir.join(format!("modmap_p{}_{k:04}.png", i + 1)), &img, 65535.0 / hm)?;
            }
        }
        ms_mod += dt_mod;
        ms_mesh += dt_mesh;
        s_mf1.push((t, mf1));
        s_mf2.push((t, mf2));
        s_w1.push((t, w1));
        s_w2.push((t, w2));
        csv.row(&[
            k.into(),
            t.into(),
            mf1.into(),
            mf2.into(),
            w1.into(),
            w2.into(),
            fpl.tri_h[2 * marked].into(),
            fpl.tri_h[2 * marked + 1].into(),
            pn.into(),
            pi.into(),
            (1e3 * dt_mod).into(),
            (1e3 * dt_mesh).into(),
        ])?;
    }
    LinePlot::new("W2: modulation factors of the marked triangle (Fig. 9)", "t (s)", "MF")
        .with(Series::new("MF1 (+45°)", s_mf1))
        .with(Series::new("MF2 (-45°)", s_mf2))
        .write_png(&ctx.out_dir.join("mf1_vs_mf2.png"))?;
    LinePlot::new("W2: pattern weights of the marked triangle (Fig. 11)", "t (s)", "W")
        .with(Series::new("W1", s_w1))
        .with(Series::new("W2", s_w2))
        .write_png(&ctx.out_dir.join("weights_vs_time.png"))?;
    let swap = (mid2.0 - mid2.1).signum() != (mid4.0 - mid4.1).signum() && mid2.0 != mid2.1;
    let dom2 = mid2.2.max(mid2.3);
    let dom4 = mid4.2.max(mid4.3);
    let mut sum = Summary::new();
    sum.set_str("mode", ctx.mode.name());
    sum.set_count("triangles", mesh.faces.len() as u64);
    sum.set("precompute_s", t_pre);
    sum.set("stage1_max_abs_mf_minus_1", stage1_dev);
    sum.set("stage3_end_max_abs_mf_minus_1", end3_dev);
    sum.set("mid_stage2_mf1", mid2.0);
    sum.set("mid_stage2_mf2", mid2.1);
    sum.set("mid_stage4_mf1", mid4.0);
    sum.set("mid_stage4_mf2", mid4.1);
    sum.set("mid_stage2_dominant_weight", dom2);
    sum.set("mid_stage4_dominant_weight", dom4);
    sum.set("popping_index_n4_max", pop4_max);
    sum.set("popping_index_ninf_max", popinf_max);
    sum.set("ms_per_frame_modulation", 1e3 * ms_mod / n_frames as f64);
    sum.set("ms_per_mesh_level", 1e3 * ms_mesh / n_frames.div_ceil(obj_every) as f64);
    let pass = stage1_dev <= 1e-9 && end3_dev <= 0.02 && swap && dom2 >= 0.9 && dom4 >= 0.9 && pop4_max < popinf_max;
    sum.set_count("ordering_swaps", swap as u64);
    sum.set_count("pass", pass as u64);
    Ok(sum)
}

// ---------------------------------------------------------------------------------------------
// W6 realtime-small

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RealtimeParams {
    /// Sheet side (m) and quads per side (7 → 98 triangles).
    size: f64,
    quads: u32,
    /// Displaced-mesh level.
    level: u32,
    /// Frames [quick, default, full].
    frames: [usize; 3],
    /// Preview resolution.
    preview: [u32; 2],
    /// Pattern wavelength (UV m) and slope.
    wavelength: f64,
    slope: f64,
}

/// A travelling compression wave along x with a sideways sway.
fn wave(mesh: &RestMesh, l: f64, t: f64) -> Vec<Pt3> {
    let k = std::f64::consts::TAU / l;
    mesh.positions
        .iter()
        .map(|p| {
            let ux = -0.04 * l * ((k * p.x - 2.0 * t).sin() + 1.0) * 0.5 * (p.x / l);
            Pt3::new(p.x + ux, p.y + 0.02 * l * (1.5 * t).sin() * (p.x / l), 0.05 * l * (k * p.y + t).sin())
        })
        .collect()
}

/// W6: fps of modulation + level-L displaced mesh, and of a bump-mapped software preview.
pub fn run_realtime(ctx: &RunCtx) -> Result<Summary> {
    let p: RealtimeParams = scene::load(&ctx.scene_file)?.params;
    let frames = ctx.mode.pick(p.frames[0], p.frames[1], p.frames[2]).max(1);
    if p.size <= 0.0 || p.quads == 0 || p.level == 0 || p.preview.contains(&0) {
        return Err(scene::invalid(&ctx.scene_file, "size, quads, level and preview must be positive"));
    }
    let mesh = sheet(p.quads, p.size, Diagonals::Alternating)?;
    let pats = vec![sinusoid(p.wavelength, 0.0, p.slope)?, sinusoid(p.wavelength, 90.0, p.slope)?];
    let rig = wr(precompute(&mesh, &pats, &PrecomputeOptions::default()))?;
    let mut a = wr(WrinkleAnimator::new(rig.clone(), ModulationOptions::default()))?;
    let refine = Refinement::new(mesh.positions.len(), &mesh.faces, &rig.edges, p.level);
    let c = p.size * 0.5;
    let cam = Camera::look_at(
        &Pt3::new(c, -0.6 * p.size, 1.2 * p.size),
        &Pt3::new(c, c, 0.0),
        &Vec3::z(),
        40.0,
        p.preview[0],
        p.preview[1],
    )?;
    let light = Vec3::new(0.3, -0.5, 1.0).normalize();
    let (mut t_mod, mut t_mesh, mut t_prev) = (0.0, 0.0, 0.0);
    let mut last_area = 0.0;
    for k in 0..frames {
        let def = wave(&mesh, p.size, k as f64 / 30.0);
        let t0 = Instant::now();
        let fm = wr(a.frame(&def))?;
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
            geom_core::image::write_png_gray8(ctx.out_dir.join("preview.png"), &img)?;
            write_obj(&ctx.out_dir, "last_frame.obj", &dm)?;
        }
    }
    let n = frames as f64;
    let mut sum = Summary::new();
    sum.set_str("mode", ctx.mode.name());
    sum.set_str("profile", if cfg!(debug_assertions) { "debug" } else { "release" });
    sum.set_count("triangles", mesh.faces.len() as u64);
    sum.set_count("frames", frames as u64);
    sum.set_count("displaced_vertices", refine.n_vertices as u64);
    sum.set("ms_modulation", 1e3 * t_mod / n);
    sum.set("ms_displaced_mesh", 1e3 * t_mesh / n);
    sum.set("ms_bump_preview", 1e3 * t_prev / n);
    sum.set("fps_modulation_plus_mesh", n / (t_mod + t_mesh));
    sum.set("fps_modulation_plus_preview", n / (t_mod + t_prev));
    sum.set("last_displaced_area_m2", last_area);
    Ok(sum)
}

// ---------------------------------------------------------------------------------------------
// W5 precompute-cost

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct PrecomputeCostParams {
    /// Quads per side of the sheets [quick, default, full] (T = 2·q²).
    quads: [Vec<u32>; 3],
    /// Tolerances [quick, default, full].
    tolerances: [Vec<f64>; 3],
    /// Image side (texels) [quick, default, full].
    image: [u32; 3],
    /// Fold wavelength in texture units ([0, 1] spans the image).
    wavelength: f64,
    /// Rest slope.
    slope: f64,
}

/// W5: precomputation time against triangle count (spec §6 W5).
pub fn run_precompute_cost(ctx: &RunCtx) -> Result<Summary> {
    let p: PrecomputeCostParams = scene::load(&ctx.scene_file)?.params;
    let quads = ctx.mode.pick(&p.quads[0], &p.quads[1], &p.quads[2]).clone();
    let tols = ctx.mode.pick(&p.tolerances[0], &p.tolerances[1], &p.tolerances[2]).clone();
    let n = ctx.mode.pick(p.image[0], p.image[1], p.image[2]);
    if quads.is_empty() || tols.is_empty() || n == 0 || quads.contains(&0) || p.wavelength <= 0.0 {
        return Err(scene::invalid(
            &ctx.scene_file,
            "quads, tolerances, image and wavelength must be non-empty/positive",
        ));
    }
    // Render the procedural folds into an n × n image (texel centres), then use the spline path.
    let folds = wr(WrinklePattern::new(
        &PatternSource::Procedural(Procedural::Folds {
            wavelength_uv: p.wavelength,
            angle_deg: 0.0,
            spread_deg: 8.0,
            count: 4,
            irregularity: 0.3,
            seed: 7,
        }),
        PatternOptions::default(),
    ))?;
    let mut img = geom_core::image::ImageF32::new(n, n, 0.0);
    for y in 0..n {
        for x in 0..n {
            let uv = Pt2::new((x as f64 + 0.5) / n as f64, (y as f64 + 0.5) / n as f64);
            img.set(x, y, (0.5 + 0.5 * folds.eval(&uv)) as f32);
        }
    }
    let l = 0.5;
    let pat = wr(WrinklePattern::new(
        &PatternSource::Image(img),
        PatternOptions {
            normalization: Normalization::TargetRestSlope(p.slope),
            blur_texels: 1.0,
            uv_transform: wrinkles::UvTransform { scale: [1.0 / l, 1.0 / l], ..Default::default() },
            ..Default::default()
        },
    ))?;
    let mut csv = CsvWriter::create(
        &ctx.out_dir.join("metrics.csv"),
        &["tolerance", "triangles", "seconds", "points_per_triangle", "unconverged"],
    )?;
    let mut sum = Summary::new();
    sum.set_str("mode", ctx.mode.name());
    sum.set_str("profile", if cfg!(debug_assertions) { "debug" } else { "release" });
    sum.set_count("image_side", n as u64);
    let mut plot = LinePlot::new("W5: precomputation time vs triangle count", "triangles", "seconds").log(true, true);
    for &tol in &tols {
        let mut pts = Vec::new();
        for &q in &quads {
            // Constant triangle size (22 quads per 0.5 m; the image repeats every 0.5 m): the
            // paper's per-triangle cost model, so the time should be linear in T.
            let mesh = sheet(q, l * q as f64 / 22.0, Diagonals::Alternating)?;
            let t0 = Instant::now();
            let rig = wr(precompute(
                &mesh,
                std::slice::from_ref(&pat),
                &PrecomputeOptions { tolerance: tol, ..Default::default() },
            ))?;
            let secs = t0.elapsed().as_secs_f64();
            let nt = mesh.faces.len();
            let ppt = rig.coeffs.iter().map(|c| c.n_points).sum::<usize>() as f64 / nt as f64;
            let unconv = rig.coeffs.iter().filter(|c| c.status == wrinkles::CoeffStatus::Unconverged).count();
            csv.row(&[tol.into(), nt.into(), secs.into(), ppt.into(), unconv.into()])?;
            pts.push((nt as f64, secs));
        }
        let logp: Vec<(f64, f64)> = pts.iter().map(|(t, s)| (t.ln(), s.ln())).collect();
        if logp.len() >= 2 {
            sum.set(&format!("loglog_slope_tol{tol:e}"), slope_fit(&logp));
        }
        if let Some(&(t, s)) = pts.last() {
            sum.set(&format!("s_per_1000_tri_tol{tol:e}"), 1000.0 * s / t);
        }
        plot = plot.with(Series::new(format!("tol {tol:e}"), pts));
    }
    plot.write_png(&ctx.out_dir.join("precompute_vs_T.png"))?;
    sum.set("paper_s_per_1000_tri", 300.0);
    Ok(sum)
}

#[cfg(test)]
mod tests {
    use crate::registry::builtin_scenes;
    use crate::run::run_scene;
    use crate::scene::Mode;

    /// The cheap built-in wrinkles scenes run end to end in quick mode and W2 meets its pass
    /// criteria (spec T23: ordering swap, dominant weight, stage-1 and stage-3 modulation factor
    /// at 1 to rounding). W1 `uniaxial` (≈ 20 s quick in release, adaptive quadrature at 1e-6) is
    /// covered by the crate's own analytic tests and left to `cargo xtask`.
    #[test]
    fn wrinkles_scenes_run_quick() {
        let root = std::env::temp_dir().join(format!("xtask-wr-scenes-{}", std::process::id()));
        let mut ran = 0;
        for s in builtin_scenes()
            .unwrap()
            .into_iter()
            .filter(|s| s.id.starts_with("wrinkles/") && s.id != "wrinkles/uniaxial")
        {
            let dir = root.join(&s.id);
            let sum = run_scene(&s.id, &s.file, Mode::Quick, &dir).unwrap_or_else(|e| panic!("{}: {e}", s.id));
            if s.id == "wrinkles/four-stage" {
                assert_eq!(sum.get("pass"), Some(1.0));
                assert!(sum.get("ordering_swaps").unwrap() >= 1.0);
                assert!(sum.get("stage1_max_abs_mf_minus_1").unwrap() < 1e-9);
                assert!(sum.get("stage3_end_max_abs_mf_minus_1").unwrap() < 1e-9);
            }
            ran += 1;
        }
        assert!(ran >= 3, "expected three quick wrinkles scenes, ran {ran}");
        std::fs::remove_dir_all(&root).unwrap();
    }
}

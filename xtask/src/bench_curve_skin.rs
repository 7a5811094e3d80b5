//! `cargo xtask bench curve-skin` (spec §9): accuracy against time for
//! (a) the curve frame-table resolution (8 … 128 samples and exact, with and without the kink
//! samples) on the reference arm bent 90° and twisted 90°: max vertex error vs the exact `f64`
//! evaluation, in units of R, for both curve shapes (circular arc and quadratic B-spline);
//! (b) the LBS influence count K ∈ {1, 2, 4, 8} on the humanoid walk: max / RMS vertex error vs
//! all weights (the `f64` reference `geom_core::anim::skin::lbs`);
//! (c) the three methods (and the B-spline curve shape) on the bent arm: volume error against ns
//! per vertex.
//! Writes `accuracy_vs_time.csv`, `table_error.png`, `weights_error.png`, `pareto.png`.
//! Loops over library calls only: setups from `curve_skin::presets`, errors from
//! `curve_skin::metrics`, timing by `curve_skin::experiments::perf::time_frames`.

use curve_skin::curve::CurveShape;
use curve_skin::experiments::perf::time_frames;
use curve_skin::metrics::{max_rms_error, signed_volume, to_f64};
use curve_skin::poses::{axis_deg, walk_pose};
use curve_skin::presets::{arm_pose, capsule_character, curve_skeleton, ramp_weights4, reference_arm, ARM_RADIUS};
use curve_skin::{CurveOptions, CurveSkin, Dqs, Lbs, PackedWeights, SkinWeights, Skinner};
use geom_core::math::{Pt3, Vec3};
use geom_core::stats::nan_max;

use crate::error::Result;
use crate::out::{CsvWriter, Summary};
use crate::plot::{LinePlot, Series};
use crate::registry::BenchCtx;

fn lbs_k<const K: usize>(rest: &[[f32; 3]], rows: &[Vec<(u16, f32)>]) -> Result<Lbs<K>> {
    let (w, _) = PackedWeights::<K>::from_sparse(rows)?;
    Ok(Lbs::new(rest.to_vec(), None, w)?)
}

/// A CSV row of the sweep: study, variant, knob, max and RMS error, seconds per deform of `n`
/// vertices.
fn row(csv: &mut CsvWriter, study: &str, variant: &str, knob: &str, err: (f64, f64), dt: f64, n: usize) -> Result<()> {
    csv.row(&[
        study.into(),
        variant.into(),
        knob.into(),
        err.0.into(),
        err.1.into(),
        (dt / n as f64 * 1e9).into(),
        (n as f64 / dt / 1e6).into(),
    ])
}

fn plot(title: &str, x: &str, y: &str, series: Vec<Series>, path: &std::path::Path) -> Result<()> {
    let mut p = LinePlot::new(title, x, y).log(true, true);
    p.series = series;
    p.write_png(path).map(|_| ())
}

/// The benchmark entry point.
pub fn run(ctx: &BenchCtx) -> Result<Summary> {
    let min_t = if ctx.quick { 0.05 } else { 0.3 };
    let time = |s: &dyn Skinner, out: &mut [[f32; 3]], min: f64| time_frames(s, out, None, 1, min);
    let mut csv = CsvWriter::create(
        &ctx.out_dir.join("accuracy_vs_time.csv"),
        &["study", "variant", "knob", "max_error", "rms_error", "ns_per_vertex", "mverts_per_s"],
    )?;
    let mut summary = Summary::new();
    summary.set_str("profile", if cfg!(debug_assertions) { "debug" } else { "release" });

    // (a) table resolution.
    let r = ARM_RADIUS;
    let (rings, segs) = if ctx.quick { (100, 32) } else { (400, 96) };
    let (mesh, sk) = reference_arm(rings, segs)?;
    let n = mesh.positions.len();
    let posed = arm_pose(&sk, axis_deg(Vec3::z(), 90.0) * axis_deg(Vec3::x(), 90.0)).globals(&sk);
    let cskel = curve_skeleton(&sk, CurveShape::CircularArc);
    let bskel = curve_skeleton(&sk, CurveShape::QuadraticBSpline);
    let mut out = vec![[0f32; 3]; n];
    let mut exact = vec![Pt3::origin(); n];
    let mut table_series: Vec<Series> = Vec::new();
    let cases = [
        ("with_kinks", "arc, with kink samples", ""),
        ("no_kinks", "arc, uniform only", ""),
        ("bspline_with_kinks", "B-spline, with kink + zone samples", "bspline_"),
        ("bspline_no_kinks", "B-spline, uniform only", "bspline_"),
    ];
    for (variant, label, prefix) in cases {
        let kinks = !variant.ends_with("no_kinks");
        let skel = if prefix.is_empty() { &cskel } else { &bskel };
        let mut pts = Vec::new();
        for k in [8usize, 16, 32, 64, 128, 0] {
            let opts = CurveOptions { table_samples: k, kink_samples: kinks, ..Default::default() };
            let mut cur = CurveSkin::new(&sk, skel.clone(), &mesh.positions, None, opts)?;
            cur.prepare(&sk, &posed)?;
            cur.deform_f64(&mut exact);
            let dt = time(&cur, &mut out, min_t)?;
            let (mx, rms) = max_rms_error(&to_f64(&out), &exact);
            let knob = if k == 0 { "exact".to_string() } else { k.to_string() };
            row(&mut csv, "table", variant, &knob, (mx / r, rms / r), dt, n)?;
            if k > 0 {
                pts.push((k as f64, mx / r));
            }
            if kinks && k == 64 {
                summary.set(&format!("{prefix}table64_max_error_over_r"), mx / r);
                summary.set(&format!("{prefix}table64_curve_mverts_per_s"), n as f64 / dt / 1e6);
            }
            if kinks && k == 0 {
                summary.set(&format!("{prefix}exact_curve_mverts_per_s"), n as f64 / dt / 1e6);
            }
        }
        table_series.push(Series::new(label, pts));
    }
    let title = "curve table error (90° bend + 90° twist)";
    plot(title, "table samples K", "max error / R", table_series, &ctx.out_dir.join("table_error.png"))?;

    // (b) LBS weight count on the humanoid walk (every inverse-distance weight kept).
    let h = capsule_character(if ctx.quick { 0.3 } else { 0.7 }, 0.0)?;
    let all = SkinWeights::from_rows(&h.rows)?;
    let hn = h.rest32.len();
    let frames: Vec<f64> = (0..if ctx.quick { 3 } else { 8 }).map(|i| i as f64 * 0.137).collect();
    let mut ws = Vec::new();
    let mut hout = vec![[0f32; 3]; hn];
    let cases: [(usize, Box<dyn Skinner>); 4] = [
        (1, Box::new(lbs_k::<1>(&h.rest32, &h.rows)?)),
        (2, Box::new(lbs_k::<2>(&h.rest32, &h.rows)?)),
        (4, Box::new(lbs_k::<4>(&h.rest32, &h.rows)?)),
        (8, Box::new(lbs_k::<8>(&h.rest32, &h.rows)?)),
    ];
    for (k, mut l) in cases {
        let (mut mx, mut rms2, mut dt) = (0.0f64, 0.0f64, 0.0f64);
        for &t in &frames {
            let posed = walk_pose(&h.sk, t).globals(&h.sk);
            let tr = curve_skin::skinning_transforms(&h.sk, &posed);
            let mut reference = vec![Pt3::origin(); hn];
            geom_core::anim::skin::lbs(&h.mesh.positions, &all, &tr, &mut reference);
            l.prepare(&h.sk, &posed)?;
            dt += time(l.as_ref(), &mut hout, min_t / frames.len() as f64)?;
            let (a, b) = max_rms_error(&to_f64(&hout), &reference);
            mx = nan_max(mx, a);
            rms2 += b * b;
        }
        let dt = dt / frames.len() as f64;
        row(&mut csv, "lbs_weights", "walk", &k.to_string(), (mx, (rms2 / frames.len() as f64).sqrt()), dt, hn)?;
        ws.push((k as f64, mx));
        summary.set(&format!("lbs_k{k}_max_error_m"), mx);
    }
    let title = "LBS: influence count vs all weights (walk)";
    let ws = vec![Series::new("max error", ws)];
    plot(title, "K", "max vertex error (m)", ws, &ctx.out_dir.join("weights_error.png"))?;

    // (c) methods: volume error vs ns/vertex on the arm bent 90°.
    let posed = arm_pose(&sk, axis_deg(Vec3::z(), 90.0)).globals(&sk);
    let v0 = signed_volume(&mesh.positions, &mesh.tris);
    let w4 = ramp_weights4(&mesh.positions, r);
    let rest = mesh.positions_f32();
    let curve = |skel: &curve_skin::CurveSkeleton| {
        CurveSkin::new(&sk, skel.clone(), &mesh.positions, None, CurveOptions::default())
    };
    let mut methods: Vec<(&str, Box<dyn Skinner>)> = vec![
        ("lbs", Box::new(Lbs::new(rest.clone(), None, w4.clone())?)),
        ("dqs", Box::new(Dqs::new(rest.clone(), None, w4)?)),
        ("curve", Box::new(curve(&cskel)?)),
        ("curve_bspline", Box::new(curve(&bskel)?)),
    ];
    let mut pareto = Vec::new();
    for (m, s) in methods.iter_mut() {
        s.prepare(&sk, &posed)?;
        let dt = time(s.as_ref(), &mut out, min_t)?;
        let verr = (signed_volume(&to_f64(&out), &mesh.tris) / v0 - 1.0).abs();
        row(&mut csv, "method", m, "bend90", (verr, f64::NAN), dt, n)?;
        pareto.push(Series::new(*m, vec![(dt / n as f64 * 1e9, verr.max(1e-7))]));
        summary.set(&format!("{m}_bend90_volume_error"), verr);
        summary.set(&format!("{m}_ns_per_vertex"), dt / n as f64 * 1e9);
    }
    plot(
        "volume error vs cost (arm bent 90°)",
        "ns per vertex",
        "|V/V0 − 1|",
        pareto,
        &ctx.out_dir.join("pareto.png"),
    )?;
    Ok(summary)
}

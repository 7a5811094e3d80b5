//! `cargo xtask bench curve-skin` (spec §9): accuracy against time for
//! (a) the curve frame-table resolution (8 … 128 samples and exact, with and without the kink
//! samples) on the reference arm bent 90° and twisted 90°: max vertex error vs the exact `f64`
//! evaluation, in units of R, for both curve shapes (circular arc and quadratic B-spline);
//! (b) the LBS influence count K ∈ {1, 2, 4, 8} on the humanoid walk: max / RMS vertex error vs
//! all weights (the `f64` reference `geom_core::anim::skin::lbs`);
//! (c) the three methods (and the B-spline curve shape) on the bent arm: volume error against ns
//! per vertex.
//! Writes `accuracy_vs_time.csv`, `table_error.png`, `weights_error.png`, `pareto.png`.

use std::time::Instant;

use curve_skin::curve::{build_curve_skeleton, CurveShape, JointCurveDefaults, TopologyRules};
use curve_skin::metrics::signed_volume;
use curve_skin::poses::{axis_deg, walk_pose, SkinPose};
use curve_skin::procedural::{cylinder_arm, humanoid, inverse_distance_weights, ramp_weights, Ramp};
use curve_skin::{CurveOptions, CurveSkin, DeformOutput, Dqs, Lbs, PackedWeights, SkinWeights, Skinner};
use geom_core::math::{Pt3, Vec3};

use crate::error::{Error, Result};
use crate::out::{CsvWriter, Summary};
use crate::plot::{LinePlot, Series};
use crate::registry::BenchCtx;

fn cs<T>(r: curve_skin::Result<T>) -> Result<T> {
    r.map_err(|e| Error::Run(format!("curve-skin: {e}")))
}

fn to_f64(p: &[[f32; 3]]) -> Vec<Pt3> {
    p.iter().map(|x| Pt3::new(x[0] as f64, x[1] as f64, x[2] as f64)).collect()
}

/// Seconds per deform (single thread), repeated for at least `min` seconds.
fn time_deform(s: &dyn Skinner, out: &mut [[f32; 3]], min: f64) -> f64 {
    s.deform(DeformOutput { positions: out, normals: None });
    let t0 = Instant::now();
    let mut reps = 0usize;
    while reps < 2 || t0.elapsed().as_secs_f64() < min {
        s.deform(DeformOutput { positions: out, normals: None });
        reps += 1;
    }
    t0.elapsed().as_secs_f64() / reps as f64
}

fn max_rms(a: &[Pt3], b: &[Pt3]) -> (f64, f64) {
    let mut mx: f64 = 0.0;
    let mut s = 0.0;
    for (x, y) in a.iter().zip(b) {
        let d = (x - y).norm();
        mx = mx.max(d);
        s += d * d;
    }
    (mx, (s / a.len().max(1) as f64).sqrt())
}

fn lbs_k<const K: usize>(rest: &[[f32; 3]], rows: &[Vec<(u16, f32)>]) -> Result<Lbs<K>> {
    let (w, _) = cs(PackedWeights::<K>::from_sparse(rows))?;
    cs(Lbs::new(rest.to_vec(), None, w))
}

/// The benchmark entry point.
pub fn run(ctx: &BenchCtx) -> Result<Summary> {
    let min_t = if ctx.quick { 0.05 } else { 0.3 };
    let mut csv = CsvWriter::create(
        &ctx.out_dir.join("accuracy_vs_time.csv"),
        &["study", "variant", "knob", "max_error", "rms_error", "ns_per_vertex", "mverts_per_s"],
    )?;
    let mut summary = Summary::new();
    summary.set_str("profile", if cfg!(debug_assertions) { "debug" } else { "release" });

    // (a) table resolution.
    let r = 0.15;
    let (rings, segs) = if ctx.quick { (100, 32) } else { (400, 96) };
    let (mesh, sk) = cs(cylinder_arm(r, 1.0, rings, segs))?;
    let n = mesh.positions.len();
    let mut pose = SkinPose::rest(&sk);
    pose.set_world(&sk, 1, axis_deg(Vec3::z(), 90.0) * axis_deg(Vec3::x(), 90.0));
    let posed = pose.globals(&sk);
    let cskel = build_curve_skeleton(&sk, &TopologyRules::default(), &JointCurveDefaults::default());
    let bskel = build_curve_skeleton(
        &sk,
        &TopologyRules::default(),
        &JointCurveDefaults { shape: CurveShape::QuadraticBSpline, ..Default::default() },
    );
    let mut out = vec![[0f32; 3]; n];
    let mut exact = vec![Pt3::origin(); n];
    let mut table_series: Vec<Series> = Vec::new();
    for (shape, kinks) in [("arc", true), ("arc", false), ("bspline", true), ("bspline", false)] {
        let cskel = if shape == "arc" { &cskel } else { &bskel };
        let mut pts = Vec::new();
        for k in [8usize, 16, 32, 64, 128, 0] {
            let opts = CurveOptions { table_samples: k, kink_samples: kinks, ..Default::default() };
            let mut cur = cs(CurveSkin::new(&sk, cskel.clone(), &mesh.positions, None, opts))?;
            cs(cur.prepare(&sk, &posed))?;
            cur.deform_f64(&mut exact);
            let dt = time_deform(&cur, &mut out, min_t);
            let (mx, rms) = max_rms(&to_f64(&out), &exact);
            let variant = match (shape, kinks) {
                ("arc", true) => "with_kinks",
                ("arc", false) => "no_kinks",
                (_, true) => "bspline_with_kinks",
                (_, false) => "bspline_no_kinks",
            };
            let knob = if k == 0 { "exact".to_string() } else { k.to_string() };
            csv.row(&[
                "table".into(),
                variant.into(),
                knob.into(),
                (mx / r).into(),
                (rms / r).into(),
                (dt / n as f64 * 1e9).into(),
                (n as f64 / dt / 1e6).into(),
            ])?;
            if k > 0 {
                pts.push((k as f64, mx / r));
            }
            let prefix = if shape == "arc" { "" } else { "bspline_" };
            if kinks && k == 64 {
                summary.set(&format!("{prefix}table64_max_error_over_r"), mx / r);
                summary.set(&format!("{prefix}table64_curve_mverts_per_s"), n as f64 / dt / 1e6);
            }
            if kinks && k == 0 {
                summary.set(&format!("{prefix}exact_curve_mverts_per_s"), n as f64 / dt / 1e6);
            }
        }
        let label = match (shape, kinks) {
            ("arc", true) => "arc, with kink samples",
            ("arc", false) => "arc, uniform only",
            (_, true) => "B-spline, with kink + zone samples",
            (_, false) => "B-spline, uniform only",
        };
        table_series.push(Series::new(label, pts));
    }
    let mut plot =
        LinePlot::new("curve table error (90° bend + 90° twist)", "table samples K", "max error / R").log(true, true);
    for s in table_series {
        plot = plot.with(s);
    }
    plot.write_png(&ctx.out_dir.join("table_error.png"))?;

    // (b) LBS weight count on the humanoid walk.
    let h = cs(humanoid(if ctx.quick { 0.3 } else { 0.7 }))?;
    let rows = inverse_distance_weights(&h.mesh.positions, &h.skeleton, 4.0, 0.0);
    let all = SkinWeights::from_rows(&rows)?;
    let rest32 = h.mesh.positions_f32();
    let hn = rest32.len();
    let frames: Vec<f64> = (0..if ctx.quick { 3 } else { 8 }).map(|i| i as f64 * 0.137).collect();
    let mut ws = Vec::new();
    let mut hout = vec![[0f32; 3]; hn];
    macro_rules! k_case {
        ($k:literal) => {{
            let mut l = lbs_k::<$k>(&rest32, &rows)?;
            let (mut mx, mut rms2, mut dt) = (0.0f64, 0.0f64, 0.0f64);
            for &t in &frames {
                let posed = walk_pose(&h.skeleton, t).globals(&h.skeleton);
                let tr = curve_skin::skinning_transforms(&h.skeleton, &posed);
                let mut reference = vec![Pt3::origin(); hn];
                geom_core::anim::skin::lbs(&h.mesh.positions, &all, &tr, &mut reference);
                cs(l.prepare(&h.skeleton, &posed))?;
                dt += time_deform(&l, &mut hout, min_t / frames.len() as f64);
                let (a, b) = max_rms(&to_f64(&hout), &reference);
                mx = mx.max(a);
                rms2 += b * b;
            }
            let rms = (rms2 / frames.len() as f64).sqrt();
            let dt = dt / frames.len() as f64;
            csv.row(&[
                "lbs_weights".into(),
                "walk".into(),
                $k.to_string().into(),
                mx.into(),
                rms.into(),
                (dt / hn as f64 * 1e9).into(),
                (hn as f64 / dt / 1e6).into(),
            ])?;
            ws.push(($k as f64, mx));
            summary.set(&format!("lbs_k{}_max_error_m", $k), mx);
        }};
    }
    k_case!(1);
    k_case!(2);
    k_case!(4);
    k_case!(8);
    LinePlot::new("LBS: influence count vs all weights (walk)", "K", "max vertex error (m)")
        .log(true, true)
        .with(Series::new("max error", ws))
        .write_png(&ctx.out_dir.join("weights_error.png"))?;

    // (c) methods: volume error vs ns/vertex on the arm bent 90°.
    let mut bent = SkinPose::rest(&sk);
    bent.set_world(&sk, 1, axis_deg(Vec3::z(), 90.0));
    let posed = bent.globals(&sk);
    let v0 = signed_volume(&mesh.positions, &mesh.tris);
    let w2 = ramp_weights(&mesh.positions, 0.0, r, Ramp::SmoothStep);
    let w4 = PackedWeights::<4> {
        bone: w2.bone.iter().map(|b| [b[0], b[1], 0, 0]).collect(),
        w: w2.w.iter().map(|x| [x[0], x[1], 0.0, 0.0]).collect(),
    };
    let rest = mesh.positions_f32();
    let mut methods: Vec<(&str, Box<dyn Skinner>)> = vec![
        ("lbs", Box::new(cs(Lbs::new(rest.clone(), None, w4.clone()))?)),
        ("dqs", Box::new(cs(Dqs::new(rest.clone(), None, w4))?)),
        ("curve", Box::new(cs(CurveSkin::new(&sk, cskel.clone(), &mesh.positions, None, CurveOptions::default()))?)),
        (
            "curve_bspline",
            Box::new(cs(CurveSkin::new(&sk, bskel.clone(), &mesh.positions, None, CurveOptions::default()))?),
        ),
    ];
    let mut pareto = Vec::new();
    for (m, s) in methods.iter_mut() {
        cs(s.prepare(&sk, &posed))?;
        let dt = time_deform(s.as_ref(), &mut out, min_t);
        let verr = (signed_volume(&to_f64(&out), &mesh.tris) / v0 - 1.0).abs();
        csv.row(&[
            "method".into(),
            (*m).into(),
            "bend90".into(),
            verr.into(),
            f64::NAN.into(),
            (dt / n as f64 * 1e9).into(),
            (n as f64 / dt / 1e6).into(),
        ])?;
        pareto.push(Series::new(*m, vec![(dt / n as f64 * 1e9, verr.max(1e-7))]));
        summary.set(&format!("{m}_bend90_volume_error"), verr);
        summary.set(&format!("{m}_ns_per_vertex"), dt / n as f64 * 1e9);
    }
    let mut plot = LinePlot::new("volume error vs cost (arm bent 90°)", "ns per vertex", "|V/V0 − 1|").log(true, true);
    for s in pareto {
        plot = plot.with(s);
    }
    plot.write_png(&ctx.out_dir.join("pareto.png"))?;
    Ok(summary)
}

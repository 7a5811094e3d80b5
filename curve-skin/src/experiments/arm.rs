//! The reference arm bent (`elbow-bend`, the collapsing elbow, spec §6.1) or twisted
//! (`candy-wrapper`, spec §6.2) through an angle sweep: LBS and DQS with smoothstep ramps of
//! several half-widths, curve skin (circular arc), curve skin with isotropic volume compensation,
//! and optionally the quadratic B-spline curve shape and a muscle action line (spec §3.4.8).
//!
//! Per angle and method: volume ratio, joint (bend) or ring (twist) radius ratio, min/max
//! distance to the posed bones ÷ R, and at the key angles the fold fraction of the analytic map,
//! the Bone_CP cap hits and the self-intersection count. Outputs: table `metrics` (and `muscle`),
//! plots `volume_ratio`, `joint_radius_ratio`, `max_dist_over_r`, OBJ files
//! `obj/<method>_<deg>.obj` at the key angles, notes with the spec's table beside ours.
//!
//! Figures (the keys of `summary.json`): `<m>_volume_ratio`, `<m>_joint_radius_ratio` (bend) or
//! `<m>_ring_radius_ratio` (twist), `<m>_min_dist_over_r`, `<m>_max_dist_over_r` at the summary
//! angle, the same with `_at_<deg>` at every key angle, `<m>_self_intersections(_at_<deg>)`,
//! `<c>_fold_fraction`, `<c>_cap_hits`, `<c>_l_over_r` for the curve methods, the exact-path
//! `<c>_max_dist_over_r_f64` and `<c>_volume_ratio_f64`, `muscle_length_ratio` and
//! `muscle_bulge_volume_ratio`, and for the twist the closed form `lbs_closed_form_volume_ratio`
//! (spec §7.2 c). Method names: `lbs`, `dqs` (h = R), `lbs_h2r`, `dqs_h2r` (h = 2R), `curve`,
//! `curve_comp`, `curve_bspline`.
//!
//! ```no_run
//! use curve_skin::experiments::arm::{run, Params};
//! use geom_core::experiment::Size;
//! use geom_core::record::NullRecorder;
//! let p: Params = ron::from_str(
//!     "(radius: 0.15, bone_len: 1.0, rings: 100, segments: 32, motion: Bend, to_deg: 90.0,
//!       step_deg: 45.0, widths: [1.0], obj_at_deg: [90.0], fold_samples: 1000,
//!       comp_max_scale: None, summary_deg: 90.0)",
//! )
//! .unwrap();
//! let report = run(&p, Size::Quick, &mut NullRecorder::default()).unwrap();
//! assert!(report.get_f64("curve_joint_radius_ratio") > 0.98);
//! ```

use geom_core::experiment::{BySize, Report, Size, Target};
use geom_core::io::{obj, MeshOut};
use geom_core::math::{Pt3, Vec3};
use geom_core::record::{Recorder, Series};
use geom_core::rng::Rng;
use serde::Deserialize;

use crate::curve::{polyline_length, ActionLine, CurveShape, MuscleBulge, VolumeComp};
use crate::error::{Result, SkinError};
use crate::metrics::{
    distance_to_bones, fold_fraction, joint_radius_ratio, ring_radius_ratio, self_intersections, signed_volume, to_f64,
};
use crate::presets::{arm_point, arm_pose, curve_skeleton, ramp_weights4, ArmMotion};
use crate::procedural::cylinder_arm;
use crate::reference::{lbs_joint_radius_ratio, lbs_twist_volume_ratio};
use crate::{CurveOptions, CurveSkeleton, CurveSkin, Dqs, Lbs, Skinner};

use super::timed_deform;

/// The scene's `params` block.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Params {
    /// Limb radius R (m).
    pub radius: f64,
    /// Bone length (m); the arm spans x ∈ [−bone_len, bone_len].
    pub bone_len: f64,
    /// Rings along the arm.
    pub rings: BySize<usize>,
    /// Vertices around.
    pub segments: BySize<usize>,
    /// Bend about z or twist about x.
    pub motion: ArmMotion,
    /// Sweep end (degrees); the sweep starts at 0.
    pub to_deg: f64,
    /// Angle step (degrees).
    pub step_deg: BySize<f64>,
    /// Ramp half-widths for LBS / DQS, in units of R.
    pub widths: Vec<f64>,
    /// Angles (degrees) with OBJ output, fold analysis and self-intersections (the key angles).
    pub obj_at_deg: BySize<Vec<f64>>,
    /// Interior samples of the fold analysis (0 = none).
    pub fold_samples: BySize<usize>,
    /// `max_scale` of the volume-compensated curve method (`None` = no cap).
    pub comp_max_scale: Option<f64>,
    /// Angle (degrees) whose figures are reported without suffix.
    pub summary_deg: f64,
    /// Curve shapes compared (spec §3.4.2): the first is method `curve` (and `curve_comp`), a
    /// `QuadraticBSpline` after it becomes `curve_bspline`. Default `[CircularArc]`.
    #[serde(default = "default_shapes")]
    pub shapes: Vec<CurveShape>,
    /// Optional muscle action line (spec §3.4.8) driven by the `curve` method.
    #[serde(default)]
    pub muscle: Option<MuscleParams>,
}

fn default_shapes() -> Vec<CurveShape> {
    vec![CurveShape::CircularArc]
}

/// A muscle action line on the arm.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MuscleParams {
    /// Control points `(x / bone_len, y / R, z / R)`.
    pub points: Vec<(f64, f64, f64)>,
    /// Rest muscle radius ÷ R.
    pub radius: f64,
    /// Bulge capsule radius ÷ R.
    pub influence: f64,
}

struct ArmMethod {
    name: String,
    skinner: Box<dyn Skinner>,
    curve: bool,
    /// The exact f64 twin of a curve method (fold analysis, f64 figures).
    twin: Option<Box<CurveSkin>>,
}

/// The figure name of a method: `lbs` / `dqs` are the h = R variants, h = 2R gets `_h2r`.
fn figure_name(method: &str) -> &str {
    match method {
        "lbs_h1" => "lbs",
        "dqs_h1" => "dqs",
        "lbs_h2" => "lbs_h2r",
        "dqs_h2" => "dqs_h2r",
        other => other,
    }
}

fn obj_file(rec: &mut dyn Recorder, name: &str, pos: &[[f32; 3]], tris: &[[u32; 3]]) -> Result<()> {
    if rec.keeps_outputs() {
        rec.file(&format!("obj/{name}"), obj::to_string(&MeshOut::tri_f32(pos, tris))?.as_bytes())?;
    }
    Ok(())
}

/// A polyline (an action line) as an OBJ with one `l` element.
fn polyline_obj(pts: &[Pt3]) -> String {
    let mut s = String::from("# curve-skin muscle action line\n");
    for p in pts {
        s.push_str(&format!("v {} {} {}\n", p.x, p.y, p.z));
    }
    s.push('l');
    for i in 1..=pts.len() {
        s.push_str(&format!(" {i}"));
    }
    s.push('\n');
    s
}

/// Runs the sweep; see the module docs.
pub fn run(p: &Params, size: Size, rec: &mut dyn Recorder) -> Result<Report> {
    let (rings, segs, step, n_fold) =
        (p.rings.get(size), p.segments.get(size), p.step_deg.get(size), p.fold_samples.get(size));
    let key_angles = p.obj_at_deg.get(size);
    if !(p.radius > 0.0 && p.bone_len > 0.0 && step > 0.0) || rings < 2 || segs < 3 {
        return Err(SkinError::Param("radius, bone_len, step_deg must be positive, rings ≥ 2, segments ≥ 3".into()));
    }
    if p.shapes.is_empty() {
        return Err(SkinError::Param("shapes must name at least one curve shape".into()));
    }
    let r = p.radius;
    let (mesh, sk) = cylinder_arm(r, p.bone_len, rings, segs)?;
    let n = mesh.positions.len();
    let side: Vec<bool> = (0..n).map(|i| i < n - 2).collect();
    let rest32 = mesh.positions_f32();
    let v0 = signed_volume(&mesh.positions, &mesh.tris);

    let mut methods: Vec<ArmMethod> = Vec::new();
    for &h in &p.widths {
        let w4 = ramp_weights4(&mesh.positions, h * r);
        let tag = format!("h{}", h);
        let lbs = Lbs::<4>::new(rest32.clone(), None, w4.clone())?;
        let dqs = Dqs::<4>::new(rest32.clone(), None, w4)?;
        methods.push(ArmMethod { name: format!("lbs_{tag}"), skinner: Box::new(lbs), curve: false, twin: None });
        methods.push(ArmMethod { name: format!("dqs_{tag}"), skinner: Box::new(dqs), curve: false, twin: None });
    }
    let new_curve =
        |cskel: &CurveSkeleton, o: CurveOptions| CurveSkin::new(&sk, cskel.clone(), &mesh.positions, None, o);
    let cskel = curve_skeleton(&sk, p.shapes[0]);
    methods.push(ArmMethod {
        name: "curve".into(),
        skinner: Box::new(new_curve(&cskel, CurveOptions::default())?),
        curve: true,
        twin: Some(Box::new(new_curve(&cskel, CurveOptions::default())?)),
    });
    let comp = CurveOptions {
        volume_comp: VolumeComp::Isotropic { max_scale: p.comp_max_scale.unwrap_or(f64::INFINITY) },
        ..Default::default()
    };
    methods.push(ArmMethod {
        name: "curve_comp".into(),
        skinner: Box::new(new_curve(&cskel, comp)?),
        curve: true,
        twin: None,
    });
    for &shape in &p.shapes[1..] {
        let name = match shape {
            CurveShape::CircularArc => "curve_arc",
            CurveShape::QuadraticBSpline => "curve_bspline",
        };
        let sk2 = curve_skeleton(&sk, shape);
        methods.push(ArmMethod {
            name: name.into(),
            skinner: Box::new(new_curve(&sk2, CurveOptions::default())?),
            curve: true,
            twin: Some(Box::new(new_curve(&sk2, CurveOptions::default())?)),
        });
    }
    // Muscle action line driven by the `curve` method's exact twin.
    let muscle = match &p.muscle {
        None => None,
        Some(mp) => {
            let line = ActionLine::new(mp.points.iter().map(|&q| arm_point(q, r, p.bone_len)).collect())?;
            let bulge = MuscleBulge::new(&line, &mesh.positions, mp.radius * r, mp.influence * r)?;
            Some((line, bulge))
        }
    };

    let mut rng = Rng::new(5);
    let samples: Vec<Pt3> = (0..n_fold)
        .map(|_| {
            let rr = 0.98 * r * rng.f64().sqrt();
            let phi = rng.range(0.0, std::f64::consts::TAU);
            Pt3::new(rng.range(-0.95, 0.95) * p.bone_len, rr * phi.cos(), rr * phi.sin())
        })
        .collect();

    rec.table(
        "metrics",
        &[
            "angle_deg",
            "method",
            "volume_ratio",
            "joint_radius_ratio",
            "min_dist_over_r",
            "max_dist_over_r",
            "fold_fraction",
            "cap_hits",
            "self_intersections",
            "time_s",
        ],
    )?;
    if muscle.is_some() {
        rec.table("muscle", &["angle_deg", "length_ratio", "length_over_r", "bulge_volume_ratio"])?;
    }
    let mut series: Vec<Vec<Vec<(f64, f64)>>> = vec![vec![Vec::new(); methods.len()]; 3];
    let mut rep = Report::default();
    rep.count("vertices", n as u64);
    let steps = (p.to_deg / step).round() as usize;
    let mut out = vec![[0f32; 3]; n];
    // The ring(s) nearest the joint: within half a ring spacing of x = 0.
    let band = 0.51 * 2.0 * p.bone_len / (rings - 1) as f64;
    let jr_key = if p.motion == ArmMotion::Bend { "joint_radius_ratio" } else { "ring_radius_ratio" };
    for k in 0..=steps {
        rec.progress(k as u64, steps as u64 + 1);
        let deg = (k as f64 * step).min(p.to_deg);
        let posed = arm_pose(&sk, p.motion.rotation(deg)).globals(&sk);
        let joints: Vec<Pt3> = posed.iter().map(|f| Pt3::from(f.translation.vector)).collect();
        let bones = [(joints[0], joints[1]), (joints[1], joints[2])];
        let is_key = key_angles.iter().any(|&a| (a - deg).abs() < 1e-9);
        let at_summary = (deg - p.summary_deg).abs() < 1e-9;
        let deg_tag = deg.round() as i64;
        // Sets `key` at the summary angle and `key_at_<deg>` at a key angle.
        let tagged = |rep: &mut Report, key: &str, v: f64| {
            if at_summary {
                rep.num(key, v);
            }
            if is_key {
                rep.num(&format!("{key}_at_{deg_tag}"), v);
            }
        };
        for (mi, m) in methods.iter_mut().enumerate() {
            m.skinner.prepare(&sk, &posed)?;
            let t = timed_deform(m.skinner.as_ref(), &mut out);
            let pos = to_f64(&out);
            let vol = signed_volume(&pos, &mesh.tris) / v0;
            let jr = match p.motion {
                ArmMotion::Bend => joint_radius_ratio(&pos, &mesh.positions, joints[1], Pt3::origin(), r, band),
                ArmMotion::Twist => ring_radius_ratio(&pos, &mesh.positions, Pt3::origin(), Vec3::x(), -band, band, r),
            };
            let side_pos: Vec<Pt3> = pos.iter().zip(&side).filter(|(_, &s)| s).map(|(x, _)| *x).collect();
            let (lo, hi) = distance_to_bones(&side_pos, &bones);
            let mut fold = f64::NAN;
            let mut caps = 0usize;
            // Skinner is a trait object; the curve diagnostics come from the f64 twin.
            if let Some(twin) = m.twin.as_deref_mut() {
                twin.prepare(&sk, &posed)?;
                if is_key && n_fold > 0 {
                    caps = twin.diagnostics().cap_hits;
                    let tw: &CurveSkin = twin;
                    fold = fold_fraction(&|x| tw.map_point(&x), &samples, 1e-5);
                }
            }
            // Self-intersections (surface) only at the key angles: a BVH over every triangle.
            let si = if is_key { self_intersections(&out, &mesh.tris) as f64 } else { f64::NAN };
            rec.row(
                "metrics",
                &[
                    deg.into(),
                    m.name.as_str().into(),
                    vol.into(),
                    jr.into(),
                    (lo / r).into(),
                    (hi / r).into(),
                    fold.into(),
                    caps.into(),
                    si.into(),
                    t.into(),
                ],
            )?;
            series[0][mi].push((deg, vol));
            series[1][mi].push((deg, jr));
            series[2][mi].push((deg, hi / r));
            if is_key {
                obj_file(rec, &format!("{}_{:03}.obj", m.name, deg_tag), &out, &mesh.tris)?;
            }
            let base = figure_name(&m.name);
            tagged(&mut rep, &format!("{base}_volume_ratio"), vol);
            tagged(&mut rep, &format!("{base}_{jr_key}"), jr);
            tagged(&mut rep, &format!("{base}_min_dist_over_r"), lo / r);
            tagged(&mut rep, &format!("{base}_max_dist_over_r"), hi / r);
            if is_key {
                tagged(&mut rep, &format!("{base}_self_intersections"), si);
            }
            if m.curve && !fold.is_nan() {
                tagged(&mut rep, &format!("{base}_fold_fraction"), fold);
                tagged(&mut rep, &format!("{base}_cap_hits"), caps as f64);
            }
            let Some(twin) = m.twin.as_deref() else { continue };
            if at_summary {
                let mut o64 = vec![Pt3::origin(); n];
                twin.deform_f64(&mut o64);
                let side64: Vec<Pt3> = o64.iter().zip(&side).filter(|(_, &s)| s).map(|(x, _)| *x).collect();
                rep.num(&format!("{base}_max_dist_over_r_f64"), distance_to_bones(&side64, &bones).1 / r);
                rep.num(&format!("{base}_volume_ratio_f64"), signed_volume(&o64, &mesh.tris) / v0);
            }
            if is_key || at_summary {
                tagged(&mut rep, &format!("{base}_l_over_r"), twin.frames()[0].l_cp / r);
            }
            if let (Some((line, bulge)), "curve") = (&muscle, m.name.as_str()) {
                let mut lp = Vec::new();
                line.deform(twin, &mut lp);
                let ratio = line.length_ratio(&lp);
                let mut bulged = out.clone();
                bulge.apply(&lp, ratio, &mut bulged);
                let vb = signed_volume(&to_f64(&bulged), &mesh.tris) / v0;
                tagged(&mut rep, "muscle_length_ratio", ratio);
                tagged(&mut rep, "muscle_bulge_volume_ratio", vb);
                rec.row("muscle", &[deg.into(), ratio.into(), (polyline_length(&lp) / r).into(), vb.into()])?;
                if is_key && rec.keeps_outputs() {
                    rec.file(&format!("obj/muscle_{deg_tag:03}.obj"), polyline_obj(&lp).as_bytes())?;
                    obj_file(rec, &format!("curve_muscle_{deg_tag:03}.obj"), &bulged, &mesh.tris)?;
                }
            }
        }
    }
    if p.motion == ArmMotion::Twist {
        // §7.2 c closed form of the LBS candy wrapper at the summary angle.
        for &h in &p.widths {
            let v = lbs_twist_volume_ratio(h * r, p.bone_len, p.summary_deg.to_radians());
            let key = if (h - 1.0).abs() < 1e-12 {
                "lbs_closed_form_volume_ratio".to_string()
            } else {
                format!("lbs_h{h}_closed_form_volume_ratio")
            };
            rep.num(&key, v);
        }
    }
    let plots = [("volume_ratio", "V/V0"), ("joint_radius_ratio", "radius ratio"), ("max_dist_over_r", "max dist / R")];
    for (si, (plot, ylab)) in plots.iter().enumerate() {
        for (mi, m) in methods.iter().enumerate() {
            rec.series(&Series {
                plot: plot.to_string(),
                label: m.name.clone(),
                axes: ("angle (deg)".into(), ylab.to_string()),
                log: (false, false),
                points: std::mem::take(&mut series[si][mi]),
            })?;
        }
    }
    add_checks(p, &mut rep);
    notes(p, &rep, rec)?;
    Ok(rep)
}

/// The spec's hard assertions (§7.2, §7.4) on the figures at the summary angle.
fn add_checks(p: &Params, rep: &mut Report) {
    let has = |rep: &Report, k: &str| rep.get(k).is_some();
    match p.motion {
        ArmMotion::Bend => {
            let cf = lbs_joint_radius_ratio(p.summary_deg.to_radians());
            if has(rep, "lbs_joint_radius_ratio") {
                rep.check(
                    "lbs_joint_radius_ratio",
                    Target::Within(cf - 0.01, cf + 0.01),
                    "spec §7.2 a: cos(β/2) ± 0.01 (reference mesh 400 × 96)",
                );
            }
            for m in ["curve", "dqs"] {
                let k = format!("{m}_joint_radius_ratio");
                if has(rep, &k) {
                    rep.check(&k, Target::AtLeast(0.98), "spec §7.4 a: no collapse, ≥ 0.98 (reference mesh 400 × 96)");
                }
            }
            if has(rep, "curve_max_dist_over_r") {
                rep.check("curve_max_dist_over_r", Target::AtMost(1.0 + 1e-5), "spec §7.4: max dist/R ≤ 1 (f32)");
                rep.check("curve_max_dist_over_r_f64", Target::AtMost(1.0 + 1e-9), "spec §7.4: max dist/R ≤ 1 (f64)");
            }
            if has(rep, "curve_fold_fraction") {
                rep.check("curve_fold_fraction", Target::Equals(0.0), "spec §7.4 c: the curve map does not fold");
            }
        }
        ArmMotion::Twist => {
            if has(rep, "curve_volume_ratio") {
                rep.check(
                    "curve_volume_ratio",
                    Target::AtLeast(0.999),
                    "spec §7.4: pure twist V/V0 ≥ 0.999 (reference mesh 400 × 96)",
                );
            }
            if has(rep, "dqs_volume_ratio") {
                rep.check(
                    "dqs_volume_ratio",
                    Target::Within(0.999, 1.001),
                    "spec §7.3 d: DQS twist V/V0 = 1 ± 1e-3 (reference mesh 400 × 96)",
                );
            }
            let cf = rep.get_f64("lbs_closed_form_volume_ratio");
            if has(rep, "lbs_volume_ratio") && cf.is_finite() {
                rep.check(
                    "lbs_volume_ratio",
                    Target::Within(cf - 2e-3, cf + 2e-3),
                    "spec §7.2 c: closed form ± 2e-3 (reference mesh 400 × 96)",
                );
            }
        }
    }
}

/// The spec's prototype table beside our figures.
fn notes(p: &Params, rep: &Report, rec: &mut dyn Recorder) -> Result<()> {
    let g = |k: &str| rep.get(k).and_then(|v| v.as_f64()).map(|v| format!("{v:.4}")).unwrap_or_else(|| "–".into());
    let mut md = String::new();
    if p.motion == ArmMotion::Bend {
        md.push_str("| bend | method | volume ratio | joint radius ratio | min dist/R | max dist/R | spec (vol / joint / min / max) |\n|---|---|---|---|---|---|---|\n");
        let spec = [
            (45, "lbs", "0.9943 / 0.924 / 0.845 / 1.017"),
            (45, "dqs", "1.0000 / 1.000 / 0.908 / 1.054"),
            (45, "curve", "0.9982 / 0.994 / 0.929 / 1.000"),
            (90, "lbs", "0.9807 / 0.707 / 0.480 / 1.010"),
            (90, "dqs", "1.0000 / 1.000 / 0.686 / 1.088"),
            (90, "dqs_h2r", "1.0000 / 1.000 / 0.651 / 1.207"),
            (90, "curve", "0.9817 / 0.988 / 0.715 / 1.000"),
            (90, "curve_comp", "1.0000 / 1.171 / 0.844 / 1.183"),
            (135, "lbs", "0.9670 / 0.383 / 0.004 / 1.003"),
            (135, "dqs", "0.9999 / 1.000 / 0.002 / 1.107"),
            (135, "curve", "0.8921 / 0.985 / 0.388 / 1.000"),
            (135, "curve_comp", "1.0000 / 1.590 / 0.613 / 1.605"),
            (45, "curve_bspline", "– (option, not in the prototype table)"),
            (90, "curve_bspline", "–"),
            (135, "curve_bspline", "–"),
        ];
        for (deg, m, sp) in spec {
            md.push_str(&format!(
                "| {deg}° | {m} | {} | {} | {} | {} | {sp} |\n",
                g(&format!("{m}_volume_ratio_at_{deg}")),
                g(&format!("{m}_joint_radius_ratio_at_{deg}")),
                g(&format!("{m}_min_dist_over_r_at_{deg}")),
                g(&format!("{m}_max_dist_over_r_at_{deg}")),
            ));
        }
    } else {
        md.push_str(&format!(
            "Twist {}°: LBS V/V0 {} (closed form {}), DQS {}, curve {} (spec ≥ 0.999); ring radius ratio LBS {}, DQS {}, curve {}.\n",
            p.summary_deg,
            g("lbs_volume_ratio"),
            g("lbs_closed_form_volume_ratio"),
            g("dqs_volume_ratio"),
            g("curve_volume_ratio"),
            g("lbs_ring_radius_ratio"),
            g("dqs_ring_radius_ratio"),
            g("curve_ring_radius_ratio"),
        ));
    }
    rec.note(md.trim_end())?;
    Ok(())
}

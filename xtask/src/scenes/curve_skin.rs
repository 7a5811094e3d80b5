//! curve-skin's scenes (spec §6): curve-skeleton skinning beside LBS and DQS.
//!
//! - `curve-skin/arm` ([`run_arm`]): the cylinder arm bent (`elbow-bend`, collapsing elbow) or
//!   twisted (`candy-wrapper`) through an angle sweep; per-frame metrics for LBS / DQS (h = R, 2R),
//!   curve skin and curve skin with volume compensation.
//! - `curve-skin/humanoid` ([`run_humanoid`]): the capsule humanoid in the test poses (elbows,
//!   forearm twists, squat, shoulder raise); volume, influence histograms, time per frame.
//! - `curve-skin/walk` ([`run_walk`]): the humanoid playing a procedural walk; per-frame metrics,
//!   OBJ frames and a glTF 2.0 export of the LBS-skinned character with the walk animation.
//! - `curve-skin/perf` ([`run_perf`]): time per frame against vertex count, 1 and 2 threads,
//!   positions only and with normals.

use std::path::Path;
use std::time::Instant;

use curve_skin::curve::{
    build_curve_skeleton, polyline_length, ActionLine, CurveShape, JointCurveDefaults, MuscleBulge, TopologyRules,
    VolumeComp,
};
use curve_skin::metrics::{
    distance_to_bones, fold_fraction, histogram_mean, influences_histogram, joint_radius_ratio, ring_radius_ratio,
    self_intersections, signed_volume,
};
use curve_skin::poses::{axis_deg, humanoid_pose, walk_pose, SkinPose, HUMANOID_POSES};
use curve_skin::procedural::{cylinder_arm, humanoid, inverse_distance_weights, ramp_weights, Ramp, SkinMesh};
use curve_skin::{deform_par, CurveOptions, CurveSkin, DeformOutput, Dqs, Lbs, PackedWeights, SkinSkeleton, Skinner};
use geom_core::io::{obj, MeshOut};
use geom_core::math::{Pt3, Vec3};
use geom_core::rng::Rng;
use serde::Deserialize;

use crate::error::{Error, Result};
use crate::out::{CsvWriter, Summary};
use crate::plot::{LinePlot, Series};
use crate::registry::{RunCtx, Runner};
use crate::scene;

/// Adds curve-skin's runners.
pub fn register(v: &mut Vec<Runner>) {
    v.push(Runner { method: "curve-skin/arm", run: run_arm });
    v.push(Runner { method: "curve-skin/humanoid", run: run_humanoid });
    v.push(Runner { method: "curve-skin/walk", run: run_walk });
    v.push(Runner { method: "curve-skin/perf", run: run_perf });
}

fn cs<T>(r: curve_skin::Result<T>) -> Result<T> {
    r.map_err(|e| Error::Run(format!("curve-skin: {e}")))
}

fn to_f64(p: &[[f32; 3]]) -> Vec<Pt3> {
    p.iter().map(|x| Pt3::new(x[0] as f64, x[1] as f64, x[2] as f64)).collect()
}

fn widen<const K: usize>(w: &PackedWeights<2>) -> PackedWeights<K> {
    PackedWeights {
        bone: w.bone.iter().map(|b| std::array::from_fn(|k| if k < 2 { b[k] } else { 0 })).collect(),
        w: w.w.iter().map(|x| std::array::from_fn(|k| if k < 2 { x[k] } else { 0.0 })).collect(),
    }
}

fn write_obj(dir: &Path, name: &str, pos: &[[f32; 3]], tris: &[[u32; 3]]) -> Result<()> {
    crate::out::ensure_dir(dir)?;
    obj::write(dir.join(name), &MeshOut::tri_f32(pos, tris))?;
    Ok(())
}

/// Writes a polyline (an action line) as an OBJ with one `l` element.
fn write_polyline(dir: &Path, name: &str, pts: &[Pt3]) -> Result<()> {
    crate::out::ensure_dir(dir)?;
    let mut s = String::from("# curve-skin muscle action line\n");
    for p in pts {
        s.push_str(&format!("v {} {} {}\n", p.x, p.y, p.z));
    }
    s.push('l');
    for i in 1..=pts.len() {
        s.push_str(&format!(" {i}"));
    }
    s.push('\n');
    let path = dir.join(name);
    std::fs::write(&path, s).map_err(crate::error::io_err(path))
}

/// Deforms with one skinner (single thread), returns positions and seconds.
fn timed(s: &dyn Skinner, out: &mut [[f32; 3]]) -> f64 {
    let t = Instant::now();
    s.deform(DeformOutput { positions: out, normals: None });
    t.elapsed().as_secs_f64()
}

// ---------------------------------------------------------------------------------------------
// arm

/// Bend (about z through the elbow) or twist (about the forearm axis).
#[derive(Clone, Copy, Debug, Deserialize, PartialEq, Eq)]
enum ArmMotion {
    Bend,
    Twist,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct ArmParams {
    /// Limb radius R (m).
    radius: f64,
    /// Bone length (m); the arm spans x ∈ [−bone_len, bone_len].
    bone_len: f64,
    /// [quick, default, full] rings along the arm.
    rings: [usize; 3],
    /// [quick, default, full] vertices around.
    segments: [usize; 3],
    motion: ArmMotion,
    /// Sweep end (degrees); the sweep starts at 0.
    to_deg: f64,
    /// [quick, default, full] angle steps (degrees).
    step_deg: [f64; 3],
    /// Ramp half-widths for LBS / DQS, in units of R.
    widths: Vec<f64>,
    /// Angles (degrees) with OBJ output and fold analysis.
    obj_at_deg: Vec<f64>,
    /// [quick, default, full] interior samples of the fold analysis.
    fold_samples: [usize; 3],
    /// max_scale of the volume-compensated curve method (None = no cap).
    comp_max_scale: Option<f64>,
    /// Angle (degrees) whose figures go to summary.json without suffix.
    summary_deg: f64,
    /// Curve shapes compared (spec §3.4.2): the first is method `curve` (and `curve_comp`), a
    /// `QuadraticBSpline` after a `CircularArc` becomes `curve_bspline`. Default `[CircularArc]`.
    #[serde(default = "default_shapes")]
    shapes: Vec<CurveShape>,
    /// Optional muscle action line (spec §3.4.8) driven by the `curve` method.
    #[serde(default)]
    muscle: Option<MuscleParams>,
}

fn default_shapes() -> Vec<CurveShape> {
    vec![CurveShape::CircularArc]
}

/// A muscle action line on the arm: control points in units of R along y and of bone_len
/// along x, rest muscle radius and bulge capsule radius in units of R.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct MuscleParams {
    /// Control points `(x / bone_len, y / R, z / R)`.
    points: Vec<(f64, f64, f64)>,
    /// Rest muscle radius ÷ R.
    radius: f64,
    /// Bulge capsule radius ÷ R.
    influence: f64,
}

struct ArmMethod {
    name: String,
    skinner: Box<dyn Skinner>,
    curve: bool,
    /// The exact f64 twin of a curve method (fold analysis, f64 figures).
    twin: Option<Box<CurveSkin>>,
}

/// The `elbow-bend` and `candy-wrapper` scenes.
pub fn run_arm(ctx: &RunCtx) -> Result<Summary> {
    let p: ArmParams = scene::load(&ctx.scene_file)?.params;
    let rings = ctx.mode.pick(p.rings[0], p.rings[1], p.rings[2]);
    let segs = ctx.mode.pick(p.segments[0], p.segments[1], p.segments[2]);
    let step = ctx.mode.pick(p.step_deg[0], p.step_deg[1], p.step_deg[2]);
    let n_fold = ctx.mode.pick(p.fold_samples[0], p.fold_samples[1], p.fold_samples[2]);
    if p.radius <= 0.0 || p.bone_len <= 0.0 || step <= 0.0 || rings < 2 || segs < 3 {
        return Err(scene::invalid(
            &ctx.scene_file,
            "radius, bone_len, step, rings ≥ 2, segments ≥ 3 must be positive",
        ));
    }
    let r = p.radius;
    let (mesh, sk) = cs(cylinder_arm(r, p.bone_len, rings, segs))?;
    let n = mesh.positions.len();
    let side: Vec<bool> = (0..n).map(|i| i < n - 2).collect();
    let rest32 = mesh.positions_f32();
    let v0 = signed_volume(&mesh.positions, &mesh.tris);

    let mut methods: Vec<ArmMethod> = Vec::new();
    for &h in &p.widths {
        let w2 = ramp_weights(&mesh.positions, 0.0, h * r, Ramp::SmoothStep);
        let tag = format!("h{}", h);
        methods.push(ArmMethod {
            name: format!("lbs_{tag}"),
            skinner: Box::new(cs(Lbs::<4>::new(rest32.clone(), None, widen(&w2)))?),
            curve: false,
            twin: None,
        });
        methods.push(ArmMethod {
            name: format!("dqs_{tag}"),
            skinner: Box::new(cs(Dqs::<4>::new(rest32.clone(), None, widen(&w2)))?),
            curve: false,
            twin: None,
        });
    }
    if p.shapes.is_empty() {
        return Err(scene::invalid(&ctx.scene_file, "shapes must name at least one curve shape"));
    }
    let skel_for = |shape: CurveShape| {
        let d = JointCurveDefaults { shape, ..Default::default() };
        build_curve_skeleton(&sk, &TopologyRules::default(), &d)
    };
    let cskel = skel_for(p.shapes[0]);
    let new_curve = |cskel: &curve_skin::CurveSkeleton, o: CurveOptions| {
        cs(CurveSkin::new(&sk, cskel.clone(), &mesh.positions, None, o))
    };
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
        let sk2 = skel_for(shape);
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
            let pts: Vec<Pt3> = mp.points.iter().map(|&(x, y, z)| Pt3::new(x * p.bone_len, y * r, z * r)).collect();
            let line = cs(ActionLine::new(pts))?;
            let bulge = cs(MuscleBulge::new(&line, &mesh.positions, mp.radius * r, mp.influence * r))?;
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

    let mut csv = CsvWriter::create(
        &ctx.out_dir.join("metrics.csv"),
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
    let mut muscle_csv = match muscle {
        Some(_) => Some(CsvWriter::create(
            &ctx.out_dir.join("muscle.csv"),
            &["angle_deg", "length_ratio", "length_over_r", "bulge_volume_ratio"],
        )?),
        None => None,
    };
    let mut series: Vec<Vec<Vec<(f64, f64)>>> = vec![vec![Vec::new(); methods.len()]; 3];
    let mut summary = Summary::new();
    summary.set_str("mode", ctx.mode.name());
    summary.set_count("vertices", n as u64);
    let steps = (p.to_deg / step).round() as usize;
    let mut out = vec![[0f32; 3]; n];
    // The ring(s) nearest the joint: within half a ring spacing of x = 0.
    let band = 0.51 * 2.0 * p.bone_len / (rings - 1) as f64;
    for k in 0..=steps {
        let deg = (k as f64 * step).min(p.to_deg);
        let mut pose = SkinPose::rest(&sk);
        let g = match p.motion {
            ArmMotion::Bend => axis_deg(Vec3::z(), deg),
            ArmMotion::Twist => axis_deg(Vec3::x(), deg),
        };
        pose.set_world(&sk, 1, g);
        let posed = pose.globals(&sk);
        let joints: Vec<Pt3> = posed.iter().map(|f| Pt3::from(f.translation.vector)).collect();
        let bones = [(joints[0], joints[1]), (joints[1], joints[2])];
        let is_key = p.obj_at_deg.iter().any(|&a| (a - deg).abs() < 1e-9);
        for (mi, m) in methods.iter_mut().enumerate() {
            cs(m.skinner.prepare(&sk, &posed))?;
            let t = timed(m.skinner.as_ref(), &mut out);
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
                cs(twin.prepare(&sk, &posed))?;
                if is_key && n_fold > 0 {
                    caps = twin.diagnostics().cap_hits;
                    let tw: &CurveSkin = twin;
                    fold = fold_fraction(&|x| tw.map_point(&x), &samples, 1e-5);
                }
            }
            // Self-intersections (surface) only at the key angles: a BVH over every triangle.
            let si = if is_key { self_intersections(&out, &mesh.tris) as f64 } else { f64::NAN };
            csv.row(&[
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
            ])?;
            series[0][mi].push((deg, vol));
            series[1][mi].push((deg, jr));
            series[2][mi].push((deg, hi / r));
            if is_key {
                write_obj(
                    &ctx.out_dir.join("obj"),
                    &format!("{}_{:03}.obj", m.name, deg.round() as i64),
                    &out,
                    &mesh.tris,
                )?;
            }
            let at_summary = (deg - p.summary_deg).abs() < 1e-9;
            let tagged = |s: &mut Summary, key: &str, v: f64| {
                if at_summary {
                    s.set(key, v);
                }
                if is_key {
                    s.set(&format!("{key}_at_{}", deg.round() as i64), v);
                }
            };
            // Summary names: "lbs" / "dqs" are the h = R variants; h = 2R gets "_h2r".
            let base = match m.name.as_str() {
                "lbs_h1" => "lbs".to_string(),
                "dqs_h1" => "dqs".to_string(),
                "lbs_h2" => "lbs_h2r".to_string(),
                "dqs_h2" => "dqs_h2r".to_string(),
                other => other.to_string(),
            };
            tagged(&mut summary, &format!("{base}_volume_ratio"), vol);
            let jr_key = if p.motion == ArmMotion::Bend { "joint_radius_ratio" } else { "ring_radius_ratio" };
            tagged(&mut summary, &format!("{base}_{jr_key}"), jr);
            tagged(&mut summary, &format!("{base}_min_dist_over_r"), lo / r);
            tagged(&mut summary, &format!("{base}_max_dist_over_r"), hi / r);
            if is_key {
                tagged(&mut summary, &format!("{base}_self_intersections"), si);
            }
            if m.curve && !fold.is_nan() {
                tagged(&mut summary, &format!("{base}_fold_fraction"), fold);
                tagged(&mut summary, &format!("{base}_cap_hits"), caps as f64);
            }
            if let Some(twin) = m.twin.as_deref() {
                if at_summary {
                    let mut o64 = vec![Pt3::origin(); n];
                    twin.deform_f64(&mut o64);
                    let side64: Vec<Pt3> = o64.iter().zip(&side).filter(|(_, &s)| s).map(|(x, _)| *x).collect();
                    summary.set(&format!("{base}_max_dist_over_r_f64"), distance_to_bones(&side64, &bones).1 / r);
                    summary.set(&format!("{base}_volume_ratio_f64"), signed_volume(&o64, &mesh.tris) / v0);
                }
                if is_key || at_summary {
                    tagged(&mut summary, &format!("{base}_l_over_r"), twin.frames()[0].l_cp / r);
                }
                if let (Some((line, bulge)), "curve") = (&muscle, m.name.as_str()) {
                    let mut lp = Vec::new();
                    line.deform(twin, &mut lp);
                    let ratio = line.length_ratio(&lp);
                    let mut bulged = out.clone();
                    bulge.apply(&lp, ratio, &mut bulged);
                    let vb = signed_volume(&to_f64(&bulged), &mesh.tris) / v0;
                    tagged(&mut summary, "muscle_length_ratio", ratio);
                    tagged(&mut summary, "muscle_bulge_volume_ratio", vb);
                    if let Some(c) = muscle_csv.as_mut() {
                        c.row(&[deg.into(), ratio.into(), (polyline_length(&lp) / r).into(), vb.into()])?;
                    }
                    if is_key {
                        let name = format!("muscle_{:03}.obj", deg.round() as i64);
                        write_polyline(&ctx.out_dir.join("obj"), &name, &lp)?;
                        write_obj(
                            &ctx.out_dir.join("obj"),
                            &format!("curve_muscle_{:03}.obj", deg.round() as i64),
                            &bulged,
                            &mesh.tris,
                        )?;
                    }
                }
            }
        }
    }
    if p.motion == ArmMotion::Twist {
        // §7.2 c closed form of the LBS candy wrapper at the summary angle.
        let th = p.summary_deg.to_radians();
        for &h in &p.widths {
            let v = 1.0 - (2.0 * h * r / (2.0 * p.bone_len)) * (1.0 - th.cos()) * 2.0 * 9.0 / 70.0;
            let key = if (h - 1.0).abs() < 1e-12 {
                "lbs_closed_form_volume_ratio".to_string()
            } else {
                format!("lbs_h{h}_closed_form_volume_ratio")
            };
            summary.set(&key, v);
        }
    }
    let titles =
        [("volume_ratio", "V/V0"), ("joint_radius_ratio", "radius ratio"), ("max_dist_over_r", "max dist / R")];
    for (si, (file, ylab)) in titles.iter().enumerate() {
        let mut plot = LinePlot::new(&format!("{} vs angle", ylab), "angle (deg)", ylab);
        for (mi, m) in methods.iter().enumerate() {
            plot = plot.with(Series::new(m.name.clone(), series[si][mi].clone()));
        }
        plot.write_png(&ctx.out_dir.join(format!("{file}.png")))?;
    }
    write_arm_report(ctx, &p, &summary)?;
    Ok(summary)
}

fn write_arm_report(ctx: &RunCtx, p: &ArmParams, s: &Summary) -> Result<()> {
    let g = |k: &str| s.get(k).map(|v| format!("{v:.4}")).unwrap_or_else(|| "–".into());
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
    std::fs::write(ctx.out_dir.join("report.md"), md).map_err(crate::error::io_err(ctx.out_dir.join("report.md")))
}

// ---------------------------------------------------------------------------------------------
// humanoid

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct HumanoidParams {
    /// [quick, default, full] mesh resolution (1.0 ≈ 50k vertices).
    resolution: [f64; 3],
    /// Pose names (see `curve_skin::poses::HUMANOID_POSES`).
    poses: Vec<String>,
    /// Weight threshold for the LBS influence statistics.
    weight_threshold: f32,
    /// Write OBJ files per pose and method.
    obj: bool,
}

struct Character {
    mesh: SkinMesh,
    sk: SkinSkeleton,
    rest32: Vec<[f32; 3]>,
    normals32: Vec<[f32; 3]>,
    w4: PackedWeights<4>,
    rows: Vec<Vec<(u16, f32)>>,
}

fn character(res: f64, threshold: f32) -> Result<Character> {
    let h = cs(humanoid(res))?;
    let rows = inverse_distance_weights(&h.mesh.positions, &h.skeleton, 4.0, threshold);
    let (w4, _) = cs(PackedWeights::<4>::from_sparse(&rows))?;
    let rest32 = h.mesh.positions_f32();
    let normals32 = h.mesh.vertex_normals().iter().map(|v| [v.x as f32, v.y as f32, v.z as f32]).collect();
    Ok(Character { mesh: h.mesh, sk: h.skeleton, rest32, normals32, w4, rows })
}

fn skinners(c: &Character, normals: bool) -> Result<Vec<(&'static str, Box<dyn Skinner>)>> {
    let n = if normals { Some(c.normals32.clone()) } else { None };
    let cskel = build_curve_skeleton(&c.sk, &TopologyRules::default(), &JointCurveDefaults::default());
    Ok(vec![
        ("lbs", Box::new(cs(Lbs::new(c.rest32.clone(), n.clone(), c.w4.clone()))?) as Box<dyn Skinner>),
        ("dqs", Box::new(cs(Dqs::new(c.rest32.clone(), n.clone(), c.w4.clone()))?)),
        (
            "curve",
            Box::new(cs(CurveSkin::new(
                &c.sk,
                cskel,
                &c.mesh.positions,
                if normals { Some(&c.normals32) } else { None },
                CurveOptions::default(),
            ))?),
        ),
    ])
}

/// The `humanoid-poses` scene.
pub fn run_humanoid(ctx: &RunCtx) -> Result<Summary> {
    let p: HumanoidParams = scene::load(&ctx.scene_file)?.params;
    let res = ctx.mode.pick(p.resolution[0], p.resolution[1], p.resolution[2]);
    let c = character(res, p.weight_threshold)?;
    let n = c.rest32.len();
    let v0 = signed_volume(&c.mesh.positions, &c.mesh.tris);
    let mut methods = skinners(&c, false)?;
    let mut summary = Summary::new();
    summary.set_str("mode", ctx.mode.name());
    summary.set_count("vertices", n as u64);
    // Influence statistics: curve curves per vertex vs LBS weights above the threshold.
    let cskel = build_curve_skeleton(&c.sk, &TopologyRules::default(), &JointCurveDefaults::default());
    summary.set_count("curves", cskel.curves.len() as u64);
    let cur = cs(CurveSkin::new(&c.sk, cskel, &c.mesh.positions, None, CurveOptions::default()))?;
    let ch = influences_histogram(&cur.binding.offsets);
    let lbs_hist = {
        let mut h = vec![0usize; 9];
        for r in &c.rows {
            h[r.len().min(8)] += 1;
        }
        h
    };
    summary.set("curve_one_weight_fraction", ch.get(1).copied().unwrap_or(0) as f64 / n as f64);
    summary.set("curve_mean_weights", histogram_mean(&ch));
    summary.set_count("curve_max_weights", (ch.len() - 1) as u64);
    summary.set("lbs_mean_influences", histogram_mean(&lbs_hist));
    summary.set_count("curve_clamped_vertices", cur.binding.stats.clamped as u64);
    let mut hcsv = CsvWriter::create(&ctx.out_dir.join("influences.csv"), &["k", "curve_vertices", "lbs_vertices"])?;
    for (k, &l) in lbs_hist.iter().enumerate() {
        hcsv.row(&[k.into(), ch.get(k).copied().unwrap_or(0).into(), l.into()])?;
    }
    let mut csv = CsvWriter::create(&ctx.out_dir.join("metrics.csv"), &["pose", "method", "volume_ratio", "time_s"])?;
    let mut out = vec![[0f32; 3]; n];
    for name in &p.poses {
        let pose = humanoid_pose(&c.sk, name).ok_or_else(|| {
            scene::invalid(&ctx.scene_file, format!("unknown pose '{name}' (known: {})", HUMANOID_POSES.join(", ")))
        })?;
        let posed = pose.globals(&c.sk);
        for (m, s) in methods.iter_mut() {
            cs(s.prepare(&c.sk, &posed))?;
            let t = timed(s.as_ref(), &mut out);
            let vol = signed_volume(&to_f64(&out), &c.mesh.tris) / v0;
            csv.row(&[name.as_str().into(), (*m).into(), vol.into(), t.into()])?;
            summary.set(&format!("{m}_volume_ratio_{name}"), vol);
            summary.set(&format!("{m}_time_s_{name}"), t);
            if p.obj {
                write_obj(&ctx.out_dir.join("obj"), &format!("{name}_{m}.obj"), &out, &c.mesh.tris)?;
            }
        }
    }
    let md = format!(
        "Capsule humanoid, {n} vertices, {} curves. Curve skin: {:.1} % of vertices with one curve, mean {:.2}, max {} (paper: mostly 1, never more than 3). LBS inverse-distance weights above {}: mean {:.2} influences (paper: 3–5 for smooth skinning).\n",
        summary.get("curves").unwrap_or(0.0),
        100.0 * summary.get("curve_one_weight_fraction").unwrap_or(0.0),
        summary.get("curve_mean_weights").unwrap_or(0.0),
        summary.get("curve_max_weights").unwrap_or(0.0),
        p.weight_threshold,
        summary.get("lbs_mean_influences").unwrap_or(0.0),
    );
    std::fs::write(ctx.out_dir.join("report.md"), md).map_err(crate::error::io_err(ctx.out_dir.join("report.md")))?;
    Ok(summary)
}

// ---------------------------------------------------------------------------------------------
// walk

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct WalkParams {
    /// [quick, default, full] mesh resolution.
    resolution: [f64; 3],
    /// [quick, default, full] clip duration (s).
    duration: [f64; 3],
    /// Frame rate (Hz).
    fps: f64,
    /// Write an OBJ every this many frames (0 = never).
    obj_every: usize,
    /// Export walk.gltf (LBS weights + animation).
    gltf: bool,
}

/// The `walk` scene.
pub fn run_walk(ctx: &RunCtx) -> Result<Summary> {
    let p: WalkParams = scene::load(&ctx.scene_file)?.params;
    if p.fps <= 0.0 {
        return Err(scene::invalid(&ctx.scene_file, "fps must be positive"));
    }
    let res = ctx.mode.pick(p.resolution[0], p.resolution[1], p.resolution[2]);
    let dur = ctx.mode.pick(p.duration[0], p.duration[1], p.duration[2]);
    let c = character(res, 0.01)?;
    let n = c.rest32.len();
    let v0 = signed_volume(&c.mesh.positions, &c.mesh.tris);
    let mut methods = skinners(&c, false)?;
    let frames = (dur * p.fps).round() as usize + 1;
    let mut csv = CsvWriter::create(
        &ctx.out_dir.join("metrics.csv"),
        &["frame", "time", "method", "volume_ratio", "deform_s", "prepare_s"],
    )?;
    let mut out = vec![[0f32; 3]; n];
    let mut stats: Vec<(f64, f64, f64)> = vec![(f64::INFINITY, f64::NEG_INFINITY, 0.0); methods.len()];
    let mut series: Vec<Vec<(f64, f64)>> = vec![Vec::new(); methods.len()];
    let mut poses = Vec::with_capacity(frames);
    for f in 0..frames {
        let t = f as f64 / p.fps;
        let pose = walk_pose(&c.sk, t);
        let posed = pose.globals(&c.sk);
        for (mi, (m, s)) in methods.iter_mut().enumerate() {
            let t0 = Instant::now();
            cs(s.prepare(&c.sk, &posed))?;
            let tp = t0.elapsed().as_secs_f64();
            let td = timed(s.as_ref(), &mut out);
            let vol = signed_volume(&to_f64(&out), &c.mesh.tris) / v0;
            csv.row(&[f.into(), t.into(), (*m).into(), vol.into(), td.into(), tp.into()])?;
            let st = &mut stats[mi];
            *st = (st.0.min(vol), st.1.max(vol), st.2 + td);
            series[mi].push((t, vol));
            if p.obj_every > 0 && f % p.obj_every == 0 {
                write_obj(&ctx.out_dir.join("obj"), &format!("{m}_{f:04}.obj"), &out, &c.mesh.tris)?;
            }
        }
        poses.push(pose);
    }
    let mut summary = Summary::new();
    summary.set_str("mode", ctx.mode.name());
    summary.set_count("vertices", n as u64);
    summary.set_count("frames", frames as u64);
    for (mi, (m, _)) in methods.iter().enumerate() {
        summary.set(&format!("{m}_min_volume_ratio"), stats[mi].0);
        summary.set(&format!("{m}_max_volume_ratio"), stats[mi].1);
        summary.set(&format!("{m}_mean_deform_s"), stats[mi].2 / frames as f64);
    }
    let mut plot = LinePlot::new("walk: volume ratio per frame", "time (s)", "V/V0");
    for (mi, (m, _)) in methods.iter().enumerate() {
        plot = plot.with(Series::new(*m, series[mi].clone()));
    }
    plot.write_png(&ctx.out_dir.join("volume_ratio.png"))?;
    if p.gltf {
        let times: Vec<f64> = (0..frames).map(|f| f as f64 / p.fps).collect();
        let path = ctx.out_dir.join("walk.gltf");
        cs(curve_skin::gltf::write_gltf(
            &path,
            &c.rest32,
            &c.normals32,
            &c.mesh.tris,
            &c.sk,
            &c.w4,
            Some((&times, &poses)),
        ))?;
        summary.set_str("gltf", "walk.gltf");
    }
    Ok(summary)
}

// ---------------------------------------------------------------------------------------------
// perf

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct PerfParams {
    /// [quick, default, full] target vertex counts.
    vertices: [Vec<usize>; 3],
    /// Thread counts to time.
    threads: Vec<usize>,
    /// Minimum timing window per measurement (s).
    min_time: f64,
    /// Vertex count (at least) whose single-thread, positions-only figures go to the summary.
    summary_at_least: usize,
}

fn time_frames(
    s: &dyn Skinner,
    out: &mut [[f32; 3]],
    nrm: Option<&mut [[f32; 3]]>,
    threads: usize,
    min_time: f64,
) -> Result<f64> {
    let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().map_err(|e| Error::Run(e.to_string()))?;
    let mut nrm = nrm;
    let mut run = |out: &mut [[f32; 3]]| {
        let o = DeformOutput { positions: out, normals: nrm.as_deref_mut() };
        if threads == 1 {
            s.deform(o);
        } else {
            pool.install(|| deform_par(s, o, 4096));
        }
    };
    run(out);
    let mut reps = 0usize;
    let t0 = Instant::now();
    while t0.elapsed().as_secs_f64() < min_time || reps < 3 {
        run(out);
        reps += 1;
    }
    Ok(t0.elapsed().as_secs_f64() / reps as f64)
}

/// The `perf` scene.
pub fn run_perf(ctx: &RunCtx) -> Result<Summary> {
    let p: PerfParams = scene::load(&ctx.scene_file)?.params;
    let counts = ctx.mode.pick(&p.vertices[0], &p.vertices[1], &p.vertices[2]).clone();
    let mut csv = CsvWriter::create(
        &ctx.out_dir.join("perf.csv"),
        &["vertices", "method", "threads", "normals", "frame_s", "mverts_per_s", "prepare_s"],
    )?;
    let mut summary = Summary::new();
    summary.set_str("mode", ctx.mode.name());
    summary.set_str("profile", if cfg!(debug_assertions) { "debug" } else { "release" });
    summary.set_count("available_threads", std::thread::available_parallelism().map(|x| x.get()).unwrap_or(1) as u64);
    let mut series: std::collections::BTreeMap<String, Vec<(f64, f64)>> = Default::default();
    // The summary figures come from the first size ≥ summary_at_least (else the largest).
    let pick = counts.iter().position(|&c| c >= p.summary_at_least).unwrap_or(counts.len().saturating_sub(1));
    for (ci, &target) in counts.iter().enumerate() {
        let at_summary = ci == pick;
        let res = (target as f64 / 50_000.0).sqrt();
        let c = character(res, 0.01)?;
        let n = c.rest32.len();
        let posed = walk_pose(&c.sk, 0.3).globals(&c.sk);
        let mut methods = skinners(&c, true)?;
        let mut out = vec![[0f32; 3]; n];
        let mut nrm = vec![[0f32; 3]; n];
        let mut frame1: std::collections::BTreeMap<&str, f64> = Default::default();
        for (m, s) in methods.iter_mut() {
            let t0 = Instant::now();
            let reps = 20;
            for _ in 0..reps {
                cs(s.prepare(&c.sk, &posed))?;
            }
            let tp = t0.elapsed().as_secs_f64() / reps as f64;
            for &th in &p.threads {
                for normals in [false, true] {
                    let dt = time_frames(
                        s.as_ref(),
                        &mut out,
                        if normals { Some(&mut nrm[..]) } else { None },
                        th,
                        p.min_time,
                    )?;
                    let mv = n as f64 / dt / 1e6;
                    csv.row(&[
                        n.into(),
                        (*m).into(),
                        th.into(),
                        (if normals { "yes" } else { "no" }).into(),
                        dt.into(),
                        mv.into(),
                        tp.into(),
                    ])?;
                    if !normals {
                        series.entry(format!("{m} {th}t")).or_default().push((n as f64, dt));
                    }
                    if th == 1 && !normals {
                        frame1.insert(*m, dt);
                    }
                    if at_summary {
                        let suffix = match (th, normals) {
                            (1, false) => String::new(),
                            (1, true) => "_normals".into(),
                            (t, false) => format!("_{t}t"),
                            (t, true) => format!("_{t}t_normals"),
                        };
                        summary.set(&format!("{m}_mverts_per_s{suffix}"), mv);
                    }
                }
            }
            if at_summary {
                summary.set(&format!("{m}_prepare_s"), tp);
            }
        }
        if at_summary {
            summary.set_count("summary_vertices", n as u64);
            if let (Some(cv), Some(lb)) = (frame1.get("curve"), frame1.get("lbs")) {
                summary.set("curve_over_lbs_time_ratio", cv / lb);
            }
        }
    }
    let mut plot = LinePlot::new("time per frame (positions only)", "vertices", "time per frame (s)").log(true, true);
    for (k, v) in series {
        plot = plot.with(Series::new(k, v));
    }
    plot.write_png(&ctx.out_dir.join("time_vs_vertices.png"))?;
    Ok(summary)
}

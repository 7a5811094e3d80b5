//! rigging's scenes (spec §6): automatic skeleton embedding and bone-heat weights.
//!
//! - `rigging/test16` ([`run_test16`]): the 16 held-out procedural characters rigged with the human
//!   template, scored against ground truth, failures re-run with one hint; weight checks.
//! - `rigging/timing` ([`run_timing`]): time per stage against vertex count (paper Table 1).
//! - `rigging/train` ([`run_train`]): max-margin learning of Γ on the training characters.
//! - `rigging/animate` ([`run_animate`]): a walk on a rigged character, OBJ frames and glTF.
//! - `rigging/heat-two-bone` ([`run_heat_two_bone`]): weights across one joint (paper Fig. 8).
//! - `rigging/odd-shapes` ([`run_odd_shapes`]): real-world defects handled or refused; quadruped.
//! - `rigging/weights-vs-proximity` ([`run_weights_vs_proximity`]): arms near the torso.

use std::fmt::Write as _;
use std::path::Path;

use geom_core::anim::skin::{forward_kinematics, lbs, skinning_transforms, SkinSkeleton, SkinWeights};
use geom_core::collide::MeshQuery;
use geom_core::io::{obj, MeshOut};
use geom_core::iso::{polygonize, sdf, PolygonizeOptions};
use geom_core::math::{Iso3, Pt3, UnitQuat, Vec3};
use geom_core::mesh::TriMesh;
use geom_core::procedural::character::{build_mesh, humanoid, quadruped, HumanoidParams, JointSet};
use geom_core::spatial::Aabb;
use rigging::characters::{test_class, test_params, train_params};
use rigging::embed::{k_best_embeddings, reinsert_joints, Problem};
use rigging::eval::score;
use rigging::heat::bone_heat;
use rigging::learn::{margin, max_margin, CharacterExamples, LearnOptions};
use rigging::{autorig, prepare_embedding, Hint, Rig, RigError, RigOptions, SkeletonTemplate, GAMMA_PUBLISHED};
use serde::Deserialize;

use crate::error::{Error, Result};
use crate::out::{Cell, CsvWriter, Summary};
use crate::plot::{LinePlot, Series};
use crate::registry::{RunCtx, Runner};
use crate::scene;

/// Adds rigging's runners.
pub fn register(v: &mut Vec<Runner>) {
    v.push(Runner { method: "rigging/test16", run: run_test16 });
    v.push(Runner { method: "rigging/timing", run: run_timing });
    v.push(Runner { method: "rigging/train", run: run_train });
    v.push(Runner { method: "rigging/animate", run: run_animate });
    v.push(Runner { method: "rigging/heat-two-bone", run: run_heat_two_bone });
    v.push(Runner { method: "rigging/odd-shapes", run: run_odd_shapes });
    v.push(Runner { method: "rigging/weights-vs-proximity", run: run_weights_vs_proximity });
}

fn rg<T>(r: rigging::Result<T>) -> Result<T> {
    r.map_err(|e| Error::Run(format!("rigging: {e}")))
}

fn gc<T>(r: geom_core::Result<T>) -> Result<T> {
    r.map_err(|e| Error::Run(format!("geom-core: {e}")))
}

/// A generated humanoid: mesh and ground truth.
fn character(p: &HumanoidParams, nv: usize) -> Result<(TriMesh, JointSet)> {
    let (sdf, truth) = gc(humanoid(p))?;
    Ok((gc(build_mesh(&sdf, nv))?, truth))
}

fn write_skeleton_obj(path: &Path, sk: &SkeletonTemplate, joints: &[Pt3]) -> Result<()> {
    let mut s = String::from("# embedded skeleton: one vertex per joint, one line per bone\n");
    for (j, p) in joints.iter().enumerate() {
        let _ = writeln!(s, "v {} {} {} # {}", p.x, p.y, p.z, sk.joints[j].name);
    }
    for (p, c) in sk.bones() {
        let _ = writeln!(s, "l {} {}", p + 1, c + 1);
    }
    std::fs::write(path, s).map_err(|e| Error::Run(format!("{}: {e}", path.display())))
}

/// Largest |Σ w − 1| over rows, the smallest weight, and the rigid-motion error over the
/// height: posing every skinning joint with the same rigid transform must move the mesh rigidly.
fn weight_checks(rig: &Rig) -> Result<(f64, f64, f64)> {
    let w = &rig.weights;
    let mut sum_err: f64 = 0.0;
    for v in 0..w.len() {
        let (_, ws) = w.row(v);
        sum_err = sum_err.max((ws.iter().map(|&x| x as f64).sum::<f64>() - 1.0).abs());
    }
    let min_w = w.w.iter().map(|&x| x as f64).fold(f64::INFINITY, f64::min);
    let sk = rg(rig.skin_skeleton())?;
    let t = Iso3::from_parts(nalgebra::Translation3::new(0.3, -0.2, 0.7), UnitQuat::from_euler_angles(0.4, -0.9, 0.25));
    let posed: Vec<Iso3> = sk.rest_world.iter().map(|r| t * r).collect();
    let tr = skinning_transforms(&sk, &posed);
    let mut out = vec![Pt3::origin(); rig.mesh.n_vertices()];
    lbs(&rig.mesh.positions, w, &tr, &mut out);
    let h = rig.mesh.aabb().size().y;
    let err = rig.mesh.positions.iter().zip(&out).map(|(x, y)| (t * x - y).norm()).fold(0.0, f64::max) / h;
    Ok((sum_err, min_w, err))
}

// ---------------------------------------------------------------------------------------------
// test16

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct Test16Params {
    /// Target vertex counts (quick, default, full).
    target_vertices: (usize, usize, usize),
    /// τ per mode.
    tau: (f64, f64, f64),
    /// First seed of the test set (16 consecutive seeds).
    first_seed: u64,
    /// Hint radius (nu) of the automatic single hint for failures.
    hint_radius_nu: f64,
    /// Write character, skeleton OBJ and weight CSV files.
    write_meshes: bool,
}

/// `rigging/test16`.
pub fn run_test16(ctx: &RunCtx) -> Result<Summary> {
    let p: Test16Params = scene::load(&ctx.scene_file)?.params;
    let nv = ctx.mode.pick(p.target_vertices.0, p.target_vertices.1, p.target_vertices.2);
    let tau = ctx.mode.pick(p.tau.0, p.tau.1, p.tau.2);
    let o = RigOptions { tau, ..Default::default() };
    let sk = SkeletonTemplate::human();
    let rs = sk.reduced();
    let header = [
        "seed",
        "class",
        "vertices",
        "success",
        "reason",
        "mean_err_pct",
        "max_err_pct",
        "t_normalize",
        "t_df",
        "t_medial",
        "t_packing",
        "t_graph",
        "t_discrete",
        "t_refine",
        "t_attach",
        "t_total",
        "expanded",
        "certified",
        "spheres",
        "min_weight",
        "sum_err",
        "rigid_err_rel",
    ];
    let mut csv = CsvWriter::create(&ctx.out_dir.join("summary.csv"), &header)?;
    let mut csv_h = CsvWriter::create(
        &ctx.out_dir.join("summary_hinted.csv"),
        &["seed", "hinted_joint", "success", "reason", "mean_err_pct"],
    )?;
    let (mut ok, mut ok_h) = (0usize, 0usize);
    let mut errs = Vec::new();
    let (mut sum_err, mut min_w, mut rigid): (f64, f64, f64) = (0.0, f64::INFINITY, 0.0);
    let mut neg = 0usize;
    let mut totals = Vec::new();
    for k in 0..16u64 {
        let seed = p.first_seed + k;
        let (mesh, truth) = character(&test_params(seed), nv)?;
        let q = gc(MeshQuery::new(&mesh))?;
        let res = autorig(&mesh.positions, &mesh.faces, &sk, &[], &o);
        let (success, reason, rig) = match res {
            Ok(rig) => {
                let s = score(&sk, &rig.joints, &truth.rest, &q);
                (s.ok, s.reason.clone(), Some((rig, s)))
            }
            Err(e) => (false, e.to_string(), None),
        };
        let mut worst = rs.full_index[1];
        if let Some((rig, s)) = &rig {
            let (se, mw, re) = weight_checks(rig)?;
            sum_err = sum_err.max(se);
            min_w = min_w.min(mw);
            rigid = rigid.max(re);
            neg += rig.weights.w.iter().filter(|&&x| x < 0.0).count();
            errs.push(s.mean_err_rel);
            worst = s.worst_reduced;
            let t = &rig.timings;
            totals.push(t.total());
            let mut cells: Vec<Cell> = vec![
                (seed as usize).into(),
                test_class(seed).into(),
                mesh.n_vertices().into(),
                (success as usize).into(),
                reason.as_str().into(),
                (100.0 * s.mean_err_rel).into(),
                (100.0 * s.max_err_rel).into(),
            ];
            cells.extend(timing_cells(t));
            cells.extend([
                rig.discrete.expanded.into(),
                (rig.discrete.certified_optimal as usize).into(),
                rig.diagnostics.spheres.into(),
                mw.into(),
                se.into(),
                re.into(),
            ]);
            csv.row(&cells)?;
            if p.write_meshes {
                let dir = ctx.out_dir.join("meshes");
                crate::out::ensure_dir(&dir)?;
                gc(obj::write(dir.join(format!("char_{seed}.obj")), &MeshOut::tri(&mesh.positions, &mesh.faces)))?;
                write_skeleton_obj(&dir.join(format!("skel_{seed}.obj")), &sk, &rig.joints)?;
            }
        } else {
            let mut cells: Vec<crate::out::Cell> = vec![
                (seed as usize).into(),
                test_class(seed).into(),
                mesh.n_vertices().into(),
                0usize.into(),
                reason.as_str().into(),
            ];
            cells.resize(header.len(), f64::NAN.into());
            csv.row(&cells)?;
        }
        if success {
            ok += 1;
            ok_h += 1;
            continue;
        }
        // One automatic hint: the ground-truth position of the worst reduced joint.
        let sim_scale = 0.9 / mesh.aabb().size().max();
        let hint = Hint::Near {
            joint: sk.joints[worst].name.clone(),
            point: truth.rest[worst].coords.into(),
            radius: p.hint_radius_nu / sim_scale,
        };
        let (hs, hr, he) = match autorig(&mesh.positions, &mesh.faces, &sk, std::slice::from_ref(&hint), &o) {
            Ok(rig) => {
                let s = score(&sk, &rig.joints, &truth.rest, &q);
                (s.ok, s.reason, s.mean_err_rel)
            }
            Err(e) => (false, e.to_string(), f64::NAN),
        };
        if hs {
            ok_h += 1;
        }
        csv_h.row(&[
            (seed as usize).into(),
            sk.joints[worst].name.as_str().into(),
            (hs as usize).into(),
            hr.into(),
            (100.0 * he).into(),
        ])?;
    }
    let mean_err = errs.iter().sum::<f64>() / errs.len().max(1) as f64;
    let mut s = Summary::new();
    s.set_count("embedded_ok", ok as u64)
        .set_count("embedded_ok_with_hints", ok_h as u64)
        .set("mean_joint_error_rel", mean_err)
        .set("weights_sum_max_err", sum_err)
        .set("weights_min", min_w)
        .set_count("negative_weights", neg as u64)
        .set("rigid_motion_err_rel", rigid)
        .set("mean_total_s", totals.iter().sum::<f64>() / totals.len().max(1) as f64)
        .set_count("target_vertices", nv as u64)
        .set("tau", tau);
    let mut md = String::from("# rigging/test16\n\n| | paper | ours |\n|---|---|---|\n");
    let _ = writeln!(md, "| embedded without hints | 13 / 16 | {ok} / 16 |");
    let _ = writeln!(md, "| with one hint | 16 / 16 | {ok_h} / 16 |");
    let _ = writeln!(md, "| mean joint error / height | — | {:.4} |", mean_err);
    let _ = writeln!(md, "\nProcedural characters replace the paper's Cosmic Blobs models (see rigging/README.md).");
    std::fs::write(ctx.out_dir.join("report.md"), md).map_err(|e| Error::Run(e.to_string()))?;
    Ok(s)
}

// ---------------------------------------------------------------------------------------------
// timing

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct TimingParams {
    /// Vertex counts (quick, default, full).
    vertices: (Vec<usize>, Vec<usize>, Vec<usize>),
    /// Character seeds.
    seeds: Vec<u64>,
    /// τ.
    tau: f64,
}

/// `rigging/timing`.
pub fn run_timing(ctx: &RunCtx) -> Result<Summary> {
    let p: TimingParams = scene::load(&ctx.scene_file)?.params;
    let counts = ctx.mode.pick(p.vertices.0.clone(), p.vertices.1.clone(), p.vertices.2.clone());
    let o = RigOptions { tau: p.tau, ..Default::default() };
    let sk = SkeletonTemplate::human();
    let mut csv = CsvWriter::create(
        &ctx.out_dir.join("timing.csv"),
        &[
            "seed",
            "target",
            "vertices",
            "normalize",
            "distance_field",
            "medial",
            "packing",
            "graph",
            "discrete",
            "refine",
            "attach",
            "total",
        ],
    )?;
    let names = ["distance_field", "medial", "graph", "discrete", "refine", "attach", "total"];
    let mut series: Vec<Vec<(f64, f64)>> = vec![Vec::new(); names.len()];
    let mut s30: Vec<f64> = Vec::new();
    let mut s = Summary::new();
    for &seed in &p.seeds {
        for &nv in &counts {
            let (mesh, _) = character(&test_params(seed), nv)?;
            let rig = rg(autorig(&mesh.positions, &mesh.faces, &sk, &[], &o))?;
            let t = rig.timings;
            let n = mesh.n_vertices();
            let mut cells: Vec<Cell> = vec![(seed as usize).into(), nv.into(), n.into()];
            cells.extend(timing_cells(&t));
            csv.row(&cells)?;
            let vals = [t.distance_field, t.medial, t.graph, t.discrete, t.refine, t.attach, t.total()];
            for (k, v) in vals.iter().enumerate() {
                series[k].push((n as f64, v.max(1e-6)));
            }
            if nv == 30000 {
                s30.push(t.total());
                for (k, v) in vals.iter().enumerate() {
                    s.set(&format!("s_30k_{}", names[k]), *v);
                }
            }
        }
    }
    let mut plot = LinePlot::new("rigging: time per stage", "vertices", "seconds").log(true, true);
    for (k, pts) in series.into_iter().enumerate() {
        plot = plot.with(Series::new(names[k], pts));
    }
    plot = plot.with(Series::new("paper total (Table 1)", vec![(19001.0, 12.6), (34339.0, 56.8), (56856.0, 77.1)]));
    plot.write_png(&ctx.out_dir.join("timing.png"))?;
    if !s30.is_empty() {
        s.set("s_30k", s30.iter().cloned().fold(0.0, f64::max));
    }
    s.set_str("profile", if cfg!(debug_assertions) { "dev" } else { "release" });
    Ok(s)
}

// ---------------------------------------------------------------------------------------------
// train

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct TrainParams {
    /// Training characters (quick, default, full).
    characters: (usize, usize, usize),
    /// Target vertices.
    target_vertices: usize,
    /// τ.
    tau: f64,
    /// Embeddings per character.
    k_best: usize,
    /// Training rounds (quick, default, full).
    rounds: (usize, usize, usize),
    /// Nelder–Mead starts per shrink round.
    n_starts: usize,
}

/// Features of the k best embeddings of one character, labelled by the ground truth (joints
/// after reinsertion, no refinement); a character with no good one gets a hinted good example.
fn examples(
    mesh: &TriMesh,
    truth: &JointSet,
    sk: &SkeletonTemplate,
    o: &RigOptions,
    k: usize,
    seen: &mut Vec<Vec<u32>>,
) -> Result<(CharacterExamples, bool)> {
    let rs = sk.reduced();
    let q = gc(MeshQuery::new(mesh))?;
    let (_, e) = rg(prepare_embedding(&mesh.positions, &mesh.faces, sk, &[], o))?;
    let pr = Problem::new(&e.graph, sk, &rs, &e.cand, o);
    let list = k_best_embeddings(&pr, k).unwrap_or_default();
    let mut ex = CharacterExamples::default();
    let mut first_ok = false;
    for (i, d) in list.iter().enumerate() {
        let joints: Vec<Pt3> =
            reinsert_joints(&e.graph, sk, &rs, &d.verts).iter().map(|p| e.sim.inverse_transform_point(p)).collect();
        let good = score(sk, &joints, &truth.rest, &q).ok;
        if i == 0 {
            first_ok = good;
        }
        if !seen.contains(&d.verts) {
            seen.push(d.verts.clone());
        }
        if good {
            ex.good.push(d.features);
        } else {
            ex.bad.push(d.features);
        }
    }
    if ex.good.is_empty() {
        let s = e.sim.scaling();
        let hints: Vec<Hint> = rs
            .full_index
            .iter()
            .map(|&f| Hint::Near {
                joint: sk.joints[f].name.clone(),
                point: truth.rest[f].coords.into(),
                radius: 0.05 / s,
            })
            .collect();
        let (_, eh) = rg(prepare_embedding(&mesh.positions, &mesh.faces, sk, &hints, o))?;
        let prh = Problem::new(&eh.graph, sk, &rs, &eh.cand, o);
        if let Ok(v) = k_best_embeddings(&prh, 1) {
            ex.good.push(v[0].features);
        }
    }
    Ok((ex, first_ok))
}

/// `rigging/train`.
pub fn run_train(ctx: &RunCtx) -> Result<Summary> {
    let p: TrainParams = scene::load(&ctx.scene_file)?.params;
    let n = ctx.mode.pick(p.characters.0, p.characters.1, p.characters.2).min(62);
    let rounds = ctx.mode.pick(p.rounds.0, p.rounds.1, p.rounds.2);
    let sk = SkeletonTemplate::human();
    let meshes: Vec<(TriMesh, JointSet)> =
        (0..n as u64).map(|s| character(&train_params(s), p.target_vertices)).collect::<Result<_>>()?;
    let mut gamma = GAMMA_PUBLISHED;
    let mut csv = CsvWriter::create(
        &ctx.out_dir.join("gamma_rounds.csv"),
        &["round", "g1", "g2", "g3", "g4", "g5", "g6", "g7", "g8", "g9", "margin", "train_ok"],
    )?;
    let mut all: Vec<CharacterExamples> = vec![CharacterExamples::default(); n];
    let mut seen: Vec<Vec<Vec<u32>>> = vec![Vec::new(); n];
    let mut ok_first = 0usize;
    let mut ok_last = 0usize;
    let mut last_margin = f64::NAN;
    for round in 0..rounds.max(1) {
        let o = RigOptions { tau: p.tau, gamma, ..Default::default() };
        let mut ok = 0usize;
        for (c, (mesh, truth)) in meshes.iter().enumerate() {
            let (ex, good) = examples(mesh, truth, &sk, &o, p.k_best, &mut seen[c])?;
            ok += good as usize;
            all[c].good.extend(ex.good);
            all[c].bad.extend(ex.bad);
        }
        if round == 0 {
            ok_first = ok;
        }
        ok_last = ok;
        let (g, m) =
            max_margin(&all, &LearnOptions { n_starts: p.n_starts, rounds: 6, iters: 300, seed: round as u64 + 1 });
        last_margin = m;
        let mut cells: Vec<crate::out::Cell> = vec![round.into()];
        cells.extend(g.iter().map(|&x| x.into()));
        cells.push(m.into());
        cells.push(ok.into());
        csv.row(&cells)?;
        let change = g.iter().zip(&gamma).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
        gamma = g;
        if change < 1e-3 {
            break;
        }
    }
    let text = ron::to_string(&gamma).map_err(|e| Error::Run(e.to_string()))?;
    std::fs::write(ctx.out_dir.join("gamma.ron"), text).map_err(|e| Error::Run(e.to_string()))?;
    let mut s = Summary::new();
    s.set_count("characters", n as u64)
        .set_count("train_ok_published", ok_first as u64)
        .set_count("train_ok_last_round", ok_last as u64)
        .set("margin", last_margin)
        .set("margin_published", margin(&GAMMA_PUBLISHED, &all));
    for (k, g) in gamma.iter().enumerate() {
        s.set(&format!("gamma_{}", k + 1), *g);
    }
    Ok(s)
}

// ---------------------------------------------------------------------------------------------
// animate

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct AnimateParams {
    seed: u64,
    target_vertices: (usize, usize, usize),
    tau: f64,
    cycles: usize,
    fps: f64,
    obj_every: usize,
}

fn pack4(w: &SkinWeights) -> Result<curve_skin::PackedWeights<4>> {
    let rows: Vec<Vec<(u16, f32)>> = (0..w.len())
        .map(|v| {
            let (j, x) = w.row(v);
            j.iter().copied().zip(x.iter().copied()).collect()
        })
        .collect();
    curve_skin::PackedWeights::<4>::from_sparse(&rows).map(|x| x.0).map_err(|e| Error::Run(format!("curve-skin: {e}")))
}

/// `rigging/animate`.
pub fn run_animate(ctx: &RunCtx) -> Result<Summary> {
    let p: AnimateParams = scene::load(&ctx.scene_file)?.params;
    if p.fps <= 0.0 {
        return Err(scene::invalid(&ctx.scene_file, "fps must be positive"));
    }
    let nv = ctx.mode.pick(p.target_vertices.0, p.target_vertices.1, p.target_vertices.2);
    let sk = SkeletonTemplate::human();
    let (mesh, _) = character(&test_params(p.seed), nv)?;
    let o = RigOptions { tau: p.tau, ..Default::default() };
    let rig = rg(autorig(&mesh.positions, &mesh.faces, &sk, &[], &o))?;
    let ssk: SkinSkeleton = rg(rig.skin_skeleton())?;
    let leg = (rig.joints[4] - rig.joints[6]).norm();
    let (times, poses) = rigging::walk::walk_cycle(&ssk, leg, p.cycles, p.fps);
    let v0 = geom_core::mesh::signed_volume(&rig.mesh.faces, &rig.mesh.positions);
    let mut csv = CsvWriter::create(&ctx.out_dir.join("frames.csv"), &["frame", "time", "volume_ratio"])?;
    let mut out = vec![Pt3::origin(); rig.mesh.n_vertices()];
    let (mut vmin, mut vmax): (f64, f64) = (f64::INFINITY, 0.0);
    let dir = ctx.out_dir.join("frames");
    crate::out::ensure_dir(&dir)?;
    for (f, pose) in poses.iter().enumerate() {
        let posed = forward_kinematics(&ssk, pose);
        let t = skinning_transforms(&ssk, &posed);
        lbs(&rig.mesh.positions, &rig.weights, &t, &mut out);
        let vr = geom_core::mesh::signed_volume(&rig.mesh.faces, &out) / v0;
        vmin = vmin.min(vr);
        vmax = vmax.max(vr);
        csv.row(&[f.into(), times[f].into(), vr.into()])?;
        if p.obj_every > 0 && f % p.obj_every == 0 {
            gc(obj::write(dir.join(format!("{f:04}.obj")), &MeshOut::tri(&out, &rig.mesh.faces)))?;
        }
    }
    let pos32: Vec<[f32; 3]> = rig.mesh.positions.iter().map(|p| [p.x as f32, p.y as f32, p.z as f32]).collect();
    let nrm: Vec<[f32; 3]> =
        geom_core::mesh::vertex_normals(&rig.mesh.faces, &rig.mesh.positions, geom_core::mesh::NormalWeight::Area)
            .iter()
            .map(|n| [n.x as f32, n.y as f32, n.z as f32])
            .collect();
    let skin_poses: Vec<curve_skin::poses::SkinPose> = poses
        .iter()
        .map(|q| curve_skin::poses::SkinPose {
            rot: q.rot.clone(),
            root_pos: q.root_pos,
            twist_hint: vec![None; q.rot.len()],
        })
        .collect();
    let gltf = ctx.out_dir.join("walk.gltf");
    curve_skin::gltf::write_gltf(
        &gltf,
        &pos32,
        &nrm,
        &rig.mesh.faces,
        &ssk,
        &pack4(&rig.weights)?,
        Some((&times, &skin_poses)),
    )
    .map_err(|e| Error::Run(format!("glTF: {e}")))?;
    let bytes = std::fs::metadata(&gltf).map(|m| m.len()).unwrap_or(0);
    let ron_text = ron::to_string(&(
        rig.template.joints.iter().map(|j| j.name.clone()).collect::<Vec<_>>(),
        rig.joints.iter().map(|p| [p.x, p.y, p.z]).collect::<Vec<_>>(),
        &rig.weights.offsets,
        &rig.weights.joint,
        &rig.weights.w,
    ))
    .map_err(|e| Error::Run(e.to_string()))?;
    std::fs::write(ctx.out_dir.join("rig.ron"), ron_text).map_err(|e| Error::Run(e.to_string()))?;
    let mut s = Summary::new();
    s.set_count("frames", poses.len() as u64)
        .set_count("vertices", rig.mesh.n_vertices() as u64)
        .set("volume_ratio_min", vmin)
        .set("volume_ratio_max", vmax)
        .set_count("gltf_bytes", bytes)
        .set_count("gltf_joints", ssk.len() as u64);
    Ok(s)
}

// ---------------------------------------------------------------------------------------------
// heat-two-bone

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct HeatTwoBoneParams {
    /// Arm radius (nu) of the bent arm.
    radius: f64,
    /// Cylinder radii of the transition-width check.
    widths: (f64, f64),
    /// Grid spacing as a fraction of the radius.
    h_rel: (f64, f64, f64),
}

fn capsules(a: Pt3, b: Pt3, c: Pt3, r: f64, h: f64) -> Result<TriMesh> {
    let f = move |p: &Pt3| sdf::union(sdf::capsule(p, &a, &b, r), sdf::capsule(p, &b, &c, r));
    let bb = Aabb::from_points(&[a, b, c]).grow(r + 3.0 * h);
    gc(polygonize(&f, &PolygonizeOptions { bounds: bb, h }))
}

/// Axial width of the 0.1 → 0.9 transition of the child weight on a straight two-bone cylinder.
fn transition_width(r: f64, h: f64) -> Result<f64> {
    let (a, b, c) = (Pt3::new(0.1, 0.5, 0.5), Pt3::new(0.5, 0.5, 0.5), Pt3::new(0.9, 0.5, 0.5));
    let m = capsules(a, b, c, r, h)?;
    let (w, _) = rg(rigging::heat::bone_heat_raw(&m, &[[a, b], [b, c]], &RigOptions::default()))?;
    let n = m.n_vertices();
    let mut pts: Vec<(f64, f64)> =
        (0..n).filter(|&j| (0.2..0.8).contains(&m.positions[j].x)).map(|j| (m.positions[j].x, w[n + j])).collect();
    pts.sort_by(|x, y| x.0.total_cmp(&y.0));
    let x10 = pts.iter().find(|p| p.1 >= 0.1).map(|p| p.0);
    let x90 = pts.iter().find(|p| p.1 >= 0.9).map(|p| p.0);
    match (x10, x90) {
        (Some(a), Some(b)) => Ok(b - a),
        _ => Err(Error::Run("transition not found".into())),
    }
}

/// `rigging/heat-two-bone`.
pub fn run_heat_two_bone(ctx: &RunCtx) -> Result<Summary> {
    let p: HeatTwoBoneParams = scene::load(&ctx.scene_file)?.params;
    let hr = ctx.mode.pick(p.h_rel.0, p.h_rel.1, p.h_rel.2);
    // Bent arm: shoulder → elbow along +x, elbow → hand along +y (90°).
    let (a, b, c) = (Pt3::new(0.15, 0.3, 0.5), Pt3::new(0.5, 0.3, 0.5), Pt3::new(0.5, 0.7, 0.5));
    let r = p.radius;
    let m = capsules(a, b, c, r, hr * r)?;
    let bones = [[a, b], [b, c]];
    let (w, rep) = rg(rigging::heat::bone_heat_raw(&m, &bones, &RigOptions::default()))?;
    let n = m.n_vertices();
    let mut csv = CsvWriter::create(&ctx.out_dir.join("weights_lines.csv"), &["side", "arc", "x", "y", "w_forearm"])?;
    // Outer side: z ≈ 0.5 plane, outside the bend (x > 0.5 or y < 0.3); inner side: inside.
    for j in 0..n {
        let x = m.positions[j];
        if (x.z - 0.5).abs() > 0.25 * r {
            continue;
        }
        let outer = x.x > b.x + 0.5 * r || x.y < b.y - 0.5 * r;
        let side = if outer { "outer" } else { "inner" };
        let arc = if x.y <= b.y { x.x - b.x } else { x.y - b.y };
        csv.row(&[side.into(), arc.into(), x.x.into(), x.y.into(), w[n + j].into()])?;
    }
    // Posed at 0, 45, 90 degrees of extra elbow bend (about z through the elbow).
    let (sw, _) = rg(bone_heat(&m, &bones, &RigOptions::default()))?;
    for deg in [0.0f64, 45.0, 90.0] {
        let rot = Iso3::rotation_wrt_point(UnitQuat::from_axis_angle(&Vec3::z_axis(), deg.to_radians()), b);
        let t = [Iso3::identity(), rot];
        let mut out = vec![Pt3::origin(); n];
        lbs(&m.positions, &sw, &t, &mut out);
        gc(obj::write(ctx.out_dir.join(format!("posed_{deg:.0}.obj")), &MeshOut::tri(&out, &m.faces)))?;
    }
    let w1 = transition_width(p.widths.0, hr * p.widths.0)?;
    let w2 = transition_width(p.widths.1, hr * p.widths.0)?;
    let mut s = Summary::new();
    s.set("transition_width_small", w1)
        .set("transition_width_large", w2)
        .set("transition_ratio", w2 / w1)
        .set("radius_ratio", p.widths.1 / p.widths.0)
        .set("partition_err_raw", rep.partition_err_raw)
        .set("min_raw_weight", rep.min_raw)
        .set("residual_max", rep.residual_max);
    Ok(s)
}

// ---------------------------------------------------------------------------------------------
// odd-shapes

/// Parameters of the one-character scenes (odd-shapes, weights-vs-proximity).
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct CharSceneParams {
    /// Test-set seed of the character.
    seed: u64,
    /// Arm elevation override (deg).
    #[serde(default)]
    arm_elevation_deg: Option<f64>,
    /// Target vertices (quick, default, full).
    target_vertices: (usize, usize, usize),
    /// τ.
    tau: f64,
}

/// `rigging/odd-shapes`.
pub fn run_odd_shapes(ctx: &RunCtx) -> Result<Summary> {
    let p: CharSceneParams = scene::load(&ctx.scene_file)?.params;
    let nv = ctx.mode.pick(p.target_vertices.0, p.target_vertices.1, p.target_vertices.2);
    let sk = SkeletonTemplate::human();
    let o = RigOptions { tau: p.tau, ..Default::default() };
    let (mesh, truth) = character(&test_params(p.seed), nv)?;
    let q = gc(MeshQuery::new(&mesh))?;
    let mut csv = CsvWriter::create(&ctx.out_dir.join("cases.csv"), &["case", "outcome", "embedded_ok", "message"])?;
    let mut s = Summary::new();
    let mut case = |name: &str, pos: &[Pt3], faces: &[[u32; 3]], o: &RigOptions, s: &mut Summary| -> Result<()> {
        let (outcome, ok, msg) = match autorig(pos, faces, &sk, &[], o) {
            Ok(rig) => {
                let sc = score(&sk, &rig.joints, &truth.rest, &q);
                (
                    "handled",
                    sc.ok,
                    format!(
                        "welded {} vertices; mean error {:.4} H",
                        rig.diagnostics.prep.welded_vertices, sc.mean_err_rel
                    ),
                )
            }
            Err(e) => ("refused", false, e.to_string()),
        };
        s.set_str(&format!("{name}_outcome"), outcome);
        s.set_count(&format!("{name}_embedded_ok"), ok as u64);
        csv.row(&[name.into(), outcome.into(), (ok as usize).into(), msg.into()])
    };
    // Duplicate vertices: every face on its own three vertices (a triangle soup).
    let mut dp = Vec::new();
    let mut df = Vec::new();
    for t in &mesh.faces {
        let base = dp.len() as u32;
        dp.extend(t.iter().map(|&v| mesh.positions[v as usize]));
        df.push([base, base + 1, base + 2]);
    }
    case("duplicates", &dp, &df, &o, &mut s)?;
    // Inverted orientation.
    let inv: Vec<[u32; 3]> = mesh.faces.iter().map(|t| [t[0], t[2], t[1]]).collect();
    case("inverted", &mesh.positions, &inv, &o, &mut s)?;
    // Several components: a floating sphere beside the character.
    let ball = gc(geom_core::procedural::icosphere(0.05, 2))?;
    let mut cp = mesh.positions.clone();
    let base = cp.len() as u32;
    cp.extend(ball.positions.iter().map(|x| x + Vec3::new(0.6, 0.1, 0.0)));
    let mut cf = mesh.faces.clone();
    cf.extend(ball.faces.iter().map(|t| t.map(|v| v + base)));
    case("components", &cp, &cf, &o, &mut s)?;
    case("components_keep_largest", &cp, &cf, &RigOptions { keep_largest_component: true, ..o.clone() }, &mut s)?;
    // Hole: remove three faces.
    case("holes", &mesh.positions, &mesh.faces[3..], &o, &mut s)?;
    // Non-manifold edge: a fin on the first edge.
    let mut np = mesh.positions.clone();
    np.push(mesh.positions[mesh.faces[0][0] as usize] + Vec3::new(0.0, 0.0, 0.2));
    let mut nf = mesh.faces.clone();
    let fin = (np.len() - 1) as u32;
    nf.push([mesh.faces[0][0], mesh.faces[0][1], fin]);
    nf.push([mesh.faces[0][1], mesh.faces[0][0], fin]);
    case("nonmanifold", &np, &nf, &o, &mut s)?;
    // A quadruped with the quadruped template (qualitative).
    let (qs, qt) = gc(quadruped(1.0, 1.0, 1.0, 0.2, p.seed))?;
    let qm = gc(build_mesh(&qs, nv))?;
    let qsk = SkeletonTemplate::quadruped();
    match autorig(&qm.positions, &qm.faces, &qsk, &[], &o) {
        Ok(rig) => {
            let qq = gc(MeshQuery::new(&qm))?;
            let sc = score(&qsk, &rig.joints, &qt.rest, &qq);
            s.set_count("quadruped_embedded_ok", sc.ok as u64)
                .set("quadruped_mean_err_rel", sc.mean_err_rel)
                .set_str("quadruped_reason", &sc.reason);
            write_skeleton_obj(&ctx.out_dir.join("quadruped_skel.obj"), &qsk, &rig.joints)?;
            gc(obj::write(ctx.out_dir.join("quadruped.obj"), &MeshOut::tri(&qm.positions, &qm.faces)))?;
        }
        Err(e) => {
            s.set_count("quadruped_embedded_ok", 0).set_str("quadruped_error", &e.to_string());
        }
    }
    // Too-thin limbs: refused with a diagnostic, never a panic.
    // Too-thin limbs (spec §3.13: limb radius 0.012 nu rigged with τ = 0.008, i.e. 1.5τ): refused
    // with a diagnostic, never a panic.
    let thin = HumanoidParams { limb_radius: 0.3, bumps: 0.0, ..test_params(p.seed) };
    let outcome = match character(&thin, nv.max(20000)) {
        Ok((tm, _)) => match autorig(&tm.positions, &tm.faces, &sk, &[], &RigOptions { tau: 0.008, ..o.clone() }) {
            Ok(rig) => {
                let tq = gc(MeshQuery::new(&tm))?;
                let (_, tt) = gc(humanoid(&thin))?;
                format!("embedded (correct: {})", score(&sk, &rig.joints, &tt.rest, &tq).ok)
            }
            Err(RigError::GraphDisconnected { components }) => format!("refused: graph has {components} components"),
            Err(e) => format!("refused: {e}"),
        },
        Err(e) => format!("not meshed: {e}"),
    };
    s.set_str("too_thin_outcome", &outcome);
    Ok(s)
}

// ---------------------------------------------------------------------------------------------
// weights-vs-proximity

/// `rigging/weights-vs-proximity`.
pub fn run_weights_vs_proximity(ctx: &RunCtx) -> Result<Summary> {
    let p: CharSceneParams = scene::load(&ctx.scene_file)?.params;
    let nv = ctx.mode.pick(p.target_vertices.0, p.target_vertices.1, p.target_vertices.2);
    let base = test_params(p.seed);
    let hp = HumanoidParams { arm_elevation_deg: p.arm_elevation_deg.unwrap_or(base.arm_elevation_deg), ..base };
    let (mesh, truth) = character(&hp, nv)?;
    let sk = SkeletonTemplate::human();
    let bones = sk.bones();
    let o = RigOptions { tau: p.tau, ..Default::default() };
    let rig = rg(autorig(&mesh.positions, &mesh.faces, &sk, &[], &o))?;
    let gt: Vec<[Pt3; 2]> = bones.iter().map(|&(a, b)| [truth.rest[a], truth.rest[b]]).collect();
    let emb: Vec<[Pt3; 2]> = bones.iter().map(|&(a, b)| [rig.joints[a], rig.joints[b]]).collect();
    let is_arm = |b: usize| {
        let name = &sk.joints[bones[b].1].name;
        name.contains("elbow") || name.contains("hand")
    };
    let is_spine = |b: usize| matches!(sk.joints[bones[b].1].name.as_str(), "back" | "hips");
    let nearest = |segs: &[[Pt3; 2]], x: &Pt3| {
        (0..segs.len())
            .map(|b| (b, (geom_core::query::closest_point_segment(x, &segs[b][0], &segs[b][1]).1 - x).norm()))
            .min_by(|a, c| a.1.total_cmp(&c.1))
            .map(|(b, _)| b)
            .expect("bones exist")
    };
    let mut csv = CsvWriter::create(
        &ctx.out_dir.join("torso_vertices.csv"),
        &["vertex", "heat_arm_weight", "proximity_arm_weight"],
    )?;
    let (mut torso, mut bad_heat, mut bad_prox) = (0usize, 0usize, 0usize);
    for v in 0..rig.mesh.n_vertices() {
        let x = rig.mesh.positions[v];
        // Torso vertex: its nearest ground-truth bone is a spine bone.
        if !is_spine(nearest(&gt, &x)) {
            continue;
        }
        torso += 1;
        let (js, ws) = rig.weights.row(v);
        let heat_arm: f64 =
            js.iter().zip(ws).filter(|(j, _)| **j > 0 && is_arm(**j as usize - 1)).map(|(_, &w)| w as f64).sum();
        let prox_arm = if is_arm(nearest(&emb, &x)) { 1.0 } else { 0.0 };
        if heat_arm > 0.5 {
            bad_heat += 1;
        }
        if prox_arm > 0.5 {
            bad_prox += 1;
        }
        csv.row(&[v.into(), heat_arm.into(), prox_arm.into()])?;
    }
    let mut s = Summary::new();
    s.set_count("torso_vertices", torso as u64)
        .set_count("torso_arm_heat", bad_heat as u64)
        .set_count("torso_arm_proximity", bad_prox as u64);
    Ok(s)
}

/// The per-stage timing columns (s) of a rig, in the order of the CSV headers:
/// normalize, distance field, medial, packing, graph, discrete, refine, attach, total.
fn timing_cells(t: &rigging::StageTimings) -> [Cell; 9] {
    [
        t.normalize.into(),
        t.distance_field.into(),
        t.medial.into(),
        t.packing.into(),
        t.graph.into(),
        t.discrete.into(),
        t.refine.into(),
        t.attach.into(),
        t.total().into(),
    ]
}

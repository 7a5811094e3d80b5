//! motion-graph's scenes (spec §6.2): randomized search over a hierarchy of motion graphs on a
//! procedural (`geom_core::anim::synth`) or real (CMU BVH) database.
//!
//! One runner, `motion-graph/search`, serves every scene: it builds the database and the graph,
//! then solves a list of problems (random reachable body constraints as in MG-1, or fixed ones
//! with hard label/frame constraints and joint constraints), assembles, smooths and corrects
//! each best path, and reports the metrics of §3.12. Outputs: `motion.bvh` (problem 0),
//! `problem_<k>.bvh`, optional stick-figure OBJ frames, `metrics.csv` (one row per problem),
//! `cuts.csv`, `anytime.csv`, `trajectory.png` (top view of every result with its constraints).

use std::path::PathBuf;
use std::time::{Duration, Instant};

use geom_core::anim::bvh::{self, BvhOptions, BvhUnits, BvhWriteOptions};
use geom_core::anim::metrics::{percentile, stick_figure};
use geom_core::anim::synth::{library, Preset};
use geom_core::anim::JointRole;
use geom_core::io::{obj, MeshOut};
use geom_core::math::{Planar, Vec3};
use motion_graph::{
    assemble, enforce_body, evaluate, fix_contacts, random_mg1, smooth, BodyConstraint, ClipStats, Database, DbParams,
    FrameRef, GraphParams, HardConstraint, JointConstraint, MotionGraph, Problem, Search, SearchParams, Tolerance,
    Weights,
};
use serde::Deserialize;

use crate::error::{Error, Result};
use crate::out::{workspace_root, Cell, CsvWriter, Summary};
use crate::plot::{LinePlot, Series};
use crate::registry::{RunCtx, Runner};
use crate::scene::{self, Mode};

/// Adds motion-graph's runner.
pub fn register(v: &mut Vec<Runner>) {
    v.push(Runner { method: "motion-graph/search", run: run_search });
}

fn mg<T>(r: motion_graph::Result<T>) -> Result<T> {
    r.map_err(|e| Error::Run(format!("motion-graph: {e}")))
}

/// Where clips come from.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub enum Source {
    /// A synthetic library: clip count per mode (quick, default, full).
    Synth { preset: Preset, clips: (usize, usize, usize), frames: (usize, usize), seed: u64 },
    /// A BVH file (path relative to the workspace root).
    Bvh { path: String, units: BvhUnits },
}

/// Database section.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DbSpec {
    pub sources: Vec<Source>,
    #[serde(default)]
    pub params: DbParams,
    /// Split the clips into two halves with no edges between them (MG-7 test hook).
    #[serde(default)]
    pub partition_halves: bool,
}

/// A fixed problem (times in frames, angles in degrees).
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ProblemSpec {
    pub length: Option<u32>,
    /// `(time, x, z, yaw_deg)`.
    pub body: Vec<(u32, f64, f64, Option<f64>)>,
    /// `(time, role, (x, y, z))`.
    #[serde(default)]
    pub joints: Vec<(u32, JointRole, (f64, f64, f64))>,
    #[serde(default)]
    pub hard: Vec<HardSpec>,
}

/// A hard constraint in a scene file.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub enum HardSpec {
    Label(u32, String),
    /// `(time, clip, frame)`; a negative clip counts from the end of the database.
    Frame(u32, i64, u32),
}

/// Problems section.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub enum Problems {
    /// MG-1: start at the origin, 1–3 intermediate constraints and an end constraint at a
    /// distance `U(dist_frac)·speed·Δt` from the previous one (spec: ≤ 0.8 × 4 m/s × Δt), the
    /// direction turning by up to ±1 rad per segment; `count` per mode.
    Random {
        count: (usize, usize, usize),
        frames: u32,
        intermediate: (usize, usize),
        speed: f64,
        dist_frac: (f64, f64),
        seed: u64,
    },
    /// Fixed problems (several = independent characters).
    Fixed(Vec<ProblemSpec>),
}

/// Parameters of `motion-graph/search`.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Params {
    pub database: DbSpec,
    #[serde(default)]
    pub graph: GraphParams,
    pub problems: Problems,
    #[serde(default)]
    pub weights: Weights,
    #[serde(default)]
    pub search: SearchParams,
    /// Time budget per problem (s) per mode.
    pub time_budget_s: (f64, f64, f64),
    pub max_iters: usize,
    #[serde(default)]
    pub tolerance: Tolerance,
    pub smooth_window: u32,
    /// Stick-figure OBJ every n frames of problem 0 (0 = off).
    #[serde(default)]
    pub obj_every: usize,
    /// Report the distance between the first two characters at this frame (MG-5).
    #[serde(default)]
    pub pair_distance_at: Option<u32>,
    /// Cancel contact sliding by root translation before §3.11 (`motion_graph::fix_contacts`;
    /// default on).
    #[serde(default = "default_true")]
    pub contact_fix: bool,
}

fn default_true() -> bool {
    true
}

fn load_db(spec: &DbSpec, mode: Mode) -> Result<Database> {
    let mut clips = Vec::new();
    for s in &spec.sources {
        match s {
            Source::Synth { preset, clips: n, frames, seed } => {
                clips.extend(library(*preset, mode.pick(n.0, n.1, n.2), *frames, spec.params.rate_hz, *seed));
            }
            Source::Bvh { path, units } => {
                let p: PathBuf = workspace_root().join(path);
                let m = bvh::read_file(&p, &BvhOptions { units: *units, ..Default::default() })
                    .map_err(|e| Error::Run(format!("{}: {e}", p.display())))?;
                clips.push(m);
            }
        }
    }
    mg(Database::from_motions(clips, &spec.params))
}

/// CPU time (s) of the calling thread so far, from `/proc/thread-self/schedstat` (Linux; `None`
/// elsewhere). The search is single-threaded, so the difference over a search is its time on an
/// idle core: reported beside the wall-clock `search_s_*` because the machine is shared.
fn thread_cpu_s() -> Option<f64> {
    let s = std::fs::read_to_string("/proc/thread-self/schedstat").ok()?;
    let ns: f64 = s.split_whitespace().next()?.parse().ok()?;
    Some(ns * 1e-9)
}

fn fixed_problem(p: &ProblemSpec, g: &MotionGraph, w: Weights) -> Result<Problem> {
    let mut joints = Vec::new();
    for (t, r, (x, y, z)) in &p.joints {
        let j = g.db.skeleton.role(*r).ok_or_else(|| Error::Run(format!("skeleton has no {r:?}")))?;
        joints.push(JointConstraint { time: *t, joint: j, pos: Vec3::new(*x, *y, *z) });
    }
    let n = g.db.clips.len() as i64;
    let hard = p
        .hard
        .iter()
        .map(|h| match h {
            HardSpec::Label(t, l) => HardConstraint::Label { time: *t, label: l.clone() },
            HardSpec::Frame(t, c, f) => {
                let clip = if *c < 0 { (n + c).max(0) } else { (*c).min(n - 1) } as u32;
                HardConstraint::Frame { time: *t, frame: FrameRef { clip, frame: *f } }
            }
        })
        .collect();
    Ok(Problem {
        length: p.length,
        body: p
            .body
            .iter()
            .map(|(t, x, z, y)| BodyConstraint { time: *t, x: *x, z: *z, yaw: y.map(f64::to_radians) })
            .collect(),
        joints,
        hard,
        weights: w,
        ..Default::default()
    })
}

/// Runs a motion-graph scene.
pub fn run_search(ctx: &RunCtx) -> Result<Summary> {
    let p: Params = scene::load::<Params>(&ctx.scene_file)?.params;
    let mode = ctx.mode;
    let t_build = Instant::now();
    let db = load_db(&p.database, mode)?;
    let mut gp = p.graph.clone();
    if p.database.partition_halves {
        let n = db.clips.len();
        gp.partition = Some((0..n).map(|c| u32::from(c >= n / 2)).collect());
    }
    let g = mg(MotionGraph::build(db, &gp))?;
    let build_s = t_build.elapsed().as_secs_f64();
    let stats = g.stats();
    let clip_stats = ClipStats::of(&g);
    let problems: Vec<Problem> = match &p.problems {
        &Problems::Random { count, frames, intermediate, speed, dist_frac, seed } => random_mg1(
            mode.pick(count.0, count.1, count.2),
            frames,
            p.database.params.rate_hz,
            intermediate,
            speed,
            dist_frac,
            1.0,
            seed,
            p.weights,
        ),
        Problems::Fixed(list) => list.iter().map(|s| fixed_problem(s, &g, p.weights)).collect::<Result<_>>()?,
    };
    let budget = Duration::from_secs_f64(mode.pick(p.time_budget_s.0, p.time_budget_s.1, p.time_budget_s.2));
    let out = &ctx.out_dir;
    let mut csv = CsvWriter::create(
        &out.join("metrics.csv"),
        &[
            "problem",
            "status",
            "search_s",
            "iterations",
            "score",
            "pieces",
            "frames",
            "err_pos_max_before_m",
            "err_yaw_max_before_deg",
            "err_pos_max_after_m",
            "joint_err_max_m",
            "hard_met",
            "skate_cm_s",
            "jv_cut_p95_before",
            "jv_cut_p95_after",
            "mean_speed_m_s",
        ],
    )?;
    let mut cuts_csv = CsvWriter::create(
        &out.join("cuts.csv"),
        &["problem", "frame", "jv_before", "ja_before", "jv_after", "ja_after"],
    )?;
    let mut anytime = CsvWriter::create(&out.join("anytime.csv"), &["problem", "time_s", "iteration", "best_score"])?;
    let mut search_s = Vec::new();
    let mut err_before = Vec::new();
    let mut err_after = Vec::new();
    let mut jv_after = Vec::new();
    let mut skate = Vec::new();
    let mut skate_plain = Vec::new();
    let mut hard_total = 0usize;
    let mut hard_met = 0usize;
    let mut pieces = Vec::new();
    let mut joint_err = Vec::new();
    let mut reasons = Vec::new();
    let mut plot = LinePlot::new("top view: torso paths (x, z) and body constraints", "x (m)", "z (m)");
    let mut positions_at: Vec<Option<Vec3>> = Vec::new();
    let mut residual_max: f64 = 0.0;
    let mut speeds = Vec::new();
    let mut search_cpu_s = Vec::new();
    let mut repairs = 0usize;
    for (k, pb) in problems.iter().enumerate() {
        let t0 = Instant::now();
        let cpu0 = thread_cpu_s();
        let sp = SearchParams { rng_seed: p.search.rng_seed.wrapping_add(k as u64), ..p.search.clone() };
        let mut s = match Search::new(&g, pb.clone(), sp.clone()) {
            Ok(mut s) => {
                s.stop_when(Some(p.tolerance));
                s
            }
            Err(e) => {
                let why = e.to_string();
                csv.row(
                    &[Cell::Int(k as i64), Cell::Text(format!("failed: {why}"))]
                        .into_iter()
                        .chain((0..14).map(|_| Cell::Text(String::new())))
                        .collect::<Vec<_>>(),
                )?;
                reasons.push(why);
                hard_total += pb.hard.len();
                positions_at.push(None);
                continue;
            }
        };
        let mut met_at = None;
        let mut it = 0;
        while t0.elapsed() < budget && it < p.max_iters {
            if s.best().is_some_and(|b| p.tolerance.met(b)) {
                met_at.get_or_insert(t0.elapsed().as_secs_f64());
                break;
            }
            let r = s.step();
            it += 1;
            anytime.row(&[
                Cell::Int(k as i64),
                Cell::Num(t0.elapsed().as_secs_f64()),
                Cell::Int(r.iteration as i64),
                Cell::Num(r.best),
            ])?;
            if s.population().is_empty() {
                s.run_until(&p.tolerance, Duration::ZERO, 0);
                break;
            }
        }
        let st = met_at.unwrap_or(t0.elapsed().as_secs_f64());
        search_s.push(st);
        if let (Some(a), Some(b)) = (cpu0, thread_cpu_s()) {
            search_cpu_s.push(b - a);
        }
        repairs += s.repairs;
        let Some(best) = s.best().cloned() else { continue };
        let b0 = pb
            .body
            .iter()
            .find(|b| b.time == 0)
            .map_or(Planar::identity(), |b| Planar::new(b.x, b.z, b.yaw.unwrap_or(0.0)));
        let Some(mut a) = assemble(&g, &best.path, b0, sp.min_piece_frames) else { continue };
        let raw = evaluate(&g, &a, pb);
        smooth(&mut a, p.smooth_window);
        let before = evaluate(&g, &a, pb);
        // Mean horizontal root speed of the search result (before the correction of §3.11).
        let speed = {
            let m = &a.motion;
            let path_len: f64 = (1..m.len()).map(|f| (m.root_pos[f] - m.root_pos[f - 1]).xz().norm()).sum();
            path_len / m.duration().max(1e-9)
        };
        speeds.push(speed);
        // Skate without the contact fix, for comparison (same §3.11 correction).
        let mut plain = a.clone();
        enforce_body(&mut plain, &pb.body);
        skate_plain.push(evaluate(&g, &plain, pb).skate.rate_cm_s);
        if p.contact_fix {
            fix_contacts(&mut a);
        }
        enforce_body(&mut a, &pb.body);
        let after = evaluate(&g, &a, pb);
        for (i, b) in pb.body.iter().enumerate() {
            if b.time > 0 {
                err_before.push(before.body_pos[i]);
                err_after.push(after.body_pos[i]);
            }
        }
        residual_max = residual_max.max(before.body_pos.iter().copied().fold(0.0, f64::max));
        joint_err.extend(after.joint.iter().copied());
        hard_total += pb.hard.len();
        hard_met += after.hard_count_met;
        pieces.push(after.pieces as f64);
        skate.push(after.skate.rate_cm_s);
        let jvb: Vec<f64> = raw.cut_jumps.iter().map(|j| j.jv).collect();
        let jva: Vec<f64> = after.cut_jumps.iter().map(|j| j.jv).collect();
        jv_after.extend(jva.iter().copied());
        for (x, y) in raw.cut_jumps.iter().zip(&after.cut_jumps) {
            cuts_csv.row(&[
                Cell::Int(k as i64),
                Cell::Int(x.frame as i64),
                Cell::Num(x.jv),
                Cell::Num(x.ja),
                Cell::Num(y.jv),
                Cell::Num(y.ja),
            ])?;
        }
        let m = &a.motion;
        let n = m.len();
        csv.row(&[
            Cell::Int(k as i64),
            Cell::Text("ok".into()),
            Cell::Num(st),
            Cell::Int(s.iterations() as i64),
            Cell::Num(best.score),
            Cell::Int(after.pieces as i64),
            Cell::Int(n as i64),
            Cell::Num(before.body_pos.iter().copied().fold(0.0, f64::max)),
            Cell::Num(before.body_yaw_deg.iter().copied().fold(0.0, f64::max)),
            Cell::Num(after.body_pos.iter().copied().fold(0.0, f64::max)),
            Cell::Num(after.joint.iter().copied().fold(0.0, f64::max)),
            Cell::Int(i64::from(after.hard_met)),
            Cell::Num(after.skate.rate_cm_s),
            Cell::Num(percentile(&jvb, 95.0)),
            Cell::Num(percentile(&jva, 95.0)),
            Cell::Num(speed),
        ])?;
        let text = bvh::write(m, &BvhWriteOptions::default());
        let name = if k == 0 { "motion.bvh".to_string() } else { format!("problem_{k}.bvh") };
        std::fs::write(out.join(&name), text).map_err(crate::error::io_err(out.join(&name)))?;
        if k == 0 && p.obj_every > 0 {
            let dir = out.join("frames");
            crate::out::ensure_dir(&dir)?;
            for f in (0..n).step_by(p.obj_every) {
                let mesh = stick_figure(m, f, 0.02)?;
                obj::write(dir.join(format!("frame_{f:04}.obj")), &MeshOut::tri(&mesh.positions, &mesh.faces))?;
            }
        }
        let pts: Vec<(f64, f64)> = (0..n).map(|f| (m.root_pos[f].x, m.root_pos[f].z)).collect();
        plot = plot.with(Series::new(format!("problem {k}"), pts));
        let cons: Vec<(f64, f64)> = pb.body.iter().map(|b| (b.x, b.z)).collect();
        plot = plot.with(Series::new(format!("constraints {k}"), cons));
        positions_at.push(p.pair_distance_at.map(|t| m.root_pos[(t as usize).min(n - 1)]));
    }
    plot.write_png(&out.join("trajectory.png"))?;
    let mut sum = Summary::new();
    sum.set("build_s", build_s);
    sum.set_count("database_frames", stats.frames as u64);
    sum.set_count("leaf_edges", stats.leaf_edges as u64);
    sum.set_count("top_edges", stats.top_edges as u64);
    sum.set_count("graph_components", stats.components as u64);
    sum.set("tau", stats.tau);
    sum.set_count("problems", problems.len() as u64);
    sum.set_count("problems_solved", search_s.len() as u64);
    sum.set("search_s_median", percentile(&search_s, 50.0));
    sum.set("search_s_p90", percentile(&search_s, 90.0));
    // Mutation candidates whose hard constraints were repaired along the diagonal (§12.6).
    sum.set_count("mutation_repairs", repairs as u64);
    if search_cpu_s.len() == search_s.len() && !search_cpu_s.is_empty() {
        sum.set("search_cpu_s_median", percentile(&search_cpu_s, 50.0));
    }
    sum.set("constraint_err_m_p90_before", percentile(&err_before, 90.0));
    sum.set("constraint_err_m_p90_after", percentile(&err_after, 90.0));
    sum.set("residual_err_m_max", residual_max);
    sum.set("hard_constraints_met", if hard_total == 0 { 1.0 } else { hard_met as f64 / hard_total as f64 });
    let within = clip_stats.jumps.jv.p95;
    sum.set("within_clip_jv_p95", within);
    sum.set("splice_jv_p95", percentile(&jv_after, 95.0));
    sum.set(
        "splice_jv_p95_over_within_clip_p95",
        if within > 0.0 { percentile(&jv_after, 95.0) / within } else { 0.0 },
    );
    sum.set("foot_skate_cm_s", percentile(&skate, 50.0));
    sum.set("foot_skate_cm_s_max", skate.iter().copied().fold(0.0, f64::max));
    sum.set("foot_skate_cm_s_without_contact_fix", percentile(&skate_plain, 50.0));
    sum.set("source_skate_cm_s", clip_stats.skate.rate_cm_s);
    sum.set("pieces_median", percentile(&pieces, 50.0));
    sum.set("mean_speed_m_s", percentile(&speeds, 50.0));
    if !joint_err.is_empty() {
        sum.set("joint_err_m_max", joint_err.iter().copied().fold(0.0, f64::max));
    }
    if let (Some(Some(a)), Some(Some(b))) = (positions_at.first(), positions_at.get(1)) {
        sum.set("inter_character_distance_m", (a - b).xz().norm());
    }
    sum.set_str("reason", &if reasons.is_empty() { "ok".to_string() } else { reasons.join("; ") });
    Ok(sum)
}

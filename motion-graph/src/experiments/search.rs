//! The one experiment behind every motion-graph scene (spec §6.2, MG-1 … MG-8): build the
//! database and the graph, solve a list of problems (random reachable body constraints as in
//! MG-1, or fixed ones with hard label/frame and joint constraints) by the randomized search of
//! §3.7–§3.8 within a time budget, assemble, smooth (§3.10), cancel contact sliding, meet the body
//! constraints exactly (§3.11), and report the metrics of §3.12 ([`crate::metrics`]).
//!
//! Outputs through the recorder: tables `metrics` (one row per problem; failed problems say
//! `failed: <why>`), `cuts` (`J_v`, `J_a` at every cut before and after smoothing), `anytime`
//! (best score per iteration), the plot `trajectory` (top view of every result and its body
//! constraints), the files `motion.bvh` (problem 0) and `problem_<k>.bvh`, and stick-figure
//! frames of problem 0 every `obj_every` frames.
//!
//! The search stops at the tolerance, after `max_iters` iterations or at the wall-clock budget,
//! whichever comes first; a run is reproducible bit for bit when the budget never binds (the
//! `tiny` sizes of the scene files give a budget of 10⁹ s and a few iterations).
//!
//! ```no_run
//! use geom_core::experiment::Size;
//! use geom_core::record::NullRecorder;
//! use motion_graph::experiments::search::{run, Params};
//!
//! let text = std::fs::read_to_string("scenes/motion-graph/football.ron").unwrap();
//! #[derive(serde::Deserialize)]
//! struct Scene { params: Params }
//! let scene: Scene = ron::from_str(&text).unwrap();
//! let report = run(&scene.params, Size::Quick, &mut NullRecorder::default()).unwrap();
//! println!("p90 error before §3.11: {} m", report.get_f64("constraint_err_m_p90_before"));
//! ```

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use geom_core::anim::bvh::{self, BvhOptions, BvhUnits, BvhWriteOptions};
use geom_core::anim::metrics::{percentile, stick_figure};
use geom_core::anim::synth::{library, Preset};
use geom_core::anim::JointRole;
use geom_core::experiment::{BySize, Report, Size, Target};
use geom_core::math::{Planar, Vec3};
use geom_core::record::{Cell, MeshFrame, Recorder, Series};
use geom_core::stats;
use serde::Deserialize;

use crate::assemble::{assemble, enforce_body, evaluate, fix_contacts, smooth, ClipStats};
use crate::db::{Database, DbParams};
use crate::graph::{FrameRef, GraphParams, MotionGraph};
use crate::metrics::{mean_speed, ProblemFigures, ProblemOutcome, SceneFigures};
use crate::problem::{random_mg1, BodyConstraint, HardConstraint, JointConstraint, Problem, Weights};
use crate::search::{Search, SearchParams, Tolerance};
use crate::{Error, Result};
use geom_core::clock::thread_cpu_s;

/// Where clips come from.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub enum Source {
    /// A synthetic library (`geom_core::anim::synth`): clip count per size.
    Synth {
        /// Preset of §3.13.3.
        preset: Preset,
        /// Clips per size.
        clips: BySize<usize>,
        /// Clip length range (frames).
        frames: (usize, usize),
        /// Generator seed.
        seed: u64,
    },
    /// A BVH file (a relative path is resolved by [`Params::resolve_paths`]).
    Bvh {
        /// The file.
        path: String,
        /// Length unit of the file.
        units: BvhUnits,
    },
}

/// Database section.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DbSpec {
    /// The clips.
    pub sources: Vec<Source>,
    /// Preprocessing (§3.1).
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
    /// Requested length `F*` (frames).
    pub length: Option<u32>,
    /// `(time, x, z, yaw_deg)`.
    pub body: Vec<(u32, f64, f64, Option<f64>)>,
    /// `(time, role, (x, y, z))`.
    #[serde(default)]
    pub joints: Vec<(u32, JointRole, (f64, f64, f64))>,
    /// Hard constraints.
    #[serde(default)]
    pub hard: Vec<HardSpec>,
}

/// A hard constraint in a scene file.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub enum HardSpec {
    /// `(time, label)`.
    Label(u32, String),
    /// `(time, clip, frame)`; a negative clip counts from the end of the database.
    Frame(u32, i64, u32),
}

/// Problems section.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub enum Problems {
    /// MG-1 ([`random_mg1`]): start at the origin, 1–3 intermediate constraints and an end
    /// constraint at a distance `U(dist_frac)·speed·Δt` from the previous one (spec: ≤ 0.8 ×
    /// 4 m/s × Δt), the direction turning by up to ±1 rad per segment; `count` per size.
    Random {
        /// Problems per size.
        count: BySize<usize>,
        /// Length (frames).
        frames: u32,
        /// Intermediate constraints (range).
        intermediate: (usize, usize),
        /// Reference speed (m/s).
        speed: f64,
        /// Fraction of `speed · Δt` between consecutive constraints.
        dist_frac: (f64, f64),
        /// Generator seed.
        seed: u64,
    },
    /// Fixed problems (several = independent characters).
    Fixed(Vec<ProblemSpec>),
}

/// A paper check stated in a scene file: the figure `key` against a bound, and where the bound
/// comes from.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub enum CheckSpec {
    /// `key ≤ x`.
    AtMost(String, f64, String),
    /// `key ≥ x`.
    AtLeast(String, f64, String),
    /// `lo ≤ key ≤ hi`.
    Within(String, f64, f64, String),
}

/// Parameters of the experiment (the `params` block of a `motion-graph/search` scene).
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Params {
    /// The database.
    pub database: DbSpec,
    /// Graph construction (§3.3, §3.4).
    #[serde(default)]
    pub graph: GraphParams,
    /// The problems.
    pub problems: Problems,
    /// Score weights.
    #[serde(default)]
    pub weights: Weights,
    /// Search parameters (the seed of problem `k` is `rng_seed + k`).
    #[serde(default)]
    pub search: SearchParams,
    /// Wall-clock budget per problem (s).
    pub time_budget_s: BySize<f64>,
    /// Iteration cap per problem.
    pub max_iters: BySize<usize>,
    /// "Acceptable" result: the search stops once the best path meets it.
    #[serde(default)]
    pub tolerance: Tolerance,
    /// Smoothing half-width `W` (frames, §3.10).
    pub smooth_window: u32,
    /// Stick-figure frames every n frames of problem 0 (0 = off).
    #[serde(default)]
    pub obj_every: usize,
    /// Report the distance between the first two characters at this frame (MG-5).
    #[serde(default)]
    pub pair_distance_at: Option<u32>,
    /// Cancel contact sliding by root translation before §3.11 ([`fix_contacts`]; default on).
    #[serde(default = "default_true")]
    pub contact_fix: bool,
    /// Paper checks of this scene.
    #[serde(default)]
    pub checks: Vec<CheckSpec>,
}

fn default_true() -> bool {
    true
}

impl Params {
    /// Resolves relative BVH paths against `root` (the scene file's folder).
    pub fn resolve_paths(&mut self, root: &Path) {
        for s in &mut self.database.sources {
            if let Source::Bvh { path, .. } = s {
                if Path::new(path.as_str()).is_relative() {
                    *path = root.join(path.as_str()).to_string_lossy().into_owned();
                }
            }
        }
    }
}

/// Builds the database of `spec` at run size `size`.
pub fn load_db(spec: &DbSpec, size: Size) -> Result<Database> {
    let mut clips = Vec::new();
    for s in &spec.sources {
        match s {
            Source::Synth { preset, clips: n, frames, seed } => {
                clips.extend(library(*preset, n.get(size), *frames, spec.params.rate_hz, *seed));
            }
            Source::Bvh { path, units } => {
                let m = bvh::read_file(PathBuf::from(path), &BvhOptions { units: *units, ..Default::default() })
                    .map_err(|source| Error::File { path: path.clone(), source })?;
                clips.push(m);
            }
        }
    }
    Database::from_motions(clips, &spec.params)
}

/// The problem of a scene file's [`ProblemSpec`] on graph `g` (degrees → radians; roles →
/// joints; negative clip indices count from the end).
pub fn fixed_problem(p: &ProblemSpec, g: &MotionGraph, w: Weights) -> Result<Problem> {
    let mut joints = Vec::new();
    for (t, r, (x, y, z)) in &p.joints {
        let j = g.db.skeleton.role(*r).ok_or_else(|| Error::UnknownJoint(format!("{r:?}")))?;
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

/// Header of the `metrics` table.
const METRICS: [&str; 16] = [
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
];

/// Largest value of a per-problem error list, 0 when the problem has none of that kind (a table
/// cell, not a figure); a NaN stays NaN.
fn cell_max(v: &[f64]) -> f64 {
    v.iter().copied().fold(0.0, stats::nan_max)
}

/// Runs the scene: see the module documentation.
pub fn run(p: &Params, size: Size, rec: &mut dyn Recorder) -> Result<Report> {
    let t_build = Instant::now();
    let db = load_db(&p.database, size)?;
    let mut gp = p.graph.clone();
    if p.database.partition_halves {
        let n = db.clips.len();
        gp.partition = Some((0..n).map(|c| u32::from(c >= n / 2)).collect());
    }
    let g = MotionGraph::build(db, &gp)?;
    let build_s = t_build.elapsed().as_secs_f64();
    let stats = g.stats();
    let clip_stats = ClipStats::of(&g);
    let problems: Vec<Problem> = match &p.problems {
        Problems::Random { count, frames, intermediate, speed, dist_frac, seed } => random_mg1(
            count.get(size),
            *frames,
            p.database.params.rate_hz,
            *intermediate,
            *speed,
            *dist_frac,
            1.0,
            *seed,
            p.weights,
        ),
        Problems::Fixed(list) => list.iter().map(|s| fixed_problem(s, &g, p.weights)).collect::<Result<_>>()?,
    };
    let budget = Duration::from_secs_f64(p.time_budget_s.get(size));
    let max_iters = p.max_iters.get(size);
    rec.table("metrics", &METRICS)?;
    rec.table("cuts", &["problem", "frame", "jv_before", "ja_before", "jv_after", "ja_after"])?;
    rec.table("anytime", &["problem", "time_s", "iteration", "best_score"])?;
    let mut outcomes = Vec::with_capacity(problems.len());
    let mut positions_at: Vec<Option<Vec3>> = Vec::new();
    let mut repairs = 0usize;
    for (k, pb) in problems.iter().enumerate() {
        rec.progress(k as u64, problems.len() as u64);
        let (outcome, pos) = solve_one(p, &g, pb, k, budget, max_iters, rec, &mut repairs)?;
        if let ProblemOutcome::Failed { reason, .. } = &outcome {
            let mut row = vec![Cell::Int(k as i64), Cell::Text(format!("failed: {reason}"))];
            row.extend((0..METRICS.len() - 2).map(|_| Cell::Text(String::new())));
            rec.row("metrics", &row)?;
        }
        outcomes.push(outcome);
        positions_at.push(pos);
    }
    rec.progress(problems.len() as u64, problems.len() as u64);
    let figs = SceneFigures::of(&outcomes, &problems);
    let mut r = Report::default();
    figs.report(&mut r, build_s, &stats, &clip_stats);
    // Mutation candidates whose hard constraints were repaired along the diagonal (§12.6).
    r.count("mutation_repairs", repairs as u64);
    if let (Some(Some(a)), Some(Some(b))) = (positions_at.first(), positions_at.get(1)) {
        r.num("inter_character_distance_m", (a - b).xz().norm());
    }
    for c in &p.checks {
        match c {
            CheckSpec::AtMost(k, x, s) => r.check(k, Target::AtMost(*x), s),
            CheckSpec::AtLeast(k, x, s) => r.check(k, Target::AtLeast(*x), s),
            CheckSpec::Within(k, lo, hi, s) => r.check(k, Target::Within(*lo, *hi), s),
        };
    }
    Ok(r)
}

/// Solves problem `k`: search (tolerance, iteration cap, budget), assembly, smoothing, contact
/// fix, §3.11, metrics; records its rows, BVH, frames and plot series. Returns the outcome and
/// the root position at `pair_distance_at` (MG-5).
#[allow(clippy::too_many_arguments)]
fn solve_one(
    p: &Params,
    g: &MotionGraph,
    pb: &Problem,
    k: usize,
    budget: Duration,
    max_iters: usize,
    rec: &mut dyn Recorder,
    repairs: &mut usize,
) -> Result<(ProblemOutcome, Option<Vec3>)> {
    let t0 = Instant::now();
    let cpu0 = thread_cpu_s();
    let sp = SearchParams { rng_seed: p.search.rng_seed.wrapping_add(k as u64), ..p.search.clone() };
    let mut s = match Search::new(g, pb.clone(), sp.clone()) {
        Ok(mut s) => {
            s.stop_when(Some(p.tolerance));
            s
        }
        Err(e) => {
            let failed = ProblemOutcome::Failed { reason: e.to_string(), hard: pb.hard.len(), search: None };
            return Ok((failed, None));
        }
    };
    let mut met_at = None;
    let mut it = 0;
    while t0.elapsed() < budget && it < max_iters {
        if s.best().is_some_and(|b| p.tolerance.met(b)) {
            met_at.get_or_insert(t0.elapsed().as_secs_f64());
            break;
        }
        let r = s.step();
        it += 1;
        rec.row(
            "anytime",
            &[
                Cell::Int(k as i64),
                Cell::Num(t0.elapsed().as_secs_f64()),
                Cell::Int(r.iteration as i64),
                Cell::Num(r.best),
            ],
        )?;
        if s.population().is_empty() {
            s.run_until(&p.tolerance, Duration::ZERO, 0);
            break;
        }
    }
    let search_s = met_at.unwrap_or(t0.elapsed().as_secs_f64());
    // None where the thread clock cannot be read (NaN readings).
    let search_cpu_s = Some(thread_cpu_s() - cpu0).filter(|c| c.is_finite());
    *repairs += s.repairs;
    let fail = |why: &str| ProblemOutcome::Failed {
        reason: format!("problem {k}: {why}"),
        hard: pb.hard.len(),
        search: Some((search_s, search_cpu_s)),
    };
    let Some(best) = s.best().cloned() else { return Ok((fail("the search found no path"), None)) };
    let b0 = pb
        .body
        .iter()
        .find(|b| b.time == 0)
        .map_or(Planar::identity(), |b| Planar::new(b.x, b.z, b.yaw.unwrap_or(0.0)));
    let Some(mut a) = assemble(g, &best.path, b0, sp.min_piece_frames) else {
        return Ok((fail("the best path cannot be assembled"), None));
    };
    let raw = evaluate(g, &a, pb);
    smooth(&mut a, p.smooth_window);
    let before = evaluate(g, &a, pb);
    // Mean horizontal root speed of the search result (before the correction of §3.11).
    let speed = mean_speed(&a.motion);
    // Skate without the contact fix, for comparison (same §3.11 correction).
    let mut plain = a.clone();
    enforce_body(&mut plain, &pb.body);
    let skate_plain = evaluate(g, &plain, pb).skate.rate_cm_s;
    if p.contact_fix {
        fix_contacts(&mut a);
    }
    enforce_body(&mut a, &pb.body);
    let after = evaluate(g, &a, pb);
    let jvb: Vec<f64> = raw.cut_jumps.iter().map(|j| j.jv).collect();
    let jva: Vec<f64> = after.cut_jumps.iter().map(|j| j.jv).collect();
    for (x, y) in raw.cut_jumps.iter().zip(&after.cut_jumps) {
        rec.row(
            "cuts",
            &[
                Cell::Int(k as i64),
                Cell::Int(x.frame as i64),
                Cell::Num(x.jv),
                Cell::Num(x.ja),
                Cell::Num(y.jv),
                Cell::Num(y.ja),
            ],
        )?;
    }
    let m = &a.motion;
    let n = m.len();
    rec.row(
        "metrics",
        &[
            Cell::Int(k as i64),
            Cell::Text("ok".into()),
            Cell::Num(search_s),
            Cell::Int(s.iterations() as i64),
            Cell::Num(best.score),
            Cell::Int(after.pieces as i64),
            Cell::Int(n as i64),
            Cell::Num(cell_max(&before.body_pos)),
            Cell::Num(cell_max(&before.body_yaw_deg)),
            Cell::Num(cell_max(&after.body_pos)),
            Cell::Num(cell_max(&after.joint)),
            Cell::Int(i64::from(after.hard_met)),
            Cell::Num(after.skate.rate_cm_s),
            Cell::Num(percentile(&jvb, 95.0)),
            Cell::Num(percentile(&jva, 95.0)),
            Cell::Num(speed),
        ],
    )?;
    let name = if k == 0 { "motion.bvh".to_string() } else { format!("problem_{k}.bvh") };
    if rec.keeps_outputs() {
        rec.file(&name, bvh::write(m, &BvhWriteOptions::default()).as_bytes())?;
    }
    if k == 0 && p.obj_every > 0 {
        for f in (0..n).step_by(p.obj_every) {
            let mesh = stick_figure(m, f, 0.02)?;
            rec.frame(&MeshFrame {
                sequence: "frames",
                index: f,
                time: f as f64 * m.frame_time,
                positions: &mesh.positions,
                faces: &mesh.faces,
                attributes: &[],
            })?;
        }
    }
    let axes = ("x (m)".to_string(), "z (m)".to_string());
    rec.series(&Series {
        plot: "trajectory".into(),
        label: format!("problem {k}"),
        axes: axes.clone(),
        log: (false, false),
        points: (0..n).map(|f| (m.root_pos[f].x, m.root_pos[f].z)).collect(),
    })?;
    rec.series(&Series {
        plot: "trajectory".into(),
        label: format!("constraints {k}"),
        axes,
        log: (false, false),
        points: pb.body.iter().map(|b| (b.x, b.z)).collect(),
    })?;
    let pos = p.pair_distance_at.map(|t| m.root_pos[(t as usize).min(n - 1)]);
    let figs = ProblemFigures {
        search_s,
        search_cpu_s,
        raw,
        before,
        after,
        skate_without_contact_fix: skate_plain,
        mean_speed_m_s: speed,
    };
    Ok((ProblemOutcome::Solved(Box::new(figs)), pos))
}

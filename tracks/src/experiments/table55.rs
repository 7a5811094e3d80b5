//! `tracks/table55` (Bergou et al. 2007 §5.5, the timing table): the flag, the box, the bag and
//! Xavier, each tracked and untracked in lockstep (best of `repeats`), with the paper's columns
//! beside ours; then, per scene, one tracked run whose every system is also solved by each
//! method of `compare` and by an unused LLᵀ of A (the untracked factorisation), all timed on
//! identical matrices (spec §3.6).
//!
//! Keys: `overhead_pct_{flag,box,bag,xavier}`, `s_per_frame_{tracked,untracked}_<scene>`,
//! `kkt_over_untracked_factor_<scene>` (median over steps of the tracked step's constrained
//! solve time over the median untracked factorisation + solve of A, issue 20),
//! `max_residual_pre` (worst of the four), `duration_s`, `repeats`, `threads`, `kkt`; from the
//! comparison: `kkt_ms_<scene>_<method>`, `llt_ms_<scene>`, `solve_overhead_pct_<scene>`
//! (100·(t_kkt − t_LLᵀ(A)) / untracked step time of the main run). Tables `table55`,
//! `kkt_methods`; the markdown table as notes.
//!
//! ```no_run
//! use geom_core::experiment::Size;
//! use geom_core::record::NullRecorder;
//! let text = std::fs::read_to_string("scenes/tracks/table55.ron").unwrap();
//! #[derive(serde::Deserialize)]
//! struct File { params: tracks::experiments::table55::Params }
//! let f: File = ron::from_str(&text).unwrap();
//! let r = tracks::experiments::table55::run(&f.params, Size::Quick, &mut NullRecorder::default()).unwrap();
//! println!("{:?}", r.get("overhead_pct_xavier"));
//! ```

use geom_core::experiment::{BySize, Report, Size, Target};
use geom_core::record::{Cell, Recorder};
use serde::Deserialize;
use shells::ContactMethod;

use super::flag::preview_duration;
use super::protocol::{run_pair, track_opts, PairOpts, PairOut};
use super::xavier::XAVIER_REGIONS;
use crate::error::Result;
use crate::kkt::KktMethod;
use crate::presets::{
    bag_setup, box_setup, flag_design, flag_setup, frames_for, xavier_setup, xavier_tf, Setup, ShellOptions,
    XAVIER_DURATION,
};
use crate::procedural::{xavier, xavier_guide};
use crate::tracker::TrackOptions;

/// Parameters of `tracks/table55` (the RON `params` block).
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Params {
    /// Simulated time per scene (s).
    pub duration: BySize<f64>,
    /// Repetitions (the faster is kept).
    pub repeats: BySize<usize>,
    /// Cloth–cloth collisions on/off.
    pub self_collision: BySize<bool>,
    /// Saddle-point solver per scene: (flag, box, bag, xavier).
    pub kkt: (KktMethod, KktMethod, KktMethod, KktMethod),
    /// Iterative refinement steps after the LDLᵀ solve.
    pub refine_steps: u32,
    /// Methods timed against each other on identical systems in one extra tracked run per
    /// scene (with the shadow LLᵀ of A for the solve-overhead column); empty = skip that run.
    pub compare: Vec<KktMethod>,
    /// Simulated time of that run (s).
    pub compare_duration: BySize<f64>,
    /// The contact model of the fine shells (default IPC).
    #[serde(default)]
    pub contact: ContactMethod,
}

/// One row of the table: the scene, its setup, the paper's overhead (%) and the paper's
/// (s/frame tracked, s/frame untracked, constraints).
struct Row {
    name: &'static str,
    setup: Setup,
    paper_overhead: f64,
    paper: [f64; 3],
}

/// Short snake-case key of a KKT method for summary keys.
pub fn method_key(m: &KktMethod) -> &'static str {
    match m {
        KktMethod::ConstraintLastLdlt => "constraint_last",
        KktMethod::InterleavedLdlt => "interleaved",
        KktMethod::AmdRegularizedLdlt { .. } => "amd_regularized",
        KktMethod::Schur => "schur",
        KktMethod::SchurPcg { .. } => "schur_pcg",
        KktMethod::Penalty { .. } => "penalty",
        KktMethod::Compliant { .. } => "compliant",
        KktMethod::AugmentedLagrangian { .. } => "augmented_lagrangian",
    }
}

/// The four scenes: 4 steps per frame, the bag 6 (its scene's setting).
fn rows(size: Size, self_collision: bool, contact: ContactMethod) -> Result<Vec<Row>> {
    let shell = &ShellOptions { substeps: 4, self_collision, contact };
    let design = flag_design(preview_duration(size), contact)?;
    let x = xavier()?;
    let xg = xavier_guide(&x, XAVIER_DURATION)?;
    let (xtf, _) = xavier_tf(&x, &xg, XAVIER_REGIONS.0, XAVIER_REGIONS.1)?;
    Ok(vec![
        Row { name: "flag", setup: flag_setup(&design, shell)?, paper_overhead: 4.1, paper: [17.7, 17.0, 4.0] },
        Row { name: "box", setup: box_setup(shell)?, paper_overhead: 6.0, paper: [15.8, 14.9, 8.0] },
        Row {
            name: "bag",
            setup: bag_setup(&ShellOptions { substeps: 6, ..*shell })?,
            paper_overhead: 2.5,
            paper: [16.1, 15.7, 88.0],
        },
        Row {
            name: "xavier",
            setup: xavier_setup(&x, &xg, xtf, shell),
            paper_overhead: 10.8,
            paper: [43.2, 39.0, 280.0],
        },
    ])
}

/// Runs the table.
pub fn run(p: &Params, size: Size, rec: &mut dyn Recorder) -> Result<Report> {
    let dur = p.duration.get(size);
    let reps = p.repeats.get(size).max(1);
    let sc = p.self_collision.get(size);
    let scenes = rows(size, sc, p.contact)?;
    rec.table(
        "table55",
        &[
            "scene",
            "guide_verts",
            "tracked_verts",
            "constraints",
            "paper_constraints",
            "dof_increase_pct",
            "s_per_frame_tracked",
            "s_per_frame_untracked",
            "overhead_pct",
            "paper_s_per_frame_tracked",
            "paper_s_per_frame_untracked",
            "paper_overhead_pct",
            "solve_s_per_step",
            "max_r_pre_over_L",
            "mean_dc",
            "kkt",
        ],
    )?;
    let mut r = Report::default();
    let mut worst_pre = 0.0f64;
    let mut md = String::from(
        "# TRACKS §5.5 table: ours beside the paper\n\n| scene | constraints | s/frame tracked (untracked) | overhead % | paper s/frame | paper overhead % |\n|---|---|---|---|---|---|\n",
    );
    // Per scene: its KKT method and the untracked ms per step of the kept run.
    let mut main_runs: Vec<(KktMethod, f64)> = Vec::new();
    for row in &scenes {
        let (name, setup, paper) = (row.name, &row.setup, row.paper);
        let kkt = match name {
            "flag" => p.kkt.0,
            "box" => p.kkt.1,
            "bag" => p.kkt.2,
            _ => p.kkt.3,
        };
        let mut best: Option<PairOut> = None;
        for rep in 0..reps {
            let o = PairOpts {
                frames: frames_for(dur, setup.fps),
                obj_every: 0,
                untracked: true,
                track: track_opts(kkt, p.refine_steps),
                intersections: false,
                anchors: None,
                tag: format!("_{name}_{rep}"),
                subsets: Vec::new(),
            };
            let out = run_pair(setup, &o, rec)?;
            worst_pre = geom_core::stats::nan_max(worst_pre, out.r_pre());
            if best.as_ref().is_none_or(|b| out.t_tracked + out.t_untracked < b.t_tracked + b.t_untracked) {
                best = Some(out);
            }
        }
        let b = best.expect("reps ≥ 1: at least one repetition ran");
        main_runs.push((kkt, 1e3 * b.t_untracked / b.steps.max(1) as f64));
        let n = setup.tracked_rest.n_vertices();
        r.timing(&format!("overhead_pct_{name}"), b.overhead_pct());
        r.timing(&format!("kkt_over_untracked_factor_{name}"), b.kkt_over_untracked_factor());
        r.timing(
            &format!("kkt_over_untracked_factor_per_iteration_{name}"),
            b.kkt_over_untracked_factor_per_iteration(),
        );
        let (it_t, it_u) = b.newton_iters_per_step();
        r.num(&format!("newton_iters_per_step_tracked_{name}"), it_t);
        r.num(&format!("newton_iters_per_step_untracked_{name}"), it_u);
        r.timing(&format!("s_per_frame_tracked_{name}"), b.s_per_frame_tracked());
        r.timing(&format!("s_per_frame_untracked_{name}"), b.s_per_frame_untracked());
        rec.row(
            "table55",
            &[
                Cell::from(name),
                Cell::from(setup.guide.n_vertices()),
                Cell::from(n),
                Cell::from(b.k),
                Cell::from(paper[2]),
                Cell::from(100.0 * b.k as f64 / n as f64),
                Cell::from(b.s_per_frame_tracked()),
                Cell::from(b.s_per_frame_untracked()),
                Cell::from(b.overhead_pct()),
                Cell::from(paper[0]),
                Cell::from(paper[1]),
                Cell::from(row.paper_overhead),
                Cell::from(b.solve_s_per_step()),
                Cell::from(b.r_pre()),
                Cell::from(geom_core::stats::mean(&b.dc_tracked)),
                Cell::from(format!("{kkt:?}")),
            ],
        )?;
        md.push_str(&format!(
            "| {name} | {} | {:.3} ({:.3}) | {:.1} | {} ({}) | {} |\n",
            b.k,
            b.s_per_frame_tracked(),
            b.s_per_frame_untracked(),
            b.overhead_pct(),
            paper[0],
            paper[1],
            row.paper_overhead
        ));
    }
    r.num("max_residual_pre", worst_pre);
    r.num("duration_s", dur);
    r.count("repeats", reps as u64);
    r.count("threads", rayon::current_num_threads() as u64);
    r.timing.push("threads".into());
    r.text("kkt", &format!("{:?}", p.kkt));
    if !p.compare.is_empty() {
        compare_methods(p, size, &scenes, &main_runs, &mut r, &mut md, rec)?;
    }
    r.text("mode", size.name());
    // Issue 20's targets: the flag's and the box's overhead ≤ 15 %; on the bag and Xavier the
    // exact constrained step costs more than the untracked factorisation (≈ 1.47× on Xavier
    // against every exact ordering tried), so their target is that ratio, ≤ 1.8.
    for name in ["flag", "box"] {
        let src = "Bergou et al. 2007 §5.5 (tracking costs a few percent); issue 20: overhead ≤ 15 %";
        r.check(&format!("overhead_pct_{name}"), Target::AtMost(15.0), src);
    }
    for name in ["bag", "xavier"] {
        let src = "issue 20: median constrained solve ≤ 1.8× the untracked factorisation + solve";
        r.check(&format!("kkt_over_untracked_factor_{name}"), Target::AtMost(1.8), src);
    }
    super::protocol::check_residual(&mut r, "max_residual_pre");
    md.push_str(&format!(
        "\nMode {}, {dur} s per scene, best of {reps}, self-collision {sc}, {} threads, profile as built.",
        size.name(),
        rayon::current_num_threads()
    ));
    rec.note(&md)?;
    Ok(r)
}

/// The spec §6.9 shadow-timed run, extended: per scene one tracked run whose every system is
/// also solved by each method of `p.compare` and by an unused LLᵀ of A, all timed on identical
/// matrices; table `kkt_methods` and a report section.
fn compare_methods(
    p: &Params,
    size: Size,
    scenes: &[Row],
    main_runs: &[(KktMethod, f64)],
    r: &mut Report,
    md: &mut String,
    rec: &mut dyn Recorder,
) -> Result<()> {
    let dur = p.compare_duration.get(size);
    rec.table(
        "kkt_methods",
        &["scene", "method", "ms_per_step", "ms_llt_of_a_per_step", "solve_overhead_pct", "max_rel_diff", "nnz_l"],
    )?;
    md.push_str(&format!(
        "\n## KKT methods on identical systems ({dur} s per scene, ms per step; LLᵀ of A = the untracked factorisation)\n\n| scene | LLᵀ of A | {} |\n|---|---|{}\n",
        p.compare.iter().map(|m| format!("{m:?}")).collect::<Vec<_>>().join(" | "),
        "---|".repeat(p.compare.len())
    ));
    for (row, (main_kkt, untracked_ms)) in scenes.iter().zip(main_runs) {
        let (name, setup) = (row.name, &row.setup);
        let o = PairOpts {
            frames: frames_for(dur, setup.fps),
            obj_every: 0,
            untracked: false,
            track: TrackOptions {
                kkt: p.compare[0],
                refine_steps: p.refine_steps,
                shadow_timing: true,
                compare: p.compare.clone(),
                ..TrackOptions::default()
            },
            intersections: false,
            anchors: None,
            tag: format!("_{name}_methods"),
            subsets: Vec::new(),
        };
        let out = run_pair(setup, &o, rec)?;
        let steps = out.steps.max(1) as f64;
        let llt_ms = 1e3 * out.t_shadow / steps;
        let mut cells = Vec::new();
        for (m, c) in p.compare.iter().zip(&out.compare) {
            let ms = 1e3 * c.0 / steps;
            rec.row(
                "kkt_methods",
                &[
                    Cell::from(name),
                    Cell::from(format!("{m:?}")),
                    Cell::from(ms),
                    Cell::from(llt_ms),
                    Cell::from(100.0 * (ms - llt_ms) / llt_ms.max(1e-300)),
                    Cell::from(c.1),
                    Cell::from(c.2),
                ],
            )?;
            r.timing(&format!("kkt_ms_{name}_{}", method_key(m)), ms);
            cells.push(format!("{ms:.2}"));
        }
        r.timing(&format!("llt_ms_{name}"), llt_ms);
        // Spec §3.8 solve overhead of the scene's method: (t_kkt − t_LLᵀ(A)) / untracked step,
        // both solves timed on the same matrices in this run.
        if let Some(c) = p.compare.iter().position(|m| m == main_kkt).map(|i| out.compare[i]) {
            r.timing(&format!("solve_overhead_pct_{name}"), 100.0 * (1e3 * c.0 / steps - llt_ms) / untracked_ms);
        }
        md.push_str(&format!("| {name} | {llt_ms:.2} | {} |\n", cells.join(" | ")));
    }
    Ok(())
}

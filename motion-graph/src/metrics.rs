//! Every figure a motion-graph scene reports (spec §3.12, §6.2), computed from the per-problem
//! results of a run: constraint errors before and after the exact correction of §3.11, hard
//! constraints met, splice jumps against the within-clip reference, foot skate, pieces, speeds,
//! and the search times.
//!
//! Failed problems (no seed path, no assemblable best path) are **counted as failed**: they add
//! their hard constraints as unmet, their reason to [`SceneFigures::reason`], and nothing to the
//! error samples. Statistics of an empty sample are NaN (`geom_core::stats`), so a run in which
//! no problem was solved reports `null` errors, never 0 m (issue 21).

use geom_core::anim::Motion;
use geom_core::experiment::Report;
use geom_core::stats::{max, percentile};

use crate::assemble::{ClipStats, Metrics};
use crate::graph::GraphStats;
use crate::problem::Problem;

/// What one solved problem measured (spec §3.12).
#[derive(Clone, Debug, Default)]
pub struct ProblemFigures {
    /// Wall time to the tolerance or the budget (s).
    pub search_s: f64,
    /// CPU time of the search thread (s), when the platform reports it.
    pub search_cpu_s: Option<f64>,
    /// Metrics of the raw assembled motion (before smoothing).
    pub raw: Metrics,
    /// After smoothing, before the correction of §3.11.
    pub before: Metrics,
    /// After the contact fix (if on) and the correction of §3.11.
    pub after: Metrics,
    /// Foot skate after §3.11 without the contact fix (cm/s).
    pub skate_without_contact_fix: f64,
    /// Mean horizontal root speed of the smoothed search result (m/s).
    pub mean_speed_m_s: f64,
}

/// The outcome of one problem of a scene.
#[derive(Clone, Debug)]
pub enum ProblemOutcome {
    /// Solved: a best path was found and assembled.
    Solved(Box<ProblemFigures>),
    /// Failed, with the reason and the number of hard constraints it asked for.
    Failed {
        /// Why (the search error, or "no assemblable path").
        reason: String,
        /// Hard constraints of the problem (all counted as unmet).
        hard: usize,
        /// Search wall and CPU time spent before failing (s), if a search ran.
        search: Option<(f64, Option<f64>)>,
    },
}

/// Mean horizontal root speed of `m` (m/s): path length in the floor plane over its duration.
pub fn mean_speed(m: &Motion) -> f64 {
    let path_len: f64 = (1..m.len()).map(|f| (m.root_pos[f] - m.root_pos[f - 1]).xz().norm()).sum();
    path_len / m.duration().max(1e-9)
}

/// The figures of a scene (the keys of `summary.json`).
#[derive(Clone, Debug)]
pub struct SceneFigures {
    /// Problems posed.
    pub problems: usize,
    /// Problems solved (a best path found and assembled).
    pub solved: usize,
    /// `"ok"`, or the failures joined by `"; "`.
    pub reason: String,
    /// Search wall times of every problem a search ran for (s).
    pub search_s: Vec<f64>,
    /// Search CPU times, one per entry of `search_s` when every search reported one.
    pub search_cpu_s: Option<Vec<f64>>,
    /// Position errors of the non-initial body constraints before §3.11 (m).
    pub err_before: Vec<f64>,
    /// The same after §3.11 (m).
    pub err_after: Vec<f64>,
    /// Every body constraint error before §3.11, the time-0 one included (m).
    pub residual: Vec<f64>,
    /// Joint constraint errors after §3.11 (m).
    pub joint_err: Vec<f64>,
    /// Hard constraints asked for / met.
    pub hard_total: usize,
    /// Hard constraints met.
    pub hard_met: usize,
    /// `J_v` at every cut after smoothing and §3.11 (m/s).
    pub jv_after: Vec<f64>,
    /// Foot skate per solved problem (cm/s).
    pub skate: Vec<f64>,
    /// Foot skate per solved problem without the contact fix (cm/s).
    pub skate_plain: Vec<f64>,
    /// Pieces per solved problem.
    pub pieces: Vec<f64>,
    /// Mean speed per solved problem (m/s).
    pub speeds: Vec<f64>,
}

impl SceneFigures {
    /// Gathers the outcomes of every problem of a scene (`outcomes[k]` is the outcome of
    /// `problems[k]`).
    pub fn of(outcomes: &[ProblemOutcome], problems: &[Problem]) -> SceneFigures {
        let mut f = SceneFigures {
            problems: outcomes.len(),
            solved: 0,
            reason: String::new(),
            search_s: vec![],
            search_cpu_s: Some(vec![]),
            err_before: vec![],
            err_after: vec![],
            residual: vec![],
            joint_err: vec![],
            hard_total: 0,
            hard_met: 0,
            jv_after: vec![],
            skate: vec![],
            skate_plain: vec![],
            pieces: vec![],
            speeds: vec![],
        };
        let mut reasons = Vec::new();
        for (o, pb) in outcomes.iter().zip(problems) {
            match o {
                ProblemOutcome::Failed { reason, hard, search } => {
                    reasons.push(reason.clone());
                    f.hard_total += hard;
                    if let Some((s, cpu)) = search {
                        f.push_time(*s, *cpu);
                    }
                }
                ProblemOutcome::Solved(p) => {
                    f.solved += 1;
                    f.push_time(p.search_s, p.search_cpu_s);
                    for (i, b) in pb.body.iter().enumerate() {
                        if b.time > 0 {
                            f.err_before.push(p.before.body_pos[i]);
                            f.err_after.push(p.after.body_pos[i]);
                        }
                    }
                    f.residual.extend(p.before.body_pos.iter().copied());
                    f.joint_err.extend(p.after.joint.iter().copied());
                    f.hard_total += pb.hard.len();
                    f.hard_met += p.after.hard_count_met;
                    f.pieces.push(p.after.pieces as f64);
                    f.skate.push(p.after.skate.rate_cm_s);
                    f.skate_plain.push(p.skate_without_contact_fix);
                    f.jv_after.extend(p.after.cut_jumps.iter().map(|j| j.jv));
                    f.speeds.push(p.mean_speed_m_s);
                }
            }
        }
        f.reason = if reasons.is_empty() { "ok".to_string() } else { reasons.join("; ") };
        f
    }

    fn push_time(&mut self, wall: f64, cpu: Option<f64>) {
        self.search_s.push(wall);
        match (&mut self.search_cpu_s, cpu) {
            (Some(v), Some(c)) => v.push(c),
            (v, _) => *v = None,
        }
    }

    /// Writes the figures into `r` (keys of spec §6.2 and the crate README): graph sizes and τ,
    /// search times (timing), errors before/after §3.11, hard constraints met, splice jumps over
    /// the within-clip p95, skate, pieces, speeds, and the reason.
    pub fn report(&self, r: &mut Report, build_s: f64, stats: &GraphStats, clips: &ClipStats) {
        r.timing("build_s", build_s);
        r.count("database_frames", stats.frames as u64);
        r.count("leaf_edges", stats.leaf_edges as u64);
        r.count("top_edges", stats.top_edges as u64);
        r.count("graph_components", stats.components as u64);
        r.num("tau", stats.tau);
        r.count("problems", self.problems as u64);
        r.count("problems_solved", self.solved as u64);
        r.timing("search_s_median", percentile(&self.search_s, 50.0));
        r.timing("search_s_p90", percentile(&self.search_s, 90.0));
        if let Some(cpu) = self.search_cpu_s.as_ref().filter(|c| !c.is_empty()) {
            r.timing("search_cpu_s_median", percentile(cpu, 50.0));
        }
        r.num("constraint_err_m_p90_before", percentile(&self.err_before, 90.0));
        r.num("constraint_err_m_p90_after", percentile(&self.err_after, 90.0));
        r.num("residual_err_m_max", max(&self.residual));
        r.num(
            "hard_constraints_met",
            if self.hard_total == 0 { 1.0 } else { self.hard_met as f64 / self.hard_total as f64 },
        );
        let within = clips.jumps.jv.p95;
        let splice = percentile(&self.jv_after, 95.0);
        r.num("within_clip_jv_p95", within);
        r.num("splice_jv_p95", splice);
        r.num("splice_jv_p95_over_within_clip_p95", if within > 0.0 { splice / within } else { f64::NAN });
        r.num("foot_skate_cm_s", percentile(&self.skate, 50.0));
        r.num("foot_skate_cm_s_max", max(&self.skate));
        r.num("foot_skate_cm_s_without_contact_fix", percentile(&self.skate_plain, 50.0));
        r.num("source_skate_cm_s", clips.skate.rate_cm_s);
        r.num("pieces_median", percentile(&self.pieces, 50.0));
        r.num("mean_speed_m_s", percentile(&self.speeds, 50.0));
        if !self.joint_err.is_empty() {
            r.num("joint_err_m_max", max(&self.joint_err));
        }
        r.text("reason", &self.reason);
    }
}

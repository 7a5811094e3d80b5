//! The run protocol every tracking experiment shares ([`run_pair`]): the tracked simulation and
//! its untracked twin (the same shell description, `tracking: None`) stepped **in lockstep**, step
//! by step in the same process, so both see the same machine load; every step is timed, its
//! residuals before and after the collision pass recorded, and the per-frame figures (coarse
//! deviation D_c, detail amplitude a_d, wavelength λ_eff, bending energy, tug index,
//! intersections) are computed outside the timed region.
//!
//! Outputs (through the [`Recorder`]): tables `steps<tag>` and `frames<tag>`, mesh sequences
//! `tracked<tag>`, `guide<tag>` and `untracked<tag>` (every `obj_every` frames, indexed by frame).

use std::time::Instant;

use geom_core::experiment::{BySize, Report, Size};
use geom_core::math::{Pt3, Vec3};
use geom_core::record::{Cell, MeshFrame, Recorder, SceneItem, Series};
use serde::Deserialize;
use shells::metrics::Sanity;
use shells::{ContactMethod, ShellSim};

use crate::error::Result;
use crate::kkt::KktMethod;
use crate::metrics::{
    centroid, guide_on_tracked, hinge_energies, kkt_over_untracked_factor, mean_speed, overhead_pct,
    overhead_pct_median, tug_index, vertex_mask, LowPass,
};
use crate::presets::{frames_for, Setup, ShellOptions};
use crate::tracker::{TrackOptions, Tracker};

/// The parameters of the single-scene experiments `tracks/flag`, `box`, `bag`, `xavier` (the
/// RON `params` block; also the `run` block of the variant scenes).
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PairParams {
    /// Simulated time (s).
    pub duration: BySize<f64>,
    /// Steps per frame.
    pub substeps: BySize<u32>,
    /// Cloth–cloth collisions on/off.
    pub self_collision: BySize<bool>,
    /// Saddle-point solver.
    pub kkt: KktMethod,
    /// Iterative refinement steps after the LDLᵀ solve.
    pub refine_steps: u32,
    /// Record mesh frames every n frames (0 = never).
    pub obj_every: usize,
    /// The contact model of the fine shell (default IPC; `Bridson` = the seed's filter).
    #[serde(default)]
    pub contact: ContactMethod,
    /// Also run the untracked twin, per run size (default true for every size). Off, the
    /// untracked keys are absent (NaN deviations): for tracked-only figures when the twin's cost
    /// does not fit (a crumpled untracked Xavier costs 1.4–6.6 s per step on the ground).
    #[serde(default = "yes")]
    pub untracked: BySize<bool>,
}

fn yes() -> BySize<bool> {
    BySize::Same(true)
}

impl PairParams {
    /// The fine shell's options at a run size.
    pub fn shell(&self, size: Size) -> ShellOptions {
        ShellOptions {
            substeps: self.substeps.get(size),
            self_collision: self.self_collision.get(size),
            contact: self.contact,
        }
    }

    /// The tracking options (the scene's solver and refinement, the library defaults otherwise).
    pub fn track(&self) -> TrackOptions {
        track_opts(self.kkt, self.refine_steps)
    }

    /// Checks the run settings; the message names the field and `scene`.
    pub fn validate(&self, scene: &str) -> Result<()> {
        for s in [Size::Tiny, Size::Quick, Size::Default, Size::Full] {
            let d = self.duration.get(s);
            if !(d.is_finite() && d > 0.0) {
                return Err(bad(scene, format!("duration must be finite and > 0 s, got {d} ({})", s.name())));
            }
            if self.substeps.get(s) == 0 {
                return Err(bad(scene, format!("substeps must be ≥ 1 ({})", s.name())));
            }
        }
        Ok(())
    }
}

/// Source line of the constraint-residual check (solver precision, spec §7 tests 8 and 11).
pub const RESIDUAL_SOURCE: &str = "Bergou et al. 2007 §4.3: exact constraints (r_pre ≤ 1e-9·L)";

/// Checks `max_residual_pre` ≤ 1e-9 (r_pre / L at solver precision).
pub fn check_residual(r: &mut Report, key: &str) {
    r.check(key, geom_core::experiment::Target::AtMost(1e-9), RESIDUAL_SOURCE);
}

/// Source line of the physical-sanity checks.
pub const SANITY_SOURCE: &str = "issue 20: tracks re-measured on the repaired simulator (tracked and untracked cloth)";

/// Registers issue 20's sanity targets on the tracked and the untracked run: edge strain ≤ 0.10,
/// no self-intersection.
pub fn check_sanity(r: &mut Report) {
    for run in ["tracked", "untracked"] {
        if r.get(&format!("max_edge_strain_{run}")).is_some() {
            r.check(&format!("max_edge_strain_{run}"), geom_core::experiment::Target::AtMost(0.10), SANITY_SOURCE);
            r.check(&format!("max_intersections_{run}"), geom_core::experiment::Target::Equals(0.0), SANITY_SOURCE);
        }
    }
}

/// A typed bad-parameter error naming the scene.
pub fn bad(scene: &str, msg: String) -> crate::TrackError {
    crate::TrackError::BadParameter(format!("{scene}: {msg}"))
}

/// Tracking options with the given solver and refinement steps, library defaults otherwise.
pub fn track_opts(kkt: KktMethod, refine_steps: u32) -> TrackOptions {
    TrackOptions { kkt, refine_steps, ..TrackOptions::default() }
}

/// What to run and record.
#[derive(Clone, Debug)]
pub struct PairOpts {
    /// Frames to simulate (frame 0, the initial state, is measured too).
    pub frames: usize,
    /// Record mesh frames every n frames (0 = never).
    pub obj_every: usize,
    /// Also run the untracked twin.
    pub untracked: bool,
    /// Tracking options.
    pub track: TrackOptions,
    /// Count exact self-intersections of the tracked mesh and the guide on every frame.
    pub intersections: bool,
    /// Anchor vertices of the tug index (Fig. 3/4), `None` = no tug index.
    pub anchors: Option<Vec<u32>>,
    /// Suffix of the table and sequence names (`""`, `"_averaged"`, `"_r16"` …).
    pub tag: String,
    /// Vertex subsets of the tracked mesh whose figures are also measured on their own
    /// ([`PairOut::subsets`]; e.g. Xavier's feet and body, the two halves of Fig. 5).
    pub subsets: Vec<Vec<u32>>,
}

/// Per-frame figures of one vertex subset of the tracked run (frames ≥ 1).
#[derive(Clone, Debug, Default)]
pub struct SubsetSeries {
    /// D_c restricted to the subset: area-RMS over its vertices of (L_τ d)_i, / L.
    pub dc: Vec<f64>,
    /// a_d restricted to the subset: area-RMS over its vertices of (d − L_τ d)_i (m).
    pub ad: Vec<f64>,
    /// Area-RMS ‖d‖ / L over the subset.
    pub rms: Vec<f64>,
    /// λ_eff of d itself restricted to the subset ([`LowPass::wavelength_subset`], m).
    pub lambda_raw: Vec<f64>,
}

/// Figures of one lockstep run.
#[derive(Clone, Debug, Default)]
pub struct PairOut {
    /// Enforced constraints K.
    pub k: usize,
    /// The guide's bounding-box diagonal L at t = 0 (m).
    pub scale: f64,
    /// Σ tracked step wall time (s).
    pub t_tracked: f64,
    /// Σ untracked step wall time (s).
    pub t_untracked: f64,
    /// Σ constrained-solve time (s).
    pub t_kkt: f64,
    /// Σ shadow LLᵀ time (s).
    pub t_shadow: f64,
    /// Steps taken.
    pub steps: usize,
    /// Frames simulated.
    pub frames: usize,
    /// max over steps of max_i ‖g_i‖ before the collision pass (m).
    pub max_r_pre: f64,
    /// max over steps of max_i ‖g_i‖ of the final state (m).
    pub max_r_post: f64,
    /// Largest per-vertex constraint force (N).
    pub max_force: f64,
    /// Largest number of stored factor entries of the constrained solve.
    pub nnz_l: usize,
    /// Per frame ≥ 1: D_c of the tracked run.
    pub dc_tracked: Vec<f64>,
    /// Per frame ≥ 1: D_c of the untracked run (NaN without it).
    pub dc_untracked: Vec<f64>,
    /// Per frame ≥ 1: a_d of the tracked run (m).
    pub ad_tracked: Vec<f64>,
    /// Per frame ≥ 1: area-RMS ‖d‖ / L of the tracked run.
    pub rms_tracked: Vec<f64>,
    /// Per frame ≥ 1: λ_eff of d itself (m; Fig. 6).
    pub lambda_raw_tracked: Vec<f64>,
    /// Per frame ≥ 0: hinge bending energy of the tracked run (J).
    pub bend_tracked: Vec<f64>,
    /// Per frame ≥ 0: tug index of the tracked run (NaN without anchors).
    pub tug_tracked: Vec<f64>,
    /// Per frame ≥ 0: self-intersections of the tracked mesh (0 unless counted).
    pub isect_tracked: Vec<usize>,
    /// Per frame ≥ 0: self-intersections of the guide (0 unless counted).
    pub isect_guide: Vec<usize>,
    /// Per frame ≥ 0: time (s).
    pub times: Vec<f64>,
    /// The guide was held past its end.
    pub guide_held: bool,
    /// Setup warnings of the tracker.
    pub warnings: Vec<String>,
    /// Final tracked positions (m).
    pub final_tracked: Vec<Pt3>,
    /// Final untracked positions (m; empty without the twin).
    pub final_untracked: Vec<Pt3>,
    /// Per frame ≥ 0: kinetic energy of the tracked run (J).
    pub ke_tracked: Vec<f64>,
    /// Times the rest-angle events changed the tracked run's rest angles.
    pub rest_updates: usize,
    /// Per frame ≥ 1: detail wavelength λ_eff = 2π sqrt(hᵀM_L h / hᵀK h) of h = d − L_τ d (m).
    pub lambda_eff_tracked: Vec<f64>,
    /// Per step: (tracked, untracked) wall time (s).
    pub step_times: Vec<(f64, f64)>,
    /// Per method of `TrackOptions::compare`: Σ solve time (s), max relative Δv difference to
    /// the main solve, stored factor entries.
    pub compare: Vec<(f64, f64, usize)>,
    /// Per step: the tracked step's constrained linear-solve time `t_kkt` (KKT values, numeric
    /// factorisation and solve, summed over the step's Newton iterations) (s).
    pub kkt_times: Vec<f64>,
    /// Per step: the untracked step's numeric factorisation + solve of A, summed over its Newton
    /// iterations (s; empty without the twin).
    pub untracked_factor_solve: Vec<f64>,
    /// Per step: Newton iterations of the (tracked, untracked) step (untracked 0 without the
    /// twin) — the step cost beside the per-iteration solve cost.
    pub newton_iters: Vec<(u32, u32)>,
    /// Physical-sanity figures of the tracked cloth over every step (issue 20).
    pub sanity_tracked: Option<Sanity>,
    /// Physical-sanity figures of the untracked cloth over every step (`None` without the twin).
    pub sanity_untracked: Option<Sanity>,
    /// Edge strain of the guide itself over the frames, against the guide's rest mesh: what the
    /// constraints ask of the cloth (a guide that stretches makes the tracked cloth stretch).
    pub sanity_guide: Option<Sanity>,
    /// Exact self-intersection count, max over the counted frames (every frame with
    /// `intersections`, otherwise every recorded frame and the last one), tracked / untracked.
    pub max_intersections: (u64, u64),
    /// Per frame ≥ 1: centroid of the tracked cloth (m).
    pub centroid_tracked: Vec<Pt3>,
    /// Per frame ≥ 1: mean vertex speed of the tracked cloth (m/s).
    pub speed_tracked: Vec<f64>,
    /// Per frame ≥ 1: centroid of the untracked cloth (m; empty without the twin).
    pub centroid_untracked: Vec<Pt3>,
    /// Per frame ≥ 1: mean vertex speed of the untracked cloth (m/s; empty without the twin).
    pub speed_untracked: Vec<f64>,
    /// Per subset of [`PairOpts::subsets`]: its per-frame figures.
    pub subsets: Vec<SubsetSeries>,
    /// Per frame ≥ 1: wrinkle-scale detail amplitude of the tracked run (m): a_d with the
    /// filter scale ℓ_w = ℓ_c/4 ([`WRINKLE_REFINE`]: detail finer than the test functions
    /// refined twice), so box-scale departures from the guide count as coarse.
    pub ad_wrinkle_tracked: Vec<f64>,
    /// Per frame ≥ 1: λ_eff of the wrinkle-scale detail (m).
    pub lambda_wrinkle_tracked: Vec<f64>,
}

/// The wrinkle-scale filter uses `WRINKLE_REFINE`·K regions' length scale: ℓ_w = ℓ_c/4, the
/// size of a test function refined by two levels of subdivision.
pub const WRINKLE_REFINE: usize = 16;

impl PairOut {
    /// Overhead (%) from the summed step times.
    pub fn overhead_pct(&self) -> f64 {
        overhead_pct(self.t_tracked, self.t_untracked)
    }
    /// Overhead (%) from the median step times.
    pub fn overhead_pct_median(&self) -> f64 {
        overhead_pct_median(&self.step_times)
    }
    /// Median tracked constrained-solve time over median untracked factorisation + solve
    /// ([`kkt_over_untracked_factor`]); NaN without the untracked twin.
    pub fn kkt_over_untracked_factor(&self) -> f64 {
        kkt_over_untracked_factor(&self.kkt_times, &self.untracked_factor_solve)
    }
    /// [`kkt_over_untracked_factor`] per Newton iteration: the median over steps of t_kkt /
    /// iterations over the median of the untracked step's (factorisation + solve) / iterations
    /// — the cost of one constrained solve against one unconstrained one, without the
    /// difference in iteration counts the step figure includes. NaN without the twin.
    pub fn kkt_over_untracked_factor_per_iteration(&self) -> f64 {
        let per = |t: &[f64], it: fn(&(u32, u32)) -> u32| -> Vec<f64> {
            t.iter().zip(&self.newton_iters).map(|(t, n)| t / f64::from(it(n).max(1))).collect()
        };
        kkt_over_untracked_factor(&per(&self.kkt_times, |n| n.0), &per(&self.untracked_factor_solve, |n| n.1))
    }
    /// Mean Newton iterations per step, (tracked, untracked); NaN when no step ran.
    pub fn newton_iters_per_step(&self) -> (f64, f64) {
        let mean = |f: fn(&(u32, u32)) -> u32| {
            geom_core::stats::mean(&self.newton_iters.iter().map(|x| f64::from(f(x))).collect::<Vec<_>>())
        };
        (mean(|x| x.0), mean(|x| x.1))
    }
    /// Tracked wall time per frame (s).
    pub fn s_per_frame_tracked(&self) -> f64 {
        self.t_tracked / self.frames.max(1) as f64
    }
    /// Untracked wall time per frame (s).
    pub fn s_per_frame_untracked(&self) -> f64 {
        self.t_untracked / self.frames.max(1) as f64
    }
    /// Mean constrained-solve time per step (s).
    pub fn solve_s_per_step(&self) -> f64 {
        self.t_kkt / self.steps.max(1) as f64
    }
    /// Times of frames ≥ 1 (aligned with `dc_tracked`, `ad_tracked`, `lambda_eff_tracked` …).
    pub fn t(&self) -> &[f64] {
        self.times.get(1..).unwrap_or(&[])
    }
    /// max r_pre / L.
    pub fn r_pre(&self) -> f64 {
        self.max_r_pre / self.scale
    }
    /// max r_post / L.
    pub fn r_post(&self) -> f64 {
        self.max_r_post / self.scale
    }

    /// The keys every tracking scene reports (see the crate README).
    pub fn report(&self, r: &mut Report) {
        let last = |v: &[f64]| v.last().copied().unwrap_or(f64::NAN);
        r.timing("overhead_pct", self.overhead_pct());
        r.timing("overhead_pct_median_step", self.overhead_pct_median());
        r.num("max_residual_pre", self.r_pre());
        r.num("max_residual_post", self.r_post());
        r.num("coarse_deviation_tracked", last(&self.dc_tracked));
        r.num("coarse_deviation_untracked", last(&self.dc_untracked));
        r.num("coarse_deviation_tracked_mean", geom_core::stats::mean(&self.dc_tracked));
        r.num("coarse_deviation_untracked_mean", geom_core::stats::mean(&self.dc_untracked));
        r.timing("s_per_frame_tracked", self.s_per_frame_tracked());
        r.timing("s_per_frame_untracked", self.s_per_frame_untracked());
        r.timing("solve_s_per_step", self.solve_s_per_step());
        r.num("max_constraint_force_N", self.max_force);
        r.count("constraints", self.k as u64);
        r.count("frames", self.frames as u64);
        r.count("nnz_l", self.nnz_l as u64);
        r.count("guide_held", self.guide_held as u64);
        r.count("setup_warnings", self.warnings.len() as u64);
        let (it_t, it_u) = self.newton_iters_per_step();
        r.num("newton_iters_per_step_tracked", it_t);
        if !self.untracked_factor_solve.is_empty() {
            r.timing("kkt_over_untracked_factor", self.kkt_over_untracked_factor());
            r.timing("kkt_over_untracked_factor_per_iteration", self.kkt_over_untracked_factor_per_iteration());
            r.num("newton_iters_per_step_untracked", it_u);
        }
        self.report_sanity(r);
    }

    /// The physical-sanity figures of issue 20 for the tracked and (when run) the untracked
    /// cloth: `max_edge_strain_*`, `max_edge_compression_*`, `max_obstacle_penetration_m_*`
    /// (over every step) and `max_intersections_*` (over the counted frames).
    pub fn report_sanity(&self, r: &mut Report) {
        let runs = [
            ("tracked", &self.sanity_tracked, self.max_intersections.0),
            ("untracked", &self.sanity_untracked, self.max_intersections.1),
        ];
        for (name, s, isect) in runs {
            let Some(s) = s else { continue };
            r.num(&format!("max_edge_strain_{name}"), s.max_edge_strain);
            r.num(&format!("max_edge_compression_{name}"), s.max_edge_compression);
            r.num(&format!("max_obstacle_penetration_m_{name}"), s.max_obstacle_penetration_m);
            r.count(&format!("max_intersections_{name}"), isect);
        }
        if let Some(g) = &self.sanity_guide {
            r.num("max_edge_strain_guide", g.max_edge_strain);
            r.num("max_edge_compression_guide", g.max_edge_compression);
        }
    }

    /// The D_c(t) curves of the tracked and the untracked run (plot `deviation`).
    pub fn record_deviation(&self, rec: &mut dyn Recorder) -> Result<()> {
        let pts = |v: &[f64]| self.t().iter().zip(v).map(|(a, b)| (*a, *b)).collect::<Vec<_>>();
        let series = |label: &str, v: &[f64]| Series {
            plot: "deviation".into(),
            label: label.into(),
            axes: ("t (s)".into(), "D_c (1/L)".into()),
            log: (false, false),
            points: pts(v),
        };
        rec.series(&series("tracked", &self.dc_tracked))?;
        if self.dc_untracked.iter().all(|x| x.is_finite()) {
            rec.series(&series("untracked", &self.dc_untracked))?;
        }
        Ok(())
    }
}

fn mesh_frame<'a>(seq: &'a str, index: usize, time: f64, q: &'a [Pt3], faces: &'a [[u32; 3]]) -> MeshFrame<'a> {
    MeshFrame { sequence: seq, index, time, positions: q, faces, attributes: &[] }
}

/// Steps the tracked and (optionally) the untracked simulation of `setup` in lockstep, timing
/// every step, and records residuals and per-frame metrics (outside the timed region).
pub fn run_pair(setup: &Setup, o: &PairOpts, rec: &mut dyn Recorder) -> Result<PairOut> {
    let desc = (setup.desc)();
    let obstacles = desc.effects.obstacles.clone();
    let sim = ShellSim::new(desc)?;
    let mut tr = Tracker::new(sim, setup.guide.clone(), setup.tf.clone(), setup.prolongation.clone(), o.track.clone())?;
    let mut un = if o.untracked { Some(ShellSim::new((setup.desc)())?) } else { None };
    let mut out = PairOut {
        k: tr.constraints().map_or(0, |c| c.len()),
        scale: setup.guide.scale(),
        warnings: tr.warnings.clone(),
        ..PairOut::default()
    };
    let sanity = |s: &ShellSim| Sanity::new(&s.mesh().rest, &s.mesh().edges, obstacles.clone(), None);
    let mut san_t = sanity(&tr.sim);
    let mut san_u = un.as_ref().map(sanity);
    let gm = &setup.guide.rest;
    let mut san_g = Sanity::new(&gm.positions, gm.topology().edges(), Vec::new(), None);
    let k_lp = out.k.max(1);
    let lp = LowPass::new(&setup.tracked_rest, LowPass::tau_for(&setup.tracked_rest, k_lp))?;
    let lp_w = LowPass::new(&setup.tracked_rest, LowPass::tau_for(&setup.tracked_rest, WRINKLE_REFINE * k_lp))?;
    let n_fine = setup.tracked_rest.n_vertices();
    let masks: Vec<Vec<bool>> = o.subsets.iter().map(|s| vertex_mask(n_fine, s)).collect();
    out.subsets = vec![SubsetSeries::default(); masks.len()];
    let h = setup.h();
    let faces = tr.sim.mesh().tris.clone();
    let mut gq = vec![Pt3::origin(); setup.guide.n_vertices()];
    let tag = &o.tag;
    let (steps_t, frames_t) = (format!("steps{tag}"), format!("frames{tag}"));
    let (seq_tr, seq_gd, seq_un) = (format!("tracked{tag}"), format!("guide{tag}"), format!("untracked{tag}"));
    rec.table(
        &steps_t,
        &[
            "t",
            "t_step_tracked",
            "t_step_untracked",
            "t_kkt",
            "t_shadow_llt",
            "r_pre",
            "r_post",
            "max_force",
            "ccd",
            "refine_steps",
            "newton_iters_tracked",
            "newton_iters_untracked",
            "t_factor_solve_untracked",
        ],
    )?;
    rec.table(
        &frames_t,
        &["frame", "t", "dc_tracked", "dc_untracked", "a_d", "rms_d", "bend_J", "tug", "isect_tracked", "isect_guide"],
    )?;
    // The frame rate of the recorded sequences (their USD time codes are frame numbers).
    rec.scene(&SceneItem::FrameRate { fps: setup.fps })?;
    let total = (o.frames as u64) * setup.substeps as u64;
    // Weight of the rest-angle events last applied (`Setup::rest_events`).
    let mut rest_w = 0.0;
    for frame in 0..=o.frames {
        if frame > 0 {
            for _ in 0..setup.substeps {
                if let Some(ev) = setup.rest_events.as_ref() {
                    // The rest angles of the step's end time, on both runs alike (not timed).
                    let t_next = tr.sim.state().t + h;
                    let mut w = rest_w;
                    out.rest_updates += usize::from(ev.apply(&mut tr.sim, t_next, &mut w)?);
                    if let Some(u) = un.as_mut() {
                        ev.apply(u, t_next, &mut rest_w)?;
                    }
                    rest_w = w;
                }
                let st = tr.step(h)?;
                san_t.observe(&tr.sim.state().q, tr.sim.state().t, None);
                out.kkt_times.push(st.t_kkt);
                out.t_tracked += st.t_step;
                out.t_kkt += st.t_kkt;
                out.t_shadow += st.t_shadow_llt;
                out.max_r_pre = geom_core::stats::nan_max(out.max_r_pre, st.residual_pre_collision);
                out.max_r_post = geom_core::stats::nan_max(out.max_r_post, st.residual_post_collision);
                out.max_force = geom_core::stats::nan_max(out.max_force, st.max_constraint_force);
                out.nnz_l = out.nnz_l.max(st.nnz_l);
                out.guide_held |= st.guide_held;
                out.compare.resize(st.compare.len(), (0.0, 0.0, 0));
                for (acc, c) in out.compare.iter_mut().zip(&st.compare) {
                    *acc = (acc.0 + c.t_solve, geom_core::stats::nan_max(acc.1, c.rel_diff), acc.2.max(c.nnz_l));
                }
                let mut tu = 0.0;
                let mut iters_u = 0;
                if let Some(u) = un.as_mut() {
                    let t0 = Instant::now();
                    let su = u.step(h)?;
                    tu = t0.elapsed().as_secs_f64();
                    out.t_untracked += tu;
                    out.untracked_factor_solve.push(su.t_factor + su.t_solve);
                    iters_u = su.newton_iters;
                    if let Some(s) = san_u.as_mut() {
                        s.observe(&u.state().q, u.state().t, None);
                    }
                }
                out.steps += 1;
                out.newton_iters.push((st.shell.newton_iters, iters_u));
                out.step_times.push((st.t_step, tu));
                rec.row(
                    &steps_t,
                    &[
                        Cell::from(tr.sim.state().t),
                        Cell::from(st.t_step),
                        Cell::from(tu),
                        Cell::from(st.t_kkt),
                        Cell::from(st.t_shadow_llt),
                        Cell::from(st.residual_pre_collision),
                        Cell::from(st.residual_post_collision),
                        Cell::from(st.max_constraint_force),
                        Cell::from(st.shell.n_ccd),
                        Cell::from(st.kkt_refine_steps),
                        Cell::from(st.shell.newton_iters),
                        Cell::from(iters_u),
                        Cell::from(out.untracked_factor_solve.last().copied().unwrap_or(f64::NAN)),
                    ],
                )?;
                rec.progress(out.steps as u64, total);
            }
            out.frames += 1;
        }
        // Metrics (not timed).
        let t = tr.sim.state().t;
        setup.guide.sample(t, &mut gq);
        san_g.observe(&gq, t, None);
        let gf = guide_on_tracked(setup.prolongation.as_ref(), &gq);
        let q = &tr.sim.state().q;
        let d: Vec<Vec3> = q.iter().zip(&gf).map(|(a, b)| a - b).collect();
        let dc = lp.coarse_deviation(&d, out.scale)?;
        let ad = lp.detail_amplitude(&d)?;
        let rms = lp.rms(&d) / out.scale;
        let dcu = match un.as_ref() {
            Some(u) => {
                let du: Vec<Vec3> = u.state().q.iter().zip(&gf).map(|(a, b)| a - b).collect();
                lp.coarse_deviation(&du, out.scale)?
            }
            None => f64::NAN,
        };
        let bend: f64 = hinge_energies(&tr.sim, q).iter().sum();
        let tug = o.anchors.as_ref().map_or(f64::NAN, |a| tug_index(&tr.sim, q, a));
        let (it, ig) = if o.intersections {
            (
                shells::collision::count_self_intersections(q, &faces),
                shells::collision::count_self_intersections(&gq, &setup.guide.rest.faces),
            )
        } else {
            (0, 0)
        };
        // Sanity intersection counts: every written frame and the last one (every frame when
        // `intersections` counted them above).
        let written = o.obj_every > 0 && frame % o.obj_every == 0;
        if o.intersections || written || frame == o.frames {
            let it_s = if o.intersections { it } else { shells::collision::count_self_intersections(q, &faces) };
            out.max_intersections.0 = out.max_intersections.0.max(it_s as u64);
            if let Some(u) = un.as_ref() {
                let iu = shells::collision::count_self_intersections(&u.state().q, &faces);
                out.max_intersections.1 = out.max_intersections.1.max(iu as u64);
            }
        }
        if frame > 0 {
            out.centroid_tracked.push(centroid(q));
            out.speed_tracked.push(mean_speed(&tr.sim.state().v));
            if let Some(u) = un.as_ref() {
                out.centroid_untracked.push(centroid(&u.state().q));
                out.speed_untracked.push(mean_speed(&u.state().v));
            }
            if !masks.is_empty() {
                let lo = lp.apply(&d)?;
                let hi: Vec<Vec3> = d.iter().zip(&lo).map(|(a, b)| a - b).collect();
                for (m, ss) in masks.iter().zip(out.subsets.iter_mut()) {
                    ss.dc.push(lp.rms_subset(&lo, m) / out.scale);
                    ss.ad.push(lp.rms_subset(&hi, m));
                    ss.rms.push(lp.rms_subset(&d, m) / out.scale);
                    ss.lambda_raw.push(lp.wavelength_subset(&d, m));
                }
            }
            out.dc_tracked.push(dc);
            out.dc_untracked.push(dcu);
            out.ad_tracked.push(ad);
            out.rms_tracked.push(rms);
            out.lambda_raw_tracked.push(lp.wavelength(&d));
            let lo = lp.apply(&d)?;
            let detail: Vec<Vec3> = d.iter().zip(&lo).map(|(a, b)| a - b).collect();
            out.lambda_eff_tracked.push(lp.wavelength(&detail));
            let lo_w = lp_w.apply(&d)?;
            let wr: Vec<Vec3> = d.iter().zip(&lo_w).map(|(a, b)| a - b).collect();
            out.ad_wrinkle_tracked.push(lp_w.rms(&wr));
            out.lambda_wrinkle_tracked.push(lp_w.wavelength(&wr));
        }
        out.bend_tracked.push(bend);
        out.tug_tracked.push(tug);
        out.isect_tracked.push(it);
        out.isect_guide.push(ig);
        out.times.push(t);
        out.ke_tracked.push(tr.sim.energies().kinetic);
        rec.row(
            &frames_t,
            &[
                Cell::from(frame),
                Cell::from(t),
                Cell::from(dc),
                Cell::from(dcu),
                Cell::from(ad),
                Cell::from(rms),
                Cell::from(bend),
                Cell::from(tug),
                Cell::from(it),
                Cell::from(ig),
            ],
        )?;
        if o.obj_every > 0 && frame % o.obj_every == 0 {
            rec.frame(&mesh_frame(&seq_tr, frame, t, q, &faces))?;
            rec.frame(&mesh_frame(&seq_gd, frame, t, &gq, &setup.guide.rest.faces))?;
            if let Some(u) = un.as_ref() {
                rec.frame(&mesh_frame(&seq_un, frame, t, &u.state().q, &faces))?;
            }
        }
    }
    out.sanity_tracked = Some(san_t);
    out.sanity_untracked = san_u;
    out.sanity_guide = Some(san_g);
    out.final_tracked = tr.sim.state().q.clone();
    if let Some(u) = un.as_ref() {
        out.final_untracked = u.state().q.clone();
    }
    Ok(out)
}

/// Runs one scene tracked and untracked with the shared parameters `p` at `size`; returns the
/// run and a report holding the common keys (plus `n_vertices`, `duration_s`, `mode`) and the
/// `deviation` plot.
pub fn run_standard(
    p: &PairParams,
    size: Size,
    setup: &Setup,
    intersections: bool,
    rec: &mut dyn Recorder,
) -> Result<(PairOut, Report)> {
    run_standard_with(p, size, setup, intersections, Vec::new(), rec)
}

/// [`run_standard`] that also measures the figures of vertex `subsets` of the tracked mesh
/// ([`PairOut::subsets`]).
pub fn run_standard_with(
    p: &PairParams,
    size: Size,
    setup: &Setup,
    intersections: bool,
    subsets: Vec<Vec<u32>>,
    rec: &mut dyn Recorder,
) -> Result<(PairOut, Report)> {
    let frames = frames_for(p.duration.get(size), setup.fps);
    let o = PairOpts {
        frames,
        obj_every: p.obj_every,
        untracked: p.untracked.get(size),
        track: p.track(),
        intersections,
        anchors: None,
        tag: String::new(),
        subsets,
    };
    let out = run_pair(setup, &o, rec)?;
    out.record_deviation(rec)?;
    let mut r = Report::default();
    out.report(&mut r);
    r.count("n_vertices", setup.tracked_rest.n_vertices() as u64);
    r.num("duration_s", frames as f64 / setup.fps);
    r.text("mode", size.name());
    Ok((out, r))
}

//! S1 (spec §6): a depth-graded pool sampled as a lattice fixed point must stay at rest (S1a),
//! with the variants the scene switches on, each in its own sub-folder: S1b (uniform mesh, the
//! lattice shifted so the surface lies between node planes), S1b with first-order free-surface
//! conditions (must move), S1a with MIC(0)-PCG at 1e−8, and a jittered pool's kinetic-energy decay.
//!
//! ```no_run
//! use flip_tet::experiments::rest_pool;
//! use geom_core::experiment::Size;
//! let r = rest_pool::run(&flip_tet::presets::rest_pool(), Size::Quick, &mut geom_core::record::NullRecorder::default())?;
//! assert!(r.get_f64("max_speed") <= 1e-7);
//! # Ok::<(), flip_tet::error::SimError>(())
//! ```

use geom_core::experiment::{BySize, Report, Size, Target};
use geom_core::record::Recorder;
use serde::{Deserialize, Serialize};

use super::probes::Probes;
use super::{one, plot, simulate, sized_scene, FrameOutput, RunOut};
use crate::error::{Result, SolverKind};
use crate::metrics::{max_speed, rel_drift, run_figures, surface_height};
use crate::presets::{s1b_scene, PCG_TOL};
use crate::scene::Scene;
use crate::sim::{FlipTetSim, StepStats};

/// Parameters (the scene file's `params`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Params {
    /// The pool (its `resolution.finest` and `duration` are set per size).
    pub scene: Scene,
    /// Finest resolution per size.
    pub finest: BySize<u32>,
    /// Duration per size (s).
    pub duration: BySize<f64>,
    /// Surface OBJ every this many frames (0 = never).
    #[serde(default = "one")]
    pub obj_every: u64,
    /// Particle PLY every this many frames (0 = never).
    #[serde(default)]
    pub ply_every: u64,
    /// High-resolution surface every this many frames (0 = never).
    #[serde(default)]
    pub hires_every: u64,
    /// The extra runs of spec §6 S1 (all off when absent).
    #[serde(default)]
    pub variants: Variants,
    /// Probes of S1a sampled every frame into `probes.csv` (issue 26): the pressure probes are
    /// checked against hydrostatics `ρ g (H − y)` below the pool's box top `H`.
    #[serde(default)]
    pub probes: Probes,
}

/// The `variants: (...)` block: which extra runs to make (all `false` by default) and at which
/// sizes.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Variants {
    /// S1b: uniform finest mesh, particle lattice shifted up by `0.37 · 2r`.
    pub offset_surface: bool,
    /// S1a with `PcgIc0` (MIC(0)-preconditioned CG) at `tol = 1e−8` instead of the direct solver.
    pub pcg: bool,
    /// S1b with `second_order: false`.
    pub first_order: bool,
    /// S1a sampled with `sampling_jitter: 0.1` for `jitter_steps` steps (kinetic-energy decay).
    pub jitter: bool,
    /// Steps of the jittered run (spec: 400).
    pub jitter_steps: BySize<u32>,
    /// Finest resolution of the jittered run; `None` = the scene's quick size (tiny at `Tiny`).
    pub jitter_finest: Option<BySize<u32>>,
    /// Finest resolution of the other variant runs; `None` = the scene's.
    pub finest: Option<BySize<u32>>,
}

impl Default for Variants {
    fn default() -> Self {
        Self {
            offset_surface: false,
            pcg: false,
            first_order: false,
            jitter: false,
            jitter_steps: BySize::Same(400),
            jitter_finest: None,
            finest: None,
        }
    }
}

/// What one resting-pool run measured.
pub struct RestRun {
    /// Per-step statistics.
    pub stats: Vec<StepStats>,
    /// Wall time (s).
    pub wall: f64,
    /// Largest particle displacement from its initial position over the steps where the particle
    /// count is unchanged (m).
    pub max_disp: f64,
    /// Largest `|surface_height − target|` over all steps at the probe columns (m; NaN without a
    /// target or when a probe found no surface).
    pub height_err: f64,
    /// Probe values per frame.
    pub probes: Vec<(f64, Vec<f64>, Vec<f64>)>,
}

impl RestRun {
    /// `(step, max speed)` for the log plot (speeds floored at 1e−20 m/s).
    pub fn speed_series(&self) -> Vec<(f64, f64)> {
        self.stats.iter().map(|x| (x.step as f64, x.max_speed.max(1e-20))).collect()
    }
}

/// Runs a resting pool, tracking the largest particle displacement and, with `target` (the
/// intended surface height, m), the surface-height error at the columns `x = ¼, ½, ¾` of the
/// domain, `z` at mid-depth, after every step.
pub fn rest_run(scene: &Scene, rec: &mut dyn Recorder, out: RunOut, target: Option<f64>) -> Result<RestRun> {
    let x0 = FlipTetSim::new(scene)?.particles().x.clone();
    let (xmin, xmax) = (scene.domain.min[0], scene.domain.max[0]);
    let zc = 0.5 * (scene.domain.min[2] + scene.domain.max[2]);
    let mut disp: f64 = 0.0;
    let mut herr: f64 = if target.is_some() { 0.0 } else { f64::NAN };
    let run = simulate(scene, rec, out, &mut |sim, _| {
        if sim.particles().len() == x0.len() {
            let d = sim.particles().x.iter().zip(&x0).map(|(a, b)| (a - b).norm()).fold(0.0, geom_core::stats::nan_max);
            disp = geom_core::stats::nan_max(disp, d);
        }
        if let Some(y) = target {
            for f in [0.25, 0.5, 0.75] {
                let e = surface_height(sim, xmin + f * (xmax - xmin), zc).map_or(f64::NAN, |h| (h - y).abs());
                herr = geom_core::stats::nan_max(herr, e);
            }
        }
        Ok(())
    })?;
    Ok(RestRun { stats: run.stats, wall: run.wall, max_disp: disp, height_err: herr, probes: run.probes })
}

/// Runs S1a and the variants the parameters switch on.
pub fn run(p: &Params, size: Size, rec: &mut dyn Recorder) -> Result<Report> {
    let scene = sized_scene(&p.scene, &p.finest, None, &p.duration, size);
    let frames = FrameOutput { obj: p.obj_every, ply: p.ply_every, hires: p.hires_every };
    let r = rest_run(&scene, rec, RunOut { probes: Some(&p.probes), ..RunOut::full("", frames) }, None)?;
    let mut s = Report::default();
    s.num("max_speed", max_speed(&r.stats));
    s.num("volume_drift_rel", rel_drift(&r.stats, |x| x.vol_levelset));
    s.num("particle_volume_drift_rel", rel_drift(&r.stats, |x| x.vol_particles));
    s.num("max_displacement", r.max_disp);
    s.count("splits_merges", r.stats.iter().map(|x| (x.n_split + x.n_merge) as u64).sum());
    run_figures(&mut s, &r.stats, r.wall);
    s.check("max_speed", Target::AtMost(1e-7), "spec §6 S1a: at rest to 1e-7 m/s");
    s.check("volume_drift_rel", Target::AtMost(1e-6), "spec §6 S1a: level-set volume drift ≤ 1e-6");
    if !p.probes.pressures.is_empty() {
        hydrostatic_figures(&scene, &p.probes, &r.probes, &mut s)?;
    }
    let axes = ("step", "max speed (m/s)");
    plot(rec, "speed_vs_step", "second order, direct", axes, (false, true), r.speed_series())?;
    variants(p, &scene, size, rec, &mut s)?;
    Ok(s)
}

fn variants(p: &Params, scene: &Scene, size: Size, rec: &mut dyn Recorder, s: &mut Report) -> Result<()> {
    let v = &p.variants;
    let every = FrameOutput::surface(p.obj_every);
    let axes = ("step", "max speed (m/s)");
    let finest = v.finest.as_ref().map_or(scene.resolution.finest, |f| f.get(size));
    if v.offset_surface || v.first_order {
        s.count("s1b_finest", u64::from(finest));
    }
    if finest != scene.resolution.finest && (v.offset_surface || v.first_order || v.pcg) {
        s.text(
            "variants_size_note",
            "S1b, first-order and PCG runs use s1b_finest / pcg_finest (time budget), not the S1a size",
        );
    }
    if v.offset_surface {
        let (sc, target) = s1b_scene(scene, finest)?;
        let r = rest_run(&sc, rec, RunOut::full("s1b/", every), Some(target))?;
        s.num("s1b_max_speed", max_speed(&r.stats));
        s.num("s1b_max_displacement", r.max_disp);
        s.num("s1b_volume_drift_rel", rel_drift(&r.stats, |x| x.vol_levelset));
        s.num("s1b_surface_height_err_m", r.height_err);
        s.num("s1b_surface_target_m", target);
        s.timing("s1b_wall_s", r.wall);
        s.check("s1b_max_speed", Target::AtMost(1e-7), "spec §6 S1b: offset surface at rest");
        plot(rec, "speed_vs_step", "S1b offset, second order", axes, (false, true), r.speed_series())?;
    }
    if v.first_order {
        let (mut sc, _) = s1b_scene(scene, finest)?;
        sc.pressure.second_order = false;
        let r = rest_run(&sc, rec, RunOut::full("s1b_first_order/", every), None)?;
        s.num("s1b_first_order_max_speed", max_speed(&r.stats));
        s.timing("s1b_first_order_wall_s", r.wall);
        plot(rec, "speed_vs_step", "S1b offset, first order", axes, (false, true), r.speed_series())?;
    }
    if v.pcg {
        let mut sc = scene.clone();
        sc.resolution.finest = finest;
        sc.pressure.solver = SolverKind::PcgIc0;
        sc.pressure.tol = PCG_TOL;
        let r = rest_run(&sc, rec, RunOut::full("pcg/", every), None)?;
        s.num("pcg_max_speed", max_speed(&r.stats));
        s.count("pcg_finest", u64::from(finest));
        s.count("pcg_max_iters", r.stats.iter().map(|x| x.solver.iters as u64).max().unwrap_or(0));
        s.timing("pcg_wall_s", r.wall);
        s.check("pcg_max_speed", Target::AtMost(1e-5), "spec §6 S1: PCG 1e-8 rest pool ≤ 1e-5 m/s");
        plot(rec, "speed_vs_step", "S1a, MIC(0)-PCG 1e-8", axes, (false, true), r.speed_series())?;
    }
    if v.jitter {
        jitter_run(p, size, scene, rec, s)?;
    }
    Ok(())
}

/// S1 jittered run: S1a sampled with `sampling_jitter: 0.1` for `jitter_steps` steps of
/// `dt_max`; keys `jitter_ke_initial_J` (after the first step), `jitter_ke_peak_J`,
/// `jitter_ke_final_J`, and `jitter/ke_vs_step.png`.
fn jitter_run(p: &Params, size: Size, scene: &Scene, rec: &mut dyn Recorder, s: &mut Report) -> Result<()> {
    let v = &p.variants;
    let base = if size == Size::Tiny { Size::Tiny } else { Size::Quick };
    let finest = v.jitter_finest.as_ref().map_or(p.finest.get(base), |f| f.get(size));
    let mut sc = scene.clone();
    sc.resolution.finest = finest;
    sc.particles.sampling_jitter = 0.1;
    sc.duration = f64::from(v.jitter_steps.get(size)) * sc.flip.dt_max;
    let out = RunOut { dir: "jitter/", frames: FrameOutput::NONE, snapshots: true, metrics: true, probes: None };
    let run = simulate(&sc, rec, out, &mut |_, _| Ok(()))?;
    let ke: Vec<(f64, f64)> = run.stats.iter().map(|x| (x.step as f64, x.kinetic_energy)).collect();
    s.num("jitter_ke_initial_J", ke.first().map_or(f64::NAN, |x| x.1));
    s.num("jitter_ke_peak_J", ke.iter().map(|x| x.1).fold(0.0, geom_core::stats::nan_max));
    s.num("jitter_ke_final_J", ke.last().map_or(f64::NAN, |x| x.1));
    s.count("jitter_steps", run.stats.len() as u64);
    s.count("jitter_finest", u64::from(finest));
    s.timing("jitter_wall_s", run.wall);
    let floored = ke.iter().map(|&(k, e)| (k, e.max(1e-30))).collect();
    plot(rec, "jitter/ke_vs_step", "jitter 0.1", ("step", "kinetic energy (J)"), (false, true), floored)?;
    Ok(())
}

/// `probe_hydrostatic_rel_err`: the largest `|p − ρ g (H − y)| / (ρ g (H − y))` over the pressure
/// probes and the frames after the first step (`H` = the pool box's top), and
/// `probe_height_max_abs_err_m` against `H` for the height probes (issue 26).
fn hydrostatic_figures(
    scene: &Scene,
    probes: &Probes,
    values: &[(f64, Vec<f64>, Vec<f64>)],
    s: &mut Report,
) -> Result<()> {
    let top = match scene.liquid.first() {
        Some(crate::scene::Shape::Box { max, .. }) => max[1],
        _ => {
            return Err(crate::error::SimError::InvalidScene(
                "rest-pool: the first liquid shape must be the pool Box".into(),
            ))
        }
    };
    let (rho, g) = (crate::sim::RHO, -scene.gravity[1]);
    let mut err = 0.0;
    let mut herr = 0.0;
    for (_, h, p) in values.iter().skip(1) {
        for (q, &v) in probes.pressures.iter().zip(p) {
            let want = crate::reference::hydrostatic_pressure(rho, g, top - q[1]);
            err = geom_core::stats::nan_max(err, (v - want).abs() / want);
        }
        for &v in h {
            herr = geom_core::stats::nan_max(herr, (v - top).abs());
        }
    }
    if values.len() < 2 {
        err = f64::NAN;
    }
    s.num("probe_hydrostatic_rel_err", err);
    if !probes.heights.is_empty() {
        s.num("probe_height_max_abs_err_m", herr);
    }
    s.check("probe_hydrostatic_rel_err", Target::AtMost(0.01), "issue 26: a pressure probe reads ρ g depth within 1 %");
    Ok(())
}

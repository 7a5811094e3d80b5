//! The extra runs ("variants") of flip-tet's S1 `rest-pool` and S3 `standing-wave` (spec §6):
//! S1b offset surface, the PCG rest pool, the first-order S1b run, the jittered pool (S1); the
//! first-order standing wave, the `H = 0.25` m wave and the uniform-mesh wave (S3).
//!
//! Every variant is opt-in: the scene file's `variants: (...)` block switches each one on (all off
//! when the block is absent, so other scenes and the benches that load these files pay nothing).
//! Each variant runs in its own sub-folder of the run's output folder with its own `metrics.csv`
//! written step by step, and adds its keys to the scene's summary.

use std::path::Path;

use flip_tet::error::SolverKind;
use flip_tet::metrics;
use flip_tet::scene::{Scene, Shape};
use flip_tet::sim::StepStats;
use serde::Deserialize;

use super::flip_tet::{rel_drift, simulate, FrameOutput, FtParams};
use crate::error::{Error, Result};
use crate::out::Summary;
use crate::plot::{LinePlot, Series};
use crate::registry::RunCtx;
use crate::scene::Mode;

/// S1b lattice shift in units of the particle spacing `2r` (spec §6 S1b: the flat surface then
/// lies `0.37 · 2r = 0.185 h` above a node plane, strictly between two planes `h/2` apart).
pub const S1B_OFFSET: f64 = 0.37;
/// Liquid depth of the second standing wave (m; spec §6 S3 "repeat with `H = 0.25`").
pub const SHALLOW_DEPTH: f64 = 0.25;
/// PCG tolerance of the S1 PCG run (relative residual; spec §6 S1).
pub const PCG_TOL: f64 = 1e-8;

/// The `variants: (...)` block of the S1/S3 scene files: which extra runs to make (all `false`
/// by default: effects are opt-in) and at which sizes. Switches that do not belong to a scene
/// are ignored by it (S1: `offset_surface`, `pcg`, `first_order`, `jitter`; S3: `first_order`,
/// `shallow`, `uniform`).
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Variants {
    /// S1b: uniform finest mesh, particle lattice shifted up by `0.37 · 2r`.
    pub offset_surface: bool,
    /// S1a with `PcgIc0` (MIC(0)-preconditioned CG) at `tol = 1e−8` instead of the direct solver.
    pub pcg: bool,
    /// First-order free-surface conditions: S1b with `second_order: false` (S1), the standing
    /// wave with `second_order: false` (S3).
    pub first_order: bool,
    /// S1: S1a sampled with `sampling_jitter: 0.1` for `jitter_steps` steps (kinetic-energy decay).
    pub jitter: bool,
    /// Steps of the jittered run (spec: 400).
    pub jitter_steps: u32,
    /// Finest resolution of the jittered run for (quick, default, full); `None` = the scene's
    /// quick size in every mode (the brief's budget: 400 steps only fit at the quick size).
    pub jitter_finest: Option<(u32, u32, u32)>,
    /// S3: the same wave over a pool of depth `H = 0.25` m.
    pub shallow: bool,
    /// S3: the wave on a uniform mesh at the same finest resolution.
    pub uniform: bool,
    /// Finest resolution of the other variant runs for (quick, default, full); `None` = the
    /// scene's. Set it when a variant does not fit the time budget at the scene's size.
    pub finest: Option<(u32, u32, u32)>,
}

impl Default for Variants {
    fn default() -> Self {
        Self {
            offset_surface: false,
            pcg: false,
            first_order: false,
            jitter: false,
            jitter_steps: 400,
            jitter_finest: None,
            shallow: false,
            uniform: false,
            finest: None,
        }
    }
}

impl Variants {
    /// The finest resolution of the variant runs in `mode` (`scene_finest` unless overridden).
    fn finest_in(&self, mode: Mode, scene_finest: u32) -> u32 {
        self.finest.map_or(scene_finest, |f| mode.pick(f.0, f.1, f.2))
    }
}

/// Creates `ctx.out_dir/name` and returns it.
fn sub_dir(ctx: &RunCtx, name: &str) -> Result<std::path::PathBuf> {
    let d = ctx.out_dir.join(name);
    crate::out::ensure_dir(&d)?;
    Ok(d)
}

/// What one resting-pool run measured.
pub(crate) struct RestRun {
    /// Per-step statistics.
    pub stats: Vec<StepStats>,
    /// Wall time (s).
    pub wall: f64,
    /// Largest particle displacement from its initial position over the steps where the particle
    /// count is unchanged (m).
    pub max_disp: f64,
    /// Largest `|surface_height − target|` over all steps at the probe columns (m; `NaN` without
    /// a target or when a probe found no surface).
    pub height_err: f64,
}

impl RestRun {
    /// Largest particle speed over all steps (m/s).
    pub fn max_speed(&self) -> f64 {
        self.stats.iter().map(|x| x.max_speed).fold(0.0, f64::max)
    }

    /// `(step, max speed)` for the log plot (speeds floored at 1e−20 m/s).
    pub fn speed_series(&self) -> Vec<(f64, f64)> {
        self.stats.iter().map(|x| (x.step as f64, x.max_speed.max(1e-20))).collect()
    }
}

/// Runs a resting pool, tracking the largest particle displacement and, with `target` (the
/// intended surface height, m), the surface-height error from `metrics::surface_height` at the
/// columns `x = ¼, ½, ¾` of the domain, `z` at mid-depth, after every step.
pub(crate) fn rest_run(scene: &Scene, dir: &Path, every: FrameOutput, target: Option<f64>) -> Result<RestRun> {
    let x0 =
        flip_tet::sim::FlipTetSim::new(scene).map_err(|e| Error::Run(format!("flip-tet: {e}")))?.particles().x.clone();
    let (xmin, xmax) = (scene.domain.min[0], scene.domain.max[0]);
    let zc = 0.5 * (scene.domain.min[2] + scene.domain.max[2]);
    let mut disp: f64 = 0.0;
    let mut herr: f64 = if target.is_some() { 0.0 } else { f64::NAN };
    let (stats, wall, _) = simulate(scene, dir, every, &mut |sim, _| {
        if sim.particles().len() == x0.len() {
            let d = sim.particles().x.iter().zip(&x0).map(|(a, b)| (a - b).norm()).fold(0.0, f64::max);
            disp = disp.max(d);
        }
        if let Some(y) = target {
            for f in [0.25, 0.5, 0.75] {
                let e = metrics::surface_height(sim, xmin + f * (xmax - xmin), zc).map_or(f64::NAN, |h| (h - y).abs());
                // NaN (no surface found) sticks: `f64::max` would drop it.
                herr = if e.is_nan() || herr.is_nan() { f64::NAN } else { herr.max(e) };
            }
        }
    })?;
    Ok(RestRun { stats, wall, max_disp: disp, height_err: herr })
}

/// The S1b scene: `base` on a uniform mesh at `finest` with the lattice shifted up by
/// `0.37 · 2r`, and its intended surface height (m): the liquid box top plus the shift.
///
/// The shift also opens a gap of `0.185 h` between the floor and the bottom particles' spheres
/// (and the side walls keep theirs: the shift is vertical only). flip-tet's level set mirrors
/// every particle within `2 l r` of a closed wall across it (`surface::levelset`, spec §3.11.3),
/// so the hull between a bottom particle and its mirror image covers the gap and the floor nodes
/// stay liquid; no extra particles or walls are added.
pub(crate) fn s1b_scene(base: &Scene, finest: u32) -> Result<(Scene, f64)> {
    let top = match base.liquid.first() {
        Some(Shape::Box { max, .. }) => max[1],
        _ => return Err(Error::Run("rest-pool: the first liquid shape must be the pool Box".into())),
    };
    let mut s = base.clone();
    s.resolution.finest = finest;
    s.resolution.coarsest = finest;
    s.particles.lattice_offset = [0.0, S1B_OFFSET, 0.0];
    // Uniform mesh: h_min = longest domain side / finest, r = h_min / 4, spacing 2r = h_min / 2.
    let longest = (0..3).map(|a| s.domain.max[a] - s.domain.min[a]).fold(0.0, f64::max);
    let h = longest / f64::from(finest);
    Ok((s, top + S1B_OFFSET * h / 2.0))
}

/// Runs the S1 variants the scene asks for, adds their keys to `s` and returns extra series for
/// `speed_vs_step.png`.
pub(crate) fn rest_pool_variants(ctx: &RunCtx, p: &FtParams, scene: &Scene, s: &mut Summary) -> Result<Vec<Series>> {
    let v = &p.variants;
    let every = FrameOutput::surface(p.obj_every);
    let mut series = Vec::new();
    let finest = v.finest_in(ctx.mode, scene.resolution.finest);
    if v.offset_surface || v.first_order {
        s.set_count("s1b_finest", u64::from(finest));
    }
    if finest != scene.resolution.finest && (v.offset_surface || v.first_order || v.pcg) {
        s.set_str(
            "variants_size_note",
            "S1b, first-order and PCG runs use s1b_finest / pcg_finest (time budget), not the S1a size",
        );
    }
    if v.offset_surface {
        let (sc, target) = s1b_scene(scene, finest)?;
        let r = rest_run(&sc, &sub_dir(ctx, "s1b")?, every, Some(target))?;
        s.set("s1b_max_speed", r.max_speed());
        s.set("s1b_max_displacement", r.max_disp);
        s.set("s1b_volume_drift_rel", rel_drift(&r.stats, |x| x.vol_levelset));
        s.set("s1b_surface_height_err_m", r.height_err);
        s.set("s1b_surface_target_m", target);
        s.set("s1b_wall_s", r.wall);
        series.push(Series::new("S1b offset, second order", r.speed_series()));
    }
    if v.first_order {
        let (mut sc, _) = s1b_scene(scene, finest)?;
        sc.pressure.second_order = false;
        let r = rest_run(&sc, &sub_dir(ctx, "s1b_first_order")?, every, None)?;
        s.set("s1b_first_order_max_speed", r.max_speed());
        s.set("s1b_first_order_wall_s", r.wall);
        series.push(Series::new("S1b offset, first order", r.speed_series()));
    }
    if v.pcg {
        let mut sc = scene.clone();
        sc.resolution.finest = finest;
        sc.pressure.solver = SolverKind::PcgIc0;
        sc.pressure.tol = PCG_TOL;
        let r = rest_run(&sc, &sub_dir(ctx, "pcg")?, every, None)?;
        s.set("pcg_max_speed", r.max_speed());
        s.set_count("pcg_finest", u64::from(finest));
        s.set_count("pcg_max_iters", r.stats.iter().map(|x| x.solver.iters as u64).max().unwrap_or(0));
        s.set("pcg_wall_s", r.wall);
        series.push(Series::new("S1a, MIC(0)-PCG 1e-8", r.speed_series()));
    }
    if v.jitter {
        jitter_run(ctx, v, p.finest.0, scene, s)?;
    }
    Ok(series)
}

/// S1 jittered run: S1a sampled with `sampling_jitter: 0.1` for `v.jitter_steps` steps of
/// `dt_max`; keys `jitter_ke_initial_J` (total particle kinetic energy `Σ ½ ρ V |v|²` after the
/// first step: the start is at rest), `jitter_ke_peak_J`, `jitter_ke_final_J` (after the last
/// step), and `ke_vs_step.png` in `jitter/`.
fn jitter_run(ctx: &RunCtx, v: &Variants, quick_finest: u32, scene: &Scene, s: &mut Summary) -> Result<()> {
    let finest = v.jitter_finest.map_or(quick_finest, |f| ctx.mode.pick(f.0, f.1, f.2));
    let mut sc = scene.clone();
    sc.resolution.finest = finest;
    sc.particles.sampling_jitter = 0.1;
    sc.duration = f64::from(v.jitter_steps) * sc.flip.dt_max;
    let dir = sub_dir(ctx, "jitter")?;
    let (stats, wall, _) = simulate(&sc, &dir, FrameOutput::NONE, &mut |_, _| {})?;
    let ke: Vec<(f64, f64)> = stats.iter().map(|x| (x.step as f64, x.kinetic_energy)).collect();
    s.set("jitter_ke_initial_J", ke.first().map_or(f64::NAN, |x| x.1));
    s.set("jitter_ke_peak_J", ke.iter().map(|x| x.1).fold(0.0, f64::max));
    s.set("jitter_ke_final_J", ke.last().map_or(f64::NAN, |x| x.1));
    s.set_count("jitter_steps", stats.len() as u64);
    s.set_count("jitter_finest", u64::from(finest));
    s.set("jitter_wall_s", wall);
    let floored = ke.iter().map(|&(k, e)| (k, e.max(1e-30))).collect();
    LinePlot::new("rest pool, jitter 0.1: particle kinetic energy", "step", "kinetic energy (J)")
        .log(false, true)
        .with(Series::new("jitter 0.1", floored))
        .write_png(&dir.join("ke_vs_step.png"))?;
    Ok(())
}

/// The standing-wave scene's mode and its linear theory (spec §6 S3).
#[derive(Clone, Copy, Debug)]
pub(crate) struct WaveTheory {
    /// Mean surface height `H̄` (m, absolute `y`).
    pub mean: f64,
    /// Initial amplitude `A` (m).
    pub amp: f64,
    /// Tank length `L` (m).
    pub len: f64,
    /// Tank start `x0` (m).
    pub x0: f64,
    /// Angular frequency `ω = √(g k tanh(k H))`, `k = π/L` (rad/s).
    pub omega: f64,
    /// Period `2π/ω` (s).
    pub period: f64,
}

impl WaveTheory {
    /// Reads the scene's `CosineSurface` and gravity.
    pub fn of(scene: &Scene) -> Result<Self> {
        let (mean, amp, len, x0) = match scene.liquid.first() {
            Some(Shape::CosineSurface { mean, amplitude, length, x0 }) => (*mean, *amplitude, *length, *x0),
            _ => return Err(Error::Run("standing-wave: the liquid must be a CosineSurface".into())),
        };
        let depth = mean - scene.domain.min[1];
        let g = -scene.gravity[1];
        let k = std::f64::consts::PI / len;
        let omega = (g * k * (k * depth).tanh()).sqrt();
        Ok(Self { mean, amp, len, x0, omega, period: 2.0 * std::f64::consts::PI / omega })
    }

    /// Linear-theory surface height at `x` and time `t` (m).
    pub fn eta(&self, x: f64, t: f64) -> f64 {
        self.mean + self.amp * (std::f64::consts::PI * (x - self.x0) / self.len).cos() * (self.omega * t).cos()
    }
}

/// What one standing-wave run measured.
pub(crate) struct WaveRun {
    /// The theory of the run's scene.
    pub th: WaveTheory,
    /// `(t, η)` at the probe column after every step.
    pub eta: Vec<(f64, f64)>,
    /// Probe `x` (m): `x0 + h_min/2`.
    pub xp: f64,
    /// Period from `metrics::zero_crossing_period` after half a theoretical period (s).
    pub period: Option<f64>,
    /// Damping ratio ζ from `metrics::damping_ratio` (log decrement of the half-cycle extrema of
    /// `η − mean` over the whole run; the partial half cycle before the first crossing is dropped
    /// there). `None` with fewer than three complete half cycles.
    pub damping: Option<f64>,
    /// Per-step statistics.
    pub stats: Vec<StepStats>,
    /// Wall time (s).
    pub wall: f64,
}

impl WaveRun {
    /// `|T_sim − T_th| / T_th` (NaN without a period).
    pub fn period_rel_err(&self) -> f64 {
        self.period.map_or(f64::NAN, |p| (p - self.th.period).abs() / self.th.period)
    }

    /// The linear-theory `η` at the probe at the run's sample times.
    pub fn theory_series(&self) -> Vec<(f64, f64)> {
        self.eta.iter().map(|&(t, _)| (t, self.th.eta(self.xp, t))).collect()
    }
}

/// Runs a standing wave with the §6 S3 probe: `η(t)` at `x = x0 + h_min/2`, mid-`z`.
pub(crate) fn wave_run(scene: &Scene, dir: &Path, every: FrameOutput) -> Result<WaveRun> {
    let th = WaveTheory::of(scene)?;
    let zc = 0.5 * (scene.domain.min[2] + scene.domain.max[2]);
    let mut eta: Vec<(f64, f64)> = Vec::new();
    let mut xp = th.x0;
    let (stats, wall, _) = simulate(scene, dir, every, &mut |sim, st| {
        xp = th.x0 + sim.spec().h_min() / 2.0;
        if let Some(h) = metrics::surface_height(sim, xp, zc) {
            eta.push((st.t, h));
        }
    })?;
    let period = metrics::zero_crossing_period(&eta, 0.5 * th.period);
    let damping = metrics::damping_ratio(&eta, 0.0);
    Ok(WaveRun { th, eta, xp, period, damping, stats, wall })
}

/// `scene` with its cosine surface's mean moved to `depth` above the floor.
pub(crate) fn with_depth(scene: &Scene, depth: f64) -> Result<Scene> {
    let mut s = scene.clone();
    match s.liquid.first_mut() {
        Some(Shape::CosineSurface { mean, .. }) => *mean = s.domain.min[1] + depth,
        _ => return Err(Error::Run("standing-wave: the liquid must be a CosineSurface".into())),
    }
    Ok(s)
}

/// Runs the S3 variants the scene asks for, adds their keys to `s` and returns extra series for
/// `eta_vs_time.png`. `main` is the graded second-order run at the scene's size; when the
/// variants run at another size (`Variants::finest`), a graded second-order reference at their
/// size runs too, so `graded_vs_uniform_period_rel_diff` compares like with like.
pub(crate) fn standing_wave_variants(
    ctx: &RunCtx,
    p: &FtParams,
    scene: &Scene,
    main: &WaveRun,
    s: &mut Summary,
) -> Result<Vec<Series>> {
    let v = &p.variants;
    let every = FrameOutput::surface(p.obj_every);
    let mut series = Vec::new();
    let finest = v.finest_in(ctx.mode, scene.resolution.finest);
    let mut base = scene.clone();
    base.resolution.finest = finest;
    if v.first_order || v.shallow || v.uniform {
        s.set_count("variants_finest", u64::from(finest));
    }
    // The variants compare against the graded second-order wave at their own finest resolution:
    // the main run when the sizes agree, else a reference run in `graded/`.
    let own;
    let graded = if (v.first_order || v.uniform) && finest != scene.resolution.finest {
        own = wave_run(&base, &sub_dir(ctx, "graded")?, every)?;
        s.set("variants_graded_period_rel_err", own.period_rel_err());
        s.set("variants_graded_damping_ratio", own.damping.unwrap_or(f64::NAN));
        s.set("variants_graded_wall_s", own.wall);
        series.push(Series::new(format!("graded second order, finest {finest}"), own.eta.clone()));
        s.set_str(
            "variants_size_note",
            "the S3 variants run at variants_finest (time budget); variants_graded_* is the graded second-order wave at that size",
        );
        &own
    } else {
        main
    };
    if v.first_order {
        let mut sc = base.clone();
        sc.pressure.second_order = false;
        let r = wave_run(&sc, &sub_dir(ctx, "first_order")?, every)?;
        s.set("first_order_period_sim_s", r.period.unwrap_or(f64::NAN));
        s.set("first_order_period_rel_err", r.period_rel_err());
        s.set("first_order_damping_ratio", r.damping.unwrap_or(f64::NAN));
        s.set("first_order_volume_drift_rel", rel_drift(&r.stats, |x| x.vol_levelset));
        s.set("first_order_wall_s", r.wall);
        series.push(Series::new(format!("first-order BC, finest {finest}"), r.eta));
    }
    if v.shallow {
        let sc = with_depth(&base, SHALLOW_DEPTH)?;
        let dir = sub_dir(ctx, "h025")?;
        let r = wave_run(&sc, &dir, every)?;
        s.set("h025_period_theory_s", r.th.period);
        s.set("h025_period_sim_s", r.period.unwrap_or(f64::NAN));
        s.set("h025_period_rel_err", r.period_rel_err());
        s.set("h025_damping_ratio", r.damping.unwrap_or(f64::NAN));
        s.set("h025_wall_s", r.wall);
        LinePlot::new("standing wave, H = 0.25 m: surface height at the wall", "t (s)", "eta (m)")
            .with(Series::new("simulation", r.eta.clone()))
            .with(Series::new("linear theory", r.theory_series()))
            .write_png(&dir.join("eta_vs_time.png"))?;
    }
    if v.uniform {
        let mut sc = base.clone();
        sc.resolution.coarsest = finest;
        let r = wave_run(&sc, &sub_dir(ctx, "uniform")?, every)?;
        s.set("uniform_period_sim_s", r.period.unwrap_or(f64::NAN));
        s.set("uniform_period_rel_err", r.period_rel_err());
        s.set("uniform_damping_ratio", r.damping.unwrap_or(f64::NAN));
        s.set("uniform_wall_s", r.wall);
        let diff = match (graded.period, r.period) {
            (Some(g), Some(u)) => (g - u).abs() / u,
            _ => f64::NAN,
        };
        s.set("graded_vs_uniform_period_rel_diff", diff);
        series.push(Series::new(format!("uniform mesh, finest {finest}"), r.eta));
    }
    Ok(series)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::out::workspace_root;
    use crate::scenes::flip_tet::load_file;

    fn scene_file(name: &str) -> std::path::PathBuf {
        workspace_root().join("scenes/flip-tet").join(name)
    }

    fn tmp(name: &str) -> std::path::PathBuf {
        let d = std::env::temp_dir().join(format!("ft-var-{name}-{}", std::process::id()));
        std::fs::create_dir_all(&d).expect("temp dir");
        d
    }

    /// Absent block = every variant off (opt-in) with the spec's 400 jitter steps; both scene files
    /// parse through the shared loader (the benches use it too) and switch their variants on.
    #[test]
    fn variants_default_off_and_scene_files_parse() {
        let d = Variants::default();
        assert!(!(d.offset_surface || d.pcg || d.first_order || d.jitter || d.shallow || d.uniform));
        assert_eq!(d.jitter_steps, 400);
        let (p, _) = load_file(&scene_file("rest-pool.ron"), Mode::Quick).expect("rest-pool.ron loads");
        let v = &p.variants;
        assert!(v.offset_surface && v.pcg && v.first_order && v.jitter);
        let (p, _) = load_file(&scene_file("standing-wave.ron"), Mode::Quick).expect("standing-wave.ron loads");
        let v = &p.variants;
        assert!(v.first_order && v.shallow && v.uniform);
        let bad: std::result::Result<Variants, _> = ron::from_str("(offset_surface: true, typo: 1)");
        assert!(bad.is_err(), "unknown variant switches are rejected");
    }

    /// Linear theory of the S3 scene: `T_th = 1.1818` s at `H = 0.5` m and `1.3976` s at
    /// `H = 0.25` m (spec §6 S3; tolerance = the spec's rounding to 0.1 ms).
    #[test]
    fn wave_theory_matches_the_spec_periods() {
        let (_, sc) = load_file(&scene_file("standing-wave.ron"), Mode::Quick).expect("loads");
        let th = WaveTheory::of(&sc).expect("cosine surface");
        assert!((th.period - 1.1818).abs() <= 5e-5, "{}", th.period);
        assert_eq!(th.eta(th.x0, 0.0), th.mean + th.amp);
        let shallow = WaveTheory::of(&with_depth(&sc, SHALLOW_DEPTH).expect("cosine")).expect("cosine");
        assert!((shallow.period - 1.3976).abs() <= 5e-5, "{}", shallow.period);
    }

    /// S1b at finest 8 for 12 steps: the offset lattice is an equilibrium with the second-order
    /// conditions (spec §6 S1 bounds: speed ≤ 1e−7 m/s, displacement ≤ 1e−6 m, surface height
    /// error ≤ 1e−6 m at the shifted surface `0.25 + 0.37 · h/2`), while the first-order run moves
    /// (the first air layer lies at two heights): its speed exceeds 1e−4 m/s (measured 2.0e−2 m/s;
    /// second order: 2.3e−16 m/s, height error 5.6e−17 m).
    #[test]
    fn s1b_offset_pool_rests_only_with_second_order() {
        let (_, base) = load_file(&scene_file("rest-pool.ron"), Mode::Quick).expect("loads");
        let (mut sc, target) = s1b_scene(&base, 8).expect("box pool");
        assert_eq!(target, 0.25 + 0.37 * 0.125 / 2.0);
        sc.duration = 12.0 / 120.0;
        let every = FrameOutput::NONE;
        let dir = tmp("s1b");
        let r = rest_run(&sc, &dir, every, Some(target)).expect("second-order run");
        assert!(r.max_speed() <= 1e-7, "{}", r.max_speed());
        assert!(r.max_disp <= 1e-6, "{}", r.max_disp);
        assert!(r.height_err <= 1e-6, "{}", r.height_err);
        sc.pressure.second_order = false;
        let f = rest_run(&sc, &dir, every, None).expect("first-order run");
        assert!(f.max_speed() > 1e-4, "{}", f.max_speed());
        let _ = std::fs::remove_dir_all(&dir);
    }
}

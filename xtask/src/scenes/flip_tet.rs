//! flip-tet's core scenes (spec §6): `rest-pool` (S1), `dam-break` (S2, Martin & Moyce 1952),
//! `standing-wave` (S3, linear theory), `drop-pool` (S4), `holes-plate` (S7) and
//! `adaptivity-payoff` (S10). Each writes `metrics.csv` (one row per step, with the per-stage
//! timings remesh / transfer / solve / advect / surface), OBJ surfaces per frame under `frames/`,
//! PNG plots and the summary keys of issue 5.

use std::path::Path;
use std::time::Instant;

use flip_tet::metrics::{self, CSV_HEADER};
use flip_tet::scene::{Scene, Shape};
use flip_tet::sim::{FlipTetSim, StepStats};
use geom_core::io::{write_obj_frame, MeshOut};
use serde::Deserialize;

use super::flip_tet_snapshots::Snapshots;
use super::flip_tet_variants::{rest_pool_variants, rest_run, standing_wave_variants, wave_run};
use crate::error::{Error, Result};
use crate::out::{Cell, CsvWriter, Summary};
use crate::plot::{LinePlot, Series};
use crate::registry::{RunCtx, Runner};
use crate::scene;

/// Adds flip-tet's core runners.
pub fn register(v: &mut Vec<Runner>) {
    v.push(Runner { method: "flip-tet/rest-pool", run: run_rest_pool });
    v.push(Runner { method: "flip-tet/dam-break", run: run_dam_break });
    v.push(Runner { method: "flip-tet/standing-wave", run: run_standing_wave });
    v.push(Runner { method: "flip-tet/drop-pool", run: run_drop_pool });
    v.push(Runner { method: "flip-tet/holes-plate", run: super::flip_tet_holes::run_holes_plate });
    v.push(Runner { method: "flip-tet/adaptivity-payoff", run: run_adaptivity });
}

fn ft<T>(r: flip_tet::error::Result<T>) -> Result<T> {
    r.map_err(|e| Error::Run(format!("flip-tet: {e}")))
}

/// Parameters shared by the core scenes: the simulator scene plus per-mode sizes.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FtParams {
    /// The flip-tet scene (its `resolution.finest` and `duration` are replaced per mode).
    pub scene: Scene,
    /// Finest resolution for (quick, default, full).
    pub finest: (u32, u32, u32),
    /// Coarsest resolution for (quick, default, full); `None` keeps the scene's.
    #[serde(default)]
    pub coarsest: Option<(u32, u32, u32)>,
    /// Duration (s) for (quick, default, full).
    pub duration: (f64, f64, f64),
    /// Write the simulation surface as OBJ every `obj_every` frames (0 = never).
    #[serde(default = "one")]
    pub obj_every: u64,
    /// Write the particles (positions; `radius`, `velocity`, `phi` per particle) as binary PLY
    /// every `ply_every` frames into `particles/` (0 = never, the default; spec output
    /// `particles_ply`).
    #[serde(default)]
    pub ply_every: u64,
    /// Write the high-resolution output surface (spec §3.11.6: a separate mesh
    /// `surface.output_extra_levels` finer around the surface and the spray) as OBJ every
    /// `hires_every` frames into `frames_hires/` (0 = never, the default: it costs a fine mesh and
    /// a level set per written frame, ≈ 0.8 s at dam-break default).
    #[serde(default)]
    pub hires_every: u64,
    /// adaptivity-payoff: finest resolutions compared for (quick, default, full).
    #[serde(default)]
    pub sizes: Option<(Vec<u32>, Vec<u32>, Vec<u32>)>,
    /// rest-pool / standing-wave: the extra runs of spec §6 S1 / S3 (all off when absent).
    #[serde(default)]
    pub variants: super::flip_tet_variants::Variants,
    /// holes-plate (spec S7): also run the uniform finest mesh and compare the volume passed
    /// through the plate, per mode (quick, default, full); the spec asks for it in full mode only.
    #[serde(default)]
    pub uniform_comparison: Option<(bool, bool, bool)>,
}

fn one() -> u64 {
    1
}

pub(crate) fn load_file(path: &Path, mode: scene::Mode) -> Result<(FtParams, Scene)> {
    let f = scene::load::<FtParams>(path)?;
    let p = f.params;
    let mut s = p.scene.clone();
    s.resolution.finest = mode.pick(p.finest.0, p.finest.1, p.finest.2);
    if let Some(c) = p.coarsest {
        s.resolution.coarsest = mode.pick(c.0, c.1, c.2);
    }
    s.duration = mode.pick(p.duration.0, p.duration.1, p.duration.2);
    Ok((p, s))
}

fn load(ctx: &RunCtx) -> Result<(FtParams, Scene)> {
    load_file(&ctx.scene_file, ctx.mode)
}

/// Runs a scene to its duration, writing `metrics.csv` every step and OBJ frames, calling `probe`
/// after every step. Returns the step statistics and the wall time.
pub(crate) fn simulate(
    scene: &Scene,
    out: &Path,
    every: FrameOutput,
    probe: &mut dyn FnMut(&FlipTetSim, &StepStats),
) -> Result<(Vec<StepStats>, f64, FlipTetSim)> {
    let t0 = Instant::now();
    let mut sim = ft(FlipTetSim::new(scene))?;
    let mut csv = CsvWriter::create(&out.join("metrics.csv"), &CSV_HEADER)?;
    let mut all = Vec::new();
    let mut frame = 0u64;
    let mut snaps = Snapshots::new(scene, out)?;
    let mut write_frame = |sim: &FlipTetSim, frame: u64| -> Result<()> {
        if every.obj > 0 && frame.is_multiple_of(every.obj) {
            if let Some(m) = sim.surface() {
                write_obj_frame(&out.join("frames"), (frame / every.obj) as usize, &MeshOut::from_tri_mesh(&m))?;
            }
        }
        if every.ply > 0 && frame.is_multiple_of(every.ply) {
            write_particles_ply(&out.join("particles"), frame, sim)?;
        }
        if every.hires > 0 && frame.is_multiple_of(every.hires) {
            let o = ft(sim.output_surface())?;
            if o.mesh.n_faces() > 0 {
                write_obj_frame(
                    &out.join("frames_hires"),
                    (frame / every.hires) as usize,
                    &MeshOut::from_tri_mesh(&o.mesh),
                )?;
            }
        }
        snaps.frame(sim, frame)
    };
    write_frame(&sim, 0)?;
    while sim.time() < scene.duration - 1e-9 {
        let st = ft(sim.step())?;
        csv.row(&metrics::csv_row(&st).into_iter().map(Cell::Num).collect::<Vec<_>>())?;
        probe(&sim, &st);
        if st.frame_end {
            frame += 1;
            write_frame(&sim, frame)?;
        }
        all.push(st);
    }
    let wall = t0.elapsed().as_secs_f64();
    snaps.finish()?;
    Ok((all, wall, sim))
}

/// Which frames of a run are written: the simulation surface as OBJ every `obj` frames, the
/// particles as PLY every `ply` frames, the high-resolution output surface (spec §3.11.6) as OBJ
/// every `hires` frames (0 = never).
#[derive(Clone, Copy, Debug)]
pub(crate) struct FrameOutput {
    pub obj: u64,
    pub ply: u64,
    pub hires: u64,
}

impl FrameOutput {
    /// Nothing written (benchmarks, comparison runs).
    pub(crate) const NONE: Self = Self { obj: 0, ply: 0, hires: 0 };

    /// Only the simulation surface, every `obj` frames.
    pub(crate) fn surface(obj: u64) -> Self {
        Self { obj, ..Self::NONE }
    }

    /// What the scene file asks for.
    pub(crate) fn of(p: &FtParams) -> Self {
        Self { obj: p.obj_every, ply: p.ply_every, hires: p.hires_every }
    }
}

/// `dir/particles_NNNN.ply`: the particles as a binary point set with per-particle `radius` (m),
/// `velocity` (m/s) and `phi` (the level set stored at the particle, m).
fn write_particles_ply(dir: &Path, frame: u64, sim: &FlipTetSim) -> Result<()> {
    use geom_core::io::ply::write_points;
    use geom_core::io::{Encoding, PlyData, Positions};
    crate::out::ensure_dir(dir)?;
    let p = sim.particles();
    let props = [("radius", PlyData::F64(&p.r)), ("velocity", PlyData::Vec3(&p.v)), ("phi", PlyData::F64(&p.phi))];
    let path = dir.join(format!("particles_{frame:04}.ply"));
    write_points(path, Positions::F64(&p.x), &props, Encoding::BinaryLittleEndian)?;
    Ok(())
}

fn common(s: &mut Summary, stats: &[StepStats], wall: f64) {
    let steps = stats.len().max(1) as f64;
    let psteps: f64 = stats.iter().map(|x| x.n_particles as f64).sum();
    s.set("wall_s", wall);
    s.set_count("steps", stats.len() as u64);
    s.set("particles_avg", psteps / steps);
    s.set("us_per_particle_step", 1e6 * wall / psteps.max(1.0));
    let mut st = [0.0; 5];
    for x in stats {
        for (a, b) in st.iter_mut().zip(x.timings.stages()) {
            *a += b;
        }
    }
    for (k, v) in ["remesh", "transfer", "solve", "advect", "surface"].iter().zip(st) {
        s.set(&format!("time_{k}_s"), v);
    }
    // The phases inside those stages (profiling aid: which part of a stage dominates).
    let phase = |f: fn(&flip_tet::sim::PhaseTimings) -> f64| stats.iter().map(|x| f(&x.timings)).sum::<f64>();
    s.set("phase_p2g_s", phase(|t| t.p2g));
    s.set("phase_extrapolate_s", phase(|t| t.extrapolate));
    s.set("phase_g2p_s", phase(|t| t.g2p));
    s.set("phase_assemble_s", phase(|t| t.assemble));
    s.set("phase_linear_solve_s", phase(|t| t.solve));
    s.set("phase_advect_s", phase(|t| t.advect));
    s.set("phase_correction_s", phase(|t| t.correction));
    s.set("phase_ballistic_s", phase(|t| t.ballistic));
    s.set_str("profile", if cfg!(debug_assertions) { "debug" } else { "release" });
}

pub(crate) fn rel_drift(stats: &[StepStats], f: impl Fn(&StepStats) -> f64) -> f64 {
    let Some(first) = stats.first() else { return 0.0 };
    let v0 = f(first);
    stats.iter().map(|x| (f(x) - v0).abs()).fold(0.0, f64::max) / v0.abs().max(1e-300)
}

/// S1 (spec §6): S1a, the adaptive lattice pool (second order, the scene's solver), in `out_dir`;
/// then the variants the scene file switches on (`flip_tet_variants`), each in its sub-folder.
fn run_rest_pool(ctx: &RunCtx) -> Result<Summary> {
    let (p, scene) = load(ctx)?;
    let r = rest_run(&scene, &ctx.out_dir, FrameOutput::of(&p), None)?;
    let mut s = Summary::new();
    s.set("max_speed", r.max_speed());
    s.set("volume_drift_rel", rel_drift(&r.stats, |x| x.vol_levelset));
    s.set("particle_volume_drift_rel", rel_drift(&r.stats, |x| x.vol_particles));
    s.set("max_displacement", r.max_disp);
    s.set_count("splits_merges", r.stats.iter().map(|x| (x.n_split + x.n_merge) as u64).sum());
    common(&mut s, &r.stats, r.wall);
    let mut plot = LinePlot::new("rest pool: max particle speed", "step", "max speed (m/s)")
        .log(false, true)
        .with(Series::new("second order, direct", r.speed_series()));
    // Plot S1a now (a long variant run that stops still leaves it), again with the variants.
    plot.write_png(&ctx.out_dir.join("speed_vs_step.png"))?;
    let extra = rest_pool_variants(ctx, &p, &scene, &mut s)?;
    if !extra.is_empty() {
        for e in extra {
            plot = plot.with(e);
        }
        plot.write_png(&ctx.out_dir.join("speed_vs_step.png"))?;
    }
    Ok(s)
}

fn run_dam_break(ctx: &RunCtx) -> Result<Summary> {
    let (p, scene) = load(ctx)?;
    // Column width a: the liquid box's x extent from the wall x = min.
    let a = match scene.liquid.first() {
        Some(Shape::Box { min, max }) => max[0] - min[0],
        _ => return Err(Error::Run("dam-break: the first liquid shape must be the column Box".into())),
    };
    let (wall, floor) = (scene.domain.min[0], scene.domain.min[1]);
    let g = -scene.gravity[1];
    let mut front: Vec<(f64, f64)> = Vec::new();
    let mut height: Vec<(f64, f64)> = Vec::new();
    let (stats, wall_s, _) = simulate(&scene, &ctx.out_dir, FrameOutput::of(&p), &mut |sim, st| {
        let parts = sim.particles();
        front.push((st.t * (2.0 * g / a).sqrt(), metrics::front_position(parts, wall) / a));
        height.push((st.t * (g / a).sqrt(), metrics::column_height(parts, wall, a / 8.0, floor) / (2.0 * a)));
    })?;
    let (errs, rms) = front_errors(&front);
    let mut csv = CsvWriter::create(&ctx.out_dir.join("front_vs_mm.csv"), &["T", "Z_exp", "Z_sim", "rel_err"])?;
    for (&(t, z), e) in metrics::MARTIN_MOYCE_FRONT.iter().zip(&errs) {
        csv.row(&[Cell::Num(t), Cell::Num(z), Cell::Num(z * (1.0 + e)), Cell::Num(*e)])?;
    }
    let mut herr: f64 = 0.0;
    let tau_end = height.last().map_or(0.0, |x| x.0);
    for &(tau, h) in metrics::MARTIN_MOYCE_HEIGHT.iter().filter(|x| x.0 <= tau_end.min(2.5)) {
        herr = herr.max((metrics::interp(&height, tau) - h).abs());
    }
    // Late slope dZ/dT by least squares over T ∈ [2.5, 3.33].
    let late: Vec<(f64, f64)> = front.iter().copied().filter(|x| x.0 >= 2.5 && x.0 <= 3.33).collect();
    let slope = if late.len() > 2 {
        let n = late.len() as f64;
        let (mx, my) = (late.iter().map(|x| x.0).sum::<f64>() / n, late.iter().map(|x| x.1).sum::<f64>() / n);
        let sxy: f64 = late.iter().map(|x| (x.0 - mx) * (x.1 - my)).sum();
        let sxx: f64 = late.iter().map(|x| (x.0 - mx).powi(2)).sum();
        sxy / sxx
    } else {
        f64::NAN
    };
    // Diagnostic only (the pass metric above has no offset): the gate-delay time shift `δ` that
    // minimises the RMS of `Z_sim(T − δ)` against `Z_exp(T)`, searched on [0, 0.6] by 0.005.
    let (shift, rms_shift) = (0..=120)
        .map(|k| {
            let d = 0.005 * f64::from(k);
            let e: Vec<f64> = metrics::MARTIN_MOYCE_FRONT
                .iter()
                .filter(|x| x.0 <= front.last().map_or(0.0, |f| f.0))
                .map(|&(t, z)| (metrics::interp(&front, t - d) - z) / z)
                .collect();
            (d, (e.iter().map(|v| v * v).sum::<f64>() / e.len().max(1) as f64).sqrt())
        })
        .fold((0.0, f64::INFINITY), |b, x| if x.1 < b.1 { x } else { b });
    let mut s = Summary::new();
    s.set("front_rms_rel_err", rms);
    s.set("diag_front_best_gate_delay_T", shift);
    s.set("diag_front_rms_rel_err_with_best_delay", rms_shift);
    s.set("front_max_rel_err", errs.iter().map(|e| e.abs()).fold(0.0, f64::max));
    s.set_count("front_points_compared", errs.len() as u64);
    s.set("height_max_abs_err_tau_le_2_5", herr);
    s.set("late_slope_dZdT", slope);
    s.set("vol_particles_drift_rel", rel_drift(&stats, |x| x.vol_particles));
    s.set("vol_levelset_drift_rel", rel_drift(&stats, |x| x.vol_levelset));
    s.set("column_width_a_m", a);
    s.set_str("time_scaling", "T = t*sqrt(2g/a) (front), tau = t*sqrt(g/a) (height), a = column width");
    common(&mut s, &stats, wall_s);
    LinePlot::new("dam break: surge front vs Martin & Moyce (1952)", "T = t sqrt(2g/a)", "Z = x/a")
        .with(Series::new("simulation", front.clone()))
        .with(Series::new("Martin & Moyce 1952", metrics::MARTIN_MOYCE_FRONT.to_vec()))
        .write_png(&ctx.out_dir.join("front_vs_mm.png"))?;
    LinePlot::new("dam break: residual column height", "tau = t sqrt(g/a)", "H = h/(2a)")
        .with(Series::new("simulation", height))
        .with(Series::new("Martin & Moyce 1952", metrics::MARTIN_MOYCE_HEIGHT.to_vec()))
        .write_png(&ctx.out_dir.join("height_vs_mm.png"))?;
    Ok(s)
}

/// Relative front errors `(Z_sim − Z_exp)/Z_exp` at the tabulated Martin & Moyce times covered by
/// the simulated series `(T, Z)`, and their RMS.
pub(crate) fn front_errors(front: &[(f64, f64)]) -> (Vec<f64>, f64) {
    let t_end = front.last().map_or(0.0, |x| x.0);
    let errs: Vec<f64> = metrics::MARTIN_MOYCE_FRONT
        .iter()
        .filter(|x| x.0 <= t_end)
        .map(|&(t, z)| (metrics::interp(front, t) - z) / z)
        .collect();
    let rms = (errs.iter().map(|e| e * e).sum::<f64>() / errs.len().max(1) as f64).sqrt();
    (errs, rms)
}

/// S3 (spec §6): the depth-graded second-order wave in `out_dir`, period and damping ratio vs
/// linear theory; then the variants the scene file switches on (`flip_tet_variants`).
fn run_standing_wave(ctx: &RunCtx) -> Result<Summary> {
    let (p, scene) = load(ctx)?;
    let r = wave_run(&scene, &ctx.out_dir, FrameOutput::of(&p))?;
    let mut s = Summary::new();
    s.set("period_theory_s", r.th.period);
    s.set("period_sim_s", r.period.unwrap_or(f64::NAN));
    s.set("period_rel_err", r.period_rel_err());
    s.set("amplitude_initial_m", r.th.amp);
    s.set("damping_ratio", r.damping.unwrap_or(f64::NAN));
    s.set("volume_drift_rel", rel_drift(&r.stats, |x| x.vol_levelset));
    common(&mut s, &r.stats, r.wall);
    let mut plot = LinePlot::new("standing wave: surface height at the wall", "t (s)", "eta (m)")
        .with(Series::new("simulation", r.eta.clone()))
        .with(Series::new("linear theory", r.theory_series()));
    plot.write_png(&ctx.out_dir.join("eta_vs_time.png"))?;
    let extra = standing_wave_variants(ctx, &p, &scene, &r, &mut s)?;
    if !extra.is_empty() {
        for e in extra {
            plot = plot.with(e);
        }
        plot.write_png(&ctx.out_dir.join("eta_vs_time.png"))?;
    }
    Ok(s)
}

/// Liquid volume of the scene's initial shapes estimated by sampling on a fine grid (m³).
fn initial_liquid_volume(scene: &Scene, n: usize) -> f64 {
    let (mn, mx) = (scene.min(), scene.max());
    let d = (mx - mn) / n as f64;
    let mut c = 0usize;
    for i in 0..n {
        for j in 0..n {
            for k in 0..n {
                let x = mn
                    + geom_core::math::Vec3::new(
                        (i as f64 + 0.5) * d.x,
                        (j as f64 + 0.5) * d.y,
                        (k as f64 + 0.5) * d.z,
                    );
                if scene.liquid_sdf(&x) < 0.0 && scene.solid_sdf(&x) > 0.0 {
                    c += 1;
                }
            }
        }
    }
    c as f64 * d.x * d.y * d.z
}

fn run_drop_pool(ctx: &RunCtx) -> Result<Summary> {
    let (p, scene) = load(ctx)?;
    let (stats, wall, _) = simulate(&scene, &ctx.out_dir, FrameOutput::of(&p), &mut |_, _| {})?;
    drop_pool_summary(&scene, &stats, wall, &ctx.out_dir)
}

/// The drop-pool figures of a finished run (spec S4; also S7's): particle counts against the
/// uniform estimate, the ballistic fraction, the Pearson correlation of step time (remesh
/// excluded) with the particle count, the level-set volume drift, and `particles_vs_time.png`.
pub(crate) fn drop_pool_summary(scene: &Scene, stats: &[StepStats], wall: f64, out_dir: &Path) -> Result<Summary> {
    let n0 = stats.first().map_or(0, |x| x.n_particles) as f64;
    let peak = stats.iter().map(|x| x.n_particles).max().unwrap_or(0) as f64;
    let end = stats.last().map_or(0, |x| x.n_particles) as f64;
    let h_min = (0..3).map(|a| scene.domain.max[a] - scene.domain.min[a]).fold(0.0, f64::max)
        / f64::from(scene.resolution.finest);
    let uniform = 8.0 * initial_liquid_volume(scene, 128) / h_min.powi(3);
    let ballistic: f64 = stats.iter().map(|x| x.n_ballistic as f64 / x.n_particles.max(1) as f64).sum::<f64>()
        / stats.len().max(1) as f64;
    // Pearson correlation of per-step wall time (remesh excluded) with particle count.
    let xs: Vec<f64> = stats.iter().map(|x| x.n_particles as f64).collect();
    let ys: Vec<f64> = stats.iter().map(|x| x.timings.total() - x.timings.remesh).collect();
    let n = xs.len().max(1) as f64;
    let (mx, my) = (xs.iter().sum::<f64>() / n, ys.iter().sum::<f64>() / n);
    let cov: f64 = xs.iter().zip(&ys).map(|(a, b)| (a - mx) * (b - my)).sum();
    let (vx, vy) = (xs.iter().map(|a| (a - mx).powi(2)).sum::<f64>(), ys.iter().map(|b| (b - my).powi(2)).sum::<f64>());
    let mut s = Summary::new();
    s.set("particles_initial", n0);
    s.set("particles_peak", peak);
    s.set("particles_end", end);
    s.set("peak_over_initial", peak / n0.max(1.0));
    s.set("end_over_initial", end / n0.max(1.0));
    s.set("uniform_particles_estimate", uniform);
    s.set("uniform_over_adaptive_initial", uniform / n0.max(1.0));
    s.set("ballistic_fraction_avg", ballistic);
    s.set("time_particles_pearson", if vx > 0.0 && vy > 0.0 { cov / (vx * vy).sqrt() } else { f64::NAN });
    s.set("vol_levelset_drift_rel", rel_drift(stats, |x| x.vol_levelset));
    common(&mut s, stats, wall);
    let pts: Vec<(f64, f64)> = stats.iter().map(|x| (x.t, x.n_particles as f64)).collect();
    LinePlot::new("particles vs time", "t (s)", "particles")
        .with(Series::new("adaptive", pts))
        .write_png(&out_dir.join("particles_vs_time.png"))?;
    Ok(s)
}

fn run_adaptivity(ctx: &RunCtx) -> Result<Summary> {
    let (p, base) = load(ctx)?;
    let sizes = p.sizes.clone().ok_or_else(|| Error::Run("adaptivity-payoff: `sizes` is required".into()))?;
    let list = ctx.mode.pick(sizes.0, sizes.1, sizes.2);
    let mut csv = CsvWriter::create(
        &ctx.out_dir.join("cost_vs_n.csv"),
        &["finest", "variant", "particle_steps", "particles_avg", "wall_s", "steps"],
    )?;
    let mut s = Summary::new();
    let mut cost = (Vec::new(), Vec::new());
    let mut parts = (Vec::new(), Vec::new());
    let mut last = (0.0, 0.0, 0.0, 0.0);
    for &n in &list {
        for adaptive in [true, false] {
            let mut sc = base.clone();
            sc.resolution.finest = n;
            if !adaptive {
                sc.resolution.coarsest = n;
            }
            let dir = ctx.out_dir.join(format!("{}_{n}", if adaptive { "adaptive" } else { "uniform" }));
            crate::out::ensure_dir(&dir)?;
            let (stats, wall, _) = simulate(&sc, &dir, FrameOutput::NONE, &mut |_, _| {})?;
            let ps: f64 = stats.iter().map(|x| x.n_particles as f64).sum();
            let avg = ps / stats.len().max(1) as f64;
            csv.row(&[
                Cell::Int(i64::from(n)),
                Cell::Text(if adaptive { "adaptive" } else { "uniform" }.into()),
                Cell::Num(ps),
                Cell::Num(avg),
                Cell::Num(wall),
                Cell::Int(stats.len() as i64),
            ])?;
            let sim_t = stats.last().map_or(1.0, |x| x.t).max(1e-9);
            if adaptive {
                cost.0.push((f64::from(n), wall / sim_t));
                parts.0.push((f64::from(n), avg));
                last.0 = avg;
                last.2 = wall;
            } else {
                cost.1.push((f64::from(n), wall / sim_t));
                parts.1.push((f64::from(n), avg));
                last.1 = avg;
                last.3 = wall;
            }
        }
    }
    s.set("finest_compared", f64::from(*list.last().unwrap_or(&0)));
    s.set("particle_ratio_adaptive_over_uniform", last.0 / last.1.max(1.0));
    s.set("time_ratio_adaptive_over_uniform", last.2 / last.3.max(1e-12));
    s.set_str("profile", if cfg!(debug_assertions) { "debug" } else { "release" });
    let beta = |v: &Vec<(f64, f64)>| {
        if v.len() >= 2 {
            (v[v.len() - 1].1 / v[0].1).ln() / (v[v.len() - 1].0 / v[0].0).ln()
        } else {
            f64::NAN
        }
    };
    s.set("beta_particles_adaptive", beta(&parts.0));
    s.set("beta_particles_uniform", beta(&parts.1));
    s.set("alpha_cost_adaptive", beta(&cost.0));
    s.set("alpha_cost_uniform", beta(&cost.1));
    LinePlot::new("cost vs finest resolution", "N", "wall s per simulated s")
        .log(true, true)
        .with(Series::new("adaptive", cost.0))
        .with(Series::new("uniform", cost.1))
        .write_png(&ctx.out_dir.join("cost_vs_N.png"))?;
    LinePlot::new("particles vs finest resolution", "N", "particles (avg)")
        .log(true, true)
        .with(Series::new("adaptive", parts.0))
        .with(Series::new("uniform", parts.1))
        .write_png(&ctx.out_dir.join("particles_vs_N.png"))?;
    Ok(s)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `ply_every: 1` writes one particle PLY per frame that reads back with the simulator's
    /// particles: positions, radius, velocity and φ equal (binary little-endian f64: exact).
    #[test]
    fn particles_ply_round_trip() {
        let text = r#"(domain: (min: (0.0, 0.0, 0.0), max: (0.5, 0.5, 0.5)),
            resolution: (coarsest: 4, finest: 8), duration: 0.05, fps: 40.0,
            liquid: [Box(min: (0.0, 0.0, 0.0), max: (0.5, 0.125, 0.5))])"#;
        let scene: Scene = ron::from_str(text).expect("scene");
        let dir = std::env::temp_dir().join(format!("ft-ply-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("dir");
        let (_, _, sim) =
            simulate(&scene, &dir, FrameOutput { ply: 1, ..FrameOutput::NONE }, &mut |_, _| {}).expect("short run");
        for f in 0..=2 {
            assert!(dir.join(format!("particles/particles_{f:04}.ply")).is_file(), "frame {f}");
        }
        let back = geom_core::io::ply::read_data(dir.join("particles/particles_0002.ply")).expect("reads back");
        let p = sim.particles();
        assert_eq!(back.positions, p.x);
        assert_eq!(back.prop("radius").expect("radius"), p.r.as_slice());
        assert_eq!(back.prop("phi").expect("phi"), p.phi.as_slice());
        let vy: Vec<f64> = p.v.iter().map(|v| v.y).collect();
        assert_eq!(back.prop("velocity_y").expect("velocity_y"), vy.as_slice());
        let _ = std::fs::remove_dir_all(&dir);
    }

    /// `hires_every: 2` writes the output surface of frames 0 and 2 into `frames_hires/` (OBJ
    /// 0000 and 0001), each with more triangles than the simulation surface of the same frame.
    #[test]
    fn hires_frames_are_written_and_finer() {
        let text = r#"(domain: (min: (0.0, 0.0, 0.0), max: (0.5, 0.5, 0.5)),
            resolution: (coarsest: 4, finest: 8), duration: 0.05, fps: 40.0,
            liquid: [Box(min: (0.0, 0.0, 0.0), max: (0.25, 0.25, 0.5))])"#;
        let scene: Scene = ron::from_str(text).expect("scene");
        let dir = std::env::temp_dir().join(format!("ft-hires-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("dir");
        simulate(&scene, &dir, FrameOutput { obj: 2, ply: 0, hires: 2 }, &mut |_, _| {}).expect("short run");
        for f in 0..=1 {
            let sim = geom_core::io::obj::read(dir.join(format!("frames/{f:04}.obj"))).expect("simulation frame");
            let hi = geom_core::io::obj::read(dir.join(format!("frames_hires/{f:04}.obj"))).expect("hires frame");
            assert!(hi.faces.len() > sim.faces.len(), "frame {f}: {} vs {}", hi.faces.len(), sim.faces.len());
        }
        let _ = std::fs::remove_dir_all(&dir);
    }
}

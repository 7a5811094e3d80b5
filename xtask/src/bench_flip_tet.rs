//! `cargo xtask bench flip-tet [--sweep <knob>]` (spec §9): accuracy against time. Without
//! `--sweep` the four sweeps the issue names run:
//! `resolution` (dam break, RMS front error vs Martin & Moyce 1952),
//! `levels` (adaptivity levels at a fixed finest resolution: coarsest = finest … 8; same error),
//! `tol` (rest pool: max speed and level-set volume drift; direct vs MIC(0)-PCG at tolerances
//!   1e−2 … 1e−8),
//! `bc` (free-surface boundary order: dam-break front error, and outside `--quick` the
//!   standing-wave period error).
//! Selectable with `--sweep` (or all of them with `--sweep all`): `solver` (direct, MIC(0)-PCG and
//! Jacobi-PCG: linear-solve time per step against DOFs on the rest pool), `remesh` (remesh
//! interval: dam-break front error and cost), `cfl` (CFL number with `dt_max` lifted to the frame
//! time so that the CFL rule sets the step: front error and level-set volume drift), `pic` (PIC
//! fraction: standing-wave period error and damping ratio, rest-pool noise) and `surface` (surface
//! method: kinetic energy of a jittered rest pool after 200 steps).
//! Writes `accuracy_vs_time.csv` (one row per setting and metric), `pareto.png` (dam-break front
//! error against wall time per knob) and one PNG per selected extra sweep, and returns summary
//! figures.

use std::path::Path;

use flip_tet::error::SolverKind;
use flip_tet::metrics;
use flip_tet::scene::Scene;

use crate::error::Result;
use crate::out::{Cell, CsvWriter, Summary};
use crate::plot::{LinePlot, Series};
use crate::registry::BenchCtx;
use crate::scene::{scenes_dir, Mode};
use crate::scenes::flip_tet::{front_errors, load_file, simulate, FrameOutput};

struct Row {
    knob: &'static str,
    value: String,
    wall: f64,
    steps: usize,
    particles: f64,
    metric: &'static str,
    error: f64,
}

/// The sweeps `--sweep` can select (besides `all`); the first four are the default set.
pub const SWEEPS: &[&str] = &["resolution", "levels", "tol", "bc", "solver", "remesh", "cfl", "pic", "surface"];

/// Dam break run: (RMS front error, wall s, steps, mean particles).
fn dam_break(scene: &Scene, dir: &Path) -> Result<(f64, f64, usize, f64)> {
    dam_break_full(scene, dir).map(|d| (d.rms, d.wall, d.steps, d.particles))
}

/// One dam-break run's figures.
struct DamRun {
    /// RMS relative front error against Martin & Moyce.
    rms: f64,
    /// Wall time (s).
    wall: f64,
    /// Time steps taken.
    steps: usize,
    /// Mean particle count.
    particles: f64,
    /// Largest |V_levelset − V_0| / V_0 over the run.
    vol_drift: f64,
}

fn dam_break_full(scene: &Scene, dir: &Path) -> Result<DamRun> {
    let a = match scene.liquid.first() {
        Some(flip_tet::scene::Shape::Box { min, max }) => max[0] - min[0],
        _ => 0.05715,
    };
    let g = -scene.gravity[1];
    let mut front = Vec::new();
    let (stats, wall, _) = simulate(scene, dir, FrameOutput::NONE, &mut |sim, st| {
        front.push((st.t * (2.0 * g / a).sqrt(), metrics::front_position(sim.particles(), scene.domain.min[0]) / a));
    })?;
    let (_, rms) = front_errors(&front);
    let pavg = stats.iter().map(|x| x.n_particles as f64).sum::<f64>() / stats.len().max(1) as f64;
    Ok(DamRun { rms, wall, steps: stats.len(), particles: pavg, vol_drift: vol_drift(&stats) })
}

/// Largest relative drift of the level-set volume from the first step's.
fn vol_drift(stats: &[flip_tet::sim::StepStats]) -> f64 {
    let v0 = stats.first().map_or(1.0, |x| x.vol_levelset);
    stats.iter().map(|x| (x.vol_levelset - v0).abs()).fold(0.0, f64::max) / v0.max(1e-300)
}

fn rest(scene: &Scene, dir: &Path) -> Result<(f64, f64, f64, usize)> {
    let (stats, wall, _) = simulate(scene, dir, FrameOutput::NONE, &mut |_, _| {})?;
    let vmax = stats.iter().map(|x| x.max_speed).fold(0.0, f64::max);
    Ok((vmax, vol_drift(&stats), wall, stats.len()))
}

/// One standing-wave run's figures.
struct WaveRun {
    /// |T_sim − T_th| / T_th.
    period_err: f64,
    /// Damping ratio ζ of η at the wall (log decrement, [`metrics::damping_ratio`]).
    zeta: f64,
    /// Wall time (s).
    wall: f64,
    /// Time steps taken.
    steps: usize,
}

fn wave_full(scene: &Scene, dir: &Path) -> Result<WaveRun> {
    let (mean, len) = match scene.liquid.first() {
        Some(flip_tet::scene::Shape::CosineSurface { mean, length, .. }) => (*mean, *length),
        _ => (0.5, 1.0),
    };
    let k = std::f64::consts::PI / len;
    let g = -scene.gravity[1];
    let t_th = 2.0 * std::f64::consts::PI / (g * k * (k * (mean - scene.domain.min[1])).tanh()).sqrt();
    let zc = 0.5 * (scene.domain.min[2] + scene.domain.max[2]);
    let mut eta = Vec::new();
    let (stats, wall, _) = simulate(scene, dir, FrameOutput::NONE, &mut |sim, st| {
        if let Some(h) = metrics::surface_height(sim, scene.domain.min[0] + sim.spec().h_min() / 2.0, zc) {
            eta.push((st.t, h));
        }
    })?;
    let p = metrics::zero_crossing_period(&eta, 0.5 * t_th).map_or(f64::NAN, |p| (p - t_th).abs() / t_th);
    let zeta = metrics::damping_ratio(&eta, 0.5 * t_th).unwrap_or(f64::NAN);
    Ok(WaveRun { period_err: p, zeta, wall, steps: stats.len() })
}

/// What every sweep needs: the mode, the loaded base scenes and where runs write.
struct Ctx {
    quick: bool,
    dam: Scene,
    dir: std::path::PathBuf,
    tmp: std::path::PathBuf,
}

impl Ctx {
    /// The scene file `scenes/flip-tet/<name>.ron` at the quick size.
    fn quick_scene(&self, name: &str) -> Result<Scene> {
        Ok(load_file(&self.dir.join(format!("{name}.ron")), Mode::Quick)?.1)
    }

    /// The standing wave at the quick resolution but the default duration (3.6 s ≈ 3 periods), so
    /// that the damping ratio has enough half cycles after the first half period.
    fn wave_scene(&self) -> Result<Scene> {
        let path = self.dir.join("standing-wave.ron");
        let mut w = load_file(&path, Mode::Quick)?.1;
        w.duration = load_file(&path, Mode::Default)?.1.duration;
        Ok(w)
    }
}

/// The rows and summary figures the sweeps accumulate.
struct Out {
    rows: Vec<Row>,
    summary: Summary,
}

impl Out {
    #[allow(clippy::too_many_arguments)]
    fn row(
        &mut self,
        knob: &'static str,
        value: &str,
        wall: f64,
        steps: usize,
        particles: f64,
        metric: &'static str,
        error: f64,
    ) {
        self.rows.push(Row { knob, value: value.to_string(), wall, steps, particles, metric, error });
    }
}

/// The benchmark entry point.
pub fn run(ctx: &BenchCtx) -> Result<Summary> {
    let dir = scenes_dir().join("flip-tet");
    let mode = if ctx.quick { Mode::Quick } else { Mode::Default };
    let (_, dam) = load_file(&dir.join("dam-break.ron"), mode)?;
    let c = Ctx { quick: ctx.quick, dam, dir, tmp: ctx.out_dir.join("runs") };
    let mut out = Out { rows: Vec::new(), summary: Summary::new() };
    out.summary.set_str("profile", if cfg!(debug_assertions) { "debug" } else { "release" });
    let selected: Vec<&str> = match ctx.sweep.as_deref() {
        None => SWEEPS[..4].to_vec(),
        Some("all") => SWEEPS.to_vec(),
        Some(k) => vec![k],
    };
    out.summary.set_str("sweeps", &selected.join(","));
    for knob in &selected {
        match *knob {
            "resolution" => sweep_resolution(&c, &mut out)?,
            "levels" => sweep_levels(&c, &mut out)?,
            "tol" => sweep_tol(&c, &mut out)?,
            "bc" => sweep_bc(&c, &mut out)?,
            "solver" => sweep_solver(&c, &mut out, &ctx.out_dir)?,
            "remesh" => sweep_remesh(&c, &mut out)?,
            "cfl" => sweep_cfl(&c, &mut out)?,
            "pic" => sweep_pic(&c, &mut out, &ctx.out_dir)?,
            "surface" => sweep_surface(&c, &mut out, &ctx.out_dir)?,
            other => {
                return Err(crate::error::Error::Usage(format!(
                    "no flip-tet sweep '{other}'; known: {}",
                    SWEEPS.join(", ")
                )))
            }
        }
    }
    write_outputs(&out.rows, &ctx.out_dir)?;
    Ok(out.summary)
}

/// `resolution`: dam break at finest 16, 32 (and 64 outside `--quick`).
fn sweep_resolution(c: &Ctx, o: &mut Out) -> Result<()> {
    let res: &[u32] = if c.quick { &[16, 32] } else { &[16, 32, 64] };
    for &n in res {
        let mut s = c.dam.clone();
        s.resolution.finest = n;
        let (rms, wall, steps, p) = dam_break(&s, &c.tmp.join(format!("res_{n}")))?;
        o.row("resolution", &n.to_string(), wall, steps, p, "front_rms_rel_err", rms);
        o.summary.set(&format!("dam_front_rms_finest_{n}"), rms);
    }
    Ok(())
}

/// `levels`: dam break with coarsest = finest, finest/2 and 8 at a fixed finest (32 quick, 64).
fn sweep_levels(c: &Ctx, o: &mut Out) -> Result<()> {
    let finest = if c.quick { 32 } else { 64 };
    for coarsest in [finest, finest / 2, 8] {
        let mut s = c.dam.clone();
        s.resolution.finest = finest;
        s.resolution.coarsest = coarsest;
        let (rms, wall, steps, p) = dam_break(&s, &c.tmp.join(format!("levels_{coarsest}")))?;
        o.row("levels", &format!("{coarsest}-{finest}"), wall, steps, p, "front_rms_rel_err", rms);
    }
    Ok(())
}

/// `tol`: rest pool (quick size) with the direct solver and MIC(0)-PCG at several tolerances.
fn sweep_tol(c: &Ctx, o: &mut Out) -> Result<()> {
    let pool = c.quick_scene("rest-pool")?;
    let tols: &[f64] = if c.quick { &[1e-2, 1e-6] } else { &[1e-2, 1e-3, 1e-4, 1e-6, 1e-8] };
    let mut variants: Vec<(String, SolverKind, f64)> = vec![("direct".into(), SolverKind::DirectCholesky, 1e-6)];
    variants.extend(tols.iter().map(|&t| (format!("mic_pcg_{t:e}"), SolverKind::PcgIc0, t)));
    for (name, kind, tol) in variants {
        let mut s = pool.clone();
        s.pressure.solver = kind;
        s.pressure.tol = tol;
        let (vmax, drift, wall, steps) = rest(&s, &c.tmp.join(format!("tol_{name}")))?;
        o.row("solver_tol", &name, wall, steps, 0.0, "rest_max_speed", vmax);
        o.row("solver_tol", &name, wall, steps, 0.0, "rest_volume_drift_rel", drift);
        o.summary.set(&format!("rest_max_speed_{name}"), vmax);
    }
    Ok(())
}

/// `bc`: first- vs second-order free surface on the dam break at finest 32 (and outside `--quick`
/// the standing wave's period error and damping ratio, quick resolution, 3.6 s).
fn sweep_bc(c: &Ctx, o: &mut Out) -> Result<()> {
    for second in [true, false] {
        let mut s = c.dam.clone();
        s.resolution.finest = 32;
        s.pressure.second_order = second;
        let tag = if second { "second" } else { "first" };
        let (rms, wall, steps, p) = dam_break(&s, &c.tmp.join(format!("bc_{tag}")))?;
        o.row("bc_order", tag, wall, steps, p, "front_rms_rel_err", rms);
        o.summary.set(&format!("dam_front_rms_{tag}_order"), rms);
        if !c.quick {
            let mut w = c.wave_scene()?;
            w.pressure.second_order = second;
            let r = wave_full(&w, &c.tmp.join(format!("wave_{tag}")))?;
            o.row("bc_order", tag, r.wall, r.steps, 0.0, "wave_period_rel_err", r.period_err);
            o.row("bc_order", tag, r.wall, r.steps, 0.0, "wave_damping_ratio", r.zeta);
            o.summary.set(&format!("wave_period_rel_err_{tag}_order"), r.period_err);
            o.summary.set(&format!("wave_damping_ratio_{tag}_order"), r.zeta);
        }
    }
    Ok(())
}

/// `solver`: linear-solve time per step against DOFs for the direct solver, MIC(0)-PCG and
/// Jacobi-PCG (tolerance 1e−6) on the rest pool at finest 16, 32 (and 64 outside `--quick`),
/// 40 steps each; the error column is the run's max particle speed (m/s).
fn sweep_solver(c: &Ctx, o: &mut Out, out_dir: &Path) -> Result<()> {
    let pool = c.quick_scene("rest-pool")?;
    let res: &[u32] = if c.quick { &[16, 32] } else { &[16, 32, 64] };
    let kinds = [
        ("direct", SolverKind::DirectCholesky),
        ("mic_pcg", SolverKind::PcgIc0),
        ("jacobi_pcg", SolverKind::PcgJacobi),
    ];
    let mut plot = LinePlot::new("flip-tet: pressure solve time vs DOFs (rest pool)", "DOFs (mean)", "ms per solve")
        .log(true, true);
    for (name, kind) in kinds {
        let mut pts = Vec::new();
        for &n in res {
            let mut s = pool.clone();
            s.resolution.finest = n;
            s.duration = 40.0 * s.flip.dt_max;
            s.pressure.solver = kind;
            s.pressure.tol = 1e-6;
            let (stats, wall, _) =
                simulate(&s, &c.tmp.join(format!("solver_{name}_{n}")), FrameOutput::NONE, &mut |_, _| {})?;
            let k = stats.len().max(1) as f64;
            let dofs = stats.iter().map(|x| x.n_dofs as f64).sum::<f64>() / k;
            let ms = 1e3 * stats.iter().map(|x| x.timings.solve).sum::<f64>() / k;
            let vmax = stats.iter().map(|x| x.max_speed).fold(0.0, f64::max);
            o.row("solver", &format!("{name}_{n}"), wall, stats.len(), dofs, "rest_max_speed", vmax);
            o.summary.set(&format!("solve_ms_{name}_finest_{n}"), ms);
            o.summary.set(&format!("solve_dofs_finest_{n}"), dofs);
            pts.push((dofs, ms.max(1e-6)));
        }
        plot = plot.with(Series::new(name, pts));
    }
    plot.write_png(&out_dir.join("solver_kind.png"))?;
    Ok(())
}

/// `remesh`: dam break (finest 32) with the remesh interval 1, 5, 10, 20 (quick: 1, 10).
fn sweep_remesh(c: &Ctx, o: &mut Out) -> Result<()> {
    let ks: &[u32] = if c.quick { &[1, 10] } else { &[1, 5, 10, 20] };
    for &k in ks {
        let mut s = c.dam.clone();
        s.resolution.finest = 32;
        s.flip.remesh_interval = k;
        let d = dam_break_full(&s, &c.tmp.join(format!("remesh_{k}")))?;
        o.row("remesh", &k.to_string(), d.wall, d.steps, d.particles, "front_rms_rel_err", d.rms);
        o.summary.set(&format!("dam_front_rms_remesh_{k}"), d.rms);
        o.summary.set(&format!("dam_wall_s_remesh_{k}"), d.wall);
    }
    Ok(())
}

/// `cfl`: dam break (finest 32) with CFL 0.5, 1, 2, 4 (quick: 0.5, 2); `dt_max` is lifted to one
/// frame so that the CFL rule, not the cap, sets the step. Front error and level-set volume drift.
fn sweep_cfl(c: &Ctx, o: &mut Out) -> Result<()> {
    let cs: &[f64] = if c.quick { &[0.5, 2.0] } else { &[0.5, 1.0, 2.0, 4.0] };
    for &cfl in cs {
        let mut s = c.dam.clone();
        s.resolution.finest = 32;
        s.flip.cfl = cfl;
        s.flip.dt_max = 1.0 / s.fps;
        let d = dam_break_full(&s, &c.tmp.join(format!("cfl_{cfl}")))?;
        o.row("cfl", &cfl.to_string(), d.wall, d.steps, d.particles, "front_rms_rel_err", d.rms);
        o.row("cfl", &cfl.to_string(), d.wall, d.steps, d.particles, "levelset_volume_drift_rel", d.vol_drift);
        o.summary.set(&format!("dam_front_rms_cfl_{cfl}"), d.rms);
        o.summary.set(&format!("dam_volume_drift_cfl_{cfl}"), d.vol_drift);
        o.summary.set_count(&format!("dam_steps_cfl_{cfl}"), d.steps as u64);
    }
    Ok(())
}

/// `pic`: PIC fraction `pic_base` 0, 0.01, 0.03, 0.1 (quick: 0, 0.03; `pic_floor` capped at it) on
/// the standing wave (quick resolution, 3.6 s: period error and damping ratio ζ) and on a rest
/// pool (quick size) jittered by 0.1 of the spacing (noise: the max particle speed over the last
/// tenth of the run).
fn sweep_pic(c: &Ctx, o: &mut Out, out_dir: &Path) -> Result<()> {
    let ps: &[f64] = if c.quick { &[0.0, 0.03] } else { &[0.0, 0.01, 0.03, 0.1] };
    let (wave0, pool0) = (c.wave_scene()?, c.quick_scene("rest-pool")?);
    let mut zetas = Vec::new();
    for &pic in ps {
        let set = |s: &mut Scene| {
            s.flip.pic_base = pic;
            s.flip.pic_floor = s.flip.pic_floor.min(pic);
        };
        let mut w = wave0.clone();
        set(&mut w);
        let r = wave_full(&w, &c.tmp.join(format!("pic_wave_{pic}")))?;
        o.row("pic", &pic.to_string(), r.wall, r.steps, 0.0, "wave_period_rel_err", r.period_err);
        o.row("pic", &pic.to_string(), r.wall, r.steps, 0.0, "wave_damping_ratio", r.zeta);
        o.summary.set(&format!("wave_period_rel_err_pic_{pic}"), r.period_err);
        o.summary.set(&format!("wave_damping_ratio_pic_{pic}"), r.zeta);
        zetas.push((r.wall, r.zeta));
        let mut p = pool0.clone();
        set(&mut p);
        p.particles.sampling_jitter = 0.1;
        let (stats, wall, _) = simulate(&p, &c.tmp.join(format!("pic_rest_{pic}")), FrameOutput::NONE, &mut |_, _| {})?;
        let tail = &stats[stats.len() - (stats.len() / 10).max(1)..];
        let noise = tail.iter().map(|x| x.max_speed).fold(0.0, f64::max);
        o.row("pic", &pic.to_string(), wall, stats.len(), 0.0, "rest_jitter_late_max_speed", noise);
        o.summary.set(&format!("rest_jitter_late_max_speed_pic_{pic}"), noise);
    }
    let pts: Vec<(f64, f64)> = ps.iter().zip(&zetas).map(|(&p, &(_, z))| (p, z)).collect();
    LinePlot::new("flip-tet: standing-wave damping ratio vs PIC fraction", "pic_base", "damping ratio")
        .with(Series::new("zeta", pts))
        .write_png(&out_dir.join("pic_damping.png"))?;
    Ok(())
}

/// `surface`: the simulation's surface method (Hulls, ZhuBridson, SphereUnion) on a rest pool
/// (quick size) jittered by 0.1 of the spacing, 200 steps: kinetic energy at the end (J) against
/// wall time (spec §9: "only Hulls settles flat with mixed radii").
fn sweep_surface(c: &Ctx, o: &mut Out, out_dir: &Path) -> Result<()> {
    use flip_tet::surface::SurfaceMethod;
    let pool = c.quick_scene("rest-pool")?;
    let mut pts = Vec::new();
    for (name, m) in [
        ("hulls", SurfaceMethod::Hulls),
        ("zhu_bridson", SurfaceMethod::ZhuBridson),
        ("sphere_union", SurfaceMethod::SphereUnion),
    ] {
        let mut s = pool.clone();
        s.surface.method = m;
        s.particles.sampling_jitter = 0.1;
        s.duration = 200.0 * s.flip.dt_max;
        let (stats, wall, _) = simulate(&s, &c.tmp.join(format!("surface_{name}")), FrameOutput::NONE, &mut |_, _| {})?;
        let ke = stats.last().map_or(f64::NAN, |x| x.kinetic_energy);
        o.row("surface", name, wall, stats.len(), 0.0, "rest_jitter_final_ke_J", ke);
        o.summary.set(&format!("rest_jitter_final_ke_J_{name}"), ke);
        o.summary.set(&format!("rest_jitter_wall_s_{name}"), wall);
        pts.push((wall, ke.max(1e-20)));
    }
    let mut plot =
        LinePlot::new("flip-tet: jittered rest pool, final KE vs wall time", "wall time (s)", "kinetic energy (J)")
            .log(false, true);
    for (p, name) in pts.iter().zip(["Hulls", "ZhuBridson", "SphereUnion"]) {
        plot = plot.with(Series::new(name, vec![*p]));
    }
    plot.write_png(&out_dir.join("surface_method.png"))?;
    Ok(())
}

/// `accuracy_vs_time.csv`, `pareto.png` (dam-break front error vs wall time per knob) and, when
/// the tolerance sweep ran, `solver_tol.png`.
fn write_outputs(rows: &[Row], out_dir: &Path) -> Result<()> {
    let mut csv = CsvWriter::create(
        &out_dir.join("accuracy_vs_time.csv"),
        &["knob", "value", "wall_s", "steps", "particles_avg", "metric", "error"],
    )?;
    for r in rows {
        csv.row(&[
            Cell::Text(r.knob.into()),
            Cell::Text(r.value.clone()),
            Cell::Num(r.wall),
            Cell::Int(r.steps as i64),
            Cell::Num(r.particles),
            Cell::Text(r.metric.into()),
            Cell::Num(r.error),
        ])?;
    }
    let front: Vec<&Row> = rows.iter().filter(|r| r.metric == "front_rms_rel_err").collect();
    if !front.is_empty() {
        let mut plot =
            LinePlot::new("flip-tet: dam-break front error vs wall time", "wall time (s)", "RMS relative front error")
                .log(true, true);
        for knob in ["resolution", "levels", "bc_order", "remesh", "cfl"] {
            let pts: Vec<(f64, f64)> =
                front.iter().filter(|r| r.knob == knob).map(|r| (r.wall, r.error.max(1e-6))).collect();
            if !pts.is_empty() {
                plot = plot.with(Series::new(knob, pts));
            }
        }
        plot.write_png(&out_dir.join("pareto.png"))?;
    }
    let pts: Vec<(f64, f64)> = rows
        .iter()
        .filter(|r| r.knob == "solver_tol" && r.metric == "rest_max_speed")
        .map(|r| (r.wall, r.error.max(1e-18)))
        .collect();
    if !pts.is_empty() {
        LinePlot::new(
            "flip-tet: rest-pool max speed vs wall time (direct, MIC-PCG tolerances)",
            "wall time (s)",
            "max speed (m/s)",
        )
        .log(true, true)
        .with(Series::new("solver/tolerance", pts))
        .write_png(&out_dir.join("solver_tol.png"))?;
    }
    Ok(())
}

//! `cargo xtask bench flip-tet [--sweep <knob>]` (spec §9, flip-tet README "Benchmark sweeps"):
//! accuracy against time as loops over flip-tet's experiment calls (`dam_break::dam_run`,
//! `standing_wave::wave_run`, `experiments::simulate`) on the scene files' setups. Writes
//! `accuracy_vs_time.csv`, `pareto.png`, one PNG per extra sweep and `runs/<name>/` per run.

use flip_tet::error::SolverKind;
use flip_tet::experiments::{dam_break, rest_pool, simulate, standing_wave, FrameOutput, RunOut, SimRun};
use flip_tet::metrics::{damping_ratio, front_errors, max_speed, rel_drift};
use flip_tet::reference::MARTIN_MOYCE_FRONT;
use flip_tet::scene::Scene;
use geom_core::experiment::Size;

use crate::bench_points::{self as P, pts};
use crate::error::{Error, Result};
use crate::out::{Cell, CsvWriter, Summary};
use crate::plot::{LinePlot, Series};
use crate::record::FileRecorder;
use crate::registry::BenchCtx;
use crate::scene::{load, scenes_dir};

/// The sweeps `--sweep` can select (besides `all`); the first four are the default set.
pub const SWEEPS: &[&str] = &["resolution", "levels", "tol", "bc", "solver", "remesh", "cfl", "pic", "surface"];

/// One row of `accuracy_vs_time.csv`: knob, value, wall s, steps, mean particles, metric, error.
type Row = (&'static str, String, f64, usize, f64, &'static str, f64);

struct Bench {
    quick: bool,
    dam: Scene,
    pool: Scene,
    wave: Scene,
    runs: std::path::PathBuf,
    rows: Vec<Row>,
    s: Summary,
}

impl Bench {
    fn sim(&self, scene: &Scene, name: &str) -> Result<SimRun> {
        let mut rec = FileRecorder::new(&self.runs.join(name))?;
        Ok(simulate(scene, &mut rec, RunOut::full("", FrameOutput::NONE), &mut |_, _| Ok(()))?)
    }
    /// Dam break: (RMS front error vs Martin & Moyce, wall s, steps, particles, level-set drift).
    fn dam(&self, scene: &Scene, name: &str) -> Result<(f64, f64, usize, f64, f64)> {
        let mut rec = FileRecorder::new(&self.runs.join(name))?;
        let d = dam_break::dam_run(scene, &mut rec, RunOut::full("", FrameOutput::NONE))?;
        let (_, rms) = front_errors(&d.front, &MARTIN_MOYCE_FRONT);
        let drift = rel_drift(&d.run.stats, |x| x.vol_levelset);
        Ok((rms, d.run.wall, d.run.stats.len(), d.run.particles_avg(), drift))
    }
    /// Standing wave: (period error, damping ratio after half a period, wall s, steps).
    fn wave(&self, scene: &Scene, name: &str) -> Result<(f64, f64, f64, usize)> {
        let mut rec = FileRecorder::new(&self.runs.join(name))?;
        let r = standing_wave::wave_run(scene, &mut rec, RunOut::full("", FrameOutput::NONE))?;
        let zeta = damping_ratio(&r.eta, 0.5 * r.th.period).unwrap_or(f64::NAN);
        Ok((r.period_rel_err(), zeta, r.wall, r.stats.len()))
    }
    fn row(&mut self, knob: &'static str, value: &str, run: (f64, usize, f64), metric: &'static str, err: f64) {
        self.rows.push((knob, value.to_string(), run.0, run.1, run.2, metric, err));
    }
}

/// The benchmark entry point.
pub fn run(ctx: &BenchCtx) -> Result<Summary> {
    let dir = scenes_dir().join("flip-tet");
    let size = if ctx.quick { Size::Quick } else { Size::Default };
    let dp = load::<dam_break::Params>(&dir.join("dam-break.ron"))?.params;
    let rp = load::<rest_pool::Params>(&dir.join("rest-pool.ron"))?.params;
    let wp = load::<standing_wave::Params>(&dir.join("standing-wave.ron"))?.params;
    let sized = |s: &Scene, f: u32, d: f64| {
        let mut s = s.clone();
        s.resolution.finest = f;
        s.duration = d;
        s
    };
    let mut b = Bench {
        quick: ctx.quick,
        dam: sized(&dp.scene, dp.finest.get(size), dp.duration.get(size)),
        pool: sized(&rp.scene, rp.finest.get(Size::Quick), rp.duration.get(Size::Quick)),
        // Quick resolution, default duration (3.6 s ≈ 3 periods) so ζ has enough half cycles.
        wave: sized(&wp.scene, wp.finest.get(Size::Quick), wp.duration.get(Size::Default)),
        runs: ctx.out_dir.join("runs"),
        rows: Vec::new(),
        s: Summary::new(),
    };
    b.s.set_str("profile", flip_tet::metrics::profile());
    let selected: Vec<&str> = match ctx.sweep.as_deref() {
        None => SWEEPS[..4].to_vec(),
        Some("all") => SWEEPS.to_vec(),
        Some(k) => vec![k],
    };
    b.s.set_str("sweeps", &selected.join(","));
    for knob in &selected {
        match *knob {
            "resolution" => {
                for n in pts(ctx, P::flip_tet_resolution(b.quick)) {
                    let mut s = b.dam.clone();
                    s.resolution.finest = n;
                    let (rms, w, st, p, _) = b.dam(&s, &format!("res_{n}"))?;
                    b.row("resolution", &n.to_string(), (w, st, p), "front_rms_rel_err", rms);
                    b.s.set(&format!("dam_front_rms_finest_{n}"), rms);
                }
            }
            "levels" => {
                for (coarsest, finest) in pts(ctx, P::flip_tet_levels(b.quick)) {
                    let mut s = b.dam.clone();
                    (s.resolution.finest, s.resolution.coarsest) = (finest, coarsest);
                    let (rms, w, st, p, _) = b.dam(&s, &format!("levels_{coarsest}"))?;
                    b.row("levels", &format!("{coarsest}-{finest}"), (w, st, p), "front_rms_rel_err", rms);
                }
            }
            "tol" => {
                let mut v: Vec<(SolverKind, f64)> = vec![(SolverKind::DirectCholesky, 1e-6)];
                v.extend(P::flip_tet_tols(b.quick).iter().map(|&t| (SolverKind::PcgIc0, t)));
                let named = P::flip_tet_tol_names(b.quick).into_iter().zip(v).collect();
                for (name, (kind, tol)) in pts(ctx, named) {
                    let mut s = b.pool.clone();
                    (s.pressure.solver, s.pressure.tol) = (kind, tol);
                    let r = b.sim(&s, &format!("tol_{name}"))?;
                    let (vmax, drift) = (max_speed(&r.stats), rel_drift(&r.stats, |x| x.vol_levelset));
                    b.row("solver_tol", &name, (r.wall, r.stats.len(), 0.0), "rest_max_speed", vmax);
                    b.row("solver_tol", &name, (r.wall, r.stats.len(), 0.0), "rest_volume_drift_rel", drift);
                    b.s.set(&format!("rest_max_speed_{name}"), vmax);
                }
            }
            "bc" => {
                for (second, tag) in pts(ctx, P::FLIP_TET_BC.to_vec()) {
                    let mut s = b.dam.clone();
                    (s.resolution.finest, s.pressure.second_order) = (32, second);
                    let (rms, w, st, p, _) = b.dam(&s, &format!("bc_{tag}"))?;
                    b.row("bc_order", tag, (w, st, p), "front_rms_rel_err", rms);
                    b.s.set(&format!("dam_front_rms_{tag}_order"), rms);
                    if !b.quick {
                        let mut w = b.wave.clone();
                        w.pressure.second_order = second;
                        let (pe, z, wall, st) = b.wave(&w, &format!("wave_{tag}"))?;
                        b.row("bc_order", tag, (wall, st, 0.0), "wave_period_rel_err", pe);
                        b.row("bc_order", tag, (wall, st, 0.0), "wave_damping_ratio", z);
                        b.s.set(&format!("wave_period_rel_err_{tag}_order"), pe);
                        b.s.set(&format!("wave_damping_ratio_{tag}_order"), z);
                    }
                }
            }
            "solver" => sweep_solver(&mut b, &ctx.out_dir)?,
            "remesh" => {
                for k in pts(ctx, P::flip_tet_remesh(b.quick)) {
                    let mut s = b.dam.clone();
                    (s.resolution.finest, s.flip.remesh_interval) = (32, k);
                    let (rms, w, st, p, _) = b.dam(&s, &format!("remesh_{k}"))?;
                    b.row("remesh", &k.to_string(), (w, st, p), "front_rms_rel_err", rms);
                    b.s.set(&format!("dam_front_rms_remesh_{k}"), rms);
                    b.s.set(&format!("dam_wall_s_remesh_{k}"), w);
                }
            }
            "cfl" => {
                for cfl in pts(ctx, P::flip_tet_cfl(b.quick)) {
                    let mut s = b.dam.clone();
                    (s.resolution.finest, s.flip.cfl, s.flip.dt_max) = (32, cfl, 1.0 / b.dam.fps);
                    let (rms, w, st, p, drift) = b.dam(&s, &format!("cfl_{cfl}"))?;
                    b.row("cfl", &cfl.to_string(), (w, st, p), "front_rms_rel_err", rms);
                    b.row("cfl", &cfl.to_string(), (w, st, p), "levelset_volume_drift_rel", drift);
                    b.s.set(&format!("dam_front_rms_cfl_{cfl}"), rms);
                    b.s.set(&format!("dam_volume_drift_cfl_{cfl}"), drift);
                    b.s.set_count(&format!("dam_steps_cfl_{cfl}"), st as u64);
                }
            }
            "pic" => sweep_pic(&mut b, &ctx.out_dir)?,
            "surface" => sweep_surface(&mut b, &ctx.out_dir)?,
            other => return Err(Error::Usage(format!("no flip-tet sweep '{other}'; known: {}", SWEEPS.join(", ")))),
        }
    }
    write_outputs(&b.rows, &ctx.out_dir)?;
    Ok(b.s)
}

/// `solver`: linear-solve ms per step against mean DOFs (direct, MIC(0)-PCG, Jacobi-PCG at 1e−6)
/// on the rest pool at finest 16, 32 (64), 40 steps each; the error column is the max speed.
fn sweep_solver(b: &mut Bench, out_dir: &std::path::Path) -> Result<()> {
    let res: Vec<u32> = if b.quick { vec![16, 32] } else { vec![16, 32, 64] };
    use SolverKind::{DirectCholesky, PcgIc0, PcgJacobi};
    let kinds = [("direct", DirectCholesky), ("mic_pcg", PcgIc0), ("jacobi_pcg", PcgJacobi)];
    let mut plot = LinePlot::new("flip-tet: pressure solve time vs DOFs (rest pool)", "DOFs (mean)", "ms per solve")
        .log(true, true);
    for (name, kind) in kinds {
        let mut pts = Vec::new();
        for &n in &res {
            let mut s = b.pool.clone();
            (s.resolution.finest, s.duration, s.pressure.solver, s.pressure.tol) =
                (n, 40.0 * s.flip.dt_max, kind, 1e-6);
            let r = b.sim(&s, &format!("solver_{name}_{n}"))?;
            let k = r.stats.len().max(1) as f64;
            let dofs = r.stats.iter().map(|x| x.n_dofs as f64).sum::<f64>() / k;
            let ms = 1e3 * r.stats.iter().map(|x| x.timings.solve).sum::<f64>() / k;
            let (v, speed) = (format!("{name}_{n}"), max_speed(&r.stats));
            b.row("solver", &v, (r.wall, r.stats.len(), dofs), "rest_max_speed", speed);
            b.s.set(&format!("solve_ms_{name}_finest_{n}"), ms);
            b.s.set(&format!("solve_dofs_finest_{n}"), dofs);
            pts.push((dofs, ms.max(1e-6)));
        }
        plot = plot.with(Series::new(name, pts));
    }
    plot.write_png(&out_dir.join("solver_kind.png"))?;
    Ok(())
}

/// `pic`: `pic_base` 0, 0.01, 0.03, 0.1 (quick: 0, 0.03) on the standing wave (period error, ζ)
/// and on a rest pool jittered by 0.1 (the max speed over the last tenth of the run).
fn sweep_pic(b: &mut Bench, out_dir: &std::path::Path) -> Result<()> {
    let ps: Vec<f64> = if b.quick { vec![0.0, 0.03] } else { vec![0.0, 0.01, 0.03, 0.1] };
    let mut pts = Vec::new();
    for &pic in &ps {
        let set = |s: &mut Scene| (s.flip.pic_base, s.flip.pic_floor) = (pic, s.flip.pic_floor.min(pic));
        let mut w = b.wave.clone();
        set(&mut w);
        let (pe, z, wall, st) = b.wave(&w, &format!("pic_wave_{pic}"))?;
        b.row("pic", &pic.to_string(), (wall, st, 0.0), "wave_period_rel_err", pe);
        b.row("pic", &pic.to_string(), (wall, st, 0.0), "wave_damping_ratio", z);
        b.s.set(&format!("wave_period_rel_err_pic_{pic}"), pe);
        b.s.set(&format!("wave_damping_ratio_pic_{pic}"), z);
        pts.push((pic, z));
        let mut p = b.pool.clone();
        set(&mut p);
        p.particles.sampling_jitter = 0.1;
        let r = b.sim(&p, &format!("pic_rest_{pic}"))?;
        let noise = max_speed(&r.stats[r.stats.len() - (r.stats.len() / 10).max(1)..]);
        b.row("pic", &pic.to_string(), (r.wall, r.stats.len(), 0.0), "rest_jitter_late_max_speed", noise);
        b.s.set(&format!("rest_jitter_late_max_speed_pic_{pic}"), noise);
    }
    LinePlot::new("flip-tet: standing-wave damping ratio vs PIC fraction", "pic_base", "damping ratio")
        .with(Series::new("zeta", pts))
        .write_png(&out_dir.join("pic_damping.png"))?;
    Ok(())
}

/// `surface`: Hulls, ZhuBridson, SphereUnion as the simulation surface on a rest pool jittered
/// by 0.1, 200 steps: final kinetic energy (J) against wall time.
fn sweep_surface(b: &mut Bench, out_dir: &std::path::Path) -> Result<()> {
    use flip_tet::surface::SurfaceMethod::{Hulls, SphereUnion, ZhuBridson};
    let mut plot =
        LinePlot::new("flip-tet: jittered rest pool, final KE vs wall time", "wall time (s)", "kinetic energy (J)")
            .log(false, true);
    let methods = [("hulls", "Hulls", Hulls), ("zhu_bridson", "ZhuBridson", ZhuBridson)];
    for (name, label, m) in methods.into_iter().chain([("sphere_union", "SphereUnion", SphereUnion)]) {
        let mut s = b.pool.clone();
        (s.surface.method, s.particles.sampling_jitter, s.duration) = (m, 0.1, 200.0 * s.flip.dt_max);
        let r = b.sim(&s, &format!("surface_{name}"))?;
        let ke = r.stats.last().map_or(f64::NAN, |x| x.kinetic_energy);
        b.row("surface", name, (r.wall, r.stats.len(), 0.0), "rest_jitter_final_ke_J", ke);
        b.s.set(&format!("rest_jitter_final_ke_J_{name}"), ke);
        b.s.set(&format!("rest_jitter_wall_s_{name}"), r.wall);
        plot = plot.with(Series::new(label, vec![(r.wall, ke.max(1e-20))]));
    }
    plot.write_png(&out_dir.join("surface_method.png"))?;
    Ok(())
}

/// `accuracy_vs_time.csv`, `pareto.png` (dam-break front error vs wall time per knob) and, when
/// the tolerance sweep ran, `solver_tol.png`.
fn write_outputs(rows: &[Row], out_dir: &std::path::Path) -> Result<()> {
    let header = ["knob", "value", "wall_s", "steps", "particles_avg", "metric", "error"];
    let mut csv = CsvWriter::create(&out_dir.join("accuracy_vs_time.csv"), &header)?;
    for r in rows {
        let text = |s: &str| Cell::Text(s.into());
        csv.row(&[
            text(r.0),
            text(&r.1),
            Cell::Num(r.2),
            Cell::Int(r.3 as i64),
            Cell::Num(r.4),
            text(r.5),
            Cell::Num(r.6),
        ])?;
    }
    let front: Vec<&Row> = rows.iter().filter(|r| r.5 == "front_rms_rel_err").collect();
    if !front.is_empty() {
        let mut plot =
            LinePlot::new("flip-tet: dam-break front error vs wall time", "wall time (s)", "RMS relative front error")
                .log(true, true);
        for knob in ["resolution", "levels", "bc_order", "remesh", "cfl"] {
            let pts: Vec<(f64, f64)> = front.iter().filter(|r| r.0 == knob).map(|r| (r.2, r.6.max(1e-6))).collect();
            if !pts.is_empty() {
                plot = plot.with(Series::new(knob, pts));
            }
        }
        plot.write_png(&out_dir.join("pareto.png"))?;
    }
    let pts: Vec<(f64, f64)> =
        rows.iter().filter(|r| r.0 == "solver_tol" && r.5 == "rest_max_speed").map(|r| (r.2, r.6.max(1e-18))).collect();
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

//! barnet's scenes (spec §6): bar-net driven skinning with force-density rest shapes.
//!
//! - `barnet/arm-muscle`: the paper's Figure 3 — biceps/triceps nets on the procedural arm,
//!   elbow sweep, q variants, Catmull–Clark level-2 skin (2816 faces).
//! - `barnet/elbow-volume`: the elbow example — loads on the elbow ring fitted per frame (§3.8)
//!   to keep the skin volume at its rest value; LBS and DQS for reference.
//! - `barnet/stiffness`: the biceps group's q animated 1 → 0.25 → 1 (refactorisation per frame)
//!   against constant q.
//! - `barnet/topology`: a triangle/quad/pentagon patch with a hole.
//! - `barnet/scaling`: analytic cable and membrane; grid membranes up to 512² free nodes.
//! - `barnet/nonlinear-vs-fdm`: elastic bars by Newton against the one-solve FDM.

use std::time::Instant;

use barnet::analytic;
use barnet::deformer::{BarNetDeformer, DeformerConfig, Drivers, FrameOutput};
use barnet::net::BarNet;
use barnet::nonlinear::{form_find_nonlinear, Elastic, NewtonOptions, NonlinearModel};
use barnet::patch;
use barnet::volume::CappedVolume;
use barnet::{FdmOptions, FdmSolver, SolverPath};
use geom_core::io::{obj, MeshOut};
use geom_core::math::{Iso3, Pt3, Vec3};
use geom_core::mesh::PolyMesh;
use geom_core::rng::Rng;
use serde::Deserialize;

use crate::error::{Error, Result};
use crate::out::{CsvWriter, Summary};
use crate::plot::{LinePlot, Series};
use crate::registry::{RunCtx, Runner};
use crate::scene;

/// Adds barnet's runners.
pub fn register(v: &mut Vec<Runner>) {
    v.push(Runner { method: "barnet/arm-muscle", run: run_arm_muscle });
    v.push(Runner { method: "barnet/elbow-volume", run: run_elbow_volume });
    v.push(Runner { method: "barnet/stiffness", run: run_stiffness });
    v.push(Runner { method: "barnet/topology", run: run_topology });
    v.push(Runner { method: "barnet/scaling", run: run_scaling });
    v.push(Runner { method: "barnet/nonlinear-vs-fdm", run: run_nonlinear_vs_fdm });
}

fn bn(e: barnet::BarNetError) -> Error {
    match e {
        barnet::BarNetError::Core(c) => Error::Core(c),
        other => Error::Run(other.to_string()),
    }
}

/// The elbow sweep of the arm scenes.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct Sweep {
    from_deg: f64,
    to_deg: f64,
    /// Frames in quick, default and full mode.
    frames: [usize; 3],
}

impl Sweep {
    fn angles(&self, ctx: &RunCtx) -> Vec<f64> {
        let n = ctx.mode.pick(self.frames[0], self.frames[1], self.frames[2]).max(2);
        (0..n)
            .map(|i| (self.from_deg + (self.to_deg - self.from_deg) * i as f64 / (n - 1) as f64).to_radians())
            .collect()
    }
}

fn write_fine_obj(
    ctx: &RunCtx,
    sub: &str,
    frame: usize,
    fine: &[[f32; 3]],
    faces: &geom_core::graph::Ragged<u32>,
) -> Result<()> {
    let dir = ctx.out_dir.join(sub);
    crate::out::ensure_dir(&dir)?;
    let m = MeshOut {
        positions: geom_core::io::Positions::F32(fine),
        faces: geom_core::io::Faces::Poly(faces),
        uv: None,
        normals: None,
    };
    obj::write(geom_core::io::frame_path(&dir, frame), &m)?;
    Ok(())
}

fn write_control_obj(
    ctx: &RunCtx,
    sub: &str,
    frame: usize,
    p: &[Pt3],
    faces: &geom_core::graph::Ragged<u32>,
) -> Result<()> {
    let dir = ctx.out_dir.join(sub);
    crate::out::ensure_dir(&dir)?;
    obj::write(geom_core::io::frame_path(&dir, frame), &MeshOut::poly(p, faces))?;
    Ok(())
}

/// Bulge height (m): the largest increase of the distance to the upper-arm axis (the x axis,
/// which the elbow sweep does not move) of a fine vertex of the upper arm, against LBS.
fn bulge(fine: &[[f32; 3]], lbs: &[[f32; 3]], x_max: f64) -> f64 {
    fine.iter()
        .zip(lbs)
        .filter(|(_, l)| (l[0] as f64) < x_max)
        .map(|(f, l)| {
            let r = |p: &[f32; 3]| ((p[1] as f64).powi(2) + (p[2] as f64).powi(2)).sqrt();
            r(f) - r(l)
        })
        .fold(0.0, f64::max)
}

/// The capped-volume measurement for meshes with these faces.
fn capped_volume(faces: &geom_core::graph::Ragged<u32>) -> Result<CappedVolume> {
    let n = faces.items.iter().map(|&v| v as usize + 1).max().unwrap_or(0);
    CappedVolume::new(&PolyMesh { positions: vec![Pt3::origin(); n], faces: faces.clone(), uv: None }).map_err(bn)
}

fn check_residual(what: &str, r: f64, bound: f64) -> Result<()> {
    if r.is_finite() && r <= bound {
        Ok(())
    } else {
        Err(Error::Run(format!("{what}: equilibrium residual {r:e} exceeds {bound:e} (spec 7.3 e)")))
    }
}

// ---------------------------------------------------------------------------------------------
// arm-muscle

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct ArmMuscleParams {
    deformer: DeformerConfig,
    /// Force-density variants (paper: lower q, bigger bulge); the first is the main run.
    q_variants: Vec<f64>,
    sweep: Sweep,
    obj_every: usize,
    /// Timing repetitions per frame (the per-frame time is the median of these).
    timing_reps: usize,
}

fn run_arm_muscle(ctx: &RunCtx) -> Result<Summary> {
    let p: ArmMuscleParams = scene::load(&ctx.scene_file)?.params;
    let angles = p.sweep.angles(ctx);
    let mut csv = CsvWriter::create(
        &ctx.out_dir.join("metrics.csv"),
        &[
            "q",
            "frame",
            "elbow_deg",
            "bulge_m",
            "volume_m3",
            "volume_lbs_m3",
            "residual",
            "t_lbs_s",
            "t_loads_s",
            "t_solve_s",
            "t_fine_s",
            "t_total_s",
        ],
    )?;
    let mut s = Summary::new();
    let mut max_res: f64 = 0.0;
    let mut bulge_series = Vec::new();
    let mut vol_series = Vec::new();
    let mut main_times = Vec::new();
    let mut main_barnet_times = Vec::new();
    let mut peak_bulges = Vec::new();
    for (vi, &q) in p.q_variants.iter().enumerate() {
        let mut cfg = p.deformer.clone();
        cfg.q = q;
        let mut d = BarNetDeformer::new(&cfg).map_err(bn)?;
        let faces = d.fine.faces().clone();
        let cv = capped_volume(&faces)?;
        let x_max = d.arm.spec.upper_len - 2.0 * cfg.ramp_half_width;
        let mut out = FrameOutput::default();
        let mut lbs_fine = Vec::new();
        let (mut bpts, mut vpts, mut vlbs) = (Vec::new(), Vec::new(), Vec::new());
        for (f, &a) in angles.iter().enumerate() {
            let pose = d.arm_pose(a, &Iso3::identity()).map_err(bn)?;
            let drivers = Drivers { joint_angles: vec![0.0, a, 0.0], time: f as f64 };
            let mut times = Vec::new();
            for _ in 0..p.timing_reps.max(1) {
                d.deform(&pose, &drivers, &mut out).map_err(bn)?;
                times.push(out.timings);
            }
            times.sort_by(|x, y| x.total.total_cmp(&y.total));
            let t = times[times.len() / 2];
            check_residual("arm-muscle", out.residual, 1e-12)?;
            max_res = max_res.max(out.residual);
            d.fine.eval(&out.lbs, &mut lbs_fine);
            let b = bulge(&out.fine, &lbs_fine, x_max);
            let vol = cv.volume(&out.fine);
            let vol_l = cv.volume(&lbs_fine);
            bpts.push((a.to_degrees(), b * 1000.0));
            vpts.push((a.to_degrees(), vol * 1e6));
            vlbs.push((a.to_degrees(), vol_l * 1e6));
            csv.row(&[
                q.into(),
                f.into(),
                a.to_degrees().into(),
                b.into(),
                vol.into(),
                vol_l.into(),
                out.residual.into(),
                t.lbs.into(),
                t.loads.into(),
                t.solve.into(),
                t.fine.into(),
                t.total.into(),
            ])?;
            if vi == 0 {
                main_times.push(t.total);
                main_barnet_times.push(t.loads + t.solve + t.stiffness);
                if f % p.obj_every.max(1) == 0 || f + 1 == angles.len() {
                    write_fine_obj(ctx, "frames", f, &out.fine, &faces)?;
                    write_control_obj(ctx, "control", f, &out.control, &d.control_rest().faces)?;
                }
            }
        }
        let peak = bpts.iter().map(|p| p.1).fold(0.0, f64::max) / 1000.0;
        peak_bulges.push((q, peak));
        s.set(&format!("bulge_height_m_q{q}"), peak);
        bulge_series.push(Series::new(format!("bar-net, q = {q}"), bpts));
        if vi == 0 {
            vol_series.push(Series::new("LBS", vlbs));
            vol_series.push(Series::new(format!("bar-net, q = {q}"), vpts));
            s.set_count("fine_faces", faces.len() as u64);
            s.set_count("fine_vertices", out.fine.len() as u64);
            s.set_count("control_vertices", out.control.len() as u64);
            s.set_count("free_nodes", d.solver.free_nodes().len() as u64);
            s.set_str("solver_path", &format!("{:?}", d.solver.path()));
        }
    }
    let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len().max(1) as f64;
    s.set("max_equilibrium_residual", max_res);
    s.set("s_per_frame", mean(&main_times));
    s.set("s_per_frame_max", main_times.iter().copied().fold(0.0, f64::max));
    s.set("s_per_frame_barnet", mean(&main_barnet_times));
    s.set_str("timing_profile", if cfg!(debug_assertions) { "dev (debug assertions, opt-level 1)" } else { "release" });
    s.set_count("frames", angles.len() as u64);
    peak_bulges.sort_by(|a, b| a.0.total_cmp(&b.0));
    let monotone = peak_bulges.windows(2).all(|w| w[0].1 > w[1].1);
    s.set_count("lower_q_bigger_bulge", monotone as u64);
    let mut plot = LinePlot::new("Biceps bulge vs elbow angle", "elbow flexion (deg)", "bulge height (mm)");
    for sr in bulge_series {
        plot = plot.with(sr);
    }
    plot.write_png(&ctx.out_dir.join("bulge.png"))?;
    let mut vplot = LinePlot::new("Enclosed volume of the capped fine mesh", "elbow flexion (deg)", "volume (cm^3)");
    for sr in vol_series {
        vplot = vplot.with(sr);
    }
    vplot.write_png(&ctx.out_dir.join("volume.png"))?;
    let report = format!(
        "### barnet/arm-muscle\n\n| item | paper | ours |\n|---|---|---|\n| fine faces | 2816 | {} |\n| fine vertices | 2891 | {} (open tube, spec §12.7) |\n| free nodes | 12 | {} |\n| lower q ⇒ bigger bulge | yes (Fig. 3d) | {} |\n| time per frame | not reported | {:.3e} s ({}) |\n| max equilibrium residual | — | {:.2e} |\n",
        s.get("fine_faces").unwrap_or(0.0),
        s.get("fine_vertices").unwrap_or(0.0),
        s.get("free_nodes").unwrap_or(0.0),
        if monotone { "yes" } else { "no" },
        mean(&main_times),
        if cfg!(debug_assertions) { "dev profile" } else { "release" },
        max_res
    );
    std::fs::write(ctx.out_dir.join("report.md"), report)
        .map_err(crate::error::io_err(ctx.out_dir.join("report.md")))?;
    Ok(s)
}

// ---------------------------------------------------------------------------------------------
// elbow-volume

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct ElbowParams {
    /// Deformer with the elbow net; its first load channel's magnitude is fitted per frame.
    deformer: DeformerConfig,
    sweep: Sweep,
    obj_every: usize,
    /// Secant iterations per frame (spec §3.8: 2–3).
    secant_iters: usize,
}

fn run_elbow_volume(ctx: &RunCtx) -> Result<Summary> {
    let p: ElbowParams = scene::load(&ctx.scene_file)?.params;
    let angles = p.sweep.angles(ctx);
    let mut d = BarNetDeformer::new(&p.deformer).map_err(bn)?;
    if d.loads.is_empty() {
        return Err(Error::Run("elbow-volume: the deformer needs a load channel to fit".into()));
    }
    let n_ch = d.loads.len();
    let faces = d.fine.faces().clone();
    let cv = capped_volume(&faces)?;
    let mut out = FrameOutput::default();
    let rest_pose = d.arm_pose(0.0, &Iso3::identity()).map_err(bn)?;
    d.deform_with(&rest_pose, &Drivers { joint_angles: vec![0.0; 3], time: 0.0 }, Some(&vec![0.0; n_ch]), &mut out)
        .map_err(bn)?;
    let v_rest = cv.volume(&out.fine);
    let mut csv = CsvWriter::create(
        &ctx.out_dir.join("metrics.csv"),
        &[
            "frame",
            "elbow_deg",
            "volume_lbs_rel",
            "volume_dqs_rel",
            "volume_barnet_rel",
            "fitted_magnitude",
            "residual",
            "t_frame_s",
            "t_fit_s",
        ],
    )?;
    let (mut max_res, mut loss_lbs, mut loss_dqs, mut err_bn, mut fmax): (f64, f64, f64, f64, f64) =
        (0.0, 0.0, 0.0, 0.0, 0.0);
    let (mut s_lbs, mut s_dqs, mut s_bn, mut s_f) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    let mut frame_times = Vec::new();
    let mut fit_times = Vec::new();
    let mut f_prev = 0.0;
    let mut dqs_ctrl = vec![Pt3::origin(); d.control_rest().positions.len()];
    let mut tmp = Vec::new();
    for (fi, &a) in angles.iter().enumerate() {
        let pose = d.arm_pose(a, &Iso3::identity()).map_err(bn)?;
        let drv = Drivers { joint_angles: vec![0.0, a, 0.0], time: fi as f64 };
        let t0 = Instant::now();
        let vol = |d: &mut BarNetDeformer, f: f64, out: &mut FrameOutput| -> Result<f64> {
            let mut m = vec![0.0; n_ch];
            m[0] = f;
            d.deform_with(&pose, &drv, Some(&m), out).map_err(bn)?;
            Ok(cv.volume(&out.fine) - v_rest)
        };
        // Secant on f (volume is nearly linear in f: positions are linear in the loads).
        let (mut f0, mut f1) = (f_prev, f_prev + 0.25);
        let (mut g0, mut g1) = (vol(&mut d, f0, &mut out)?, vol(&mut d, f1, &mut out)?);
        for _ in 0..p.secant_iters {
            if g1 == g0 || (g1.abs() <= 1e-12 * v_rest) {
                break;
            }
            let f2 = f1 - g1 * (f1 - f0) / (g1 - g0);
            f0 = f1;
            g0 = g1;
            f1 = f2;
            g1 = vol(&mut d, f1, &mut out)?;
        }
        fit_times.push(t0.elapsed().as_secs_f64());
        let t1 = Instant::now();
        vol(&mut d, f1, &mut out)?;
        frame_times.push(t1.elapsed().as_secs_f64());
        f_prev = f1;
        check_residual("elbow-volume", out.residual, 1e-12)?;
        max_res = max_res.max(out.residual);
        d.fine.eval(&out.lbs, &mut tmp);
        let v_l = cv.volume(&tmp) / v_rest - 1.0;
        d.weights.dqs(&d.control_rest().positions, &pose, &mut dqs_ctrl);
        d.fine.eval(&dqs_ctrl, &mut tmp);
        let v_d = cv.volume(&tmp) / v_rest - 1.0;
        let v_b = cv.volume(&out.fine) / v_rest - 1.0;
        loss_lbs = loss_lbs.max(-v_l);
        loss_dqs = loss_dqs.max(-v_d);
        err_bn = err_bn.max(v_b.abs());
        fmax = fmax.max(f1.abs());
        let deg = a.to_degrees();
        s_lbs.push((deg, v_l * 100.0));
        s_dqs.push((deg, v_d * 100.0));
        s_bn.push((deg, v_b * 100.0));
        s_f.push((deg, f1));
        csv.row(&[
            fi.into(),
            deg.into(),
            v_l.into(),
            v_d.into(),
            v_b.into(),
            f1.into(),
            out.residual.into(),
            frame_times[fi].into(),
            fit_times[fi].into(),
        ])?;
        if fi % p.obj_every.max(1) == 0 || fi + 1 == angles.len() {
            write_fine_obj(ctx, "frames", fi, &out.fine, &faces)?;
        }
    }
    LinePlot::new("Fine-mesh volume change vs elbow angle", "elbow flexion (deg)", "volume change (%)")
        .with(Series::new("LBS", s_lbs))
        .with(Series::new("DQS", s_dqs))
        .with(Series::new("LBS + bar-net (fitted loads)", s_bn))
        .write_png(&ctx.out_dir.join("volume.png"))?;
    LinePlot::new("Fitted elbow-ring load magnitude (spec 3.8)", "elbow flexion (deg)", "magnitude (x scale)")
        .with(Series::new("fitted", s_f))
        .write_png(&ctx.out_dir.join("fitted_magnitude.png"))?;
    let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len().max(1) as f64;
    let mut s = Summary::new();
    s.set("max_equilibrium_residual", max_res);
    s.set("volume_loss_lbs_max_rel", loss_lbs);
    s.set("volume_loss_dqs_max_rel", loss_dqs);
    s.set("volume_err_barnet_max_rel", err_bn);
    s.set("fitted_magnitude_max", fmax);
    s.set("s_per_frame", mean(&frame_times));
    s.set("s_per_frame_with_fit", mean(&fit_times));
    s.set_count("free_nodes", d.solver.free_nodes().len() as u64);
    s.set_count("frames", angles.len() as u64);
    s.set_str("curve_skin_reference", "not run: barnet must not depend on curve-skin this session");
    Ok(s)
}

// ---------------------------------------------------------------------------------------------
// stiffness

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct StiffnessParams {
    /// Deformer with a stiffness channel (driver Time, t in [0, 1] over the run).
    deformer: DeformerConfig,
    /// Elbow angle held during the run (deg).
    elbow_deg: f64,
    /// Frames in quick, default and full mode.
    frames: [usize; 3],
    obj_every: usize,
    timing_reps: usize,
}

fn run_stiffness(ctx: &RunCtx) -> Result<Summary> {
    let p: StiffnessParams = scene::load(&ctx.scene_file)?.params;
    let n = ctx.mode.pick(p.frames[0], p.frames[1], p.frames[2]).max(2);
    let mut csv = CsvWriter::create(
        &ctx.out_dir.join("metrics.csv"),
        &["case", "frame", "t", "bulge_m", "residual", "refactored", "t_stiffness_s", "t_solve_s", "t_total_s"],
    )?;
    let mut s = Summary::new();
    let mut max_res: f64 = 0.0;
    let mut plot = LinePlot::new("Bulge with animated biceps stiffness", "t", "bulge height (mm)");
    let mut tplot = LinePlot::new("Time per frame", "t", "time per frame (us)").log(false, true);
    for case in ["animated_q", "constant_q"] {
        let mut cfg = p.deformer.clone();
        if case == "constant_q" {
            cfg.stiffness.clear();
        }
        let mut d = BarNetDeformer::new(&cfg).map_err(bn)?;
        let faces = d.fine.faces().clone();
        let a = p.elbow_deg.to_radians();
        let pose = d.arm_pose(a, &Iso3::identity()).map_err(bn)?;
        let x_max = d.arm.spec.upper_len - 2.0 * cfg.ramp_half_width;
        let mut out = FrameOutput::default();
        let mut lbs_fine = Vec::new();
        let (mut bp, mut tp, mut totals) = (Vec::new(), Vec::new(), Vec::new());
        let mut refactors = 0usize;
        for f in 0..n {
            let t = f as f64 / (n - 1) as f64;
            let mut times = Vec::new();
            for r in 0..p.timing_reps.max(1) {
                // Alternate the driver so that every repetition refactorises when q is animated.
                let tt = if r % 2 == 1 && case == "animated_q" { (t + 0.5 / n as f64).min(1.0) } else { t };
                d.deform(&pose, &Drivers { joint_angles: vec![0.0, a, 0.0], time: tt }, &mut out).map_err(bn)?;
                refactors += out.refactored as usize;
                times.push(out.timings);
            }
            d.deform(&pose, &Drivers { joint_angles: vec![0.0, a, 0.0], time: t }, &mut out).map_err(bn)?;
            times.sort_by(|x, y| x.total.total_cmp(&y.total));
            let tm = times[times.len() / 2];
            check_residual("stiffness", out.residual, 1e-12)?;
            max_res = max_res.max(out.residual);
            d.fine.eval(&out.lbs, &mut lbs_fine);
            let b = bulge(&out.fine, &lbs_fine, x_max);
            bp.push((t, b * 1000.0));
            tp.push((t, tm.total * 1e6));
            totals.push(tm.total);
            csv.row(&[
                case.into(),
                f.into(),
                t.into(),
                b.into(),
                out.residual.into(),
                (out.refactored as usize).into(),
                tm.stiffness.into(),
                tm.solve.into(),
                tm.total.into(),
            ])?;
            if case == "animated_q" && (f % p.obj_every.max(1) == 0 || f + 1 == n) {
                write_fine_obj(ctx, "frames", f, &out.fine, &faces)?;
            }
        }
        let mean = totals.iter().sum::<f64>() / totals.len() as f64;
        s.set(&format!("s_per_frame_{case}"), mean);
        s.set(&format!("bulge_max_m_{case}"), bp.iter().map(|x| x.1).fold(0.0, f64::max) / 1000.0);
        if case == "animated_q" {
            s.set_count("refactorizations", refactors as u64);
        }
        plot = plot.with(Series::new(case, bp));
        tplot = tplot.with(Series::new(case, tp));
    }
    plot.write_png(&ctx.out_dir.join("bulge.png"))?;
    tplot.write_png(&ctx.out_dir.join("time.png"))?;
    s.set("max_equilibrium_residual", max_res);
    let (a, c) = (s.get("s_per_frame_animated_q").unwrap_or(0.0), s.get("s_per_frame_constant_q").unwrap_or(1.0));
    s.set("refactor_time_ratio", a / c);
    s.set_str("timing_profile", if cfg!(debug_assertions) { "dev" } else { "release" });
    Ok(s)
}

// ---------------------------------------------------------------------------------------------
// topology

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct TopologyParams {
    rings: usize,
    around: usize,
    q: f64,
    /// Free nodes receiving a random load.
    n_loaded: usize,
    /// Load amplitude (force units).
    load_scale: f64,
    /// Rigid rotation amplitude of the whole patch (rad).
    rotate_amp: f64,
    frames: [usize; 3],
    seed: u64,
    obj_every: usize,
}

fn run_topology(ctx: &RunCtx) -> Result<Summary> {
    let p: TopologyParams = scene::load(&ctx.scene_file)?.params;
    let n = ctx.mode.pick(p.frames[0], p.frames[1], p.frames[2]).max(2);
    let pt = patch::mixed_patch(p.rings, p.around);
    let free: Vec<bool> = pt.boundary.iter().map(|b| !b).collect();
    let net = BarNet::from_mesh_edges(&pt.mesh, &free, p.q).map_err(bn)?;
    let t0 = Instant::now();
    let solver = FdmSolver::new(&net, &FdmOptions::default()).map_err(bn)?;
    let t_factor = t0.elapsed().as_secs_f64();
    let fr = solver.free_nodes().to_vec();
    let fx = solver.fixed_nodes().to_vec();
    let rest = &pt.mesh.positions;
    let rest_free: Vec<Pt3> = fr.iter().map(|&v| rest[v as usize]).collect();
    let rest_fixed: Vec<Pt3> = fx.iter().map(|&v| rest[v as usize]).collect();
    let p0 = solver.rest_loads(&rest_free, &rest_fixed).map_err(bn)?;
    let mut rng = Rng::new(p.seed);
    let mut loaded: Vec<(usize, Vec3, f64)> = Vec::new();
    for _ in 0..p.n_loaded.min(fr.len()) {
        let i = rng.below(fr.len());
        let normal = rest_free[i].coords.normalize();
        loaded.push((i, normal, rng.range(0.5, 1.5)));
    }
    let mut csv =
        CsvWriter::create(&ctx.out_dir.join("metrics.csv"), &["frame", "t", "residual", "max_disp_m", "t_solve_s"])?;
    let (mut max_res, mut times, mut rest_err): (f64, Vec<f64>, f64) = (0.0, Vec::new(), 0.0);
    let mut ctrl = rest.clone();
    let mut rpts = Vec::new();
    for f in 0..n {
        let t = f as f64 / (n - 1) as f64;
        let ang = p.rotate_amp * (std::f64::consts::TAU * t).sin();
        let g = Iso3::rotation(Vec3::new(0.3, 1.0, 0.2).normalize() * ang);
        let amp = p.load_scale * (std::f64::consts::PI * t).sin().powi(2);
        let mut loads: Vec<Vec3> = p0.iter().map(|v| g.rotation * v).collect();
        for &(i, nrm, w) in &loaded {
            loads[i] += g.rotation * nrm * (amp * w);
        }
        let fixed: Vec<Pt3> = rest_fixed.iter().map(|x| g * x).collect();
        let ts = Instant::now();
        let mut x = Vec::new();
        let info = solver.solve_into(&loads, &fixed, &mut x).map_err(bn)?;
        let dt = ts.elapsed().as_secs_f64();
        check_residual("topology", info.rel_residual, 1e-12)?;
        max_res = max_res.max(info.rel_residual);
        times.push(dt);
        let mut md: f64 = 0.0;
        for (i, &v) in fr.iter().enumerate() {
            ctrl[v as usize] = x[i];
            md = md.max((x[i] - g * rest_free[i]).norm());
        }
        for (k, &v) in fx.iter().enumerate() {
            ctrl[v as usize] = fixed[k];
        }
        if f == 0 {
            rest_err = md;
        }
        rpts.push((t, md * 1000.0));
        csv.row(&[f.into(), t.into(), info.rel_residual.into(), md.into(), dt.into()])?;
        if f % p.obj_every.max(1) == 0 || f + 1 == n {
            write_control_obj(ctx, "frames", f, &ctrl, &pt.mesh.faces)?;
        }
    }
    LinePlot::new("Mixed patch: load-induced displacement", "t", "max displacement from rigid (mm)")
        .with(Series::new("bar-net", rpts))
        .write_png(&ctx.out_dir.join("displacement.png"))?;
    let h = patch::face_histogram(&pt.mesh);
    let topo = barnet::topo::PolyTopo::new(&pt.mesh).map_err(bn)?;
    let mut s = Summary::new();
    s.set("max_equilibrium_residual", max_res);
    s.set("s_per_frame", times.iter().sum::<f64>() / times.len() as f64);
    s.set("s_factorization", t_factor);
    s.set("rest_reproduction_err_m", rest_err);
    s.set_count("n_vertices", rest.len() as u64);
    s.set_count("n_free", fr.len() as u64);
    s.set_count("faces_tri", h[0] as u64);
    s.set_count("faces_quad", h[1] as u64);
    s.set_count("faces_pent", h[2] as u64);
    s.set_count("boundary_loops", topo.boundary_loops(&pt.mesh).len() as u64);
    s.set_str("solver_path", &format!("{:?}", solver.path()));
    Ok(s)
}

// ---------------------------------------------------------------------------------------------
// scaling

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct ScalingParams {
    /// Free-node counts of the analytic cable.
    cable_nodes: Vec<usize>,
    /// Membrane resolutions N of the convergence study (h = 1/(N+1)).
    membrane_n: Vec<usize>,
    /// Largest membrane N in quick, default and full mode.
    membrane_max: [usize; 3],
    /// Grid sizes n (n × n free nodes) of the timing sweep.
    grid_n: Vec<usize>,
    /// Largest grid n in quick, default and full mode.
    grid_max: [usize; 3],
    /// Largest n solved on the dense path too.
    dense_max: usize,
    /// Timing repetitions of the solve.
    reps: usize,
}

/// Least-squares slope of log y against log x.
fn loglog_slope(pts: &[(f64, f64)]) -> f64 {
    let n = pts.len() as f64;
    let (sx, sy) = pts.iter().fold((0.0, 0.0), |a, p| (a.0 + p.0.ln(), a.1 + p.1.ln()));
    let (mx, my) = (sx / n, sy / n);
    let (num, den) =
        pts.iter().fold((0.0, 0.0), |a, p| (a.0 + (p.0.ln() - mx) * (p.1.ln() - my), a.1 + (p.0.ln() - mx).powi(2)));
    num / den
}

fn run_scaling(ctx: &RunCtx) -> Result<Summary> {
    let p: ScalingParams = scene::load(&ctx.scene_file)?.params;
    let mut s = Summary::new();
    let mut max_res: f64 = 0.0;
    // Analytic cable.
    let mut csv = CsvWriter::create(&ctx.out_dir.join("cable.csv"), &["n_free", "max_rel_err", "residual"])?;
    let mut cable_err: f64 = 0.0;
    for &n in &p.cable_nodes {
        let c = analytic::cable(n, 1.0, 1.0);
        let solver = FdmSolver::new(&c.net, &FdmOptions::default()).map_err(bn)?;
        let (loads, fixed) = c.split();
        let mut x = Vec::new();
        let info = solver.solve_into(&loads, &fixed, &mut x).map_err(bn)?;
        let e = analytic::max_rel_err(&x, c.exact.as_ref().expect("cable has an exact solution"), 1);
        cable_err = cable_err.max(e);
        max_res = max_res.max(info.rel_residual);
        csv.row(&[n.into(), e.into(), info.rel_residual.into()])?;
    }
    s.set("cable_max_rel_err", cable_err);
    s.set_count("cable_max_nodes", p.cable_nodes.iter().copied().max().unwrap_or(0) as u64);
    // Membrane convergence.
    let mmax = ctx.mode.pick(p.membrane_max[0], p.membrane_max[1], p.membrane_max[2]);
    let mut csv = CsvWriter::create(&ctx.out_dir.join("membrane.csv"), &["N", "h", "max_err", "order", "residual"])?;
    let mut errs: Vec<(f64, f64)> = Vec::new();
    let mut min_order = f64::INFINITY;
    for &n in p.membrane_n.iter().filter(|&&n| n <= mmax) {
        let c = analytic::membrane(n, 1.0);
        let solver = FdmSolver::new(&c.net, &FdmOptions::default()).map_err(bn)?;
        let (loads, fixed) = c.split();
        let mut x = Vec::new();
        let info = solver.solve_into(&loads, &fixed, &mut x).map_err(bn)?;
        max_res = max_res.max(info.rel_residual);
        let e = analytic::max_abs_err(&x, c.exact.as_ref().expect("membrane has an exact solution"), 2);
        let h = 1.0 / (n as f64 + 1.0);
        let order = errs.last().map_or(f64::NAN, |&(h0, e0)| (e0 / e).ln() / (h0 / h).ln());
        if order.is_finite() {
            min_order = min_order.min(order);
        }
        errs.push((h, e));
        csv.row(&[n.into(), h.into(), e.into(), order.into(), info.rel_residual.into()])?;
    }
    if errs.len() >= 2 {
        s.set("membrane_convergence_order", loglog_slope(&errs));
        s.set("membrane_convergence_order_min_pairwise", min_order);
    }
    LinePlot::new("Membrane: max nodal error vs h", "h", "max error")
        .log(true, true)
        .with(Series::new("bar-net (FDM)", errs.clone()))
        .with(Series::new("h^2", errs.iter().map(|&(h, _)| (h, errs[0].1 * (h / errs[0].0).powi(2))).collect()))
        .write_png(&ctx.out_dir.join("membrane_convergence.png"))?;
    // Timing sweep.
    let gmax = ctx.mode.pick(p.grid_max[0], p.grid_max[1], p.grid_max[2]);
    let mut csv = CsvWriter::create(
        &ctx.out_dir.join("scaling.csv"),
        &["n", "n_free", "path", "t_factor_s", "t_solve_s", "residual", "refinements", "nnz_l"],
    )?;
    let (mut fac_pts, mut sol_pts, mut dfac, mut dsol) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    let mut crossover: Option<usize> = None;
    for &n in p.grid_n.iter().filter(|&&n| n <= gmax) {
        let c = analytic::membrane_uniform(n, 1.0);
        let (loads, fixed) = c.split();
        let nf = loads.len() as f64;
        let mut totals = [f64::NAN; 2];
        for (pi, path) in ["sparse", "dense"].iter().enumerate() {
            if *path == "dense" && n > p.dense_max {
                continue;
            }
            let o = FdmOptions { dense_threshold: if *path == "dense" { usize::MAX } else { 0 }, ..Default::default() };
            let t0 = Instant::now();
            let solver = FdmSolver::new(&c.net, &o).map_err(bn)?;
            let tf = t0.elapsed().as_secs_f64();
            let mut x = Vec::new();
            let mut ts = Vec::new();
            let mut info = Default::default();
            for _ in 0..p.reps.max(1) {
                let t1 = Instant::now();
                info = solver.solve_into(&loads, &fixed, &mut x).map_err(bn)?;
                ts.push(t1.elapsed().as_secs_f64());
            }
            ts.sort_by(f64::total_cmp);
            let tsol = ts[ts.len() / 2];
            let info: barnet::SolveInfo = info;
            check_residual("scaling", info.rel_residual, 1e-10)?;
            max_res = max_res.max(info.rel_residual);
            totals[pi] = tf + tsol;
            let pname = match solver.path() {
                SolverPath::Dense => "dense",
                SolverPath::Sparse => "sparse",
                SolverPath::Ldlt => "ldlt",
                SolverPath::Empty => "empty",
            };
            csv.row(&[
                n.into(),
                (nf as usize).into(),
                pname.into(),
                tf.into(),
                tsol.into(),
                info.rel_residual.into(),
                (info.refinements as usize).into(),
                solver.nnz_l().into(),
            ])?;
            if *path == "sparse" {
                fac_pts.push((nf, tf));
                sol_pts.push((nf, tsol));
            } else {
                dfac.push((nf, tf));
                dsol.push((nf, tsol));
            }
        }
        if crossover.is_none() && totals[1].is_finite() && totals[0] < totals[1] {
            crossover = Some(n);
        }
    }
    let big = |v: &[(f64, f64)]| -> Vec<(f64, f64)> {
        let b: Vec<(f64, f64)> = v.iter().copied().filter(|p| p.0 >= 1000.0).collect();
        if b.len() >= 2 {
            b
        } else {
            v.to_vec()
        }
    };
    if sol_pts.len() >= 2 {
        s.set("solve_time_exponent", loglog_slope(&big(&sol_pts)));
        s.set("factor_time_exponent", loglog_slope(&big(&fac_pts)));
    }
    if let (Some(f), Some(so)) = (fac_pts.last(), sol_pts.last()) {
        s.set_count("largest_free_nodes", f.0 as u64);
        s.set("largest_factor_s", f.1);
        s.set("largest_solve_s", so.1);
    }
    if let Some(c) = crossover {
        s.set_count("dense_sparse_crossover_n", c as u64);
    }
    s.set("max_equilibrium_residual", max_res);
    s.set_str("timing_profile", if cfg!(debug_assertions) { "dev" } else { "release" });
    LinePlot::new("Grid membranes: time vs free nodes", "free nodes", "time (s)")
        .log(true, true)
        .with(Series::new("sparse factorisation", fac_pts))
        .with(Series::new("sparse solve (3 RHS)", sol_pts))
        .with(Series::new("dense factorisation", dfac))
        .with(Series::new("dense solve (3 RHS)", dsol))
        .write_png(&ctx.out_dir.join("scaling.png"))?;
    Ok(s)
}

// ---------------------------------------------------------------------------------------------
// nonlinear-vs-fdm

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct NonlinearParams {
    /// Multiples of the base load.
    load_scales: Vec<f64>,
    /// Base load magnitude on the biceps middle nodes (force units).
    base_load: f64,
    /// Bar stiffness k.
    k: f64,
    /// Rest length as a fraction of the modelled length (pretension).
    prestress: f64,
    /// Timing repetitions.
    reps: usize,
}

/// The 12-free-node arm net, free and fixed rest positions, bar lengths, biceps-mid load pattern.
type ArmNet = (BarNet, Vec<Pt3>, Vec<Pt3>, Vec<f64>, Vec<Vec3>);

fn arm_net() -> Result<ArmNet> {
    let arm = barnet::arm::Arm::new(&Default::default()).map_err(bn)?;
    let mut free = vec![false; arm.mesh.positions.len()];
    for v in arm.named("biceps_triceps_12").map_err(bn)? {
        free[v as usize] = true;
    }
    let net = BarNet::from_mesh_edges(&arm.mesh, &free, 1.0).map_err(bn)?;
    let (fr, fx, index) = net.index_maps();
    let pos = &arm.mesh.positions;
    let xf: Vec<Pt3> = fr.iter().map(|&v| pos[v as usize]).collect();
    let xs: Vec<Pt3> = fx.iter().map(|&v| pos[v as usize]).collect();
    let len = net.bars.iter().map(|b| (pos[b.a as usize] - pos[b.b as usize]).norm()).collect();
    let mut pattern = vec![Vec3::zeros(); fr.len()];
    for v in arm.named("biceps_mid").map_err(bn)? {
        let p = pos[v as usize];
        pattern[index[v as usize] as usize] = Vec3::new(0.0, p.y, p.z).normalize();
    }
    Ok((net, xf, xs, len, pattern))
}

fn run_nonlinear_vs_fdm(ctx: &RunCtx) -> Result<Summary> {
    let p: NonlinearParams = scene::load(&ctx.scene_file)?.params;
    let (net, xf, xs, len, pattern) = arm_net()?;
    let edge = len.iter().sum::<f64>() / len.len() as f64;
    let k = vec![p.k; net.bars.len()];
    let l0: Vec<f64> = len.iter().map(|l| p.prestress * l).collect();
    let zero = vec![Vec3::zeros(); xf.len()];
    let p0 = Elastic::new(&net, &k, &l0, &zero, &xs, &xf).gradient(&xf);
    let mut fnet = net.clone();
    for b in &mut fnet.bars {
        b.q = p.k * (1.0 - p.prestress);
    }
    let t0 = Instant::now();
    let fdm = FdmSolver::new(&fnet, &FdmOptions::default()).map_err(bn)?;
    let t_factor = t0.elapsed().as_secs_f64();
    let model = NonlinearModel::ElasticBars { k: k.clone(), rest_len: l0.clone() };
    let mut csv = CsvWriter::create(
        &ctx.out_dir.join("metrics.csv"),
        &[
            "load_scale",
            "shape_diff_rel_edge",
            "fdm_s",
            "newton_s",
            "newton_iters",
            "newton_converged",
            "fdm_residual",
            "max_disp_rel_edge",
        ],
    )?;
    let mut hist = CsvWriter::create(&ctx.out_dir.join("newton_history.csv"), &["load_scale", "iter", "grad_norm"])?;
    // Every mode runs the whole sweep: the 12-free-node net takes milliseconds.
    let scales = p.load_scales.clone();
    let (mut diff_pts, mut tf_pts, mut tn_pts) = (Vec::new(), Vec::new(), Vec::new());
    let (mut max_res, mut max_it, mut all_conv, mut ratio_at_1, mut diff_at_1): (f64, usize, bool, f64, f64) =
        (0.0, 0, true, f64::NAN, f64::NAN);
    for &lam in &scales {
        let loads: Vec<Vec3> = p0.iter().zip(&pattern).map(|(a, b)| a + b * (lam * p.base_load)).collect();
        let mut x = Vec::new();
        let mut tf = Vec::new();
        let mut info = Default::default();
        for _ in 0..p.reps.max(1) {
            let t = Instant::now();
            info = fdm.solve_into(&loads, &xs, &mut x).map_err(bn)?;
            tf.push(t.elapsed().as_secs_f64());
        }
        let info: barnet::SolveInfo = info;
        tf.sort_by(f64::total_cmp);
        let t_fdm = tf[tf.len() / 2];
        check_residual("nonlinear-vs-fdm", info.rel_residual, 1e-12)?;
        max_res = max_res.max(info.rel_residual);
        let t = Instant::now();
        let r = form_find_nonlinear(&net, &model, &loads, &xs, &xf, &NewtonOptions::default()).map_err(bn)?;
        let t_newton = t.elapsed().as_secs_f64();
        for (i, g) in r.history.iter().enumerate() {
            hist.row(&[lam.into(), i.into(), (*g).into()])?;
        }
        let diff = x.iter().zip(&r.x).map(|(a, b)| (a - b).norm()).fold(0.0, f64::max) / edge;
        let disp = r.x.iter().zip(&xf).map(|(a, b)| (a - b).norm()).fold(0.0, f64::max) / edge;
        max_it = max_it.max(r.iterations);
        all_conv &= r.converged;
        if (lam - 1.0).abs() < 1e-12 {
            ratio_at_1 = t_newton / t_fdm;
            diff_at_1 = diff;
        }
        diff_pts.push((lam, diff));
        tf_pts.push((lam, t_fdm));
        tn_pts.push((lam, t_newton));
        csv.row(&[
            lam.into(),
            diff.into(),
            t_fdm.into(),
            t_newton.into(),
            r.iterations.into(),
            (r.converged as usize).into(),
            info.rel_residual.into(),
            disp.into(),
        ])?;
    }
    // Schek's nonlinear FDM (prescribed forces) on a small membrane: residual history.
    let mut c = analytic::grid_net(5, 1.0);
    for v in 0..c.net.n_nodes {
        if !c.net.fixed[v] {
            c.loads[v] = Vec3::new(0.0, 0.0, 0.01);
        }
    }
    let (ml, mf) = c.split();
    let (fr, _, _) = c.net.index_maps();
    let mx0: Vec<Pt3> = fr.iter().map(|&v| c.positions[v as usize]).collect();
    let fp = form_find_nonlinear(
        &c.net,
        &NonlinearModel::PrescribedForces { s: vec![1.0; c.net.bars.len()] },
        &ml,
        &mf,
        &mx0,
        &NewtonOptions::default(),
    )
    .map_err(bn)?;
    let mut fph = CsvWriter::create(&ctx.out_dir.join("fixed_point_history.csv"), &["iter", "rel_change", "ratio"])?;
    let mut ratios = Vec::new();
    for (i, h) in fp.history.iter().enumerate() {
        let r = if i > 0 { h / fp.history[i - 1] } else { f64::NAN };
        if i >= 2 && r.is_finite() && *h > 1e-14 {
            ratios.push(r);
        }
        fph.row(&[i.into(), (*h).into(), r.into()])?;
    }
    LinePlot::new(
        "Linear FDM vs elastic-bar Newton: shape difference",
        "load scale",
        "max |x_FDM - x_Newton| / mean edge",
    )
    .log(true, true)
    .with(Series::new("difference", diff_pts))
    .write_png(&ctx.out_dir.join("shape_difference.png"))?;
    LinePlot::new("Time per frame", "load scale", "time (s)")
        .log(true, true)
        .with(Series::new("FDM (back-substitution)", tf_pts))
        .with(Series::new("Newton (elastic bars)", tn_pts))
        .write_png(&ctx.out_dir.join("time.png"))?;
    let mut s = Summary::new();
    s.set("max_equilibrium_residual", max_res);
    s.set_count("newton_iters_max", max_it as u64);
    s.set_count("newton_converged_all", all_conv as u64);
    s.set("time_ratio_newton_vs_fdm", ratio_at_1);
    s.set("shape_diff_rel_edge_at_scale1", diff_at_1);
    s.set("fdm_factor_s", t_factor);
    s.set_count("fixed_point_iters", fp.iterations as u64);
    s.set_count("fixed_point_converged", fp.converged as u64);
    if !ratios.is_empty() {
        s.set("fixed_point_contraction_max", ratios.iter().copied().fold(0.0, f64::max));
    }
    Ok(s)
}

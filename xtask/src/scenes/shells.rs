//! Scenes of the `shells` crate (shells.md §6): `calib-bend`, `cantilever`, `drape`,
//! `fold-stress`, `plastic-crease`, `wind-flag`.
//!
//! Every simulated scene writes `frames/NNNN.obj` as soon as a frame is computed, `steps.csv`
//! (per-step timings and counts) and `frames.csv` (per-frame energies, intersections), so a long
//! or failing run keeps what it finished. Effects are opt-in per scene file; runs that compare
//! "with" and "without" an effect (drape: collisions, wind-flag: wind) build the second
//! simulation from the same file with that effect removed and time both in the same run.

use std::path::Path;
use std::sync::Arc;
use std::time::Instant;

use geom_core::io::{write_obj_frame, MeshOut};
use geom_core::math::{Pt3, Vec3};
use serde::Deserialize;
use shells::calib;
use shells::collision::count_self_intersections;
use shells::scene::{BuiltScene, ShellScene};
use shells::{
    BlockTriplets, ExternalForce, Material, PlasticRule, Plasticity, ShellSceneDesc, ShellSim,
    StepStats, VertexConstraint,
};

use crate::error::{Error, Result};
use crate::out::{Cell, CsvWriter, Summary};
use crate::plot::{LinePlot, Series};
use crate::registry::{RunCtx, Runner};
use crate::scene::{self, Mode};

/// Adds the shells runners.
pub fn register(v: &mut Vec<Runner>) {
    v.push(Runner { method: "shells/calib-bend", run: run_calib });
    v.push(Runner { method: "shells/cantilever", run: run_cantilever });
    v.push(Runner { method: "shells/drape", run: run_drape });
    v.push(Runner { method: "shells/fold-stress", run: run_fold });
    v.push(Runner { method: "shells/plastic-crease", run: run_plastic });
    v.push(Runner { method: "shells/wind-flag", run: run_wind });
}

fn err(e: shells::Error) -> Error {
    Error::Run(format!("shells: {e}"))
}

fn threads() -> u64 {
    rayon::current_num_threads() as u64
}

/// Runs `frames` frames of `substeps` steps each, writing OBJ frames (every `obj_every`),
/// `steps.csv` and `frames.csv` progressively into `dir`. Returns per-run statistics.
struct RunStats {
    steps: u64,
    wall_s: f64,
    step_wall: Vec<f64>,
    max_intersections: u64,
    nan_steps: u64,
    totals: StepStats,
    max_zone: u32,
    max_zones_per_step: u32,
    error: Option<String>,
}

struct RunOpts<'a> {
    dir: &'a Path,
    frames: usize,
    substeps: u32,
    h: f64,
    obj_every: usize,
    count_intersections: bool,
    write: bool,
}

fn simulate(sim: &mut ShellSim, faces: &[[u32; 3]], o: &RunOpts, mut per_frame: impl FnMut(&ShellSim, usize)) -> Result<RunStats> {
    let mut rs = RunStats {
        steps: 0,
        wall_s: 0.0,
        step_wall: Vec::new(),
        max_intersections: 0,
        nan_steps: 0,
        totals: StepStats::default(),
        max_zone: 0,
        max_zones_per_step: 0,
        error: None,
    };
    let (mut steps_csv, mut frames_csv) = if o.write {
        (
            Some(CsvWriter::create(
                &o.dir.join("steps.csv"),
                &[
                    "t", "h", "wall_s", "assembly_s", "factor_s", "solve_s", "collision_s", "lin_residual", "n_proximity",
                    "n_ccd", "n_zones", "plastic_events", "regularization",
                ],
            )?),
            Some(CsvWriter::create(
                &o.dir.join("frames.csv"),
                &["frame", "t", "wall_s", "kinetic_J", "membrane_J", "bending_J", "gravity_J", "intersections"],
            )?),
        )
    } else {
        (None, None)
    };
    if o.write {
        write_obj_frame(&o.dir.join("frames"), 0, &MeshOut::tri(&sim.state().q, faces))?;
    }
    'outer: for f in 1..=o.frames {
        let tf = Instant::now();
        for _ in 0..o.substeps {
            let t0 = Instant::now();
            match sim.step(o.h) {
                Ok(st) => {
                    let dt = t0.elapsed().as_secs_f64();
                    rs.steps += 1;
                    rs.wall_s += dt;
                    rs.step_wall.push(dt);
                    let t = &mut rs.totals;
                    t.t_assembly += st.t_assembly;
                    t.t_factor += st.t_factor;
                    t.t_solve += st.t_solve;
                    t.t_collision += st.t_collision;
                    t.n_proximity += st.n_proximity;
                    t.n_ccd += st.n_ccd;
                    t.n_impact_zones += st.n_impact_zones;
                    t.n_frozen += st.n_frozen;
                    t.plastic_events += st.plastic_events;
                    t.lin_residual = t.lin_residual.max(st.lin_residual);
                    t.regularization_shift = t.regularization_shift.max(st.regularization_shift);
                    rs.max_zone = rs.max_zone.max(st.max_zone_size);
                    rs.max_zones_per_step = rs.max_zones_per_step.max(st.n_impact_zones);
                    if let Some(c) = steps_csv.as_mut() {
                        c.row(&[
                            Cell::Num(sim.state().t),
                            Cell::Num(o.h),
                            Cell::Num(dt),
                            Cell::Num(st.t_assembly),
                            Cell::Num(st.t_factor),
                            Cell::Num(st.t_solve),
                            Cell::Num(st.t_collision),
                            Cell::Num(st.lin_residual),
                            Cell::Int(st.n_proximity as i64),
                            Cell::Int(st.n_ccd as i64),
                            Cell::Int(st.n_impact_zones as i64),
                            Cell::Int(st.plastic_events as i64),
                            Cell::Num(st.regularization_shift),
                        ])?;
                    }
                }
                Err(e) => {
                    if matches!(e, shells::Error::Diverged { .. }) {
                        rs.nan_steps += 1;
                    }
                    rs.error = Some(e.to_string());
                    break 'outer;
                }
            }
        }
        let inter = if o.count_intersections { count_self_intersections(&sim.state().q, faces) as u64 } else { 0 };
        rs.max_intersections = rs.max_intersections.max(inter);
        if o.write {
            if o.obj_every > 0 && f % o.obj_every == 0 {
                write_obj_frame(&o.dir.join("frames"), f, &MeshOut::tri(&sim.state().q, faces))?;
            }
            let e = sim.energies();
            if let Some(c) = frames_csv.as_mut() {
                c.row(&[
                    Cell::Int(f as i64),
                    Cell::Num(sim.state().t),
                    Cell::Num(tf.elapsed().as_secs_f64()),
                    Cell::Num(e.kinetic),
                    Cell::Num(e.membrane),
                    Cell::Num(e.bending),
                    Cell::Num(e.gravity),
                    Cell::Int(inter as i64),
                ])?;
            }
        }
        per_frame(sim, f);
    }
    Ok(rs)
}

fn median(v: &[f64]) -> f64 {
    if v.is_empty() {
        return f64::NAN;
    }
    let mut s = v.to_vec();
    s.sort_by(|a, b| a.total_cmp(b));
    s[s.len() / 2]
}

fn mean(v: &[f64]) -> f64 {
    v.iter().sum::<f64>() / v.len().max(1) as f64
}

fn build(shell: &ShellScene) -> Result<BuiltScene> {
    shell.build(&crate::out::workspace_root()).map_err(err)
}

fn write_report(ctx: &RunCtx, text: &str) -> Result<()> {
    let p = ctx.out_dir.join("report.md");
    std::fs::write(&p, text).map_err(crate::error::io_err(&p))
}

// ---------------------------------------------------------------------------------------------
// calib-bend

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct CalibParams {
    /// Patch size (m).
    patch: f64,
    /// Edge lengths ℓ (m).
    ells: Vec<f64>,
    /// Cylinder radius (m).
    cylinder_radius: f64,
    /// Sphere radius (m); the patch must stay ≤ 0.2 R.
    sphere_radius: f64,
    /// ℓ at which the Must-hold figures are read (m).
    report_ell: f64,
}

fn run_calib(ctx: &RunCtx) -> Result<Summary> {
    let p: CalibParams = scene::load(&ctx.scene_file)?.params;
    if p.ells.iter().any(|&l| !(l > 0.0) || l > p.patch / 4.0) || !(p.cylinder_radius > 0.0) || !(p.sphere_radius > 0.0) {
        return Err(scene::invalid(&ctx.scene_file, "ells must be in (0, patch/4], radii > 0"));
    }
    let mut csv = CsvWriter::create(
        &ctx.out_dir.join("calib.csv"),
        &["ell_m", "orientation", "cylinder_ratio", "cylinder_rel_err", "sphere_ratio", "sphere_rel_err"],
    )?;
    let mut s = Summary::new();
    let (mut cyl_err, mut sph_err) = (0.0f64, 0.0f64);
    let mut cyl_series = Vec::new();
    let mut sph_series = Vec::new();
    let mut rows = String::new();
    for &ell in &p.ells {
        let (mut wc, mut ws) = (0.0f64, 0.0f64);
        for rotated in [false, true] {
            let c = calib::measure(p.patch, ell, rotated, p.cylinder_radius, false).map_err(err)?;
            let sp = calib::measure(p.patch, ell, rotated, p.sphere_radius, true).map_err(err)?;
            csv.row(&[
                Cell::Num(ell),
                Cell::Text(if rotated { "rows-along-y" } else { "rows-along-x" }.into()),
                Cell::Num(c.ratio),
                Cell::Num(c.rel_err),
                Cell::Num(sp.ratio),
                Cell::Num(sp.rel_err),
            ])?;
            rows += &format!(
                "| {ell} | {} | {:.4} | {:.4} |\n",
                if rotated { "rows along y" } else { "rows along x" },
                c.ratio,
                sp.ratio
            );
            wc = wc.max(c.rel_err);
            ws = ws.max(sp.rel_err);
        }
        cyl_series.push((ell, wc));
        sph_series.push((ell, ws));
        if (ell - p.report_ell).abs() <= 1e-12 * p.report_ell {
            cyl_err = wc;
            sph_err = ws;
        }
    }
    LinePlot::new("Bending calibration: worst relative error of the energy density", "edge length ℓ (m)", "relative error")
        .log(true, true)
        .with(Series::new("cylinder vs 3k_B/R²", cyl_series))
        .with(Series::new("sphere vs 4k_B/R²", sph_series))
        .write_png(&ctx.out_dir.join("calib.png"))?;
    s.set("cylinder_rel_err", cyl_err);
    s.set("sphere_rel_err", sph_err);
    s.set("report_ell_m", p.report_ell);
    write_report(
        ctx,
        &format!(
            "### shells/calib-bend\n\nInterior bending-energy density of an equilateral patch divided by k_B/R² \
             (ideal: 3 on the cylinder R = {} m, 4 on the sphere R = {} m; spec §3.2).\n\n\
             | ℓ (m) | lattice | cylinder | sphere |\n|---|---|---|---|\n{rows}\n\
             Worst of the two orientations at ℓ = {}: cylinder {:.2e}, sphere {:.2e} (Must hold ≤ 0.01).\n",
            p.cylinder_radius, p.sphere_radius, p.report_ell, cyl_err, sph_err
        ),
    )?;
    Ok(s)
}

// ---------------------------------------------------------------------------------------------
// cantilever

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct CantileverParams {
    /// Strip length (m).
    length: f64,
    /// Strip width (m).
    width: f64,
    /// Vertices along the length per resolution (default mode); the last is the finest.
    nx: Vec<u32>,
    /// Quick-mode resolutions.
    quick_nx: Vec<u32>,
    /// Vertices across the width.
    ny: u32,
    /// Hinge stiffness k_B (J); EI = 6 k_B · width.
    bending: f64,
    /// Membrane Yt (N/m), large: the strip is nearly inextensible.
    young_thickness: f64,
    /// Load steps for the end moment.
    moment_load_steps: u32,
    /// Newton iterations per load step.
    newton_iters: u32,
    /// Small tip load as a fraction of the linear-theory deflection: δ/L.
    small_deflection: f64,
}

/// Conservative end moment on the last column pair: V = −M φ, φ the angle of the end segment
/// in the x–z plane (work-conjugate to the end rotation; a follower moment).
struct EndMoment {
    pairs: Vec<(u32, u32, f64)>,
    moment: std::sync::Mutex<f64>,
}

impl ExternalForce for EndMoment {
    fn add_forces(&self, _t: f64, q: &[Pt3], _v: &[Vec3], f: &mut [Vec3]) {
        let m = *self.moment.lock().expect("moment lock is never poisoned (no panics inside)");
        for &(tip, prev, w) in &self.pairs {
            let d = q[tip as usize] - q[prev as usize];
            let l2 = d.x * d.x + d.z * d.z;
            let g = Vec3::new(-d.z, 0.0, d.x) / l2;
            f[tip as usize] += m * w * g;
            f[prev as usize] -= m * w * g;
        }
    }
    fn add_jacobians(&self, _t: f64, _q: &[Pt3], _v: &[Vec3], _jx: &mut BlockTriplets, _jv: &mut BlockTriplets) {}
}

/// Dead tip load.
struct TipLoad(Vec<(u32, Vec3)>);
impl ExternalForce for TipLoad {
    fn add_forces(&self, _t: f64, _q: &[Pt3], _v: &[Vec3], f: &mut [Vec3]) {
        for &(i, p) in &self.0 {
            f[i as usize] += p;
        }
    }
}

fn strip_desc(p: &CantileverParams, nx: u32, custom: Arc<dyn ExternalForce>) -> Result<(ShellSceneDesc, Vec<[u32; 3]>)> {
    use geom_core::procedural::{grid, Diagonals, GridSpec, Plane};
    let g = grid(&GridSpec {
        quads: [nx - 1, p.ny - 1],
        size: [p.length, p.width],
        plane: Plane::XY,
        diagonals: Diagonals::Alternating,
        center: Pt3::origin(),
    })?;
    let mut pins = Vec::new();
    for j in 0..p.ny {
        pins.extend([j * nx, j * nx + 1]);
    }
    let material = Material {
        density: 0.01,
        membrane: shells::MembraneLaw::Isotropic { young_thickness: p.young_thickness, poisson: 0.0, compression_softening: None },
        bending: p.bending,
        damping: shells::Damping::None,
        plasticity: None,
    };
    let mut effects = shells::Effects::default();
    effects.custom.push(custom);
    let desc = ShellSceneDesc {
        rest: g.positions.clone(),
        faces: g.faces.clone(),
        uv: None,
        initial: None,
        initial_velocity: None,
        material,
        effects,
        constraints: vec![VertexConstraint::Pinned(pins)],
        integrator: shells::IntegratorSettings { newton_iters: p.newton_iters, ..Default::default() },
        t0: 0.0,
    };
    Ok((desc, g.faces.clone()))
}

fn run_cantilever(ctx: &RunCtx) -> Result<Summary> {
    let p: CantileverParams = scene::load(&ctx.scene_file)?.params;
    let res = if ctx.mode == Mode::Quick { p.quick_nx.clone() } else { p.nx.clone() };
    if res.is_empty() || res.iter().any(|&n| n < 4) || p.ny < 2 {
        return Err(scene::invalid(&ctx.scene_file, "nx entries must be ≥ 4 and ny ≥ 2"));
    }
    let mut csv = CsvWriter::create(
        &ctx.out_dir.join("cantilever.csv"),
        &["nx", "edge_m", "moment_circle_gap_rel", "tip_deflection_m", "beam_theory_m", "small_load_tip_rel_err"],
    )?;
    let ei = 6.0 * p.bending * p.width;
    let h = 1e3; // quasi-static: inertia negligible against h²K
    let mut last = (f64::NAN, f64::NAN);
    let mut rows = String::new();
    let mut conv = Vec::new();
    for &nx in &res {
        let dx = p.length / (nx - 1) as f64;
        let lfree = p.length - dx; // clamp = first two columns
        let mid = p.ny / 2;
        let root = mid * nx + 1;
        let tip = mid * nx + nx - 1;
        // Pure end moment M = 2πEI/L ramped over load steps.
        let wts: Vec<f64> = (0..p.ny).map(|j| if j == 0 || j == p.ny - 1 { 0.5 } else { 1.0 } / (p.ny - 1) as f64).collect();
        let em = Arc::new(EndMoment {
            pairs: (0..p.ny).map(|j| (j * nx + nx - 1, j * nx + nx - 2, wts[j as usize])).collect(),
            moment: std::sync::Mutex::new(0.0),
        });
        let (desc, faces) = strip_desc(&p, nx, em.clone())?;
        let mut sim = ShellSim::new(desc).map_err(err)?;
        let mtot = 2.0 * std::f64::consts::PI * ei / lfree;
        let n_load = p.moment_load_steps.max(1);
        for k in 1..=n_load + 20 {
            *em.moment.lock().expect("moment lock is never poisoned") = mtot * (k.min(n_load) as f64 / n_load as f64);
            sim.step(h).map_err(err)?;
        }
        let gap = (sim.state().q[tip as usize] - sim.state().q[root as usize]).norm() / lfree;
        write_obj_frame(&ctx.out_dir.join(format!("moment_nx{nx}")), 0, &MeshOut::tri(&sim.state().q, &faces))?;
        // Small tip load P: δ = P L³ / (3 EI).
        let delta_want = p.small_deflection * lfree;
        let pload = 3.0 * ei * delta_want / lfree.powi(3);
        let loads: Vec<(u32, Vec3)> = (0..p.ny).map(|j| (j * nx + nx - 1, Vec3::new(0.0, 0.0, -pload * wts[j as usize]))).collect();
        let (desc, _) = strip_desc(&p, nx, Arc::new(TipLoad(loads)))?;
        let mut sim = ShellSim::new(desc).map_err(err)?;
        for _ in 0..30 {
            sim.step(h).map_err(err)?;
        }
        let d = -(0..p.ny).map(|j| sim.state().q[(j * nx + nx - 1) as usize].z * wts[j as usize]).sum::<f64>();
        let rel = (d - delta_want).abs() / delta_want;
        csv.row(&[Cell::Int(nx as i64), Cell::Num(dx), Cell::Num(gap), Cell::Num(d), Cell::Num(delta_want), Cell::Num(rel)])?;
        rows += &format!("| {nx} | {dx:.4} | {gap:.4} | {d:.5e} | {delta_want:.5e} | {rel:.4} |\n");
        conv.push((dx, gap));
        last = (gap, rel);
    }
    LinePlot::new("End moment 2πEI/L: end-point gap over L", "edge length (m)", "gap / L")
        .log(true, true)
        .with(Series::new("gap", conv))
        .write_png(&ctx.out_dir.join("cantilever.png"))?;
    let mut s = Summary::new();
    s.set("moment_circle_gap_rel", last.0);
    s.set("small_load_tip_rel_err", last.1);
    s.set_count("finest_nx", *res.last().unwrap_or(&0) as u64);
    write_report(
        ctx,
        &format!(
            "### shells/cantilever\n\nStrip {} m × {} m clamped at one end (EI = 6k_B·w). End moment 2πEI/L must close a \
             circle; small tip load vs beam theory δ = PL³/(3EI).\n\n| nx | ℓ (m) | gap/L | δ (m) | theory (m) | rel. err |\n\
             |---|---|---|---|---|---|\n{rows}",
            p.length, p.width
        ),
    )?;
    Ok(s)
}

// ---------------------------------------------------------------------------------------------
// drape

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct DrapeParams {
    pub(crate) shell: ShellScene,
    /// Quick mode: grid vertices per side and duration (s).
    pub(crate) quick_grid: u32,
    pub(crate) quick_duration: f64,
    /// Write every n-th frame as OBJ.
    pub(crate) obj_every: usize,
}

fn with_grid(shell: &ShellScene, n: u32) -> ShellScene {
    let mut s = shell.clone();
    if let shells::scene::MeshSpec::Grid { nx, ny, .. } = &mut s.mesh {
        *nx = n;
        *ny = n;
    }
    s
}

fn run_drape(ctx: &RunCtx) -> Result<Summary> {
    let p: DrapeParams = scene::load(&ctx.scene_file)?.params;
    let shell = if ctx.mode == Mode::Quick {
        let mut s = with_grid(&p.shell, p.quick_grid);
        s.duration = p.quick_duration;
        s
    } else {
        p.shell.clone()
    };
    let fps = shell.integrator.fps;
    let frames = (shell.duration * fps).round() as usize;
    let mut s = Summary::new();
    // With collisions (as listed in the scene file).
    let b = build(&shell)?;
    let faces = b.desc.faces.clone();
    let nv = b.desc.rest.len();
    let mut sim = ShellSim::new(b.desc).map_err(err)?;
    let e0 = sim.energies().total();
    let p0 = sim.momentum();
    let o = RunOpts {
        dir: &ctx.out_dir,
        frames,
        substeps: shell.integrator.substeps,
        h: shell.integrator.h(),
        obj_every: p.obj_every,
        count_intersections: true,
        write: true,
    };
    let with = simulate(&mut sim, &faces, &o, |_, _| {})?;
    let e1 = sim.energies().total();
    // Without collisions: same file, effect removed, same duration, timed in the same run.
    let mut nocol = shell.clone();
    nocol.effects.collision = None;
    nocol.effects.self_collision = false;
    let b2 = build(&nocol)?;
    let mut sim2 = ShellSim::new(b2.desc).map_err(err)?;
    let dir2 = ctx.out_dir.join("no-collision");
    let o2 = RunOpts { dir: &dir2, write: false, count_intersections: true, ..o };
    let without = simulate(&mut sim2, &faces, &o2, |_, _| {})?;
    s.set_count("n_vertices", nv as u64);
    s.set_count("threads", threads());
    s.set_count("steps", with.steps);
    s.set_count("max_intersections", with.max_intersections);
    s.set_count("nan_steps", with.nan_steps);
    s.set("s_per_step", with.wall_s / with.steps.max(1) as f64);
    s.set("s_per_step_median", median(&with.step_wall));
    s.set("s_per_step_no_collision", without.wall_s / without.steps.max(1) as f64);
    s.set("collision_share", with.totals.t_collision / with.wall_s.max(1e-300));
    s.set("assembly_s", with.totals.t_assembly);
    s.set("factor_s", with.totals.t_factor);
    s.set("solve_s", with.totals.t_solve);
    s.set("collision_s", with.totals.t_collision);
    s.set_count("no_collision_max_intersections", without.max_intersections);
    s.set("energy_start_J", e0);
    s.set("energy_end_J", e1);
    s.set("momentum_change", (sim.momentum() - p0).norm());
    s.set_count("ccd_events", with.totals.n_ccd as u64);
    s.set_count("frozen_vertices", with.totals.n_frozen as u64);
    s.set_str("profile", if cfg!(debug_assertions) { "dev" } else { "release" });
    if let Some(e) = &with.error {
        return Err(Error::Run(format!("drape failed after {} steps (frames kept): {e}", with.steps)));
    }
    write_report(
        ctx,
        &format!(
            "### shells/drape\n\n{nv} vertices, {} threads, {} steps. Per implicit step: {:.4} s with self-collision, \
             {:.4} s without (collisions {:.0}% of the time). Max intersecting triangle pairs: {} with collisions, {} \
             without.\n",
            threads(),
            with.steps,
            with.wall_s / with.steps.max(1) as f64,
            without.wall_s / without.steps.max(1) as f64,
            100.0 * with.totals.t_collision / with.wall_s.max(1e-300),
            with.max_intersections,
            without.max_intersections
        ),
    )?;
    Ok(s)
}

// ---------------------------------------------------------------------------------------------
// fold-stress

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct FoldParams {
    shell: ShellScene,
    /// Quick mode grid (nx, ny) and duration (s).
    quick_grid: (u32, u32),
    quick_duration: f64,
    obj_every: usize,
}

fn run_fold(ctx: &RunCtx) -> Result<Summary> {
    let p: FoldParams = scene::load(&ctx.scene_file)?.params;
    let mut shell = p.shell.clone();
    if ctx.mode == Mode::Quick {
        if let shells::scene::MeshSpec::Grid { nx, ny, .. } = &mut shell.mesh {
            *nx = p.quick_grid.0;
            *ny = p.quick_grid.1;
        }
        shell.duration = p.quick_duration;
    }
    let b = build(&shell)?;
    let faces = b.desc.faces.clone();
    let mut sim = ShellSim::new(b.desc).map_err(err)?;
    let frames = (shell.duration * shell.integrator.fps).round() as usize;
    let o = RunOpts {
        dir: &ctx.out_dir,
        frames,
        substeps: shell.integrator.substeps,
        h: shell.integrator.h(),
        obj_every: p.obj_every,
        count_intersections: true,
        write: true,
    };
    let r = simulate(&mut sim, &faces, &o, |_, _| {})?;
    let ymin = sim.state().q.iter().map(|q| q.y).fold(f64::INFINITY, f64::min);
    let ymax = sim.state().q.iter().map(|q| q.y).fold(f64::NEG_INFINITY, f64::max);
    let mut s = Summary::new();
    s.set_count("max_intersections", r.max_intersections);
    s.set_count("nan_steps", r.nan_steps);
    s.set_count("steps", r.steps);
    s.set_count("ccd_events", r.totals.n_ccd as u64);
    s.set_count("impact_zones", r.totals.n_impact_zones as u64);
    s.set_count("max_zone_size", r.max_zone as u64);
    s.set_count("frozen_vertices", r.totals.n_frozen as u64);
    s.set_count("proximity_pairs", r.totals.n_proximity as u64);
    s.set("collision_share", r.totals.t_collision / r.wall_s.max(1e-300));
    s.set("s_per_step", r.wall_s / r.steps.max(1) as f64);
    s.set("final_height_span_m", ymax - ymin);
    s.set_count("threads", threads());
    if let Some(e) = &r.error {
        return Err(Error::Run(format!("fold-stress failed after {} steps (frames kept): {e}", r.steps)));
    }
    Ok(s)
}

// ---------------------------------------------------------------------------------------------
// plastic-crease

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct PlasticParams {
    shell: ShellScene,
    /// Kinematic half: vertices with x ≥ this (m) rotate about the line x = 0 (along z).
    kinematic_from_x: f64,
    /// Peak rotation (degrees) reached at half of `motion_time`.
    peak_deg: f64,
    /// Duration of the there-and-back rotation (s).
    motion_time: f64,
    /// Settling time after release (s).
    settle_time: f64,
    /// Yield values Δκ_max (1/m; `inf` allowed as 1e300).
    yields: Vec<f64>,
    /// Hardening values η (m).
    hardenings: Vec<f64>,
    /// Substeps for the step-size study.
    substeps_study: Vec<u32>,
    /// Yield used in the step-size study (1/m).
    study_yield: f64,
    /// Quick mode: grid and study substeps.
    quick_grid: (u32, u32),
    quick_substeps_study: Vec<u32>,
}

struct CreaseOut {
    crease: f64,
    k_ratio: f64,
    final_max_angle: f64,
}

fn crease_run(p: &PlasticParams, shell: &ShellScene, plasticity: Option<Plasticity>, substeps: u32) -> Result<CreaseOut> {
    let mut sh = shell.clone();
    sh.material.plasticity = plasticity;
    sh.integrator.substeps = substeps;
    let b = build(&sh)?;
    let rest = b.desc.rest.clone();
    let kin: Vec<u32> = (0..rest.len() as u32).filter(|&i| rest[i as usize].x >= p.kinematic_from_x).collect();
    let peak = p.peak_deg.to_radians();
    let tm = p.motion_time;
    let rest_k = rest.clone();
    let path = move |t: f64, i: u32| {
        let phi = peak * (std::f64::consts::PI * (t / tm).min(1.0)).sin().powi(2);
        let x = rest_k[i as usize];
        Pt3::new(x.x * phi.cos() - x.y * phi.sin(), x.x * phi.sin() + x.y * phi.cos(), x.z)
    };
    let mut desc = b.desc;
    desc.constraints.push(VertexConstraint::Kinematic(kin, Box::new(path)));
    let h = sh.integrator.h();
    let mut sim = ShellSim::new(desc).map_err(err)?;
    let theta0 = sim.rest_angles();
    let k0 = sim.hinge_stiffness();
    let n1 = (tm / h).round() as usize;
    for _ in 0..n1 {
        sim.step(h).map_err(err)?;
    }
    // Release the kinematic half and let it settle.
    let b2 = build(&sh)?;
    let mut d2 = b2.desc;
    d2.initial = Some(sim.state().q.clone());
    d2.initial_velocity = Some(sim.state().v.clone());
    let theta_bar = sim.rest_angles();
    let kk = sim.hinge_stiffness();
    let mut sim2 = ShellSim::new(d2).map_err(err)?;
    sim2.set_rest_angles(&theta_bar).map_err(err)?;
    sim2.set_hinge_stiffness(&kk).map_err(err)?;
    let n2 = (p.settle_time / h).round() as usize;
    for _ in 0..n2 {
        sim2.step(h).map_err(err)?;
    }
    let crease = sim2.rest_angles().iter().zip(&theta0).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
    let k_ratio = sim2.hinge_stiffness().iter().zip(&k0).map(|(a, b)| a / b).fold(1.0, |m: f64, r| if (r - 1.0).abs() > (m - 1.0).abs() { r } else { m });
    let final_max_angle = sim2.hinge_angles(&sim2.state().q).iter().fold(0.0f64, |m, a| m.max(a.abs()));
    Ok(CreaseOut { crease, k_ratio, final_max_angle })
}

fn run_plastic(ctx: &RunCtx) -> Result<Summary> {
    let p: PlasticParams = scene::load(&ctx.scene_file)?.params;
    let mut shell = p.shell.clone();
    let study = if ctx.mode == Mode::Quick {
        if let shells::scene::MeshSpec::Grid { nx, ny, .. } = &mut shell.mesh {
            *nx = p.quick_grid.0;
            *ny = p.quick_grid.1;
        }
        p.quick_substeps_study.clone()
    } else {
        p.substeps_study.clone()
    };
    let base_sub = shell.integrator.substeps;
    let mut csv = CsvWriter::create(
        &ctx.out_dir.join("crease.csv"),
        &["rule", "yield_per_m", "hardening_m", "substeps", "crease_angle_rad", "stiffness_ratio", "final_max_angle_rad"],
    )?;
    let mut s = Summary::new();
    let mut rows = String::new();
    let mut elastic_angle = f64::NAN;
    let mut record = |rule: &str, y: f64, eta: f64, sub: u32, c: &CreaseOut, csv: &mut CsvWriter| -> Result<()> {
        csv.row(&[
            Cell::Text(rule.into()),
            Cell::Num(y),
            Cell::Num(eta),
            Cell::Int(sub as i64),
            Cell::Num(c.crease),
            Cell::Num(c.k_ratio),
            Cell::Num(c.final_max_angle),
        ])?;
        rows += &format!("| {rule} | {y} | {eta} | {sub} | {:.4} | {:.3} | {:.4} |\n", c.crease, c.k_ratio, c.final_max_angle);
        Ok(())
    };
    for &y in &p.yields {
        let etas: Vec<f64> = if y >= 1e299 { vec![0.0] } else { p.hardenings.clone() };
        for &eta in &etas {
            let pl = (y < 1e299).then_some(Plasticity { max_curvature_dev: y, hardening: eta, rule: PlasticRule::ReturnMapping });
            let c = crease_run(&p, &shell, pl, base_sub)?;
            if pl.is_none() {
                elastic_angle = c.final_max_angle;
            }
            record("ReturnMapping", y, eta, base_sub, &c, &mut csv)?;
        }
    }
    let mut spreads = Vec::new();
    for rule in [PlasticRule::ReturnMapping, PlasticRule::SeedLiteral] {
        let mut angles = Vec::new();
        for &sub in &study {
            let pl = Plasticity { max_curvature_dev: p.study_yield, hardening: 0.0, rule };
            let c = crease_run(&p, &shell, Some(pl), sub)?;
            record(&format!("{rule:?}"), p.study_yield, 0.0, sub, &c, &mut csv)?;
            angles.push(c.crease);
        }
        let mx = angles.iter().cloned().fold(f64::NEG_INFINITY, f64::max);
        let mn = angles.iter().cloned().fold(f64::INFINITY, f64::min);
        spreads.push((mx - mn) / mean(&angles).max(1e-300));
    }
    s.set("elastic_final_max_angle", elastic_angle);
    s.set("plastic_crease_spread", spreads[0]);
    s.set("seed_literal_crease_spread", spreads[1]);
    write_report(
        ctx,
        &format!(
            "### shells/plastic-crease\n\nFoil strip, one end pinned, the other half rotated by {}° and back, then released.\n\n\
             | rule | Δκ_max (1/m) | η (m) | substeps | crease max|θ̄−θ̄₀| (rad) | k/k₀ | final max|θ| (rad) |\n\
             |---|---|---|---|---|---|---|\n{rows}\nStep-size spread of the crease angle: return map {:.3}, seed-literal {:.3}.\n",
            p.peak_deg, spreads[0], spreads[1]
        ),
    )?;
    Ok(s)
}

// ---------------------------------------------------------------------------------------------
// wind-flag

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct WindParams {
    pub(crate) shell: ShellScene,
    pub(crate) quick_grid: (u32, u32),
    pub(crate) quick_duration: f64,
    /// Time after which the flutter and drag are measured (s).
    pub(crate) settle_time: f64,
    pub(crate) obj_every: usize,
}

fn run_wind(ctx: &RunCtx) -> Result<Summary> {
    let p: WindParams = scene::load(&ctx.scene_file)?.params;
    let mut shell = p.shell.clone();
    if ctx.mode == Mode::Quick {
        if let shells::scene::MeshSpec::Grid { nx, ny, .. } = &mut shell.mesh {
            *nx = p.quick_grid.0;
            *ny = p.quick_grid.1;
        }
        shell.duration = p.quick_duration;
    }
    let (nx, _) = match &shell.mesh {
        shells::scene::MeshSpec::Grid { nx, ny, .. } => (*nx, *ny),
        _ => return Err(scene::invalid(&ctx.scene_file, "wind-flag needs a Grid mesh")),
    };
    let b = build(&shell)?;
    let faces = b.desc.faces.clone();
    let ny = b.grid.map(|g| g.1).unwrap_or(2);
    let tip = (ny * nx - 1) as usize; // far corner of the last row
    let wind = shell.effects.wind.clone().ok_or_else(|| scene::invalid(&ctx.scene_file, "wind-flag needs a wind"))?;
    let wf = shells::wind::WindField::new(&wind);
    let mut sim = ShellSim::new(b.desc).map_err(err)?;
    let frames = (shell.duration * shell.integrator.fps).round() as usize;
    let o = RunOpts {
        dir: &ctx.out_dir,
        frames,
        substeps: shell.integrator.substeps,
        h: shell.integrator.h(),
        obj_every: p.obj_every,
        count_intersections: false,
        write: true,
    };
    let mut tip_z = Vec::new();
    let mut drag = Vec::new();
    let settle = p.settle_time.min(0.5 * shell.duration);
    let r = simulate(&mut sim, &faces, &o, |sim, _| {
        let st = sim.state();
        if st.t >= settle {
            tip_z.push(st.q[tip].z);
            let mut f = Vec3::zeros();
            for t in &faces {
                let x = t.map(|i| st.q[i as usize]);
                let v = t.map(|i| st.v[i as usize]);
                f += 3.0 * wf.triangle(&x, &v, st.t).0;
            }
            drag.push(f.dot(&wind.base.normalize()));
        }
    })?;
    if let Some(e) = &r.error {
        return Err(Error::Run(format!("wind-flag failed after {} steps (frames kept): {e}", r.steps)));
    }
    // Without wind, same file, same duration, timed in the same run.
    let mut nowind = shell.clone();
    nowind.effects.wind = None;
    let b2 = build(&nowind)?;
    let mut sim2 = ShellSim::new(b2.desc).map_err(err)?;
    let o2 = RunOpts { write: false, ..o };
    let r2 = simulate(&mut sim2, &faces, &o2, |_, _| {})?;
    // Flutter frequency: peak of the DFT of the tip's z displacement (mean removed).
    let fs = shell.integrator.fps;
    let freq = dominant_frequency(&tip_z, fs);
    let mut s = Summary::new();
    s.set("flutter_hz", freq);
    s.set("mean_drag_N", mean(&drag));
    s.set("s_per_step_wind", r.wall_s / r.steps.max(1) as f64);
    s.set("s_per_step_no_wind", r2.wall_s / r2.steps.max(1) as f64);
    s.set("wind_time_overhead", r.wall_s / r2.wall_s.max(1e-300) - 1.0);
    s.set_count("nan_steps", r.nan_steps);
    s.set_count("n_vertices", sim.state().q.len() as u64);
    s.set_count("threads", threads());
    Ok(s)
}

fn dominant_frequency(x: &[f64], fs: f64) -> f64 {
    let n = x.len();
    if n < 8 {
        return f64::NAN;
    }
    let m = mean(x);
    let (mut best, mut bf) = (0.0, f64::NAN);
    for k in 1..n / 2 {
        let (mut re, mut im) = (0.0, 0.0);
        for (j, v) in x.iter().enumerate() {
            let a = 2.0 * std::f64::consts::PI * (k * j) as f64 / n as f64;
            re += (v - m) * a.cos();
            im -= (v - m) * a.sin();
        }
        let p = re * re + im * im;
        if p > best {
            best = p;
            bf = k as f64 * fs / n as f64;
        }
    }
    bf
}

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
use geom_core::math::{Mat3, Pt3, Vec3};
use serde::Deserialize;
use shells::calib;
use shells::collision::count_self_intersections;
use shells::scene::{BuiltScene, ShellScene};
use shells::{
    BlockTriplets, ExternalForce, Material, PlasticRule, Plasticity, ShellSceneDesc, ShellSim, StepStats,
    VertexConstraint,
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
    v.push(Runner { method: "shells/contact", run: run_contact });
}

impl From<shells::Error> for Error {
    fn from(e: shells::Error) -> Self {
        Error::Run(format!("shells: {e}"))
    }
}

/// The contact suite (`shells::experiments::contact`).
fn run_contact(ctx: &RunCtx) -> Result<Summary> {
    crate::record::run_experiment(ctx, shells::experiments::contact::run)
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

fn simulate(
    sim: &mut ShellSim,
    faces: &[[u32; 3]],
    o: &RunOpts,
    mut per_frame: impl FnMut(&ShellSim, usize),
) -> Result<RunStats> {
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
                    "t",
                    "h",
                    "wall_s",
                    "assembly_s",
                    "factor_s",
                    "solve_s",
                    "collision_s",
                    "lin_residual",
                    "n_proximity",
                    "n_ccd",
                    "n_zones",
                    "plastic_events",
                    "regularization",
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
    if p.ells.iter().any(|&l| !positive(l) || l > p.patch / 4.0)
        || !positive(p.cylinder_radius)
        || !positive(p.sphere_radius)
    {
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
    LinePlot::new(
        "Bending calibration: worst relative error of the energy density",
        "edge length ℓ (m)",
        "relative error",
    )
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
    /// Strip width (m); the row count is the nearest odd number of lattice rows.
    width: f64,
    /// Equilateral edge lengths (default mode); the last is the finest.
    ells: Vec<f64>,
    /// Quick-mode edge lengths.
    quick_ells: Vec<f64>,
    /// Hinge stiffness k_B (J).
    bending: f64,
    /// Membrane Yt (N/m) of the end-moment run: large, so that the strip bends cylindrically
    /// (Searle parameter w²κ/t ≫ 1 with t = √(72 k_B/Yt)): plate rigidity EI = 6 k_B w.
    young_thickness_moment: f64,
    /// Membrane Yt (N/m) of the small-load run: w²κ/t ≪ 1, a free (anticlastic) beam.
    young_thickness_small: f64,
    /// Load steps for the end moment.
    moment_load_steps: u32,
    /// Newton iterations per load step.
    newton_iters: u32,
    /// Relaxation steps at full moment.
    hold_steps: u32,
    /// Fraction of the velocity kept between relaxation steps.
    relaxation_keep: f64,
    /// Small tip load, as the beam-theory deflection over L.
    small_deflection: f64,
}

/// Conservative end moment on each row's last segment: V = −M w_r φ_r, φ_r the angle of the
/// segment in the x–z plane (work-conjugate to the end rotation; a follower moment).
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
    /// J_x = M w ∇²φ (symmetric): with d = tip − prev in the x–z plane and r² = |d|²,
    /// ∂²φ/∂d² = [[2d_xd_z, d_z² − d_x²], [d_z² − d_x², −2d_xd_z]]/r⁴.
    fn add_jacobians(&self, _t: f64, q: &[Pt3], _v: &[Vec3], jx: &mut BlockTriplets, _jv: &mut BlockTriplets) {
        let m = *self.moment.lock().expect("moment lock is never poisoned (no panics inside)");
        for &(tip, prev, w) in &self.pairs {
            let d = q[tip as usize] - q[prev as usize];
            let r2 = d.x * d.x + d.z * d.z;
            let (a, b) = (2.0 * d.x * d.z / (r2 * r2), (d.z * d.z - d.x * d.x) / (r2 * r2));
            let mut hd = Mat3::zeros();
            hd[(0, 0)] = a;
            hd[(0, 2)] = b;
            hd[(2, 0)] = b;
            hd[(2, 2)] = -a;
            let k = m * w * hd;
            jx.push(tip, tip, k);
            jx.push(prev, prev, k);
            jx.push(tip, prev, -k);
            jx.push(prev, tip, -k);
        }
    }
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

/// An equilateral strip along x: even rows hold n+1 vertices at x = iℓ, odd rows n vertices at
/// (i+½)ℓ; returns positions, faces and the vertex rows.
fn equilateral_strip(length: f64, ell: f64, rows: u32) -> (Vec<Pt3>, Vec<[u32; 3]>, Vec<Vec<u32>>) {
    let n = (length / ell).round() as usize;
    let dy = ell * 3f64.sqrt() / 2.0;
    let mut p = Vec::new();
    let mut rv: Vec<Vec<u32>> = Vec::new();
    for j in 0..rows as usize {
        let odd = j % 2 == 1;
        let cnt = if odd { n } else { n + 1 };
        let mut r = Vec::with_capacity(cnt);
        for i in 0..cnt {
            let x = (i as f64 + if odd { 0.5 } else { 0.0 }) * ell;
            r.push(p.len() as u32);
            p.push(Pt3::new(x, j as f64 * dy, 0.0));
        }
        rv.push(r);
    }
    let mut f = Vec::new();
    for j in 0..rows as usize - 1 {
        let (lo, hi) = (&rv[j], &rv[j + 1]);
        if j % 2 == 0 {
            // even below, odd above
            for i in 0..n {
                f.push([lo[i], lo[i + 1], hi[i]]);
            }
            for i in 0..n - 1 {
                f.push([lo[i + 1], hi[i + 1], hi[i]]);
            }
        } else {
            for i in 0..n - 1 {
                f.push([lo[i], lo[i + 1], hi[i + 1]]);
            }
            for i in 0..n {
                f.push([hi[i], lo[i], hi[i + 1]]);
            }
        }
    }
    (p, f, rv)
}

fn strip_sim(
    p: &CantileverParams,
    yt: f64,
    pos: &[Pt3],
    faces: &[[u32; 3]],
    pins: Vec<u32>,
    custom: Arc<dyn ExternalForce>,
) -> Result<ShellSim> {
    let material = Material {
        density: 0.01,
        membrane: shells::MembraneLaw::Isotropic { young_thickness: yt, poisson: 0.0, compression_softening: None },
        bending: p.bending,
        damping: shells::Damping::None,
        plasticity: None,
    };
    let mut effects = shells::Effects::default();
    effects.custom.push(custom);
    let desc = ShellSceneDesc {
        rest: pos.to_vec(),
        faces: faces.to_vec(),
        uv: None,
        initial: None,
        initial_velocity: None,
        material,
        effects,
        constraints: vec![VertexConstraint::Pinned(pins)],
        integrator: shells::IntegratorSettings {
            newton_iters: p.newton_iters,
            hessian: shells::HessianMode::ProjectedEigen,
            ..Default::default()
        },
        t0: 0.0,
    };
    ShellSim::new(desc).map_err(err)
}

/// Dynamic relaxation toward the static equilibrium: one step with h ≫ the inertial time scale
/// (each step is a few Newton iterations on the static problem started from the extrapolated
/// increment q_k + h v_k), then the velocity is scaled by `keep` ∈ [0, 1) so the extrapolation
/// accelerates the slow rotation modes without oscillating.
fn quasi_static_step(sim: &mut ShellSim, h: f64, keep: f64) -> Result<()> {
    sim.step(h).map_err(err)?;
    let mut st = sim.state().clone();
    st.v.iter_mut().for_each(|v| *v *= keep);
    sim.set_state(st).map_err(err)
}

fn run_cantilever(ctx: &RunCtx) -> Result<Summary> {
    let p: CantileverParams = scene::load(&ctx.scene_file)?.params;
    let ells = if ctx.mode == Mode::Quick { p.quick_ells.clone() } else { p.ells.clone() };
    if ells.is_empty() || ells.iter().any(|&l| !positive(l) || l > p.length / 8.0) || !positive(p.width) {
        return Err(scene::invalid(&ctx.scene_file, "ells must be in (0, length/8] and width > 0"));
    }
    let mut csv = CsvWriter::create(
        &ctx.out_dir.join("cantilever.csv"),
        &[
            "ell_m",
            "vertices",
            "rigidity_factor",
            "moment_circle_gap_rel",
            "tip_deflection_m",
            "beam_theory_m",
            "small_load_tip_rel_err",
            "plate_rigidity_tip_rel_err",
        ],
    )?;
    let h = 1e3; // quasi-static: inertia negligible against h²K
    let mut last = (f64::NAN, f64::NAN, f64::NAN);
    let mut rows_md = String::new();
    let mut conv = Vec::new();
    for &ell in &ells {
        let dy = ell * 3f64.sqrt() / 2.0;
        let rows = (2.0 * (p.width / (2.0 * dy)).round()).max(2.0) as u32 + 1;
        let (pos, faces, rv) = equilateral_strip(p.length, ell, rows);
        let width = pos.iter().map(|q| q.y).fold(0.0, f64::max);
        // Effective rigidity of this discretisation (its own cylinder/sphere calibration).
        let (pp, pf) = calib::equilateral_patch(0.5, ell, false);
        let factor = calib::strip_rigidity_factor(&pp, &pf, 2.5, 1.5 * ell).map_err(err)?;
        let ei = factor * p.bending * width;
        let ei_plate = 6.0 * p.bending * width;
        let lfree = p.length - ell;
        let pins: Vec<u32> = (0..pos.len() as u32).filter(|&i| pos[i as usize].x <= ell * 1.001).collect();
        let nr = rv.len();
        let wts: Vec<f64> = (0..nr).map(|j| if j == 0 || j == nr - 1 { 0.5 } else { 1.0 } / (nr - 1) as f64).collect();
        let mid = &rv[nr / 2];
        let root = *mid.iter().rfind(|&&i| pins.contains(&i)).expect("the clamp holds ≥ 1 vertex per row");
        let tip = *mid.last().expect("rows are non-empty");
        // Pure end moment M = 2πEI/L (plate rigidity: cylindrical regime) ramped over load steps.
        let em = Arc::new(EndMoment {
            pairs: rv.iter().zip(&wts).map(|(r, &w)| (r[r.len() - 1], r[r.len() - 2], w)).collect(),
            moment: std::sync::Mutex::new(0.0),
        });
        let mut sim = strip_sim(&p, p.young_thickness_moment, &pos, &faces, pins.clone(), em.clone())?;
        let mtot = 2.0 * std::f64::consts::PI * ei_plate / lfree;
        let n_load = p.moment_load_steps.max(1);
        for k in 1..=n_load + p.hold_steps {
            *em.moment.lock().expect("moment lock is never poisoned") = mtot * (k.min(n_load) as f64 / n_load as f64);
            quasi_static_step(&mut sim, h, p.relaxation_keep)?;
        }
        let gap = (sim.state().q[tip as usize] - sim.state().q[root as usize]).norm() / lfree;
        write_obj_frame(&ctx.out_dir.join(format!("moment_ell{ell}")), 0, &MeshOut::tri(&sim.state().q, &faces))?;
        // Small tip load P: δ = P L³ / (3 EI).
        let delta_want = p.small_deflection * lfree;
        let pload = 3.0 * ei * delta_want / lfree.powi(3);
        let loads: Vec<(u32, Vec3)> =
            rv.iter().zip(&wts).map(|(r, &w)| (r[r.len() - 1], Vec3::new(0.0, 0.0, -pload * w))).collect();
        let mut sim = strip_sim(&p, p.young_thickness_small, &pos, &faces, pins, Arc::new(TipLoad(loads)))?;
        for _ in 0..10 {
            quasi_static_step(&mut sim, h, p.relaxation_keep)?;
        }
        let d = -rv.iter().zip(&wts).map(|(r, &w)| sim.state().q[r[r.len() - 1] as usize].z * w).sum::<f64>();
        let rel = (d - delta_want).abs() / delta_want;
        let plate = (d * factor / 6.0 - delta_want).abs() / delta_want;
        csv.row(&[
            Cell::Num(ell),
            Cell::Int(pos.len() as i64),
            Cell::Num(factor),
            Cell::Num(gap),
            Cell::Num(d),
            Cell::Num(delta_want),
            Cell::Num(rel),
            Cell::Num(plate),
        ])?;
        rows_md += &format!(
            "| {ell} | {} | {factor:.4} | {gap:.4} | {d:.5e} | {delta_want:.5e} | {rel:.4} | {plate:.4} |\n",
            pos.len()
        );
        conv.push((ell, gap.max(1e-12)));
        last = (gap, rel, plate);
    }
    LinePlot::new("End moment 2πEI/L: end-point gap over L", "edge length ℓ (m)", "gap / L")
        .log(true, true)
        .with(Series::new("gap", conv))
        .write_png(&ctx.out_dir.join("cantilever.png"))?;
    let mut s = Summary::new();
    s.set("moment_circle_gap_rel", last.0);
    s.set("small_load_tip_rel_err", last.1);
    s.set("small_load_tip_rel_err_plate_rigidity", last.2);
    s.set("finest_ell_m", *ells.last().unwrap_or(&f64::NAN));
    write_report(
        ctx,
        &format!(
            "### shells/cantilever\n\nEquilateral strip {} m × {} m clamped at one end, ν = 0. End moment 2πEI/L with \
             the plate rigidity EI = 6k_B·w (stiff membrane, Searle parameter ≫ 1: cylindrical bending) must close a \
             circle. Small tip load vs δ = PL³/(3EI) with the free-strip rigidity EI = c·k_B·w, c measured from the \
             same lattice's cylinder and sphere energies (a free strip relaxes anticlastically: c = 16/3 for \
             Discrete Shells on equilateral meshes; the last column shows the error if 6 is used).\n\n\
             | ℓ (m) | vertices | c | gap/L | δ (m) | theory (m) | rel. err | with c = 6 |\n\
             |---|---|---|---|---|---|---|---|\n{rows_md}",
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
    set_grid(&mut s, (n, n));
    s
}

/// Sets the vertex counts of a grid mesh (no-op for other meshes): the quick-mode resolution.
fn set_grid(shell: &mut ShellScene, (gx, gy): (u32, u32)) {
    if let shells::scene::MeshSpec::Grid { nx, ny, .. } = &mut shell.mesh {
        *nx = gx;
        *ny = gy;
    }
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
        set_grid(&mut shell, p.quick_grid);
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
    /// Kinematic half: vertices with x ≥ this (m) rotate about the strip's middle line x = 0
    /// (along y, in the sheet plane), folding toward +z.
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
    /// Quick mode: grid, substeps of the parameter table and of the step-size study.
    quick_grid: (u32, u32),
    quick_substeps: u32,
    quick_substeps_study: Vec<u32>,
}

#[derive(Clone)]
struct CreaseOut {
    /// Geometric fold angle after settling: angle between the clamp's first segment and the free
    /// end's last segment (middle row) — the integrated crease, insensitive to how the plastic
    /// rotation is spread over neighbouring hinges.
    fold: f64,
    crease: f64,
    k_ratio: f64,
    final_max_angle: f64,
}

/// Kinematic path of the rotating half: a rigid rotation of the rest point about the strip's
/// middle line (x = 0, along y, lying in the sheet plane z = 0) by
/// φ(t) = peak·sin²(π·min(t/tm, 1)), folding the half x > 0 toward +z (the faces' normal side).
///
/// The axis must lie in the sheet: a rotation about the sheet normal (z) is an in-plane
/// rotation that shears the membrane and crumples the free part into a zig-zag of alternating
/// plastic creases instead of one fold (the bug behind the old 0.39 step-size spread).
fn fold_path(rest: Vec<Pt3>, peak: f64, tm: f64) -> impl Fn(f64, u32) -> Pt3 + Send + Sync + 'static {
    move |t: f64, i: u32| {
        let phi = peak * (std::f64::consts::PI * (t / tm).min(1.0)).sin().powi(2);
        let x = rest[i as usize];
        Pt3::new(x.x * phi.cos() - x.z * phi.sin(), x.y, x.x * phi.sin() + x.z * phi.cos())
    }
}

fn crease_run(
    p: &PlasticParams,
    shell: &ShellScene,
    plasticity: Option<Plasticity>,
    substeps: u32,
) -> Result<CreaseOut> {
    let mut sh = shell.clone();
    sh.material.plasticity = plasticity;
    sh.integrator.substeps = substeps;
    let b = build(&sh)?;
    let rest = b.desc.rest.clone();
    let kin: Vec<u32> = (0..rest.len() as u32).filter(|&i| rest[i as usize].x >= p.kinematic_from_x).collect();
    let path = fold_path(rest.clone(), p.peak_deg.to_radians(), p.motion_time);
    let mut desc = b.desc;
    desc.constraints.push(VertexConstraint::Kinematic(kin, Box::new(path)));
    let h = sh.integrator.h();
    let mut sim = ShellSim::new(desc).map_err(err)?;
    let theta0 = sim.rest_angles();
    let k0 = sim.hinge_stiffness();
    let n1 = (p.motion_time / h).round() as usize;
    for _ in 0..n1 {
        sim.step(h).map_err(err)?;
    }
    // Release the kinematic half and let it settle.
    let b2 = build(&sh)?;
    let grid = b2.grid;
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
    let k_ratio = sim2.hinge_stiffness().iter().zip(&k0).map(|(a, b)| a / b).fold(1.0, |m: f64, r| {
        if (r - 1.0).abs() > (m - 1.0).abs() {
            r
        } else {
            m
        }
    });
    let final_max_angle = sim2.hinge_angles(&sim2.state().q).iter().fold(0.0f64, |m, a| m.max(a.abs()));
    let (nx, ny) = grid.ok_or_else(|| Error::Run("plastic-crease needs a Grid mesh".into()))?;
    let row = (ny / 2) * nx;
    let q = &sim2.state().q;
    let d0 = q[row as usize + 1] - q[row as usize];
    let d1 = q[(row + nx - 1) as usize] - q[(row + nx - 2) as usize];
    let fold = d0.cross(&d1).norm().atan2(d0.dot(&d1));
    Ok(CreaseOut { fold, crease, k_ratio, final_max_angle })
}

fn run_plastic(ctx: &RunCtx) -> Result<Summary> {
    let p: PlasticParams = scene::load(&ctx.scene_file)?.params;
    let mut shell = p.shell.clone();
    let study = if ctx.mode == Mode::Quick {
        set_grid(&mut shell, p.quick_grid);
        shell.integrator.substeps = p.quick_substeps;
        p.quick_substeps_study.clone()
    } else {
        p.substeps_study.clone()
    };
    let base_sub = shell.integrator.substeps;
    // Runs are deterministic: the table's (study yield, η = 0, base substeps) run is reused by the
    // step-size study instead of being simulated twice.
    let mut memo: Vec<((PlasticRule, u64, u64, u32), CreaseOut)> = Vec::new();
    let mut csv = CsvWriter::create(
        &ctx.out_dir.join("crease.csv"),
        &[
            "rule",
            "yield_per_m",
            "hardening_m",
            "substeps",
            "fold_angle_rad",
            "crease_angle_rad",
            "stiffness_ratio",
            "final_max_angle_rad",
        ],
    )?;
    let mut s = Summary::new();
    let mut rows = String::new();
    let mut elastic_angle = f64::NAN;
    let mut diverged = 0u64;
    let mut record = |rule: &str, y: f64, eta: f64, sub: u32, c: &CreaseOut, csv: &mut CsvWriter| -> Result<()> {
        csv.row(&[
            Cell::Text(rule.into()),
            Cell::Num(y),
            Cell::Num(eta),
            Cell::Int(sub as i64),
            Cell::Num(c.fold),
            Cell::Num(c.crease),
            Cell::Num(c.k_ratio),
            Cell::Num(c.final_max_angle),
        ])?;
        rows += &format!(
            "| {rule} | {y} | {eta} | {sub} | {:.4} | {:.4} | {:.3} | {:.4} |\n",
            c.fold, c.crease, c.k_ratio, c.final_max_angle
        );
        Ok(())
    };
    for &y in &p.yields {
        let etas: Vec<f64> = if y >= 1e299 { vec![0.0] } else { p.hardenings.clone() };
        for &eta in &etas {
            let pl = (y < 1e299).then_some(Plasticity {
                max_curvature_dev: y,
                hardening: eta,
                rule: PlasticRule::ReturnMapping,
            });
            match crease_run(&p, &shell, pl, base_sub) {
                Ok(c) => {
                    if let Some(pl) = pl {
                        memo.push(((pl.rule, y.to_bits(), eta.to_bits(), base_sub), c.clone()));
                    }
                    if pl.is_none() {
                        elastic_angle = c.final_max_angle;
                    }
                    record("ReturnMapping", y, eta, base_sub, &c, &mut csv)?;
                }
                // A diverging combination is reported in the table, not fatal for the scene.
                Err(e) => {
                    diverged += 1;
                    let nan =
                        CreaseOut { fold: f64::NAN, crease: f64::NAN, k_ratio: f64::NAN, final_max_angle: f64::NAN };
                    record(
                        &format!("ReturnMapping (diverged: {e})").replace(',', ";"),
                        y,
                        eta,
                        base_sub,
                        &nan,
                        &mut csv,
                    )?;
                }
            }
        }
    }
    // Step-size study: spread (max − min)/mean over substeps of the geometric fold angle after
    // settling (the integrated crease: `plastic_crease_spread`) and of the largest rest-angle
    // change max|θ̄ − θ̄₀| (spec §6.5's per-hinge crease angle: `…_max_hinge`); a diverged run
    // makes the spread NaN (reported, not hidden).
    let mut spreads = Vec::new();
    for rule in [PlasticRule::ReturnMapping, PlasticRule::SeedLiteral] {
        let (mut folds, mut creases) = (Vec::new(), Vec::new());
        for &sub in &study {
            let pl = Plasticity { max_curvature_dev: p.study_yield, hardening: 0.0, rule };
            let key = (rule, p.study_yield.to_bits(), 0f64.to_bits(), sub);
            let res = match memo.iter().find(|(k, _)| *k == key) {
                Some((_, c)) => Ok(c.clone()),
                None => crease_run(&p, &shell, Some(pl), sub),
            };
            match res {
                Ok(c) => {
                    record(&format!("{rule:?}"), p.study_yield, 0.0, sub, &c, &mut csv)?;
                    folds.push(c.fold);
                    creases.push(c.crease);
                }
                Err(e) => {
                    diverged += 1;
                    let nan =
                        CreaseOut { fold: f64::NAN, crease: f64::NAN, k_ratio: f64::NAN, final_max_angle: f64::NAN };
                    record(
                        &format!("{rule:?} (diverged: {e})").replace(',', ";"),
                        p.study_yield,
                        0.0,
                        sub,
                        &nan,
                        &mut csv,
                    )?;
                    folds.push(f64::NAN);
                    creases.push(f64::NAN);
                }
            }
        }
        let spread = |v: &[f64]| {
            let mx = v.iter().cloned().fold(f64::NEG_INFINITY, f64::max);
            let mn = v.iter().cloned().fold(f64::INFINITY, f64::min);
            if v.iter().any(|x| x.is_nan()) {
                f64::NAN
            } else {
                (mx - mn) / mean(v).max(1e-300)
            }
        };
        spreads.push((spread(&folds), spread(&creases)));
    }
    s.set("elastic_final_max_angle", elastic_angle);
    s.set("plastic_crease_spread", spreads[0].0);
    s.set("plastic_crease_spread_max_hinge", spreads[0].1);
    s.set("seed_literal_crease_spread", spreads[1].0);
    s.set("seed_literal_crease_spread_max_hinge", spreads[1].1);
    s.set_count("diverged_runs", diverged);
    write_report(
        ctx,
        &format!(
            "### shells/plastic-crease\n\nFoil strip, one end pinned, the other half rotated by {}° and back, then released.\n\n\
             | rule | Δκ_max (1/m) | η (m) | substeps | fold angle (rad) | max|θ̄−θ̄₀| (rad) | k/k₀ | final max|θ| (rad) |\n\
             |---|---|---|---|---|---|---|---|\n{rows}\nStep-size spread of the fold angle after settling: return map {:.4}, \
             seed-literal {:.4}; of the largest rest-angle change max|θ̄−θ̄₀|: {:.4} and {:.4}.\n",
            p.peak_deg, spreads[0].0, spreads[1].0, spreads[0].1, spreads[1].1
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
        set_grid(&mut shell, p.quick_grid);
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

/// True for a finite or infinite number above zero; false for zero, negatives and NaN (so a NaN
/// parameter is refused like a non-positive one).
fn positive(x: f64) -> bool {
    x > 0.0
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The plastic-crease fold is a rigid rotation about the strip's middle line, which lies in
    /// the sheet (z = 0): y is kept, distances to the axis are kept, and the half leaves the
    /// sheet plane toward +z. An in-plane rotation about the normal (the old path, which
    /// crumpled the strip into alternating creases) fails the first and last checks.
    #[test]
    fn fold_path_rotates_about_an_in_sheet_axis() {
        let rest = vec![Pt3::new(0.1, 0.03, 0.0), Pt3::new(0.2, -0.05, 0.0)];
        let peak = 120f64.to_radians();
        let path = fold_path(rest.clone(), peak, 2.0);
        for t in [0.0, 0.3, 1.0, 1.7, 2.0, 3.0] {
            let phi = peak * (std::f64::consts::PI * (t / 2.0f64).min(1.0)).sin().powi(2);
            for (i, r) in rest.iter().enumerate() {
                let p = path(t, i as u32);
                assert!((p.y - r.y).abs() < 1e-15, "y kept");
                assert!((p.x.hypot(p.z) - r.x).abs() < 1e-15, "distance to the axis kept");
                assert!((p.z - r.x * phi.sin()).abs() < 1e-15, "lifted toward +z by φ");
            }
            let d = (path(t, 0) - path(t, 1)).norm();
            assert!((d - (rest[0] - rest[1]).norm()).abs() < 1e-15, "rigid");
        }
        assert!((path(1.0, 0).z - 0.1 * peak.sin()).abs() < 1e-15, "peak at half the motion time");
    }
}

//! tracks' scenes (spec §6): a fine `shells` simulation tracking a coarse guide, always run in
//! lockstep with the untracked simulation of the same scene (`tracking: None`, same settings) so
//! both see the same machine load; the overhead is the ratio of their summed step times.
//!
//! - `tracks/flag` (§6.1): coarse preview design loop, then the 1617-vertex flag tracking it.
//! - `tracks/box` (§6.2): twisting box, 8 subdivision hats.
//! - `tracks/bag` (§6.3): backflipping bag rig, 88 hats, self-intersecting guide.
//! - `tracks/xavier` (§6.4): the X-shaped character stand-in, 200 + 80 clustered regions.
//! - `tracks/fig3-band` (§6.5): elastic ribbon, averaged vs pointwise under a jolt.
//! - `tracks/fig4-sphere` (§6.6): pulsating sphere, averaged vs pointwise constraints.
//! - `tracks/fig6-partitions` (§6.7): Xavier with 16 … 1024 uniform clusters.
//! - `tracks/fig7-clustering` (§6.8): animation-aware vs static VSA.
//! - `tracks/table55` (§6.9): the four paper scenes, tracked vs untracked, the §5.5 table.

use std::path::Path;
use std::time::Instant;

use geom_core::io::{obj, MeshOut};
use geom_core::linalg::Csr;
use geom_core::math::{Pt3, Vec3};
use geom_core::mesh::{subdivide_linear, TriMesh};
use serde::Deserialize;
use shells::{
    CollisionSettings, Damping, Effects, IntegratorSettings, Material, MembraneLaw, Obstacle, ObstacleShape,
    ShellSceneDesc, ShellSim, VertexConstraint, Wind,
};
use tracks::metrics::{guide_on_tracked, hinge_energies, tug_index, LowPass};
use tracks::procedural::{bag_guide, box_guide, flag_coarse, pulsating_sphere, xavier, xavier_guide, Xavier};
use tracks::{
    build_test_functions, cluster, ClusterMetric, ClusterOptions, GuideAnimation, KktMethod, RegionSel,
    TestFunctionSpec, TestFunctions, TimeInterp, TrackOptions, Tracker,
};

use crate::error::{Error, Result};
use crate::out::{Cell, CsvWriter, Summary};
use crate::plot::{LinePlot, Series};
use crate::registry::{RunCtx, Runner};
use crate::scene::{self, Mode};

/// Adds tracks' runners.
pub fn register(v: &mut Vec<Runner>) {
    v.push(Runner { method: "tracks/flag", run: run_flag });
    v.push(Runner { method: "tracks/box", run: run_box });
    v.push(Runner { method: "tracks/bag", run: run_bag });
    v.push(Runner { method: "tracks/xavier", run: run_xavier });
    v.push(Runner { method: "tracks/fig3-band", run: run_fig3 });
    v.push(Runner { method: "tracks/fig4-sphere", run: run_fig4 });
    v.push(Runner { method: "tracks/fig6-partitions", run: run_fig6 });
    v.push(Runner { method: "tracks/fig7-clustering", run: run_fig7 });
    v.push(Runner { method: "tracks/table55", run: run_table55 });
}

pub(crate) fn tk<T>(r: tracks::Result<T>) -> Result<T> {
    r.map_err(|e| Error::Run(format!("tracks: {e}")))
}

pub(crate) fn sh<T>(r: shells::Result<T>) -> Result<T> {
    r.map_err(|e| Error::Run(format!("shells: {e}")))
}

fn core<T>(r: geom_core::Result<T>) -> Result<T> {
    r.map_err(|e| Error::Run(format!("geom-core: {e}")))
}

// ---------------------------------------------------------------------------------------------
// materials (ours; the seed names the materials only)

/// Isotropic St Venant–Kirchhoff shell: areal density (kg/m²), Young's modulus × thickness (N/m),
/// Poisson ratio, bending stiffness (N·m) and Rayleigh stiffness damping β (s).
pub(crate) fn iso_material(density: f64, young_thickness: f64, poisson: f64, bending: f64, beta: f64) -> Material {
    Material {
        density,
        membrane: MembraneLaw::Isotropic { young_thickness, poisson, compression_softening: None },
        bending,
        damping: Damping::Rayleigh { alpha: 0.0, beta },
        plasticity: None,
    }
}

pub(crate) fn rubber() -> Material {
    iso_material(0.5, 2.0e4, 0.4, 2e-4, 1e-3)
}

pub(crate) fn vinyl() -> Material {
    iso_material(0.3, 5.0e3, 0.35, 5e-5, 5e-3)
}

/// Gravity, the given obstacles and (optionally) self-collision; no wind.
fn gravity_effects(self_collision: bool, obstacles: Vec<Obstacle>) -> Effects {
    let any_obstacle = !obstacles.is_empty();
    Effects {
        gravity: Some(Vec3::new(0.0, -9.81, 0.0)),
        obstacles,
        self_collision,
        collision: collision(self_collision, any_obstacle),
        ..Effects::default()
    }
}

/// A scene of `mesh` at rest with `material` and `effects`, no constraints, default integrator;
/// callers override fields with struct-update syntax.
fn shell_desc(mesh: &TriMesh, material: Material, effects: Effects) -> ShellSceneDesc {
    ShellSceneDesc {
        rest: mesh.positions.clone(),
        faces: mesh.faces.clone(),
        uv: None,
        initial: None,
        initial_velocity: None,
        material,
        effects,
        constraints: vec![],
        integrator: IntegratorSettings::default(),
        t0: 0.0,
    }
}

fn ground(friction: f64) -> Obstacle {
    Obstacle { shape: ObstacleShape::Plane { normal: Vec3::y(), offset: 0.0 }, friction, motion: None }
}

fn collision(self_collision: bool, obstacles: bool) -> Option<CollisionSettings> {
    (self_collision || obstacles).then(CollisionSettings::default)
}

// ---------------------------------------------------------------------------------------------
// one scene setup and the lockstep tracked/untracked run

/// Everything needed to run one scene tracked and untracked.
pub(crate) struct Setup {
    pub guide: GuideAnimation,
    pub prolongation: Option<Csr>,
    pub tracked_rest: TriMesh,
    pub desc: Box<dyn Fn() -> ShellSceneDesc>,
    pub tf: TestFunctions,
    pub fps: f64,
    pub substeps: u32,
    /// Scheduled rest-angle changes applied to the tracked and the untracked run alike
    /// (Xavier's CrinkleRest / RestoreRest, spec §6.4); `None` for the other scenes.
    pub rest_events: Option<std::sync::Arc<tracks::RestEvents>>,
}

/// What to run and record.
pub(crate) struct PairOpts {
    pub frames: usize,
    pub obj_every: usize,
    pub untracked: bool,
    pub track: TrackOptions,
    pub intersections: bool,
    pub anchors: Option<Vec<u32>>,
    pub tag: String,
}

/// Figures of one lockstep run.
#[derive(Default)]
pub(crate) struct PairOut {
    pub k: usize,
    pub scale: f64,
    pub t_tracked: f64,
    pub t_untracked: f64,
    pub t_kkt: f64,
    pub t_shadow: f64,
    pub steps: usize,
    pub frames: usize,
    pub max_r_pre: f64,
    pub max_r_post: f64,
    pub max_force: f64,
    pub nnz_l: usize,
    pub dc_tracked: Vec<f64>,
    pub dc_untracked: Vec<f64>,
    pub ad_tracked: Vec<f64>,
    pub rms_tracked: Vec<f64>,
    pub lambda_raw_tracked: Vec<f64>,
    pub bend_tracked: Vec<f64>,
    pub tug_tracked: Vec<f64>,
    pub isect_tracked: Vec<usize>,
    pub isect_guide: Vec<usize>,
    pub times: Vec<f64>,
    pub guide_held: bool,
    pub warnings: Vec<String>,
    pub final_tracked: Vec<Pt3>,
    pub final_untracked: Vec<Pt3>,
    pub ke_tracked: Vec<f64>,
    /// Times the rest-angle events changed the tracked run's rest angles.
    pub rest_updates: usize,
    /// Detail wavelength λ_eff = 2π sqrt(hᵀM_L h / hᵀK h) of h = d − L_τ d per frame ≥ 1 (spec §3.8).
    pub lambda_eff_tracked: Vec<f64>,
    pub step_times: Vec<(f64, f64)>,
    /// Per method of `TrackOptions::compare`: Σ solve time (s), max relative Δv difference to
    /// the main solve, stored factor entries.
    pub compare: Vec<(f64, f64, usize)>,
}

impl PairOut {
    pub fn overhead_pct(&self) -> f64 {
        if self.t_untracked > 0.0 {
            100.0 * (self.t_tracked / self.t_untracked - 1.0)
        } else {
            f64::NAN
        }
    }
    /// Overhead from the median step times (robust to load bursts on a shared machine).
    pub fn overhead_pct_median(&self) -> f64 {
        let med = |mut v: Vec<f64>| -> f64 {
            if v.is_empty() {
                return f64::NAN;
            }
            v.sort_by(f64::total_cmp);
            v[v.len() / 2]
        };
        let t = med(self.step_times.iter().map(|x| x.0).collect());
        let u = med(self.step_times.iter().map(|x| x.1).collect());
        100.0 * (t / u - 1.0)
    }
    pub fn s_per_frame_tracked(&self) -> f64 {
        self.t_tracked / self.frames.max(1) as f64
    }
    pub fn s_per_frame_untracked(&self) -> f64 {
        self.t_untracked / self.frames.max(1) as f64
    }
    fn last(v: &[f64]) -> f64 {
        v.last().copied().unwrap_or(f64::NAN)
    }
    fn mean(v: &[f64]) -> f64 {
        if v.is_empty() {
            f64::NAN
        } else {
            v.iter().sum::<f64>() / v.len() as f64
        }
    }
    /// The keys every tracking scene reports (issue 4 "Must hold").
    pub fn fill(&self, s: &mut Summary) {
        s.set("overhead_pct", self.overhead_pct());
        s.set("overhead_pct_median_step", self.overhead_pct_median());
        s.set("max_residual_pre", self.max_r_pre / self.scale);
        s.set("max_residual_post", self.max_r_post / self.scale);
        s.set("coarse_deviation_tracked", Self::last(&self.dc_tracked));
        s.set("coarse_deviation_untracked", Self::last(&self.dc_untracked));
        s.set("coarse_deviation_tracked_mean", Self::mean(&self.dc_tracked));
        s.set("coarse_deviation_untracked_mean", Self::mean(&self.dc_untracked));
        s.set("s_per_frame_tracked", self.s_per_frame_tracked());
        s.set("s_per_frame_untracked", self.s_per_frame_untracked());
        s.set("solve_s_per_step", self.t_kkt / self.steps.max(1) as f64);
        s.set("max_constraint_force_N", self.max_force);
        s.set_count("constraints", self.k as u64);
        s.set_count("frames", self.frames as u64);
        s.set_count("nnz_l", self.nnz_l as u64);
        s.set_count("guide_held", self.guide_held as u64);
        s.set_count("setup_warnings", self.warnings.len() as u64);
    }
}

fn write_obj(dir: &Path, frame: usize, q: &[Pt3], faces: &[[u32; 3]]) -> Result<()> {
    crate::out::ensure_dir(dir)?;
    core(obj::write(dir.join(format!("{frame:04}.obj")), &MeshOut::tri(q, faces)))?;
    Ok(())
}

/// Steps the tracked and (optionally) the untracked simulation in lockstep, timing every step,
/// and records residuals and per-frame metrics (outside the timed region).
pub(crate) fn run_pair(setup: &Setup, o: &PairOpts, out_dir: &Path) -> Result<PairOut> {
    let sim = sh(ShellSim::new((setup.desc)()))?;
    let mut tr =
        tk(Tracker::new(sim, setup.guide.clone(), setup.tf.clone(), setup.prolongation.clone(), o.track.clone()))?;
    let mut un = if o.untracked { Some(sh(ShellSim::new((setup.desc)()))?) } else { None };
    let mut out = PairOut {
        k: tr.constraints().map_or(0, |c| c.len()),
        scale: setup.guide.scale(),
        warnings: tr.warnings.clone(),
        ..PairOut::default()
    };
    let k_lp = out.k.max(1);
    let lp = tk(LowPass::new(&setup.tracked_rest, LowPass::tau_for(&setup.tracked_rest, k_lp)))?;
    let h = 1.0 / (setup.fps * setup.substeps as f64);
    let faces = tr.sim.mesh().tris.clone();
    let mut gq = vec![Pt3::origin(); setup.guide.n_vertices()];
    let tag = &o.tag;
    let mut steps_csv = CsvWriter::create(
        &out_dir.join(format!("steps{tag}.csv")),
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
        ],
    )?;
    let mut frames_csv = CsvWriter::create(
        &out_dir.join(format!("frames{tag}.csv")),
        &["frame", "t", "dc_tracked", "dc_untracked", "a_d", "rms_d", "bend_J", "tug", "isect_tracked", "isect_guide"],
    )?;
    // Weight of the rest-angle events last applied (`Setup::rest_events`).
    let mut rest_w = 0.0;
    for frame in 0..=o.frames {
        if frame > 0 {
            for _ in 0..setup.substeps {
                if let Some(ev) = setup.rest_events.as_ref() {
                    // The rest angles of the step's end time, on both runs alike (not timed).
                    let t_next = tr.sim.state().t + h;
                    let mut w = rest_w;
                    out.rest_updates += usize::from(sh(ev.apply(&mut tr.sim, t_next, &mut w))?);
                    if let Some(u) = un.as_mut() {
                        sh(ev.apply(u, t_next, &mut rest_w))?;
                    }
                    rest_w = w;
                }
                let st = tk(tr.step(h))?;
                out.t_tracked += st.t_step;
                out.t_kkt += st.t_kkt;
                out.t_shadow += st.t_shadow_llt;
                out.max_r_pre = out.max_r_pre.max(st.residual_pre_collision);
                out.max_r_post = out.max_r_post.max(st.residual_post_collision);
                out.max_force = out.max_force.max(st.max_constraint_force);
                out.nnz_l = out.nnz_l.max(st.nnz_l);
                out.guide_held |= st.guide_held;
                out.compare.resize(st.compare.len(), (0.0, 0.0, 0));
                for (acc, c) in out.compare.iter_mut().zip(&st.compare) {
                    *acc = (acc.0 + c.t_solve, acc.1.max(c.rel_diff), acc.2.max(c.nnz_l));
                }
                let mut tu = 0.0;
                if let Some(u) = un.as_mut() {
                    let t0 = Instant::now();
                    sh(u.step(h))?;
                    tu = t0.elapsed().as_secs_f64();
                    out.t_untracked += tu;
                }
                out.steps += 1;
                out.step_times.push((st.t_step, tu));
                steps_csv.row(&[
                    Cell::Num(tr.sim.state().t),
                    Cell::Num(st.t_step),
                    Cell::Num(tu),
                    Cell::Num(st.t_kkt),
                    Cell::Num(st.t_shadow_llt),
                    Cell::Num(st.residual_pre_collision),
                    Cell::Num(st.residual_post_collision),
                    Cell::Num(st.max_constraint_force),
                    Cell::Int(st.shell.n_ccd as i64),
                    Cell::Int(i64::from(st.kkt_refine_steps)),
                ])?;
            }
            out.frames += 1;
        }
        // Metrics (not timed).
        let t = tr.sim.state().t;
        setup.guide.sample(t, &mut gq);
        let gf = guide_on_tracked(setup.prolongation.as_ref(), &gq);
        let q = &tr.sim.state().q;
        let d: Vec<Vec3> = q.iter().zip(&gf).map(|(a, b)| a - b).collect();
        let dc = tk(lp.coarse_deviation(&d, out.scale))?;
        let ad = tk(lp.detail_amplitude(&d))?;
        let rms = lp.rms(&d) / out.scale;
        let dcu = match un.as_ref() {
            Some(u) => {
                let du: Vec<Vec3> = u.state().q.iter().zip(&gf).map(|(a, b)| a - b).collect();
                tk(lp.coarse_deviation(&du, out.scale))?
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
        if frame > 0 {
            out.dc_tracked.push(dc);
            out.dc_untracked.push(dcu);
            out.ad_tracked.push(ad);
            out.rms_tracked.push(rms);
            out.lambda_raw_tracked.push(lp.wavelength(&d));
            let lo = tk(lp.apply(&d))?;
            let detail: Vec<Vec3> = d.iter().zip(&lo).map(|(a, b)| a - b).collect();
            out.lambda_eff_tracked.push(lp.wavelength(&detail));
        }
        out.bend_tracked.push(bend);
        out.tug_tracked.push(tug);
        out.isect_tracked.push(it);
        out.isect_guide.push(ig);
        out.times.push(t);
        out.ke_tracked.push(tr.sim.energies().kinetic);
        frames_csv.row(&[
            Cell::Int(frame as i64),
            Cell::Num(t),
            Cell::Num(dc),
            Cell::Num(dcu),
            Cell::Num(ad),
            Cell::Num(rms),
            Cell::Num(bend),
            Cell::Num(tug),
            Cell::Int(it as i64),
            Cell::Int(ig as i64),
        ])?;
        if o.obj_every > 0 && frame % o.obj_every == 0 {
            write_obj(&out_dir.join(format!("tracked{tag}")), frame, q, &faces)?;
            write_obj(&out_dir.join(format!("guide{tag}")), frame, &gq, &setup.guide.rest.faces)?;
            if let Some(u) = un.as_ref() {
                write_obj(&out_dir.join(format!("untracked{tag}")), frame, &u.state().q, &faces)?;
            }
        }
    }
    out.final_tracked = tr.sim.state().q.clone();
    if let Some(u) = un.as_ref() {
        out.final_untracked = u.state().q.clone();
    }
    Ok(out)
}

fn plot_pair(out: &PairOut, dir: &Path, title: &str) -> Result<()> {
    let ts = &out.times[1..];
    let pts = |v: &[f64]| ts.iter().zip(v).map(|(a, b)| (*a, *b)).collect::<Vec<_>>();
    let mut p = LinePlot::new(&format!("{title}: coarse deviation D_c"), "t (s)", "D_c (1/L)")
        .with(Series::new("tracked", pts(&out.dc_tracked)));
    if out.dc_untracked.iter().all(|x| x.is_finite()) {
        p = p.with(Series::new("untracked", pts(&out.dc_untracked)));
    }
    p.write_png(&dir.join("deviation.png"))?;
    Ok(())
}

pub(crate) fn pick3<T: Copy>(m: Mode, v: (T, T, T)) -> T {
    m.pick(v.0, v.1, v.2)
}

pub(crate) fn frames_for(duration: f64, fps: f64) -> usize {
    (duration * fps).round().max(1.0) as usize
}

// ---------------------------------------------------------------------------------------------
// parameters shared by the single-scene runners

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct PairParams {
    /// Simulated time (s) for quick / default / full.
    pub duration: (f64, f64, f64),
    /// Substeps per frame for quick / default / full.
    pub substeps: (u32, u32, u32),
    /// Self-collision for quick / default / full.
    pub self_collision: (bool, bool, bool),
    /// Saddle-point solver.
    pub kkt: KktMethod,
    /// Iterative refinement steps after the LDLᵀ solve.
    pub refine_steps: u32,
    /// Write OBJ frames every n frames (0 = never).
    pub obj_every: usize,
}

pub(crate) fn track_opts(kkt: KktMethod, refine_steps: u32) -> TrackOptions {
    TrackOptions { kkt, refine_steps, ..TrackOptions::default() }
}

/// Runs one scene tracked and untracked with the shared scene parameters; returns the run and a
/// summary holding the common keys (`mode`, `duration_s`, `n_vertices` added).
fn run_standard(
    ctx: &RunCtx,
    p: &PairParams,
    setup: &Setup,
    name: &str,
    intersections: bool,
) -> Result<(PairOut, Summary)> {
    let frames = frames_for(pick3(ctx.mode, p.duration), setup.fps);
    let o = PairOpts {
        frames,
        obj_every: p.obj_every,
        untracked: true,
        track: track_opts(p.kkt, p.refine_steps),
        intersections,
        anchors: None,
        tag: String::new(),
    };
    let out = run_pair(setup, &o, &ctx.out_dir)?;
    plot_pair(&out, &ctx.out_dir, name)?;
    let mut s = Summary::new();
    out.fill(&mut s);
    s.set_count("n_vertices", setup.tracked_rest.n_vertices() as u64);
    s.set("duration_s", frames as f64 / setup.fps);
    s.set_str("mode", ctx.mode.name());
    Ok((out, s))
}

// ---------------------------------------------------------------------------------------------
// flag (§6.1)

const FLAG_FPS: f64 = 30.0;

fn flag_effects(self_collision: bool) -> Effects {
    let branch = Obstacle {
        shape: ObstacleShape::Capsule { a: Pt3::new(2.0, 1.2, -1.0), b: Pt3::new(2.0, 1.2, 1.0), radius: 0.03 },
        friction: 0.8,
        motion: None,
    };
    Effects { wind: Some(Wind::steady(Vec3::new(1.5, 0.0, 0.0))), ..gravity_effects(self_collision, vec![branch]) }
}

/// Initial velocity: (v_x, v_y, 0) plus a spin of 1.5 rad/s about z through the flag centre.
fn flag_velocity(p: &[Pt3], vx: f64, vy: f64) -> Vec<Vec3> {
    let c = Vec3::new(0.0, 2.0, 0.0);
    let w = Vec3::new(0.0, 0.0, 1.5);
    p.iter().map(|x| Vec3::new(vx, vy, 0.0) + w.cross(&(x.coords - c))).collect()
}

fn flag_desc(m: &TriMesh, vx: f64, vy: f64, self_collision: bool) -> ShellSceneDesc {
    ShellSceneDesc {
        initial_velocity: Some(flag_velocity(&m.positions, vx, vy)),
        ..shell_desc(m, Material::cotton(), flag_effects(self_collision))
    }
}

/// Stuck on the branch: centroid within 0.3 m of the branch axis and mean speed < 0.05 m/s over
/// the last 0.5 s.
fn stuck(centroids: &[Pt3], speeds: &[f64], fps: f64) -> bool {
    let n = (0.5 * fps).round() as usize;
    let (Some(c), true) = (centroids.last(), speeds.len() >= n) else { return false };
    let d = ((c.x - 2.0).powi(2) + (c.y - 1.2).powi(2)).sqrt();
    let mean_v = speeds[speeds.len() - n..].iter().sum::<f64>() / n as f64;
    d < 0.3 && mean_v < 0.05
}

fn centroid(q: &[Pt3]) -> Pt3 {
    Pt3::from(q.iter().fold(Vec3::zeros(), |a, p| a + p.coords) / q.len() as f64)
}

fn mean_speed(v: &[Vec3]) -> f64 {
    v.iter().map(|x| x.norm()).sum::<f64>() / v.len() as f64
}

/// Runs the coarse preview design loop; returns (chosen frames, (vx, vy), stuck flags, time).
fn flag_design_loop(coarse: &TriMesh, duration: f64) -> Result<FlagDesign> {
    let t0 = Instant::now();
    let mut flags = Vec::new();
    let mut chosen: Option<(Frames, (f64, f64))> = None;
    let nf = frames_for(duration, FLAG_FPS);
    for &vx in &[1.6, 1.9, 2.2, 2.5, 2.8] {
        for &vy in &[0.5, 1.0, 1.5, 2.0] {
            let mut sim = sh(ShellSim::new(flag_desc(coarse, vx, vy, false)))?;
            let mut frames = vec![sim.state().q.clone()];
            let (mut cs, mut vs) = (Vec::new(), Vec::new());
            for _ in 0..nf {
                sh(sim.step(1.0 / FLAG_FPS))?;
                frames.push(sim.state().q.clone());
                cs.push(centroid(&sim.state().q));
                vs.push(mean_speed(&sim.state().v));
            }
            let s = stuck(&cs, &vs, FLAG_FPS);
            flags.push(s);
            if s && chosen.is_none() {
                chosen = Some((frames, (vx, vy)));
            }
        }
    }
    let (frames, v) = match chosen {
        Some(c) => c,
        None => {
            // No preview got stuck: keep the last design (reported as stuck_preview = 0).
            let mut sim = sh(ShellSim::new(flag_desc(coarse, 2.8, 2.0, false)))?;
            let mut frames = vec![sim.state().q.clone()];
            for _ in 0..nf {
                sh(sim.step(1.0 / FLAG_FPS))?;
                frames.push(sim.state().q.clone());
            }
            (frames, (2.8, 2.0))
        }
    };
    let guide = tk(GuideAnimation::from_frames(coarse.clone(), frames, FLAG_FPS, TimeInterp::CatmullRom))?;
    Ok(FlagDesign { guide, velocity: v, stuck_flags: flags, preview_s: t0.elapsed().as_secs_f64() })
}

/// Guide frames of a preview run.
type Frames = Vec<Vec<Pt3>>;

fn quadrants() -> Vec<RegionSel> {
    let q = |u: (f64, f64), v: (f64, f64)| RegionSel::Uv { u, v };
    vec![q((0.0, 0.6), (0.0, 0.4)), q((0.6, 1.2), (0.0, 0.4)), q((0.0, 0.6), (0.4, 0.8)), q((0.6, 1.2), (0.4, 0.8))]
}

pub(crate) struct FlagDesign {
    pub guide: GuideAnimation,
    pub velocity: (f64, f64),
    pub stuck_flags: Vec<bool>,
    pub preview_s: f64,
}

pub(crate) fn flag_design() -> Result<FlagDesign> {
    let coarse = tk(flag_coarse())?;
    flag_design_loop(&coarse, 4.0)
}

pub(crate) fn flag_setup(d: &FlagDesign, substeps: u32, self_collision: bool) -> Result<Setup> {
    let (fine, p) = subdivide_linear(&d.guide.rest, 3);
    let spec = TestFunctionSpec::PaintedOnGuide { guide: quadrants() };
    let tf = tk(build_test_functions(&spec, &d.guide, &fine, Some(&p)))?;
    let (vx, vy) = d.velocity;
    let f2 = fine.clone();
    Ok(Setup {
        guide: d.guide.clone(),
        prolongation: Some(p),
        tracked_rest: fine,
        desc: Box::new(move || flag_desc(&f2, vx, vy, self_collision)),
        tf,
        fps: FLAG_FPS,
        substeps,
        rest_events: None,
    })
}

fn run_flag(ctx: &RunCtx) -> Result<Summary> {
    let p: PairParams = scene::load(&ctx.scene_file)?.params;
    let m = ctx.mode;
    let design = flag_design()?;
    let setup = flag_setup(&design, pick3(m, p.substeps), pick3(m, p.self_collision))?;
    let (out, mut s) = run_standard(ctx, &p, &setup, "flag", false)?;
    let cs_t = centroid(&out.final_tracked);
    let cs_u = centroid(&out.final_untracked);
    let near = |c: &Pt3| ((c.x - 2.0).powi(2) + (c.y - 1.2).powi(2)).sqrt();
    s.set("deviation_ratio_untracked_over_tracked", PairOut::last(&out.dc_untracked) / PairOut::last(&out.dc_tracked));
    s.set("deviation_ratio_mean", PairOut::mean(&out.dc_untracked) / PairOut::mean(&out.dc_tracked));
    s.set_count("stuck_preview", design.stuck_flags.iter().any(|&x| x) as u64);
    s.set_count("stuck_previews_of_20", design.stuck_flags.iter().filter(|&&x| x).count() as u64);
    s.set("preview_total_s", design.preview_s);
    s.set("preview_vx", design.velocity.0);
    s.set("preview_vy", design.velocity.1);
    s.set("tracked_branch_distance_end_m", near(&cs_t));
    s.set("untracked_branch_distance_end_m", near(&cs_u));
    s.set("detail_amplitude_end_m", PairOut::last(&out.ad_tracked));
    Ok(s)
}

// ---------------------------------------------------------------------------------------------
// box (§6.2)

pub(crate) fn box_setup(substeps: u32, self_collision: bool) -> Result<Setup> {
    let guide = tk(box_guide(6.0))?;
    let (fine, p) = subdivide_linear(&guide.rest, 4);
    let tf = tk(build_test_functions(&TestFunctionSpec::SubdivisionBasis, &guide, &fine, Some(&p)))?;
    let pins: Vec<u32> =
        (0..fine.n_vertices() as u32).filter(|&v| fine.positions[v as usize].y.abs() < 1e-12).collect();
    let f2 = fine.clone();
    Ok(Setup {
        guide,
        prolongation: Some(p),
        tracked_rest: fine,
        desc: Box::new(move || ShellSceneDesc {
            constraints: vec![VertexConstraint::Pinned(pins.clone())],
            ..shell_desc(&f2, rubber(), gravity_effects(self_collision, vec![]))
        }),
        tf,
        fps: 30.0,
        substeps,
        rest_events: None,
    })
}

fn run_box(ctx: &RunCtx) -> Result<Summary> {
    let p: PairParams = scene::load(&ctx.scene_file)?.params;
    let m = ctx.mode;
    let setup = box_setup(pick3(m, p.substeps), pick3(m, p.self_collision))?;
    let (out, mut s) = run_standard(ctx, &p, &setup, "box", false)?;
    // Detail at 2.5 s (twisted) and after the abrupt stop (tracked kinetic energy > 0).
    let at = |t: f64, v: &[f64]| -> f64 {
        out.times[1..]
            .iter()
            .zip(v)
            .filter(|(x, _)| (**x - t).abs() < 0.5 / 30.0)
            .map(|(_, y)| *y)
            .next()
            .unwrap_or(f64::NAN)
    };
    s.set("detail_amplitude_2_5s_m", at(2.5, &out.ad_tracked));
    s.set("detail_amplitude_4_4s_m", at(4.4, &out.ad_tracked));
    s.set("kinetic_energy_end_J", out.ke_tracked.last().copied().unwrap_or(f64::NAN));
    Ok(s)
}

// ---------------------------------------------------------------------------------------------
// bag (§6.3)

pub(crate) fn bag_setup(substeps: u32, self_collision: bool) -> Result<Setup> {
    let guide = tk(bag_guide(3.0, tracks::procedural::BAG_B1_GAIN))?;
    let (fine, p) = subdivide_linear(&guide.rest, 2);
    let tf = tk(build_test_functions(&TestFunctionSpec::SubdivisionBasis, &guide, &fine, Some(&p)))?;
    // Fine rest projected back onto the smooth cylinder (side) — the disc is already planar.
    let mut rest = fine.clone();
    for q in rest.positions.iter_mut() {
        let r = (q.x * q.x + q.z * q.z).sqrt();
        if q.y > 1e-9 || r > 0.19 {
            q.x *= 0.2 / r;
            q.z *= 0.2 / r;
        }
    }
    let r2 = rest.clone();
    let tracked_rest = rest;
    Ok(Setup {
        guide,
        prolongation: Some(p),
        tracked_rest,
        desc: Box::new(move || shell_desc(&r2, vinyl(), gravity_effects(self_collision, vec![ground(0.5)]))),
        tf,
        fps: 30.0,
        substeps,
        rest_events: None,
    })
}

fn run_bag(ctx: &RunCtx) -> Result<Summary> {
    let p: PairParams = scene::load(&ctx.scene_file)?.params;
    let m = ctx.mode;
    let setup = bag_setup(pick3(m, p.substeps), pick3(m, p.self_collision))?;
    let (out, mut s) = run_standard(ctx, &p, &setup, "bag", true)?;
    s.set_count("tracked_intersections_max", *out.isect_tracked.iter().max().unwrap_or(&0) as u64);
    s.set_count("guide_intersections_max", *out.isect_guide.iter().max().unwrap_or(&0) as u64);
    s.set_count("guide_self_intersecting_frames", out.isect_guide.iter().filter(|&&x| x > 0).count() as u64);
    Ok(s)
}

// ---------------------------------------------------------------------------------------------
// xavier (§6.4)

/// Feet: leg limbs (2, 3) with membership > 0.5 and radial coordinate s > 0.85.
fn feet(x: &Xavier) -> Vec<u32> {
    (0..x.mesh.n_vertices() as u32)
        .filter(|&v| {
            let m = x.membership[v as usize];
            (m[2] > 0.5 || m[3] > 0.5) && x.s[v as usize] > 0.85
        })
        .collect()
}

fn xavier_effects(self_collision: bool) -> Effects {
    let mut wind = Wind::steady(Vec3::new(0.0, 0.0, -12.0));
    wind.turbulence = 0.5;
    wind.seed = 7;
    // Switched on over 4–7 s.
    wind.schedule = vec![(3.99, 0.0), (4.0, 1.0), (7.0, 1.0), (7.01, 0.0)];
    Effects { wind: Some(wind), ..gravity_effects(self_collision, vec![ground(0.5)]) }
}

pub(crate) fn xavier_setup(
    x: &Xavier,
    guide: &GuideAnimation,
    tf: TestFunctions,
    substeps: u32,
    self_collision: bool,
) -> Setup {
    let mesh = x.mesh.clone();
    let g0 = {
        let mut p = vec![Pt3::origin(); guide.n_vertices()];
        guide.sample(0.0, &mut p);
        p
    };
    let desc = move || ShellSceneDesc {
        initial: Some(g0.clone()),
        ..shell_desc(&mesh, tracks::procedural::xavier_material(), xavier_effects(self_collision))
    };
    // CrinkleRest / RestoreRest (spec §6.4): ±4 mm normal noise, seed 7; they act from 7 s on,
    // so only the full (10 s) run sees them.
    // (An invalid description fails again, with its error, when `run_pair` builds the runs.)
    let rest_events =
        ShellSim::new(desc()).ok().map(|sim| std::sync::Arc::new(tracks::RestEvents::xavier(&sim, &x.mesh, 0.004, 7)));
    Setup {
        guide: guide.clone(),
        prolongation: None,
        tracked_rest: x.mesh.clone(),
        desc: Box::new(desc),
        tf,
        fps: 30.0,
        substeps,
        rest_events,
    }
}

/// Xavier's 200 + 80 test functions (μ = 0.98, F = 32, seed 7); returns them and the time (s).
pub(crate) fn xavier_tf(x: &Xavier, guide: &GuideAnimation) -> Result<(TestFunctions, f64)> {
    let t0 = Instant::now();
    let base = ClusterOptions { regions: 200, mu: 0.98, frames: 32, seed: 7, ..ClusterOptions::default() };
    let spec = TestFunctionSpec::ClusteredWithRefinement { base, refine: vec![(RegionSel::Vertices(feet(x)), 80)] };
    let tf = tk(build_test_functions(&spec, guide, &x.mesh, None))?;
    Ok((tf, t0.elapsed().as_secs_f64()))
}

fn run_xavier(ctx: &RunCtx) -> Result<Summary> {
    let p: PairParams = scene::load(&ctx.scene_file)?.params;
    let m = ctx.mode;
    let x = tk(xavier())?;
    let guide = tk(xavier_guide(&x, 10.0))?;
    let (tf, clustering_s) = xavier_tf(&x, &guide)?;
    let k = tf.len();
    let setup = xavier_setup(&x, &guide, tf, pick3(m, p.substeps), pick3(m, p.self_collision));
    let (out, mut s) = run_standard(ctx, &p, &setup, "xavier", false)?;
    // Rest-angle updates of the CrinkleRest / RestoreRest blends (0 before 7 s: quick and default).
    s.set_count("rest_event_updates", out.rest_updates as u64);
    s.set("clustering_s", clustering_s);
    s.set_count("regions", k as u64);
    s.set("mesh_min_angle_deg", x.quality.0);
    s.set("mesh_edge_ratio", x.quality.1);
    Ok(s)
}

// ---------------------------------------------------------------------------------------------
// fig3-band (§6.5, as a shell ribbon)

/// Guide of the band: a 9 × 2-vertex ribbon (1 m × 0.05 m) bending into a sine arc of 0.15 m over
/// the first second, then shifted sideways by 0.3 m within 0.1 s at t = 1.5 s (the jolt).
fn band_guide() -> Result<GuideAnimation> {
    let m = core(geom_core::procedural::grid(&geom_core::procedural::GridSpec {
        quads: [8, 1],
        size: [1.0, 0.05],
        plane: geom_core::procedural::Plane::XZ,
        diagonals: geom_core::procedural::Diagonals::Alternating,
        center: Pt3::new(0.5, 0.0, 0.0),
    }))?;
    let rest = m.positions.clone();
    tk(GuideAnimation::procedural(
        m,
        std::sync::Arc::new(move |t: f64| {
            let arc = geom_core::math::smoothstep(0.0, 1.0, t);
            let jolt = geom_core::math::smoothstep(1.5, 1.6, t);
            rest.iter()
                .map(|p| p + Vec3::new(0.0, 0.15 * arc * (std::f64::consts::PI * p.x).sin() + 0.3 * jolt, 0.0))
                .collect()
        }),
        3.0,
    ))
}

/// Runs the averaged (subdivision hats, with its untracked twin) and the pointwise (anchors at the
/// coarse vertices) variants of a Fig. 3/4 experiment: rubber with β = 1e-4, no gravity.
fn averaged_vs_pointwise(
    ctx: &RunCtx,
    p: &Fig4Params,
    avg_guide: &GuideAnimation,
    pw_guide: &GuideAnimation,
    fine: &TriMesh,
    pm: &Csr,
    material_rest: Option<Vec<Pt3>>,
) -> Result<(PairOut, PairOut)> {
    let m = ctx.mode;
    let mut mat = rubber();
    mat.damping = Damping::Rayleigh { alpha: 0.0, beta: 1e-4 };
    let make = |tf: TestFunctions, guide: &GuideAnimation| -> Setup {
        let f2 = fine.clone();
        let mat = mat.clone();
        let material_rest = material_rest.clone();
        Setup {
            guide: guide.clone(),
            prolongation: Some(pm.clone()),
            tracked_rest: fine.clone(),
            desc: Box::new(move || {
                let d = ShellSceneDesc {
                    // The guide pumps energy into the shell: shells' blow-up guard is relative to
                    // the (tiny) initial energy, so it is widened here.
                    integrator: IntegratorSettings { divergence_energy_factor: 1e12, ..IntegratorSettings::default() },
                    ..shell_desc(&f2, mat.clone(), Effects::default())
                };
                match &material_rest {
                    // Start at `fine`, with the material's rest shape elsewhere (pre-stretched).
                    Some(r) => ShellSceneDesc { rest: r.clone(), initial: Some(f2.positions.clone()), ..d },
                    None => d,
                }
            }),
            tf,
            fps: 30.0,
            substeps: pick3(m, p.substeps),
            rest_events: None,
        }
    };
    let nb = avg_guide.n_vertices() as u32;
    let anchors: Vec<u32> = (0..nb).collect();
    let avg_tf = tk(build_test_functions(&TestFunctionSpec::SubdivisionBasis, avg_guide, fine, Some(pm)))?;
    let pw_tf = tk(build_test_functions(
        &TestFunctionSpec::Pointwise { pairs: (0..nb).map(|j| (j, j)).collect() },
        pw_guide,
        fine,
        Some(pm),
    ))?;
    let frames = frames_for(pick3(m, p.duration), 30.0);
    let mk = |tag: &str, untracked: bool| PairOpts {
        frames,
        obj_every: p.obj_every,
        untracked,
        track: track_opts(p.kkt, p.refine_steps),
        intersections: false,
        anchors: Some(anchors.clone()),
        tag: tag.to_string(),
    };
    let avg = run_pair(&make(avg_tf, avg_guide), &mk("_averaged", true), &ctx.out_dir)?;
    let pw = run_pair(&make(pw_tf, pw_guide), &mk("_pointwise", false), &ctx.out_dir)?;
    Ok((avg, pw))
}

/// Largest value of `v` over the frames with t ∈ [a, b].
fn window_max(o: &PairOut, a: f64, b: f64, v: &[f64]) -> f64 {
    o.times.iter().zip(v).filter(|(t, _)| **t >= a && **t <= b).map(|(_, e)| *e).fold(0.0, f64::max)
}

fn run_fig3(ctx: &RunCtx) -> Result<Summary> {
    let p: Fig4Params = scene::load(&ctx.scene_file)?.params;
    let m = ctx.mode;
    let guide = band_guide()?;
    let (fine, pm) = subdivide_linear(&guide.rest, 3);
    let (avg, pw) = averaged_vs_pointwise(ctx, &p, &guide, &guide, &fine, &pm, None)?;
    let frames = avg.frames;
    let window = window_max;
    let mut s = Summary::new();
    avg.fill(&mut s);
    let (eb_a, eb_p) = (window(&avg, 1.5, 3.0, &avg.bend_tracked), window(&pw, 1.5, 3.0, &pw.bend_tracked));
    s.set("bend_energy_max_jolt_averaged_J", eb_a);
    s.set("bend_energy_max_jolt_pointwise_J", eb_p);
    s.set("bend_energy_ratio_pointwise_over_averaged", eb_p / eb_a);
    s.set("bend_energy_max_quasistatic_averaged_J", window(&avg, 0.0, 1.4, &avg.bend_tracked));
    s.set("bend_energy_max_quasistatic_pointwise_J", window(&pw, 0.0, 1.4, &pw.bend_tracked));
    s.set("tug_index_pointwise_jolt", window(&pw, 1.5, 3.0, &pw.tug_tracked));
    s.set("tug_index_averaged_jolt", window(&avg, 1.5, 3.0, &avg.tug_tracked));
    s.set("max_residual_pre_pointwise", pw.max_r_pre / pw.scale);
    s.set("duration_s", frames as f64 / 30.0);
    s.set_str("mode", m.name());
    Ok(s)
}

// ---------------------------------------------------------------------------------------------
// fig4-sphere (§6.6)

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct Fig4Params {
    /// Simulated time (s) for quick / default / full (the fast phase is 2–3 s).
    duration: (f64, f64, f64),
    substeps: (u32, u32, u32),
    kkt: KktMethod,
    refine_steps: u32,
    obj_every: usize,
    /// fig4 only: radius of the tracked material's rest sphere over the guide's rest radius
    /// (the simulation starts at the guide's radius; absent = 1, the spec's setup).
    #[serde(default)]
    tracked_rest_scale: Option<f64>,
}

fn run_fig4(ctx: &RunCtx) -> Result<Summary> {
    let p: Fig4Params = scene::load(&ctx.scene_file)?.params;
    let m = ctx.mode;
    let guide = tk(pulsating_sphere(3.0))?;
    let (mut fine, pm) = subdivide_linear(&guide.rest, 2);
    for q in fine.positions.iter_mut() {
        *q = Pt3::from(q.coords.normalize() * 0.5);
    }
    let nb = guide.n_vertices() as u32;
    let avg_tf = tk(build_test_functions(&TestFunctionSpec::SubdivisionBasis, &guide, &fine, Some(&pm)))?;
    // The smooth (projected) tracked sphere does not satisfy the hat constraints of the faceted
    // guide (hat averages of a sphere lie inside it): pick the averaged guide's positions q̄* with
    // C̄ q̄* = C q_sphere (C̄ is square and invertible), so that the perfect response — uniform
    // scaling of the smooth sphere — satisfies the constraints and has zero bending energy. The
    // pointwise guide keeps the icosphere vertices, which lie on the smooth sphere.
    let cons = tk(tracks::TrackingConstraints::build(&guide.rest, &fine, &avg_tf))?;
    let nbu = nb as usize;
    let cb = nalgebra::DMatrix::from_fn(nbu, nbu, |i, j| cons.c_bar.get(i, j));
    let mut rhs = nalgebra::DMatrix::zeros(nbu, 3);
    for i in 0..nbu {
        let (c, v) = cons.c.row(i);
        for (&l, &w) in c.iter().zip(v) {
            for d in 0..3 {
                rhs[(i, d)] += w * fine.positions[l as usize][d];
            }
        }
    }
    let qs = cb.lu().solve(&rhs).ok_or_else(|| Error::Run("fig4: singular C̄".into()))?;
    let qstar: Vec<Pt3> = (0..nbu).map(|i| Pt3::new(qs[(i, 0)], qs[(i, 1)], qs[(i, 2)])).collect();
    let avg_guide = tk(GuideAnimation::procedural(
        guide.rest.clone(),
        std::sync::Arc::new(move |t: f64| {
            let s = tracks::procedural::sphere_scale(t);
            qstar.iter().map(|p| Pt3::from(p.coords * s)).collect()
        }),
        3.0,
    ))?;
    // The material's rest sphere: `tracked_rest_scale` × the guide's rest radius (1 = the spec).
    let scale = p.tracked_rest_scale.unwrap_or(1.0);
    let material_rest = (scale != 1.0).then(|| fine.positions.iter().map(|q| Pt3::from(q.coords * scale)).collect());
    let (avg, pw) = averaged_vs_pointwise(ctx, &p, &avg_guide, &guide, &fine, &pm, material_rest)?;
    let frames = avg.frames;
    let window = window_max;
    let fast = (2.0, 3.0);
    let eb_avg = window(&avg, fast.0, fast.1, &avg.bend_tracked);
    let eb_pw = window(&pw, fast.0, fast.1, &pw.bend_tracked);
    let slow_avg = window(&avg, 0.0, 2.0, &avg.bend_tracked);
    let slow_pw = window(&pw, 0.0, 2.0, &pw.bend_tracked);
    let mut s = Summary::new();
    avg.fill(&mut s);
    s.set("bend_energy_max_fast_averaged_J", eb_avg);
    s.set("bend_energy_max_fast_pointwise_J", eb_pw);
    s.set("bend_energy_ratio_pointwise_over_averaged", eb_pw / eb_avg);
    s.set("bend_energy_max_slow_averaged_J", slow_avg);
    s.set("bend_energy_max_slow_pointwise_J", slow_pw);
    s.set("tracked_rest_scale", scale);
    s.set("tug_index_pointwise_fast", window(&pw, fast.0, fast.1, &pw.tug_tracked));
    s.set("tug_index_averaged_fast", window(&avg, fast.0, fast.1, &avg.tug_tracked));
    s.set("max_residual_pre_pointwise", pw.max_r_pre / pw.scale);
    s.set("duration_s", frames as f64 / 30.0);
    s.set_str("mode", m.name());
    let series = |o: &PairOut, v: &[f64], l: &str| {
        Series::new(l, o.times.iter().zip(v).map(|(a, b)| (*a, b.max(1e-16))).collect())
    };
    LinePlot::new("fig4: bending energy of the pulsating sphere", "t (s)", "E_bend (J)")
        .log(false, true)
        .with(series(&avg, &avg.bend_tracked, "averaged (42 hats)"))
        .with(series(&pw, &pw.bend_tracked, "pointwise (42 anchors)"))
        .write_png(&ctx.out_dir.join("bend_energy.png"))?;
    Ok(s)
}

// ---------------------------------------------------------------------------------------------
// fig6-partitions (§6.7) — also used by the benchmark

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct Fig6Params {
    regions: Vec<usize>,
    duration: (f64, f64, f64),
    substeps: (u32, u32, u32),
    self_collision: (bool, bool, bool),
    /// Solver per region count above which the AMD-regularised LDLᵀ is used instead.
    kkt: KktMethod,
    kkt_large: KktMethod,
    large_from: usize,
    refine_steps: u32,
}

/// The per-r keys of the partition study (fig6 and the benchmark).
pub(crate) fn partition_keys(rows: &[PartitionRow], s: &mut Summary) {
    for r in rows {
        s.set(&format!("deviation_r{}", r.regions), r.deviation);
        s.set(&format!("overhead_pct_r{}", r.regions), r.overhead_pct);
        s.set(&format!("overhead_pct_median_step_r{}", r.regions), r.overhead_pct_median);
        s.set(&format!("wavelength_m_r{}", r.regions), r.wavelength);
        s.set(&format!("s_per_frame_r{}", r.regions), r.s_per_frame);
        s.set(&format!("max_residual_pre_r{}", r.regions), r.r_pre);
    }
}

/// One row of the partition study.
pub(crate) struct PartitionRow {
    pub regions: usize,
    pub k: usize,
    pub deviation: f64,
    pub wavelength: f64,
    pub s_per_frame: f64,
    pub s_per_frame_untracked: f64,
    pub overhead_pct: f64,
    pub overhead_pct_median: f64,
    pub r_pre: f64,
    pub nnz_l: usize,
    pub clustering_s: f64,
    /// Mean KKT solve time per step (s).
    pub solve_s_per_step: f64,
}

/// Runs the Xavier clip with uniform clusterings of each size (spec §6.7).
#[allow(clippy::too_many_arguments)]
pub(crate) fn partition_study(
    regions: &[usize],
    duration: f64,
    substeps: u32,
    self_collision: bool,
    kkt: KktMethod,
    kkt_large: KktMethod,
    large_from: usize,
    refine_steps: u32,
    out_dir: &Path,
) -> Result<Vec<PartitionRow>> {
    let x = tk(xavier())?;
    let guide = tk(xavier_guide(&x, 10.0))?;
    let mut rows = Vec::new();
    for &r in regions {
        let t0 = Instant::now();
        let o = ClusterOptions { regions: r, mu: 0.98, frames: 32, seed: 7, ..ClusterOptions::default() };
        let tf = tk(build_test_functions(&TestFunctionSpec::Clustered(o), &guide, &x.mesh, None))?;
        let clustering_s = t0.elapsed().as_secs_f64();
        let k = tf.len();
        let setup = xavier_setup(&x, &guide, tf, substeps, self_collision);
        let po = PairOpts {
            frames: frames_for(duration, 30.0),
            obj_every: 0,
            untracked: true,
            track: track_opts(if r >= large_from { kkt_large } else { kkt }, refine_steps),
            intersections: false,
            anchors: None,
            tag: format!("_r{r}"),
        };
        let out = run_pair(&setup, &po, out_dir)?;
        rows.push(PartitionRow {
            regions: r,
            k,
            deviation: PairOut::mean(&out.rms_tracked),
            wavelength: PairOut::mean(&out.lambda_raw_tracked),
            s_per_frame: out.s_per_frame_tracked(),
            s_per_frame_untracked: out.s_per_frame_untracked(),
            overhead_pct: out.overhead_pct(),
            overhead_pct_median: out.overhead_pct_median(),
            r_pre: out.max_r_pre / out.scale,
            nnz_l: out.nnz_l,
            clustering_s,
            solve_s_per_step: out.t_kkt / out.steps.max(1) as f64,
        });
    }
    Ok(rows)
}

pub(crate) fn write_partition_outputs(rows: &[PartitionRow], dir: &Path) -> Result<()> {
    let mut csv = CsvWriter::create(
        &dir.join("partitions.csv"),
        &[
            "regions",
            "k",
            "deviation_rms_over_L",
            "wavelength_m",
            "s_per_frame",
            "s_per_frame_untracked",
            "overhead_pct",
            "r_pre_over_L",
            "nnz_l",
            "clustering_s",
            "solve_s_per_step",
        ],
    )?;
    for r in rows {
        csv.row(&[
            Cell::Int(r.regions as i64),
            Cell::Int(r.k as i64),
            Cell::Num(r.deviation),
            Cell::Num(r.wavelength),
            Cell::Num(r.s_per_frame),
            Cell::Num(r.s_per_frame_untracked),
            Cell::Num(r.overhead_pct),
            Cell::Num(r.r_pre),
            Cell::Int(r.nnz_l as i64),
            Cell::Num(r.clustering_s),
            Cell::Num(r.solve_s_per_step),
        ])?;
    }
    let xy = |f: &dyn Fn(&PartitionRow) -> (f64, f64)| rows.iter().map(f).collect::<Vec<_>>();
    LinePlot::new("deviation vs regions", "regions r", "RMS ‖d‖ / L")
        .log(true, true)
        .with(Series::new("xavier", xy(&|r| (r.regions as f64, r.deviation))))
        .write_png(&dir.join("deviation_vs_r.png"))?;
    LinePlot::new("wavelength of d vs regions", "regions r", "λ_eff (m)")
        .log(true, false)
        .with(Series::new("xavier", xy(&|r| (r.regions as f64, r.wavelength))))
        .write_png(&dir.join("wavelength_vs_r.png"))?;
    LinePlot::new("overhead vs regions", "regions r", "overhead (%)")
        .log(true, false)
        .with(Series::new("xavier", xy(&|r| (r.regions as f64, r.overhead_pct))))
        .write_png(&dir.join("overhead_vs_r.png"))?;
    LinePlot::new("accuracy for time", "s per frame (tracked)", "RMS ‖d‖ / L")
        .log(false, true)
        .with(Series::new("xavier", xy(&|r| (r.s_per_frame, r.deviation))))
        .write_png(&dir.join("deviation_vs_time_per_frame.png"))?;
    Ok(())
}

fn run_fig6(ctx: &RunCtx) -> Result<Summary> {
    let p: Fig6Params = scene::load(&ctx.scene_file)?.params;
    let m = ctx.mode;
    let rows = partition_study(
        &p.regions,
        pick3(m, p.duration),
        pick3(m, p.substeps),
        pick3(m, p.self_collision),
        p.kkt,
        p.kkt_large,
        p.large_from,
        p.refine_steps,
        &ctx.out_dir,
    )?;
    write_partition_outputs(&rows, &ctx.out_dir)?;
    let dev_mono = rows.windows(2).all(|w| w[1].deviation < w[0].deviation);
    // Overhead from median step times: robust to load bursts of the shared machine (the mean-based
    // figure is reported beside it per r).
    let ovh_mono = rows.windows(2).all(|w| w[1].overhead_pct_median > w[0].overhead_pct_median);
    let wl_mono = rows.windows(2).all(|w| w[1].wavelength < w[0].wavelength);
    let mut s = Summary::new();
    s.set_count("deviation_monotone", dev_mono as u64);
    s.set_count("overhead_monotone", ovh_mono as u64);
    s.set_count("wavelength_monotone", wl_mono as u64);
    partition_keys(&rows, &mut s);
    s.set("max_residual_pre", rows.iter().map(|r| r.r_pre).fold(0.0, f64::max));
    s.set("duration_s", pick3(m, p.duration));
    s.set_str("mode", m.name());
    Ok(s)
}

// ---------------------------------------------------------------------------------------------
// fig7-clustering (§6.8)

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct Fig7Params {
    regions: usize,
    mu: f64,
    frames: usize,
    seed: u64,
    /// Frames at which non-rigidity is evaluated (every n-th frame of the clip).
    eval_every: (usize, usize, usize),
}

fn write_regions_ply(path: &Path, m: &TriMesh, labels: &[u32]) -> Result<()> {
    use geom_core::io::ply::{write, Encoding, PlyData};
    let color = |l: u32| -> [u8; 3] {
        let h = (l as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15);
        [(h >> 16) as u8, (h >> 32) as u8, (h >> 48) as u8]
    };
    let rgb: Vec<[u8; 3]> = labels.iter().map(|&l| color(l)).collect();
    core(write(path, &MeshOut::tri(&m.positions, &m.faces), &[("color", PlyData::Rgb(&rgb))], Encoding::Ascii))
}

fn run_fig7(ctx: &RunCtx) -> Result<Summary> {
    let p: Fig7Params = scene::load(&ctx.scene_file)?.params;
    let m = ctx.mode;
    let x = tk(xavier())?;
    let guide = tk(xavier_guide(&x, 10.0))?;
    let base =
        ClusterOptions { regions: p.regions, mu: p.mu, frames: p.frames, seed: p.seed, ..ClusterOptions::default() };
    let anim = tk(cluster(&guide, &base, None))?;
    let stat = tk(cluster(&guide, &ClusterOptions { metric: ClusterMetric::StaticVsaL21, ..base.clone() }, None))?;
    let every = pick3(m, p.eval_every).max(1);
    let times: Vec<f64> = (0..=300).step_by(every).map(|f| f as f64 / 30.0).collect();
    let nr_a = tracks::metrics::non_rigidity(&guide, &anim.vertex_labels, anim.regions, &times);
    let nr_s = tracks::metrics::non_rigidity(&guide, &stat.vertex_labels, stat.regions, &times);
    // Max skinning weight per vertex (the rig of procedural::xavier_guide).
    let maxw: Vec<f64> = x
        .membership
        .iter()
        .zip(&x.s)
        .map(|(mb, &s)| {
            let root = 1.0 - geom_core::math::smoothstep(0.25, 0.4, s);
            let up = geom_core::math::smoothstep(0.25, 0.4, s) * (1.0 - geom_core::math::smoothstep(0.55, 0.7, s));
            let lo = geom_core::math::smoothstep(0.55, 0.7, s);
            mb.iter().flat_map(|w| [w * up, w * lo]).fold(root, f64::max)
        })
        .collect();
    let sja = tracks::metrics::seam_joint_alignment(&x.mesh, &anim.vertex_labels, &maxw);
    let sjs = tracks::metrics::seam_joint_alignment(&x.mesh, &stat.vertex_labels, &maxw);
    let area_cv = |c: &tracks::Clustering| -> f64 {
        let areas = geom_core::mesh::face_areas(&x.mesh.faces, &x.mesh.positions);
        let mut ra = vec![0.0; c.regions_tri];
        for (f, &l) in c.tri_labels.iter().enumerate() {
            ra[l as usize] += areas[f];
        }
        let n = ra.len() as f64;
        let mean = ra.iter().sum::<f64>() / n;
        (ra.iter().map(|a| (a - mean).powi(2)).sum::<f64>() / n).sqrt() / mean
    };
    write_regions_ply(&ctx.out_dir.join("regions_animated.ply"), &x.mesh, &anim.vertex_labels)?;
    write_regions_ply(&ctx.out_dir.join("regions_static.ply"), &x.mesh, &stat.vertex_labels)?;
    let mut s = Summary::new();
    s.set("non_rigidity_animated", nr_a);
    s.set("non_rigidity_static", nr_s);
    s.set("seam_joint_alignment_animated", sja);
    s.set("seam_joint_alignment_static", sjs);
    s.set("area_cv_animated", area_cv(&anim));
    s.set("area_cv_static", area_cv(&stat));
    s.set_count("iterations_animated", anim.iterations as u64);
    s.set_count("iterations_static", stat.iterations as u64);
    s.set("clustering_s_animated", anim.time_s);
    s.set("clustering_s_static", stat.time_s);
    s.set("mean_position_term", anim.mean_terms.0);
    s.set("mean_normal_term", anim.mean_terms.1);
    s.set_count("regions_animated", anim.regions as u64);
    s.set_str("mode", m.name());
    Ok(s)
}

// ---------------------------------------------------------------------------------------------
// table55 (§6.9)

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct TableParams {
    /// Simulated time per scene (s) for quick / default / full.
    duration: (f64, f64, f64),
    /// Repetitions (the faster is kept) for quick / default / full.
    repeats: (usize, usize, usize),
    /// Self-collision for quick / default / full.
    self_collision: (bool, bool, bool),
    /// Saddle-point solver per scene: (flag, box, bag, xavier).
    kkt: (KktMethod, KktMethod, KktMethod, KktMethod),
    refine_steps: u32,
    /// Methods timed against each other on identical systems in one extra tracked run per scene
    /// (with the shadow LLᵀ of A for the solve-overhead column); empty = skip that run.
    compare: Vec<KktMethod>,
    /// Simulated time of that run (s) for quick / default / full.
    compare_duration: (f64, f64, f64),
}

fn run_table55(ctx: &RunCtx) -> Result<Summary> {
    let p: TableParams = scene::load(&ctx.scene_file)?.params;
    let m = ctx.mode;
    let dur = pick3(m, p.duration);
    let reps = pick3(m, p.repeats).max(1);
    let sc = pick3(m, p.self_collision);
    let design = flag_design()?;
    let x = tk(xavier())?;
    let xg = tk(xavier_guide(&x, 10.0))?;
    let (xtf, _) = xavier_tf(&x, &xg)?;
    let scenes: Vec<(&str, Setup, f64, [f64; 3])> = vec![
        ("flag", flag_setup(&design, 4, sc)?, 4.1, [17.7, 17.0, 4.0]),
        ("box", box_setup(4, sc)?, 6.0, [15.8, 14.9, 8.0]),
        ("bag", bag_setup(6, sc)?, 2.5, [16.1, 15.7, 88.0]),
        ("xavier", xavier_setup(&x, &xg, xtf, 4, sc), 10.8, [43.2, 39.0, 280.0]),
    ];
    let mut csv = CsvWriter::create(
        &ctx.out_dir.join("table55.csv"),
        &[
            "scene",
            "guide_verts",
            "tracked_verts",
            "constraints",
            "paper_constraints",
            "dof_increase_pct",
            "s_per_frame_tracked",
            "s_per_frame_untracked",
            "overhead_pct",
            "paper_s_per_frame_tracked",
            "paper_s_per_frame_untracked",
            "paper_overhead_pct",
            "solve_s_per_step",
            "max_r_pre_over_L",
            "mean_dc",
            "kkt",
        ],
    )?;
    let mut s = Summary::new();
    let mut worst_pre = 0.0f64;
    let mut report = String::from(
        "# TRACKS §5.5 table: ours beside the paper\n\n| scene | constraints | s/frame tracked (untracked) | overhead % | paper s/frame | paper overhead % |\n|---|---|---|---|---|---|\n",
    );
    // Per scene: its KKT method and the untracked ms per step of the kept run.
    let mut main_runs: Vec<(KktMethod, f64)> = Vec::new();
    for (name, setup, paper_ovh, paper) in &scenes {
        let mut best: Option<PairOut> = None;
        let kkt = match *name {
            "flag" => p.kkt.0,
            "box" => p.kkt.1,
            "bag" => p.kkt.2,
            _ => p.kkt.3,
        };
        for rep in 0..reps {
            let o = PairOpts {
                frames: frames_for(dur, setup.fps),
                obj_every: 0,
                untracked: true,
                track: track_opts(kkt, p.refine_steps),
                intersections: false,
                anchors: None,
                tag: format!("_{name}_{rep}"),
            };
            let out = run_pair(setup, &o, &ctx.out_dir)?;
            worst_pre = worst_pre.max(out.max_r_pre / out.scale);
            if best.as_ref().is_none_or(|b| out.t_tracked + out.t_untracked < b.t_tracked + b.t_untracked) {
                best = Some(out);
            }
        }
        let b = best.expect("at least one repetition");
        main_runs.push((kkt, 1e3 * b.t_untracked / b.steps.max(1) as f64));
        let n = setup.tracked_rest.n_vertices();
        s.set(&format!("overhead_pct_{name}"), b.overhead_pct());
        s.set(&format!("s_per_frame_tracked_{name}"), b.s_per_frame_tracked());
        s.set(&format!("s_per_frame_untracked_{name}"), b.s_per_frame_untracked());
        csv.row(&[
            Cell::Text(name.to_string()),
            Cell::Int(setup.guide.n_vertices() as i64),
            Cell::Int(n as i64),
            Cell::Int(b.k as i64),
            Cell::Num(paper[2]),
            Cell::Num(100.0 * b.k as f64 / n as f64),
            Cell::Num(b.s_per_frame_tracked()),
            Cell::Num(b.s_per_frame_untracked()),
            Cell::Num(b.overhead_pct()),
            Cell::Num(paper[0]),
            Cell::Num(paper[1]),
            Cell::Num(*paper_ovh),
            Cell::Num(b.t_kkt / b.steps.max(1) as f64),
            Cell::Num(b.max_r_pre / b.scale),
            Cell::Num(PairOut::mean(&b.dc_tracked)),
            Cell::Text(format!("{kkt:?}")),
        ])?;
        report.push_str(&format!(
            "| {name} | {} | {:.3} ({:.3}) | {:.1} | {} ({}) | {} |\n",
            b.k,
            b.s_per_frame_tracked(),
            b.s_per_frame_untracked(),
            b.overhead_pct(),
            paper[0],
            paper[1],
            paper_ovh
        ));
    }
    s.set("max_residual_pre", worst_pre);
    s.set("duration_s", dur);
    s.set_count("repeats", reps as u64);
    s.set_count("threads", rayon::current_num_threads() as u64);
    s.set_str("kkt", &format!("{:?}", p.kkt));
    if !p.compare.is_empty() {
        compare_methods(ctx, &p, &scenes, &main_runs, &mut s, &mut report)?;
    }
    s.set_str("mode", m.name());
    report.push_str(&format!(
        "\nMode {}, {dur} s per scene, best of {reps}, self-collision {sc}, {} threads, profile as built.\n",
        m.name(),
        rayon::current_num_threads()
    ));
    std::fs::write(ctx.out_dir.join("report.md"), report)
        .map_err(crate::error::io_err(ctx.out_dir.join("report.md")))?;
    Ok(s)
}

/// The spec §6.9 shadow-timed run, extended: per scene one tracked run whose every system is also
/// solved by each method of `p.compare` and by an unused LLᵀ of A (the untracked factorisation),
/// all timed on identical matrices; writes `kkt_methods.csv` and a report section.
fn compare_methods(
    ctx: &RunCtx,
    p: &TableParams,
    scenes: &[(&str, Setup, f64, [f64; 3])],
    main_runs: &[(KktMethod, f64)],
    s: &mut Summary,
    report: &mut String,
) -> Result<()> {
    let dur = pick3(ctx.mode, p.compare_duration);
    let mut csv = CsvWriter::create(
        &ctx.out_dir.join("kkt_methods.csv"),
        &["scene", "method", "ms_per_step", "ms_llt_of_a_per_step", "solve_overhead_pct", "max_rel_diff", "nnz_l"],
    )?;
    report.push_str(&format!(
        "\n## KKT methods on identical systems ({dur} s per scene, ms per step; LLᵀ of A = the untracked factorisation)\n\n| scene | LLᵀ of A | {} |\n|---|---|{}\n",
        p.compare.iter().map(|m| format!("{m:?}")).collect::<Vec<_>>().join(" | "),
        "---|".repeat(p.compare.len())
    ));
    for ((name, setup, _, _), (main_kkt, untracked_ms)) in scenes.iter().zip(main_runs) {
        let o = PairOpts {
            frames: frames_for(dur, setup.fps),
            obj_every: 0,
            untracked: false,
            track: TrackOptions {
                kkt: p.compare[0],
                refine_steps: p.refine_steps,
                shadow_timing: true,
                compare: p.compare.clone(),
                ..TrackOptions::default()
            },
            intersections: false,
            anchors: None,
            tag: format!("_{name}_methods"),
        };
        let out = run_pair(setup, &o, &ctx.out_dir)?;
        let steps = out.steps.max(1) as f64;
        let llt_ms = 1e3 * out.t_shadow / steps;
        let mut cells = Vec::new();
        for (m, c) in p.compare.iter().zip(&out.compare) {
            let ms = 1e3 * c.0 / steps;
            csv.row(&[
                Cell::Text(name.to_string()),
                Cell::Text(format!("{m:?}")),
                Cell::Num(ms),
                Cell::Num(llt_ms),
                Cell::Num(100.0 * (ms - llt_ms) / llt_ms.max(1e-300)),
                Cell::Num(c.1),
                Cell::Int(c.2 as i64),
            ])?;
            s.set(&format!("kkt_ms_{name}_{}", method_key(m)), ms);
            cells.push(format!("{ms:.2}"));
        }
        s.set(&format!("llt_ms_{name}"), llt_ms);
        // Spec §3.8 solve overhead of the scene's method: (t_kkt − t_LLᵀ(A)) / untracked step,
        // both solves timed on the same matrices in this run.
        if let Some(c) = p.compare.iter().position(|m| m == main_kkt).map(|i| out.compare[i]) {
            s.set(&format!("solve_overhead_pct_{name}"), 100.0 * (1e3 * c.0 / steps - llt_ms) / untracked_ms);
        }
        report.push_str(&format!("| {name} | {llt_ms:.2} | {} |\n", cells.join(" | ")));
    }
    Ok(())
}

/// Short snake-case key of a KKT method for summary keys.
fn method_key(m: &KktMethod) -> &'static str {
    match m {
        KktMethod::ConstraintLastLdlt => "constraint_last",
        KktMethod::InterleavedLdlt => "interleaved",
        KktMethod::AmdRegularizedLdlt { .. } => "amd_regularized",
        KktMethod::Schur => "schur",
        KktMethod::SchurPcg { .. } => "schur_pcg",
        KktMethod::Penalty { .. } => "penalty",
        KktMethod::Compliant { .. } => "compliant",
        KktMethod::AugmentedLagrangian { .. } => "augmented_lagrangian",
    }
}

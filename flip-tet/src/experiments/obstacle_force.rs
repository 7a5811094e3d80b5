//! Obstacle force probes, mesh obstacles and a moving paddle (issue 26 item 4), each against an
//! analytic answer:
//!
//! 1. `box/`: a box held fully submerged in a resting pool; the liquid's pressure force on it is
//!    the buoyancy `ρ g V` upward (`buoyancy_rel_err_box`), its torque about the box centre zero.
//! 2. `mesh/`: the same box as a closed triangle mesh (`Shape::Mesh`, the scene's `mesh_box`):
//!    the same resting pool (`max_speed_mesh`) and the same force (`mesh_vs_box_force_rel_diff`).
//! 3. `paddle/`: a wall-to-wall plate holding liquid of depth `H` on its `−x` side, at rest until
//!    its path starts, then pushing into the liquid: at rest the force on it is the hydrostatic
//!    `ρ g w H² / 2` along `+x` (`paddle_force_rel_err_rest`); the moving phase is reported.
//!
//! Forces and torques are written per frame to each run's `probes.csv` (columns
//! `force_<k>_{x,y,z}_N`, `torque_<k>_{x,y,z}_Nm`). Sign: the force of the liquid on the
//! obstacle, `y` up.
//!
//! ```no_run
//! use flip_tet::experiments::obstacle_force;
//! use geom_core::experiment::Size;
//! #[derive(serde::Deserialize)]
//! struct File { params: obstacle_force::Params }
//! let text = std::fs::read_to_string("scenes/flip-tet/obstacle-force.ron")?;
//! let opts = ron::Options::default().with_default_extension(ron::extensions::Extensions::IMPLICIT_SOME);
//! let p = opts.from_str::<File>(&text)?.params;
//! let r = obstacle_force::run(&p, Size::Quick, &mut geom_core::record::NullRecorder::default())?;
//! println!("buoyancy error {}", r.get_f64("buoyancy_rel_err_box"));
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

use geom_core::experiment::{BySize, Report, Size, Target};
use geom_core::math::Vec3;
use geom_core::record::Recorder;
use geom_core::stats;
use serde::{Deserialize, Serialize};

use super::probes::Probes;
use super::{one, plot, simulate, sized_scene, FrameOutput, RunOut, SimRun};
use crate::error::{Result, SimError};
use crate::metrics::{max_speed, rel_drift};
use crate::scene::{Scene, Shape};
use crate::sim::StepStats;
use crate::sim::RHO;

/// Parameters (the scene file's `params`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Params {
    /// The pool with the submerged box as its first obstacle (an analytic `Box`).
    pub scene: Scene,
    /// The same box as a closed mesh (`Mesh(path: …)`, relative to the scene file's folder).
    pub mesh_box: Shape,
    /// The paddle scene: liquid on the `−x` side of a moving obstacle (its first).
    pub paddle: Scene,
    /// Finest resolution per size (all three runs).
    pub finest: BySize<u32>,
    /// Duration of the pool runs per size (s).
    pub duration: BySize<f64>,
    /// Duration of the paddle run per size (s).
    pub paddle_duration: BySize<f64>,
    /// Surface OBJ every this many frames (0 = never).
    #[serde(default = "one")]
    pub obj_every: u64,
}

impl Params {
    /// Makes the mesh paths absolute against `dir` (the scene file's folder).
    pub fn resolve_paths(&mut self, dir: &std::path::Path) {
        let mut sc = Scene::new(([0.0; 3], [1.0; 3]), (1, 1), vec![]);
        sc.obstacles = vec![self.mesh_box.clone()];
        sc.resolve_paths(dir);
        self.mesh_box = sc.obstacles.remove(0);
        self.scene.resolve_paths(dir);
        self.paddle.resolve_paths(dir);
    }
}

/// Per-frame `(t, force, torque)` of obstacle 0.
pub type ForceSeries = Vec<(f64, Vec3, Vec3)>;

/// Runs `scene` recording the force and torque on obstacle 0 at every frame (and the probes of
/// every obstacle into `probes.csv`).
pub fn force_run(scene: &Scene, rec: &mut dyn Recorder, dir: &str, obj: u64) -> Result<(SimRun, ForceSeries)> {
    let probes = Probes { obstacle_forces: true, ..Default::default() };
    let out = RunOut { probes: Some(&probes), ..RunOut::full(dir, FrameOutput::surface(obj)) };
    let mut forces = Vec::new();
    let run = simulate(scene, rec, out, &mut |sim, st: &StepStats| {
        if st.frame_end && !sim.obstacles().is_empty() {
            let (f, t) = sim.obstacle_force(0);
            forces.push((st.t, f, t));
        }
        Ok(())
    })?;
    Ok((run, forces))
}

fn box_volume(s: &Shape) -> Result<f64> {
    match s {
        Shape::Box { min, max } => Ok((0..3).map(|a| max[a] - min[a]).product()),
        _ => Err(SimError::InvalidScene("obstacle-force: the pool's first obstacle must be a Box".into())),
    }
}

/// Sanity figures of one run under `tag`: particle-volume drift, largest speed (NaN-safe), and
/// whether every per-step figure is finite.
pub fn sanity(s: &mut Report, stats: &[StepStats], tag: &str) {
    s.num(&format!("particle_volume_drift_rel_{tag}"), rel_drift(stats, |x| x.vol_particles));
    s.num(&format!("max_speed_{tag}"), max_speed(stats));
    let finite = stats.iter().all(|x| x.vol_particles.is_finite() && x.kinetic_energy.is_finite());
    s.flag(&format!("finite_{tag}"), finite);
}

/// Runs the three cases.
pub fn run(p: &Params, size: Size, rec: &mut dyn Recorder) -> Result<Report> {
    let g = -p.scene.gravity[1];
    let mut s = Report::default();
    // 1. Analytic box.
    let scene = sized_scene(&p.scene, &p.finest, None, &p.duration, size);
    let bx = scene.obstacles.first().ok_or_else(|| SimError::InvalidScene("obstacle-force: no obstacle".into()))?;
    let vol = box_volume(bx)?;
    let buoy = RHO * g * vol;
    let (run_box, f_box) = force_run(&scene, rec, "box/", p.obj_every)?;
    let last = |f: &ForceSeries| f.last().map_or((Vec3::repeat(f64::NAN), Vec3::repeat(f64::NAN)), |x| (x.1, x.2));
    let (fb, tb) = last(&f_box);
    s.num("buoyancy_expected_N", buoy);
    s.num("force_y_box_N", fb.y);
    s.num("buoyancy_rel_err_box", (fb.y - buoy).abs() / buoy);
    s.num("force_horizontal_box_N", fb.x.hypot(fb.z));
    s.num("torque_norm_box_Nm", tb.norm());
    sanity(&mut s, &run_box.stats, "box");
    // 2. The same box as a mesh.
    let mut ms = scene.clone();
    ms.obstacles[0] = p.mesh_box.clone();
    let (run_mesh, f_mesh) = force_run(&ms, rec, "mesh/", p.obj_every)?;
    let (fm, tm) = last(&f_mesh);
    s.num("force_y_mesh_N", fm.y);
    s.num("buoyancy_rel_err_mesh", (fm.y - buoy).abs() / buoy);
    s.num("torque_norm_mesh_Nm", tm.norm());
    s.num("mesh_vs_box_force_rel_diff", (fm - fb).norm() / buoy);
    sanity(&mut s, &run_mesh.stats, "mesh");
    // 3. Paddle at rest, then moving.
    let pad = sized_scene(&p.paddle, &p.finest, None, &p.paddle_duration, size);
    let start = pad
        .moving_obstacles
        .first()
        .map(|m| rest_until(&m.path))
        .ok_or_else(|| SimError::InvalidScene("obstacle-force: the paddle scene needs a moving obstacle".into()))?;
    let depth = match pad.liquid.first() {
        Some(Shape::Box { min, max }) => max[1] - min[1],
        _ => return Err(SimError::InvalidScene("obstacle-force: the paddle's liquid must be a Box".into())),
    };
    let width = pad.domain.max[2] - pad.domain.min[2];
    let hydro = 0.5 * RHO * g * width * depth * depth;
    let (run_pad, f_pad) = force_run(&pad, rec, "paddle/", p.obj_every)?;
    let rest: Vec<&(f64, Vec3, Vec3)> = f_pad.iter().filter(|x| x.0 <= start + 1e-9).collect();
    let f_rest = rest.last().map_or(f64::NAN, |x| x.1.x);
    s.num("paddle_hydrostatic_N", hydro);
    s.num("paddle_force_x_rest_N", f_rest);
    s.num("paddle_force_rel_err_rest", (f_rest - hydro).abs() / hydro);
    let rest_speed: Vec<f64> = run_pad.stats.iter().filter(|x| x.t <= start + 1e-9).map(|x| x.max_speed).collect();
    s.num("max_speed_paddle_rest", stats::max(&rest_speed));
    let moving: Vec<f64> = f_pad.iter().filter(|x| x.0 > start + 1e-9).map(|x| x.1.x).collect();
    s.num("paddle_force_x_max_moving_N", stats::max(&moving));
    sanity(&mut s, &run_pad.stats, "paddle");
    let axes = ("t (s)", "force (N)");
    plot(rec, "forces", "box F_y", axes, (false, false), f_box.iter().map(|x| (x.0, x.1.y)).collect())?;
    plot(rec, "forces", "mesh box F_y", axes, (false, false), f_mesh.iter().map(|x| (x.0, x.1.y)).collect())?;
    plot(rec, "forces", "rho g V", axes, (false, false), f_box.iter().map(|x| (x.0, buoy)).collect())?;
    plot(rec, "paddle_force", "paddle F_x", axes, (false, false), f_pad.iter().map(|x| (x.0, x.1.x)).collect())?;
    plot(rec, "paddle_force", "rho g w H^2/2", axes, (false, false), f_pad.iter().map(|x| (x.0, hydro)).collect())?;
    s.text("force_sign", "force of the liquid's gauge pressure on the obstacle, y up");
    s.check("buoyancy_rel_err_box", Target::AtMost(0.01), "issue 26: submerged box, force = rho g V (ours: 1 %)");
    s.check("max_speed_mesh", Target::AtMost(1e-7), "issue 26: a closed mesh box rests like the analytic box");
    s.check("paddle_force_rel_err_rest", Target::AtMost(0.01), "issue 26: paddle at rest, hydrostatic force to 1 %");
    Ok(s)
}

/// The time (s) until which a path is at rest: `After { start }`'s start, else 0.
fn rest_until(p: &geom_core::kinematic::KinematicPath) -> f64 {
    match p {
        geom_core::kinematic::KinematicPath::After { start, .. } => *start,
        _ => 0.0,
    }
}

//! `shells/drape` (shells.md §6 scene 3): a 1 m cotton square pinned at two corners falls under
//! gravity with self-collision; then the same scene without collisions, timed in the same run.
//!
//! Figures: `max_intersections` (exact count over written frames), `nan_steps`, `steps`,
//! `n_vertices`, `energy_start_J`, `energy_end_J`, `momentum_change` (|Δp|, kg·m/s),
//! `ccd_events`, `frozen_vertices`, `no_collision_max_intersections`, and the timings
//! `s_per_step` (mean wall time of a step with collisions), `s_per_step_median`,
//! `s_per_step_no_collision`, `collision_share`, `assembly_s`, `factor_s`, `solve_s`,
//! `collision_s`, `threads`, `profile`. Frames `frames/NNNN.obj`, tables `steps_frames`,
//! `frames_frames`.
//!
//! ```no_run
//! use geom_core::experiment::Size;
//! use geom_core::record::NullRecorder;
//! #[derive(serde::Deserialize)]
//! struct File { params: shells::experiments::drape::Params }
//! let f: File = ron::from_str(&std::fs::read_to_string("scenes/shells/drape.ron").unwrap()).unwrap();
//! let r = shells::experiments::drape::run(&f.params, Size::Quick, &mut NullRecorder::default()).unwrap();
//! println!("{:?}", r.get("s_per_step"));
//! ```

use geom_core::experiment::{BySize, Report, Size, Target};
use geom_core::record::{NullRecorder, Recorder};
use serde::Deserialize;

use super::protocol::{self, RunPlan, RunStats};
use crate::error::{Error, Result};
use crate::metrics::{self, Sanity};
use crate::scene::ShellScene;
use crate::sim::ShellSim;

/// Parameters (the scene file's `params` block).
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Params {
    /// The simulation (with its collision settings).
    pub shell: ShellScene,
    /// Grid (nx, ny) vertices per run size; `None` keeps the scene's mesh.
    #[serde(default)]
    pub resolution: Option<BySize<(u32, u32)>>,
    /// Simulated time per run size (s); `None` keeps `shell.duration`.
    #[serde(default)]
    pub duration: Option<BySize<f64>>,
    /// Record every n-th frame's mesh (0 = none; intersections are counted on recorded frames).
    #[serde(default = "one")]
    pub frame_every: usize,
}

fn one() -> usize {
    1
}

/// The run plan of a scene (frames from its duration and frame rate).
pub(crate) fn plan(shell: &ShellScene, frame_every: usize, tables: bool, track_energy: bool) -> RunPlan {
    let it = &shell.integrator;
    RunPlan {
        frames: (shell.duration * it.fps).round() as usize,
        substeps: it.substeps,
        h: it.h(),
        frame_every,
        sequence: "frames".into(),
        count_intersections: true,
        track_energy,
        tables,
    }
}

/// A simulation of `shell` and a sanity monitor of its mesh; on a passive scene
/// ([`metrics::is_passive`]: gravity, static pins and obstacles only) the monitor tracks
/// `energy_gain_rel` (scale m·g·D). Returns whether the scene is passive.
pub(crate) fn start(shell: &ShellScene) -> Result<(ShellSim, Sanity, bool)> {
    let built = shell.build(std::path::Path::new("."))?;
    let obstacles = built.desc.effects.obstacles.clone();
    let passive = metrics::is_passive(&built.desc);
    let g = built.desc.effects.gravity.map(|g| g.norm()).unwrap_or(0.0);
    let sim = ShellSim::new(built.desc)?;
    let scale = passive.then(|| Sanity::passive_energy_scale(&sim.mesh().rest, &sim.mesh().mass, g));
    let sanity = Sanity::new(&sim.mesh().rest, &sim.mesh().edges, obstacles, scale);
    Ok((sim, sanity, passive))
}

/// The per-phase timings of a run (s, summed over steps) and its collision share.
pub(crate) fn phase_timings(r: &mut Report, rs: &RunStats) {
    let wall: f64 = rs.step_wall.iter().sum();
    r.timing("collision_share", rs.totals.t_collision / wall.max(1e-300));
    r.timing("assembly_s", rs.totals.t_assembly);
    r.timing("factor_s", rs.totals.t_factor);
    r.timing("solve_s", rs.totals.t_solve);
    r.timing("collision_s", rs.totals.t_collision);
}

/// Runs the drape with collisions (as in the scene file) and without.
pub fn run(p: &Params, size: Size, rec: &mut dyn Recorder) -> Result<Report> {
    let shell = protocol::sized(&p.shell, p.resolution.as_ref(), p.duration.as_ref(), size);
    let (mut sim, mut sanity, passive) = start(&shell)?;
    super::contact::record_context(&sim, &shell, rec)?;
    let nv = sim.state().q.len();
    let e0 = sim.energies().total();
    let p0 = sim.momentum();
    let with = protocol::run(&mut sim, &plan(&shell, p.frame_every, true, passive), &mut sanity, rec, |_, _| {})?;
    let e1 = sim.energies().total();
    // Without collisions: same file, effect removed, same duration, timed in the same run.
    let mut nocol = shell.clone();
    nocol.effects.collision = None;
    nocol.effects.self_collision = false;
    let (mut sim2, mut sanity2, _) = start(&nocol)?;
    let without = protocol::run(
        &mut sim2,
        &plan(&nocol, 1, false, false),
        &mut sanity2,
        &mut NullRecorder::default(),
        |_, _| {},
    )?;
    let mut r = Report::default();
    r.count("n_vertices", nv as u64);
    r.timing("threads", rayon::current_num_threads() as f64);
    super::contact::sanity_figures(&mut r, "", &sanity, &with);
    r.timing("s_per_step", with.s_per_step());
    r.timing("s_per_step_median", geom_core::stats::median(&with.step_wall));
    r.timing("s_per_step_no_collision", without.s_per_step());
    phase_timings(&mut r, &with);
    r.count("no_collision_max_intersections", without.max_intersections);
    r.num("energy_start_J", e0);
    r.num("energy_end_J", e1);
    r.num("momentum_change", (sim.momentum() - p0).norm());
    r.count("ccd_events", with.totals.n_ccd as u64);
    r.count("frozen_vertices", with.totals.n_frozen as u64);
    r.text("profile", if cfg!(debug_assertions) { "dev" } else { "release" });
    if let Some(e) = &with.error {
        return Err(Error::RunFailed { scene: "drape".into(), steps: with.steps, message: e.clone() });
    }
    rec.note(&format!(
        "### shells/drape\n\n{nv} vertices, {} threads, {} steps. Per implicit step: {:.4} s with self-collision, \
         {:.4} s without (collisions {:.0}% of the time). Max intersecting triangle pairs: {} with collisions, {} \
         without.\n",
        rayon::current_num_threads(),
        with.steps,
        with.s_per_step(),
        without.s_per_step(),
        100.0 * with.totals.t_collision / with.step_wall.iter().sum::<f64>().max(1e-300),
        with.max_intersections,
        without.max_intersections
    ))?;
    super::contact::checks(&mut r, "", 0.10, passive);
    r.check("s_per_step", Target::AtMost(0.025), "issue 20 / shells.md §6.3 (drape timing, default size)");
    Ok(r)
}

//! The contact suite (`shells/sphere-drop`, `spinning-sphere`, `table`, `twist`, and the
//! sanity figures of `fold-stress` and `drape`): cloth dropped, draped, spun and twisted against
//! obstacles and itself, judged by the invariants that expose nonsense — edge strain and
//! compression, obstacle penetration, exact self-intersections, energy gained from nowhere, NaN.
//!
//! ```no_run
//! use geom_core::experiment::Size;
//! use geom_core::record::NullRecorder;
//! let text = std::fs::read_to_string("scenes/shells/sphere-drop.ron").unwrap();
//! #[derive(serde::Deserialize)]
//! struct File { params: shells::experiments::contact::Params }
//! let f: File = ron::from_str(&text).unwrap();
//! let report = shells::experiments::contact::run(&f.params, Size::Quick, &mut NullRecorder::default()).unwrap();
//! assert!(report.all_pass());
//! ```

use geom_core::experiment::{BySize, Report, Size, Target};
use geom_core::record::{Recorder, SceneItem};
use serde::Deserialize;

use super::protocol::{self, RunPlan};
use crate::effects::ObstacleShape;
use crate::error::{Error, Result};
use crate::metrics::Sanity;
use crate::scene::ShellScene;
use crate::sim::ShellSim;

/// Parameters of a contact-suite scene (the RON `params` block).
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Params {
    /// The simulation.
    pub shell: ShellScene,
    /// Mesh resolution per run size: a grid's (nx, ny) vertices or a tube's (around, along);
    /// `None` keeps the scene's mesh.
    #[serde(default)]
    pub resolution: Option<BySize<(u32, u32)>>,
    /// Simulated time per run size (s); `None` keeps `shell.duration`.
    #[serde(default)]
    pub duration: Option<BySize<f64>>,
    /// Gravity, static pins and static obstacles only: `energy_gain_rel` is defined.
    #[serde(default)]
    pub passive: bool,
    /// Record every n-th frame's mesh (0 = none).
    #[serde(default = "one")]
    pub frame_every: usize,
    /// The `max_edge_strain` target (the issue's 0.10; 0.15 for the collapsing twisted tube).
    #[serde(default = "strain_target")]
    pub strain_target: f64,
}

fn one() -> usize {
    1
}
fn strain_target() -> f64 {
    0.10
}

/// The shell scene at a run size.
pub fn sized(p: &Params, size: Size) -> ShellScene {
    protocol::sized(&p.shell, p.resolution.as_ref(), p.duration.as_ref(), size)
}

/// Context of the scene for previews: ground planes, obstacle meshes, pinned vertices, frame
/// rate.
pub fn record_context(sim: &ShellSim, shell: &ShellScene, rec: &mut dyn Recorder) -> Result<()> {
    rec.scene(&SceneItem::FrameRate { fps: shell.integrator.fps })?;
    let d = sim.free_dofs();
    let mut pinned: Vec<u32> = d.pinned.iter().chain(&d.kinematic).copied().collect();
    pinned.sort_unstable();
    if !pinned.is_empty() {
        rec.scene(&SceneItem::Pinned { sequence: "frames".into(), vertices: pinned })?;
    }
    for (k, o) in sim.effects().obstacles.iter().enumerate() {
        let name = format!("obstacle-{k}");
        let item = match &o.shape {
            ObstacleShape::Plane { normal, offset } if normal.x == 0.0 && normal.z == 0.0 && normal.y > 0.0 => {
                SceneItem::Ground { y: offset / normal.y }
            }
            ObstacleShape::Plane { .. } => continue,
            shape => match shape.surface_mesh()? {
                Some((positions, faces)) => SceneItem::Mesh { name, positions, faces },
                None => continue,
            },
        };
        rec.scene(&item)?;
    }
    Ok(())
}

/// Runs the scene and reports the sanity figures with the issue's targets.
pub fn run(p: &Params, size: Size, rec: &mut dyn Recorder) -> Result<Report> {
    if !(p.strain_target > 0.0) {
        return Err(Error::BadParameter(format!("strain_target must be > 0, got {}", p.strain_target)));
    }
    let shell = sized(p, size);
    let built = shell.build(std::path::Path::new("."))?;
    let obstacles = built.desc.effects.obstacles.clone();
    let g = built.desc.effects.gravity.map(|g| g.norm()).unwrap_or(0.0);
    let mut sim = ShellSim::new(built.desc)?;
    record_context(&sim, &shell, rec)?;
    let it = &shell.integrator;
    let frames = (shell.duration * it.fps).round() as usize;
    let scale = p.passive.then(|| Sanity::passive_energy_scale(&sim.mesh().rest, &sim.mesh().mass, g));
    let mut sanity = Sanity::new(&sim.mesh().rest, &sim.mesh().edges, obstacles, scale);
    let plan = RunPlan {
        frames,
        substeps: it.substeps,
        h: it.h(),
        frame_every: p.frame_every,
        sequence: "frames".into(),
        count_intersections: true,
        track_energy: p.passive,
        tables: true,
    };
    let rs = protocol::run(&mut sim, &plan, &mut sanity, rec, |_, _| {})?;
    let mut r = Report::default();
    sanity_figures(&mut r, "", &sanity, &rs);
    r.count("n_vertices", sim.state().q.len() as u64);
    r.timing("s_per_step", rs.s_per_step());
    r.timing("s_per_step_median", geom_core::stats::median(&rs.step_wall));
    r.timing("sim_wall_s", rs.step_wall.iter().sum());
    r.timing("threads", rayon::current_num_threads() as f64);
    if let Some(e) = &rs.error {
        rec.note(&format!("the run stopped: {e}"))?;
    }
    checks(&mut r, "", p.strain_target, p.passive);
    Ok(r)
}

/// The sanity and contact figures of one run, keys suffixed by `suffix` (e.g. `_tracked`).
pub fn sanity_figures(r: &mut Report, suffix: &str, s: &Sanity, rs: &protocol::RunStats) {
    let k = |name: &str| format!("{name}{suffix}");
    r.num(&k("max_edge_strain"), s.max_edge_strain);
    r.num(&k("max_edge_compression"), s.max_edge_compression);
    r.num(&k("max_obstacle_penetration_m"), s.max_obstacle_penetration_m);
    r.count(&k("max_intersections"), rs.max_intersections);
    r.count(&k("nan_steps"), rs.nan_steps);
    if let Some(e) = s.energy_gain_rel() {
        r.num(&k("energy_gain_rel"), e);
    }
    r.count(&k("steps"), rs.steps);
    let iters: Vec<f64> = rs.newton_iters.iter().map(|&x| x as f64).collect();
    r.num(&k("newton_iters_mean"), geom_core::stats::mean(&iters));
    r.num(&k("newton_iters_max"), geom_core::stats::max(&iters));
    let c = &rs.totals.contact;
    r.count(&k("max_active_contacts"), rs.max_active_contacts as u64);
    r.num(&k("min_contact_gap_m"), if c.min_gap.is_finite() { c.min_gap } else { f64::NAN });
    r.count(&k("ccd_clamped_steps"), c.ccd_clamps as u64);
    r.count(&k("unconverged_steps"), c.unconverged as u64);
    r.count(&k("contact_free_steps"), c.contact_free_steps as u64);
    r.count(&k("line_search_failures"), c.line_search_failures as u64);
}

/// The issue's targets for a contact scene.
pub fn checks(r: &mut Report, suffix: &str, strain_target: f64, passive: bool) {
    let k = |name: &str| format!("{name}{suffix}");
    let src = "issue 20 (contact invariants)";
    r.check(&k("max_obstacle_penetration_m"), Target::AtMost(1e-4), src);
    r.check(&k("max_intersections"), Target::Equals(0.0), src);
    r.check(&k("nan_steps"), Target::Equals(0.0), src);
    r.check(&k("max_edge_compression"), Target::AtMost(0.5), src);
    r.check(&k("max_edge_strain"), Target::AtMost(strain_target), src);
    if passive {
        r.check(&k("energy_gain_rel"), Target::AtMost(0.01), src);
    }
}

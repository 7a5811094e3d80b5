//! `shells/wind-flag` (shells.md §6 scene 6): a 1.2 m × 0.8 m cotton flag pinned along its
//! short side flutters in an 8 m/s gusty wind; then the same flag without wind, timed in the same
//! run.
//!
//! Figures: `flutter_hz` (dominant frequency of the far tip's z after `settle_time`, Hz),
//! `mean_drag_N` (mean wind force along the base wind direction, N; [`metrics::wind_drag`]),
//! the sanity figures of [`super::contact::sanity_figures`] (`max_edge_strain`,
//! `max_edge_compression`, `max_obstacle_penetration_m`, `max_intersections`, `nan_steps`, …;
//! no `energy_gain_rel`: the wind drives the flag), `n_vertices`, and the timings `s_per_step` (= `s_per_step_wind`), `s_per_step_wind`, `s_per_step_no_wind`,
//! `wind_time_overhead` (relative), `threads`. Frames `frames/NNNN.obj`, tables
//! `steps_frames`, `frames_frames`.
//!
//! ```no_run
//! use geom_core::experiment::Size;
//! use geom_core::record::NullRecorder;
//! #[derive(serde::Deserialize)]
//! struct File { params: shells::experiments::wind_flag::Params }
//! let f: File = ron::from_str(&std::fs::read_to_string("scenes/shells/wind-flag.ron").unwrap()).unwrap();
//! let r = shells::experiments::wind_flag::run(&f.params, Size::Quick, &mut NullRecorder::default()).unwrap();
//! println!("{:?}", r.get("flutter_hz"));
//! ```

use geom_core::experiment::{BySize, Report, Size};
use geom_core::record::{NullRecorder, Recorder};
use serde::Deserialize;

use super::drape::{plan, start};
use super::protocol;
use crate::error::{Error, Result};
use crate::metrics;
use crate::scene::MeshSpec;
use crate::wind::WindField;

/// Parameters (the scene file's `params` block).
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Params {
    /// The flag (a Grid mesh with a wind).
    pub shell: crate::scene::ShellScene,
    /// Grid (nx, ny) vertices per run size; `None` keeps the scene's mesh.
    #[serde(default)]
    pub resolution: Option<BySize<(u32, u32)>>,
    /// Simulated time per run size (s); `None` keeps `shell.duration`.
    #[serde(default)]
    pub duration: Option<BySize<f64>>,
    /// Time after which the flutter and drag are measured (s; at most half the duration).
    pub settle_time: f64,
    /// Record every n-th frame's mesh (0 = none).
    #[serde(default = "one")]
    pub frame_every: usize,
}

fn one() -> usize {
    1
}

/// Runs the flag with and without wind.
pub fn run(p: &Params, size: Size, rec: &mut dyn Recorder) -> Result<Report> {
    let shell = protocol::sized(&p.shell, p.resolution.as_ref(), p.duration.as_ref(), size);
    let nx = match &shell.mesh {
        MeshSpec::Grid { nx, .. } => *nx,
        _ => return Err(Error::BadParameter("wind-flag: shell.mesh must be a Grid".into())),
    };
    let wind = shell
        .effects
        .wind
        .clone()
        .ok_or_else(|| Error::BadParameter("wind-flag: shell.effects.wind is missing".into()))?;
    let (mut sim, mut sanity, _) = start(&shell)?;
    super::contact::record_context(&sim, &shell, rec)?;
    let faces = sim.mesh().tris.clone();
    let ny = sim.state().q.len() as u32 / nx;
    let tip = (ny * nx - 1) as usize; // far corner of the last row
    let wf = WindField::new(&wind);
    let dir = wind.base.normalize();
    let settle = p.settle_time.min(0.5 * shell.duration);
    let substeps = shell.integrator.substeps as u64;
    let (mut tip_z, mut drag) = (Vec::new(), Vec::new());
    let mut steps = 0u64;
    let pl = plan(&shell, p.frame_every, true, false);
    let r1 = protocol::run(&mut sim, &pl, &mut sanity, rec, |sim, _| {
        steps += 1;
        let st = sim.state();
        // Sampled once per frame, after its last step.
        if steps.is_multiple_of(substeps) && st.t >= settle {
            tip_z.push(st.q[tip].z);
            drag.push(metrics::wind_drag(&wf, &faces, &st.q, &st.v, st.t, &dir));
        }
    })?;
    if let Some(e) = &r1.error {
        return Err(Error::RunFailed { scene: "wind-flag".into(), steps: r1.steps, message: e.clone() });
    }
    // Without wind, same file, same duration, timed in the same run.
    let mut nowind = shell.clone();
    nowind.effects.wind = None;
    let (mut sim2, mut sanity2, _) = start(&nowind)?;
    let mut pl2 = plan(&nowind, 0, false, false);
    pl2.count_intersections = false;
    let r2 = protocol::run(&mut sim2, &pl2, &mut sanity2, &mut NullRecorder::default(), |_, _| {})?;
    let (w1, w2): (f64, f64) = (r1.step_wall.iter().sum(), r2.step_wall.iter().sum());
    let mut r = Report::default();
    r.num("flutter_hz", geom_core::stats::dominant_frequency(&tip_z, shell.integrator.fps));
    r.num("mean_drag_N", geom_core::stats::mean(&drag));
    r.timing("s_per_step_wind", r1.s_per_step());
    r.timing("s_per_step_no_wind", r2.s_per_step());
    r.timing("wind_time_overhead", w1 / w2.max(1e-300) - 1.0);
    super::contact::sanity_figures(&mut r, "", &sanity, &r1);
    r.count("n_vertices", sim.state().q.len() as u64);
    r.timing("threads", rayon::current_num_threads() as f64);
    r.timing("s_per_step", r1.s_per_step());
    Ok(r)
}

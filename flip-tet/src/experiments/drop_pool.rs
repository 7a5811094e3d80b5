//! S4 (spec §6, the paper's Fig. 3 analogue): a liquid ball falling into a pool with curvature,
//! turbulence and depth sizing; the particle-count curve against a uniform sampling and the cost
//! against the particle count.
//!
//! ```no_run
//! use flip_tet::experiments::drop_pool;
//! use geom_core::experiment::Size;
//! let r = drop_pool::run(&flip_tet::presets::drop_pool(), Size::Quick, &mut geom_core::record::NullRecorder::default())?;
//! println!("peak / initial particles {}", r.get_f64("peak_over_initial"));
//! # Ok::<(), flip_tet::error::SimError>(())
//! ```

use geom_core::experiment::{BySize, Report, Size};
use geom_core::record::Recorder;
use serde::{Deserialize, Serialize};

use super::{one, plot, simulate, sized_scene, FrameOutput, RunOut};
use crate::error::Result;
use crate::metrics::{pearson, rel_drift, run_figures, sampled_liquid_volume};
use crate::scene::Scene;
use crate::sim::StepStats;

/// Parameters (the scene file's `params`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Params {
    /// The pool and the drop.
    pub scene: Scene,
    /// Finest resolution per size.
    pub finest: BySize<u32>,
    /// Duration per size (s).
    pub duration: BySize<f64>,
    /// Surface OBJ every this many frames (0 = never).
    #[serde(default = "one")]
    pub obj_every: u64,
    /// Particle PLY every this many frames (0 = never).
    #[serde(default)]
    pub ply_every: u64,
    /// High-resolution surface every this many frames (0 = never).
    #[serde(default)]
    pub hires_every: u64,
}

/// Runs S4.
pub fn run(p: &Params, size: Size, rec: &mut dyn Recorder) -> Result<Report> {
    let scene = sized_scene(&p.scene, &p.finest, None, &p.duration, size);
    let frames = FrameOutput { obj: p.obj_every, ply: p.ply_every, hires: p.hires_every };
    let run = simulate(&scene, rec, RunOut::full("", frames), &mut |_, _| Ok(()))?;
    let mut s = Report::default();
    particle_figures(&mut s, &scene, &run.stats, run.wall);
    let pts: Vec<(f64, f64)> = run.stats.iter().map(|x| (x.t, x.n_particles as f64)).collect();
    plot(rec, "particles_vs_time", "adaptive", ("t (s)", "particles"), (false, false), pts)?;
    Ok(s)
}

/// The drop-pool figures of a finished run (spec S4; also S7's): particle counts against the
/// uniform estimate (8 particles per finest cube of the initial liquid), the ballistic fraction,
/// the Pearson correlation of step time (remesh excluded) with the particle count, the level-set
/// volume drift, and the run figures.
pub fn particle_figures(s: &mut Report, scene: &Scene, stats: &[StepStats], wall: f64) {
    let n0 = stats.first().map_or(0, |x| x.n_particles) as f64;
    let peak = stats.iter().map(|x| x.n_particles).max().unwrap_or(0) as f64;
    let end = stats.last().map_or(0, |x| x.n_particles) as f64;
    let h_min = (0..3).map(|a| scene.domain.max[a] - scene.domain.min[a]).fold(0.0, f64::max)
        / f64::from(scene.resolution.finest);
    let uniform = 8.0 * sampled_liquid_volume(scene, 128) / h_min.powi(3);
    let ballistic: f64 = stats.iter().map(|x| x.n_ballistic as f64 / x.n_particles.max(1) as f64).sum::<f64>()
        / stats.len().max(1) as f64;
    let xs: Vec<f64> = stats.iter().map(|x| x.n_particles as f64).collect();
    let ys: Vec<f64> = stats.iter().map(|x| x.timings.total() - x.timings.remesh).collect();
    s.num("particles_initial", n0);
    s.num("particles_peak", peak);
    s.num("particles_end", end);
    s.num("peak_over_initial", peak / n0.max(1.0));
    s.num("end_over_initial", end / n0.max(1.0));
    s.num("uniform_particles_estimate", uniform);
    s.num("uniform_over_adaptive_initial", uniform / n0.max(1.0));
    s.num("ballistic_fraction_avg", ballistic);
    s.timing("time_particles_pearson", pearson(&xs, &ys));
    s.num("vol_levelset_drift_rel", rel_drift(stats, |x| x.vol_levelset));
    run_figures(s, stats, wall);
}

//! S5 (spec §6, the paper's Figure 1 analogue): a liquid sphere dropped into a wide shallow pool
//! with liquid-curvature sizing; particle counts against a uniform sampling, cost per frame and
//! per million particle-steps, top views of the leaf levels.
//!
//! ```no_run
//! use flip_tet::experiments::open_splash;
//! use geom_core::experiment::Size;
//! let r = open_splash::run(&flip_tet::presets::open_splash(), Size::Quick, &mut geom_core::record::NullRecorder::default())?;
//! println!("uniform / adaptive particles {}", r.get_f64("particle_ratio_uniform_over_adaptive"));
//! # Ok::<(), flip_tet::error::SimError>(())
//! ```

use geom_core::experiment::{BySize, Report, Size};
use geom_core::image::{png_gray8_bytes, ImageF32};
use geom_core::record::{Cell, MeshFrame, Recorder};
use serde::{Deserialize, Serialize};

use super::{plot, simulate_frames, sized_scene, FrameLog, Snapshots};
use crate::error::Result;
use crate::octree::Octree;
use crate::scene::Scene;

/// Parameters of the frame-by-frame scenes S5 and S6 (the scene file's `params`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Params {
    /// The scene.
    pub scene: Scene,
    /// Finest resolution per size.
    pub finest: BySize<u32>,
    /// Duration per size (s).
    pub duration: BySize<f64>,
    /// Surface OBJ every this many frames (0 = never).
    pub obj_every: u32,
}

impl Params {
    /// The scene at `size`.
    pub fn scene_at(&self, size: Size) -> Scene {
        sized_scene(&self.scene, &self.finest, None, &self.duration, size)
    }
}

/// Top view of the octree leaf levels (finest level over each column), one grey PNG pixel per
/// finest cube; brighter = finer.
pub fn levels_topview(oct: &Octree) -> ImageF32 {
    let sp = oct.spec;
    let ext = sp.extent_units();
    let cell = sp.size_units(sp.levels - 1);
    let (w, d) = ((ext[0] / cell) as u32, (ext[2] / cell) as u32);
    let mut img = ImageF32::new(w, d, 0.0);
    for lf in &oct.leaves {
        let s = sp.size_units(lf.level) / cell;
        let (x0, z0) = (lf.origin.0[0] / cell, lf.origin.0[2] / cell);
        let v = (lf.level as f32 + 1.0) / sp.levels as f32;
        for i in x0..x0 + s {
            for k in z0..z0 + s {
                if img.at(i as u32, k as u32) < v {
                    img.set(i as u32, k as u32, v);
                }
            }
        }
    }
    img
}

/// Records the level top view as `name` (skipped when outputs are discarded).
pub fn record_topview(rec: &mut dyn Recorder, name: &str, oct: &Octree) -> Result<()> {
    if rec.keeps_outputs() {
        rec.file(name, &png_gray8_bytes(&levels_topview(oct))?)?;
    }
    Ok(())
}

/// `frames*.csv` of a frame log: `t_s, particles, ballistic, frame_wall_s`.
pub fn frames_table(rec: &mut dyn Recorder, name: &str, log: &FrameLog) -> Result<()> {
    rec.table(name, &["t_s", "particles", "ballistic", "frame_wall_s"])?;
    for f in &log.frames {
        rec.row(name, &[Cell::Num(f.0), Cell::Int(f.1 as i64), Cell::Int(f.2 as i64), Cell::Num(f.3)])?;
    }
    Ok(())
}

/// Cost (`plot`) and particle (`plot_particles`) curves per frame of the labelled runs.
pub fn cost_plots(rec: &mut dyn Recorder, plot_name: &str, runs: &[(&str, &FrameLog)]) -> Result<()> {
    for (name, log) in runs {
        let pts = log.frames.iter().map(|f| (f.0, f.3)).collect();
        plot(rec, plot_name, name, ("t (s)", "wall seconds per frame"), (false, false), pts)?;
        let pts = log.frames.iter().map(|f| (f.0, f.1 as f64)).collect();
        plot(rec, &format!("{plot_name}_particles"), name, ("t (s)", "particles"), (false, false), pts)?;
    }
    Ok(())
}

/// Runs S5.
pub fn run(p: &Params, size: Size, rec: &mut dyn Recorder) -> Result<Report> {
    let scene = p.scene_at(size);
    let n_frames = (scene.duration * scene.fps).round().max(1.0) as usize;
    let snaps = [0, n_frames / 2, n_frames];
    let mut rendered = Snapshots::new(&scene, "")?;
    let obj_every = p.obj_every;
    let log = {
        let rec = &mut *rec;
        simulate_frames(&scene, |sim, f| {
            rendered.frame(sim, f as u64, rec)?;
            if snaps.contains(&f) {
                record_topview(rec, &format!("levels_topview_{f:04}.png"), sim.octree())?;
            }
            if obj_every > 0 && (f as u32).is_multiple_of(obj_every) {
                if let Some(m) = sim.surface() {
                    let fr = MeshFrame {
                        sequence: "frames",
                        index: f,
                        time: sim.time(),
                        positions: &m.positions,
                        faces: &m.faces,
                        attributes: &[],
                    };
                    rec.frame(&fr)?;
                }
            }
            Ok(())
        })?
    };
    rendered.finish(rec)?;
    frames_table(rec, "frames", &log)?;
    cost_plots(rec, "cost_per_frame", &[("adaptive", &log)])?;
    // Uniform baseline (spec §12 G11): 8 particles per finest cube over the liquid volume.
    let uniform = log.initial_liquid_volume / (0.5 * log.h_min).powi(3);
    let s_factor = 1024.0 / scene.resolution.finest as f64;
    let ratio = uniform / log.initial_particles.max(1) as f64;
    let ballistic: f64 =
        log.frames.iter().map(|f| f.2 as f64 / f.1.max(1) as f64).sum::<f64>() / log.frames.len().max(1) as f64;
    let mut sum = Report::default();
    sum.count("finest", scene.resolution.finest as u64)
        .num("scale_factor_s", s_factor)
        .count("initial_particles", log.initial_particles as u64)
        .count("peak_particles", log.peak_particles as u64)
        .count("final_particles", log.final_particles as u64)
        .num("uniform_particles_estimate", uniform)
        .num("particle_ratio_uniform_over_adaptive", ratio)
        .num("paper_ratio_235_scaled", 235.0 / s_factor)
        .num("pass_threshold_ratio", 0.3 * 235.0 / s_factor)
        .num("ballistic_fraction_mean", ballistic)
        .count("steps", log.steps)
        .num("particle_steps", log.particle_steps)
        .timing("wall_s", log.wall_s)
        .timing("s_per_frame", log.wall_s / log.frames.len().max(1) as f64)
        .timing("s_per_million_particle_steps", log.wall_s / (log.particle_steps / 1e6).max(1e-12))
        .num("paper_min_per_frame", 4.6);
    Ok(sum)
}

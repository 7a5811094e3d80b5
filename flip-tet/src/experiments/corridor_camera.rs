//! S6 (spec §6): liquid released at one end of a U-shaped corridor under a moving camera; the same
//! scene with visibility sizing on and off, particle-steps and wall time compared, and the
//! visible liquid's surface compared between the two runs (issue 26): at every frame, the
//! surface height of the columns on a grid of finest-cube spacing whose surface point lies inside
//! the camera's (unexpanded) frustum in both runs.
//!
//! ```no_run
//! use flip_tet::experiments::corridor_camera;
//! use geom_core::experiment::Size;
//! let r = corridor_camera::run(&flip_tet::presets::corridor_camera(), Size::Quick, &mut geom_core::record::NullRecorder::default())?;
//! println!("particle-steps on / off {}", r.get_f64("particle_steps_ratio_on_over_off"));
//! # Ok::<(), flip_tet::error::SimError>(())
//! ```

use geom_core::experiment::{Report, Size, Target};
use geom_core::record::Recorder;

use super::open_splash::{cost_plots, frames_table, record_topview, Params};
use super::{simulate_frames, Snapshots};
use crate::error::{Result, SimError};
use crate::metrics::surface_height;
use crate::sim::FlipTetSim;

/// Surface heights `(x, z, y)` (m) of the grid columns (spacing `h_min`, at cube centres) that
/// hold liquid.
fn column_heights(sim: &FlipTetSim) -> Vec<(f64, f64, f64)> {
    let (lo, hi, h) = (sim.scene().min(), sim.scene().max(), sim.spec().h_min());
    let (nx, nz) = (((hi.x - lo.x) / h).round() as usize, ((hi.z - lo.z) / h).round() as usize);
    let mut out = Vec::new();
    for i in 0..nx {
        for k in 0..nz {
            let (x, z) = (lo.x + (i as f64 + 0.5) * h, lo.z + (k as f64 + 0.5) * h);
            if let Some(y) = surface_height(sim, x, z) {
                out.push((x, z, y));
            }
        }
    }
    out
}

/// Runs S6.
pub fn run(p: &Params, size: Size, rec: &mut dyn Recorder) -> Result<Report> {
    let scene = p.scene_at(size);
    let vis = scene
        .sizing
        .visibility
        .clone()
        .ok_or_else(|| SimError::InvalidScene("corridor-camera: the scene must set sizing.visibility".into()))?;
    // On: count, at every frame, the particles outside the (unexpanded) frustum and how many of
    // them are at least r_max / 2.
    let (mut outside, mut outside_coarse) = (0usize, 0usize);
    let mut heights_on: Vec<Vec<(f64, f64, f64)>> = Vec::new();
    let mut rendered = Snapshots::new(&scene, "")?;
    let on = {
        let rec = &mut *rec;
        simulate_frames(&scene, |sim, f| {
            rendered.frame(sim, f as u64, rec)?;
            let fr = vis.frustum(sim.time());
            let parts = sim.particles();
            let r_max = sim.spec().h_root / crate::sizing::C_H;
            for i in 0..parts.len() {
                if !fr.contains(&parts.x[i], 0.0) {
                    outside += 1;
                    if parts.r[i] >= 0.5 * r_max * (1.0 - 1e-12) {
                        outside_coarse += 1;
                    }
                }
            }
            if f.is_multiple_of(10) {
                record_topview(rec, &format!("levels_topview_on_{f:04}.png"), sim.octree())?;
            }
            heights_on.push(column_heights(sim));
            Ok(())
        })?
    };
    rendered.finish(rec)?;
    let mut off_scene = scene.clone();
    off_scene.sizing.visibility = None;
    // The visible surface of both runs: columns whose surface point is inside the frustum in both.
    let mut devs: Vec<f64> = Vec::new();
    let off = simulate_frames(&off_scene, |sim, f| {
        let fr = vis.frustum(sim.time());
        let on = &heights_on[f];
        for (x, z, y) in column_heights(sim) {
            let Some(&(_, _, y_on)) = on.iter().find(|c| c.0 == x && c.1 == z) else { continue };
            let inside = |y: f64| fr.contains(&geom_core::math::Pt3::new(x, y, z), 0.0);
            if inside(y) && inside(y_on) {
                devs.push((y_on - y).abs());
            }
        }
        Ok(())
    })?;
    frames_table(rec, "frames_visibility_on", &on)?;
    frames_table(rec, "frames_visibility_off", &off)?;
    cost_plots(rec, "cost_per_frame", &[("visibility on", &on), ("visibility off", &off)])?;
    let mut sum = Report::default();
    sum.count("finest", scene.resolution.finest as u64)
        .num("particle_steps_on", on.particle_steps)
        .num("particle_steps_off", off.particle_steps)
        .num("particle_steps_ratio_on_over_off", on.particle_steps / off.particle_steps.max(1.0))
        .timing("wall_s_on", on.wall_s)
        .timing("wall_s_off", off.wall_s)
        .timing("time_ratio_on_over_off", on.wall_s / off.wall_s.max(1e-12))
        .count("peak_particles_on", on.peak_particles as u64)
        .count("peak_particles_off", off.peak_particles as u64)
        .num(
            "outside_frustum_coarse_fraction",
            if outside > 0 { outside_coarse as f64 / outside as f64 } else { f64::NAN },
        )
        .count("outside_frustum_particle_frames", outside as u64)
        .num("r_max_m", on.r_max)
        .count("visible_surface_columns_compared", devs.len() as u64)
        .num("visible_surface_height_max_dev_m", geom_core::stats::max(&devs))
        .num("visible_surface_height_rms_dev_m", geom_core::stats::rms(&devs));
    sum.check(
        "particle_steps_ratio_on_over_off",
        Target::AtMost(0.7),
        "spec §6 S6: visibility sizing saves ≥ 30 % of particle-steps",
    );
    Ok(sum)
}

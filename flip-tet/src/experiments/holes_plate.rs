//! S7 (spec §6): a liquid block falls on a plate with a 3×3 grid of round holes, the mesh graded by
//! the solid-curvature sizing. Besides the drop-pool figures the run checks the sizing at the hole
//! rims (spec: "≥ 90 % of tets within `2 h_min` of a hole rim are at the finest level") and, when
//! asked (`uniform_comparison`, the spec's full-mode check), compares the liquid volume that passed
//! through the plate with a run on the uniform finest mesh.
//!
//! ```no_run
//! use flip_tet::experiments::holes_plate;
//! use geom_core::experiment::Size;
//! let r = holes_plate::run(&flip_tet::presets::holes_plate(), Size::Quick, &mut geom_core::record::NullRecorder::default())?;
//! println!("rim finest fraction {}", r.get_f64("rim_finest_fraction_final"));
//! # Ok::<(), flip_tet::error::SimError>(())
//! ```

use geom_core::experiment::{BySize, Report, Size, Target};
use geom_core::math::Pt3;
use geom_core::record::Recorder;
use serde::{Deserialize, Serialize};

use super::drop_pool::particle_figures;
use super::{one, plot, simulate, sized_scene, FrameOutput, RunOut};
use crate::error::{Result, SimError};
use crate::metrics::volume_below;
use crate::scene::{Scene, Shape};
use crate::sim::FlipTetSim;

/// Parameters (the scene file's `params`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Params {
    /// The block and the plate (first obstacle: `Subtract(Box, [vertical Cylinder])`).
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
    /// Also run the uniform finest mesh and compare the passed volume, per size.
    #[serde(default)]
    pub uniform_comparison: Option<BySize<bool>>,
}

/// A hole rim: a horizontal circle (centre, radius), m.
#[derive(Clone, Copy, Debug)]
pub struct Rim {
    /// Centre (m).
    pub centre: Pt3,
    /// Radius (m).
    pub radius: f64,
}

/// The rims and the plate's bottom height of the scene's first obstacle, which must be a `Box`
/// plate minus vertical `Cylinder` holes.
pub fn plate_rims(scene: &Scene) -> Result<(Vec<Rim>, f64)> {
    let bad = |what: &str| {
        SimError::InvalidScene(format!("holes-plate: {what}; expected Subtract(base: Box, holes: [vertical Cylinder])"))
    };
    let (min, max, holes) = match scene.obstacles.first() {
        Some(Shape::Subtract { base, holes }) => match base.as_ref() {
            Shape::Box { min, max } => (min, max, holes),
            _ => return Err(bad("the plate is not a Box")),
        },
        _ => return Err(bad("the first obstacle is not a Subtract")),
    };
    let mut rims = Vec::new();
    for h in holes {
        match h {
            Shape::Cylinder { a, b, radius } if (a[0] - b[0]).abs() < 1e-12 && (a[2] - b[2]).abs() < 1e-12 => {
                for y in [min[1], max[1]] {
                    rims.push(Rim { centre: Pt3::new(a[0], y, a[2]), radius: *radius });
                }
            }
            _ => return Err(bad("a hole is not a vertical Cylinder")),
        }
    }
    Ok((rims, min[1]))
}

/// Distance (m) from `x` to the circle `rim`.
pub fn rim_distance(x: &Pt3, rim: &Rim) -> f64 {
    let rho = (x.x - rim.centre.x).hypot(x.z - rim.centre.z);
    (rho - rim.radius).hypot(x.y - rim.centre.y)
}

/// Tets whose centroid lies within `2 h_min` of a rim, and the fraction of them at the finest
/// level (1 when there are none).
pub fn rim_finest_fraction(sim: &FlipTetSim, rims: &[Rim]) -> (usize, f64) {
    let (mesh, spec) = (sim.mesh(), sim.spec());
    let (band, finest) = (2.0 * spec.h_min(), spec.levels - 1);
    let (mut n, mut fine) = (0usize, 0usize);
    for (t, c) in mesh.centroid.iter().enumerate() {
        if rims.iter().any(|r| rim_distance(c, r) <= band) {
            n += 1;
            fine += usize::from(mesh.tet_level[t] == finest);
        }
    }
    (n, if n > 0 { fine as f64 / n as f64 } else { 1.0 })
}

/// Runs S7.
pub fn run(p: &Params, size: Size, rec: &mut dyn Recorder) -> Result<Report> {
    let scene = sized_scene(&p.scene, &p.finest, None, &p.duration, size);
    let (rims, plate_bottom) = plate_rims(&scene)?;
    let mut worst = f64::INFINITY;
    let frames = FrameOutput { obj: p.obj_every, ply: p.ply_every, hires: p.hires_every };
    let run = simulate(&scene, rec, RunOut::full("", frames), &mut |sim, st| {
        if st.remeshed || st.step == 0 {
            worst = worst.min(rim_finest_fraction(sim, &rims).1);
        }
        Ok(())
    })?;
    let mut s = Report::default();
    particle_figures(&mut s, &scene, &run.stats, run.wall);
    let pts: Vec<(f64, f64)> = run.stats.iter().map(|x| (x.t, x.n_particles as f64)).collect();
    plot(rec, "particles_vs_time", "adaptive", ("t (s)", "particles"), (false, false), pts)?;
    let (n, frac) = rim_finest_fraction(&run.sim, &rims);
    s.count("rim_tets", n as u64);
    s.num("rim_finest_fraction_final", frac);
    s.num("rim_finest_fraction_min", worst.min(frac));
    s.check("rim_finest_fraction_final", Target::AtLeast(0.9), "spec §6 S7: ≥ 90 % finest tets at the rims");
    let passed = volume_below(run.sim.particles(), plate_bottom);
    s.num("passed_volume_m3", passed);
    if p.uniform_comparison.as_ref().is_some_and(|u| u.get(size)) {
        let mut u = scene.clone();
        u.resolution.coarsest = u.resolution.finest;
        let out = RunOut { dir: "uniform/", frames: FrameOutput::NONE, snapshots: true, metrics: true, probes: None };
        let ur = simulate(&u, rec, out, &mut |_, _| Ok(()))?;
        let up = volume_below(ur.sim.particles(), plate_bottom);
        s.num("passed_volume_uniform_m3", up);
        s.num("passed_volume_rel_diff", if up > 0.0 { (passed - up).abs() / up } else { f64::NAN });
        s.timing("uniform_wall_s", ur.wall);
        s.check("passed_volume_rel_diff", Target::AtMost(0.10), "spec §6 S7: passed volume within 10 % of uniform");
    }
    Ok(s)
}

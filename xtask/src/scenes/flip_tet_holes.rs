//! `flip-tet/holes-plate` (spec §6 S7): a liquid block falls on a plate with a 3×3 grid of round
//! holes, the mesh graded by the solid-curvature sizing. Besides the drop-pool figures (particle
//! counts, cost against particles) the run checks the sizing where it matters — at the hole rims
//! — and, when asked (`uniform_comparison`, the spec's full-mode check), compares the liquid
//! volume that passed through the plate with a run on the uniform finest mesh.
//!
//! Rim check (spec: "≥ 90 % of tets within `2 h_min` of a hole rim are at the finest level"):
//! the rims are the circles where each vertical hole cylinder meets the plate's top and bottom
//! faces; a tet is "at the rim" when its centroid lies within `2 h_min` of one of them. Measured
//! on the mesh after every remesh; the summary gives the final and the smallest fraction.

use flip_tet::scene::{Scene, Shape};
use flip_tet::sim::FlipTetSim;
use geom_core::math::Pt3;

use super::flip_tet::{drop_pool_summary, load_file, simulate, FrameOutput, FtParams};
use crate::error::{Error, Result};
use crate::out::Summary;
use crate::registry::RunCtx;

/// A hole rim: a horizontal circle (centre, radius), m.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Rim {
    pub centre: Pt3,
    pub radius: f64,
}

/// The rims and the plate's bottom height of the scene's first obstacle, which must be a `Box`
/// plate minus vertical `Cylinder` holes (the S7 geometry); anything else is an error naming
/// what was found.
pub(crate) fn plate_rims(scene: &Scene) -> Result<(Vec<Rim>, f64)> {
    let bad = |what: &str| {
        Error::Run(format!("holes-plate: {what}; expected Subtract(base: Box, holes: [vertical Cylinder])"))
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
fn rim_distance(x: &Pt3, rim: &Rim) -> f64 {
    let rho = (x.x - rim.centre.x).hypot(x.z - rim.centre.z);
    (rho - rim.radius).hypot(x.y - rim.centre.y)
}

/// Tets whose centroid lies within `2 h_min` of a rim, and the fraction of them at the finest
/// level (1 when there are none).
pub(crate) fn rim_finest_fraction(sim: &FlipTetSim, rims: &[Rim]) -> (usize, f64) {
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

/// Particle volume (m³, `Σ 8 r³`) below height `y`.
fn volume_below(sim: &FlipTetSim, y: f64) -> f64 {
    let p = sim.particles();
    (0..p.len()).filter(|&i| p.x[i].y < y).map(|i| p.volume(i)).sum()
}

/// The S7 runner: drop-pool keys plus `rim_tets`, `rim_finest_fraction_final`,
/// `rim_finest_fraction_min` (over every remeshed mesh), `passed_volume_m3` (particle volume
/// below the plate at the end) and, with `uniform_comparison` on for the mode,
/// `passed_volume_uniform_m3`, `passed_volume_rel_diff` (spec: ≤ 0.10) and the uniform run's
/// `uniform_wall_s`.
pub(crate) fn run_holes_plate(ctx: &RunCtx) -> Result<Summary> {
    let (p, scene) = load_file(&ctx.scene_file, ctx.mode)?;
    let (rims, plate_bottom) = plate_rims(&scene)?;
    let mut worst = f64::INFINITY;
    let (stats, wall, sim) = simulate(&scene, &ctx.out_dir, FrameOutput::of(&p), &mut |sim, st| {
        if st.remeshed || st.step == 0 {
            worst = worst.min(rim_finest_fraction(sim, &rims).1);
        }
    })?;
    let mut s = drop_pool_summary(&scene, &stats, wall, &ctx.out_dir)?;
    let (n, frac) = rim_finest_fraction(&sim, &rims);
    s.set_count("rim_tets", n as u64);
    s.set("rim_finest_fraction_final", frac);
    s.set("rim_finest_fraction_min", worst.min(frac));
    let passed = volume_below(&sim, plate_bottom);
    s.set("passed_volume_m3", passed);
    if uniform_comparison(&p, ctx) {
        let mut u = scene.clone();
        u.resolution.coarsest = u.resolution.finest;
        let dir = ctx.out_dir.join("uniform");
        let (_, uwall, usim) = simulate(&u, &dir, FrameOutput::NONE, &mut |_, _| {})?;
        let up = volume_below(&usim, plate_bottom);
        s.set("passed_volume_uniform_m3", up);
        s.set("passed_volume_rel_diff", if up > 0.0 { (passed - up).abs() / up } else { f64::NAN });
        s.set("uniform_wall_s", uwall);
    }
    Ok(s)
}

/// Whether the uniform-finest comparison runs in this mode (`uniform_comparison: (quick,
/// default, full)` in the scene file; the spec asks for it in full mode only).
fn uniform_comparison(p: &FtParams, ctx: &RunCtx) -> bool {
    p.uniform_comparison.is_some_and(|(q, d, f)| ctx.mode.pick(q, d, f))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The rim distance is zero on the circle, the radial offset in the plane, the vertical
    /// offset above the circle; the S7 scene's plate gives 9 holes × 2 faces.
    #[test]
    fn rims_and_distances() {
        let r = Rim { centre: Pt3::new(0.3, 0.6, 0.3), radius: 0.07 };
        assert!(rim_distance(&Pt3::new(0.37, 0.6, 0.3), &r) < 1e-15);
        assert!((rim_distance(&Pt3::new(0.3, 0.6, 0.4), &r) - 0.03).abs() < 1e-15);
        assert!((rim_distance(&Pt3::new(0.3, 0.65, 0.37), &r) - 0.05).abs() < 1e-15);
        let path = crate::scene::scenes_dir().join("flip-tet/holes-plate.ron");
        let (_, scene) = load_file(&path, crate::scene::Mode::Quick).expect("scene");
        let (rims, bottom) = plate_rims(&scene).expect("S7 plate");
        assert_eq!(rims.len(), 18);
        assert!((bottom - 0.6).abs() < 1e-15);
    }
}

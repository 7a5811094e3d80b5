//! flip-tet's surface, sizing and baseline scenes (spec §6, ft-aux's part):
//!
//! - `flip-tet/surface-mixed-radii` ([`run_surface`], S8, static): particles of radii `r`, `2r`,
//!   `4r` in strips, all tangent to `y = H` from below, plus a blob of mixed sizes; the level set
//!   by triplet hulls, Zhu–Bridson (fixed-radius averaging) and sphere union on a fine uniform BCC
//!   mesh; flatness over the patch, blob area, cost per million node evaluations; three OBJ files,
//!   `flatness.csv`, a height-profile comparison plot and shaded previews.
//! - `flip-tet/fvm-vs-nodal` ([`run_fvm`], S9): one hydrostatic projection on a depth-graded BCC
//!   mesh (graded by this crate's sizing: surface band + depth floor), ours (node pressures,
//!   ft-core's `pressure` module) against the circumcentric finite-volume baseline.
//! - `flip-tet/open-splash` ([`run_splash`], S5): a sphere dropped into a wide shallow pool with
//!   liquid-curvature sizing (the paper's Figure 1 analogue); particle counts vs a uniform
//!   sampling, cost per frame and per million particle-steps, top views of the leaf levels.
//! - `flip-tet/corridor-camera` ([`run_corridor`], S6): liquid released in a U-shaped corridor with
//!   a circling camera; the same scene with visibility sizing on and off.

use std::path::Path;
use std::time::Instant;

use flip_tet::bcc::{tetrahedralize, TetMesh};
use flip_tet::octree::{Octree, OctreeSpec};
use flip_tet::particles::{ParticleFlags, Particles};
use flip_tet::surface::{
    level_set_on_nodes, marching_tets, smooth_surface, LevelSetSampler, SurfaceMethod, SurfaceParams, Walls,
};
use geom_core::io::{obj, MeshOut};
use geom_core::math::{Pt3, Vec3};
use geom_core::mesh::TriMesh;
use geom_core::rng::Rng;
use serde::Deserialize;

use super::flip_tet_snapshots::Snapshots;
use crate::error::{Error, Result};
use crate::out::{Cell, CsvWriter, Summary};
use crate::plot::{LinePlot, Series};
use crate::registry::{RunCtx, Runner};
use crate::scene;

/// Adds ft-aux's flip-tet runners.
pub fn register(v: &mut Vec<Runner>) {
    v.push(Runner { method: "flip-tet/surface-mixed-radii", run: run_surface });
    v.push(Runner { method: "flip-tet/fvm-vs-nodal", run: run_fvm });
    v.push(Runner { method: "flip-tet/open-splash", run: run_splash });
    v.push(Runner { method: "flip-tet/corridor-camera", run: run_corridor });
}

fn ft<T, E: std::fmt::Display>(r: std::result::Result<T, E>) -> Result<T> {
    r.map_err(|e| Error::Run(format!("flip-tet: {e}")))
}

/// Parameters of `flip-tet/surface-mixed-radii`.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct SurfaceScene {
    /// Smallest particle radius `r` (m); the strips use `r`, `2r`, `4r`.
    r: f64,
    /// Height `H` of the plane the patch particles touch from below (m).
    plane_y: f64,
    /// Domain box minimum / maximum corner (m).
    domain_min: (f64, f64, f64),
    domain_max: (f64, f64, f64),
    /// Root cubes along the longest axis.
    coarsest: u32,
    /// Uniform mesh resolution (cubes along the longest axis) per mode (quick, default, full).
    finest: (u32, u32, u32),
    /// Patch extent in x and z: `(x0, x1, z0, z1)` (m); the strips split `[x0, x1]` in three.
    patch: (f64, f64, f64, f64),
    /// Margin from the patch edges excluded from the flatness metric, in units of `4r`.
    edge_margin: f64,
    /// Blob of mixed radii: centre (m), radius (m), particle count.
    blob_center: (f64, f64, f64),
    blob_radius: f64,
    blob_particles: usize,
    /// RNG seed for the blob.
    seed: u64,
    /// Surface parameters (method is overridden per comparison run).
    #[serde(default)]
    surface: SurfaceParams,
}

fn pt(v: (f64, f64, f64)) -> Pt3 {
    Pt3::new(v.0, v.1, v.2)
}

/// The particle set: strips of touching particles tangent to `y = H` (two layers), and the blob.
fn mixed_particles(s: &SurfaceScene) -> Particles {
    let mut p = Particles::default();
    let mut push = |x: Pt3, r: f64, phi: f64| p.push(x, Vec3::zeros(), r, phi);
    let (x0, x1, z0, z1) = s.patch;
    let w = (x1 - x0) / 3.0;
    for (k, mult) in [1.0, 2.0, 4.0].into_iter().enumerate() {
        let r = s.r * mult;
        let (sx0, sx1) = (x0 + k as f64 * w, x0 + (k + 1) as f64 * w);
        // +1e-9: a strip width that is a multiple of 2r may divide to k − ε in floating point.
        let nx = ((sx1 - sx0) / (2.0 * r) + 1e-9).floor() as usize;
        let nz = ((z1 - z0) / (2.0 * r) + 1e-9).floor() as usize;
        for i in 0..nx {
            for j in 0..nz {
                let (x, z) = (sx0 + r * (2 * i + 1) as f64, z0 + r * (2 * j + 1) as f64);
                // Top layer tangent to the plane (stored φ = −r), second layer touching it below.
                push(Pt3::new(x, s.plane_y - r, z), r, -r);
                push(Pt3::new(x, s.plane_y - 3.0 * r, z), r, -3.0 * r);
            }
        }
    }
    let mut rng = Rng::new(s.seed);
    let c = pt(s.blob_center);
    let mut placed = 0;
    while placed < s.blob_particles {
        let d = Vec3::new(rng.range(-1.0, 1.0), rng.range(-1.0, 1.0), rng.range(-1.0, 1.0));
        if d.norm() > 1.0 {
            continue;
        }
        let r = s.r * [1.0, 2.0, 4.0][rng.below(3)];
        let x = c + d * (s.blob_radius - r);
        push(x, r, (x - c).norm() - s.blob_radius);
        placed += 1;
    }
    p
}

/// Flatness of the top surface over the patch interior: (max |y − H|, RMS, count) over vertices
/// within `h` of the plane (the top side of the slab).
fn flatness(m: &TriMesh, s: &SurfaceScene, h: f64) -> (f64, f64, usize) {
    let (x0, x1, z0, z1) = s.patch;
    let mg = s.edge_margin * 4.0 * s.r;
    let mut max: f64 = 0.0;
    let mut sum2 = 0.0;
    let mut n = 0;
    for p in &m.positions {
        if p.x > x0 + mg && p.x < x1 - mg && p.z > z0 + mg && p.z < z1 - mg && (p.y - s.plane_y).abs() < h {
            let d = (p.y - s.plane_y).abs();
            max = max.max(d);
            sum2 += d * d;
            n += 1;
        }
    }
    (max, if n > 0 { (sum2 / n as f64).sqrt() } else { f64::NAN }, n)
}

/// Height profile (x, (y − H)/r) of the top surface near the mid-z line, sorted by x.
fn profile(m: &TriMesh, s: &SurfaceScene, h: f64) -> Vec<(f64, f64)> {
    let zm = 0.5 * (s.patch.2 + s.patch.3);
    let mut v: Vec<(f64, f64)> = m
        .positions
        .iter()
        .filter(|p| (p.z - zm).abs() < 0.5 * h && p.x < s.patch.1 && (p.y - s.plane_y).abs() < 2.0 * s.r)
        .map(|p| (p.x, (p.y - s.plane_y) / s.r))
        .collect();
    v.sort_by(|a, b| a.0.total_cmp(&b.0));
    v
}

/// Area of the faces whose centroid lies within `1.5 R` of the blob centre.
fn blob_area(m: &TriMesh, s: &SurfaceScene) -> f64 {
    let c = pt(s.blob_center);
    m.faces
        .iter()
        .filter_map(|f| {
            let [a, b, d] = f.map(|i| m.positions[i as usize]);
            let g = Pt3::from((a.coords + b.coords + d.coords) / 3.0);
            ((g - c).norm() < 1.5 * s.blob_radius).then(|| 0.5 * (b - a).cross(&(d - a)).norm())
        })
        .sum()
}

fn write_mesh(dir: &Path, name: &str, m: &TriMesh) -> Result<()> {
    obj::write(dir.join(name), &MeshOut::from_tri_mesh(m))?;
    Ok(())
}

fn preview(dir: &Path, name: &str, m: &TriMesh, s: &SurfaceScene) -> Result<()> {
    use geom_core::raster::{lambert_preview, Camera, RasterOptions};
    if m.n_faces() == 0 {
        return Ok(());
    }
    let (lo, hi) = (pt(s.domain_min), pt(s.domain_max));
    let target = Pt3::new(0.5 * (lo.x + hi.x), s.plane_y, 0.5 * (lo.z + hi.z));
    let eye = target + Vec3::new(0.35, 0.9, 1.1) * (hi - lo).norm() * 0.6;
    let cam = Camera::look_at(&eye, &target, &Vec3::y(), 35.0, 800, 500)?;
    let img = lambert_preview(
        &cam,
        &m.positions,
        &m.faces,
        &Vec3::new(0.3, 1.0, 0.5),
        &RasterOptions { supersample: 2, ..Default::default() },
    );
    geom_core::image::write_png_gray8(dir.join(name), &img)?;
    Ok(())
}

/// S8: flat surfaces from mixed radii (the paper's Figure 4 analogue).
fn run_surface(ctx: &RunCtx) -> Result<Summary> {
    let sc: SurfaceScene = scene::load::<SurfaceScene>(&ctx.scene_file)?.params;
    ft(sc.surface.validate())?;
    let n = ctx.mode.pick(sc.finest.0, sc.finest.1, sc.finest.2);
    let spec = ft(OctreeSpec::new(pt(sc.domain_min), pt(sc.domain_max), sc.coarsest, n))?;
    let oct = Octree::uniform(spec, spec.levels - 1);
    let mesh: TetMesh = ft(tetrahedralize(&oct))?;
    let h = spec.h_min();
    let parts = mixed_particles(&sc);
    let mut csv = CsvWriter::create(
        &ctx.out_dir.join("flatness.csv"),
        &[
            "method",
            "max_dev_m",
            "max_dev_over_r",
            "rms_dev_over_r",
            "patch_vertices",
            "blob_area_m2",
            "nodes",
            "levelset_s",
            "s_per_million_nodes",
        ],
    )?;
    let mut sum = Summary::new();
    sum.set_count("nodes", mesh.nodes.len() as u64)
        .set_count("tets", mesh.tets.len() as u64)
        .set_count("particles", parts.len() as u64)
        .set("h_over_r", h / sc.r)
        .set_str("mode", ctx.mode.name());
    let mut plot = LinePlot::new("Top surface along the patch mid-line (strips r | 2r | 4r)", "x (m)", "(y − H) / r");
    for (method, tag) in [
        (SurfaceMethod::Hulls, "hulls"),
        (SurfaceMethod::ZhuBridson, "zhu_bridson"),
        (SurfaceMethod::SphereUnion, "sphere_union"),
    ] {
        let params = SurfaceParams { method, ..sc.surface.clone() };
        let t0 = Instant::now();
        let phi = level_set_on_nodes(&mesh, &parts, &params, &Walls::none());
        let dt = t0.elapsed().as_secs_f64();
        let raw = ft(marching_tets(&mesh, &phi))?;
        let (max, rms, cnt) = flatness(&raw, &sc, h);
        let smooth = smooth_surface(&raw, params.smoothing_iterations);
        let area = blob_area(&smooth, &sc);
        write_mesh(&ctx.out_dir, &format!("surface_{tag}.obj"), &smooth)?;
        preview(&ctx.out_dir, &format!("surface_{tag}.png"), &smooth, &sc)?;
        let per_m = dt / (mesh.nodes.len() as f64 / 1e6);
        csv.row(&[
            Cell::Text(tag.into()),
            Cell::Num(max),
            Cell::Num(max / sc.r),
            Cell::Num(rms / sc.r),
            Cell::Int(cnt as i64),
            Cell::Num(area),
            Cell::Int(mesh.nodes.len() as i64),
            Cell::Num(dt),
            Cell::Num(per_m),
        ])?;
        plot = plot.with(Series::new(tag, profile(&raw, &sc, h)));
        if method == SurfaceMethod::Hulls {
            if cnt == 0 {
                return Err(Error::Run("surface-mixed-radii: no surface vertex over the patch".into()));
            }
            sum.set("flat_patch_max_dev_over_r", max / sc.r)
                .set("flat_patch_rms_dev_over_r", rms / sc.r)
                .set_count("flat_patch_vertices", cnt as u64)
                .set("blob_area_m2", area)
                .set("hulls_s_per_million_nodes", per_m);
        } else {
            sum.set(&format!("{tag}_flat_patch_max_dev_over_r"), max / sc.r)
                .set(&format!("{tag}_flat_patch_rms_dev_over_r"), rms / sc.r)
                .set(&format!("{tag}_blob_area_m2"), area)
                .set(&format!("{tag}_s_per_million_nodes"), per_m);
        }
    }
    plot.write_png(&ctx.out_dir.join("flatness_profile.png"))?;
    levelset_cost(&mesh, &parts, &sc.surface, &mut sum);
    Ok(sum)
}

/// The level set's fast node path against the exhaustive reference evaluation, both timed in the
/// same run (so the ratio is meaningful on a loaded machine) on every k-th node: the node values
/// before interior redistancing, `value_on_node` (pruned, what the simulator uses) vs
/// `value_exhaustive` (every source in the search ball, every pair and triplet of the `K` nearest).
/// Differences are allowed only at air nodes whose both values exceed the local mesh size.
fn levelset_cost(mesh: &TetMesh, parts: &Particles, surface: &SurfaceParams, sum: &mut Summary) {
    use rayon::prelude::*;
    let params = SurfaceParams { method: SurfaceMethod::Hulls, ..surface.clone() };
    let s = LevelSetSampler::new(parts, &params, &Walls::none());
    // Every k-th node (at most ~50 000), so the exhaustive reference stays a small part of the run.
    let k = mesh.nodes.len().div_ceil(50_000).max(1);
    let sub: Vec<(Pt3, f64)> = mesh.nodes.iter().zip(&mesh.node_h).step_by(k).map(|(q, &h)| (*q, h)).collect();
    let t0 = Instant::now();
    let fast: Vec<f64> = sub.par_iter().map(|(q, h)| s.value_on_node(q, *h)).collect();
    let t_fast = t0.elapsed().as_secs_f64();
    let t0 = Instant::now();
    let slow: Vec<f64> = sub.par_iter().map(|(q, h)| s.value_exhaustive(q, *h)).collect();
    let t_slow = t0.elapsed().as_secs_f64();
    let differ = fast.iter().zip(&slow).filter(|(a, b)| a.to_bits() != b.to_bits()).count();
    let max_diff = fast.iter().zip(&slow).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
    sum.set("levelset_fast_s", t_fast)
        .set("levelset_exhaustive_s", t_slow)
        .set("levelset_speedup_exhaustive_over_fast", t_slow / t_fast.max(1e-12))
        .set_count("levelset_nodes_compared", sub.len() as u64)
        .set_count("levelset_nodes_differing", differ as u64)
        .set("levelset_max_abs_diff_over_r", max_diff / parts.r_max().max(1e-300));
}

/// Parameters of `flip-tet/fvm-vs-nodal`.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct FvmScene {
    /// Domain box (m).
    domain_min: (f64, f64, f64),
    domain_max: (f64, f64, f64),
    /// Root cubes along the longest axis.
    coarsest: u32,
    /// Finest cubes along the longest axis per mode (quick, default, full); 4 levels in the spec.
    finest: (u32, u32, u32),
    /// Pool depth `H` (m): `φ = y − H`.
    depth: f64,
    /// Time step (s) of `u* = Δt g`.
    dt: f64,
    /// Sizing that grades the mesh (spec S1a: surface band + depth floor).
    sizing: flip_tet::sizing::SizingParams,
    /// CG tolerance for both discretisations (spec: 1e-8).
    tol: f64,
    /// Circumcentre distance floor `ε_fvm` (spec: 0.1).
    eps_fvm: f64,
}

/// Depth-graded octree: demands from the sizing function sampled at the finest cube centres.
fn graded_mesh(sc: &FvmScene, n: u32) -> Result<(OctreeSpec, TetMesh)> {
    use flip_tet::octree::{build_octree, SizeDemand};
    use flip_tet::sizing::{level_for_radius, Sizing, SizingContext, C_H};
    let spec = ft(OctreeSpec::new(pt(sc.domain_min), pt(sc.domain_max), sc.coarsest, n))?;
    let sizing = ft(Sizing::from_params(&sc.sizing))?;
    let ctx = SizingContext::new(spec.h_min(), spec.h_root);
    let h = spec.h_min();
    let (lo, hi) = (pt(sc.domain_min), pt(sc.domain_max));
    let cnt = |a: f64, b: f64| ((b - a) / h).round() as usize;
    let mut demands = Vec::new();
    for i in 0..cnt(lo.x, hi.x) {
        for j in 0..cnt(lo.y, hi.y) {
            for k in 0..cnt(lo.z, hi.z) {
                let x = lo + Vec3::new(i as f64 + 0.5, j as f64 + 0.5, k as f64 + 0.5) * h;
                let phi = x.y - sc.depth;
                if phi > 0.5 * h {
                    continue; // air: no demand
                }
                let s = sizing.radius_at_phi(&x, Some(phi), &ctx);
                if s.is_finite() {
                    let level = level_for_radius(s, spec.h_root, spec.levels - 1);
                    demands.push(SizeDemand { center: x, pad: 0.5 * C_H * s, level });
                }
            }
        }
    }
    let oct = build_octree(spec, &demands);
    Ok((spec, ft(tetrahedralize(&oct))?))
}

/// S9: one projection of `u* = Δt g` under a planar surface, nodal (ours) vs circumcentric FVM.
fn run_fvm(ctx: &RunCtx) -> Result<Summary> {
    use flip_tet::error::SolverKind;
    use flip_tet::fvm_baseline::{fvm_project, FvmParams};
    use flip_tet::pressure::{apply_pressure, assemble_pressure, PressureParams, PressureSolver};
    let sc: FvmScene = scene::load::<FvmScene>(&ctx.scene_file)?.params;
    let n = ctx.mode.pick(sc.finest.0, sc.finest.1, sc.finest.2);
    let (spec, mesh) = graded_mesh(&sc, n)?;
    let g = Vec3::new(0.0, -9.81, 0.0);
    let u_star = vec![g * sc.dt; mesh.tets.len()];
    let phi: Vec<f64> = mesh.nodes.iter().map(|p| p.y - sc.depth).collect();
    let scale = 9.81 * sc.dt;
    // Ours: node pressures, second-order free surface, Jacobi-PCG to the same tolerance (the
    // comparison of iteration counts uses the same preconditioner), then the direct solve for the
    // residual-velocity check (spec S9 pass: ≤ 1e-8 Δt g with the direct solver).
    let pp = PressureParams { solver: SolverKind::PcgJacobi, tol: sc.tol, max_iters: 100_000, ..Default::default() };
    let t0 = Instant::now();
    let sys = assemble_pressure(&mesh, &phi, &u_star, spec.h_min(), &pp);
    let mut solver = PressureSolver::default();
    let (_, rep_cg) = ft(solver.solve(&sys, &pp, None))?;
    let ours_cg_s = t0.elapsed().as_secs_f64();
    let pd = PressureParams { solver: SolverKind::DirectCholesky, ..pp.clone() };
    let (q, _) = ft(solver.solve(&sys, &pd, None))?;
    let mut u = u_star.clone();
    let upd = apply_pressure(&mesh, &sys, &q, &mut u);
    let ours_max = u.iter().zip(&upd).filter(|(_, &m)| m).map(|(v, _)| v.norm()).fold(0.0, f64::max);
    // Baseline.
    let t1 = Instant::now();
    let fvm =
        ft(fvm_project(&mesh, &phi, &u_star, &FvmParams { eps_fvm: sc.eps_fvm, tol: sc.tol, max_iters: 100_000 }))?;
    let fvm_s = t1.elapsed().as_secs_f64();
    let levels = {
        let mut h = vec![0usize; spec.levels as usize];
        for &l in &mesh.tet_level {
            h[l as usize] += 1;
        }
        h
    };
    let mut csv = CsvWriter::create(
        &ctx.out_dir.join("fvm_vs_nodal.csv"),
        &["method", "unknowns", "cg_iterations", "rel_residual", "max_residual_velocity_over_dt_g", "wall_s"],
    )?;
    csv.row(&[
        Cell::Text("nodal".into()),
        Cell::Int(sys.rhs.len() as i64),
        Cell::Int(rep_cg.iters as i64),
        Cell::Num(rep_cg.rel_residual),
        Cell::Num(ours_max / scale),
        Cell::Num(ours_cg_s),
    ])?;
    csv.row(&[
        Cell::Text("fvm_circumcentric".into()),
        Cell::Int(fvm.n_unknowns as i64),
        Cell::Int(fvm.iterations as i64),
        Cell::Num(fvm.rel_residual),
        Cell::Num(fvm.max_face_velocity / scale),
        Cell::Num(fvm_s),
    ])?;
    let mut sum = Summary::new();
    sum.set_str("mode", ctx.mode.name())
        .set_count("nodes", mesh.nodes.len() as u64)
        .set_count("tets", mesh.tets.len() as u64)
        .set_count("levels_used", levels.iter().filter(|&&c| c > 0).count() as u64)
        .set_count("nodal_unknowns", sys.rhs.len() as u64)
        .set_count("fvm_unknowns", fvm.n_unknowns as u64)
        .set("unknowns_ratio_fvm_over_nodal", fvm.n_unknowns as f64 / sys.rhs.len().max(1) as f64)
        .set_count("fvm_interior_faces", fvm.n_interior_faces as u64)
        .set_count("fvm_coincident_circumcentre_faces", fvm.n_coincident as u64)
        .set_count("fvm_floored_faces", fvm.n_floored as u64)
        .set_count("nodal_cg_iterations", rep_cg.iters as u64)
        .set_count("fvm_cg_iterations", fvm.iterations as u64)
        .set("nodal_max_residual_velocity_over_dt_g", ours_max / scale)
        .set("fvm_max_residual_velocity_over_dt_g", fvm.max_face_velocity / scale)
        .set("fvm_max_divergence_per_s", fvm.max_divergence)
        .set("nodal_cg_s", ours_cg_s)
        .set("fvm_cg_s", fvm_s);
    Ok(sum)
}

/// A simulation scene with per-mode resolution and duration (quick, default, full).
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct SimScene {
    /// The flip-tet scene (its `resolution.finest` and `duration` are overridden per mode).
    scene: flip_tet::scene::Scene,
    /// Finest resolution per mode.
    finest: (u32, u32, u32),
    /// Duration per mode (s).
    duration: (f64, f64, f64),
    /// Write the simulation surface as OBJ every this many frames (0 = never).
    obj_every: u32,
}

/// Per-run record of [`simulate`].
struct RunLog {
    particle_steps: f64,
    steps: u64,
    wall_s: f64,
    frames: Vec<(f64, usize, usize, f64)>, // (t, particles, ballistic, wall seconds of the frame)
    initial_particles: usize,
    peak_particles: usize,
    final_particles: usize,
    h_min: f64,
    r_max: f64,
    initial_liquid_volume: f64,
}

fn load_sim(ctx: &RunCtx) -> Result<(flip_tet::scene::Scene, u32)> {
    let sc: SimScene = scene::load::<SimScene>(&ctx.scene_file)?.params;
    let mut s = sc.scene.clone();
    s.resolution.finest = ctx.mode.pick(sc.finest.0, sc.finest.1, sc.finest.2);
    s.duration = ctx.mode.pick(sc.duration.0, sc.duration.1, sc.duration.2);
    Ok((s, sc.obj_every))
}

/// Runs `scene` frame by frame; `on_frame(sim, frame)` sees the state after each frame.
fn simulate(
    scene: &flip_tet::scene::Scene,
    mut on_frame: impl FnMut(&flip_tet::sim::FlipTetSim, usize) -> Result<()>,
) -> Result<RunLog> {
    use flip_tet::sim::FlipTetSim;
    let t0 = Instant::now();
    let mut sim = ft(FlipTetSim::new(scene))?;
    let n0 = sim.particles().len();
    let vol0: f64 = (0..n0).map(|i| sim.particles().volume(i)).sum();
    let spec = *sim.spec();
    let mut log = RunLog {
        particle_steps: 0.0,
        steps: 0,
        wall_s: 0.0,
        frames: Vec::new(),
        initial_particles: n0,
        peak_particles: n0,
        final_particles: n0,
        h_min: spec.h_min(),
        r_max: spec.h_root / flip_tet::sizing::C_H,
        initial_liquid_volume: vol0,
    };
    let n_frames = (scene.duration * scene.fps).round().max(1.0) as usize;
    on_frame(&sim, 0)?;
    for f in 1..=n_frames {
        let tf = Instant::now();
        let stats = ft(sim.advance_to(f as f64 / scene.fps))?;
        for s in &stats {
            log.particle_steps += s.n_particles as f64;
            log.steps += 1;
            log.peak_particles = log.peak_particles.max(s.n_particles);
        }
        let p = sim.particles();
        let nb = p.flags.iter().filter(|fl| fl.has(ParticleFlags::BALLISTIC)).count();
        log.frames.push((sim.time(), p.len(), nb, tf.elapsed().as_secs_f64()));
        log.final_particles = p.len();
        on_frame(&sim, f)?;
    }
    log.wall_s = t0.elapsed().as_secs_f64();
    Ok(log)
}

/// Top view of the octree leaf levels (finest level over each column), one grey PNG pixel per
/// finest cube; brighter = finer.
fn levels_topview(path: &Path, oct: &Octree) -> Result<()> {
    let sp = oct.spec;
    let ext = sp.extent_units();
    let cell = sp.size_units(sp.levels - 1);
    let (w, d) = ((ext[0] / cell) as u32, (ext[2] / cell) as u32);
    let mut img = geom_core::image::ImageF32::new(w, d, 0.0);
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
    geom_core::image::write_png_gray8(path, &img)?;
    Ok(())
}

fn cost_plot(path: &Path, title: &str, runs: &[(&str, &RunLog)]) -> Result<()> {
    let mut plot = LinePlot::new(title, "t (s)", "wall seconds per frame");
    for (name, log) in runs {
        plot = plot.with(Series::new(*name, log.frames.iter().map(|f| (f.0, f.3)).collect()));
    }
    plot.write_png(path)?;
    let mut plot = LinePlot::new(title, "t (s)", "particles");
    for (name, log) in runs {
        plot = plot.with(Series::new(*name, log.frames.iter().map(|f| (f.0, f.1 as f64)).collect()));
    }
    plot.write_png(
        &path.with_file_name(format!("{}_particles.png", path.file_stem().and_then(|s| s.to_str()).unwrap_or("cost"))),
    )?;
    Ok(())
}

fn frames_csv(path: &Path, log: &RunLog) -> Result<()> {
    let mut csv = CsvWriter::create(path, &["t_s", "particles", "ballistic", "frame_wall_s"])?;
    for f in &log.frames {
        csv.row(&[Cell::Num(f.0), Cell::Int(f.1 as i64), Cell::Int(f.2 as i64), Cell::Num(f.3)])?;
    }
    Ok(())
}

/// S5: open splash with curvature sizing (the paper's Figure 1 analogue).
fn run_splash(ctx: &RunCtx) -> Result<Summary> {
    let (scene, obj_every) = load_sim(ctx)?;
    let n_frames = (scene.duration * scene.fps).round().max(1.0) as usize;
    let snaps = [0, n_frames / 2, n_frames];
    let dir = ctx.out_dir.clone();
    let mut rendered = Snapshots::new(&scene, &dir)?;
    let log = simulate(&scene, |sim, f| {
        rendered.frame(sim, f as u64)?;
        if snaps.contains(&f) {
            levels_topview(&dir.join(format!("levels_topview_{f:04}.png")), sim.octree())?;
        }
        if obj_every > 0 && (f as u32).is_multiple_of(obj_every) {
            if let Some(m) = sim.surface() {
                crate::out::ensure_dir(&dir.join("frames"))?;
                write_mesh(&dir.join("frames"), &format!("surface_{f:04}.obj"), &m)?;
            }
        }
        Ok(())
    })?;
    rendered.finish()?;
    frames_csv(&ctx.out_dir.join("frames.csv"), &log)?;
    cost_plot(&ctx.out_dir.join("cost_per_frame.png"), "open splash: cost per frame", &[("adaptive", &log)])?;
    // Uniform baseline (spec §12 G11): 8 particles per finest cube over the liquid volume.
    let uniform = log.initial_liquid_volume / (0.5 * log.h_min).powi(3);
    let s_factor = 1024.0 / scene.resolution.finest as f64;
    let ratio = uniform / log.initial_particles.max(1) as f64;
    let ballistic: f64 =
        log.frames.iter().map(|f| f.2 as f64 / f.1.max(1) as f64).sum::<f64>() / log.frames.len().max(1) as f64;
    let mut sum = Summary::new();
    sum.set_str("mode", ctx.mode.name())
        .set_count("finest", scene.resolution.finest as u64)
        .set("scale_factor_s", s_factor)
        .set_count("initial_particles", log.initial_particles as u64)
        .set_count("peak_particles", log.peak_particles as u64)
        .set_count("final_particles", log.final_particles as u64)
        .set("uniform_particles_estimate", uniform)
        .set("particle_ratio_uniform_over_adaptive", ratio)
        .set("paper_ratio_235_scaled", 235.0 / s_factor)
        .set("pass_threshold_ratio", 0.3 * 235.0 / s_factor)
        .set("ballistic_fraction_mean", ballistic)
        .set_count("steps", log.steps)
        .set("particle_steps", log.particle_steps)
        .set("wall_s", log.wall_s)
        .set("s_per_frame", log.wall_s / log.frames.len().max(1) as f64)
        .set("s_per_million_particle_steps", log.wall_s / (log.particle_steps / 1e6).max(1e-12))
        .set("paper_min_per_frame", 4.6);
    Ok(sum)
}

/// S6: visibility sizing on vs off in a U-shaped corridor.
fn run_corridor(ctx: &RunCtx) -> Result<Summary> {
    let (scene, _) = load_sim(ctx)?;
    let vis = scene
        .sizing
        .visibility
        .clone()
        .ok_or_else(|| Error::Run("corridor-camera: the scene must set sizing.visibility".into()))?;
    // On: count, at every frame, the particles outside the (unexpanded) frustum and how many of
    // them are at least r_max / 2.
    let (mut outside, mut outside_coarse) = (0usize, 0usize);
    let dir = ctx.out_dir.clone();
    let mut rendered = Snapshots::new(&scene, &dir)?;
    let on = simulate(&scene, |sim, f| {
        rendered.frame(sim, f as u64)?;
        let fr = vis.frustum(sim.time());
        let p = sim.particles();
        let r_max = sim.spec().h_root / flip_tet::sizing::C_H;
        for i in 0..p.len() {
            if !fr.contains(&p.x[i], 0.0) {
                outside += 1;
                if p.r[i] >= 0.5 * r_max * (1.0 - 1e-12) {
                    outside_coarse += 1;
                }
            }
        }
        if f.is_multiple_of(10) {
            levels_topview(&dir.join(format!("levels_topview_on_{f:04}.png")), sim.octree())?;
        }
        Ok(())
    })?;
    rendered.finish()?;
    let mut off_scene = scene.clone();
    off_scene.sizing.visibility = None;
    let off = simulate(&off_scene, |_, _| Ok(()))?;
    frames_csv(&ctx.out_dir.join("frames_visibility_on.csv"), &on)?;
    frames_csv(&ctx.out_dir.join("frames_visibility_off.csv"), &off)?;
    cost_plot(
        &ctx.out_dir.join("cost_per_frame.png"),
        "corridor: visibility on vs off",
        &[("visibility on", &on), ("visibility off", &off)],
    )?;
    let mut sum = Summary::new();
    sum.set_str("mode", ctx.mode.name())
        .set_count("finest", scene.resolution.finest as u64)
        .set("particle_steps_on", on.particle_steps)
        .set("particle_steps_off", off.particle_steps)
        .set("particle_steps_ratio_on_over_off", on.particle_steps / off.particle_steps.max(1.0))
        .set("wall_s_on", on.wall_s)
        .set("wall_s_off", off.wall_s)
        .set("time_ratio_on_over_off", on.wall_s / off.wall_s.max(1e-12))
        .set_count("peak_particles_on", on.peak_particles as u64)
        .set_count("peak_particles_off", off.peak_particles as u64)
        .set(
            "outside_frustum_coarse_fraction",
            if outside > 0 { outside_coarse as f64 / outside as f64 } else { f64::NAN },
        )
        .set_count("outside_frustum_particle_frames", outside as u64)
        .set("r_max_m", on.r_max);
    Ok(sum)
}

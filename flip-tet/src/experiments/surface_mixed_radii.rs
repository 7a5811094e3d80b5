//! S8 (spec §6, the paper's Figure 4 analogue, static): particles of radii `r`, `2r`, `4r` in strips,
//! all tangent to `y = H` from below, plus a blob of mixed sizes; the level set by triplet hulls,
//! Zhu–Bridson and sphere union on a uniform BCC mesh: flatness over the patch, blob area, cost per
//! million node evaluations; the fast node path timed against the exhaustive reference.
//!
//! ```no_run
//! use flip_tet::experiments::surface_mixed_radii;
//! use geom_core::experiment::Size;
//! let r = surface_mixed_radii::run(&flip_tet::presets::surface_mixed_radii(), Size::Quick, &mut geom_core::record::NullRecorder::default())?;
//! assert!(r.get_f64("flat_patch_max_dev_over_r") <= 1e-9);
//! # Ok::<(), flip_tet::error::SimError>(())
//! ```

use std::time::Instant;

use geom_core::experiment::{BySize, Report, Size, Target};
use geom_core::image::png_gray8_bytes;
use geom_core::math::{Pt3, Vec3};
use geom_core::mesh::TriMesh;
use geom_core::record::{Cell, Recorder};
use geom_core::rng::Rng;
use geom_core::stats::nan_max;
use serde::{Deserialize, Serialize};

use super::plot;
use crate::bcc::tetrahedralize;
use crate::error::{Result, SimError};
use crate::octree::{Octree, OctreeSpec};
use crate::particles::Particles;
use crate::surface::{
    level_set_on_nodes, marching_tets, smooth_surface, LevelSetSampler, SurfaceMethod, SurfaceParams, Walls,
};

/// Parameters (the scene file's `params`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Params {
    /// Smallest particle radius `r` (m); the strips use `r`, `2r`, `4r`.
    pub r: f64,
    /// Height `H` of the plane the patch particles touch from below (m).
    pub plane_y: f64,
    /// Domain box minimum corner (m).
    pub domain_min: (f64, f64, f64),
    /// Domain box maximum corner (m).
    pub domain_max: (f64, f64, f64),
    /// Root cubes along the longest axis.
    pub coarsest: u32,
    /// Uniform mesh resolution (cubes along the longest axis) per size.
    pub finest: BySize<u32>,
    /// Patch extent in x and z: `(x0, x1, z0, z1)` (m); the strips split `[x0, x1]` in three.
    pub patch: (f64, f64, f64, f64),
    /// Margin from the patch edges excluded from the flatness metric, in units of `4r`.
    pub edge_margin: f64,
    /// Blob centre (m).
    pub blob_center: (f64, f64, f64),
    /// Blob radius (m).
    pub blob_radius: f64,
    /// Blob particle count.
    pub blob_particles: usize,
    /// RNG seed for the blob.
    pub seed: u64,
    /// Surface parameters (the method is overridden per comparison run).
    #[serde(default)]
    pub surface: SurfaceParams,
}

fn pt(v: (f64, f64, f64)) -> Pt3 {
    Pt3::new(v.0, v.1, v.2)
}

/// The particle set: strips of touching particles tangent to `y = H` (two layers), and the blob.
pub fn mixed_particles(s: &Params) -> Particles {
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
/// within `h` of the plane.
pub fn flatness(m: &TriMesh, s: &Params, h: f64) -> (f64, f64, usize) {
    let (x0, x1, z0, z1) = s.patch;
    let mg = s.edge_margin * 4.0 * s.r;
    let mut max: f64 = 0.0;
    let mut sum2 = 0.0;
    let mut n = 0;
    for p in &m.positions {
        if p.x > x0 + mg && p.x < x1 - mg && p.z > z0 + mg && p.z < z1 - mg && (p.y - s.plane_y).abs() < h {
            let d = (p.y - s.plane_y).abs();
            max = nan_max(max, d);
            sum2 += d * d;
            n += 1;
        }
    }
    (max, if n > 0 { (sum2 / n as f64).sqrt() } else { f64::NAN }, n)
}

/// Height profile `(x, (y − H)/r)` of the top surface near the mid-z line, sorted by x.
pub fn profile(m: &TriMesh, s: &Params, h: f64) -> Vec<(f64, f64)> {
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

/// Area of the faces whose centroid lies within `1.5 R` of the blob centre (m²).
pub fn blob_area(m: &TriMesh, s: &Params) -> f64 {
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

fn preview(rec: &mut dyn Recorder, name: &str, m: &TriMesh, s: &Params) -> Result<()> {
    use geom_core::raster::{lambert_preview, Camera, RasterOptions};
    if m.n_faces() == 0 || !rec.keeps_outputs() {
        return Ok(());
    }
    let (lo, hi) = (pt(s.domain_min), pt(s.domain_max));
    let target = Pt3::new(0.5 * (lo.x + hi.x), s.plane_y, 0.5 * (lo.z + hi.z));
    let eye = target + Vec3::new(0.35, 0.9, 1.1) * (hi - lo).norm() * 0.6;
    let cam = Camera::look_at(&eye, &target, &Vec3::y(), 35.0, 800, 500)?;
    let o = RasterOptions { supersample: 2, ..Default::default() };
    let img = lambert_preview(&cam, &m.positions, &m.faces, &Vec3::new(0.3, 1.0, 0.5), &o);
    rec.file(name, &png_gray8_bytes(&img)?)?;
    Ok(())
}

fn obj_bytes(m: &TriMesh) -> Vec<u8> {
    let mut s = String::new();
    for p in &m.positions {
        s.push_str(&format!("v {:?} {:?} {:?}\n", p.x, p.y, p.z));
    }
    for f in &m.faces {
        s.push_str(&format!("f {} {} {}\n", f[0] + 1, f[1] + 1, f[2] + 1));
    }
    s.into_bytes()
}

/// Runs S8.
pub fn run(sc: &Params, size: Size, rec: &mut dyn Recorder) -> Result<Report> {
    sc.surface.validate().map_err(|e| SimError::InvalidScene(e.to_string()))?;
    let n = sc.finest.get(size);
    let spec = OctreeSpec::new(pt(sc.domain_min), pt(sc.domain_max), sc.coarsest, n)?;
    let oct = Octree::uniform(spec, spec.levels - 1);
    let mesh = tetrahedralize(&oct)?;
    let h = spec.h_min();
    let parts = mixed_particles(sc);
    let header = [
        "method",
        "max_dev_m",
        "max_dev_over_r",
        "rms_dev_over_r",
        "patch_vertices",
        "blob_area_m2",
        "nodes",
        "levelset_s",
        "s_per_million_nodes",
    ];
    rec.table("flatness", &header)?;
    let mut sum = Report::default();
    sum.count("nodes", mesh.nodes.len() as u64)
        .count("tets", mesh.tets.len() as u64)
        .count("particles", parts.len() as u64)
        .num("h_over_r", h / sc.r);
    for (method, tag) in [
        (SurfaceMethod::Hulls, "hulls"),
        (SurfaceMethod::ZhuBridson, "zhu_bridson"),
        (SurfaceMethod::SphereUnion, "sphere_union"),
    ] {
        let params = SurfaceParams { method, ..sc.surface.clone() };
        let t0 = Instant::now();
        let phi = level_set_on_nodes(&mesh, &parts, &params, &Walls::none());
        let dt = t0.elapsed().as_secs_f64();
        let raw = marching_tets(&mesh, &phi)?;
        let (max, rms, cnt) = flatness(&raw, sc, h);
        let smooth = smooth_surface(&raw, params.smoothing_iterations);
        let area = blob_area(&smooth, sc);
        if rec.keeps_outputs() {
            rec.file(&format!("surface_{tag}.obj"), &obj_bytes(&smooth))?;
        }
        preview(rec, &format!("surface_{tag}.png"), &smooth, sc)?;
        let per_m = dt / (mesh.nodes.len() as f64 / 1e6);
        rec.row(
            "flatness",
            &[
                Cell::Text(tag.into()),
                Cell::Num(max),
                Cell::Num(max / sc.r),
                Cell::Num(rms / sc.r),
                Cell::Int(cnt as i64),
                Cell::Num(area),
                Cell::Int(mesh.nodes.len() as i64),
                Cell::Num(dt),
                Cell::Num(per_m),
            ],
        )?;
        let prof = profile(&raw, sc, h);
        plot(rec, "flatness_profile", tag, ("x (m)", "(y − H) / r"), (false, false), prof)?;
        if method == SurfaceMethod::Hulls {
            if cnt == 0 {
                return Err(SimError::InvalidScene("surface-mixed-radii: no surface vertex over the patch".into()));
            }
            sum.num("flat_patch_max_dev_over_r", max / sc.r)
                .num("flat_patch_rms_dev_over_r", rms / sc.r)
                .count("flat_patch_vertices", cnt as u64)
                .num("blob_area_m2", area)
                .timing("hulls_s_per_million_nodes", per_m);
        } else {
            sum.num(&format!("{tag}_flat_patch_max_dev_over_r"), max / sc.r)
                .num(&format!("{tag}_flat_patch_rms_dev_over_r"), rms / sc.r)
                .num(&format!("{tag}_blob_area_m2"), area)
                .timing(&format!("{tag}_s_per_million_nodes"), per_m);
        }
    }
    sum.check("flat_patch_max_dev_over_r", Target::AtMost(1e-9), "spec §6 S8: flat patch exact to 1e-9 r");
    levelset_cost(&mesh, &parts, &sc.surface, &mut sum);
    Ok(sum)
}

/// The level set's fast node path against the exhaustive reference evaluation, both timed in the
/// same run on every k-th node (≤ 50 000): differences are allowed only at air nodes whose both
/// values exceed the local mesh size.
fn levelset_cost(mesh: &crate::bcc::TetMesh, parts: &Particles, surface: &SurfaceParams, sum: &mut Report) {
    use rayon::prelude::*;
    let params = SurfaceParams { method: SurfaceMethod::Hulls, ..surface.clone() };
    let s = LevelSetSampler::new(parts, &params, &Walls::none());
    let k = mesh.nodes.len().div_ceil(50_000).max(1);
    let sub: Vec<(Pt3, f64)> = mesh.nodes.iter().zip(&mesh.node_h).step_by(k).map(|(q, &h)| (*q, h)).collect();
    let t0 = Instant::now();
    let fast: Vec<f64> = sub.par_iter().map(|(q, h)| s.value_on_node(q, *h)).collect();
    let t_fast = t0.elapsed().as_secs_f64();
    let t0 = Instant::now();
    let slow: Vec<f64> = sub.par_iter().map(|(q, h)| s.value_exhaustive(q, *h)).collect();
    let t_slow = t0.elapsed().as_secs_f64();
    let differ = fast.iter().zip(&slow).filter(|(a, b)| a.to_bits() != b.to_bits()).count();
    let max_diff = fast.iter().zip(&slow).map(|(a, b)| (a - b).abs()).fold(0.0, nan_max);
    sum.timing("levelset_fast_s", t_fast)
        .timing("levelset_exhaustive_s", t_slow)
        .timing("levelset_speedup_exhaustive_over_fast", t_slow / t_fast.max(1e-12))
        .count("levelset_nodes_compared", sub.len() as u64)
        .count("levelset_nodes_differing", differ as u64)
        .num("levelset_max_abs_diff_over_r", max_diff / parts.r_max().max(1e-300));
}

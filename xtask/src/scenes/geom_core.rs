//! geom-core's own scenes: they show the foundation working on real input, end to end, and put
//! its invariants in the report.
//!
//! - `geom-core/render` ([`run_render`]): depth, normal, silhouette and shaded images of
//!   procedural meshes through the software rasteriser.
//! - `geom-core/subdivision` ([`run_subdivision`]): linear subdivision with its prolongation
//!   matrix and the cotangent Laplacian's identities, level by level.
//! - `geom-core/mocap` ([`run_mocap`]): the two CMU clips through the BVH reader, forward
//!   kinematics and a write/read round trip.

use std::path::PathBuf;
use std::time::Instant;

use geom_core::math::{Pt3, Vec3};
use geom_core::mesh::TriMesh;
use serde::Deserialize;

use crate::error::{Error, Result};
use crate::out::{CsvWriter, Summary};
use crate::plot::{LinePlot, Series};
use crate::registry::{RunCtx, Runner};
use crate::scene;

/// Adds geom-core's runners.
pub fn register(v: &mut Vec<Runner>) {
    v.push(Runner { method: "geom-core/render", run: run_render });
    v.push(Runner { method: "geom-core/subdivision", run: run_subdivision });
    v.push(Runner { method: "geom-core/mocap", run: run_mocap });
}

// ---------------------------------------------------------------------------------------------
// render

/// A procedural mesh a scene can name.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub enum MeshSource {
    /// `procedural::icosphere(radius, level)`.
    Icosphere { radius: f64, level: u32 },
    /// `procedural::box_surface` of the given size, centred at the origin.
    Box { size: [f64; 3], segments: [u32; 3] },
    /// A square sheet in the XZ plane with a sinusoidal height field `amplitude·sin(2π x/λ)`.
    WavySheet { size: f64, quads: u32, amplitude: f64, wavelength: f64 },
    /// A mesh file (OBJ/PLY/OFF), relative to the workspace root.
    File(PathBuf),
}

impl MeshSource {
    fn build(&self) -> Result<TriMesh> {
        use geom_core::procedural::{self, Diagonals, GridSpec, Plane};
        Ok(match self {
            MeshSource::Icosphere { radius, level } => procedural::icosphere(*radius, *level)?,
            MeshSource::Box { size, segments } => {
                let h = Vec3::new(size[0], size[1], size[2]) * 0.5;
                procedural::box_surface(Pt3::from(-h), Pt3::from(h), *segments, Diagonals::Alternating)?
            }
            MeshSource::WavySheet { size, quads, amplitude, wavelength } => {
                let g = procedural::grid(&GridSpec {
                    quads: [*quads, *quads],
                    size: [*size, *size],
                    plane: Plane::XZ,
                    diagonals: Diagonals::Alternating,
                    center: Pt3::origin(),
                })?;
                let p: Vec<Pt3> = g
                    .positions
                    .iter()
                    .map(|q| Pt3::new(q.x, q.y + amplitude * (std::f64::consts::TAU * q.x / wavelength).sin(), q.z))
                    .collect();
                g.with_positions(p)?
            }
            MeshSource::File(path) => geom_core::io::obj::read_tri(crate::out::workspace_root().join(path))?,
        })
    }
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RenderParams {
    /// Image width and height in pixels.
    size: [u32; 2],
    /// Quick-mode image size.
    quick_size: [u32; 2],
    /// Supersampling per axis.
    supersample: u32,
    /// Vertical field of view (degrees).
    fov_y_deg: f64,
    /// Camera position, relative to the mesh's bounding-box centre, in bounding-box diagonals.
    eye_offset: [f64; 3],
    /// Direction towards the light.
    light: [f64; 3],
    /// The meshes, each rendered into `<name>_{depth,normal,silhouette,shaded}.png`.
    meshes: Vec<(String, MeshSource)>,
}

fn run_render(ctx: &RunCtx) -> Result<Summary> {
    use geom_core::raster::{self, Camera, RasterOptions};
    let sc: scene::SceneFile<RenderParams> = scene::load(&ctx.scene_file)?;
    let p = sc.params;
    let [w, h] = ctx.mode.pick(p.quick_size, p.size, [p.size[0] * 2, p.size[1] * 2]);
    if w == 0 || h == 0 || p.supersample == 0 || !(1.0..179.0).contains(&p.fov_y_deg) {
        return Err(scene::invalid(&ctx.scene_file, "size and supersample must be ≥ 1 and fov_y_deg in [1, 179)"));
    }
    let mut s = Summary::new();
    let opts = RasterOptions { supersample: p.supersample, ..RasterOptions::default() };
    let light = Vec3::new(p.light[0], p.light[1], p.light[2]);
    let mut total_s = 0.0;
    for (name, src) in &p.meshes {
        let m = src.build()?;
        let (lo, hi) = m.bbox().ok_or_else(|| scene::invalid(&ctx.scene_file, format!("mesh '{name}' is empty")))?;
        let center = Pt3::from((lo.coords + hi.coords) * 0.5);
        let diag = (hi - lo).norm().max(1e-12);
        let eye = center + Vec3::new(p.eye_offset[0], p.eye_offset[1], p.eye_offset[2]) * diag;
        let cam = Camera::look_at(&eye, &center, &Vec3::y(), p.fov_y_deg, w, h)?;
        let t0 = Instant::now();
        let views = raster::render_views(&cam, &m.positions, &m.faces, &light, &opts, &ctx.out_dir, name)?;
        let dt = t0.elapsed().as_secs_f64();
        total_s += dt;
        let covered = raster::rasterize(&cam, &m.positions, &m.faces, &opts).silhouette(0.5).count();
        s.set_count(&format!("{name}_triangles"), m.faces.len() as u64);
        s.set_count(&format!("{name}_silhouette_px"), covered as u64);
        s.set(&format!("{name}_depth_max_m"), views.depth_max);
        s.set(&format!("{name}_render_s"), dt);
    }
    s.set("render_total_s", total_s);
    s.set_count("image_width", w as u64);
    s.set_count("image_height", h as u64);
    Ok(s)
}

// ---------------------------------------------------------------------------------------------
// subdivision

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct SubdivisionParams {
    /// Subdivision levels (default mode); quick uses fewer, full more.
    levels: [u32; 3],
    /// The coarse meshes.
    meshes: Vec<(String, MeshSource)>,
}

fn run_subdivision(ctx: &RunCtx) -> Result<Summary> {
    use geom_core::mesh::{cotan_stiffness, face_areas, mass_p1, subdivide_linear};
    let sc: scene::SceneFile<SubdivisionParams> = scene::load(&ctx.scene_file)?;
    let p = sc.params;
    let levels = ctx.mode.pick(p.levels[0], p.levels[1], p.levels[2]);
    let mut s = Summary::new();
    let mut csv = CsvWriter::create(
        &ctx.out_dir.join("levels.csv"),
        &[
            "mesh",
            "level",
            "vertices",
            "faces",
            "euler",
            "prolongation_err",
            "area_rel_err",
            "galerkin_mass_err",
            "laplacian_rowsum_max",
            "laplacian_asym_max",
            "subdivide_s",
            "cotan_s",
        ],
    )?;
    let mut plot = LinePlot::new("linear subdivision: time per level", "faces", "time (s)").log(true, true);
    let (mut worst_p, mut worst_area, mut worst_galerkin, mut worst_rowsum, mut worst_asym) =
        (0.0f64, 0.0f64, 0.0f64, 0.0f64, 0.0f64);
    for (name, src) in &p.meshes {
        let coarse = src.build()?;
        let area0: f64 = face_areas(&coarse.faces, &coarse.positions).iter().sum();
        let m_coarse = mass_p1(&coarse.faces, &coarse.positions);
        let mut pts = Vec::new();
        for level in 0..=levels {
            let t0 = Instant::now();
            let (fine, pmat) = subdivide_linear(&coarse, level);
            let t_sub = t0.elapsed().as_secs_f64();
            // Prolongation maps coarse positions to the fine ones.
            let mut perr = 0.0f64;
            for d in 0..3 {
                let xc: Vec<f64> = coarse.positions.iter().map(|q| q[d]).collect();
                let mut xf = vec![0.0; fine.positions.len()];
                pmat.mul_vec(&xc, &mut xf);
                for (a, q) in xf.iter().zip(&fine.positions) {
                    perr = perr.max((a - q[d]).abs());
                }
            }
            // Area of the fine mesh (linear subdivision keeps every coarse triangle's plane).
            let area: f64 = face_areas(&fine.faces, &fine.positions).iter().sum();
            let area_err = (area - area0).abs() / area0.max(f64::MIN_POSITIVE);
            // Galerkin identity Pᵀ M_fine P = M_coarse for the consistent P1 mass.
            let m_fine = mass_p1(&fine.faces, &fine.positions);
            let galerkin = pmat.transpose().matmul(&m_fine).matmul(&pmat);
            let mut gerr = 0.0f64;
            let scale = m_coarse.val.iter().fold(0.0f64, |a, v| a.max(v.abs()));
            for i in 0..m_coarse.nrows {
                let (cols, _) = galerkin.row(i);
                for &j in cols {
                    gerr = gerr.max((galerkin.get(i, j as usize) - m_coarse.get(i, j as usize)).abs());
                }
                let (cols, _) = m_coarse.row(i);
                for &j in cols {
                    gerr = gerr.max((galerkin.get(i, j as usize) - m_coarse.get(i, j as usize)).abs());
                }
            }
            gerr /= scale.max(f64::MIN_POSITIVE);
            let t1 = Instant::now();
            let l = cotan_stiffness(&fine.faces, &fine.positions, None);
            let t_cot = t1.elapsed().as_secs_f64();
            let diag_max = (0..l.nrows).map(|i| l.get(i, i).abs()).fold(0.0f64, f64::max).max(f64::MIN_POSITIVE);
            let mut rowsum = 0.0f64;
            let mut asym = 0.0f64;
            for i in 0..l.nrows {
                let (cols, vals) = l.row(i);
                rowsum = rowsum.max(vals.iter().sum::<f64>().abs() / diag_max);
                for (&j, &v) in cols.iter().zip(vals) {
                    asym = asym.max((v - l.get(j as usize, i)).abs() / diag_max);
                }
            }
            let topo = fine.topology();
            let euler = topo.n_vertices() as i64 - topo.n_edges() as i64 + topo.n_faces() as i64;
            csv.row(&[
                name.as_str().into(),
                (level as usize).into(),
                fine.positions.len().into(),
                fine.faces.len().into(),
                crate::out::Cell::Int(euler),
                perr.into(),
                area_err.into(),
                gerr.into(),
                rowsum.into(),
                asym.into(),
                t_sub.into(),
                t_cot.into(),
            ])?;
            pts.push((fine.faces.len() as f64, t_sub.max(1e-7)));
            worst_p = worst_p.max(perr);
            worst_area = worst_area.max(area_err);
            worst_galerkin = worst_galerkin.max(gerr);
            worst_rowsum = worst_rowsum.max(rowsum);
            worst_asym = worst_asym.max(asym);
            if level == levels {
                s.set_count(&format!("{name}_fine_vertices"), fine.positions.len() as u64);
                s.set_count(&format!("{name}_euler_characteristic"), euler.max(0) as u64);
                s.set(&format!("{name}_subdivide_s"), t_sub);
            }
        }
        plot = plot.with(Series::new(name.clone(), pts));
    }
    plot.write_png(&ctx.out_dir.join("subdivide_time.png"))?;
    s.set("prolongation_max_abs_err", worst_p);
    s.set("area_max_rel_err", worst_area);
    s.set("galerkin_mass_max_rel_err", worst_galerkin);
    s.set("laplacian_rowsum_max_rel", worst_rowsum);
    s.set("laplacian_asymmetry_max_rel", worst_asym);
    s.set_count("levels", levels as u64);
    Ok(s)
}

// ---------------------------------------------------------------------------------------------
// mocap

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct MocapParams {
    /// BVH files relative to the workspace root.
    clips: Vec<PathBuf>,
    /// Frames to run forward kinematics on in quick mode (all frames otherwise).
    quick_frames: usize,
}

fn run_mocap(ctx: &RunCtx) -> Result<Summary> {
    use geom_core::anim::bvh;
    let sc: scene::SceneFile<MocapParams> = scene::load(&ctx.scene_file)?;
    let p = sc.params;
    let mut s = Summary::new();
    let mut top = LinePlot::new("root trajectories (top view)", "x (m)", "z (m)");
    let mut heights = LinePlot::new("head height over time", "time (s)", "height (m)");
    for path in &p.clips {
        let full = crate::out::workspace_root().join(path);
        let name = path.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
        let text = std::fs::read_to_string(&full).map_err(crate::error::io_err(&full))?;
        let t0 = Instant::now();
        let m = bvh::read(&text, &bvh::BvhOptions::default())?;
        let parse_s = t0.elapsed().as_secs_f64();
        let nj = m.skeleton.joints.len();
        let frames = match ctx.mode {
            scene::Mode::Quick => m.len().min(p.quick_frames),
            _ => m.len(),
        };
        let mut pos = vec![Pt3::origin(); nj];
        let t1 = Instant::now();
        let mut min_y = f64::INFINITY;
        let mut max_y = f64::NEG_INFINITY;
        let head = m.skeleton.role(geom_core::anim::JointRole::Head);
        let mut head_curve = Vec::new();
        let mut root_curve = Vec::new();
        for f in 0..frames {
            m.joint_positions(f, &mut pos);
            for q in &pos {
                min_y = min_y.min(q.y);
                max_y = max_y.max(q.y);
            }
            if let Some(hj) = head {
                head_curve.push((f as f64 * m.frame_time, pos[hj as usize].y));
            }
            root_curve.push((pos[0].x, pos[0].z));
        }
        let fk_s = t1.elapsed().as_secs_f64();
        // Write, read back, compare joint positions.
        let written = bvh::write(&m, &bvh::BvhWriteOptions::default());
        let back = bvh::read(&written, &bvh::BvhOptions::default())?;
        if back.len() != m.len() {
            return Err(Error::Run(format!("{name}: round trip changed the frame count")));
        }
        let mut pos2 = vec![Pt3::origin(); nj];
        let mut rt_err = 0.0f64;
        for f in (0..frames).step_by((frames / 200).max(1)) {
            m.joint_positions(f, &mut pos);
            back.joint_positions(f, &mut pos2);
            for (a, b) in pos.iter().zip(&pos2) {
                rt_err = rt_err.max((a - b).norm());
            }
        }
        s.set_count(&format!("{name}_joints"), nj as u64);
        s.set_count(&format!("{name}_frames"), m.len() as u64);
        s.set(&format!("{name}_frame_rate_hz"), 1.0 / m.frame_time);
        s.set(&format!("{name}_duration_s"), m.duration());
        s.set(&format!("{name}_parse_s"), parse_s);
        s.set(&format!("{name}_fk_us_per_frame"), 1e6 * fk_s / frames.max(1) as f64);
        s.set(&format!("{name}_height_range_m"), max_y - min_y);
        s.set(&format!("{name}_roundtrip_max_err_m"), rt_err);
        top = top.with(Series::new(name.clone(), root_curve));
        heights = heights.with(Series::new(name, head_curve));
    }
    top.write_png(&ctx.out_dir.join("root_top_view.png"))?;
    heights.write_png(&ctx.out_dir.join("head_height.png"))?;
    Ok(s)
}

#[cfg(test)]
mod tests {
    use crate::registry::builtin_scenes;
    use crate::run::run_scene;
    use crate::scene::Mode;

    /// Every built-in geom-core scene parses and runs end to end in quick mode, and its
    /// invariant figures hold.
    #[test]
    fn geom_core_scenes_run_quick() {
        let root = std::env::temp_dir().join(format!("xtask-gc-scenes-{}", std::process::id()));
        for s in builtin_scenes().unwrap().into_iter().filter(|s| s.id.starts_with("geom-core/")) {
            let dir = root.join(&s.id);
            let sum = run_scene(&s.id, &s.file, Mode::Quick, &dir).unwrap_or_else(|e| panic!("{}: {e}", s.id));
            match s.id.as_str() {
                "geom-core/subdivision" => {
                    assert_eq!(sum.get("prolongation_max_abs_err"), Some(0.0));
                    assert!(sum.get("galerkin_mass_max_rel_err").unwrap() < 1e-12);
                    assert!(sum.get("laplacian_rowsum_max_rel").unwrap() < 1e-12);
                }
                "geom-core/mocap" => assert!(sum.get("01_01_roundtrip_max_err_m").unwrap() < 1e-6),
                "geom-core/render" => assert!(sum.get("icosphere_silhouette_px").unwrap() > 0.0),
                _ => {}
            }
        }
        std::fs::remove_dir_all(&root).unwrap();
    }
}

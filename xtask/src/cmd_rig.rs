//! `cargo xtask rig <mesh> [--skeleton human|quadruped|FILE.ron] [--up AXIS --front AXIS]
//! [--units UNIT] [--out DIR]`: rigs a user's character mesh (`rigging::character::rig_character`)
//! and writes `rig.json` (joints and weights in the input's axes and units, format in the
//! rigging README), the rigged character as `character.glb` (glTF: +Y up, facing +Z, metres)
//! and `preview.png` (front and side, skeleton over the mesh).

use std::path::{Path, PathBuf};
use std::time::Instant;

use geom_core::anim::skin::SkinWeights;
use geom_core::io::gltf::{skinned_glb, GltfJoint, SkinnedMesh};
use geom_core::math::Pt3;
use rigging::character::{rig_character, CharacterOptions};
use rigging::export::{joint_weights, RigFile};
use rigging::orient::Axis;
use rigging::SkeletonTemplate;

use crate::error::{io_err, Error, Result};

/// Command-line arguments of `rig`.
pub struct RigArgs {
    /// The mesh file (OBJ, PLY, OFF, GLB).
    pub mesh: PathBuf,
    /// `human`, `quadruped` or a template RON file.
    pub skeleton: String,
    /// Up axis override.
    pub up: Option<String>,
    /// Front axis override.
    pub front: Option<String>,
    /// Length unit of the mesh: m, cm, mm, in or auto.
    pub units: String,
    /// Output folder.
    pub out: PathBuf,
}

/// Reads a mesh file as a triangle soup (polygons fan-triangulated, nothing repaired).
pub fn read_soup(path: &Path) -> Result<(Vec<Pt3>, Vec<[u32; 3]>)> {
    let is_glb = path.extension().is_some_and(|e| e.eq_ignore_ascii_case("glb"));
    if is_glb {
        let bytes = std::fs::read(path).map_err(io_err(path))?;
        return geom_core::io::gltf::read_glb_triangles(&bytes).map_err(|e| file_err(path, e));
    }
    let m = geom_core::io::read_any(path).map_err(|e| file_err(path, e))?;
    let mut faces = Vec::new();
    for f in 0..m.faces.len() {
        let r = m.faces.row(f);
        for i in 1..r.len().saturating_sub(1) {
            faces.push([r[0], r[i], r[i + 1]]);
        }
    }
    Ok((m.positions, faces))
}

fn file_err(path: &Path, e: impl std::fmt::Display) -> Error {
    Error::Run(format!("{}: {e}", path.display()))
}

/// Metres per unit for `--units` (`auto`: the unit that brings `height` closest to 1.7 m).
pub fn metres_per_unit(units: &str, height: f64) -> Result<f64> {
    let known = [("m", 1.0), ("cm", 0.01), ("mm", 0.001), ("in", 0.0254)];
    if units == "auto" {
        let score = |s: f64| (s * height / 1.7).ln().abs();
        return Ok(known.iter().map(|k| k.1).min_by(|a, b| score(*a).total_cmp(&score(*b))).unwrap_or(1.0));
    }
    known
        .iter()
        .find(|k| k.0 == units)
        .map(|k| k.1)
        .ok_or_else(|| Error::Usage(format!("--units {units}: expected m, cm, mm, in or auto")))
}

/// The skeleton template named on the command line.
pub fn template(name: &str) -> Result<SkeletonTemplate> {
    Ok(match name {
        "human" => SkeletonTemplate::human(),
        "quadruped" => SkeletonTemplate::quadruped(),
        file => SkeletonTemplate::from_ron_file(Path::new(file))?,
    })
}

/// `cargo xtask rig`.
pub fn run(a: &RigArgs) -> Result<()> {
    let sk = template(&a.skeleton)?;
    let axis = |s: &Option<String>| s.as_deref().map(str::parse::<Axis>).transpose();
    let o = CharacterOptions { up: axis(&a.up)?, front: axis(&a.front)?, ..Default::default() };
    let (positions, faces) = read_soup(&a.mesh)?;
    let t0 = Instant::now();
    let r = rig_character(&positions, &faces, &sk, &o).map_err(|e| file_err(&a.mesh, e))?;
    let secs = t0.elapsed().as_secs_f64();
    std::fs::create_dir_all(&a.out).map_err(io_err(&a.out))?;
    let file = RigFile::new(&r, &positions, &faces)?;
    let json = serde_json::to_string(&file).map_err(|e| Error::Run(format!("rig.json: {e}")))?;
    let path = a.out.join("rig.json");
    std::fs::write(&path, json).map_err(io_err(&path))?;
    // The rigged character as glTF: the rig's frame (+Y up, facing +Z), in metres.
    let s = metres_per_unit(&a.units, file.height)?;
    let scaled: Vec<Pt3> = r.rig.joints.iter().map(|p| p * s).collect();
    let skel = sk.anim_skeleton(&scaled)?;
    let pos: Vec<Pt3> = r.rig.mesh.positions.iter().map(|p| p * s).collect();
    let w: SkinWeights = joint_weights(&r.rig)?;
    let joints = GltfJoint::from_skeleton(&skel);
    let glb = skinned_glb(&SkinnedMesh {
        name: "character",
        positions: &pos,
        faces: &r.rig.mesh.faces,
        joints: &joints,
        weights: &w,
        animation: None,
    })?;
    let path = a.out.join("character.glb");
    std::fs::write(&path, glb).map_err(io_err(&path))?;
    let left: Vec<bool> = sk.joints.iter().map(|j| j.name.starts_with('l')).collect();
    let img = rigging::preview::rig_preview(
        &r.rig.mesh.positions,
        &r.rig.mesh.faces,
        &r.rig.joints,
        &sk.bones(),
        &left,
        512,
    )?;
    let path = a.out.join("preview.png");
    geom_core::image::write_png_rgb8(&path, &img)?;
    let d = &r.rig.discrete;
    println!("rig {}: {}", a.mesh.display(), a.out.display());
    println!("  orientation  = {}{}", r.orientation, if r.detection.is_some() { " (detected)" } else { " (given)" });
    println!(
        "  vertices     = {} (split {} non-manifold)",
        r.rig.mesh.n_vertices(),
        r.rig.diagnostics.prep.split_vertices
    );
    println!("  height       = {} (input units; glTF at {s} m per unit)", file.height);
    println!("  search       = {} expansions, certified_optimal = {}", d.expanded, d.certified_optimal);
    println!("  time_s       = {secs:.2}");
    Ok(())
}

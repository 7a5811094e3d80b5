//! Numbered OBJ frame sequences: `dir/0000.obj`, `dir/0001.obj`, … sharing one topology (an
//! animation or simulation output). The subfolder (`frames/`, `guide/` …) is the caller's.

use std::path::{Path, PathBuf};

use crate::error::{Error, Result};
use crate::math::Pt3;
use crate::mesh::TriMesh;

use super::fs::io_error;
use super::tri::fan;
use super::{obj, MeshOut, ReadOptions};

/// Path of frame `i`: `dir/NNNN.obj` with at least four digits (`0007.obj`, `12345.obj`), so
/// that a plain name sort is the frame order up to 10 000 frames.
pub fn frame_path(dir: &Path, i: usize) -> PathBuf {
    dir.join(format!("{i:04}.obj"))
}

/// Writes frame `i` to [`frame_path`]`(dir, i)`, creating `dir` if needed; returns the path.
pub fn write_obj_frame(dir: &Path, i: usize, m: &MeshOut) -> Result<PathBuf> {
    std::fs::create_dir_all(dir).map_err(|e| io_error(dir, "cannot create directory", e))?;
    let p = frame_path(dir, i);
    obj::write(&p, m)?;
    Ok(p)
}

/// The frame files of `dir`: names that are all digits plus `.obj`, by frame number, checked
/// to be exactly `0, 1, …, n−1`.
fn frame_files(dir: &Path) -> Result<Vec<PathBuf>> {
    let rd = std::fs::read_dir(dir).map_err(|e| io_error(dir, "cannot list", e))?;
    let mut frames: Vec<(u64, PathBuf)> = Vec::new();
    for entry in rd {
        let entry = entry.map_err(|e| io_error(dir, "cannot list", e))?;
        let name = entry.file_name();
        let Some(name) = name.to_str() else { continue };
        let Some(stem) = name.strip_suffix(".obj") else { continue };
        if stem.is_empty() || !stem.bytes().all(|b| b.is_ascii_digit()) {
            continue;
        }
        let Ok(i) = stem.parse::<u64>() else { continue };
        frames.push((i, entry.path()));
    }
    frames.sort();
    if frames.is_empty() {
        return Err(Error::InvalidParameter(format!("no frame files (0000.obj, 0001.obj, …) in {}", dir.display())));
    }
    for (k, (i, p)) in frames.iter().enumerate() {
        if *i != k as u64 {
            let what = if *i < k as u64 { "appears twice" } else { "is missing" };
            return Err(Error::InvalidParameter(format!(
                "frame {k} {what} in {} (found {})",
                dir.display(),
                p.display()
            )));
        }
    }
    Ok(frames.into_iter().map(|(_, p)| p).collect())
}

/// Reads the frames `0000.obj, 0001.obj, …` of `dir`: frame 0 as a validated [`TriMesh`]
/// (strict, no welding; UVs as in [`obj::read_tri`]) and the positions of every frame
/// (including frame 0). Every frame must have the same vertex count and the same (fan
/// triangulated) faces as frame 0.
///
/// Errors: [`Error::InvalidParameter`] when `dir` has no frames or the numbering has a gap or a
/// duplicate (e.g. `1.obj` and `0001.obj`); [`Error::TopologyMismatch`] when a frame's vertex
/// count (`expected`/`got` are vertex counts) or triangle count (triangle counts) differs;
/// [`Error::Parse`] (line 0) naming the file, the first differing triangle and both index
/// triples when the counts agree but the faces do not (the counts of `TopologyMismatch` could
/// not say where). Parse errors name the file and line.
pub fn read_obj_sequence(dir: &Path) -> Result<(TriMesh, Vec<Vec<Pt3>>)> {
    let files = frame_files(dir)?;
    let first = obj::read_data(&files[0])?;
    let mesh = first.to_tri(&ReadOptions::default())?;
    let mut frames = Vec::with_capacity(files.len());
    frames.push(mesh.positions.clone());
    for p in &files[1..] {
        let d = obj::read_data(p)?;
        if d.positions.len() != mesh.n_vertices() {
            return Err(Error::TopologyMismatch { expected: mesh.n_vertices(), got: d.positions.len() });
        }
        let (tris, _) = fan(&d.faces);
        if tris.len() != mesh.n_faces() {
            return Err(Error::TopologyMismatch { expected: mesh.n_faces(), got: tris.len() });
        }
        if let Some(f) = (0..tris.len()).find(|&f| tris[f] != mesh.faces[f]) {
            return Err(Error::Parse {
                format: "OBJ",
                line: 0,
                msg: format!(
                    "{}: triangle {f} is {:?} but {:?} in frame 0: frames must share topology",
                    p.display(),
                    tris[f],
                    mesh.faces[f]
                ),
            });
        }
        frames.push(d.positions);
    }
    Ok((mesh, frames))
}

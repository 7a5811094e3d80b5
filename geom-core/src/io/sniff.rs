//! Format detection for [`read_any`]: by file extension, then by the first bytes.

use std::path::Path;

use crate::error::{Error, Result};
use crate::mesh::PolyMesh;

use super::fs::{empty_mesh, read_file, with_path};
use super::text::{lines, strip_bom, tokens};
use super::{obj, off, ply};

/// A mesh file format [`read_any`] knows.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MeshFormat {
    /// Wavefront OBJ.
    Obj,
    /// PLY (any encoding).
    Ply,
    /// OFF.
    Off,
}

/// Statements that may open an OBJ file.
const OBJ_START: &[&[u8]] =
    &[b"v", b"vt", b"vn", b"vp", b"f", b"o", b"g", b"s", b"l", b"p", b"mtllib", b"usemtl", b"mg", b"cstype"];

/// Guesses the format from the first bytes of a file: `ply` on the first line → PLY; a first
/// keyword ending in `OFF` → OFF; a first statement that is an OBJ vertex, face, group or
/// material statement → OBJ. Comments (`#`) and blank lines before it are skipped; only the
/// first 64 KiB are looked at.
pub fn sniff(data: &[u8]) -> Option<MeshFormat> {
    let data = strip_bom(data);
    let head = &data[..data.len().min(1 << 16)];
    let first = head.split(|&b| b == b'\n').next().unwrap_or_default();
    if first.trim_ascii() == b"ply" {
        return Some(MeshFormat::Ply);
    }
    for (_, l) in lines(head) {
        let code = match l.iter().position(|&b| b == b'#') {
            Some(c) => &l[..c],
            None => l,
        };
        let Some(t) = tokens(code).next() else { continue };
        if t.ends_with(b"OFF") && t.iter().all(|b| b.is_ascii_alphanumeric()) {
            return Some(MeshFormat::Off);
        }
        if OBJ_START.contains(&t) {
            return Some(MeshFormat::Obj);
        }
        return None;
    }
    None
}

/// Reads a mesh file of any supported format as a polygon mesh (PLY properties other than UVs
/// are dropped; use [`ply::read_data`] to keep them). The format comes from the extension
/// (`.obj`, `.ply`, `.off`, any case), otherwise from [`sniff`]; a file that is neither is an
/// [`Error::Parse`] (format `"mesh"`, line 0) saying so; a file with neither vertices nor faces
/// (an empty file) is an [`Error::Parse`] saying the mesh is empty, naming the file.
pub fn read_any(path: impl AsRef<Path>) -> Result<PolyMesh> {
    let path = path.as_ref();
    let data = read_file(path)?;
    let ext = path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase);
    let fmt = match ext.as_deref() {
        Some("obj") => Some(MeshFormat::Obj),
        Some("ply") => Some(MeshFormat::Ply),
        Some("off") => Some(MeshFormat::Off),
        _ => sniff(&data),
    };
    let r = match fmt {
        Some(MeshFormat::Obj) => obj::parse(&data).map(obj::ObjData::into_poly),
        Some(MeshFormat::Ply) => ply::read_bytes(&data).map(|d| d.to_poly()),
        Some(MeshFormat::Off) => off::parse(&data),
        None => Err(Error::Parse {
            format: "mesh",
            line: 0,
            msg: format!(
                "cannot tell the format: the extension is not .obj, .ply or .off and the content does not look like OBJ, PLY or OFF (first bytes: {:?})",
                String::from_utf8_lossy(&data[..data.len().min(16)])
            ),
        }),
    };
    let m = r.map_err(|e| with_path(e, path))?;
    if m.positions.is_empty() && m.faces.is_empty() {
        let format = match fmt {
            Some(MeshFormat::Ply) => "PLY",
            Some(MeshFormat::Off) => "OFF",
            _ => "OBJ",
        };
        return Err(empty_mesh(format, path, "no vertices, no faces"));
    }
    Ok(m)
}

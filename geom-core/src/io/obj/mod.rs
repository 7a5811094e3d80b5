//! Wavefront OBJ: read polygon meshes with UVs and normals from real-world files, write meshes
//! with the shortest round-trip number text.
//!
//! # What the reader accepts
//! - `v x y z`, optionally followed by `w` (4 numbers) or by vertex colours `r g b` (6 or 7
//!   numbers); `w` and colours are read and dropped (`w` only matters for rational free-form
//!   geometry, which is not kept).
//! - `vt u [v [w]]` (missing `v` is 0), `vn x y z`.
//! - `f` (and the old `fo`) with corners `v`, `v/vt`, `v//vn`, `v/vt/vn`, any number (≥ 3) of
//!   corners; positive 1-based indices (which may refer forward to vertices defined later) and
//!   negative indices relative to the elements defined so far (`-1` = the last one).
//! - Comments from `#` to the end of the line (also trailing), CRLF or LF line ends, tabs, a
//!   missing final newline, blank lines, a leading UTF-8 byte-order mark, a trailing `\`
//!   continuing a statement on the next line (comments are cut from each physical line before
//!   joining).
//! - Several objects and groups: `o`, `g`, `s`, `mg`, `usemtl`, `mtllib` … are skipped and all
//!   faces go into one mesh, in file order.
//! - Every other keyword of the OBJ specification is skipped without error (`p`, `l`, `vp` and
//!   the free-form statements `cstype`, `curv`, `surf`, …; see the list in the source). A keyword
//!   that is not OBJ at all is an error: such a line usually means the file is not OBJ, or is
//!   damaged, and silently skipping it could drop geometry.
//!
//! # Errors
//! [`Error::Parse`](crate::Error::Parse) with format `"OBJ"`, the 1-based line and what is
//! wrong: a bad or non-finite number, the wrong count of numbers on `v`/`vt`/`vn`, index 0, an
//! index out of range (for forward references reported at the line of the largest index), a face
//! with fewer than 3 corners, an unknown statement. File readers append the path.
//!
//! # UVs
//! [`ObjData`] keeps every `vt` and, per face corner, which one it uses. Meshes get UVs only when
//! *every* corner has a `vt` (otherwise the file's UVs are partial and are left in `ObjData`):
//! per vertex when each vertex gets one UV value at all its corners, else per corner
//! ([`Uv::PerCorner`], triangles only: [`PolyMesh`] has no per-corner UVs, so [`read`] drops
//! them, [`read_tri`] keeps them).

mod parse;
mod write;

use std::path::Path;

use crate::error::Result;
use crate::graph::Ragged;
use crate::math::{Pt2, Pt3, Vec3};
use crate::mesh::{PolyMesh, TriMesh};
use crate::NONE;

use super::fs::{empty_mesh, read_file, with_path};
use super::tri::{build_tri, consistent_vertex_uv, SourceUv};
use super::ReadOptions;

pub use parse::parse;
pub use write::{to_string, write};

/// Everything an OBJ file holds that a mesh can use, before any interpretation.
#[derive(Clone, Debug, PartialEq)]
pub struct ObjData {
    /// `v` positions (m), in file order.
    pub positions: Vec<Pt3>,
    /// `vt` texture coordinates, in file order.
    pub texcoords: Vec<Pt2>,
    /// `vn` normals as written (not normalised), in file order.
    pub normals: Vec<Vec3>,
    /// Faces (0-based vertex indices, ≥ 3 per face), in file order across all objects/groups.
    pub faces: Ragged<u32>,
    /// Per face corner (aligned with `faces.items`), the 0-based `vt` index or [`NONE`] where the
    /// corner has none; `None` when no corner has one.
    pub corner_texcoord: Option<Vec<u32>>,
    /// Per face corner, the 0-based `vn` index or [`NONE`]; `None` when no corner has one.
    pub corner_normal: Option<Vec<u32>>,
}

impl ObjData {
    /// The UV of every face corner (aligned with `faces.items`), when every corner has one.
    pub fn corner_uv(&self) -> Option<Vec<Pt2>> {
        let c = self.corner_texcoord.as_ref()?;
        if c.contains(&NONE) {
            return None;
        }
        // The parser range-checks indices; `get` keeps hand-built data from panicking.
        c.iter().map(|&t| self.texcoords.get(t as usize).copied()).collect()
    }

    /// One UV per vertex, when every corner has one and every vertex has the same UV at all its
    /// corners (vertices in no face get `(0, 0)`).
    pub fn vertex_uv(&self) -> Option<Vec<Pt2>> {
        consistent_vertex_uv(self.positions.len(), &self.faces.items, &self.corner_uv()?)
    }

    /// The polygon mesh (positions, faces, per-vertex UVs when consistent).
    pub fn to_poly(&self) -> PolyMesh {
        PolyMesh { positions: self.positions.clone(), faces: self.faces.clone(), uv: self.vertex_uv() }
    }

    /// As [`ObjData::to_poly`], consuming the data.
    pub fn into_poly(self) -> PolyMesh {
        let uv = self.vertex_uv();
        PolyMesh { positions: self.positions, faces: self.faces, uv }
    }

    /// Fan-triangulates and validates with [`TriMesh::new`]; UVs per vertex or per corner (see
    /// the module docs); welding only if `opts` asks for it.
    pub fn to_tri(&self, opts: &ReadOptions) -> Result<TriMesh> {
        let uv = match (self.vertex_uv(), self.corner_uv()) {
            (Some(v), _) => SourceUv::PerVertex(v),
            (None, Some(c)) => SourceUv::PerCorner(c),
            (None, None) => SourceUv::None,
        };
        build_tri(self.positions.clone(), &self.faces, uv, opts)
    }
}

/// Reads an OBJ file into [`ObjData`]; errors name the line and the path. A file with neither
/// vertices nor faces is an error saying the mesh is empty.
pub fn read_data(path: impl AsRef<Path>) -> Result<ObjData> {
    let path = path.as_ref();
    let d = parse(&read_file(path)?).map_err(|e| with_path(e, path))?;
    if d.positions.is_empty() && d.faces.is_empty() {
        return Err(empty_mesh("OBJ", path, "no vertices, no faces"));
    }
    Ok(d)
}

/// Reads an OBJ file as a polygon mesh (all objects merged; per-vertex UVs when consistent).
pub fn read(path: impl AsRef<Path>) -> Result<PolyMesh> {
    read_data(path).map(ObjData::into_poly)
}

/// Parses OBJ text as a polygon mesh (for tests and embedded data).
pub fn read_str(text: &str) -> Result<PolyMesh> {
    parse(text.as_bytes()).map(ObjData::into_poly)
}

/// Reads an OBJ file as a validated triangle mesh: polygons fan-triangulated, strict
/// [`TriMesh::new`] checks, no welding. Face indices in validation errors
/// ([`crate::Error::DegenerateFace`] …) count triangles after the fan triangulation, which is
/// the file's face order when all faces are triangles.
pub fn read_tri(path: impl AsRef<Path>) -> Result<TriMesh> {
    read_tri_with(path, &ReadOptions::default())
}

/// As [`read_tri`] with options (explicit vertex welding). A file without faces is an error
/// saying the mesh is empty.
pub fn read_tri_with(path: impl AsRef<Path>, opts: &ReadOptions) -> Result<TriMesh> {
    let path = path.as_ref();
    let d = read_data(path)?;
    if d.faces.is_empty() {
        return Err(empty_mesh("OBJ", path, &format!("{} vertices, no faces", d.positions.len())));
    }
    d.to_tri(opts)
}

/// Parses OBJ text as a validated triangle mesh.
pub fn read_tri_str(text: &str, opts: &ReadOptions) -> Result<TriMesh> {
    parse(text.as_bytes())?.to_tri(opts)
}

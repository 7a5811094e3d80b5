//! PLY (Stanford polygon file format): meshes and point sets with named per-vertex attributes,
//! ASCII, binary little-endian and binary big-endian.
//!
//! # What the reader accepts
//! - Header: `ply`, one `format` line (`ascii`, `binary_little_endian`, `binary_big_endian`,
//!   version 1.0), `comment` and `obj_info` lines (kept in [`PlyMesh`]), `element` and `property`
//!   lines with every scalar type (`char uchar short ushort int uint float double` and the aliases
//!   `int8 uint8 int16 uint16 int32 uint32 float32 float64`) and `list` properties with any
//!   integer count type and any item type; LF or CRLF line ends.
//! - `vertex`: scalar `x`, `y`, `z` (any types) are the positions; every other scalar property
//!   (normals, colours, UVs, custom data) is returned as a named per-vertex `Vec<f64>` in header
//!   order; list properties on vertices are read and dropped. Values are widened exactly to f64
//!   (ASCII `float` values are parsed as f32 first, so ASCII and binary give the same numbers).
//!   Non-finite values are kept (point clouds use NaN for missing points); [`PlyMesh::to_tri`]
//!   refuses them through `TriMesh::new`.
//! - `face`: the list `vertex_indices` (or `vertex_index`), any integer types, polygons of 3 or
//!   more vertices (fan-triangulated by the triangle readers); an optional list `texcoord` of
//!   `2n` values (MeshLab's per-corner UVs); other face properties are read and dropped.
//! - Any other element (edges, materials, …) is read past correctly in all encodings.
//! - ASCII bodies: one element instance per line (blank lines skipped). Binary bodies may be
//!   followed by a single newline.
//!
//! UVs: per-vertex from the property pairs `u v`, `s t`, `texture_u texture_v` or
//! `texture_s texture_t` (first found), else per corner from `texcoord`.
//!
//! # Errors
//! [`Error::Parse`](crate::Error::Parse) with format `"PLY"`: header problems name the header
//! line (missing `ply`, unknown format or type, property outside an element, no `end_header`);
//! ASCII body problems name the line, element and instance (bad or out-of-range number, too few
//! or too many values on a line, file ending early, data after the last element); binary body
//! problems have line 0 and name the element, instance, property and byte offset (truncated
//! body, trailing bytes). Face indices out of range, negative or non-integer counts, faces with
//! fewer than 3 vertices are errors in every encoding.
//!
//! # Writer
//! [`write`] / [`to_bytes`]: `vertex` with `x y z` (`double`, or `float` for f32 positions),
//! `nx ny nz` for normals, `u v` for per-vertex UVs, then the named properties; `face` with
//! `list uchar int vertex_indices` (`uint` where needed) and, for per-corner UVs,
//! `list uchar double texcoord`. ASCII numbers are the shortest round-trip text of their type,
//! so ASCII and binary files read back to identical values.

mod body;
mod header;
mod write;

use std::path::Path;

use crate::error::Result;
use crate::graph::Ragged;
use crate::math::{Pt2, Pt3};
use crate::mesh::{PolyMesh, TriMesh};

use super::fs::{read_file, with_path};
use super::tri::{build_tri_mapped, consistent_vertex_uv, remap_first, SourceUv};
use super::ReadOptions;

pub use write::{points_to_bytes, to_bytes, write, write_points, Encoding, PlyData};

/// Named per-vertex scalar properties, in header order, values widened to f64.
pub type Props = Vec<(String, Vec<f64>)>;

/// What a PLY file holds that a mesh or point set can use.
#[derive(Clone, Debug, PartialEq)]
pub struct PlyMesh {
    /// Vertex positions (m) from `x y z`.
    pub positions: Vec<Pt3>,
    /// Faces (empty for a point set), 0-based indices, ≥ 3 per face, range-checked.
    pub faces: Ragged<u32>,
    /// Every other scalar vertex property, by name, one value per vertex.
    pub props: Props,
    /// Per-corner UVs from a face `texcoord` list, aligned with `faces.items`.
    pub corner_uv: Option<Vec<Pt2>>,
    /// `comment` lines of the header (text after the keyword).
    pub comments: Vec<String>,
    /// `obj_info` lines of the header.
    pub obj_info: Vec<String>,
}

/// Property-name pairs recognised as per-vertex UVs, in order of preference.
const UV_NAMES: [(&str, &str); 4] = [("u", "v"), ("s", "t"), ("texture_u", "texture_v"), ("texture_s", "texture_t")];

impl PlyMesh {
    /// A named per-vertex property.
    pub fn prop(&self, name: &str) -> Option<&[f64]> {
        self.props.iter().find(|(n, _)| n == name).map(|(_, v)| v.as_slice())
    }

    /// Per-vertex UVs: from a vertex property pair (see the module docs), else from per-corner
    /// `texcoord` when each vertex has one consistent value.
    pub fn vertex_uv(&self) -> Option<Vec<Pt2>> {
        for (a, b) in UV_NAMES {
            if let (Some(u), Some(v)) = (self.prop(a), self.prop(b)) {
                return Some(u.iter().zip(v).map(|(&u, &v)| Pt2::new(u, v)).collect());
            }
        }
        consistent_vertex_uv(self.positions.len(), &self.faces.items, self.corner_uv.as_ref()?)
    }

    /// The polygon mesh (per-vertex UVs when available).
    pub fn to_poly(&self) -> PolyMesh {
        PolyMesh { positions: self.positions.clone(), faces: self.faces.clone(), uv: self.vertex_uv() }
    }

    /// Fan-triangulates and validates with [`TriMesh::new`]; UVs per vertex when available,
    /// else per corner.
    pub fn to_tri(&self, opts: &ReadOptions) -> Result<TriMesh> {
        self.to_tri_mapped(opts).map(|(m, _)| m)
    }

    /// As [`PlyMesh::to_tri`], also returning the old → new vertex map when welding was done.
    fn to_tri_mapped(&self, opts: &ReadOptions) -> Result<(TriMesh, Option<Vec<u32>>)> {
        let uv = match (self.vertex_uv(), &self.corner_uv) {
            (Some(v), _) => SourceUv::PerVertex(v),
            (None, Some(c)) => SourceUv::PerCorner(c.clone()),
            (None, None) => SourceUv::None,
        };
        build_tri_mapped(self.positions.clone(), &self.faces, uv, opts)
    }
}

/// Parses a PLY file held in memory (any encoding).
pub fn read_bytes(data: &[u8]) -> Result<PlyMesh> {
    body::parse(data)
}

/// Reads a PLY file into [`PlyMesh`]; errors name the path.
pub fn read_data(path: impl AsRef<Path>) -> Result<PlyMesh> {
    let path = path.as_ref();
    read_bytes(&read_file(path)?).map_err(|e| with_path(e, path))
}

/// Reads a PLY file as a validated triangle mesh (polygons fan-triangulated, strict
/// [`TriMesh::new`]) and its named per-vertex properties.
pub fn read(path: impl AsRef<Path>) -> Result<(TriMesh, Props)> {
    read_with(path, &ReadOptions::default())
}

/// As [`read`] with options (explicit vertex welding). With welding, each welded vertex takes
/// the property values of its first (lowest-index) file vertex.
pub fn read_with(path: impl AsRef<Path>, opts: &ReadOptions) -> Result<(TriMesh, Props)> {
    let mut d = read_data(path)?;
    let (m, map) = d.to_tri_mapped(opts)?;
    if let Some(map) = map {
        for (_, v) in &mut d.props {
            *v = remap_first(v, &map, m.n_vertices());
        }
    }
    Ok((m, d.props))
}

/// Reads a PLY file as a polygon mesh (or point set: no faces) and its named properties.
pub fn read_poly(path: impl AsRef<Path>) -> Result<(PolyMesh, Props)> {
    let d = read_data(path)?;
    Ok((d.to_poly(), d.props))
}

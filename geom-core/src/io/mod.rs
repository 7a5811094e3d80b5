//! Mesh files (GEOM-CORE.md §3.5): Wavefront OBJ ([`obj`]), PLY ([`ply`], ASCII and binary,
//! meshes or point sets with named per-vertex attributes), OFF ([`off`], read only), time-sampled
//! USD text for animated meshes ([`usd`], write only), format
//! detection ([`read_any`]) and numbered OBJ frame sequences ([`frame_path`],
//! [`read_obj_sequence`], [`write_obj_frame`]).
//!
//! # Conventions
//! - Readers are strict about what is malformed and tolerant about what real exporters write
//!   (see each module). They never panic on any input, including random bytes: every problem is
//!   an [`Error::Parse`](crate::Error::Parse) naming the format, the 1-based line (text) or the
//!   element index and byte offset (binary PLY, `line` = 0), and what is wrong. Counts declared
//!   in a header never drive an allocation larger than the bytes actually present.
//! - Readers return what the file holds (`PolyMesh`, format-specific data) or, through the
//!   `*_tri` / `ply::read` functions, a [`TriMesh`](crate::mesh::TriMesh) built with the strict
//!   `TriMesh::new` after fan triangulation. Nothing is repaired silently: welding duplicate
//!   vertices is the explicit [`ReadOptions::weld`].
//! - Writers take a borrowed [`MeshOut`] and validate it first, so they never produce a file that
//!   the readers refuse; numbers are the shortest text that parses back to the same f64, so a
//!   write/read round trip is exact.
//! - File errors: an operating-system failure stays [`Error::Io`](crate::Error::Io) with its
//!   `ErrorKind` (so `NotFound` can be matched) and gets the path in its message; parse errors
//!   from file readers get ` (in <path>)` appended to their message.

mod fmt;
mod fs;
mod out;
mod sequence;
mod sniff;
mod text;
mod tri;

pub mod gltf;
pub mod obj;
pub mod off;
pub mod ply;
pub mod usd;

pub use out::{Faces, MeshOut, Positions};
pub use ply::{Encoding, PlyData};
pub use sequence::{frame_path, read_obj_sequence, write_obj_frame};
pub use sniff::{read_any, sniff, MeshFormat};

/// Options of the `*_with` readers that build a [`TriMesh`](crate::mesh::TriMesh).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ReadOptions {
    /// Merge vertices closer than this distance (m) before validation, e.g. for OBJ exports
    /// that split vertices at UV seams or per face ([`crate::mesh::weld`]: greedy, in index order;
    /// triangles that collapse are dropped with their UVs). `None` (the default) keeps the file's
    /// vertices as they are: welding changes vertex numbering, so it is never done silently.
    pub weld: Option<f64>,
}

//! OFF (Object File Format, Geomview), as used by many geometry data sets (Princeton shape
//! benchmark, ModelNet, CGAL). Read only.
//!
//! # What the reader accepts
//! - A header keyword `OFF` with optional prefixes `ST` (texture coordinates), `C` (colours),
//!   `N` (normals), in that order: `OFF`, `COFF`, `NOFF`, `CNOFF`, `STOFF`, `STCNOFF` … The
//!   per-vertex extras they announce are ignored: only the first three numbers of a vertex line
//!   are read. `4OFF`, `nOFF` (other dimensions) and `OFF BINARY` are refused with a clear error.
//! - The counts `n_vertices n_faces n_edges` (edges ignored, may be absent) on the header line
//!   itself or on the next non-comment line.
//! - Then one vertex per line and one face per line: `n i0 … i(n−1)` followed by optional colour
//!   values, which are ignored.
//! - `#` comments (whole-line and trailing), blank lines, CRLF, tabs, a missing final newline,
//!   a leading UTF-8 byte-order mark.
//!
//! # Errors
//! [`Error::Parse`](crate::Error::Parse) with format `"OFF"`, the 1-based line and what is
//! wrong: missing or unknown header, bad counts, bad or non-finite numbers, a vertex line with
//! fewer than 3 numbers, a face with fewer than 3 vertices or fewer indices than it declares,
//! an index out of range, the file ending before the declared counts, non-blank data after the
//! last face.

use std::path::Path;

use crate::error::{Error, Result};
use crate::graph::Ragged;
use crate::math::Pt3;
use crate::mesh::{PolyMesh, TriMesh};

use super::fs::{read_file, with_path};
use super::text::{as_str, lines, show, strip_bom, tokens};
use super::tri::{build_tri, SourceUv};
use super::ReadOptions;

fn err(line: usize, msg: impl Into<String>) -> Error {
    Error::Parse { format: "OFF", line, msg: msg.into() }
}

/// Non-blank lines with comments removed, as `(line number, tokens)`.
struct Lines<'a, I: Iterator<Item = (usize, &'a [u8])>> {
    it: I,
    last: usize,
}

impl<'a, I: Iterator<Item = (usize, &'a [u8])>> Lines<'a, I> {
    fn next(&mut self) -> Option<(usize, Vec<&'a [u8]>)> {
        for (n, l) in self.it.by_ref() {
            self.last = n;
            let code = match l.iter().position(|&b| b == b'#') {
                Some(c) => &l[..c],
                None => l,
            };
            let t: Vec<&[u8]> = tokens(code).collect();
            if !t.is_empty() {
                return Some((n, t));
            }
        }
        None
    }
}

/// Does the keyword end in "OFF" with only `ST`, `C`, `N` before it (in that order)?
fn header_keyword(t: &[u8]) -> Option<Result<()>> {
    let prefix = t.strip_suffix(b"OFF")?;
    let mut p = prefix;
    for opt in [&b"ST"[..], b"C", b"N"] {
        if let Some(r) = p.strip_prefix(opt) {
            p = r;
        }
    }
    if p.is_empty() {
        Some(Ok(()))
    } else if p.ends_with(b"4") || p.ends_with(b"n") {
        Some(Err(err(0, format!("'{}': only 3-D OFF is supported (no 4OFF / nOFF)", show(t)))))
    } else {
        None
    }
}

fn count(t: &[u8], line: usize, what: &str) -> Result<usize> {
    as_str(t).and_then(|s| s.parse().ok()).ok_or_else(|| err(line, format!("bad {what} count '{}'", show(t))))
}

/// Parses OFF text (as bytes) into a polygon mesh.
pub fn parse(data: &[u8]) -> Result<PolyMesh> {
    let mut ls = Lines { it: lines(strip_bom(data)), last: 0 };
    let Some((hl, head)) = ls.next() else {
        return Err(err(1, "empty file: expected an 'OFF' header"));
    };
    match header_keyword(head[0]) {
        Some(Ok(())) => {}
        Some(Err(Error::Parse { format, msg, .. })) => return Err(Error::Parse { format, line: hl, msg }),
        Some(Err(e)) => return Err(e),
        None => return Err(err(hl, format!("expected an OFF header (OFF, COFF, NOFF, …), found '{}'", show(head[0])))),
    }
    let mut rest = &head[1..];
    if rest.first() == Some(&&b"BINARY"[..]) {
        return Err(err(hl, "binary OFF is not supported"));
    }
    let owned;
    let cl = if rest.is_empty() {
        let Some((cl, t)) = ls.next() else {
            return Err(err(ls.last, "file ends before the vertex/face counts"));
        };
        owned = t;
        rest = &owned;
        cl
    } else {
        hl
    };
    if rest.len() < 2 {
        return Err(err(cl, "expected 'n_vertices n_faces [n_edges]'"));
    }
    let nv = count(rest[0], cl, "vertex")?;
    let nf = count(rest[1], cl, "face")?;
    if rest.len() > 2 {
        count(rest[2], cl, "edge")?;
    }
    if nv > u32::MAX as usize {
        return Err(err(cl, format!("{nv} vertices do not fit u32 indices")));
    }
    // Declared counts are not trusted for allocation: a vertex line has at least 6 bytes.
    let mut positions = Vec::with_capacity(nv.min(data.len() / 6));
    for i in 0..nv {
        let Some((l, t)) = ls.next() else {
            return Err(err(ls.last, format!("file ends at vertex {i} of {nv}")));
        };
        if t.len() < 3 {
            return Err(err(l, format!("vertex {i} has {} numbers, expected at least 3", t.len())));
        }
        let mut x = [0.0; 3];
        for k in 0..3 {
            x[k] = as_str(t[k])
                .and_then(|s| s.parse::<f64>().ok())
                .filter(|v| v.is_finite())
                .ok_or_else(|| err(l, format!("vertex {i}: bad number '{}'", show(t[k]))))?;
        }
        positions.push(Pt3::new(x[0], x[1], x[2]));
    }
    let mut faces = Ragged::new();
    faces.offsets.reserve(nf.min(data.len() / 8));
    for i in 0..nf {
        let Some((l, t)) = ls.next() else {
            return Err(err(ls.last, format!("file ends at face {i} of {nf}")));
        };
        let n = count(t[0], l, "face vertex")?;
        if n < 3 {
            return Err(err(l, format!("face {i} has {n} vertices; at least 3 are needed")));
        }
        if t.len() - 1 < n {
            return Err(err(l, format!("face {i} declares {n} vertices but lists {}", t.len() - 1)));
        }
        for &s in &t[1..=n] {
            let v: u64 = as_str(s)
                .and_then(|s| s.parse().ok())
                .ok_or_else(|| err(l, format!("face {i}: bad vertex index '{}'", show(s))))?;
            if v >= nv as u64 {
                return Err(err(l, format!("face {i}: vertex index {v} out of range ({nv} vertices)")));
            }
            faces.items.push(v as u32);
        }
        if faces.items.len() > u32::MAX as usize {
            return Err(err(l, "more face corners than u32 offsets can hold"));
        }
        faces.offsets.push(faces.items.len() as u32);
    }
    if let Some((l, t)) = ls.next() {
        return Err(err(
            l,
            format!("data after the last face ('{}'): do the header counts match the body?", show(t[0])),
        ));
    }
    Ok(PolyMesh { positions, faces, uv: None })
}

/// Reads an OFF file as a polygon mesh; errors name the line and the path.
pub fn read(path: impl AsRef<Path>) -> Result<PolyMesh> {
    let path = path.as_ref();
    parse(&read_file(path)?).map_err(|e| with_path(e, path))
}

/// Reads an OFF file as a validated triangle mesh (fan triangulation, strict `TriMesh::new`,
/// welding only if `opts` asks).
pub fn read_tri_with(path: impl AsRef<Path>, opts: &ReadOptions) -> Result<TriMesh> {
    let m = read(path)?;
    build_tri(m.positions, &m.faces, SourceUv::None, opts)
}

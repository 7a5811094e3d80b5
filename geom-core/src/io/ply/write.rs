//! The PLY writer: meshes ([`write`]) and point sets ([`write_points`]) with named per-vertex
//! properties, ASCII or binary.

use std::fmt::Write as _;
use std::io::Write;
use std::path::Path;

use crate::error::{Error, Result};
use crate::math::{Pt2, Vec3};
use crate::mesh::Uv;

use super::super::fmt::{push_f32, push_f64};
use super::super::fs::write_file;
use super::super::out::{Faces, MeshOut, Positions};

/// Body encoding of a written PLY file.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Encoding {
    /// Text; numbers are the shortest round-trip text of their type.
    Ascii,
    /// Binary, little-endian (the usual choice: compact and exact).
    #[default]
    BinaryLittleEndian,
    /// Binary, big-endian.
    BinaryBigEndian,
}

/// A named per-vertex property to write (one entry per vertex).
///
/// Naming: `F64` → one `double` property `name`; `Vec3` → three `double` properties `name_x`,
/// `name_y`, `name_z`; `Rgb` → three `uchar` properties, `red green blue` (what viewers show as
/// vertex colour) when the name is `"color"` or `"colour"`, else `name_red`, `name_green`,
/// `name_blue`.
#[derive(Clone, Copy, Debug)]
pub enum PlyData<'a> {
    /// A scalar per vertex.
    F64(&'a [f64]),
    /// A 3-vector per vertex.
    Vec3(&'a [Vec3]),
    /// An 8-bit colour per vertex.
    Rgb(&'a [[u8; 3]]),
}

impl PlyData<'_> {
    fn len(&self) -> usize {
        match self {
            PlyData::F64(v) => v.len(),
            PlyData::Vec3(v) => v.len(),
            PlyData::Rgb(v) => v.len(),
        }
    }
}

/// One written vertex column.
#[derive(Clone, Copy)]
enum Src<'a> {
    Pos(Positions<'a>, usize),
    Normal(&'a [Vec3], usize),
    Uv(&'a [Pt2], usize),
    F64(&'a [f64]),
    Vec3(&'a [Vec3], usize),
    Rgb(&'a [[u8; 3]], usize),
}

#[derive(Clone, Copy, PartialEq)]
enum Ty {
    U8,
    F32,
    F64,
}

struct Column<'a> {
    name: String,
    ty: Ty,
    src: Src<'a>,
}

/// The vertex columns, with names validated (non-empty, no whitespace, unique).
fn columns<'a>(
    positions: Positions<'a>,
    normals: Option<&'a [Vec3]>,
    uv: Option<&'a [Pt2]>,
    props: &[(&str, PlyData<'a>)],
) -> Result<Vec<Column<'a>>> {
    let n = positions.len();
    let pos_ty = match positions {
        Positions::F64(_) => Ty::F64,
        Positions::F32(_) => Ty::F32,
    };
    let mut cols = Vec::new();
    for (k, a) in ["x", "y", "z"].iter().enumerate() {
        cols.push(Column { name: a.to_string(), ty: pos_ty, src: Src::Pos(positions, k) });
    }
    if let Some(nr) = normals {
        for (k, a) in ["nx", "ny", "nz"].iter().enumerate() {
            cols.push(Column { name: a.to_string(), ty: Ty::F64, src: Src::Normal(nr, k) });
        }
    }
    if let Some(uv) = uv {
        for (k, a) in ["u", "v"].iter().enumerate() {
            cols.push(Column { name: a.to_string(), ty: Ty::F64, src: Src::Uv(uv, k) });
        }
    }
    for (name, d) in props {
        if name.is_empty() || name.bytes().any(|b| b.is_ascii_whitespace() || !b.is_ascii_graphic()) {
            return Err(Error::InvalidParameter(format!(
                "PLY property name '{name}' must be non-empty printable ASCII without spaces"
            )));
        }
        if d.len() != n {
            return Err(Error::DimensionMismatch { what: "PLY per-vertex property", expected: n, got: d.len() });
        }
        match *d {
            PlyData::F64(v) => {
                if v.iter().any(|x| !x.is_finite()) {
                    // ASCII could not express NaN portably; keep binary and ASCII consistent.
                    return Err(Error::InvalidParameter(format!("PLY property '{name}' has a non-finite value")));
                }
                cols.push(Column { name: name.to_string(), ty: Ty::F64, src: Src::F64(v) });
            }
            PlyData::Vec3(v) => {
                if v.iter().any(|x| x.iter().any(|c| !c.is_finite())) {
                    return Err(Error::InvalidParameter(format!("PLY property '{name}' has a non-finite value")));
                }
                for (k, a) in ["x", "y", "z"].iter().enumerate() {
                    cols.push(Column { name: format!("{name}_{a}"), ty: Ty::F64, src: Src::Vec3(v, k) });
                }
            }
            PlyData::Rgb(v) => {
                let standard = *name == "color" || *name == "colour";
                for (k, a) in ["red", "green", "blue"].iter().enumerate() {
                    let name = if standard { a.to_string() } else { format!("{name}_{a}") };
                    cols.push(Column { name, ty: Ty::U8, src: Src::Rgb(v, k) });
                }
            }
        }
    }
    for (i, c) in cols.iter().enumerate() {
        if cols[..i].iter().any(|d| d.name == c.name) {
            return Err(Error::InvalidParameter(format!("PLY property '{}' would be written twice", c.name)));
        }
    }
    Ok(cols)
}

/// Value of column `c` at vertex `i`, with its written type.
fn value(c: &Column, i: usize) -> f64 {
    match c.src {
        Src::Pos(p, k) => p.get(i)[k],
        Src::Normal(v, k) | Src::Vec3(v, k) => v[i][k],
        Src::Uv(v, k) => v[i][k],
        Src::F64(v) => v[i],
        Src::Rgb(v, k) => v[i][k] as f64,
    }
}

/// Output buffer that knows the encoding.
struct Out<'w> {
    w: &'w mut dyn Write,
    enc: Encoding,
    text: String,
    bin: Vec<u8>,
}

impl Out<'_> {
    fn spill(&mut self, force: bool) -> Result<()> {
        if force || self.text.len() + self.bin.len() > 1 << 16 {
            self.w.write_all(self.text.as_bytes())?;
            self.w.write_all(&self.bin)?;
            self.text.clear();
            self.bin.clear();
        }
        Ok(())
    }

    fn sep(&mut self, first: bool) {
        if self.enc == Encoding::Ascii && !first {
            self.text.push(' ');
        }
    }

    fn f64(&mut self, x: f64, first: bool) {
        self.sep(first);
        match self.enc {
            Encoding::Ascii => push_f64(&mut self.text, x),
            Encoding::BinaryLittleEndian => self.bin.extend_from_slice(&x.to_le_bytes()),
            Encoding::BinaryBigEndian => self.bin.extend_from_slice(&x.to_be_bytes()),
        }
    }

    fn f32(&mut self, x: f32, first: bool) {
        self.sep(first);
        match self.enc {
            Encoding::Ascii => push_f32(&mut self.text, x),
            Encoding::BinaryLittleEndian => self.bin.extend_from_slice(&x.to_le_bytes()),
            Encoding::BinaryBigEndian => self.bin.extend_from_slice(&x.to_be_bytes()),
        }
    }

    fn u8(&mut self, x: u8, first: bool) {
        self.sep(first);
        match self.enc {
            // `write!` into a String cannot fail.
            Encoding::Ascii => {
                let _ = write!(self.text, "{x}");
            }
            _ => self.bin.push(x),
        }
    }

    fn u32(&mut self, x: u32, first: bool) {
        self.sep(first);
        match self.enc {
            Encoding::Ascii => {
                let _ = write!(self.text, "{x}");
            }
            Encoding::BinaryLittleEndian => self.bin.extend_from_slice(&x.to_le_bytes()),
            Encoding::BinaryBigEndian => self.bin.extend_from_slice(&x.to_be_bytes()),
        }
    }

    fn end_line(&mut self) {
        if self.enc == Encoding::Ascii {
            self.text.push('\n');
        }
    }
}

/// Writes header and body. `faces`/`corner_uv` are `None` for a point set.
fn write_to(
    w: &mut dyn Write,
    enc: Encoding,
    cols: &[Column],
    n_vertices: usize,
    faces: Option<Faces>,
    corner_uv: Option<&[[Pt2; 3]]>,
) -> Result<()> {
    let mut h = String::new();
    let fmt = match enc {
        Encoding::Ascii => "ascii",
        Encoding::BinaryLittleEndian => "binary_little_endian",
        Encoding::BinaryBigEndian => "binary_big_endian",
    };
    let _ = writeln!(h, "ply\nformat {fmt} 1.0\ncomment written by geom-core\nelement vertex {n_vertices}");
    for c in cols {
        let t = match c.ty {
            Ty::U8 => "uchar",
            Ty::F32 => "float",
            Ty::F64 => "double",
        };
        let _ = writeln!(h, "property {t} {}", c.name);
    }
    // Count type uchar unless a face is longer than 255; index type int (what most tools expect)
    // unless indices exceed i32::MAX.
    let (mut wide_count, wide_index) = (false, n_vertices > i32::MAX as usize + 1);
    if let Some(f) = faces {
        wide_count = (0..f.len()).any(|i| f.row(i).len() > 255);
        let _ = writeln!(h, "element face {}", f.len());
        let _ = writeln!(
            h,
            "property list {} {} vertex_indices",
            if wide_count { "uint" } else { "uchar" },
            if wide_index { "uint" } else { "int" }
        );
        if corner_uv.is_some() {
            h.push_str("property list uchar double texcoord\n");
        }
    }
    h.push_str("end_header\n");
    let mut o = Out { w, enc, text: h, bin: Vec::new() };
    o.spill(true)?;
    for i in 0..n_vertices {
        for (k, c) in cols.iter().enumerate() {
            let x = value(c, i);
            match c.ty {
                // Exact: these columns hold f32 or u8 values widened to f64.
                Ty::F32 => o.f32(x as f32, k == 0),
                Ty::U8 => o.u8(x as u8, k == 0),
                Ty::F64 => o.f64(x, k == 0),
            }
        }
        o.end_line();
        o.spill(false)?;
    }
    if let Some(f) = faces {
        for i in 0..f.len() {
            let row = f.row(i);
            if wide_count {
                o.u32(row.len() as u32, true);
            } else {
                o.u8(row.len() as u8, true);
            }
            for &v in row {
                o.u32(v, false);
            }
            if let Some(uv) = corner_uv {
                o.u8(6, false);
                for p in &uv[i] {
                    o.f64(p.x, false);
                    o.f64(p.y, false);
                }
            }
            o.end_line();
            o.spill(false)?;
        }
    }
    o.spill(true)
}

/// Per-vertex UVs (written as columns) and per-corner UVs (written as face lists).
type UvParts<'a> = (Option<&'a [Pt2]>, Option<&'a [[Pt2; 3]]>);

/// Checks `m` and splits its UVs into per-vertex and per-corner parts.
fn mesh_parts<'a>(m: &MeshOut<'a>) -> Result<UvParts<'a>> {
    m.validate()?;
    Ok(match m.uv {
        None => (None, None),
        Some(Uv::PerVertex(v)) => (Some(v.as_slice()), None),
        Some(Uv::PerCorner(c)) => (None, Some(c.as_slice())),
    })
}

/// Writes a mesh to `path` with extra named per-vertex properties. Errors: those of
/// [`MeshOut::validate`], [`Error::DimensionMismatch`] for a property of the wrong length,
/// [`Error::InvalidParameter`] for a bad or duplicate property name or a non-finite value, I/O
/// errors naming the path.
pub fn write(path: impl AsRef<Path>, m: &MeshOut, props: &[(&str, PlyData)], enc: Encoding) -> Result<()> {
    let (uv, corner) = mesh_parts(m)?;
    let cols = columns(m.positions, m.normals, uv, props)?;
    write_file(path.as_ref(), |w| write_to(w, enc, &cols, m.positions.len(), Some(m.faces), corner))
}

/// The bytes [`write`] would write.
pub fn to_bytes(m: &MeshOut, props: &[(&str, PlyData)], enc: Encoding) -> Result<Vec<u8>> {
    let (uv, corner) = mesh_parts(m)?;
    let cols = columns(m.positions, m.normals, uv, props)?;
    let mut out = Vec::new();
    write_to(&mut out, enc, &cols, m.positions.len(), Some(m.faces), corner)?;
    Ok(out)
}

/// Writes a point set (a `vertex` element only) with named per-vertex properties, e.g.
/// particles with velocity and radius. Errors as [`write`]; non-finite positions are refused
/// ([`Error::NonFiniteVertex`]).
pub fn write_points(path: impl AsRef<Path>, p: Positions, props: &[(&str, PlyData)], enc: Encoding) -> Result<()> {
    if let Some(v) = p.first_non_finite() {
        return Err(Error::NonFiniteVertex { vertex: v as u32 });
    }
    let cols = columns(p, None, None, props)?;
    write_file(path.as_ref(), |w| write_to(w, enc, &cols, p.len(), None, None))
}

/// The bytes [`write_points`] would write.
pub fn points_to_bytes(p: Positions, props: &[(&str, PlyData)], enc: Encoding) -> Result<Vec<u8>> {
    if let Some(v) = p.first_non_finite() {
        return Err(Error::NonFiniteVertex { vertex: v as u32 });
    }
    let cols = columns(p, None, None, props)?;
    let mut out = Vec::new();
    write_to(&mut out, enc, &cols, p.len(), None, None)?;
    Ok(out)
}

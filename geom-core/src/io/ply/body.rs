//! The PLY body: element instances in header order, from ASCII lines or binary bytes of either
//! endianness, into [`PlyMesh`].
//!
//! One generic walk over the header ([`read`]) drives a [`Body`] that yields typed values; the
//! two encodings differ only in how a value is fetched and what "the end of an instance" means
//! (ASCII: the end of its line; binary: nothing). Declared counts are never trusted for
//! allocation: capacities are capped by the bytes left in the file.

use crate::error::{Error, Result};
use crate::graph::Ragged;
use crate::math::{Pt2, Pt3};

use super::super::text::{as_str, show};
use super::header::{Element, Format, Header, Kind, Scalar};
use super::PlyMesh;

/// Where a value is read: element, instance, property (for messages).
#[derive(Clone, Copy)]
pub(crate) struct At<'a> {
    el: &'a str,
    i: u64,
    prop: &'a str,
}

/// A source of typed values, one element instance at a time.
pub(crate) trait Body {
    /// Bytes not yet consumed.
    fn remaining(&self) -> usize;
    /// Lower bound of the bytes one instance of `el` occupies (for capping allocations).
    fn min_instance_bytes(&self, el: &Element) -> usize;
    /// Starts instance `i` of `el`.
    fn begin(&mut self, el: &Element, i: u64) -> Result<()>;
    /// Reads one value of type `ty`.
    fn value(&mut self, ty: Scalar, at: At) -> Result<f64>;
    /// Ends the current instance.
    fn end(&mut self, el: &Element, i: u64) -> Result<()>;
    /// Skips all instances of `el` at once if the encoding allows (fixed-size binary); returns
    /// whether it did.
    fn skip_all(&mut self, el: &Element) -> Result<bool>;
    /// Checks that nothing but a final newline follows the last element.
    fn finish(&mut self) -> Result<()>;
}

fn perr(line: usize, msg: String) -> Error {
    Error::Parse { format: "PLY", line, msg }
}

// ---------------------------------------------------------------------------------------------
// ASCII

/// ASCII body: one element instance per line (blank lines are skipped), values separated by
/// whitespace. Errors name the 1-based file line.
pub(crate) struct Ascii<'a> {
    data: &'a [u8],
    pos: usize,
    line: usize,
    cur: &'a [u8],
}

impl<'a> Ascii<'a> {
    pub(crate) fn new(data: &'a [u8], body: usize, header_lines: usize) -> Self {
        Self { data, pos: body.min(data.len()), line: header_lines, cur: &[] }
    }

    /// Next line (without LF/CR) or `None` at the end.
    fn next_line(&mut self) -> Option<&'a [u8]> {
        if self.pos >= self.data.len() {
            return None;
        }
        let rest = &self.data[self.pos..];
        let (l, adv) = match rest.iter().position(|&b| b == b'\n') {
            Some(i) => (&rest[..i], i + 1),
            None => (rest, rest.len()),
        };
        self.pos += adv;
        self.line += 1;
        Some(l)
    }

    fn token(&mut self) -> Option<&'a [u8]> {
        let s = self.cur.trim_ascii_start();
        if s.is_empty() {
            self.cur = s;
            return None;
        }
        let end = s.iter().position(|b| b.is_ascii_whitespace()).unwrap_or(s.len());
        self.cur = &s[end..];
        Some(&s[..end])
    }
}

/// Integer range of each integer type.
fn int_range(ty: Scalar) -> (i64, i64) {
    match ty {
        Scalar::I8 => (i8::MIN as i64, i8::MAX as i64),
        Scalar::U8 => (0, u8::MAX as i64),
        Scalar::I16 => (i16::MIN as i64, i16::MAX as i64),
        Scalar::U16 => (0, u16::MAX as i64),
        Scalar::I32 => (i32::MIN as i64, i32::MAX as i64),
        Scalar::U32 => (0, u32::MAX as i64),
        Scalar::F32 | Scalar::F64 => (i64::MIN, i64::MAX),
    }
}

impl Body for Ascii<'_> {
    fn remaining(&self) -> usize {
        self.data.len() - self.pos + self.cur.len()
    }

    fn min_instance_bytes(&self, el: &Element) -> usize {
        // Each value is at least one character and one separator (the line end counts).
        2 * el.props.len()
    }

    fn begin(&mut self, el: &Element, i: u64) -> Result<()> {
        loop {
            let Some(l) = self.next_line() else {
                return Err(perr(
                    self.line,
                    format!("file ends before element '{}' #{i} (the header declares {} of them)", el.name, el.count),
                ));
            };
            if !l.trim_ascii().is_empty() {
                self.cur = l;
                return Ok(());
            }
        }
    }

    fn value(&mut self, ty: Scalar, at: At) -> Result<f64> {
        let line = self.line;
        let Some(t) = self.token() else {
            return Err(perr(
                line,
                format!("element '{}' #{} has too few values: property '{}' is missing", at.el, at.i, at.prop),
            ));
        };
        let bad = || {
            perr(
                line,
                format!("element '{}' #{}, property '{}': bad {} '{}'", at.el, at.i, at.prop, ty.name(), show(t)),
            )
        };
        let s = as_str(t).ok_or_else(bad)?;
        match ty {
            Scalar::F32 => s.parse::<f32>().map(f64::from).map_err(|_| bad()),
            Scalar::F64 => s.parse::<f64>().map_err(|_| bad()),
            _ => {
                let v: i64 = s.parse().map_err(|_| bad())?;
                let (lo, hi) = int_range(ty);
                if v < lo || v > hi {
                    return Err(perr(
                        line,
                        format!(
                            "element '{}' #{}, property '{}': {v} is out of range for {}",
                            at.el,
                            at.i,
                            at.prop,
                            ty.name()
                        ),
                    ));
                }
                Ok(v as f64)
            }
        }
    }

    fn end(&mut self, el: &Element, i: u64) -> Result<()> {
        let line = self.line;
        if let Some(t) = self.token() {
            return Err(perr(
                line,
                format!("element '{}' #{i} has more values than its properties take (extra '{}')", el.name, show(t)),
            ));
        }
        Ok(())
    }

    fn skip_all(&mut self, _el: &Element) -> Result<bool> {
        Ok(false)
    }

    fn finish(&mut self) -> Result<()> {
        while let Some(l) = self.next_line() {
            if !l.trim_ascii().is_empty() {
                return Err(perr(
                    self.line,
                    format!(
                        "data after the last element ('{}'): do the header counts match the body?",
                        show(l.trim_ascii())
                    ),
                ));
            }
        }
        Ok(())
    }
}

// ---------------------------------------------------------------------------------------------
// Binary

/// Binary body of either endianness. Errors have `line` 0 and name the element, instance,
/// property and byte offset.
pub(crate) struct Binary<'a> {
    data: &'a [u8],
    pos: usize,
    big: bool,
}

impl<'a> Binary<'a> {
    pub(crate) fn new(data: &'a [u8], body: usize, big: bool) -> Self {
        Self { data, pos: body.min(data.len()), big }
    }
}

impl Body for Binary<'_> {
    fn remaining(&self) -> usize {
        self.data.len() - self.pos
    }

    fn min_instance_bytes(&self, el: &Element) -> usize {
        el.min_size()
    }

    fn begin(&mut self, _el: &Element, _i: u64) -> Result<()> {
        Ok(())
    }

    fn value(&mut self, ty: Scalar, at: At) -> Result<f64> {
        let n = ty.size();
        let Some(b) = self.data.get(self.pos..self.pos + n) else {
            return Err(perr(
                0,
                format!(
                    "truncated binary body: element '{}' #{}, property '{}' needs {n} bytes at byte offset {} but the file has {} bytes",
                    at.el,
                    at.i,
                    at.prop,
                    self.pos,
                    self.data.len()
                ),
            ));
        };
        self.pos += n;
        macro_rules! num {
            ($t:ty) => {{
                // `b` has exactly `size_of::<$t>()` bytes (taken above with ty.size()).
                let a = b.try_into().expect("slice of the type's size");
                (if self.big { <$t>::from_be_bytes(a) } else { <$t>::from_le_bytes(a) }) as f64
            }};
        }
        Ok(match ty {
            Scalar::I8 => b[0] as i8 as f64,
            Scalar::U8 => b[0] as f64,
            Scalar::I16 => num!(i16),
            Scalar::U16 => num!(u16),
            Scalar::I32 => num!(i32),
            Scalar::U32 => num!(u32),
            Scalar::F32 => num!(f32),
            Scalar::F64 => num!(f64),
        })
    }

    fn end(&mut self, _el: &Element, _i: u64) -> Result<()> {
        Ok(())
    }

    fn skip_all(&mut self, el: &Element) -> Result<bool> {
        let Some(size) = el.fixed_size() else { return Ok(false) };
        let total = (size as u64).checked_mul(el.count).filter(|&t| t <= self.remaining() as u64);
        match total {
            Some(t) => {
                self.pos += t as usize;
                Ok(true)
            }
            None => {
                // Element index of the first instance that does not fit.
                let fit = self.remaining().checked_div(size).map_or(el.count, |k| k as u64);
                Err(perr(
                    0,
                    format!(
                        "truncated binary body: element '{}' #{fit} ({size} bytes each, {} declared) starts at byte offset {} but the file has {} bytes",
                        el.name,
                        el.count,
                        self.pos as u64 + fit * size as u64,
                        self.data.len()
                    ),
                ))
            }
        }
    }

    fn finish(&mut self) -> Result<()> {
        let rest = &self.data[self.pos..];
        // A final newline after the binary body is written by some tools; anything else means
        // the header counts do not describe the body.
        if rest.is_empty() || rest == b"\n" || rest == b"\r\n" {
            Ok(())
        } else {
            Err(perr(
                0,
                format!(
                    "{} bytes after the last element at byte offset {}: do the header counts match the body?",
                    rest.len(),
                    self.pos
                ),
            ))
        }
    }
}

// ---------------------------------------------------------------------------------------------
// The walk

/// A list length or an index: a non-negative integer that fits u32.
fn to_u32(x: f64, what: &str, at: At, line_hint: usize) -> Result<u32> {
    if x >= 0.0 && x <= u32::MAX as f64 && x.fract() == 0.0 {
        Ok(x as u32)
    } else {
        Err(perr(
            line_hint,
            format!("element '{}' #{}, property '{}': {what} {x} is not a valid count/index", at.el, at.i, at.prop),
        ))
    }
}

/// Reads (and drops) every value of a list property.
fn skip_list<B: Body>(b: &mut B, count: Scalar, item: Scalar, at: At, line: usize) -> Result<()> {
    let n = to_u32(b.value(count, at)?, "list length", at, line)?;
    for _ in 0..n {
        b.value(item, at)?;
    }
    Ok(())
}

/// Reads the body described by `h` from `b`.
pub(crate) fn read<B: Body>(b: &mut B, h: &Header, line_of: impl Fn(&B) -> usize) -> Result<PlyMesh> {
    let mut m = PlyMesh {
        positions: Vec::new(),
        faces: Ragged::new(),
        props: Vec::new(),
        corner_uv: None,
        comments: h.comments.clone(),
        obj_info: h.obj_info.clone(),
    };
    let n_vertices = h.elements.iter().find(|e| e.name == "vertex").map_or(0, |e| e.count);
    if n_vertices > u32::MAX as u64 {
        return Err(perr(0, format!("{n_vertices} vertices do not fit u32 indices")));
    }
    for el in &h.elements {
        // Capacity a truthful file can need, never more than the bytes left allow.
        let cap = (el.count as usize).min(b.remaining() / b.min_instance_bytes(el).max(1));
        match el.name.as_str() {
            "vertex" => read_vertices(b, el, cap, &mut m, &line_of)?,
            "face" => read_faces(b, el, cap, n_vertices as u32, &mut m, &line_of)?,
            _ => {
                if !b.skip_all(el)? {
                    for i in 0..el.count {
                        b.begin(el, i)?;
                        for p in &el.props {
                            let at = At { el: &el.name, i, prop: &p.name };
                            match p.kind {
                                Kind::Scalar(s) => {
                                    b.value(s, at)?;
                                }
                                Kind::List { count, item } => skip_list(b, count, item, at, line_of(b))?,
                            }
                        }
                        b.end(el, i)?;
                    }
                }
            }
        }
    }
    b.finish()?;
    Ok(m)
}

/// Where each vertex property's value goes.
#[derive(Clone, Copy)]
enum Slot {
    X(usize),
    Column(usize),
    List(Scalar, Scalar),
}

fn read_vertices<B: Body>(
    b: &mut B,
    el: &Element,
    cap: usize,
    m: &mut PlyMesh,
    line_of: &impl Fn(&B) -> usize,
) -> Result<()> {
    let mut slots = Vec::with_capacity(el.props.len());
    let mut has = [false; 3];
    for p in &el.props {
        let axis = ["x", "y", "z"].iter().position(|a| *a == p.name);
        slots.push(match (p.kind, axis) {
            (Kind::Scalar(_), Some(k)) => {
                has[k] = true;
                Slot::X(k)
            }
            (Kind::Scalar(_), None) => {
                m.props.push((p.name.clone(), Vec::with_capacity(cap)));
                Slot::Column(m.props.len() - 1)
            }
            (Kind::List { count, item }, _) => Slot::List(count, item),
        });
    }
    if let Some(k) = has.iter().position(|h| !h) {
        return Err(perr(0, format!("element 'vertex' has no scalar property '{}'", ["x", "y", "z"][k])));
    }
    m.positions.reserve(cap);
    for i in 0..el.count {
        b.begin(el, i)?;
        let mut x = [0.0; 3];
        for (p, slot) in el.props.iter().zip(&slots) {
            let at = At { el: "vertex", i, prop: &p.name };
            match (*slot, p.kind) {
                (Slot::X(k), Kind::Scalar(s)) => x[k] = b.value(s, at)?,
                (Slot::Column(c), Kind::Scalar(s)) => {
                    let v = b.value(s, at)?;
                    m.props[c].1.push(v);
                }
                (Slot::List(count, item), _) => skip_list(b, count, item, at, line_of(b))?,
                // Slots were built from the same properties' kinds.
                _ => unreachable!("slot kind matches property kind"),
            }
        }
        b.end(el, i)?;
        m.positions.push(Pt3::new(x[0], x[1], x[2]));
    }
    Ok(())
}

fn read_faces<B: Body>(
    b: &mut B,
    el: &Element,
    cap: usize,
    n_vertices: u32,
    m: &mut PlyMesh,
    line_of: &impl Fn(&B) -> usize,
) -> Result<()> {
    let vi = el.find("vertex_indices").or_else(|| el.find("vertex_index"));
    let Some(vi) = vi else {
        if el.count == 0 {
            return Ok(());
        }
        return Err(perr(0, "element 'face' has no list property 'vertex_indices' (or 'vertex_index')".into()));
    };
    match el.props[vi].kind {
        Kind::List { item, .. } if item.is_integer() => {}
        _ => return Err(perr(0, format!("face property '{}' must be a list of an integer type", el.props[vi].name))),
    }
    let tc = el.find("texcoord").filter(|&k| matches!(el.props[k].kind, Kind::List { .. }));
    m.faces.offsets.reserve(cap);
    let mut corner_uv: Vec<Pt2> = Vec::new();
    let mut face_tc: Vec<f64> = Vec::new();
    for i in 0..el.count {
        b.begin(el, i)?;
        let start = m.faces.items.len();
        face_tc.clear();
        for (k, p) in el.props.iter().enumerate() {
            let at = At { el: "face", i, prop: &p.name };
            match p.kind {
                Kind::Scalar(s) => {
                    b.value(s, at)?;
                }
                Kind::List { count, item } if k == vi => {
                    let line = line_of(b);
                    let n = to_u32(b.value(count, at)?, "list length", at, line)?;
                    if n < 3 {
                        return Err(perr(line, format!("face #{i} has {n} vertices; at least 3 are needed")));
                    }
                    for _ in 0..n {
                        let line = line_of(b);
                        let v = to_u32(b.value(item, at)?, "vertex index", at, line)?;
                        if v >= n_vertices {
                            return Err(perr(
                                line,
                                format!("face #{i} refers to vertex {v}, but there are {n_vertices} vertices"),
                            ));
                        }
                        m.faces.items.push(v);
                    }
                }
                Kind::List { count, item } if Some(k) == tc => {
                    let line = line_of(b);
                    let n = to_u32(b.value(count, at)?, "list length", at, line)?;
                    for _ in 0..n {
                        face_tc.push(b.value(item, at)?);
                    }
                }
                Kind::List { count, item } => skip_list(b, count, item, at, line_of(b))?,
            }
        }
        b.end(el, i)?;
        let n = m.faces.items.len() - start;
        if m.faces.items.len() > u32::MAX as usize {
            return Err(perr(line_of(b), "more face corners than u32 offsets can hold".into()));
        }
        m.faces.offsets.push(m.faces.items.len() as u32);
        if tc.is_some() {
            if face_tc.len() != 2 * n {
                return Err(perr(
                    line_of(b),
                    format!("face #{i}: 'texcoord' has {} values, expected 2 per vertex ({})", face_tc.len(), 2 * n),
                ));
            }
            corner_uv.extend(face_tc.chunks_exact(2).map(|c| Pt2::new(c[0], c[1])));
        }
    }
    if tc.is_some() {
        m.corner_uv = Some(corner_uv);
    }
    Ok(())
}

/// Parses a whole PLY file held in memory.
pub(crate) fn parse(data: &[u8]) -> Result<PlyMesh> {
    let h = super::header::parse(data)?;
    match h.format {
        Format::Ascii => {
            let mut b = Ascii::new(data, h.body, h.lines);
            read(&mut b, &h, |b: &Ascii| b.line)
        }
        Format::BinaryLittleEndian => read(&mut Binary::new(data, h.body, false), &h, |_: &Binary| 0),
        Format::BinaryBigEndian => read(&mut Binary::new(data, h.body, true), &h, |_: &Binary| 0),
    }
}

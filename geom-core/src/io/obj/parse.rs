//! The OBJ text parser: statements into [`ObjData`].
//!
//! Works on bytes, so a file with Latin-1 names or comments still loads; only the numbers must be
//! ASCII. See the module docs of [`super`] for the accepted grammar and what is ignored.

use crate::error::{Error, Result};
use crate::graph::Ragged;
use crate::math::{Pt2, Pt3, Vec3};
use crate::NONE;

use super::super::text::{as_str, show, strip_bom, tokens};
use super::ObjData;

/// Statements that are valid OBJ but carry nothing a polygon mesh keeps: grouping and naming
/// (`o g s mg usemtl mtllib maplib usemap lod`), display attributes (`bevel c_interp d_interp
/// shadow_obj trace_obj`), point/line elements (`p l`), and the free-form curve and surface
/// statements (`vp cstype deg bmat step curv curv2 surf parm trim hole scrv sp end con ctech
/// stech call csh`). They are skipped without looking at their arguments.
const IGNORED: &[&[u8]] = &[
    b"o",
    b"g",
    b"s",
    b"mg",
    b"usemtl",
    b"mtllib",
    b"maplib",
    b"usemap",
    b"lod",
    b"bevel",
    b"c_interp",
    b"d_interp",
    b"shadow_obj",
    b"trace_obj",
    b"p",
    b"l",
    b"vp",
    b"cstype",
    b"deg",
    b"bmat",
    b"step",
    b"curv",
    b"curv2",
    b"surf",
    b"parm",
    b"trim",
    b"hole",
    b"scrv",
    b"sp",
    b"end",
    b"con",
    b"ctech",
    b"stech",
    b"call",
    b"csh",
];

const FORMAT: &str = "OBJ";

fn err(line: usize, msg: impl Into<String>) -> Error {
    Error::Parse { format: FORMAT, line, msg: msg.into() }
}

fn trim_end(mut l: &[u8]) -> &[u8] {
    while let [rest @ .., last] = l {
        if last.is_ascii_whitespace() || *last == 0x0b {
            l = rest;
        } else {
            break;
        }
    }
    l
}

/// A finite f64 from a token.
fn number(t: &[u8], line: usize, what: &str) -> Result<f64> {
    let x: f64 = as_str(t)
        .and_then(|s| s.parse().ok())
        .ok_or_else(|| err(line, format!("bad number '{}' in '{what}' statement", show(t))))?;
    if !x.is_finite() {
        return Err(err(line, format!("non-finite number '{}' in '{what}' statement", show(t))));
    }
    Ok(x)
}

/// Index kinds for messages and the deferred range check.
const KIND: [&str; 3] = ["vertex", "texture coordinate", "normal"];

struct Parser {
    d: ObjData,
    corner_uv: Vec<u32>,
    corner_n: Vec<u32>,
    any_uv: bool,
    any_n: bool,
    /// Largest positive (1-based) index seen per kind and the line where it appeared: positive
    /// indices may refer forward, so they are range-checked once the whole file is read.
    max_ref: [(u64, usize); 3],
}

impl Parser {
    fn count(&self, kind: usize) -> usize {
        match kind {
            0 => self.d.positions.len(),
            1 => self.d.texcoords.len(),
            _ => self.d.normals.len(),
        }
    }

    /// 0-based index from a 1-based or negative (relative) OBJ index token.
    fn index(&mut self, t: &[u8], kind: usize, corner: &[u8], line: usize) -> Result<u32> {
        let i: i64 = as_str(t).and_then(|s| s.parse().ok()).ok_or_else(|| {
            err(line, format!("bad {} index '{}' in face vertex '{}'", KIND[kind], show(t), show(corner)))
        })?;
        let n = self.count(kind);
        if i == 0 {
            return Err(err(
                line,
                format!("{} index 0 in face vertex '{}' (OBJ indices start at 1)", KIND[kind], show(corner)),
            ));
        }
        if i > 0 {
            if i > u32::MAX as i64 {
                return Err(err(line, format!("{} index {i} out of range", KIND[kind])));
            }
            if i as u64 > self.max_ref[kind].0 {
                self.max_ref[kind] = (i as u64, line);
            }
            return Ok((i - 1) as u32);
        }
        let r = n as i64 + i;
        if r < 0 {
            return Err(err(
                line,
                format!("relative {} index {i} points before the first one ({n} defined so far)", KIND[kind]),
            ));
        }
        Ok(r as u32)
    }

    fn statement(&mut self, l: &[u8], line: usize) -> Result<()> {
        let mut toks = tokens(l);
        let Some(kw) = toks.next() else { return Ok(()) };
        match kw {
            b"v" => {
                let mut xyz = [0.0; 3];
                let mut n = 0;
                for t in toks {
                    let x = number(t, line, "v")?;
                    if n < 3 {
                        xyz[n] = x;
                    }
                    n += 1;
                }
                if !matches!(n, 3 | 4 | 6 | 7) {
                    return Err(err(line, format!("'v' needs 3, 4 (x y z w) or 6, 7 (with r g b) numbers, got {n}")));
                }
                self.d.positions.push(Pt3::new(xyz[0], xyz[1], xyz[2]));
            }
            b"vt" => {
                let mut uv = [0.0; 2];
                let mut n = 0;
                for t in toks {
                    let x = number(t, line, "vt")?;
                    if n < 2 {
                        uv[n] = x;
                    }
                    n += 1;
                }
                if !(1..=3).contains(&n) {
                    return Err(err(line, format!("'vt' needs 1 to 3 numbers, got {n}")));
                }
                self.d.texcoords.push(Pt2::new(uv[0], uv[1]));
            }
            b"vn" => {
                let mut xyz = [0.0; 3];
                let mut n = 0;
                for t in toks {
                    let x = number(t, line, "vn")?;
                    if n < 3 {
                        xyz[n] = x;
                    }
                    n += 1;
                }
                if n != 3 {
                    return Err(err(line, format!("'vn' needs 3 numbers, got {n}")));
                }
                self.d.normals.push(Vec3::new(xyz[0], xyz[1], xyz[2]));
            }
            b"f" | b"fo" => {
                let start = self.d.faces.items.len();
                for corner in toks {
                    let mut parts = corner.split(|&b| b == b'/');
                    // `split` yields at least one part.
                    let v = parts.next().unwrap_or_default();
                    let vt = parts.next().filter(|p| !p.is_empty());
                    let vn = parts.next().filter(|p| !p.is_empty());
                    if parts.next().is_some() {
                        return Err(err(
                            line,
                            format!("face vertex '{}' has more than 3 '/'-separated parts", show(corner)),
                        ));
                    }
                    if v.is_empty() {
                        return Err(err(line, format!("face vertex '{}' has no vertex index", show(corner))));
                    }
                    let vi = self.index(v, 0, corner, line)?;
                    let ti = match vt {
                        Some(t) => {
                            self.any_uv = true;
                            self.index(t, 1, corner, line)?
                        }
                        None => NONE,
                    };
                    let ni = match vn {
                        Some(t) => {
                            self.any_n = true;
                            self.index(t, 2, corner, line)?
                        }
                        None => NONE,
                    };
                    self.d.faces.items.push(vi);
                    self.corner_uv.push(ti);
                    self.corner_n.push(ni);
                }
                let n = self.d.faces.items.len() - start;
                if n < 3 {
                    return Err(err(line, format!("face has {n} vertices; at least 3 are needed")));
                }
                if self.d.faces.items.len() > u32::MAX as usize {
                    return Err(err(line, "more face corners than u32 offsets can hold"));
                }
                self.d.faces.offsets.push(self.d.faces.items.len() as u32);
            }
            k if IGNORED.contains(&k) => {}
            k => {
                return Err(err(line, format!("unknown statement '{}' (not an OBJ keyword)", show(k))));
            }
        }
        Ok(())
    }
}

/// Parses OBJ text (as bytes) into [`ObjData`]. Errors are [`Error::Parse`] with format `"OBJ"`
/// and the 1-based line of the offending statement (for a continued statement, its first line).
/// A leading UTF-8 byte-order mark is skipped.
pub fn parse(bytes: &[u8]) -> Result<ObjData> {
    let mut p = Parser {
        d: ObjData {
            positions: Vec::new(),
            texcoords: Vec::new(),
            normals: Vec::new(),
            faces: Ragged::new(),
            corner_texcoord: None,
            corner_normal: None,
        },
        corner_uv: Vec::new(),
        corner_n: Vec::new(),
        any_uv: false,
        any_n: false,
        max_ref: [(0, 0); 3],
    };
    // A statement continued with a trailing '\': its first line and the text gathered so far.
    let mut cont: Option<(usize, Vec<u8>)> = None;
    for (i, raw) in strip_bom(bytes).split(|&b| b == b'\n').enumerate() {
        let line = i + 1;
        let code = match raw.iter().position(|&b| b == b'#') {
            Some(c) => &raw[..c],
            None => raw,
        };
        let code = trim_end(code);
        if let Some(body) = code.strip_suffix(b"\\") {
            let c = cont.get_or_insert_with(|| (line, Vec::new()));
            c.1.extend_from_slice(body);
            c.1.push(b' ');
            continue;
        }
        match cont.take() {
            Some((start, mut buf)) => {
                buf.extend_from_slice(code);
                p.statement(&buf, start)?;
            }
            None => p.statement(code, line)?,
        }
    }
    if let Some((start, buf)) = cont {
        p.statement(&buf, start)?;
    }
    for (kind, name) in KIND.iter().enumerate() {
        let (max, line) = p.max_ref[kind];
        let n = p.count(kind);
        if max > n as u64 {
            return Err(err(line, format!("{name} index {max} out of range (the file defines {n})")));
        }
    }
    let Parser { mut d, corner_uv, corner_n, any_uv, any_n, .. } = p;
    d.corner_texcoord = any_uv.then_some(corner_uv);
    d.corner_normal = any_n.then_some(corner_n);
    Ok(d)
}

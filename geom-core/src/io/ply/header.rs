//! The PLY header: magic line, format, elements with their scalar and list properties, comments
//! and `obj_info` lines, up to `end_header`.

use crate::error::{Error, Result};

use super::super::text::{as_str, show, tokens};

/// Body encoding declared by the `format` line.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Format {
    Ascii,
    BinaryLittleEndian,
    BinaryBigEndian,
}

/// A PLY scalar type (both the classic names and the sized aliases are accepted).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Scalar {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    F32,
    F64,
}

impl Scalar {
    fn parse(t: &[u8]) -> Option<Scalar> {
        Some(match t {
            b"char" | b"int8" => Scalar::I8,
            b"uchar" | b"uint8" => Scalar::U8,
            b"short" | b"int16" => Scalar::I16,
            b"ushort" | b"uint16" => Scalar::U16,
            b"int" | b"int32" => Scalar::I32,
            b"uint" | b"uint32" => Scalar::U32,
            b"float" | b"float32" => Scalar::F32,
            b"double" | b"float64" => Scalar::F64,
            _ => return None,
        })
    }

    /// Size in bytes in a binary body.
    pub(crate) fn size(self) -> usize {
        match self {
            Scalar::I8 | Scalar::U8 => 1,
            Scalar::I16 | Scalar::U16 => 2,
            Scalar::I32 | Scalar::U32 | Scalar::F32 => 4,
            Scalar::F64 => 8,
        }
    }

    pub(crate) fn is_integer(self) -> bool {
        !matches!(self, Scalar::F32 | Scalar::F64)
    }

    /// The classic PLY name, for messages.
    pub(crate) fn name(self) -> &'static str {
        match self {
            Scalar::I8 => "char",
            Scalar::U8 => "uchar",
            Scalar::I16 => "short",
            Scalar::U16 => "ushort",
            Scalar::I32 => "int",
            Scalar::U32 => "uint",
            Scalar::F32 => "float",
            Scalar::F64 => "double",
        }
    }
}

/// A property: one scalar, or a list with its count type and item type.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Kind {
    Scalar(Scalar),
    List { count: Scalar, item: Scalar },
}

#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Property {
    pub name: String,
    pub kind: Kind,
}

#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Element {
    pub name: String,
    /// Declared number of instances (not trusted for allocation).
    pub count: u64,
    pub props: Vec<Property>,
}

impl Element {
    /// Bytes per instance in a binary body when it has no list property.
    pub(crate) fn fixed_size(&self) -> Option<usize> {
        self.props
            .iter()
            .map(|p| match p.kind {
                Kind::Scalar(s) => Some(s.size()),
                Kind::List { .. } => None,
            })
            .sum()
    }

    /// Smallest possible size of one instance in a binary body (lists may be empty).
    pub(crate) fn min_size(&self) -> usize {
        self.props
            .iter()
            .map(|p| match p.kind {
                Kind::Scalar(s) => s.size(),
                Kind::List { count, .. } => count.size(),
            })
            .sum()
    }

    pub(crate) fn find(&self, name: &str) -> Option<usize> {
        self.props.iter().position(|p| p.name == name)
    }
}

#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Header {
    pub format: Format,
    pub elements: Vec<Element>,
    pub comments: Vec<String>,
    pub obj_info: Vec<String>,
    /// Byte offset of the body (just after the `end_header` line).
    pub body: usize,
    /// Number of header lines (the body's first line is `lines + 1`).
    pub lines: usize,
}

fn err(line: usize, msg: impl Into<String>) -> Error {
    Error::Parse { format: "PLY", line, msg: msg.into() }
}

/// Text after the keyword, trimmed (for comments).
fn rest_after(l: &[u8], kw: &[u8]) -> String {
    String::from_utf8_lossy(l[kw.len()..].trim_ascii()).into_owned()
}

/// Parses the header at the start of `data`.
pub(crate) fn parse(data: &[u8]) -> Result<Header> {
    let mut pos = 0usize;
    let mut line = 0usize;
    // Next header line (without its LF / CRLF), or None at the end of the data.
    let next_line = |pos: &mut usize, line: &mut usize| -> Option<&[u8]> {
        if *pos >= data.len() {
            return None;
        }
        let rest = &data[*pos..];
        let (l, adv) = match rest.iter().position(|&b| b == b'\n') {
            Some(i) => (&rest[..i], i + 1),
            None => (rest, rest.len()),
        };
        *pos += adv;
        *line += 1;
        Some(l.strip_suffix(b"\r").unwrap_or(l))
    };
    match next_line(&mut pos, &mut line) {
        Some(l) if l.trim_ascii_end() == b"ply" => {}
        _ => return Err(err(1, "not a PLY file: the first line must be 'ply'")),
    }
    let mut format = None;
    let mut elements: Vec<Element> = Vec::new();
    let mut comments = Vec::new();
    let mut obj_info = Vec::new();
    loop {
        let Some(l) = next_line(&mut pos, &mut line) else {
            return Err(err(line, "header has no 'end_header' line"));
        };
        let mut t = tokens(l);
        let Some(kw) = t.next() else { continue };
        match kw {
            b"end_header" => break,
            b"comment" => comments.push(rest_after(l.trim_ascii_start(), kw)),
            b"obj_info" => obj_info.push(rest_after(l.trim_ascii_start(), kw)),
            b"format" => {
                if format.is_some() {
                    return Err(err(line, "second 'format' line"));
                }
                let f = match t.next() {
                    Some(b"ascii") => Format::Ascii,
                    Some(b"binary_little_endian") => Format::BinaryLittleEndian,
                    Some(b"binary_big_endian") => Format::BinaryBigEndian,
                    other => {
                        return Err(err(
                            line,
                            format!(
                                "unknown format '{}' (expected ascii, binary_little_endian or binary_big_endian)",
                                show(other.unwrap_or_default())
                            ),
                        ))
                    }
                };
                match t.next() {
                    Some(b"1.0") | Some(b"1") => {}
                    other => {
                        return Err(err(
                            line,
                            format!("unsupported PLY version '{}' (expected 1.0)", show(other.unwrap_or_default())),
                        ))
                    }
                }
                format = Some(f);
            }
            b"element" => {
                let (Some(name), Some(count)) = (t.next(), t.next()) else {
                    return Err(err(line, "'element' needs a name and a count"));
                };
                let count: u64 = as_str(count)
                    .and_then(|s| s.parse().ok())
                    .ok_or_else(|| err(line, format!("bad element count '{}'", show(count))))?;
                let name = String::from_utf8_lossy(name).into_owned();
                if elements.iter().any(|e| e.name == name) {
                    return Err(err(line, format!("element '{name}' declared twice")));
                }
                elements.push(Element { name, count, props: Vec::new() });
            }
            b"property" => {
                let Some(el) = elements.last_mut() else {
                    return Err(err(line, "'property' before any 'element'"));
                };
                let ty = t.next().unwrap_or_default();
                let kind = if ty == b"list" {
                    let (c, i) = (t.next().unwrap_or_default(), t.next().unwrap_or_default());
                    let count =
                        Scalar::parse(c).ok_or_else(|| err(line, format!("unknown list count type '{}'", show(c))))?;
                    let item =
                        Scalar::parse(i).ok_or_else(|| err(line, format!("unknown list item type '{}'", show(i))))?;
                    if !count.is_integer() {
                        return Err(err(line, format!("list count type must be an integer type, got '{}'", show(c))));
                    }
                    Kind::List { count, item }
                } else {
                    Kind::Scalar(
                        Scalar::parse(ty).ok_or_else(|| err(line, format!("unknown property type '{}'", show(ty))))?,
                    )
                };
                let Some(name) = t.next() else {
                    return Err(err(line, "'property' without a name"));
                };
                let name = String::from_utf8_lossy(name).into_owned();
                if el.find(&name).is_some() {
                    return Err(err(line, format!("property '{name}' declared twice in element '{}'", el.name)));
                }
                el.props.push(Property { name, kind });
            }
            other => return Err(err(line, format!("unknown header keyword '{}'", show(other)))),
        }
    }
    let Some(format) = format else {
        return Err(err(line, "header has no 'format' line"));
    };
    Ok(Header { format, elements, comments, obj_info, body: pos, lines: line })
}

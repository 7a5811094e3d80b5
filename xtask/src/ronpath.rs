//! Field paths in RON text: where each field of a scene file is (line, column, the byte span of
//! its value), so that `--set shell.material.density=0.2` can replace or add a value in the text
//! before the scene is parsed (and is then validated exactly like the file), and so that an error
//! about a field names the line the field is on.
//!
//! A path is the chain of field names and element indices from the top of the file, written with
//! dots: `params.shell.material.density`, `params.size.0`, `params.meshes.2.1.radius`. Struct
//! names and enum variants (`Grid(n: 3)`) are not part of a path. The scanner knows RON's
//! lexical structure (strings, raw strings, chars, nested comments, `#![enable(…)]` headers) and
//! never fails: text it cannot follow ends the outline there (the typed parser reports the error).

use std::ops::Range;

/// One step of a path: a field name or an element index (tuples, lists, map entries in order).
#[derive(Clone, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum Seg {
    /// `name: value` inside `( … )`.
    Field(String),
    /// The n-th element of a tuple, list or map.
    Index(usize),
}

impl Seg {
    fn parse(s: &str) -> Seg {
        match s.parse::<usize>() {
            Ok(i) => Seg::Index(i),
            Err(_) => Seg::Field(s.to_string()),
        }
    }
}

/// Parses `a.b.0.c` into segments.
pub fn parse_path(p: &str) -> Vec<Seg> {
    p.split('.').filter(|s| !s.is_empty()).map(Seg::parse).collect()
}

/// Writes segments back as `a.b.0.c`.
pub fn path_string(p: &[Seg]) -> String {
    p.iter()
        .map(|s| match s {
            Seg::Field(f) => f.clone(),
            Seg::Index(i) => i.to_string(),
        })
        .collect::<Vec<_>>()
        .join(".")
}

/// What kind of value an entry holds.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Kind {
    /// `( … )` (optionally named): a struct, tuple or enum variant with data. `close` is the byte
    /// offset of its `)`; `fields` is true when its items are `name: value`.
    Paren { close: usize, fields: bool, empty: bool },
    /// `[ … ]`.
    List,
    /// `{ … }`.
    Map,
    /// A number, string, char, identifier or unit variant.
    Atom,
}

/// One value in the text.
#[derive(Clone, Debug, PartialEq)]
pub struct Entry {
    /// Its path from the top.
    pub path: Vec<Seg>,
    /// Byte offset of its field name (or of the value itself for elements).
    pub key_at: usize,
    /// Byte span of the value.
    pub value: Range<usize>,
    /// What it holds.
    pub kind: Kind,
    /// The struct or enum variant name written before `(`, if any (`Grid` in `Grid(n: 3)`).
    pub name: Option<String>,
}

/// Every value of a RON text with its path, in text order.
pub fn outline(text: &str) -> Vec<Entry> {
    let mut s = Scanner { b: text.as_bytes(), i: 0, out: Vec::new() };
    s.skip_header();
    s.skip_ws();
    let start = s.i;
    s.value(Vec::new(), start);
    s.out
}

/// 1-based (line, column) of a byte offset (columns count characters).
pub fn line_col(text: &str, at: usize) -> (usize, usize) {
    let at = at.min(text.len());
    let before = &text[..floor_char(text, at)];
    let line = before.matches('\n').count() + 1;
    let col = before.rsplit('\n').next().map(|l| l.chars().count()).unwrap_or(0) + 1;
    (line, col)
}

/// Byte offset of 1-based (line, column), clamped to the text.
pub fn offset_of(text: &str, line: usize, col: usize) -> usize {
    let mut off = 0;
    for (k, l) in text.split_inclusive('\n').enumerate() {
        if k + 1 == line {
            let c = l.char_indices().nth(col.saturating_sub(1)).map(|(i, _)| i).unwrap_or(l.len());
            return off + c;
        }
        off += l.len();
    }
    text.len()
}

fn floor_char(text: &str, mut at: usize) -> usize {
    while at > 0 && !text.is_char_boundary(at) {
        at -= 1;
    }
    at
}

/// The entry at exactly `path`.
pub fn find<'a>(entries: &'a [Entry], path: &[Seg]) -> Option<&'a Entry> {
    entries.iter().find(|e| e.path == path)
}

/// The deepest entry whose value span contains byte offset `at`.
pub fn innermost(entries: &[Entry], at: usize) -> Option<&Entry> {
    entries
        .iter()
        .filter(|e| e.value.start <= at && at < e.value.end.max(e.value.start + 1))
        .max_by_key(|e| e.path.len())
}

struct Scanner<'a> {
    b: &'a [u8],
    i: usize,
    out: Vec<Entry>,
}

impl Scanner<'_> {
    fn peek(&self) -> Option<u8> {
        self.b.get(self.i).copied()
    }

    fn skip_header(&mut self) {
        // `#![enable(implicit_some)]` lines before the value.
        loop {
            self.skip_ws();
            if self.b[self.i..].starts_with(b"#![") {
                while let Some(c) = self.peek() {
                    self.i += 1;
                    if c == b']' {
                        break;
                    }
                }
            } else {
                return;
            }
        }
    }

    fn skip_ws(&mut self) {
        loop {
            match self.peek() {
                Some(c) if c.is_ascii_whitespace() => self.i += 1,
                Some(b'/') if self.b.get(self.i + 1) == Some(&b'/') => {
                    while let Some(c) = self.peek() {
                        self.i += 1;
                        if c == b'\n' {
                            break;
                        }
                    }
                }
                Some(b'/') if self.b.get(self.i + 1) == Some(&b'*') => {
                    self.i += 2;
                    let mut depth = 1;
                    while depth > 0 && self.i < self.b.len() {
                        if self.b[self.i..].starts_with(b"/*") {
                            depth += 1;
                            self.i += 2;
                        } else if self.b[self.i..].starts_with(b"*/") {
                            depth -= 1;
                            self.i += 2;
                        } else {
                            self.i += 1;
                        }
                    }
                }
                _ => return,
            }
        }
    }

    fn is_word(c: u8) -> bool {
        c.is_ascii_alphanumeric() || matches!(c, b'_' | b'.' | b'+' | b'-') || c >= 0x80
    }

    fn word(&mut self) -> Range<usize> {
        let s = self.i;
        while self.peek().is_some_and(Self::is_word) {
            self.i += 1;
        }
        s..self.i
    }

    fn string(&mut self) {
        // At `"`: escapes skip the next byte.
        self.i += 1;
        while let Some(c) = self.peek() {
            self.i += 1;
            match c {
                b'\\' => self.i += 1,
                b'"' => return,
                _ => {}
            }
        }
    }

    fn raw_string(&mut self) {
        // At `r`, then hashes, then `"`.
        self.i += 1;
        let mut hashes = 0;
        while self.peek() == Some(b'#') {
            hashes += 1;
            self.i += 1;
        }
        self.i += 1;
        let mut close = vec![b'"'];
        close.extend(std::iter::repeat_n(b'#', hashes));
        while self.i < self.b.len() {
            if self.b[self.i..].starts_with(&close) {
                self.i += close.len();
                return;
            }
            self.i += 1;
        }
    }

    /// Scans one value starting at the current position; `key_at` is where its name (or itself)
    /// starts. Returns false when the text cannot be followed.
    fn value(&mut self, path: Vec<Seg>, key_at: usize) -> bool {
        self.skip_ws();
        let start = self.i;
        let Some(c) = self.peek() else { return false };
        let idx = self.out.len();
        self.out.push(Entry { path: path.clone(), key_at, value: start..start, kind: Kind::Atom, name: None });
        let ok = match c {
            b'"' => {
                self.string();
                true
            }
            b'r' if matches!(self.b.get(self.i + 1), Some(b'"' | b'#')) => {
                self.raw_string();
                true
            }
            b'b' if self.b.get(self.i + 1) == Some(&b'"') => {
                self.i += 1;
                self.string();
                true
            }
            b'\'' => {
                self.i += 1;
                if self.peek() == Some(b'\\') {
                    self.i += 1;
                }
                while let Some(c) = self.peek() {
                    self.i += 1;
                    if c == b'\'' {
                        break;
                    }
                }
                true
            }
            b'(' => self.paren(&path, idx),
            b'[' => self.seq(&path, b']', idx, Kind::List),
            b'{' => self.seq(&path, b'}', idx, Kind::Map),
            c if Self::is_word(c) => {
                let w = self.word();
                self.skip_ws_no_newline_sensitive();
                if self.peek() == Some(b'(') {
                    self.out[idx].name = Some(String::from_utf8_lossy(&self.b[w]).into_owned());
                    self.paren(&path, idx)
                } else {
                    true
                }
            }
            _ => false,
        };
        self.out[idx].value = start..self.i;
        ok
    }

    fn skip_ws_no_newline_sensitive(&mut self) {
        let save = self.i;
        self.skip_ws();
        if self.peek() != Some(b'(') {
            self.i = save;
        }
    }

    /// `( … )`: fields `name: value` or tuple elements.
    fn paren(&mut self, path: &[Seg], idx: usize) -> bool {
        self.i += 1; // (
        let mut n = 0usize;
        let mut fields = false;
        loop {
            self.skip_ws();
            match self.peek() {
                None => return false,
                Some(b')') => {
                    self.out[idx].kind = Kind::Paren { close: self.i, fields, empty: n == 0 };
                    self.i += 1;
                    return true;
                }
                _ => {}
            }
            let item_at = self.i;
            // `name :` makes a field; anything else is an element.
            let save = self.i;
            let mut child = path.to_vec();
            let w = if self.peek().is_some_and(|c| c.is_ascii_alphabetic() || c == b'_') { self.word() } else { 0..0 };
            let mut is_field = false;
            if !w.is_empty() {
                self.skip_ws();
                if self.peek() == Some(b':') {
                    is_field = true;
                    self.i += 1;
                    child.push(Seg::Field(String::from_utf8_lossy(&self.b[w]).into_owned()));
                }
            }
            if !is_field {
                self.i = save;
                child.push(Seg::Index(n));
            } else {
                fields = true;
            }
            if !self.value(child, item_at) {
                return false;
            }
            n += 1;
            self.skip_ws();
            match self.peek() {
                Some(b',') => self.i += 1,
                Some(b')') => {}
                _ => return false,
            }
        }
    }

    /// `[ … ]` or `{ key: value, … }` (map values are indexed by entry order).
    fn seq(&mut self, path: &[Seg], close: u8, idx: usize, kind: Kind) -> bool {
        self.i += 1;
        let mut n = 0usize;
        loop {
            self.skip_ws();
            match self.peek() {
                None => return false,
                Some(c) if c == close => {
                    self.i += 1;
                    self.out[idx].kind = kind;
                    return true;
                }
                _ => {}
            }
            let item_at = self.i;
            let mut child = path.to_vec();
            child.push(Seg::Index(n));
            if close == b'}' {
                // key: skip it as an unrecorded value, then the colon.
                let mut inner = Scanner { b: self.b, i: self.i, out: Vec::new() };
                if !inner.value(Vec::new(), item_at) {
                    return false;
                }
                self.i = inner.i;
                self.skip_ws();
                if self.peek() != Some(b':') {
                    return false;
                }
                self.i += 1;
            }
            if !self.value(child, item_at) {
                return false;
            }
            n += 1;
            self.skip_ws();
            match self.peek() {
                Some(b',') => self.i += 1,
                Some(c) if c == close => {}
                _ => return false,
            }
        }
    }
}

/// Checks that `v` is exactly one RON value (what `--set` accepts).
pub fn is_single_value(v: &str) -> bool {
    let mut s = Scanner { b: v.as_bytes(), i: 0, out: Vec::new() };
    s.skip_ws();
    if s.i >= v.len() {
        return false;
    }
    let ok = s.value(Vec::new(), 0);
    s.skip_ws();
    ok && s.i == v.len()
}

#[cfg(test)]
mod tests {
    use super::*;

    const TEXT: &str = r##"#![enable(implicit_some)]
// a scene
(
    method: "shells/drape",
    description: "a (tricky) \"string\"",
    params: (
        size: (640, 480), /* a (comment) */
        shell: (
            mesh: Grid(n: 12, size: [1.0, 2.0]),
            material: ( density: 0.15, name: r#"raw "x""#, c: 'a' ),
        ),
        frames: (10, 60, 240),
        empty: (),
        list: [ (a: 1), (a: 2) ],
        map: { "k": 3 },
        unit: None,
    ),
)
"##;

    #[test]
    fn finds_every_field_with_its_line() {
        let o = outline(TEXT);
        let at = |p: &str| {
            let e = find(&o, &parse_path(p)).unwrap_or_else(|| panic!("{p} not found"));
            (line_col(TEXT, e.key_at).0, TEXT[e.value.clone()].to_string())
        };
        assert_eq!(at("method"), (4, "\"shells/drape\"".into()));
        assert_eq!(at("params.size.1"), (7, "480".into()));
        assert_eq!(at("params.shell.mesh.n"), (9, "12".into()));
        assert_eq!(at("params.shell.mesh.size.1"), (9, "2.0".into()));
        assert_eq!(at("params.shell.material.density"), (10, "0.15".into()));
        assert_eq!(at("params.shell.material.c"), (10, "'a'".into()));
        assert_eq!(at("params.frames"), (12, "(10, 60, 240)".into()));
        assert_eq!(at("params.list.1.a"), (14, "2".into()));
        assert_eq!(at("params.map.0"), (15, "3".into()));
        assert_eq!(at("params.unit"), (16, "None".into()));
        let e = find(&o, &parse_path("params.empty")).unwrap();
        assert!(matches!(e.kind, Kind::Paren { empty: true, .. }));
        assert_eq!(find(&o, &parse_path("params.shell.mesh")).unwrap().name.as_deref(), Some("Grid"));
        let e = find(&o, &parse_path("params.shell.material")).unwrap();
        assert!(matches!(e.kind, Kind::Paren { fields: true, .. }));
        let inner = innermost(&o, TEXT.find("0.15").unwrap()).unwrap();
        assert_eq!(path_string(&inner.path), "params.shell.material.density");
    }

    #[test]
    fn broken_text_never_panics() {
        for cut in 0..TEXT.len() {
            if TEXT.is_char_boundary(cut) {
                let _ = outline(&TEXT[..cut]);
            }
        }
        assert!(outline("").is_empty());
    }

    #[test]
    fn single_values() {
        assert!(is_single_value("0.2"));
        assert!(is_single_value(" Grid(n: 3) "));
        assert!(is_single_value("[1, 2]"));
        assert!(is_single_value("\"a b\""));
        assert!(!is_single_value("1, 2"));
        assert!(!is_single_value("(1, 2"));
        assert!(!is_single_value(""));
    }

    #[test]
    fn line_and_offset_agree() {
        let t = "ab\ncdé\nf";
        assert_eq!(line_col(t, 0), (1, 1));
        assert_eq!(line_col(t, 4), (2, 2));
        assert_eq!(offset_of(t, 2, 2), 4);
        assert_eq!(offset_of(t, 3, 1), t.find('f').unwrap());
    }
}

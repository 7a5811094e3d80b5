//! Collects the doc comments of every struct and enum field in the method crates' sources (and
//! the scene runners in `xtask/src`) into a table compiled into the binary, so that
//! `cargo xtask params <method>` can annotate a scene's parameters with the units and meaning
//! written once, on the field itself. A light line scanner (no parser dependency): it reads
//! `///` lines, `#[serde(default…)]`, `struct`/`enum` headers and `name: Type,` fields.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

struct Field {
    krate: String,
    owner: String,
    name: String,
    ty: String,
    doc: String,
    default: bool,
}

fn rs_files(dir: &Path, out: &mut Vec<PathBuf>) {
    let Ok(rd) = std::fs::read_dir(dir) else { return };
    let mut v: Vec<PathBuf> = rd.flatten().map(|e| e.path()).collect();
    v.sort();
    for p in v {
        if p.is_dir() {
            rs_files(&p, out);
        } else if p.extension().is_some_and(|e| e == "rs") {
            out.push(p);
        }
    }
}

/// `pub struct Name {`, `pub(crate) enum Name<T> {` → ("struct"|"enum", "Name").
fn header(line: &str) -> Option<(&'static str, String)> {
    let l = line.trim_start();
    let l = l.strip_prefix("pub(crate) ").or_else(|| l.strip_prefix("pub ")).unwrap_or(l);
    let (kind, rest) = if let Some(r) = l.strip_prefix("struct ") {
        ("struct", r)
    } else if let Some(r) = l.strip_prefix("enum ") {
        ("enum", r)
    } else {
        return None;
    };
    if !l.trim_end().ends_with('{') {
        return None;
    }
    let name: String = rest.chars().take_while(|c| c.is_alphanumeric() || *c == '_').collect();
    (!name.is_empty()).then_some((kind, name))
}

fn scan(krate: &str, text: &str, out: &mut Vec<Field>) {
    let mut doc: Vec<String> = Vec::new();
    let mut default = false;
    // (owner, brace depth at which its fields sit, is enum)
    let mut stack: Vec<(String, i32, bool)> = Vec::new();
    let mut depth = 0i32;
    for raw in text.lines() {
        let line = raw.trim();
        if let Some(d) = line.strip_prefix("///") {
            doc.push(d.trim().to_string());
            continue;
        }
        if line.starts_with("#[") {
            if line.contains("serde(") && line.contains("default") {
                default = true;
            }
            continue;
        }
        let opens = line.matches('{').count() as i32;
        let closes = line.matches('}').count() as i32;
        if let Some((kind, name)) = header(line) {
            stack.push((name, depth + 1, kind == "enum"));
        } else if let Some((owner, d, is_enum)) = stack.last().cloned() {
            if depth == d {
                let body = line.strip_prefix("pub(crate) ").or_else(|| line.strip_prefix("pub ")).unwrap_or(line);
                let ident: String = body.chars().take_while(|c| c.is_alphanumeric() || *c == '_').collect();
                let after = body[ident.len()..].trim_start();
                if !ident.is_empty() && !is_enum && after.starts_with(':') && !after.starts_with("::") {
                    let ty = after[1..].trim().trim_end_matches(',').trim().to_string();
                    out.push(Field {
                        krate: krate.into(),
                        owner: owner.clone(),
                        name: ident,
                        ty,
                        doc: doc.join(" "),
                        default,
                    });
                } else if !ident.is_empty() && is_enum {
                    // A variant: its own doc, and a struct variant's fields below it.
                    out.push(Field {
                        krate: krate.into(),
                        owner: owner.clone(),
                        name: ident.clone(),
                        ty: "variant".into(),
                        doc: doc.join(" "),
                        default: false,
                    });
                    if after.starts_with('{') && opens > closes {
                        stack.push((format!("{owner}::{ident}"), depth + 1, false));
                    } else if let Some(inner) = after.strip_prefix('{').and_then(|a| a.rsplit_once('}')).map(|(i, _)| i)
                    {
                        // `Variant { a: f64, b: [u32; 3] }` on one line (types hold no commas
                        // outside brackets in practice; split at top-level commas).
                        let mut level = 0;
                        let mut part = String::new();
                        let mut parts = Vec::new();
                        for ch in inner.chars() {
                            match ch {
                                '<' | '[' | '(' => level += 1,
                                '>' | ']' | ')' => level -= 1,
                                ',' if level == 0 => {
                                    parts.push(std::mem::take(&mut part));
                                    continue;
                                }
                                _ => {}
                            }
                            part.push(ch);
                        }
                        parts.push(part);
                        for p in parts {
                            if let Some((n, t)) = p.split_once(':') {
                                out.push(Field {
                                    krate: krate.into(),
                                    owner: format!("{owner}::{ident}"),
                                    name: n.trim().to_string(),
                                    ty: t.trim().to_string(),
                                    doc: String::new(),
                                    default: false,
                                });
                            }
                        }
                    }
                }
            }
        }
        depth += opens - closes;
        while stack.last().is_some_and(|(_, d, _)| depth < *d) {
            stack.pop();
        }
        if !line.is_empty() {
            doc.clear();
            default = false;
        }
    }
}

fn escape(s: &str) -> String {
    s.replace('\\', "\\\\").replace('"', "\\\"")
}

fn main() {
    let manifest = PathBuf::from(std::env::var("CARGO_MANIFEST_DIR").expect("cargo sets CARGO_MANIFEST_DIR"));
    let root = manifest.parent().expect("xtask sits in the workspace").to_path_buf();
    let mut fields = Vec::new();
    let mut dirs: Vec<(String, PathBuf)> = Vec::new();
    if let Ok(rd) = std::fs::read_dir(&root) {
        for e in rd.flatten() {
            let p = e.path();
            let name = e.file_name().to_string_lossy().into_owned();
            if p.join("Cargo.toml").is_file() && p.join("src").is_dir() && name != "xtask" && name != "tests" {
                dirs.push((name, p.join("src")));
            }
        }
    }
    dirs.sort();
    for (krate, src) in &dirs {
        println!("cargo:rerun-if-changed={}", src.display());
        let mut files = Vec::new();
        rs_files(src, &mut files);
        let snake = krate.replace('-', "_");
        for sub in ["scenes", "crates"] {
            let d = manifest.join("src").join(sub);
            if let Ok(rd) = std::fs::read_dir(&d) {
                for e in rd.flatten() {
                    let n = e.file_name().to_string_lossy().into_owned();
                    if n.starts_with(&snake) && n.ends_with(".rs") {
                        files.push(e.path());
                    }
                }
            }
        }
        for f in files {
            if let Ok(text) = std::fs::read_to_string(&f) {
                scan(krate, &text, &mut fields);
            }
        }
    }
    println!("cargo:rerun-if-changed={}", manifest.join("src/scenes").display());
    println!("cargo:rerun-if-changed={}", manifest.join("src/crates").display());
    let mut s = String::from(
        "/// (crate, owner type, field, field type, doc, has a serde default), from the sources.\n\
         pub static FIELD_DOCS: &[(&str, &str, &str, &str, &str, bool)] = &[\n",
    );
    for f in &fields {
        let _ = writeln!(
            s,
            "    (\"{}\", \"{}\", \"{}\", \"{}\", \"{}\", {}),",
            escape(&f.krate),
            escape(&f.owner),
            escape(&f.name),
            escape(&f.ty),
            escape(&f.doc),
            f.default
        );
    }
    s.push_str("];\n");
    let out = PathBuf::from(std::env::var("OUT_DIR").expect("cargo sets OUT_DIR")).join("field_docs.rs");
    std::fs::write(out, s).expect("OUT_DIR is writable");
}

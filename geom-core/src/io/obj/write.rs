//! The OBJ writer.
//!
//! Layout: a `#` header line, `v` lines, then `vt` lines (one per vertex for per-vertex UVs,
//! three per triangle in face order for per-corner UVs), `vn` lines (one per vertex), `f` lines
//! with 1-based indices (`v`, `v/vt`, `v//vn` or `v/vt/vn`). Numbers use the shortest text that
//! parses back to the same f64 (see `io::fmt`); f32 positions are written as the exact f64 of
//! the f32 value, so reading gives `x as f64` bit for bit (and rounding back to f32 gives `x`).

use std::fmt::Write as _;
use std::io::Write;
use std::path::Path;

use crate::error::Result;
use crate::mesh::Uv;

use super::super::fmt::push_f64;
use super::super::fs::write_file;
use super::super::MeshOut;

/// Writes `m` as OBJ text to `path` (created or truncated). Errors: those of
/// [`MeshOut::validate`], and I/O errors naming the path.
pub fn write(path: impl AsRef<Path>, m: &MeshOut) -> Result<()> {
    m.validate()?;
    write_file(path.as_ref(), |w| write_to(w, m))
}

/// `m` as OBJ text (same layout as [`write`]).
pub fn to_string(m: &MeshOut) -> Result<String> {
    m.validate()?;
    let mut out = Vec::new();
    write_to(&mut out, m)?;
    // Only ASCII was written.
    Ok(String::from_utf8(out).expect("OBJ writer emits ASCII"))
}

/// Flushes `buf` into `w` when it has grown past 64 KiB (or always, with `force`).
fn spill(w: &mut dyn Write, buf: &mut String, force: bool) -> Result<()> {
    if force || buf.len() > 1 << 16 {
        w.write_all(buf.as_bytes())?;
        buf.clear();
    }
    Ok(())
}

fn push_xyz(buf: &mut String, key: &str, xyz: [f64; 3]) {
    buf.push_str(key);
    for c in xyz {
        buf.push(' ');
        push_f64(buf, c);
    }
    buf.push('\n');
}

fn write_to(w: &mut dyn Write, m: &MeshOut) -> Result<()> {
    let n = m.positions.len();
    let mut buf = String::with_capacity(1 << 17);
    let _ = writeln!(buf, "# geom-core OBJ: {n} vertices, {} faces", m.faces.len());
    for i in 0..n {
        push_xyz(&mut buf, "v", m.positions.get(i));
        spill(w, &mut buf, false)?;
    }
    let push_uv = |buf: &mut String, p: &crate::math::Pt2| {
        buf.push_str("vt ");
        push_f64(buf, p.x);
        buf.push(' ');
        push_f64(buf, p.y);
        buf.push('\n');
    };
    match m.uv {
        None => {}
        Some(Uv::PerVertex(uv)) => {
            for p in uv {
                push_uv(&mut buf, p);
                spill(w, &mut buf, false)?;
            }
        }
        Some(Uv::PerCorner(uv)) => {
            for p in uv.iter().flatten() {
                push_uv(&mut buf, p);
                spill(w, &mut buf, false)?;
            }
        }
    }
    if let Some(nr) = m.normals {
        for v in nr {
            push_xyz(&mut buf, "vn", [v.x, v.y, v.z]);
            spill(w, &mut buf, false)?;
        }
    }
    let has_n = m.normals.is_some();
    for f in 0..m.faces.len() {
        buf.push('f');
        for (k, &v) in m.faces.row(f).iter().enumerate() {
            let v = v as u64 + 1;
            let t = match m.uv {
                None => None,
                Some(Uv::PerVertex(_)) => Some(v),
                // Per-corner UVs only come with triangles (validated): corner k of face f.
                Some(Uv::PerCorner(_)) => Some(3 * f as u64 + k as u64 + 1),
            };
            // `write!` into a String cannot fail.
            let _ = match (t, has_n) {
                (None, false) => write!(buf, " {v}"),
                (Some(t), false) => write!(buf, " {v}/{t}"),
                (None, true) => write!(buf, " {v}//{v}"),
                (Some(t), true) => write!(buf, " {v}/{t}/{v}"),
            };
        }
        buf.push('\n');
        spill(w, &mut buf, false)?;
    }
    spill(w, &mut buf, true)
}

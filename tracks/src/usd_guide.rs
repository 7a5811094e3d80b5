//! Reading a guide animation back from the time-sampled `.usda` text this toolkit writes
//! (`geom_core::io::usd`): one mesh with fixed triangle topology (`faceVertexCounts` all 3,
//! `faceVertexIndices` once) and `points.timeSamples` at equally spaced time codes, played at
//! `timeCodesPerSecond` frames per second. The first sample is the guide's rest mesh (as for
//! OBJ sequences, [`GuideAnimation::from_obj_sequence`]).
//!
//! This is not a general USD reader: layers, references, variants, time-sampled topology and
//! non-triangle faces are rejected with an error naming the file and line.
//!
//! ```
//! use geom_core::io::usd::{self, UsdFrame, UsdOptions};
//! use geom_core::math::Pt3;
//! let p0 = [Pt3::origin(), Pt3::new(1.0, 0.0, 0.0), Pt3::new(0.0, 1.0, 0.0)];
//! let p1 = [Pt3::origin(), Pt3::new(1.0, 0.5, 0.0), Pt3::new(0.0, 1.0, 0.0)];
//! let tri = [[0u32, 1, 2]];
//! let frames = [UsdFrame::new(&p0, &tri), UsdFrame::new(&p1, &tri)];
//! let text = usd::to_string("guide", &frames, &UsdOptions { fps: 30.0, ..Default::default() }).unwrap();
//! let g = tracks::usd_guide::guide_from_usda_text(&text, "guide.usda").unwrap();
//! assert_eq!((g.n_vertices(), g.frames.len(), g.fps), (3, 2, 30.0));
//! assert!((g.frames[1][1].y - 0.5).abs() < 1e-7);
//! ```

use std::path::Path;

use geom_core::math::Pt3;
use geom_core::mesh::TriMesh;

use crate::error::{Result, TrackError};
use crate::guide::{GuideAnimation, TimeInterp};

fn err(file: &str, text: &str, at: usize, msg: impl std::fmt::Display) -> TrackError {
    let line = text[..at.min(text.len())].matches('\n').count() + 1;
    TrackError::BadParameter(format!("{file}:{line}: {msg}"))
}

/// Byte offset just after `key` (first occurrence), or `None`.
fn after(text: &str, key: &str) -> Option<usize> {
    text.find(key).map(|i| i + key.len())
}

/// A header number `key = value` (e.g. `timeCodesPerSecond = 30`).
fn header_num(text: &str, file: &str, key: &str) -> Result<f64> {
    let Some(i) = text.find(&format!("{key} =")) else {
        return Err(TrackError::BadParameter(format!("{file}: no `{key}` in the stage metadata")));
    };
    let start = i + key.len() + 2;
    let rest = &text[start..];
    let end = rest.find('\n').unwrap_or(rest.len());
    rest[..end].trim().parse::<f64>().map_err(|e| err(file, text, start, format!("`{key}`: {e}")))
}

/// The text between the `[` at or after `from` and its `]`, and the offset after the `]`.
fn bracket(text: &str, file: &str, from: usize, what: &str) -> Result<(usize, usize)> {
    let open =
        text[from..].find('[').map(|i| from + i).ok_or_else(|| err(file, text, from, format!("{what}: no `[`")))?;
    let close = text[open..]
        .find(']')
        .map(|i| open + i)
        .ok_or_else(|| err(file, text, open, format!("{what}: no closing `]`")))?;
    Ok((open + 1, close))
}

fn ints(text: &str, file: &str, (a, b): (usize, usize), what: &str) -> Result<Vec<i64>> {
    text[a..b]
        .split(',')
        .map(str::trim)
        .filter(|s| !s.is_empty())
        .map(|s| s.parse::<i64>().map_err(|e| err(file, text, a, format!("{what}: `{s}`: {e}"))))
        .collect()
}

/// Points `[(x, y, z), …]` between byte offsets `a` and `b`.
fn points(text: &str, file: &str, (a, b): (usize, usize)) -> Result<Vec<Pt3>> {
    let mut out = Vec::new();
    let mut rest = &text[a..b];
    let mut off = a;
    while let Some(i) = rest.find('(') {
        let j = rest[i..].find(')').map(|j| i + j).ok_or_else(|| err(file, text, off + i, "point: no closing `)`"))?;
        let c: Vec<f64> = rest[i + 1..j]
            .split(',')
            .map(|s| s.trim().parse::<f64>().map_err(|e| err(file, text, off + i, format!("point `{s}`: {e}"))))
            .collect::<Result<_>>()?;
        if c.len() != 3 || c.iter().any(|x| !x.is_finite()) {
            return Err(err(file, text, off + i, format!("point {} is not three finite numbers", out.len())));
        }
        out.push(Pt3::new(c[0], c[1], c[2]));
        off += j + 1;
        rest = &rest[j + 1..];
    }
    Ok(out)
}

/// Parses the `.usda` text of an animated triangle mesh written by `geom_core::io::usd`
/// (`file` names it in errors). Errors (`BadParameter` naming file and line): missing frame
/// rate, topology or points; time-sampled topology; a face that is not a triangle; an index out
/// of range; a sample with a different vertex count; time codes not equally spaced.
pub fn guide_from_usda_text(text: &str, file: &str) -> Result<GuideAnimation> {
    if !text.starts_with("#usda") {
        return Err(TrackError::BadParameter(format!("{file}:1: not a USD text layer (no `#usda` header)")));
    }
    let tcps = header_num(text, file, "timeCodesPerSecond")?;
    if !(tcps > 0.0 && tcps.is_finite()) {
        return Err(TrackError::BadParameter(format!("{file}: timeCodesPerSecond must be > 0, got {tcps}")));
    }
    if let Some(i) = text.find("faceVertexIndices.timeSamples") {
        return Err(err(file, text, i, "time-sampled topology: a guide keeps its triangles"));
    }
    let counts_at = after(text, "int[] faceVertexCounts =")
        .ok_or_else(|| TrackError::BadParameter(format!("{file}: no `faceVertexCounts`")))?;
    let counts = ints(text, file, bracket(text, file, counts_at, "faceVertexCounts")?, "faceVertexCounts")?;
    if let Some(k) = counts.iter().position(|&c| c != 3) {
        return Err(err(
            file,
            text,
            counts_at,
            format!("face {k} has {} vertices; only triangles are read", counts[k]),
        ));
    }
    let idx_at = after(text, "int[] faceVertexIndices =")
        .ok_or_else(|| TrackError::BadParameter(format!("{file}: no `faceVertexIndices`")))?;
    let idx = ints(text, file, bracket(text, file, idx_at, "faceVertexIndices")?, "faceVertexIndices")?;
    if idx.len() != 3 * counts.len() {
        return Err(err(file, text, idx_at, format!("{} indices for {} triangles", idx.len(), counts.len())));
    }
    let pts_at = after(text, "points.timeSamples = {")
        .ok_or_else(|| TrackError::BadParameter(format!("{file}: no `points.timeSamples`")))?;
    let end = text[pts_at..].find('}').map(|i| pts_at + i).ok_or_else(|| err(file, text, pts_at, "no closing `}`"))?;
    let mut samples: Vec<(f64, Vec<Pt3>)> = Vec::new();
    let mut pos = pts_at;
    while let Some(colon) = text[pos..end].find(':').map(|i| pos + i) {
        let code_text = text[pos..colon].trim().trim_start_matches(',').trim();
        let code: f64 = code_text.parse().map_err(|e| err(file, text, pos, format!("time code `{code_text}`: {e}")))?;
        let (a, b) = bracket(text, file, colon, "points")?;
        samples.push((code, points(text, file, (a, b))?));
        pos = b + 1;
    }
    if samples.is_empty() {
        return Err(err(file, text, pts_at, "no point samples"));
    }
    let n = samples[0].1.len();
    if let Some(&bad) = idx.iter().find(|&&v| v < 0 || v as usize >= n) {
        return Err(err(file, text, idx_at, format!("index {bad} out of range for {n} points")));
    }
    if let Some(k) = samples.iter().position(|s| s.1.len() != n) {
        return Err(err(file, text, pts_at, format!("sample {k} has {} points, the first {n}", samples[k].1.len())));
    }
    // Equally spaced codes: the guide's frame rate is timeCodesPerSecond / spacing.
    let step = if samples.len() > 1 { samples[1].0 - samples[0].0 } else { 1.0 };
    for (k, w) in samples.windows(2).enumerate() {
        if !(step > 0.0) || ((w[1].0 - w[0].0) - step).abs() > 1e-6 * step {
            return Err(err(file, text, pts_at, format!("time codes not equally spaced at sample {}", k + 1)));
        }
    }
    let faces: Vec<[u32; 3]> = idx.chunks(3).map(|t| [t[0] as u32, t[1] as u32, t[2] as u32]).collect();
    let rest = TriMesh::new(samples[0].1.clone(), faces)?;
    let frames = samples.into_iter().map(|s| s.1).collect();
    GuideAnimation::from_frames(rest, frames, tcps / step, TimeInterp::CatmullRom)
}

/// Reads a guide from a `.usda` file written by this toolkit ([`guide_from_usda_text`]).
pub fn guide_from_usda(path: &Path) -> Result<GuideAnimation> {
    let text = std::fs::read_to_string(path)
        .map_err(|e| TrackError::BadParameter(format!("{}: cannot read: {e}", path.display())))?;
    guide_from_usda_text(&text, &path.display().to_string())
}

#[cfg(test)]
mod tests {
    use super::*;
    use geom_core::io::usd::{to_string, UsdFrame, UsdOptions};

    fn sample() -> String {
        let p: Vec<Vec<Pt3>> = (0..4)
            .map(|k| {
                vec![
                    Pt3::origin(),
                    Pt3::new(1.0, 0.1 * k as f64, 0.0),
                    Pt3::new(0.0, 1.0, 0.0),
                    Pt3::new(1.0, 1.0, 0.2),
                ]
            })
            .collect();
        let tris = [[0u32, 1, 2], [1, 3, 2]];
        let frames: Vec<UsdFrame> =
            p.iter().enumerate().map(|(k, q)| UsdFrame::new(q, &tris).at(2.0 * k as f64)).collect();
        to_string("g", &frames, &UsdOptions { fps: 60.0, ..Default::default() }).unwrap()
    }

    /// The toolkit's own writer round-trips (f32 precision): topology, frame count, the frame
    /// rate from the code spacing (60 codes/s, every 2nd code → 30 fps).
    #[test]
    fn round_trip() {
        let g = guide_from_usda_text(&sample(), "s.usda").expect("reads");
        assert_eq!((g.n_vertices(), g.frames.len(), g.rest.faces.len()), (4, 4, 2));
        assert_eq!(g.fps, 30.0);
        assert!((g.frames[3][1].y - 0.3).abs() < 1e-6);
    }

    /// Bad input is an error naming the file and line, never a panic.
    #[test]
    fn bad_input_names_file_and_line() {
        let s = sample().replace("timeCodesPerSecond = 60", "timeCodesPerSecond = -1");
        assert!(guide_from_usda_text(&s, "a.usda").unwrap_err().to_string().contains("a.usda"));
        let s = sample().replacen("(1, 0.1, 0)", "(1, nope, 0)", 1);
        let e = guide_from_usda_text(&s, "b.usda").unwrap_err().to_string();
        assert!(e.contains("b.usda:") && e.contains("nope"), "{e}");
        let s = sample().replace("[3, 3]", "[3, 4]");
        assert!(guide_from_usda_text(&s, "c.usda").unwrap_err().to_string().contains("triangles"));
        assert!(guide_from_usda_text("hello", "d.usda").unwrap_err().to_string().contains("d.usda:1"));
    }
}

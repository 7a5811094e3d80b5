//! Time-sampled USD text (`.usda`) for animated meshes: the form animation packages (Houdini,
//! Maya, Blender, usdview) read an OBJ-per-frame sequence in, with its frame rate.
//!
//! One `Mesh` prim under one `Xform` root: face topology written once (or time-sampled, for a
//! sequence whose topology changes from frame to frame, such as a liquid surface), `points` and
//! `extent` per time code, `subdivisionScheme = "none"` (USD's default is Catmull–Clark, which
//! would smooth simulation meshes), two-sided. The stage metadata that USD's validators require is
//! always set: `defaultPrim`, `upAxis` (Y, the toolkit's convention), `metersPerUnit` (1: the
//! toolkit works in metres), `timeCodesPerSecond` and `framesPerSecond` (the frame rate), and the
//! time range. Frame `k` is at time code `k` unless given its own ([`UsdFrame::at`]: a sequence
//! written every tenth step keeps its timing).
//!
//! ```
//! use geom_core::io::usd::{self, UsdFrame, UsdOptions};
//! use geom_core::math::Pt3;
//! let p0 = [Pt3::origin(), Pt3::new(1.0, 0.0, 0.0), Pt3::new(0.0, 1.0, 0.0)];
//! let p1 = [Pt3::origin(), Pt3::new(1.0, 0.5, 0.0), Pt3::new(0.0, 1.0, 0.0)];
//! let tri = [[0u32, 1, 2]];
//! let frames = [UsdFrame::new(&p0, &tri), UsdFrame::new(&p1, &tri)];
//! let text = usd::to_string("cloth", &frames, &UsdOptions { fps: 30.0, ..Default::default() }).unwrap();
//! assert!(text.contains("timeCodesPerSecond = 30"));
//! assert_eq!(text.matches("faceVertexIndices").count(), 1); // topology once
//! ```

use std::fmt::Write as _;
use std::path::Path;

use super::fs::write_file;
use crate::error::{Error, Result};
use crate::math::Pt3;

/// One frame of an animated triangle mesh.
#[derive(Clone, Copy, Debug)]
pub struct UsdFrame<'a> {
    /// Vertex positions (m).
    pub positions: &'a [Pt3],
    /// Triangles over `positions`.
    pub faces: &'a [[u32; 3]],
    /// Its time code (frames at the frame rate); `None`: its index in the sequence.
    pub time_code: Option<f64>,
}

impl<'a> UsdFrame<'a> {
    /// A frame from positions and triangles, at the time code of its index.
    pub fn new(positions: &'a [Pt3], faces: &'a [[u32; 3]]) -> Self {
        Self { positions, faces, time_code: None }
    }

    /// The same frame at time code `t` (codes must increase along the sequence).
    pub fn at(self, t: f64) -> Self {
        Self { time_code: Some(t), ..self }
    }
}

fn code(f: &UsdFrame, k: usize) -> f64 {
    f.time_code.unwrap_or(k as f64)
}

/// Stage settings.
#[derive(Clone, Debug, PartialEq)]
pub struct UsdOptions {
    /// Frames per second (`timeCodesPerSecond` and `framesPerSecond`); > 0.
    pub fps: f64,
    /// Metres per scene unit (1 for the toolkit's SI positions).
    pub meters_per_unit: f64,
    /// A line of documentation stored in the layer (`doc`), e.g. where the frames came from.
    pub doc: String,
}

impl Default for UsdOptions {
    /// 24 frames per second, metres, no doc line.
    fn default() -> Self {
        Self { fps: 24.0, meters_per_unit: 1.0, doc: String::new() }
    }
}

/// A valid USD prim name from any text: letters, digits and `_`, not starting with a digit.
pub fn prim_name(s: &str) -> String {
    let mut n: String = s.chars().map(|c| if c.is_ascii_alphanumeric() { c } else { '_' }).collect();
    if n.is_empty() || n.starts_with(|c: char| c.is_ascii_digit()) {
        n.insert(0, '_');
    }
    n
}

fn check(frames: &[UsdFrame], o: &UsdOptions) -> Result<()> {
    if frames.is_empty() {
        return Err(Error::InvalidParameter("usd: no frames to write".into()));
    }
    if !(o.fps > 0.0 && o.fps.is_finite()) {
        return Err(Error::InvalidParameter(format!("usd: fps must be > 0, got {}", o.fps)));
    }
    if !(o.meters_per_unit > 0.0 && o.meters_per_unit.is_finite()) {
        return Err(Error::InvalidParameter(format!("usd: meters_per_unit must be > 0, got {}", o.meters_per_unit)));
    }
    for (k, f) in frames.iter().enumerate() {
        let t = code(f, k);
        if !t.is_finite() || (k > 0 && t <= code(&frames[k - 1], k - 1)) {
            return Err(Error::InvalidParameter(format!(
                "usd: frame {k} has time code {t}, not after the previous one"
            )));
        }
        if f.faces.is_empty() || f.positions.is_empty() {
            return Err(Error::InvalidParameter(format!("usd: frame {k} has no faces or no vertices")));
        }
        if let Some(i) = f.positions.iter().position(|p| !p.iter().all(|c| c.is_finite())) {
            return Err(Error::InvalidParameter(format!("usd: frame {k}, vertex {i} is not finite")));
        }
        if let Some(t) = f.faces.iter().position(|t| t.iter().any(|&v| v as usize >= f.positions.len())) {
            return Err(Error::InvalidParameter(format!(
                "usd: frame {k}, triangle {t} refers to a vertex ≥ {}",
                f.positions.len()
            )));
        }
    }
    Ok(())
}

/// A number as USD text (shortest round-trip form of the f32 value; USD reads `point3f`).
fn num(x: f64) -> String {
    let v = x as f32;
    if v == 0.0 {
        "0".into()
    } else {
        format!("{v}")
    }
}

fn write_points(s: &mut String, p: &[Pt3]) {
    s.push('[');
    for (i, q) in p.iter().enumerate() {
        if i > 0 {
            s.push_str(", ");
        }
        let _ = write!(s, "({}, {}, {})", num(q.x), num(q.y), num(q.z));
    }
    s.push(']');
}

fn write_indices(s: &mut String, faces: &[[u32; 3]]) {
    s.push('[');
    for (i, t) in faces.iter().enumerate() {
        if i > 0 {
            s.push_str(", ");
        }
        let _ = write!(s, "{}, {}, {}", t[0], t[1], t[2]);
    }
    s.push(']');
}

fn write_counts(s: &mut String, n: usize) {
    s.push('[');
    for i in 0..n {
        s.push_str(if i == 0 { "3" } else { ", 3" });
    }
    s.push(']');
}

fn extent(p: &[Pt3]) -> [Pt3; 2] {
    let mut lo = p[0];
    let mut hi = p[0];
    for q in p {
        lo = lo.inf(q);
        hi = hi.sup(q);
    }
    [lo, hi]
}

/// The `.usda` text of an animated mesh named `name` (made a valid prim name): topology once when
/// every frame shares frame 0's triangles, time-sampled otherwise; points and extent per frame.
///
/// Errors (`InvalidParameter`): no frames, a frame without faces or vertices, a non-finite vertex,
/// an index out of range, `fps` or `meters_per_unit` not > 0.
pub fn to_string(name: &str, frames: &[UsdFrame], o: &UsdOptions) -> Result<String> {
    check(frames, o)?;
    let root = prim_name(name);
    let fixed = frames.iter().all(|f| f.faces == frames[0].faces);
    let mut s = String::new();
    s.push_str("#usda 1.0\n(\n");
    let _ = writeln!(s, "    defaultPrim = \"{root}\"");
    if !o.doc.is_empty() {
        let _ = writeln!(s, "    doc = \"{}\"", o.doc.replace('\\', "\\\\").replace('"', "\\\""));
    }
    let _ = writeln!(s, "    endTimeCode = {}", code(&frames[frames.len() - 1], frames.len() - 1));
    let _ = writeln!(s, "    framesPerSecond = {}", o.fps);
    let _ = writeln!(s, "    metersPerUnit = {}", o.meters_per_unit);
    let _ = writeln!(s, "    startTimeCode = {}", code(&frames[0], 0));
    let _ = writeln!(s, "    timeCodesPerSecond = {}", o.fps);
    s.push_str("    upAxis = \"Y\"\n)\n\n");
    let _ = writeln!(s, "def Xform \"{root}\" (\n    kind = \"component\"\n)\n{{");
    s.push_str("    def Mesh \"mesh\"\n    {\n");
    s.push_str("        uniform bool doubleSided = 1\n");
    // extent: per frame.
    s.push_str("        float3[] extent.timeSamples = {\n");
    for (k, f) in frames.iter().enumerate() {
        let _ = write!(s, "            {}: ", code(f, k));
        write_points(&mut s, &extent(f.positions));
        s.push_str(",\n");
    }
    s.push_str("        }\n");
    if fixed {
        s.push_str("        int[] faceVertexCounts = ");
        write_counts(&mut s, frames[0].faces.len());
        s.push_str("\n        int[] faceVertexIndices = ");
        write_indices(&mut s, frames[0].faces);
        s.push('\n');
    } else {
        s.push_str("        int[] faceVertexCounts.timeSamples = {\n");
        for (k, f) in frames.iter().enumerate() {
            let _ = write!(s, "            {}: ", code(f, k));
            write_counts(&mut s, f.faces.len());
            s.push_str(",\n");
        }
        s.push_str("        }\n        int[] faceVertexIndices.timeSamples = {\n");
        for (k, f) in frames.iter().enumerate() {
            let _ = write!(s, "            {}: ", code(f, k));
            write_indices(&mut s, f.faces);
            s.push_str(",\n");
        }
        s.push_str("        }\n");
    }
    s.push_str("        point3f[] points.timeSamples = {\n");
    for (k, f) in frames.iter().enumerate() {
        let _ = write!(s, "            {}: ", code(f, k));
        write_points(&mut s, f.positions);
        s.push_str(",\n");
    }
    s.push_str("        }\n");
    s.push_str("        uniform token subdivisionScheme = \"none\"\n");
    s.push_str("    }\n}\n");
    Ok(s)
}

/// Writes [`to_string`] to `path`; errors name the file.
pub fn write(path: impl AsRef<Path>, name: &str, frames: &[UsdFrame], o: &UsdOptions) -> Result<()> {
    let text = to_string(name, frames, o)?;
    write_file(path.as_ref(), |w| w.write_all(text.as_bytes()).map_err(Error::Io))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn quad(z: f64) -> Vec<Pt3> {
        vec![Pt3::new(0.0, 0.0, z), Pt3::new(1.0, 0.0, z), Pt3::new(1.0, 1.0, z), Pt3::new(0.0, 1.0, z)]
    }

    #[test]
    fn fixed_topology_once_points_per_frame_and_stage_metadata() {
        let (a, b) = (quad(0.0), quad(0.25));
        let f = [[0, 1, 2], [0, 2, 3]];
        let t =
            to_string("frames/seq 1", &[UsdFrame::new(&a, &f), UsdFrame::new(&b, &f)], &UsdOptions::default()).unwrap();
        for needle in [
            "defaultPrim = \"frames_seq_1\"",
            "upAxis = \"Y\"",
            "metersPerUnit = 1",
            "timeCodesPerSecond = 24",
            "endTimeCode = 1",
            "def Xform \"frames_seq_1\"",
            "int[] faceVertexIndices = [0, 1, 2, 0, 2, 3]",
            "1: [(0, 0, 0.25), (1, 0, 0.25), (1, 1, 0.25), (0, 1, 0.25)]",
            "subdivisionScheme = \"none\"",
        ] {
            assert!(t.contains(needle), "missing {needle} in\n{t}");
        }
        assert_eq!(t.matches("faceVertexCounts").count(), 1);
    }

    #[test]
    fn frames_keep_their_own_time_codes() {
        let a = quad(0.0);
        let f = [[0, 1, 2]];
        let t =
            to_string("s", &[UsdFrame::new(&a, &f), UsdFrame::new(&a, &f).at(10.0)], &UsdOptions::default()).unwrap();
        assert!(t.contains("endTimeCode = 10") && t.contains("            10: ["), "{t}");
        let back = [UsdFrame::new(&a, &f).at(5.0), UsdFrame::new(&a, &f).at(5.0)];
        assert!(to_string("s", &back, &UsdOptions::default()).is_err(), "time codes must increase");
    }

    #[test]
    fn changing_topology_is_time_sampled() {
        let a = quad(0.0);
        let (f0, f1) = ([[0, 1, 2], [0, 2, 3]], [[0, 1, 3]]);
        let t = to_string("s", &[UsdFrame::new(&a, &f0), UsdFrame::new(&a[..], &f1)], &UsdOptions::default()).unwrap();
        assert!(t.contains("faceVertexIndices.timeSamples"));
        assert!(t.contains("1: [0, 1, 3]"));
    }

    /// Where tests leave standard-format files for CI's validators (`.ci/validate-formats`):
    /// `<workspace>/target/test-outputs/<crate>/`.
    fn test_outputs() -> std::path::PathBuf {
        let d = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../target/test-outputs/geom-core");
        std::fs::create_dir_all(&d).expect("test-outputs folder");
        d
    }

    #[test]
    fn files_for_the_validators() {
        // A waving sheet (fixed topology) and a surface whose topology changes.
        let n = 6;
        let mut faces = Vec::new();
        for j in 0..n - 1 {
            for i in 0..n - 1 {
                let a = (j * n + i) as u32;
                faces.push([a, a + 1, a + n as u32 + 1]);
                faces.push([a, a + n as u32 + 1, a + n as u32]);
            }
        }
        let frames: Vec<Vec<Pt3>> = (0..10)
            .map(|k| {
                (0..n * n)
                    .map(|v| {
                        let (x, z) = ((v % n) as f64 / 5.0, (v / n) as f64 / 5.0);
                        Pt3::new(x, 0.1 * (x * 6.0 + k as f64 * 0.5).sin(), z)
                    })
                    .collect()
            })
            .collect();
        let seq: Vec<UsdFrame> = frames.iter().map(|p| UsdFrame::new(p, &faces)).collect();
        let dir = test_outputs();
        let opts = UsdOptions { fps: 30.0, doc: "geom-core usd test: waving sheet".into(), ..Default::default() };
        write(dir.join("usd_sheet.usda"), "sheet", &seq, &opts).unwrap();
        let fewer = &faces[..faces.len() / 2];
        let varying = [UsdFrame::new(&frames[0], &faces), UsdFrame::new(&frames[1], fewer)];
        write(dir.join("usd_varying.usda"), "surface", &varying, &UsdOptions::default()).unwrap();
        let back = std::fs::read_to_string(dir.join("usd_sheet.usda")).unwrap();
        assert!(back.starts_with("#usda 1.0") && back.contains("9: ["));
    }

    #[test]
    fn bad_input_is_an_error() {
        let a = quad(0.0);
        let f = [[0, 1, 2]];
        assert!(to_string("s", &[], &UsdOptions::default()).is_err());
        assert!(to_string("s", &[UsdFrame::new(&a, &[[0, 1, 7]])], &UsdOptions::default()).is_err());
        let mut nan = a.clone();
        nan[1].x = f64::NAN;
        assert!(to_string("s", &[UsdFrame::new(&nan, &f)], &UsdOptions::default()).is_err());
        assert!(to_string("s", &[UsdFrame::new(&a, &f)], &UsdOptions { fps: 0.0, ..Default::default() }).is_err());
        assert_eq!(prim_name("0abc"), "_0abc");
    }
}

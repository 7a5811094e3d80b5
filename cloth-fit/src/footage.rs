//! The real-footage path (spec §3.4): PNG frame sequences, lens undistortion, the calibration
//! file, corner tracks from CSV, silhouettes, and `write_synthetic_capture`, which writes a
//! synthetic experiment in exactly this format so that the path can be tested end to end.
//!
//! The paper captured "video of real fabric" under projected stripes, measured the corners
//! "using a Vicon motion capture system" and computed "the projection matrices for the camera
//! and projector using a calibration grid comprising of several motion capture markers"
//! (Bhat et al. 2003 §5).

use std::path::{Path, PathBuf};

use geom_core::image::{read_png, write_png_gray8, Border, ImageF32, Mask};
use geom_core::math::{Pt2, Pt3};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::angle::{angle_map, AngleOptions};
use crate::camera::decompose;
use crate::error::{FitError, Result};
use crate::morphology::{close, largest_component, open};
use crate::objective::Target;
use crate::rig::{CameraSpec, ProjectorSpec, Rig, RigSpec};
use crate::setup::{Experiment, ExperimentKind};
use crate::trajectory::Trajectory;

fn io(path: &Path, e: impl std::fmt::Display) -> FitError {
    FitError::Io { path: path.to_path_buf(), msg: e.to_string() }
}

/// The file name of frame `k` of a printf-style pattern with one `%0Nd` (or `%d`).
pub fn frame_path(pattern: &str, k: usize) -> Result<PathBuf> {
    let start = pattern
        .find('%')
        .ok_or_else(|| FitError::BadParameter(format!("frame pattern '{pattern}' has no %d / %0Nd field")))?;
    let rest = &pattern[start + 1..];
    let dpos = rest
        .find('d')
        .ok_or_else(|| FitError::BadParameter(format!("frame pattern '{pattern}': expected %d or %0Nd")))?;
    let spec = &rest[..dpos];
    let width: usize = if spec.is_empty() {
        0
    } else {
        spec.trim_start_matches('0')
            .parse()
            .map_err(|_| FitError::BadParameter(format!("frame pattern '{pattern}': bad width '{spec}'")))?
    };
    Ok(PathBuf::from(format!("{}{:0width$}{}", &pattern[..start], k, &rest[dpos + 1..])))
}

/// Loads frames `first .. first + count` of a PNG sequence as luminance in [0, 1] (spec §3.4
/// step 1): 8/16-bit gray, gray + alpha, RGB, RGBA and palette images; RGB through
/// Y = 0.2126R + 0.7152G + 0.0722B on the stored values. Errors name the file (missing,
/// corrupt, truncated) and catch frames whose size differs from the first.
pub fn load_png_sequence(pattern: &str, first: usize, count: usize) -> Result<Vec<ImageF32>> {
    let paths: Vec<PathBuf> = (first..first + count).map(|k| frame_path(pattern, k)).collect::<Result<_>>()?;
    let frames: Vec<ImageF32> = paths.par_iter().map(|p| read_png(p).map_err(|e| io(p, e))).collect::<Result<_>>()?;
    if let Some(f0) = frames.first() {
        for (f, p) in frames.iter().zip(&paths) {
            if (f.width, f.height) != (f0.width, f0.height) {
                return Err(FitError::ImageSizeMismatch {
                    what: p.display().to_string(),
                    expected: (f0.width, f0.height),
                    got: (f.width, f.height),
                });
            }
        }
    }
    Ok(frames)
}

/// Checks that every frame has the camera's size (spec §3.4 step 1).
pub fn check_sizes(frames: &[ImageF32], rig: &Rig, what: &str) -> Result<()> {
    for (k, f) in frames.iter().enumerate() {
        if (f.width, f.height) != (rig.camera.width, rig.camera.height) {
            return Err(FitError::ImageSizeMismatch {
                what: format!("{what} frame {k}"),
                expected: (rig.camera.width, rig.camera.height),
                got: (f.width, f.height),
            });
        }
    }
    Ok(())
}

/// Resamples a frame of the real (distorted) camera into the distortion-free camera of the rig
/// (spec §3.4 step 2; bilinear, clamped at the border). Without distortion the frame is
/// returned unchanged.
pub fn undistort(img: &ImageF32, rig: &Rig) -> ImageF32 {
    let Some(d) = rig.distortion else { return img.clone() };
    let (k, _, _) = decompose(&rig.camera);
    let mut out = ImageF32::new(img.width, img.height, 0.0);
    for y in 0..img.height {
        for x in 0..img.width {
            let q = d.distorted_pixel(&k, Pt2::new(x as f64, y as f64));
            out.set(x, y, img.sample_bilinear(q.x, q.y, Border::Clamp));
        }
    }
    out
}

/// Corner tracks read from CSV, with what the reader noticed.
#[derive(Clone, Debug, PartialEq)]
pub struct CornerTracks {
    /// Paths of corner 0 and corner 1.
    pub corners: [Trajectory; 2],
    /// Warnings (e.g. samples that end before the sequence).
    pub warnings: Vec<String>,
}

/// Reads corner tracks (spec §3.4 step 5): header `t,corner,x,y,z` (seconds, corner 0 or 1,
/// metres in the calibration's world frame). A corner with one row is `Fixed`, more rows give
/// Catmull–Rom `Samples`. Errors name the file and line: a missing or wrong header, a bad
/// number, a corner index other than 0/1, non-increasing times, or a corner without rows.
pub fn load_corner_tracks(path: &Path) -> Result<CornerTracks> {
    let text = std::fs::read_to_string(path).map_err(|e| io(path, e))?;
    let csv = |line: usize, msg: String| FitError::Csv { path: path.to_path_buf(), line, msg };
    let mut lines = text.lines().enumerate().filter(|(_, l)| !l.trim().is_empty());
    let (_, header) = lines.next().ok_or_else(|| csv(0, "empty file (expected header t,corner,x,y,z)".into()))?;
    let cols: Vec<String> = header.split(',').map(|s| s.trim().to_lowercase()).collect();
    if cols != ["t", "corner", "x", "y", "z"] {
        return Err(csv(1, format!("header must be t,corner,x,y,z, got '{header}'")));
    }
    let mut samples: [Vec<(f64, Pt3)>; 2] = [Vec::new(), Vec::new()];
    for (i, line) in lines {
        let ln = i + 1;
        let f: Vec<&str> = line.split(',').map(str::trim).collect();
        if f.len() != 5 {
            return Err(csv(ln, format!("expected 5 fields, got {}", f.len())));
        }
        let num = |k: usize, name: &str| -> Result<f64> {
            let v: f64 = f[k].parse().map_err(|_| csv(ln, format!("{name} '{}' is not a number", f[k])))?;
            if !v.is_finite() {
                return Err(csv(ln, format!("{name} is not finite")));
            }
            Ok(v)
        };
        let t = num(0, "t")?;
        let c: usize = match f[1] {
            "0" => 0,
            "1" => 1,
            other => return Err(csv(ln, format!("corner must be 0 or 1, got '{other}'"))),
        };
        let p = Pt3::new(num(2, "x")?, num(3, "y")?, num(4, "z")?);
        if let Some(&(tp, _)) = samples[c].last() {
            if t <= tp {
                return Err(csv(ln, format!("corner {c}: time {t} not after {tp}")));
            }
        }
        samples[c].push((t, p));
    }
    let mk = |c: usize, s: Vec<(f64, Pt3)>| -> Result<Trajectory> {
        match s.len() {
            0 => Err(csv(0, format!("corner {c} has no rows"))),
            1 => Ok(Trajectory::Fixed(s[0].1)),
            _ => Ok(Trajectory::Samples(s)),
        }
    };
    let [s0, s1] = samples;
    let corners = [mk(0, s0)?, mk(1, s1)?];
    Ok(CornerTracks { corners, warnings: Vec::new() })
}

/// Warnings for tracks that do not cover `[t0, t1]` (the end values are held, spec §8).
pub fn coverage_warnings(tracks: &CornerTracks, t0: f64, t1: f64) -> Vec<String> {
    let mut w = Vec::new();
    for (c, tr) in tracks.corners.iter().enumerate() {
        if let Some((a, b)) = tr.sample_range() {
            if a > t0 + 1e-9 || b < t1 - 1e-9 {
                w.push(format!(
                    "corner {c}: samples cover [{a:.4}, {b:.4}] s but the sequence needs [{t0:.4}, {t1:.4}] s; end values held"
                ));
            }
        }
    }
    w
}

/// Where silhouettes come from (spec §3.4 step 6).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum SilhouetteSource {
    /// |I − I_plate| > threshold against a background plate.
    Background {
        /// The plate (PNG).
        plate: PathBuf,
        /// Threshold (intensity units).
        threshold: f64,
    },
    /// I > level (dark backdrop).
    Threshold {
        /// Level.
        level: f64,
    },
    /// User masks, non-zero = inside (printf pattern, same numbering as the frames).
    Masks {
        /// Pattern.
        pattern: String,
        /// First index.
        first: usize,
    },
}

/// Raw silhouette → close (radius 2) → open (radius 1) → largest 4-connected component.
pub fn clean_silhouette(raw: &Mask) -> Mask {
    largest_component(&open(&close(raw, 2), 1))
}

/// Silhouettes of `frames` (spec §3.4 step 6). Errors: unreadable plate or masks (naming the
/// file), size mismatches, a non-finite threshold.
pub fn silhouettes(frames: &[ImageF32], s: &SilhouetteSource) -> Result<Vec<Mask>> {
    let raw: Vec<Mask> = match s {
        SilhouetteSource::Background { plate, threshold } => {
            if !threshold.is_finite() {
                return Err(FitError::BadParameter("background threshold is not finite".into()));
            }
            let p = read_png(plate).map_err(|e| io(plate, e))?;
            frames
                .iter()
                .enumerate()
                .map(|(k, f)| {
                    if (f.width, f.height) != (p.width, p.height) {
                        return Err(FitError::ImageSizeMismatch {
                            what: format!("frame {k} vs background plate {}", plate.display()),
                            expected: (p.width, p.height),
                            got: (f.width, f.height),
                        });
                    }
                    let data = f.data.iter().zip(&p.data).map(|(a, b)| (a - b).abs() as f64 > *threshold).collect();
                    Ok(Mask { width: f.width, height: f.height, data })
                })
                .collect::<Result<_>>()?
        }
        SilhouetteSource::Threshold { level } => frames
            .iter()
            .map(|f| Mask {
                width: f.width,
                height: f.height,
                data: f.data.iter().map(|&v| v as f64 > *level).collect(),
            })
            .collect(),
        SilhouetteSource::Masks { pattern, first } => {
            let m = load_png_sequence(pattern, *first, frames.len())?;
            m.iter()
                .zip(frames)
                .enumerate()
                .map(|(k, (mi, f))| {
                    if (mi.width, mi.height) != (f.width, f.height) {
                        return Err(FitError::ImageSizeMismatch {
                            what: format!("mask {k}"),
                            expected: (f.width, f.height),
                            got: (mi.width, mi.height),
                        });
                    }
                    Ok(Mask { width: mi.width, height: mi.height, data: mi.data.iter().map(|&v| v > 0.0).collect() })
                })
                .collect::<Result<_>>()?
        }
    };
    Ok(raw.par_iter().map(clean_silhouette).collect())
}

/// A capture on disk in the format of spec §3.4.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CaptureSpec {
    /// Frame pattern, e.g. `frames/frame_%04d.png` (relative to the capture directory).
    pub frames: String,
    /// First frame index.
    pub first: usize,
    /// Number of frames.
    pub count: usize,
    /// Calibration file (RON [`RigSpec`]).
    pub rig: String,
    /// Corner CSV.
    pub corners: String,
    /// Silhouettes.
    pub silhouettes: SilhouetteSource,
}

/// Calibration markers used by [`write_synthetic_capture`]: a 4 × 3 × 3 grid around the swatch
/// (the paper's "calibration grid comprising of several motion capture markers").
pub fn marker_grid() -> Vec<Pt3> {
    let mut v = Vec::new();
    for i in 0..4 {
        for j in 0..3 {
            for k in 0..3 {
                v.push(Pt3::new(-0.3 + 0.2 * i as f64, -0.15 + 0.15 * j as f64, -0.55 + 0.3 * k as f64));
            }
        }
    }
    v
}

/// Writes a synthetic capture of experiment `e` into `dir` (spec §3.4 step 7): the footage
/// frames as 8-bit PNGs `frames/frame_NNNN.png`, a background plate `background.png` (the
/// backdrop through the same degradation), `rig.ron` with camera and projector as marker
/// correspondences (so the DLT runs on reading), `corners.csv` sampled at 120 Hz over the
/// sequence, and `capture.ron` ([`CaptureSpec`]). `plate` is the empty-scene image.
pub fn write_synthetic_capture(
    dir: &Path,
    images: &[ImageF32],
    plate: &ImageF32,
    rig: &Rig,
    e: &Experiment,
    silhouette_threshold: f64,
) -> Result<CaptureSpec> {
    let fdir = dir.join("frames");
    std::fs::create_dir_all(&fdir).map_err(|er| io(&fdir, er))?;
    for (k, img) in images.iter().enumerate() {
        let p = fdir.join(format!("frame_{k:04}.png"));
        write_png_gray8(&p, img).map_err(|er| io(&p, er))?;
    }
    let pp = dir.join("background.png");
    write_png_gray8(&pp, plate).map_err(|er| io(&pp, er))?;
    // Markers through the nominal camera and projector.
    let world = marker_grid();
    let proj = |c: &geom_core::raster::Camera| -> Result<Vec<Pt2>> {
        world
            .iter()
            .map(|x| {
                c.project(x).map(|(p, _)| p).ok_or_else(|| FitError::BadParameter("marker behind a camera".into()))
            })
            .collect()
    };
    let spec = RigSpec {
        camera: CameraSpec::Markers {
            world: world.clone(),
            image: proj(&rig.camera)?,
            width: rig.camera.width,
            height: rig.camera.height,
            distortion: rig.distortion,
        },
        projector: ProjectorSpec {
            camera: CameraSpec::Markers {
                world: world.clone(),
                image: proj(&rig.projector.camera)?,
                width: rig.projector.camera.width,
                height: rig.projector.camera.height,
                distortion: None,
            },
            stripe_period_px: rig.projector.stripe_period_px,
            profile: rig.projector.profile,
        },
        fps: rig.fps,
        world_up: rig.world_up,
        time_offset_s: 0.0,
    };
    let rp = dir.join("rig.ron");
    let text = ron::ser::to_string_pretty(&spec, ron::ser::PrettyConfig::default()).map_err(|er| io(&rp, er))?;
    std::fs::write(&rp, text).map_err(|er| io(&rp, er))?;
    // Corners at 120 Hz over the sequence (and one sample beyond its end).
    let t_end = (e.frames.max(1) - 1) as f64 / rig.fps;
    let n = (t_end * 120.0).ceil() as usize + 1;
    let mut csv = String::from("t,corner,x,y,z\n");
    for c in 0..2 {
        for k in 0..=n {
            let t = k as f64 / 120.0;
            let p = e.corner_at(c, t);
            csv.push_str(&format!("{t:?},{c},{:?},{:?},{:?}\n", p.x, p.y, p.z));
        }
    }
    let cp = dir.join("corners.csv");
    std::fs::write(&cp, csv).map_err(|er| io(&cp, er))?;
    let cap = CaptureSpec {
        frames: "frames/frame_%04d.png".into(),
        first: 0,
        count: images.len(),
        rig: "rig.ron".into(),
        corners: "corners.csv".into(),
        silhouettes: SilhouetteSource::Background { plate: "background.png".into(), threshold: silhouette_threshold },
    };
    let sp = dir.join("capture.ron");
    let text = ron::ser::to_string_pretty(&cap, ron::ser::PrettyConfig::default()).map_err(|er| io(&sp, er))?;
    std::fs::write(&sp, text).map_err(|er| io(&sp, er))?;
    Ok(cap)
}

/// A capture read back from disk and preprocessed.
#[derive(Clone, Debug)]
pub struct LoadedCapture {
    /// The rig from the calibration file (DLT solved).
    pub rig: Rig,
    /// RMS reprojection error of the camera / projector DLT (px).
    pub calib_rms_px: (f64, f64),
    /// The tracked experiment.
    pub experiment: Experiment,
    /// The preprocessed target.
    pub target: Target,
    /// The (undistorted) frames.
    pub frames: Vec<ImageF32>,
    /// Their silhouettes.
    pub silhouettes: Vec<Mask>,
    /// Warnings (track coverage …).
    pub warnings: Vec<String>,
}

/// Reads a capture (`capture.ron` in `dir`) and preprocesses it into a target: calibration,
/// frames (sizes checked against the camera, undistorted), corner tracks, silhouettes, angle
/// maps. `template` gives the swatch and settle protocol of the experiment. Every input error
/// is raised here, before any evaluation.
pub fn load_capture(dir: &Path, template: &Experiment, angle: &AngleOptions) -> Result<LoadedCapture> {
    let sp = dir.join("capture.ron");
    let text = std::fs::read_to_string(&sp).map_err(|e| io(&sp, e))?;
    let cap: CaptureSpec = ron::from_str(&text).map_err(|e| FitError::Parse {
        path: sp.clone(),
        line: e.span.start.line,
        col: e.span.start.col,
        msg: e.code.to_string(),
    })?;
    let built = crate::rig::load_rig(&dir.join(&cap.rig))?;
    let rig = built.rig;
    let pattern = dir.join(&cap.frames).display().to_string();
    let frames = load_png_sequence(&pattern, cap.first, cap.count)?;
    check_sizes(&frames, &rig, &pattern)?;
    let frames: Vec<ImageF32> = frames.par_iter().map(|f| undistort(f, &rig)).collect();
    let tracks = load_corner_tracks(&dir.join(&cap.corners))?;
    let t1 = rig.time_offset_s + (cap.count.max(1) - 1) as f64 / rig.fps;
    let mut warnings = coverage_warnings(&tracks, rig.time_offset_s, t1);
    warnings.extend(tracks.warnings.iter().cloned());
    let src = match &cap.silhouettes {
        SilhouetteSource::Background { plate, threshold } => {
            SilhouetteSource::Background { plate: dir.join(plate), threshold: *threshold }
        }
        SilhouetteSource::Masks { pattern, first } => {
            SilhouetteSource::Masks { pattern: dir.join(pattern).display().to_string(), first: *first }
        }
        other => other.clone(),
    };
    let sils = silhouettes(&frames, &src)?;
    let experiment = Experiment {
        kind: ExperimentKind::Tracked { corners: tracks.corners.clone(), start_s: rig.time_offset_s },
        swatch: template.swatch,
        frames: cap.count,
        settle: template.settle,
    };
    experiment.validate()?;
    let af: Vec<_> = frames.par_iter().zip(sils.par_iter()).map(|(f, s)| angle_map(f, s, angle)).collect();
    Ok(LoadedCapture {
        rig,
        calib_rms_px: (built.camera_rms_px, built.projector_rms_px),
        target: Target { experiment: experiment.clone(), frames: af },
        experiment,
        frames,
        silhouettes: sils,
        warnings,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frame_patterns() {
        assert_eq!(frame_path("a/frame_%04d.png", 7).unwrap(), PathBuf::from("a/frame_0007.png"));
        assert_eq!(frame_path("f%d.png", 12).unwrap(), PathBuf::from("f12.png"));
        assert!(frame_path("nopattern.png", 1).is_err());
    }
}

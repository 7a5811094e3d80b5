//! BVH motion files (motion-graph.md §2.2): [`read`] into a [`Motion`] (metres, quaternions,
//! roles guessed), [`write()`] back in the stored channel layout, and [`inspect`] for a report that
//! does not fail on a frame-count mismatch.
//!
//! Semantics: a joint's local transform is `T(offset + p)·R` with `p` its position channels and
//! `R = R_a1(θ1)·R_a2(θ2)·R_a3(θ3)` for its rotation channels in the listed order (degrees in
//! the file); any order, fewer than three rotation channels, position channels on any joint and
//! `End Site`s are supported. The root's OFFSET is folded into [`Motion::root_pos`] (world root
//! position); position channels of other joints go to [`Motion::extra_trans`]. End sites become
//! joints named `<parent>_End`. After reading, hemispheres are fixed and roles guessed.
//!
//! Errors are [`BvhError`]s with the 1-based line where the problem was found; no input panics.

mod lex;
mod parse;
mod write;

pub use write::{write, BvhWriteOptions};

use super::motion::Motion;
use super::skeleton::{Channel, Joint, JointRole, Skeleton};
#[cfg(doc)]
use crate::error::BvhError;
use crate::error::{Error, Result};
use crate::math::{axis_quat, UnitQuat, Vec3};
use parse::{Mode, Parsed};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::fmt;
use std::path::Path;
use std::sync::Arc;

/// Length unit of a BVH file's OFFSET and position values.
#[derive(Clone, Copy, Debug, PartialEq, Default, Serialize, Deserialize)]
pub enum BvhUnits {
    /// 1 unit = 1 m.
    Metres,
    /// 1 unit = 0.01 m.
    Centimetres,
    /// 1 unit = 0.0254 m.
    Inches,
    /// CMU ASF length unit: 1 unit = 0.056444 m (1/0.45 inch; the cgspeed CMU BVH conversion).
    CmuAsf,
    /// 1 unit = the given number of metres.
    Scale(f64),
    /// Reading: pick among metres, centimetres, inches and CMU-ASF the scale that brings the
    /// rest-pose leg length ([`Skeleton::leg_length`], root to toe drop) closest to 0.9 m in ratio
    /// (smallest `|ln(scale·L / 0.9 m)|`): CMU files (L ≈ 16 units) get CMU-ASF, centimetre files
    /// (L ≈ 92) centimetres, metre files metres. A skeleton with zero leg length is read as
    /// metres. Writing: centimetres.
    #[default]
    Auto,
}

/// Metres per CMU-ASF length unit.
pub const CMU_ASF_METRES: f64 = 0.056444;

impl BvhUnits {
    /// Metres per file unit, `None` for [`BvhUnits::Auto`].
    pub fn scale(self) -> Option<f64> {
        match self {
            BvhUnits::Metres => Some(1.0),
            BvhUnits::Centimetres => Some(0.01),
            BvhUnits::Inches => Some(0.0254),
            BvhUnits::CmuAsf => Some(CMU_ASF_METRES),
            BvhUnits::Scale(s) => Some(s),
            BvhUnits::Auto => None,
        }
    }

    /// The unit [`BvhUnits::Auto`] picks for a leg length of `leg` file units.
    pub fn auto_for_leg_length(leg: f64) -> BvhUnits {
        if !(leg > 0.0 && leg.is_finite()) {
            return BvhUnits::Metres;
        }
        let cands = [BvhUnits::Metres, BvhUnits::Centimetres, BvhUnits::Inches, BvhUnits::CmuAsf];
        let score = |u: &BvhUnits| (u.scale().unwrap_or(1.0) * leg / 0.9).ln().abs();
        cands.into_iter().min_by(|a, b| score(a).total_cmp(&score(b))).unwrap_or(BvhUnits::Metres)
    }
}

/// What to do when the number of frame rows differs from the `Frames:` line.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, Serialize, Deserialize)]
pub enum FrameCount {
    /// Read exactly the declared frames: fewer → [`BvhError::Truncated`]; extra rows are ignored
    /// (some exporters write one more row than they declare; [`read_with_info`] reports it).
    #[default]
    Strict,
    /// Keep every complete row found, fewer or more than declared (an incomplete last row is
    /// dropped); only zero complete rows is an error.
    Lenient,
}

/// Reader options (serialisable, so scene files can carry them; missing fields take defaults).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct BvhOptions {
    /// Length unit of the file (default [`BvhUnits::Auto`]).
    pub units: BvhUnits,
    /// Frame-count policy (default [`FrameCount::Strict`]).
    pub frame_count: FrameCount,
    /// Roles to assign by joint name after guessing (overrides the guesses); a name that is not in
    /// the file is an [`Error::InvalidParameter`].
    pub roles: Option<BTreeMap<JointRole, String>>,
}

/// What a BVH file holds, as reported by [`inspect`] and [`read_with_info`].
#[derive(Clone, Debug, PartialEq)]
pub struct BvhInfo {
    /// The hierarchy with offsets in **file units** (not scaled), end sites named `<parent>_End`,
    /// roles guessed.
    pub skeleton: Skeleton,
    /// Channels per frame row.
    pub channels: usize,
    /// The `Frames:` count.
    pub declared_frames: usize,
    /// Complete rows of values present in the file.
    pub rows_present: usize,
    /// Values of an incomplete final row (0 for a well-formed file).
    pub trailing_values: usize,
    /// `Frame Time:` (s).
    pub frame_time: f64,
    /// The unit [`BvhUnits::Auto`] picks for this file.
    pub auto_units: BvhUnits,
    /// Rest-pose leg length in file units.
    pub leg_length_units: f64,
}

impl BvhInfo {
    /// Frames per second.
    pub fn frame_rate(&self) -> f64 {
        1.0 / self.frame_time
    }

    /// Joints that are not end sites.
    pub fn joint_count(&self) -> usize {
        self.skeleton.joints.iter().filter(|j| !j.end_site).count()
    }

    /// End sites.
    pub fn end_site_count(&self) -> usize {
        self.skeleton.joints.iter().filter(|j| j.end_site).count()
    }

    /// Whether the present rows differ from the declared count (or a partial row exists).
    pub fn count_mismatch(&self) -> bool {
        self.rows_present != self.declared_frames || self.trailing_values != 0
    }
}

impl fmt::Display for BvhInfo {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(f, "BVH skeleton '{}'", self.skeleton.name)?;
        writeln!(
            f,
            "  joints: {} (+{} end sites), channels per frame: {}",
            self.joint_count(),
            self.end_site_count(),
            self.channels
        )?;
        write!(f, "  frames: {} declared, {} present", self.declared_frames, self.rows_present)?;
        if self.trailing_values > 0 {
            write!(f, " (+{} values of an incomplete row)", self.trailing_values)?;
        }
        if self.rows_present < self.declared_frames {
            write!(f, "  MISMATCH: {} rows missing (strict reading fails)", self.declared_frames - self.rows_present)?;
        } else if self.rows_present > self.declared_frames {
            write!(
                f,
                "  MISMATCH: {} extra rows (ignored by strict reading)",
                self.rows_present - self.declared_frames
            )?;
        }
        writeln!(f)?;
        let dur = self.declared_frames.saturating_sub(1) as f64 * self.frame_time;
        writeln!(f, "  frame time: {} s ({:.3} Hz), duration {:.3} s", self.frame_time, self.frame_rate(), dur)?;
        let scale = self.auto_units.scale().unwrap_or(1.0);
        writeln!(
            f,
            "  units (auto): {:?}, {} m per unit; leg length {:.3} units = {:.3} m",
            self.auto_units,
            scale,
            self.leg_length_units,
            self.leg_length_units * scale
        )?;
        writeln!(f, "  hierarchy:")?;
        let mut depth = vec![0usize; self.skeleton.joints.len()];
        for (i, j) in self.skeleton.joints.iter().enumerate() {
            if let Some(p) = j.parent {
                depth[i] = depth[p as usize] + 1;
            }
            let role = self.skeleton.roles.iter().find(|(_, &v)| v as usize == i).map(|(r, _)| format!(" <{r:?}>"));
            let chans: Vec<&str> = j.channels.iter().map(|c| c.bvh_name()).collect();
            writeln!(
                f,
                "    {}{}{} [{}]{}",
                "  ".repeat(depth[i].min(40)),
                j.name,
                if j.end_site { " (end site)" } else { "" },
                chans.join(" "),
                role.unwrap_or_default()
            )?;
        }
        Ok(())
    }
}

/// Raw joints → skeleton with offsets multiplied by `scale`.
fn build_skeleton(p: &Parsed, scale: f64) -> Skeleton {
    let joints = p
        .joints
        .iter()
        .map(|j| Joint {
            name: j.name.clone(),
            parent: j.parent.map(|x| x as u16),
            offset: Vec3::new(j.offset[0], j.offset[1], j.offset[2]) * scale,
            channels: j.channels.clone(),
            end_site: j.end_site,
        })
        .collect();
    let name = p.joints.first().map(|j| j.name.clone()).unwrap_or_default();
    let mut s = Skeleton { name, joints, roles: BTreeMap::new() };
    s.guess_roles();
    s
}

fn info_of(p: &Parsed) -> BvhInfo {
    let skeleton = build_skeleton(p, 1.0);
    let leg = skeleton.leg_length();
    BvhInfo {
        channels: p.channels,
        declared_frames: p.declared,
        rows_present: p.rows_present,
        trailing_values: p.trailing,
        frame_time: p.frame_time,
        auto_units: BvhUnits::auto_for_leg_length(leg),
        leg_length_units: leg,
        skeleton,
    }
}

/// Reads a BVH text into a motion (see the module docs). Equivalent to [`read_with_info`]
/// without the report.
pub fn read(text: &str, opts: &BvhOptions) -> Result<Motion> {
    read_with_info(text, opts).map(|(m, _)| m)
}

/// Reads a BVH text and also returns the [`BvhInfo`] report (declared vs present rows, the unit
/// `Auto` picked, …) so that callers can warn about extra or missing rows.
pub fn read_with_info(text: &str, opts: &BvhOptions) -> Result<(Motion, BvhInfo)> {
    let mode = match opts.frame_count {
        FrameCount::Strict => Mode::Strict,
        FrameCount::Lenient => Mode::Lenient,
    };
    let p = parse::parse(text, mode)?;
    let info = info_of(&p);
    let scale = match opts.units {
        BvhUnits::Auto => info.auto_units.scale().unwrap_or(1.0),
        u => u.scale().unwrap_or(1.0),
    };
    if !(scale > 0.0 && scale.is_finite()) {
        return Err(Error::InvalidParameter(format!("BVH unit scale {scale} m must be positive and finite")));
    }
    let mut skel = build_skeleton(&p, scale);
    if let Some(roles) = &opts.roles {
        for (role, name) in roles {
            let j = skel.find(name).ok_or_else(|| {
                Error::InvalidParameter(format!("role {role:?} names joint '{name}', which is not in the file"))
            })?;
            skel.roles.retain(|_, v| *v != j);
            skel.roles.insert(*role, j);
        }
    }
    let nj = skel.joints.len();
    let frames = p.frames;
    let root_offset = skel.joints[0].offset;
    let has_extra = skel.joints.iter().skip(1).any(|j| j.channels.iter().any(|c| !c.is_rotation()));
    let mut root_pos = Vec::with_capacity(frames);
    let mut rot = Vec::with_capacity(frames * nj);
    let mut extra = if has_extra { Some(Vec::with_capacity(frames * nj)) } else { None };
    let mut k = 0;
    for _ in 0..frames {
        for (j, joint) in skel.joints.iter().enumerate() {
            let mut pos = Vec3::zeros();
            let mut q = UnitQuat::identity();
            for c in &joint.channels {
                let v = p.values[k];
                k += 1;
                match c {
                    Channel::Xpos | Channel::Ypos | Channel::Zpos => pos[c.axis()] = v * scale,
                    _ => q *= axis_quat(c.axis(), v.to_radians()),
                }
            }
            if j == 0 {
                root_pos.push(root_offset + pos);
            }
            if let Some(e) = extra.as_mut() {
                // The root's position lives in `root_pos`; its extra entry stays zero.
                e.push(if j == 0 { Vec3::zeros() } else { pos });
            }
            rot.push(q);
        }
    }
    let mut m = Motion::new(Arc::new(skel), p.frame_time, root_pos, rot, extra)?;
    m.fix_hemispheres();
    Ok((m, info))
}

/// Reads a BVH file (see [`read`]). Errors name the file: [`Error::Io`] (its kind kept, the path in
/// its message) when the file cannot be read, [`Error::InFile`] around any other error; bytes that
/// are not UTF-8 are replaced (they can only occur in names).
pub fn read_file(path: impl AsRef<Path>, opts: &BvhOptions) -> Result<Motion> {
    let path = path.as_ref();
    let bytes = std::fs::read(path)
        .map_err(|e| Error::Io(std::io::Error::new(e.kind(), format!("cannot read {}: {e}", path.display()))))?;
    read(&String::from_utf8_lossy(&bytes), opts)
        .map_err(|e| Error::InFile { path: path.to_path_buf(), source: Box::new(e) })
}

/// Reports what a BVH text holds — joints, channels, declared frame count, rows actually present,
/// frame rate, the unit `Auto` would pick — without failing on a frame-count mismatch or a zero
/// frame count. Structural errors (braces, keywords, channels, numbers, frame time) are still
/// errors, so the report never describes a file that cannot be read at all.
pub fn inspect(text: &str) -> Result<BvhInfo> {
    let p = parse::parse(text, Mode::Inspect)?;
    Ok(info_of(&p))
}

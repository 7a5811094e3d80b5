//! The motion database (motion-graph.md §3.1 steps 1–3): clips on one skeleton, resampled to
//! one rate, split into overlapping fragments, with contacts and labels.

use crate::error::{Error, Result};
use geom_core::anim::{ContactParams, FrameLabels, JointRole, Motion, Skeleton};
use geom_core::math::Pt3;
use serde::{Deserialize, Serialize};
use std::sync::Arc;

/// Database construction parameters (§4).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct DbParams {
    /// Database frame rate (Hz); default 30.
    pub rate_hz: f64,
    /// Longest fragment (frames); longer clips are split with a one-frame overlap; default 300.
    pub max_clip_frames: usize,
    /// Contact detection thresholds for clips that carry no contacts.
    pub contacts: ContactParams,
    /// Drop frame 0 of every source (the CMU converter's reference T-pose, §6.1).
    pub drop_first_frame: bool,
}

impl Default for DbParams {
    fn default() -> Self {
        Self { rate_hz: 30.0, max_clip_frames: 300, contacts: ContactParams::default(), drop_first_frame: false }
    }
}

/// Clips on one skeleton at one rate (§2.4). Fragments of one source are linked (`next`,
/// `prev`) so that derivatives at fragment ends use the neighbouring fragment (§3.1 step 2).
#[derive(Clone, Debug)]
pub struct Database {
    /// The clips (fragments), all at `rate_hz` on `skeleton`, labels in one shared name table.
    pub clips: Vec<Motion>,
    /// The shared skeleton.
    pub skeleton: Arc<Skeleton>,
    /// Frame rate (Hz).
    pub rate_hz: f64,
    /// The fragment continuing each clip (its first frame equals this clip's last), if any.
    pub next: Vec<Option<u32>>,
    /// The fragment preceding each clip, if any.
    pub prev: Vec<Option<u32>>,
    /// Source motion index of each clip.
    pub source: Vec<usize>,
    /// Label names shared by every clip (bit `i` = `labels[i]`).
    pub labels: Vec<String>,
    /// Warnings (skipped clips, detected contacts).
    pub warnings: Vec<String>,
}

/// First difference between two skeletons, if any.
fn skeleton_diff(a: &Skeleton, b: &Skeleton) -> Option<String> {
    if a.joints.len() != b.joints.len() {
        return Some(format!("{} joints instead of {}", b.joints.len(), a.joints.len()));
    }
    for (ja, jb) in a.joints.iter().zip(&b.joints) {
        if ja.name != jb.name || ja.parent != jb.parent {
            return Some(format!("joint '{}' differs from '{}' (name or parent)", jb.name, ja.name));
        }
        if (ja.offset - jb.offset).norm() > 1e-6 {
            return Some(format!("joint '{}' offset differs by {:.3e} m", jb.name, (ja.offset - jb.offset).norm()));
        }
    }
    None
}

/// Automatic labels of a real clip (§3.1 step 3): `jump` (3–30-frame runs with both feet out of
/// contact whose peak hip height exceeds the clip's median), `ground` (hip < 0.30 m), `climb`
/// (hip > 1.30 m), `stand` / `walk` / `run` by horizontal root speed (< 0.2, 0.2–2.0, > 2.0 m/s).
pub fn auto_labels(m: &mut Motion) {
    let n = m.len();
    if n == 0 {
        return;
    }
    let root = m.skeleton.role(JointRole::Root).unwrap_or(0) as usize;
    let nj = m.n_joints();
    let mut p = vec![Pt3::origin(); nj];
    let hip: Vec<f64> = (0..n)
        .map(|f| {
            m.joint_positions(f, &mut p);
            p[root].y
        })
        .collect();
    let mut sorted = hip.clone();
    sorted.sort_by(f64::total_cmp);
    let median = sorted[n / 2];
    let ids: Vec<usize> = ["jump", "ground", "climb", "stand", "walk", "run"]
        .iter()
        // Invariant: at most 6 new labels are added to a table of < 58 labels (checked below).
        .map(|l| m.labels.add(l).unwrap_or(63))
        .collect();
    let feet = FrameLabels::L_ANKLE | FrameLabels::L_TOE | FrameLabels::R_ANKLE | FrameLabels::R_TOE;
    let mut f = 0;
    while f < n {
        if m.labels.contacts[f] & feet == 0 {
            let s = f;
            while f < n && m.labels.contacts[f] & feet == 0 {
                f += 1;
            }
            let len = f - s;
            let peak = hip[s..f].iter().copied().fold(f64::MIN, f64::max);
            if (3..=30).contains(&len) && peak > median {
                for k in s..f {
                    m.labels.set(k, ids[0], true);
                }
            }
        } else {
            f += 1;
        }
    }
    for (k, &hk) in hip.iter().enumerate() {
        let a = k.saturating_sub(1);
        let b = (k + 1).min(n - 1);
        let d = m.root_pos[b] - m.root_pos[a];
        let speed = if b > a { d.x.hypot(d.z) / ((b - a) as f64 * m.frame_time) } else { 0.0 };
        if hk < 0.30 {
            m.labels.set(k, ids[1], true);
        }
        if hk > 1.30 {
            m.labels.set(k, ids[2], true);
        }
        let id = if speed < 0.2 {
            ids[3]
        } else if speed <= 2.0 {
            ids[4]
        } else {
            ids[5]
        };
        m.labels.set(k, id, true);
    }
}

impl Database {
    /// Builds the database: checks skeletons (all must equal the first one's hierarchy and
    /// offsets to 1e-6 m), resamples to `p.rate_hz` (slerp/lerp; clips already at the rate are
    /// kept as they are), detects contacts and automatic labels for clips without contacts,
    /// unifies label tables, fixes quaternion hemispheres, and splits clips longer than
    /// `max_clip_frames` into fragments overlapping by one frame. Clips shorter than 3 frames
    /// are skipped with a warning.
    ///
    /// Errors: [`Error::EmptyDatabase`] (no clip left), [`Error::SkeletonMismatch`] (naming the
    /// clip and the first differing joint), [`Error::InvalidParameter`] (rate or fragment size).
    pub fn from_motions(ms: Vec<Motion>, p: &DbParams) -> Result<Database> {
        if !(p.rate_hz.is_finite() && p.rate_hz > 0.0) {
            return Err(Error::InvalidParameter(format!("rate_hz = {} must be positive", p.rate_hz)));
        }
        if p.max_clip_frames < 3 {
            return Err(Error::InvalidParameter(format!("max_clip_frames = {} must be at least 3", p.max_clip_frames)));
        }
        let Some(first) = ms.first() else {
            return Err(Error::EmptyDatabase("no source clips".into()));
        };
        let skeleton = first.skeleton.clone();
        let dt = 1.0 / p.rate_hz;
        let mut warnings = Vec::new();
        let mut labels: Vec<String> = Vec::new();
        let mut prepared = Vec::new();
        for (i, m) in ms.into_iter().enumerate() {
            if let Some(what) = skeleton_diff(&skeleton, &m.skeleton) {
                return Err(Error::SkeletonMismatch { clip: i, what });
            }
            let m = if p.drop_first_frame { m.slice(1, m.len()) } else { m };
            let mut m = if (m.frame_time - dt).abs() > 1e-9 * dt { m.resample(dt)? } else { m };
            m.skeleton = skeleton.clone();
            if m.len() < 3 {
                warnings.push(format!("clip {i}: {} frames (< 3), skipped", m.len()));
                continue;
            }
            if m.labels.contacts.len() != m.len() || m.labels.contacts.iter().all(|&c| c == 0) {
                m.detect_contacts(&p.contacts);
                if m.labels.bits.len() != m.len() {
                    m.labels.bits = vec![0; m.len()];
                }
                auto_labels(&mut m);
                warnings.push(format!("clip {i}: contacts detected, automatic labels"));
            }
            m.fix_hemispheres();
            for l in &m.labels.names {
                if !labels.contains(l) {
                    if labels.len() >= 64 {
                        return Err(Error::InvalidParameter(format!("more than 64 labels (at '{l}')")));
                    }
                    labels.push(l.clone());
                }
            }
            prepared.push((i, m));
        }
        if prepared.is_empty() {
            return Err(Error::EmptyDatabase(format!("every clip was skipped: {}", warnings.join("; "))));
        }
        let mut clips = Vec::new();
        let mut next = Vec::new();
        let mut prev = Vec::new();
        let mut source = Vec::new();
        for (i, mut m) in prepared {
            // Remap label bits to the shared table.
            let map: Vec<usize> =
                m.labels.names.iter().map(|l| labels.iter().position(|x| x == l).unwrap_or(63)).collect();
            for b in m.labels.bits.iter_mut() {
                let old = *b;
                let mut new = 0u64;
                for (k, &g) in map.iter().enumerate() {
                    if old >> k & 1 == 1 {
                        new |= 1 << g;
                    }
                }
                *b = new;
            }
            m.labels.names = labels.clone();
            let n = m.len();
            let step = p.max_clip_frames - 1;
            let mut start = 0;
            let mut last: Option<u32> = None;
            loop {
                let end = (start + p.max_clip_frames).min(n);
                if end - start < 3 {
                    break;
                }
                let id = clips.len() as u32;
                clips.push(m.slice(start, end));
                source.push(i);
                prev.push(last);
                next.push(None);
                if let Some(l) = last {
                    next[l as usize] = Some(id);
                }
                last = Some(id);
                if end == n {
                    break;
                }
                start += step;
            }
        }
        Ok(Database { clips, skeleton, rate_hz: p.rate_hz, next, prev, source, labels, warnings })
    }

    /// Total frames.
    pub fn frames(&self) -> usize {
        self.clips.iter().map(|c| c.len()).sum()
    }

    /// Bit of label `name` in the shared table.
    pub fn label_bit(&self, name: &str) -> Option<u64> {
        self.labels.iter().position(|l| l == name).map(|i| 1u64 << i)
    }
}

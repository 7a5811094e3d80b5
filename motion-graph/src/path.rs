//! Paths through the graph, their placement on the floor and their score (motion-graph.md §3.5,
//! §3.6; paper eq. 1).
//!
//! A path is a start frame, cut edges `e_1 … e_n` and an end frame. Pieces: piece 0 = clip `c₀`
//! frames `[f₀, from(e₁)]`, piece `k` = clip `to(e_k)` frames `[to(e_k), from(e_{k+1})]`, the last
//! `[to(e_n), end_frame]`. Placement: `W₀ = B₀ ∘ T(c₀, f₀)⁻¹`; at a cut `(s,i) → (t,j)`,
//! `W_next = W_prev ∘ T(s, i+1) ∘ T(t, j)⁻¹`, so the world torso frame of frame `m` of a piece is
//! `W ∘ T(clip, m)` and planar position and heading are continuous by construction.

use crate::eval::{edge_sum, place_r, score_view, View};
use crate::graph::{EdgeId, FrameRef, MotionGraph};
use crate::problem::{HardConstraint, Problem};
use crate::rigid::Rigid2;
use crate::Error;
use geom_core::math::Planar;

/// A path (§2.4).
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub struct Path {
    /// First frame.
    pub start: FrameRef,
    /// Cut edges (leaves or inner nodes).
    pub cuts: Vec<EdgeId>,
    /// Last frame of the last piece.
    pub end_frame: u32,
}

/// One piece of a placed path.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Piece {
    /// Clip.
    pub clip: u32,
    /// First and last frame (inclusive).
    pub first: u32,
    /// Last frame.
    pub last: u32,
    /// Output time of `first`.
    pub t0: u32,
    /// Placement: clip coordinates → world.
    pub w: Planar,
}

/// Weighted score terms (§3.6).
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct ScoreParts {
    /// `w_c Σ cost(e_k)`.
    pub edge: f64,
    /// `w_f (F − F*)²`.
    pub length: f64,
    /// Body constraint terms.
    pub body: f64,
    /// Joint constraint terms.
    pub joint: f64,
    /// Style terms.
    pub style: f64,
    /// Obstacle terms.
    pub obstacle: f64,
}

/// Raw constraint errors of a path (before any post-processing).
#[derive(Clone, Debug, PartialEq, Default)]
pub struct Errors {
    /// Position error per body constraint (m).
    pub body_pos: Vec<f64>,
    /// Heading error per body constraint (deg; 0 if unconstrained).
    pub body_yaw_deg: Vec<f64>,
    /// Joint position error per joint constraint (m).
    pub joint: Vec<f64>,
    /// `|F − F*|` (frames).
    pub length: u32,
}

/// A scored path.
#[derive(Clone, Debug, PartialEq)]
pub struct Scored {
    /// The path.
    pub path: Path,
    /// Total score (lower is better).
    pub score: f64,
    /// Its terms.
    pub parts: ScoreParts,
    /// Constraint errors.
    pub errors: Errors,
    /// Output length (frames).
    pub frames: u32,
}

/// A problem resolved against a graph: label bits, weights as `1/unit²`, hard constraints sorted.
#[derive(Clone, Debug)]
pub struct Compiled {
    pub(crate) pb: Problem,
    pub(crate) target: u32,
    pub(crate) start_r: Rigid2,
    pub(crate) hard: Vec<(u32, Hard)>,
    pub(crate) style: Vec<(u32, u32, u64, f64)>,
    pub(crate) w_f: f64,
    pub(crate) w_p: f64,
    pub(crate) w_o: f64,
    pub(crate) w_j: f64,
}

/// A resolved hard constraint.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Hard {
    Frame(FrameRef),
    Label(u64),
}

impl Compiled {
    /// Validates and resolves `pb` (errors of §8: `NoStartConstraint`, `ConflictingHard`,
    /// `ConstraintOutOfRange`, unknown labels and joints, out-of-range frames).
    pub fn new(g: &MotionGraph, pb: Problem) -> crate::Result<Compiled> {
        let Some(b0) = pb.body.iter().find(|b| b.time == 0) else {
            return Err(Error::NoStartConstraint);
        };
        let target = pb.target_length();
        let limit = 10u64 * target as u64;
        let times = pb
            .body
            .iter()
            .map(|b| b.time)
            .chain(pb.joints.iter().map(|j| j.time))
            .chain(pb.hard.iter().map(|h| h.time()));
        for t in times {
            if t as u64 > limit {
                return Err(Error::ConstraintOutOfRange { time: t, length: target });
            }
        }
        for j in &pb.joints {
            if j.joint as usize >= g.db.skeleton.joints.len() {
                return Err(Error::UnknownJoint(format!("joint index {}", j.joint)));
            }
        }
        let mut hard = Vec::new();
        for h in &pb.hard {
            let r = match h {
                HardConstraint::Frame { frame, .. } => {
                    if frame.clip as usize >= g.db.clips.len() || frame.frame >= g.clip_len(frame.clip) {
                        return Err(Error::InvalidParameter(format!(
                            "hard constraint frame {frame:?} is not in the database"
                        )));
                    }
                    Hard::Frame(*frame)
                }
                HardConstraint::Label { label, .. } => {
                    Hard::Label(g.db.label_bit(label).ok_or_else(|| Error::UnknownLabel(label.clone()))?)
                }
            };
            hard.push((h.time(), r));
        }
        hard.sort_by_key(|x| x.0);
        for w in hard.windows(2) {
            if w[0].0 == w[1].0 && w[0].1 != w[1].1 {
                return Err(Error::ConflictingHard { time: w[0].0 });
            }
        }
        hard.dedup();
        let mut style = Vec::new();
        for s in &pb.style {
            style.push((
                s.from,
                s.to,
                g.db.label_bit(&s.label).ok_or_else(|| Error::UnknownLabel(s.label.clone()))?,
                s.weight,
            ));
        }
        let unit = |u: f64| if u > 0.0 && u.is_finite() { 1.0 / (u * u) } else { 0.0 };
        let w = pb.weights;
        Ok(Compiled {
            start_r: Rigid2::from(Planar::new(b0.x, b0.z, b0.yaw.unwrap_or(0.0))),
            target,
            hard,
            style,
            w_f: unit(w.length_frames),
            w_p: unit(w.pos_m),
            w_o: unit(w.yaw_deg.to_radians()),
            w_j: unit(w.joint_m),
            pb,
        })
    }
}

/// Whether database frame `f` satisfies a hard constraint.
pub(crate) fn hard_ok(g: &MotionGraph, h: &Hard, f: FrameRef) -> bool {
    match h {
        Hard::Frame(r) => *r == f,
        Hard::Label(bit) => g.db.clips[f.clip as usize].labels.bits.get(f.frame as usize).is_some_and(|b| b & bit != 0),
    }
}

/// The pieces of `path` placed from `start`, or `None` if the path is invalid (§3.5 rules with
/// `min_piece` frames per piece). Same placement as the search's [`place_r`].
pub fn place(g: &MotionGraph, path: &Path, start: &Planar, min_piece: u32) -> Option<Vec<Piece>> {
    let mut pieces = Vec::with_capacity(path.cuts.len() + 1);
    if !place_r(g, path, &Rigid2::from(*start), min_piece, &mut pieces) {
        return None;
    }
    Some(
        pieces
            .into_iter()
            .map(|p| Piece { clip: p.clip, first: p.first, last: p.last, t0: p.t0, w: p.w.into() })
            .collect(),
    )
}

/// Scores a path (§3.6): `None` if invalid or a hard constraint is not met.
pub(crate) fn score(g: &MotionGraph, cp: &Compiled, path: &Path, min_piece: u32) -> Option<Scored> {
    let mut errors = Errors::default();
    let (score, parts, frames) = score_into(g, cp, path, min_piece, Some(&mut errors))?;
    Some(Scored { path: path.clone(), score, parts, errors, frames })
}

/// The score alone (no allocation besides the piece table): for screening mutation candidates.
pub(crate) fn score_value(g: &MotionGraph, cp: &Compiled, path: &Path, min_piece: u32) -> Option<f64> {
    score_into(g, cp, path, min_piece, None).map(|x| x.0)
}

/// Score, its parts and the output length; constraint errors go to `errs` when given. The path
/// is placed with [`place_r`] and scored by [`score_view`] (the same code the incremental
/// candidate scoring of the search uses).
fn score_into(
    g: &MotionGraph,
    cp: &Compiled,
    path: &Path,
    min_piece: u32,
    errs: Option<&mut Errors>,
) -> Option<(f64, ScoreParts, u32)> {
    let mut pieces = Vec::with_capacity(path.cuts.len() + 1);
    if !place_r(g, path, &cp.start_r, min_piece, &mut pieces) {
        return None;
    }
    score_view(g, cp, &View::whole(&pieces), edge_sum(g, &path.cuts), errs)
}

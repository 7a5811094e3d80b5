//! Building the output (spec §3.9) and post-processing it (§3.10): the chosen target segments are
//! stretched, placed by their alignments, made to agree at the seams by linear offsets, and
//! concatenated (each shared boundary frame written once, overhangs cut).

use crate::cell::Column;
use crate::db::MappingDb;
use crate::dp::Interpretation;
use crate::error::{PcError, Result};
use crate::track::PointTrack;
use geom_core::anim::{FrameLabels, Motion};
use geom_core::math::{quat_exp, quat_log, UnitQuat, Vec3};
use std::sync::Arc;

fn check_rate(db: &MappingDb, it: &Interpretation) -> Result<()> {
    if (db.working_rate_hz - it.rate_hz).abs() > 1e-9 * it.rate_hz {
        return Err(PcError::RateMismatch {
            what: "interpretation".into(),
            expected: db.working_rate_hz,
            got: it.rate_hz,
        });
    }
    if it.segments.iter().any(|s| s.instance as usize >= db.instances.len()) {
        return Err(PcError::BadParameter {
            name: "interpretation",
            msg: "instance index outside the database".into(),
        });
    }
    Ok(())
}

/// Which signal of the instances to place.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Signal {
    /// The control (the DP's explanation of the input).
    Control,
    /// The target.
    Target,
}

/// Every chosen segment's signal stretched to its duration and placed by its `M` (`d + 1`
/// frames each, overhangs included). `db` must be at the interpretation's rate.
pub fn placed_segments(db: &MappingDb, it: &Interpretation, which: Signal) -> Result<Vec<PointTrack>> {
    check_rate(db, it)?;
    Ok(it
        .segments
        .iter()
        .map(|s| {
            let col = Column::new(db, s.instance, (s.end - s.start) as usize);
            let (data, k) = match which {
                Signal::Control => (col.ctrl, db.control_points()),
                Signal::Target => (col.tgt, db.target_points()),
            };
            PointTrack::new(it.rate_hz, k, data).transformed(&s.m)
        })
        .collect())
}

/// Linear seam offsets (spec §3.10): for the seam between segments `i` and `i + 1` with mismatch
/// `δ_i = ω_i − α_{i+1}`, segment `i` gets an offset that goes linearly from `δ_{i−1}/2` at its
/// first frame to `−δ_i/2` at its last (zero at the outer ends), so both sides meet at the
/// midpoint. The result is C⁰ at every seam (to rounding).
#[allow(clippy::needless_range_loop)] // p indexes the mismatches of two seams and the frames
pub fn postprocess_segments(segs: &mut [PointTrack]) {
    let l = segs.len();
    if l < 2 {
        return;
    }
    let k = segs[0].n_points;
    // Mismatches per seam and point.
    let delta: Vec<Vec<Vec3>> = (0..l - 1)
        .map(|i| {
            let w = segs[i].frame(segs[i].len() - 1);
            let a = segs[i + 1].frame(0);
            (0..k).map(|p| w[p] - a[p]).collect()
        })
        .collect();
    for (i, seg) in segs.iter_mut().enumerate() {
        let n = seg.len();
        for p in 0..k {
            let o0 = if i > 0 { delta[i - 1][p] * 0.5 } else { Vec3::zeros() };
            let o1 = if i + 1 < l { -delta[i][p] * 0.5 } else { Vec3::zeros() };
            for f in 0..n {
                let s = if n > 1 { f as f64 / (n - 1) as f64 } else { 0.0 };
                seg.data[f * k + p] += o0 * (1.0 - s) + o1 * s;
            }
        }
    }
}

/// Frames of segment `i` (of `l`) written to the output: global frames `start + j` for local `j`
/// in `0..d` (`0..=d` for the last segment), clipped to `[0, T − 1]`.
fn kept_frames(start: i64, d: usize, last: bool, t_len: usize) -> impl Iterator<Item = (usize, usize)> {
    let jmax = if last { d } else { d.saturating_sub(1) };
    (0..=jmax).filter_map(move |j| {
        let g = start + j as i64;
        (g >= 0 && g < t_len as i64).then_some((j, g as usize))
    })
}

/// Concatenates placed segments into one track of `it.frames` frames.
pub fn concat(segs: &[PointTrack], it: &Interpretation) -> PointTrack {
    let k = segs.first().map_or(0, |s| s.n_points);
    let mut out = Vec::with_capacity(it.frames * k);
    let l = segs.len();
    for (i, (seg, ch)) in segs.iter().zip(&it.segments).enumerate() {
        for (j, _) in kept_frames(ch.start, seg.len() - 1, i + 1 == l, it.frames) {
            out.extend_from_slice(seg.frame(j));
        }
    }
    PointTrack::new(it.rate_hz, k, out)
}

/// Annotation propagation (spec §3.11): the output inherits the per-frame annotations of the
/// chosen instances, stretched like the motion (sample `j` of a segment stretched from `n` to `d`
/// intervals takes the instance's annotation at the nearest index `round(j·n/d)`), one value per
/// input frame. `None` when a chosen instance carries no annotations. `db` must be at the
/// interpretation's rate.
pub fn propagate(db: &MappingDb, it: &Interpretation) -> Result<Option<Vec<u64>>> {
    check_rate(db, it)?;
    let mut out = Vec::with_capacity(it.frames);
    let l = it.segments.len();
    for (i, s) in it.segments.iter().enumerate() {
        let inst = &db.instances[s.instance as usize];
        let Some(a) = inst.annotations.as_ref() else { return Ok(None) };
        let n = inst.n();
        let d = (s.end - s.start) as usize;
        for (j, _) in kept_frames(s.start, d, i + 1 == l, it.frames) {
            out.push(a[((j * n) as f64 / d as f64).round() as usize]);
        }
    }
    Ok(Some(out))
}

/// The output target points (spec §3.9): raw concatenation, or post-processed (§3.10) when
/// `post` is set.
pub fn target_points(db: &MappingDb, it: &Interpretation, post: bool) -> Result<PointTrack> {
    let mut segs = placed_segments(db, it, Signal::Target)?;
    if post {
        postprocess_segments(&mut segs);
    }
    Ok(concat(&segs, it))
}

/// The placed control chain (what the DP says the input looks like), raw.
pub fn achieved_control(db: &MappingDb, it: &Interpretation) -> Result<PointTrack> {
    Ok(concat(&placed_segments(db, it, Signal::Control)?, it))
}

/// Skeletal output (spec §3.9): each chosen instance's source slice (native rate) stretched to its
/// duration (slerp of local rotations, lerp of the root), the root moved by `M` (position and
/// heading), then, if `post`, seam offsets (§3.10): root position linear as for points, every
/// joint rotation `q·exp(offset)` with the seam mismatch `r = log(ω⁻¹ α)` split half/half.
/// Labels and foot contacts are copied from the source frames. The interpretation must be at the
/// takes' native rate (refine first) and every take must carry its source motion.
pub fn target_motion(db: &MappingDb, it: &Interpretation, post: bool) -> Result<Motion> {
    let segs = placed_motions(db, it, post)?;
    concat_motions(&segs, it)
}

/// The placed (and, if `post`, seam-blended) source slices of every chosen segment, before
/// concatenation (`d + 1` frames each; see [`target_motion`]).
pub fn placed_motions(db: &MappingDb, it: &Interpretation, post: bool) -> Result<Vec<Motion>> {
    check_rate(db, it)?;
    let native = db.takes[0].control.rate_hz;
    if (native - it.rate_hz).abs() > 1e-9 * native {
        return Err(PcError::RateMismatch { what: "skeletal output".into(), expected: native, got: it.rate_hz });
    }
    let mut segs: Vec<Motion> = Vec::with_capacity(it.segments.len());
    for s in &it.segments {
        let (ti, fa, fb) = db.instances[s.instance as usize].source;
        let src = db.takes[ti as usize]
            .source
            .as_ref()
            .ok_or_else(|| PcError::BadParameter { name: "take source", msg: format!("take {ti} has no motion") })?;
        let mut m = src.slice(fa, fb + 1);
        // Spec §8: consistent quaternion hemispheres before slerp and log-map offsets.
        m.fix_hemispheres();
        let mut m = m.time_stretch((s.end - s.start) as usize + 1);
        let nj = m.n_joints();
        let ry = UnitQuat::from_axis_angle(&Vec3::y_axis(), s.m.yaw);
        for f in 0..m.len() {
            m.root_pos[f] = s.m.apply_point(m.root_pos[f]);
            m.rot[f * nj] = ry * m.rot[f * nj];
        }
        segs.push(m);
    }
    let l = segs.len();
    if post && l > 1 {
        let nj = segs[0].n_joints();
        let seams: Vec<(Vec3, Vec<Vec3>)> = (0..l - 1)
            .map(|i| {
                let a = &segs[i];
                let b = &segs[i + 1];
                let la = a.len() - 1;
                let dp = a.root_pos[la] - b.root_pos[0];
                let dr = (0..nj).map(|j| quat_log(&(a.rot[la * nj + j].inverse() * b.rot[j]))).collect();
                (dp, dr)
            })
            .collect();
        for (i, m) in segs.iter_mut().enumerate() {
            let n = m.len();
            for f in 0..n {
                let s = if n > 1 { f as f64 / (n - 1) as f64 } else { 0.0 };
                // Position: +δ_{i−1}/2 at the start, −δ_i/2 at the end.
                let mut off = Vec3::zeros();
                if i > 0 {
                    off += seams[i - 1].0 * 0.5 * (1.0 - s);
                }
                if i + 1 < l {
                    off -= seams[i].0 * 0.5 * s;
                }
                m.root_pos[f] += off;
                for j in 0..nj {
                    // Rotation: the incoming side gets −r/2 at its first frame, the outgoing +r/2
                    // at its last (α·exp(−r/2) = ω·exp(r/2)).
                    let mut r = Vec3::zeros();
                    if i > 0 {
                        r -= seams[i - 1].1[j] * 0.5 * (1.0 - s);
                    }
                    if i + 1 < l {
                        r += seams[i].1[j] * 0.5 * s;
                    }
                    let q = m.rot[f * nj + j];
                    m.rot[f * nj + j] = q * quat_exp(&r);
                }
            }
        }
    }
    Ok(segs)
}

/// Concatenates placed motions (shared boundary frames once, overhangs cut).
fn concat_motions(segs: &[Motion], it: &Interpretation) -> Result<Motion> {
    let l = segs.len();
    if l == 0 {
        return Err(PcError::NoInterpretation("empty interpretation".into()));
    }
    let skel: Arc<_> = segs[0].skeleton.clone();
    let nj = skel.joints.len();
    let (mut root, mut rot) = (Vec::new(), Vec::new());
    let mut labels = FrameLabels { names: segs[0].labels.names.clone(), bits: vec![], contacts: vec![] };
    for (i, (m, ch)) in segs.iter().zip(&it.segments).enumerate() {
        for (j, _) in kept_frames(ch.start, m.len() - 1, i + 1 == l, it.frames) {
            root.push(m.root_pos[j]);
            rot.extend_from_slice(&m.rot[j * nj..(j + 1) * nj]);
            labels.bits.push(m.labels.bits.get(j).copied().unwrap_or(0));
            labels.contacts.push(m.labels.contacts.get(j).copied().unwrap_or(0));
        }
    }
    let mut out = Motion::new(skel, segs[0].frame_time, root, rot, None)?;
    out.labels = labels;
    Ok(out)
}

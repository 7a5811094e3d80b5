//! Handhold constraints (spec §3.11, the paper's constraint propagation): the output inherits the
//! per-frame handhold annotations of the chosen instances ([`crate::output::propagate`]), and
//! [`close_hands`] then moves the follower's held hand onto the leader's hand during the annotated
//! frames. The dance output is a point cloud (no follower skeleton), so the IK is the spec's
//! direct snap for point output, with the correction ramped linearly to zero over `ramp` frames on
//! both sides of every annotated run so the hand does not jump when a hold starts or ends.

use crate::data::duet::{HOLD_LR, HOLD_RR};
use crate::track::PointTrack;
use geom_core::math::Vec3;

/// Index of the follower's right hand in the dance target (points: left hand, right hand, left
/// ankle, right ankle).
pub const FOLLOWER_RIGHT_HAND: usize = 1;

/// The leader's hand (control point 0 = left, 1 = right) that holds the follower's right hand
/// according to annotation bits `a`, if any.
pub fn held_leader_hand(a: u64) -> Option<usize> {
    if a & HOLD_LR != 0 {
        Some(0)
    } else if a & HOLD_RR != 0 {
        Some(1)
    } else {
        None
    }
}

/// Closes the held hands of a dance output (point snap with ramps, see the module docs):
/// `target` the follower's points, `control` the leader's (the input), `annotations` one bit set
/// per frame (the propagated handholds). Frames beyond the shortest of the three are left alone.
pub fn close_hands(target: &mut PointTrack, control: &PointTrack, annotations: &[u64], ramp: usize) {
    let n = target.len().min(control.len()).min(annotations.len());
    let k = target.n_points;
    // Correction on annotated frames.
    let corr: Vec<Option<Vec3>> = (0..n)
        .map(|f| held_leader_hand(annotations[f]).map(|h| control.frame(f)[h] - target.frame(f)[FOLLOWER_RIGHT_HAND]))
        .collect();
    // Ramps: distance to the nearest annotated frame on each side, with its correction.
    let mut before: Vec<Option<(usize, Vec3)>> = vec![None; n];
    let mut last = None;
    for f in 0..n {
        if let Some(c) = corr[f] {
            last = Some((f, c));
        }
        before[f] = last;
    }
    let mut after: Vec<Option<(usize, Vec3)>> = vec![None; n];
    let mut next = None;
    for f in (0..n).rev() {
        if let Some(c) = corr[f] {
            next = Some((f, c));
        }
        after[f] = next;
    }
    for f in 0..n {
        let delta = match corr[f] {
            Some(c) => c,
            None => {
                let w = |side: Option<(usize, Vec3)>| {
                    side.map(|(g, c)| (1.0 - (f.abs_diff(g) as f64) / (ramp as f64 + 1.0)).max(0.0) * c)
                };
                let (a, b) = (w(before[f]), w(after[f]));
                match (a, b) {
                    (Some(a), Some(b)) => {
                        if a.norm() >= b.norm() {
                            a
                        } else {
                            b
                        }
                    }
                    (Some(a), None) => a,
                    (None, Some(b)) => b,
                    (None, None) => Vec3::zeros(),
                }
            }
        };
        target.data[f * k + FOLLOWER_RIGHT_HAND] += delta;
    }
}

/// Held-hand gap per frame (m): on every frame where `truth` says the hands are held, the
/// distance between the leader's holding hand (from `control`) and the follower's right hand.
pub fn held_gaps(target: &PointTrack, control: &PointTrack, truth: &[u64]) -> Vec<f64> {
    let n = target.len().min(control.len()).min(truth.len());
    (0..n)
        .filter_map(|f| {
            held_leader_hand(truth[f]).map(|h| (control.frame(f)[h] - target.frame(f)[FOLLOWER_RIGHT_HAND]).norm())
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Annotated frames are closed exactly; the correction fades out linearly over the ramp.
    #[test]
    fn snap_closes_annotated_frames_and_ramps_out() {
        let n = 20;
        let control = PointTrack::new(30.0, 4, (0..n * 4).map(|i| Vec3::new(i as f64, 1.0, 0.0)).collect());
        let mut target = PointTrack::new(30.0, 4, vec![Vec3::new(0.0, 1.0, 0.5); n * 4]);
        let ann: Vec<u64> = (0..n).map(|f| if (5..10).contains(&f) { HOLD_LR } else { 0 }).collect();
        let before = target.clone();
        close_hands(&mut target, &control, &ann, 3);
        for f in 5..10 {
            assert!((target.frame(f)[1] - control.frame(f)[0]).norm() < 1e-12);
        }
        for f in [0, 1, 14, 19] {
            assert_eq!(target.frame(f), before.frame(f), "frame {f} is beyond the ramp");
        }
        // One frame after the run: 3/4 of the last correction.
        let c = control.frame(9)[0] - before.frame(9)[1];
        assert!((target.frame(10)[1] - (before.frame(10)[1] + c * 0.75)).norm() < 1e-12);
        assert!(held_gaps(&target, &control, &ann).iter().all(|g| *g < 1e-12));
    }
}

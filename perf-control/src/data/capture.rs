//! Capture set-up frames (PC-6, issue 27): the CMU clips open with the converter's reference
//! T-pose (frame 0, motion-graph spec §6.1) and may hold a few frames of the subject settling
//! into the capture. Those frames are not motion of the task and are dropped by a stated,
//! measured rule before the clip enters the database or the control:
//!
//! **Rule.** Describe every frame by its end effectors (hands and ankles, the target points of
//! [`crate::end_effectors`]) in the torso frame ([`Motion::torso_frames`]: root floor point and
//! heading removed, height kept). The reference is the median pose (per coordinate) of the
//! clip's *supported* frames — at least one foot on the ground (ankle or toe contact,
//! [`crate::eval::stance_states`]) — and `δ_f = sqrt(mean_points ‖p − p̄‖²)` (m) the pose
//! distance of frame `f` to it. A frame is *settled* when it is supported and `δ_f ≤ pose_tol_m`.
//! The clip starts at the first frame of the first run of `max(1, round(hold_s · rate))`
//! consecutive settled frames; every frame before it is dropped.
//!
//! Measured on the CMU clips at 30 Hz (README, PC-6): the T-pose has `δ_0` = 0.43 m (01_01) and
//! 0.42 m (01_03); frame 1 has no detected contact in either clip (the T-pose → frame 1 jump
//! makes the feet's speed exceed the contact threshold); every supported frame of 01_01 has
//! `δ ≤ 0.26` m. With the scenes' `pose_tol_m` = 0.3 m and `hold_s` = 0.2 s the rule drops frames
//! 0 and 1 of both clips. Requiring *both* feet down instead would drop the first 441 frames of
//! 01_03 (14.7 s), because that clip opens with a walk (single support all along).
//!
//! ```no_run
//! use perf_control::data::capture::{settled_start, SetupRule};
//! use perf_control::experiments::real_data::load_clip;
//! let m = load_clip("assets/mocap/01_01.bvh", 30.0).unwrap();
//! let s = settled_start(&m, &SetupRule::default()).unwrap();
//! println!("drop {} frames (δ of frame 0: {:.2} m)", s.first, s.pose_dist_m[0]);
//! ```

use geom_core::anim::Motion;
use geom_core::stats::median;
use serde::Deserialize;

use crate::control::end_effectors;
use crate::error::{PcError, Result};
use crate::eval::stance_states;

/// The set-up rule's two thresholds (the RON `setup` block of the PC-6 scenes).
#[derive(Clone, Copy, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SetupRule {
    /// Settled frames needed in a row (s).
    pub hold_s: f64,
    /// Largest pose distance `δ_f` to the clip's median pose of a settled frame (m).
    pub pose_tol_m: f64,
}

impl Default for SetupRule {
    /// 0.2 s in a row within 0.3 m of the median pose (the PC-6 scenes' values).
    fn default() -> Self {
        Self { hold_s: 0.2, pose_tol_m: 0.3 }
    }
}

/// What the rule found on one clip.
#[derive(Clone, Debug, PartialEq)]
pub struct Settled {
    /// First kept frame (= frames dropped).
    pub first: usize,
    /// Pose distance `δ_f` of every frame to the clip's median pose (m).
    pub pose_dist_m: Vec<f64>,
    /// Per frame: at least one foot on the ground (detected contact).
    pub support: Vec<bool>,
}

/// Applies the set-up rule (module docs) to `m`, whose contacts must be detected
/// ([`Motion::detect_contacts`]). Errors: a non-positive or NaN threshold, a clip without contact
/// flags, or no settled run at all.
pub fn settled_start(m: &Motion, rule: &SetupRule) -> Result<Settled> {
    if !(rule.hold_s.is_finite() && rule.hold_s >= 0.0) {
        return Err(PcError::BadParameter {
            name: "setup.hold_s",
            msg: format!("{} must be finite and ≥ 0", rule.hold_s),
        });
    }
    if !(rule.pose_tol_m.is_finite() && rule.pose_tol_m > 0.0) {
        return Err(PcError::BadParameter {
            name: "setup.pose_tol_m",
            msg: format!("{} must be finite and > 0", rule.pose_tol_m),
        });
    }
    let n = m.len();
    if m.labels.contacts.len() != n {
        return Err(PcError::BadParameter { name: "setup", msg: "the clip's contacts are not detected".into() });
    }
    let ee = end_effectors(m);
    let tf = m.torso_frames();
    let k = ee.n_points;
    let local: Vec<[f64; 3]> = (0..n)
        .flat_map(|f| {
            let inv = tf[f].inverse();
            ee.frame(f).iter().map(move |p| {
                let q = inv.apply_point(*p);
                [q.x, q.y, q.z]
            })
        })
        .collect();
    let support: Vec<bool> = stance_states(&m.labels).iter().map(|&s| s != 0).collect();
    let standing: Vec<usize> = (0..n).filter(|&f| support[f]).collect();
    if standing.is_empty() {
        return Err(PcError::BadParameter { name: "setup", msg: format!("no frame of the {n} has a foot down") });
    }
    let med: Vec<[f64; 3]> = (0..k)
        .map(|i| {
            let mut a = [0.0; 3];
            for (c, v) in a.iter_mut().enumerate() {
                *v = median(&standing.iter().map(|&f| local[f * k + i][c]).collect::<Vec<f64>>());
            }
            a
        })
        .collect();
    let pose_dist_m: Vec<f64> = (0..n)
        .map(|f| {
            let s: f64 = (0..k).map(|i| (0..3).map(|c| (local[f * k + i][c] - med[i][c]).powi(2)).sum::<f64>()).sum();
            (s / k as f64).sqrt()
        })
        .collect();
    let hold = ((rule.hold_s / m.frame_time).round() as usize).max(1);
    let mut run = 0usize;
    for f in 0..n {
        // A NaN distance is not settled (the comparison is false).
        if support[f] && pose_dist_m[f] <= rule.pose_tol_m {
            run += 1;
            if run == hold {
                return Ok(Settled { first: f + 1 - hold, pose_dist_m, support });
            }
        } else {
            run = 0;
        }
    }
    Err(PcError::BadParameter {
        name: "setup",
        msg: format!(
            "no {hold} consecutive frames with a foot down within {} m of the median pose ({n} frames)",
            rule.pose_tol_m
        ),
    })
}

/// `m` without its set-up frames ([`settled_start`]), and what the rule found.
pub fn trim_setup(m: Motion, rule: &SetupRule) -> Result<(Motion, Settled)> {
    let s = settled_start(&m, rule)?;
    Ok((m.slice(s.first, m.len()), s))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::data::walk_motion;

    /// A synthesised walk is settled from its first frame; clearing the contacts of its first
    /// frames (unsupported, like the CMU clips' frames 0 and 1) drops exactly those; bad
    /// thresholds and a clip without contacts are typed errors.
    #[test]
    fn rule_drops_unsupported_start_frames() {
        let m = walk_motion(3, 4.0, 30.0);
        let rule = SetupRule::default();
        let s = settled_start(&m, &rule).unwrap();
        assert_eq!(s.first, 0);
        assert!(s.pose_dist_m.iter().all(|d| d.is_finite()));
        let mut m2 = m.clone();
        for f in 0..3 {
            m2.labels.contacts[f] = 0;
        }
        assert_eq!(settled_start(&m2, &rule).unwrap().first, 3);
        let (t, s2) = trim_setup(m2, &rule).unwrap();
        assert_eq!((t.len(), s2.first), (m.len() - 3, 3));
        // A tolerance below every frame's distance finds no settled run.
        assert!(settled_start(&m, &SetupRule { hold_s: 0.2, pose_tol_m: 1e-9 }).is_err());
        for bad in [SetupRule { hold_s: f64::NAN, pose_tol_m: 0.3 }, SetupRule { hold_s: 0.2, pose_tol_m: 0.0 }] {
            assert!(matches!(settled_start(&m, &bad), Err(PcError::BadParameter { .. })));
        }
        let mut m3 = m.clone();
        m3.labels.contacts.clear();
        assert!(matches!(settled_start(&m3, &rule), Err(PcError::BadParameter { .. })));
    }
}

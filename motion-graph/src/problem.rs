//! What the user asks for (motion-graph.md §3.6, §3.7): length, body constraints (position and
//! heading at a frame), joint constraints, hard constraints (a database frame or a labelled
//! action at a frame), style windows, obstacles, and the weights of the score (paper eq. 1).

use crate::graph::FrameRef;
use geom_core::math::Vec3;
use serde::{Deserialize, Serialize};

/// Torso position `(x, z)` (m) and optional heading `yaw` (rad) at output frame `time`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct BodyConstraint {
    /// Output frame.
    pub time: u32,
    /// World x (m).
    pub x: f64,
    /// World z (m).
    pub z: f64,
    /// Heading (rad, `atan2(f.x, f.z)`), if constrained.
    pub yaw: Option<f64>,
}

/// World position (m) of skeleton joint `joint` at output frame `time`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct JointConstraint {
    /// Output frame.
    pub time: u32,
    /// Joint index in the skeleton.
    pub joint: u16,
    /// Target world position (m).
    pub pos: Vec3,
}

/// A hard constraint: restricts the search space (§3.7).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum HardConstraint {
    /// Output frame `time` must be database frame `frame`.
    Frame {
        /// Output frame.
        time: u32,
        /// Required database frame.
        frame: FrameRef,
    },
    /// Output frame `time` must carry label `label` ("do this action here").
    Label {
        /// Output frame.
        time: u32,
        /// Label name.
        label: String,
    },
}

impl HardConstraint {
    /// Output frame of the constraint.
    pub fn time(&self) -> u32 {
        match self {
            HardConstraint::Frame { time, .. } | HardConstraint::Label { time, .. } => *time,
        }
    }
}

/// Penalise frames in `[from, to]` lacking `label` (§3.6 optional term).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct StyleConstraint {
    /// First output frame.
    pub from: u32,
    /// Last output frame.
    pub to: u32,
    /// Wanted label.
    pub label: String,
    /// Weight per 30 frames lacking the label.
    pub weight: f64,
}

/// A disc-shaped obstacle on the floor (m).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Disc {
    /// Centre x.
    pub x: f64,
    /// Centre z.
    pub z: f64,
    /// Radius.
    pub radius: f64,
}

/// Score weights, given as the error that costs one unit (§3.6): the code uses `w = 1/unit²`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Weights {
    /// `w_c`: weight per unit of normalized cut cost (default 0.25).
    pub cut: f64,
    /// Length error costing one unit (frames; default 10).
    pub length_frames: f64,
    /// Body position error costing one unit (m; default 0.30).
    pub pos_m: f64,
    /// Heading error costing one unit (deg; default 10).
    pub yaw_deg: f64,
    /// Joint position error costing one unit (m; default 0.30).
    pub joint_m: f64,
    /// Obstacle weight per m² of penetration (default 100).
    pub obstacle: f64,
}

impl Default for Weights {
    fn default() -> Self {
        Self { cut: 0.25, length_frames: 10.0, pos_m: 0.30, yaw_deg: 10.0, joint_m: 0.30, obstacle: 100.0 }
    }
}

/// A synthesis request (§2.4).
#[derive(Clone, Debug, PartialEq, Default, Serialize, Deserialize)]
pub struct Problem {
    /// Desired number of frames `F*` (default: last body constraint time + 1).
    pub length: Option<u32>,
    /// Body constraints; one at time 0 is required (it places the motion).
    pub body: Vec<BodyConstraint>,
    /// Joint constraints.
    pub joints: Vec<JointConstraint>,
    /// Hard constraints.
    pub hard: Vec<HardConstraint>,
    /// Style windows.
    pub style: Vec<StyleConstraint>,
    /// Obstacles.
    pub obstacles: Vec<Disc>,
    /// Score weights.
    pub weights: Weights,
}

impl Problem {
    /// `F*`: the requested length, or the last body constraint's time + 1.
    pub fn target_length(&self) -> u32 {
        self.length.unwrap_or_else(|| self.body.iter().map(|b| b.time + 1).max().unwrap_or(1)).max(1)
    }
}

/// The random problems of MG-1 (spec §6.2, "football positions"): `n` problems of `frames`
/// frames at `rate_hz`, starting at the origin facing +Z, with `intermediate.0 ..= intermediate.1`
/// intermediate body constraints (times evenly spread, ±10 frames of jitter) and an end
/// constraint at frame `frames − 1` with a heading. Consecutive constraints lie
/// `U(dist_frac) · speed · Δt` apart (spec: ≤ 0.8 × 4 m/s × Δt, "reachable by the database's
/// speeds") and the direction between them turns by up to `±turn` rad per segment (the
/// scene's default 1 rad). Deterministic in `seed`.
#[allow(clippy::too_many_arguments)]
pub fn random_mg1(
    n: usize,
    frames: u32,
    rate_hz: f64,
    intermediate: (usize, usize),
    speed: f64,
    dist_frac: (f64, f64),
    turn: f64,
    seed: u64,
    weights: Weights,
) -> Vec<Problem> {
    let mut rng = geom_core::rng::Rng::new(seed);
    let frames = frames.max(2);
    (0..n)
        .map(|_| {
            let k = intermediate.0 + rng.below(intermediate.1.saturating_sub(intermediate.0) + 1);
            let mut body = vec![BodyConstraint { time: 0, x: 0.0, z: 0.0, yaw: Some(0.0) }];
            let (mut x, mut z, mut dir) = (0.0, 0.0, 0.0f64);
            let mut t_prev = 0u32;
            for i in 1..=k + 1 {
                let t = if i == k + 1 {
                    frames - 1
                } else {
                    ((frames as f64 * i as f64 / (k + 1) as f64 + rng.range(-10.0, 10.0)) as u32)
                        .min(frames - 2)
                        .max(t_prev + 1)
                };
                let dt = t.saturating_sub(t_prev) as f64 / rate_hz;
                let d = rng.range(dist_frac.0, dist_frac.1) * speed * dt;
                dir += rng.range(-turn, turn);
                x += d * dir.sin();
                z += d * dir.cos();
                let yaw = if i == k + 1 { Some(dir) } else { None };
                body.push(BodyConstraint { time: t, x, z, yaw });
                t_prev = t;
            }
            Problem { length: Some(frames), body, weights, ..Default::default() }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// MG-1 problems respect the spec's reachability bound (consecutive constraints at most
    /// `dist_frac.1 · speed · Δt` apart, here 0.8 × 4 m/s), start at the origin, end at the last
    /// frame with a heading, and are the same for the same seed.
    #[test]
    fn random_mg1_respects_the_reachability_bound() {
        let pbs = random_mg1(50, 300, 30.0, (1, 3), 4.0, (0.3, 0.8), 1.0, 11, Weights::default());
        assert_eq!(pbs, random_mg1(50, 300, 30.0, (1, 3), 4.0, (0.3, 0.8), 1.0, 11, Weights::default()));
        for p in &pbs {
            assert!(p.body.len() >= 3 && p.body.len() <= 5);
            assert_eq!((p.body[0].time, p.body[0].x, p.body[0].z), (0, 0.0, 0.0));
            let last = p.body.last().unwrap();
            assert!(last.time == 299 && last.yaw.is_some());
            for w in p.body.windows(2) {
                assert!(w[1].time > w[0].time);
                let dt = (w[1].time - w[0].time) as f64 / 30.0;
                let d = (w[1].x - w[0].x).hypot(w[1].z - w[0].z);
                assert!(d <= 0.8 * 4.0 * dt + 1e-9 && d >= 0.3 * 4.0 * dt - 1e-9, "{d} m in {dt} s");
            }
        }
    }
}

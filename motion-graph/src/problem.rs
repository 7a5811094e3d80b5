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

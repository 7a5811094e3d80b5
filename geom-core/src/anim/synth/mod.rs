//! Procedural motion synthesiser (motion-graph.md §2.3, §3.13): kinematically plausible walks,
//! runs, turns, jumps, pick-ups and gestures on [`Skeleton::standard_humanoid`], with per-clip
//! style and band-limited noise, **exact** foot contacts and per-frame labels, deterministic from a
//! seed. It is the offline data source of the motion-graph experiments (databases of any size) and
//! of the crates that need a walking character (rigging, curve-skin, tracks, perf-control).
//!
//! How it works:
//! 1. [`plan`]: a 120 Hz simulation integrates the root path (`ẋ = v sin ψ`, `ż = v cos ψ`,
//!    `ψ̇ = κ v`), the gait clock `φ̇ = f(v)` and the behaviour state machine, and records every
//!    foot stance as an interval of time with a fixed plant pose.
//! 2. [`pose`]: every output frame is evaluated **directly at its time** (never resampled): the
//!    feet are placed from their stances (fixed while in stance, so contact points do not slide),
//!    the pelvis height is limited so that every leg can reach, and the legs are solved by
//!    analytic two-bone IK, so contact points are exact to rounding.
//!
//! Conventions: metres, seconds, radians (degrees in [`SynthStyle::lean_deg`],
//! [`SynthStyle::noise_deg`] and [`Behaviour::TurnInPlace`]); +Y up, the character faces +Z at yaw
//! 0 and its left is +X ([`Planar`]).
//!
//! Labels written per frame: `stand`, `walk`, `run`, `turn`, `jump` (flight frames: both feet
//! off the ground), `pickup`, `wave`, `reach`, and the style tags `calm` / `energetic`. Contact
//! bits ([`FrameLabels::L_ANKLE`] …): the ankle while its foot is flat on the ground, the toe for
//! the whole stance (it stays fixed while the heel rises at toe-off).

mod plan;
mod pose;
pub mod presets;

pub use presets::{library, Preset};

use super::motion::{FrameLabels, Motion};
use super::skeleton::{JointRole, Skeleton};
use crate::math::Planar;
use serde::{Deserialize, Serialize};
use std::sync::Arc;

/// Overall energy of a clip: scales bounce, arm swing and cadence (§3.13.2 step 11) and sets the
/// style tag `calm` / `energetic`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, Serialize, Deserialize)]
pub enum Energy {
    /// −20 % bounce and arm swing, −5 % cadence; label `calm`.
    Calm,
    /// No change, no label.
    #[default]
    Normal,
    /// +30 % bounce and arm swing, +8 % cadence; label `energetic`.
    Energetic,
}

/// Style of one clip (§3.13.2 step 11).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct SynthStyle {
    /// Arm swing amplitude factor (1 = `±(10° + 12°·v)`).
    pub arm_swing: f64,
    /// Pelvis bob factor (1 = 0.025 m walking, 0.05 m running).
    pub bounce: f64,
    /// Forward lean of the trunk (deg), added to `3°·v`.
    pub lean_deg: f64,
    /// Lateral distance between the left and right foot plants (m).
    pub step_width: f64,
    /// Cadence factor on the stride frequency `f(v)`.
    pub cadence_scale: f64,
    /// Energy class.
    pub energy: Energy,
    /// RMS of the band-limited noise on every free rotational DOF (deg).
    pub noise_deg: f64,
}

impl Default for SynthStyle {
    /// The middle of every range of §3.13.2 step 11: arm swing 1, bounce 1, lean 3°, step width
    /// 0.14 m, cadence 1, `Normal`, noise 1.5°.
    fn default() -> Self {
        Self {
            arm_swing: 1.0,
            bounce: 1.0,
            lean_deg: 3.0,
            step_width: 0.14,
            cadence_scale: 1.0,
            energy: Energy::Normal,
            noise_deg: 1.5,
        }
    }
}

impl SynthStyle {
    /// Effective (arm swing, bounce, cadence) factors after the energy class.
    pub(crate) fn effective(&self) -> (f64, f64, f64) {
        let (a, b, c) = match self.energy {
            Energy::Calm => (0.8, 0.8, 0.95),
            Energy::Normal => (1.0, 1.0, 1.0),
            Energy::Energetic => (1.3, 1.3, 1.08),
        };
        (self.arm_swing * a, self.bounce * b, self.cadence_scale * c)
    }
}

/// A scalar function of the normalised time `u ∈ [0, 1]` of a behaviour: piecewise linear through
/// `keys` (sorted by `u`), constant outside the first and last key; no keys reads as 0.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Profile {
    /// `(u, value)` pairs.
    pub keys: Vec<(f64, f64)>,
}

impl Profile {
    /// The constant `v`.
    pub fn constant(v: f64) -> Self {
        Self { keys: vec![(0.0, v)] }
    }

    /// Linear from `a` at `u = 0` to `b` at `u = 1`.
    pub fn linear(a: f64, b: f64) -> Self {
        Self { keys: vec![(0.0, a), (1.0, b)] }
    }

    /// Value at `u` (non-finite keys read as 0).
    pub fn eval(&self, u: f64) -> f64 {
        let k = &self.keys;
        let fin = |x: f64| if x.is_finite() { x } else { 0.0 };
        match k.len() {
            0 => 0.0,
            _ if u <= k[0].0 => fin(k[0].1),
            _ => {
                for w in k.windows(2) {
                    let ((u0, v0), (u1, v1)) = (w[0], w[1]);
                    if u <= u1 {
                        let s = if u1 > u0 { (u - u0) / (u1 - u0) } else { 1.0 };
                        return fin(v0 + (v1 - v0) * s.clamp(0.0, 1.0));
                    }
                }
                fin(k[k.len() - 1].1)
            }
        }
    }
}

/// Upper-body gesture kind.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum GestureKind {
    /// Right arm raised, forearm oscillating at 2 Hz; label `wave`.
    Wave,
    /// Right hand to a point 1.5–1.9 m high ahead (two-bone IK); label `reach`.
    Reach,
}

/// One step of a [`Script`]. Behaviours play one after the other, except [`Behaviour::Gesture`],
/// which takes no time of its own: it overlays the upper body from the start of the **next**
/// behaviour for `secs` seconds (so `[Gesture(Wave, 2), Locomote(4 s)]` waves while walking).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum Behaviour {
    /// Stand still for `secs` s (both feet planted; the gait first settles into double support).
    Stand {
        /// Duration (s).
        secs: f64,
    },
    /// Walk or run (chosen by speed, hysteresis 1.8–2.3 m/s) for `secs` s with speed `v(u)`
    /// (m/s) and path curvature `κ(u)` (1/m, positive turns left) over `u ∈ [0, 1]`.
    Locomote {
        /// Duration (s).
        secs: f64,
        /// Forward speed profile (m/s); below 0.1 m/s the gait stops.
        speed: Profile,
        /// Curvature profile (1/m).
        curvature: Profile,
    },
    /// Turn on the spot by `deg` degrees (positive = left), stepping; takes `0.6 + 1.2·|deg|/180` s.
    TurnInPlace {
        /// Turn angle (deg).
        deg: f64,
    },
    /// Standing jump forward: crouch 0.3 s, ballistic flight of `distance` m with the pelvis rising
    /// `apex` m (flight time `2√(2·apex/g)`), landing crouch 0.3 s.
    Jump {
        /// Horizontal distance (m).
        distance: f64,
        /// Apex height of the pelvis above take-off (m).
        apex: f64,
    },
    /// Crouch, right hand towards a floor point 0.35 m ahead, stand up; `secs` s in total
    /// (at least 1.6 s: 0.6 s down, hold, 0.6 s up).
    Pickup {
        /// Duration (s).
        secs: f64,
    },
    /// Upper-body overlay starting with the next behaviour.
    Gesture {
        /// Which gesture.
        kind: GestureKind,
        /// Duration (s).
        secs: f64,
    },
}

/// What to synthesise: the start pose on the ground, the behaviours in order, the style.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Script {
    /// Torso frame at time 0 (position and heading on the ground).
    pub start: Planar,
    /// Behaviours in order.
    pub behaviours: Vec<Behaviour>,
    /// Style of the whole clip.
    pub style: SynthStyle,
}

/// Label names in their bit order (bit `i` = `LABELS[i]`).
pub const LABELS: [&str; 10] = ["stand", "walk", "run", "turn", "jump", "pickup", "wave", "reach", "calm", "energetic"];

/// Bit of a label in [`LABELS`].
pub(crate) fn bit(name: &str) -> u64 {
    LABELS.iter().position(|l| *l == name).map_or(0, |i| 1 << i)
}

/// Synthesises the motion of `script` on `skel` at `rate_hz` frames per second, deterministic in
/// `seed` (noise phases, initial gait phase, curvature perturbation).
///
/// `skel` must carry the roles of [`Skeleton::standard_humanoid`] (root, spine, chest, neck,
/// head, collars, shoulders, elbows, hands, hips, knees, ankles, toes); bone lengths are read from
/// it, so a scaled copy works too. Frames are sampled at `k / rate_hz`, `k = 0 … ⌊T·rate⌋`, with
/// `T` the script's total duration (at least one frame). Non-finite or negative durations and
/// rates are sanitised (durations clamped to ≥ 0, `rate_hz` to [1, 1000], default 30 when not
/// finite); a skeleton lacking a needed role yields a rest-pose clip with no labels.
///
/// Output: root positions and local rotations, labels ([`LABELS`]) and exact contact flags
/// (a flagged foot point's world position is constant over its stance to rounding, ≈ 1e-15 m).
pub fn synthesize(skel: &Skeleton, script: &Script, rate_hz: f64, seed: u64) -> Motion {
    let rate = if rate_hz.is_finite() { rate_hz.clamp(1.0, 1000.0) } else { 30.0 };
    let skel_arc = Arc::new(skel.clone());
    let rig = match pose::Rig::new(skel) {
        Some(r) => r,
        None => {
            // Missing roles: a one-frame rest clip (documented fallback, never a panic).
            let p = skel.rest_pose();
            // Invariant: the rest pose has exactly one rotation per joint and dt > 0.
            return Motion::from_poses(skel_arc, 1.0 / rate, &[p]).expect("rest pose matches its skeleton");
        }
    };
    let pl = plan::simulate(script, seed);
    let n = ((pl.duration * rate) * (1.0 + 1e-12)).floor() as usize + 1;
    let noise = pose::Noise::new(skel.joints.len(), script.style.noise_deg, seed);
    let mut poses = Vec::with_capacity(n);
    let mut labels = FrameLabels::new(n);
    for name in LABELS {
        // Invariant: 10 labels < 64.
        labels.add(name).expect("fewer than 64 labels");
    }
    let style_bits = match script.style.energy {
        Energy::Calm => bit("calm"),
        Energy::Normal => 0,
        Energy::Energetic => bit("energetic"),
    };
    for k in 0..n {
        let t = k as f64 / rate;
        let (p, contacts, bits) = pose::frame(&rig, &pl, &script.style, &noise, t);
        poses.push(p);
        labels.bits[k] = bits | style_bits;
        labels.contacts[k] = contacts;
    }
    // Invariant: every pose has one rotation per joint of `skel` and 1/rate > 0.
    let mut m = Motion::from_poses(skel_arc, 1.0 / rate, &poses).expect("synthesised poses match the skeleton");
    m.labels = labels;
    m.fix_hemispheres();
    m
}

/// Roles the synthesiser drives (all must exist on the skeleton): the first 21 roles of
/// [`JointRole::ALL`] (every non-tip role).
pub(crate) const NEEDED_ROLES: &[JointRole] = JointRole::ALL.split_at(21).0;

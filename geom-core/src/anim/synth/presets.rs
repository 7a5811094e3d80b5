//! Motion-library presets (motion-graph.md §3.13.3): random scripts by behaviour class, styles
//! drawn per clip, every clip synthesised from its own random stream (so the library is the same
//! for any thread count) and cut to a random length in the requested frame range.

use super::{synthesize, Behaviour, Energy, GestureKind, Profile, Script, SynthStyle};
use crate::anim::motion::Motion;
use crate::anim::skeleton::Skeleton;
use crate::math::Planar;
use crate::rng::Rng;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use std::f64::consts::PI;

/// Which mix of behaviours a library holds.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum Preset {
    /// The paper's football database: strong bias to running forward. Shares: 45 % run forward
    /// (3–6 m/s, gentle curvature), 15 % run with sharp cuts (|κ| up to 1.2 1/m; cruising at
    /// 2.5–5 m/s, slowing into each cut to keep the lateral acceleration ≤ 6 m/s², never below
    /// 2.3 m/s), 15 % walk
    /// (0.8–1.8 m/s), 5 % U-turn, 5 % jump, 5 % stand → start / stop → stand, 5 % pick-up, 5 %
    /// walk with a wave or reach.
    Football,
    /// The same eight classes with equal shares (joint and pose constraint scenes).
    Mixed,
    /// Long walks (1.2–1.6 m/s, gentle curvature) for perf-control's training data.
    Walk2Min,
    /// Long walks from a different random domain (perf-control's test data).
    WalkTest,
}

/// Behaviour classes of §3.13.3.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Class {
    RunForward,
    RunCuts,
    Walk,
    UTurn,
    Jump,
    StartStop,
    Pickup,
    WalkGesture,
}

const CLASSES: [Class; 8] = [
    Class::RunForward,
    Class::RunCuts,
    Class::Walk,
    Class::UTurn,
    Class::Jump,
    Class::StartStop,
    Class::Pickup,
    Class::WalkGesture,
];

fn pick_class(p: Preset, rng: &mut Rng) -> Class {
    match p {
        Preset::Football => {
            let shares = [0.45, 0.15, 0.15, 0.05, 0.05, 0.05, 0.05, 0.05];
            let mut u = rng.f64();
            for (c, s) in CLASSES.iter().zip(shares) {
                if u < s {
                    return *c;
                }
                u -= s;
            }
            Class::WalkGesture
        }
        Preset::Mixed => CLASSES[rng.below(CLASSES.len())],
        Preset::Walk2Min | Preset::WalkTest => Class::Walk,
    }
}

/// A random style with the ranges of §3.13.2 step 11.
pub fn random_style(rng: &mut Rng) -> SynthStyle {
    let e = rng.f64();
    SynthStyle {
        arm_swing: rng.range(0.6, 1.4),
        bounce: rng.range(0.7, 1.3),
        lean_deg: rng.range(0.0, 8.0),
        step_width: rng.range(0.08, 0.20),
        cadence_scale: rng.range(0.9, 1.1),
        energy: if e < 0.2 {
            Energy::Calm
        } else if e < 0.8 {
            Energy::Normal
        } else {
            Energy::Energetic
        },
        noise_deg: 1.5,
    }
}

/// Largest lateral acceleration `v² |κ|` of a run with sharp cuts (m/s², ≈ 0.6 g).
const CUT_LATERAL_ACC: f64 = 6.0;

/// Slowest speed a run with cuts slows to (m/s): the top of the walk → run hysteresis of
/// §3.13.2 step 2, so the gait stays a run.
const RUN_MIN_SPEED: f64 = 2.3;

fn loco(secs: f64, speed: Profile, curvature: Profile) -> Behaviour {
    Behaviour::Locomote { secs, speed, curvature }
}

/// Behaviours of one clip of class `c` lasting at least `d` seconds.
fn behaviours(c: Class, d: f64, rng: &mut Rng) -> Vec<Behaviour> {
    let sign = |rng: &mut Rng| if rng.chance(0.5) { 1.0 } else { -1.0 };
    let gentle = |rng: &mut Rng| Profile {
        keys: vec![(0.0, rng.range(-0.15, 0.15)), (0.5, rng.range(-0.15, 0.15)), (1.0, rng.range(-0.15, 0.15))],
    };
    let mut b = Vec::new();
    match c {
        Class::RunForward => {
            let p = gentle(rng);
            b.push(loco(d + 1.0, Profile::linear(rng.range(3.0, 6.0), rng.range(3.0, 6.0)), p));
        }
        Class::RunCuts => {
            // A runner slows into a sharp cut: the lateral acceleration `v² |κ|` is capped at
            // `CUT_LATERAL_ACC` (≈ 0.6 g; taking |κ| = 1.2 1/m at 5 m/s would need 3 g), with the
            // speed floored at `RUN_MIN_SPEED` so the gait stays a run. Between cuts the runner
            // is back at the clip's cruising speed.
            let mut t = 0.0;
            let v = rng.range(2.5, 5.0);
            while t < d + 1.0 {
                let secs = rng.range(0.8, 1.8);
                let k: f64 = sign(rng) * rng.range(0.4, 1.2);
                let vc = (CUT_LATERAL_ACC / k.abs()).sqrt().clamp(RUN_MIN_SPEED.min(v), v);
                b.push(loco(
                    secs,
                    Profile { keys: vec![(0.0, v), (0.3, vc), (0.7, vc), (1.0, v)] },
                    Profile { keys: vec![(0.0, 0.0), (0.3, k), (0.7, k), (1.0, 0.0)] },
                ));
                t += secs;
            }
        }
        Class::Walk => {
            let p = Profile {
                keys: vec![(0.0, rng.range(-0.3, 0.3)), (0.5, rng.range(-0.3, 0.3)), (1.0, rng.range(-0.3, 0.3))],
            };
            b.push(loco(d + 1.0, Profile::linear(rng.range(0.8, 1.8), rng.range(0.8, 1.8)), p));
        }
        Class::UTurn => {
            let v = rng.range(1.0, 4.0);
            let pre = rng.range(0.5, 0.5 * d.max(1.0));
            b.push(loco(pre, Profile::constant(v), Profile::constant(0.0)));
            if rng.chance(0.5) {
                // Turn on a tight arc: ψ̇ = κ v, half a turn.
                let k = sign(rng) * rng.range(0.8, 1.2) * (3.0 / v).min(1.5);
                b.push(loco(PI / (k.abs() * v), Profile::constant(v), Profile::constant(k)));
            } else {
                b.push(loco(1.0, Profile::linear(v, 0.0), Profile::constant(0.0)));
                b.push(Behaviour::TurnInPlace { deg: sign(rng) * rng.range(150.0, 200.0) });
            }
            b.push(loco(d + 1.0, Profile { keys: vec![(0.0, 0.0), (0.1, v), (1.0, v)] }, Profile::constant(0.0)));
        }
        Class::Jump => {
            let v = rng.range(0.8, 1.6);
            b.push(loco(rng.range(1.0, 2.0), Profile { keys: vec![(0.0, v), (0.6, v), (1.0, 0.0)] }, gentle(rng)));
            b.push(Behaviour::Jump { distance: rng.range(0.5, 1.4), apex: rng.range(0.2, 0.5) });
            b.push(loco(d + 1.0, Profile { keys: vec![(0.0, 0.0), (0.15, v), (1.0, v)] }, gentle(rng)));
        }
        Class::StartStop => {
            let v = rng.range(1.0, 4.0);
            b.push(Behaviour::Stand { secs: rng.range(0.5, 1.5) });
            let secs = rng.range(2.0, 4.0);
            b.push(loco(secs, Profile { keys: vec![(0.0, 0.0), (0.3, v), (0.7, v), (1.0, 0.0)] }, gentle(rng)));
            b.push(Behaviour::Stand { secs: d + 1.0 });
        }
        Class::Pickup => {
            let v = rng.range(0.8, 1.5);
            b.push(loco(rng.range(1.0, 2.0), Profile { keys: vec![(0.0, v), (0.5, v), (1.0, 0.0)] }, gentle(rng)));
            b.push(Behaviour::Pickup { secs: rng.range(2.0, 3.0) });
            b.push(loco(d + 1.0, Profile { keys: vec![(0.0, 0.0), (0.15, v), (1.0, v)] }, gentle(rng)));
        }
        Class::WalkGesture => {
            let v = rng.range(0.8, 1.6);
            let kind = if rng.chance(0.5) { GestureKind::Wave } else { GestureKind::Reach };
            b.push(loco(rng.range(0.5, 1.5), Profile::constant(v), gentle(rng)));
            b.push(Behaviour::Gesture { kind, secs: rng.range(2.0, 3.5) });
            b.push(loco(d + 1.0, Profile::constant(v), gentle(rng)));
        }
    }
    b
}

/// A random script of preset `p` lasting at least `secs` seconds, and its class name.
pub fn random_script(p: Preset, secs: f64, rng: &mut Rng) -> Script {
    let c = pick_class(p, rng);
    let style = random_style(rng);
    let start = Planar::new(0.0, 0.0, rng.range(-PI, PI));
    Script { start, behaviours: behaviours(c, secs.max(0.0), rng), style }
}

/// `n_clips` clips of preset `p` on [`Skeleton::standard_humanoid`], each `frames.0 ..= frames.1`
/// frames long (uniformly drawn; the range is sorted and at least 1) at `rate_hz`. Clip `i` uses
/// the random stream `(seed, i)` for its script and its synthesis seed, so the library does not
/// depend on the thread count (clips are built in parallel).
pub fn library(p: Preset, n_clips: usize, frames: (usize, usize), rate_hz: f64, seed: u64) -> Vec<Motion> {
    let skel = Skeleton::standard_humanoid();
    let (lo, hi) = (frames.0.min(frames.1).max(1), frames.0.max(frames.1).max(1));
    let rate = if rate_hz.is_finite() { rate_hz.clamp(1.0, 1000.0) } else { 30.0 };
    let domain = if p == Preset::WalkTest { 0x7E57 } else { 0 };
    (0..n_clips)
        .into_par_iter()
        .map(|i| {
            let mut rng = Rng::stream(seed ^ domain, i as u64);
            let n = lo + rng.below(hi - lo + 1);
            let script = random_script(p, (n as f64 - 1.0) / rate, &mut rng);
            let m = synthesize(&skel, &script, rate, rng.next_u64());
            m.slice(0, n)
        })
        .collect()
}

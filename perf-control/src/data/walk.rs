//! Walk generator (spec §3.13 "Walk"): a long walk with random changes of speed and direction
//! (Ornstein–Uhlenbeck speed and curvature plus a sharp turn every 12–18 s) synthesised by
//! `geom_core::anim::synth`, segmented at every foot plant (exact, from the synthesiser's
//! contacts) into one instance per step.

use crate::control::{end_effectors, hips_control};
use crate::db::{SegmentLabel, Side, Take};
use crate::eval::plants;
use geom_core::anim::synth::{synthesize, Behaviour, Profile, Script, SynthStyle};
use geom_core::anim::{Motion, Skeleton};
use geom_core::math::Planar;
use geom_core::rng::Rng;

/// Normalized hip width of the walk control (m, spec §3.12).
pub const HIP_WIDTH: f64 = 0.20;

/// Key spacing of the speed and curvature profiles (s).
const KEY_DT: f64 = 0.1;

/// A sharp turn of a generated walk.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SharpTurn {
    /// Start time (s): a plant of the foot on the turn side.
    pub start: f64,
    /// Duration (s).
    pub secs: f64,
    /// Turn angle (rad, positive = left).
    pub angle: f64,
}

/// Speed of the walker during a sharp turn (m/s).
const TURN_SPEED: f64 = 0.9;
/// Ease in/out of the turn speed (s).
const EASE: f64 = 0.3;

fn script(secs: f64, speed: &[f64], curv: &[f64]) -> Script {
    let keys = |v: &[f64]| Profile {
        keys: v.iter().enumerate().map(|(i, &x)| (((i as f64) * KEY_DT / secs).min(1.0), x)).collect(),
    };
    Script {
        start: Planar::identity(),
        behaviours: vec![Behaviour::Locomote { secs, speed: keys(speed), curvature: keys(curv) }],
        style: SynthStyle::default(),
    }
}

/// The walk of `secs` seconds at `rate_hz` from `seed` ([`walk_motion_with_turns`]).
pub fn walk_motion(seed: u64, secs: f64, rate_hz: f64) -> Motion {
    walk_motion_with_turns(seed, secs, rate_hz).0
}

/// The walk of `secs` seconds at `rate_hz` from `seed` and its sharp turns: speed = 1.3 m/s +
/// OU(σ 0.25 m/s, correlation 3 s) clamped to 0.7–2.0 m/s; curvature = OU(σ 0.35 1/m,
/// correlation 2 s); every 12–18 s a sharp turn of 90–160° (random side) over 1.2–1.8 s at
/// 0.9 m/s. Footwork habit (spec §3.13, §12 item 11): the walker slows to the turn speed, and the
/// turn starts at the first plant of the foot on the turn side (left turns on a left-foot plant).
/// The plan is causal, so each turn's onset is found by synthesising the walk up to a few seconds
/// past it with the earlier turns in place (profile keys every 0.1 s, so the onset of the
/// curvature is resolved to 0.1 s).
pub fn walk_motion_with_turns(seed: u64, secs: f64, rate_hz: f64) -> (Motion, Vec<SharpTurn>) {
    let secs = if secs.is_finite() { secs.clamp(1.0, 7200.0) } else { 10.0 };
    let mut rng = Rng::new(seed);
    let nk = (secs / KEY_DT).ceil() as usize + 1;
    let ou = |rng: &mut Rng, sigma: f64, tau: f64| {
        let a = (-KEY_DT / tau).exp();
        let b = sigma * (1.0 - a * a).sqrt();
        let mut x = sigma * rng.normal();
        (0..nk)
            .map(|_| {
                let v = x;
                x = a * x + b * rng.normal();
                v
            })
            .collect::<Vec<f64>>()
    };
    let mut speed: Vec<f64> = ou(&mut rng, 0.25, 3.0).iter().map(|v| (1.3 + v).clamp(0.7, 2.0)).collect();
    let mut curv = ou(&mut rng, 0.35, 2.0);
    let skel = Skeleton::standard_humanoid();
    let synth_seed = seed ^ 0x5eed;
    let mut turns = Vec::new();
    let mut t = rng.range(12.0, 18.0) * 0.5;
    while t + 4.0 < secs {
        let dur = rng.range(1.2, 1.8);
        let ang = rng.range(90.0, 160.0).to_radians() * if rng.chance(0.5) { 1.0 } else { -1.0 };
        // Slow down to the turn speed from t − EASE, hold it for up to 1.5 s of search + the turn.
        let hold_end = t + 1.5 + dur;
        let set_speed = |speed: &mut [f64], from: f64, to: f64| {
            for (i, s) in speed.iter_mut().enumerate() {
                let tk = i as f64 * KEY_DT;
                let w = if tk >= from && tk <= to {
                    1.0
                } else if tk < from {
                    (1.0 - (from - tk) / EASE).max(0.0)
                } else {
                    (1.0 - (tk - to) / EASE).max(0.0)
                };
                *s = *s * (1.0 - w) + TURN_SPEED * w;
            }
        };
        let saved = speed.clone();
        set_speed(&mut speed, t, hold_end);
        // Synthesise up to a little past the search window, keys rescaled to that length.
        let horizon = (hold_end + 1.0).min(secs);
        let nk_h = (horizon / KEY_DT).floor() as usize + 1;
        let m = synthesize(&skel, &script(horizon, &speed[..nk_h.min(nk)], &curv[..nk_h.min(nk)]), rate_hz, synth_seed);
        let foot = if ang > 0.0 { 0u8 } else { 1u8 };
        let start = plants(&m.labels)
            .into_iter()
            .map(|(f, ft)| (f as f64 / rate_hz, ft))
            .find(|&(tf, ft)| ft == foot && tf >= t)
            .map_or(t, |(tf, _)| tf);
        // Final speed profile: hold only until the end of the turn.
        speed = saved;
        set_speed(&mut speed, t, start + dur);
        for (i, c) in curv.iter_mut().enumerate() {
            let tk = i as f64 * KEY_DT;
            if tk >= start && tk <= start + dur {
                *c = ang / (TURN_SPEED * dur);
            }
        }
        turns.push(SharpTurn { start, secs: dur, angle: ang });
        t = start + dur + rng.range(12.0, 18.0);
    }
    (synthesize(&skel, &script(secs, &speed, &curv), rate_hz, synth_seed), turns)
}

/// A take from a walk: control = hips control (width [`HIP_WIDTH`]), target = hands and ankles,
/// boundaries at every foot plant (segments shorter than 3 frames are merged into the next), label
/// = the foot planted at the segment's start (the first segment: the other foot than the one
/// planting at its end).
pub fn take_from_walk(m: Motion) -> Take {
    let n = m.len();
    let mut boundaries = vec![0usize];
    let mut labels = Vec::new();
    let mut lead = None;
    for (f, foot) in plants(&m.labels) {
        if f + 3 > n || f < boundaries[boundaries.len() - 1] + 3 {
            continue;
        }
        let side = if foot == 0 { Side::Left } else { Side::Right };
        let this = lead.unwrap_or(match side {
            Side::Left => Side::Right,
            Side::Right => Side::Left,
        });
        labels.push(SegmentLabel::Step { lead_foot: this });
        boundaries.push(f);
        lead = Some(side);
    }
    if n >= 2 {
        boundaries.push(n - 1);
        labels.push(lead.map_or(SegmentLabel::None, |s| SegmentLabel::Step { lead_foot: s }));
    }
    Take {
        control: hips_control(&m, HIP_WIDTH),
        target: end_effectors(&m),
        source: Some(m),
        boundaries,
        labels,
        annotations: None,
    }
}

/// [`walk_motion`] as a [`Take`] ([`take_from_walk`]).
pub fn walk_take(seed: u64, secs: f64, rate_hz: f64) -> Take {
    take_from_walk(walk_motion(seed, secs, rate_hz))
}

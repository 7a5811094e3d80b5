//! The "Lindy-like" duet generator (spec §3.13 "Partner dance"; our design, no capture of the
//! task exists offline): a leader and a follower dance a chain of 8-beat patterns of the grammar
//! of [`crate::dance::grammar`] at a tempo; the control is the leader's hands and ankles, the
//! target the follower's, sampled at 30 Hz and segmented exactly every two beats.
//!
//! Kinematics, in the couple frame (origin at the leader's pelvis floor point, leader facing +Z,
//! left = +X; the whole couple drifts with an Ornstein–Uhlenbeck yaw rate σ 15°/s and a slow OU
//! translation, so alignment matters):
//! - beat clock from the tempo with per-beat jitter σ 10 ms;
//! - feet, both dancers: one weight change per beat, alternating feet (the follower mirrored); the
//!   first beat of every transition is a rock step (stepping foot 0.25 m backward), the second
//!   returns under the hip, the others step in place (±5 cm); swing over 60 % of the beat with
//!   5 cm clearance; stance feet exactly fixed in the world;
//! - the leader's held hand (left in normal hold, right in crosshand) sits at its stance base
//!   (open (±0.20, 0.95, 0.45) m, + for the left hand; closed (0.30, 1.30, 0.20), mirrored in x for
//!   crosshand) plus the cue of the half: `S/a` Δz = +0.10 sin 2πu, `S/b` Δz = −0.08 sin 2πu,
//!   `I/a` Δz = −0.15 sin πu and Δy = +0.35 sm(u), `I/b` a counter-clockwise circle of radius
//!   0.15 m descending to the closed base, `U/a` Δy = +0.35 sm(u) and Δx = +0.12 sin πu, `U/b` a
//!   clockwise circle descending to the open base (u ∈ [0, 1] over the half, sm = smoothstep);
//! - the leader's free hand: in open stances the mirror image of the held hand's base, in closed
//!   ones on the follower's back (−0.05, 1.10, 0.45) (mirrored for crosshand), moving between them
//!   by smoothstep during half `b` of `I` and `U`;
//! - a toggle: over the last quarter of half `b` both leader hands blend to the new stance's bases
//!   and the held hand makes a lateral bump of `toggle_cue_m` (deliberately weak: into an open
//!   stance the bases are the same positions and only the bump and the hand that carries the next
//!   cues tell it); the hands are released during that quarter (no handhold annotated);
//! - the follower: pelvis at distance `r` along the leader's forward axis (open 1.25 m, closed
//!   0.35 m), facing the leader; `S`: `r` oscillates ±0.12 m over the transition (the mirrored
//!   rock step); `a` halves of `I`/`U` start the approach (`r` moves 10 % of the way); `I/b`: `r` →
//!   closed with a lateral arc +0.25 sin πu and a +360° spin; `U/b`: `r` → open, arc −0.25 sin πu,
//!   −360° spin. Right hand = the leader's held hand + smooth noise (the ground-truth handhold;
//!   during a toggle it moves between the leader's hands); left hand on the leader's right
//!   shoulder (−0.18, 1.40, 0.05) in closed stances (mirrored for crosshand), a random smooth
//!   flourish of 0.10–0.30 m per two-beat segment in open ones (the follower's freer style);
//! - every hand point gets smooth noise of RMS `noise_m` (sinusoids of 0.5–2 Hz, bounded); feet
//!   get none (they are planted exactly).
//!
//! Annotations per frame ([`HOLD_LR`], [`HOLD_RR`], [`CLOSED`]): which leader hand holds the
//! follower's right hand, and whether the couple is closed (from the middle of half `b` of `I`).

use std::f64::consts::{PI, TAU};

use geom_core::math::{smoothstep, Planar, Vec3};
use geom_core::rng::Rng;
use serde::Deserialize;

use crate::dance::grammar::{basic_patterns, composable, DanceLabel, Half, Pattern, Stance, Transition};
use crate::db::{SegmentLabel, Take};
use crate::error::{PcError, Result};
use crate::track::PointTrack;

/// Annotation bit: the leader's left hand holds the follower's right hand.
pub const HOLD_LR: u64 = 1;
/// Annotation bit: the leader's right hand holds the follower's right hand (crosshand).
pub const HOLD_RR: u64 = 2;
/// Annotation bit: closed stance.
pub const CLOSED: u64 = 4;

/// Generator parameters (spec §4 "duet generator").
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct DuetParams {
    /// Sample rate (Hz).
    pub rate_hz: f64,
    /// Lateral bump of the held hand at a toggle (m; spec: 0.06, reported at 0.03, 0.06, 0.12).
    pub toggle_cue_m: f64,
    /// RMS of the smooth noise on every hand point (m).
    pub noise_m: f64,
    /// Per-beat timing jitter σ (s).
    pub beat_jitter_s: f64,
    /// σ of the OU yaw rate of the couple (deg/s).
    pub drift_yaw_deg_s: f64,
    /// σ of the OU floor velocity of the couple (m/s).
    pub drift_speed_m_s: f64,
    /// Follower distance in open stances (m).
    pub open_r: f64,
    /// Follower distance in closed stances (m).
    pub closed_r: f64,
    /// Range of the follower's free-hand flourish amplitude in open stances (m).
    pub flourish_m: (f64, f64),
}

impl Default for DuetParams {
    fn default() -> Self {
        Self {
            rate_hz: 30.0,
            toggle_cue_m: 0.06,
            noise_m: 0.01,
            beat_jitter_s: 0.010,
            drift_yaw_deg_s: 15.0,
            drift_speed_m_s: 0.05,
            open_r: 1.25,
            closed_r: 0.35,
            flourish_m: (0.10, 0.30),
        }
    }
}

/// Ground truth of a generated dance.
#[derive(Clone, Debug)]
pub struct DuetTruth {
    /// The patterns danced, in order.
    pub patterns: Vec<Pattern>,
    /// Tempo (beats per minute).
    pub bpm: f64,
    /// Every two-beat segment: (start s, end s, label).
    pub segments: Vec<(f64, f64, DanceLabel)>,
    /// Per frame: the annotation bits ([`HOLD_LR`], [`HOLD_RR`], [`CLOSED`]).
    pub annotations: Vec<u64>,
}

impl DuetTruth {
    /// Per frame: the couple is in a closed stance.
    pub fn closed(&self, f: usize) -> bool {
        self.annotations[f] & CLOSED != 0
    }
}

/// The segment label of a take for a dance label (`pattern` = index of the pattern in the dance).
pub fn segment_label(l: DanceLabel, pattern: u16) -> SegmentLabel {
    SegmentLabel::Dance { stance: l.stance, transition: l.transition, half: l.half, toggle: l.toggle, pattern }
}

/// Base positions (couple frame) of the leader's left and right hands in a stance.
fn bases(s: Stance) -> [Vec3; 2] {
    match s {
        Stance::O | Stance::OX => [Vec3::new(0.20, 0.95, 0.45), Vec3::new(-0.20, 0.95, 0.45)],
        Stance::C => [Vec3::new(0.30, 1.30, 0.20), Vec3::new(-0.05, 1.10, 0.45)],
        Stance::CX => [Vec3::new(0.05, 1.10, 0.45), Vec3::new(-0.30, 1.30, 0.20)],
    }
}

/// The leader's hand holding the follower's right hand: 0 left, 1 right.
fn held(s: Stance) -> usize {
    usize::from(s.crosshand())
}

/// Bounded smooth noise: per axis three sinusoids of 0.5–2 Hz whose sum has RMS `rms/√3`, so the
/// 3-D displacement has RMS `rms`; each axis stays within `√2·rms` and the displacement within
/// `√6·rms` ≈ 2.45 `rms`.
struct SmoothNoise {
    terms: [[(f64, f64, f64); 3]; 3],
}

impl SmoothNoise {
    fn new(rng: &mut Rng, rms: f64) -> Self {
        let a = rms / 3f64.sqrt() * (2.0f64 / 3.0).sqrt();
        let mut term = || (a, TAU * rng.range(0.5, 2.0), TAU * rng.f64());
        SmoothNoise { terms: [[term(), term(), term()], [term(), term(), term()], [term(), term(), term()]] }
    }

    fn at(&self, t: f64) -> Vec3 {
        let ax = |i: usize| self.terms[i].iter().map(|(a, w, p)| a * (w * t + p).sin()).sum::<f64>();
        Vec3::new(ax(0), ax(1), ax(2))
    }
}

/// One transition of the dance: stance before and after, type, toggle.
#[derive(Clone, Copy, Debug)]
struct Tr {
    from: Stance,
    to: Stance,
    kind: Transition,
    toggle: bool,
    /// The stance after the transition without the toggle.
    plain: Stance,
}

/// Where frame time `t` falls: transition index, half, phase `u` in the half, beat position `τ`
/// in the transition (0–4).
#[derive(Clone, Copy, Debug)]
struct Phase {
    tr: usize,
    half: Half,
    u: f64,
    tau: f64,
}

struct Clock {
    beats: Vec<f64>,
}

impl Clock {
    fn phase(&self, t: f64) -> Phase {
        let nb = self.beats.len() - 1;
        let b = self.beats.partition_point(|&x| x <= t).saturating_sub(1).min(nb - 1);
        let phi = ((t - self.beats[b]) / (self.beats[b + 1] - self.beats[b])).clamp(0.0, 1.0);
        let h = b / 2;
        let u = ((b % 2) as f64 + phi) / 2.0;
        Phase { tr: h / 2, half: if h % 2 == 0 { Half::A } else { Half::B }, u, tau: (b % 4) as f64 + phi }
    }
}

/// The couple's drift, sampled at the frame rate and interpolated.
struct Drift {
    rate: f64,
    frames: Vec<Planar>,
}

impl Drift {
    fn new(p: &DuetParams, n: usize, rng: &mut Rng) -> Drift {
        let dt = 1.0 / p.rate_hz;
        let (ay, av) = ((-dt / 2.0f64).exp(), (-dt / 3.0f64).exp());
        let sy = p.drift_yaw_deg_s.to_radians();
        let sv = p.drift_speed_m_s;
        let (mut w, mut vx, mut vz) = (sy * rng.normal(), sv * rng.normal(), sv * rng.normal());
        let mut g = Planar::identity();
        let mut frames = Vec::with_capacity(n + 2);
        for _ in 0..n + 2 {
            frames.push(g);
            g = Planar::new(g.x + vx * dt, g.z + vz * dt, g.yaw + w * dt);
            w = ay * w + sy * (1.0 - ay * ay).sqrt() * rng.normal();
            vx = av * vx + sv * (1.0 - av * av).sqrt() * rng.normal();
            vz = av * vz + sv * (1.0 - av * av).sqrt() * rng.normal();
        }
        Drift { rate: p.rate_hz, frames }
    }

    fn at(&self, t: f64) -> Planar {
        let x = (t * self.rate).clamp(0.0, (self.frames.len() - 2) as f64);
        let i = x.floor() as usize;
        let s = x - i as f64;
        let (a, b) = (self.frames[i], self.frames[i + 1]);
        Planar::new(a.x + (b.x - a.x) * s, a.z + (b.z - a.z) * s, a.yaw + (b.yaw - a.yaw) * s)
    }
}

struct Dance<'a> {
    p: &'a DuetParams,
    trs: Vec<Tr>,
    clock: Clock,
    drift: Drift,
    /// Per two-beat segment: flourish amplitude and two directions.
    flourish: Vec<(f64, Vec3, Vec3)>,
}

fn sm(u: f64) -> f64 {
    smoothstep(0.0, 1.0, u)
}

impl Dance<'_> {
    fn r_of(&self, s: Stance) -> f64 {
        if s.closed() {
            self.p.closed_r
        } else {
            self.p.open_r
        }
    }

    /// Toggle window weight (0 before the last quarter of a toggling half `b`, smoothstep to 1).
    fn toggle_w(tr: &Tr, ph: &Phase) -> f64 {
        if tr.toggle && ph.half == Half::B && ph.u >= 0.75 {
            sm((ph.u - 0.75) / 0.25)
        } else {
            0.0
        }
    }

    /// The leader's hands in the couple frame.
    fn leader_hands(&self, ph: &Phase) -> [Vec3; 2] {
        let tr = &self.trs[ph.tr];
        let (b0, b1) = (bases(tr.from), bases(tr.plain));
        let hh = held(tr.from);
        let sx = if hh == 0 { 1.0 } else { -1.0 };
        let u = ph.u;
        let lift = Vec3::new(0.0, 0.35, 0.0);
        let mut hands = b0;
        let free = 1 - hh;
        match (tr.kind, ph.half) {
            (Transition::S, Half::A) => hands[hh].z += 0.10 * (TAU * u).sin(),
            (Transition::S, Half::B) => hands[hh].z -= 0.08 * (TAU * u).sin(),
            (Transition::I, Half::A) => {
                hands[hh].z -= 0.15 * (PI * u).sin();
                hands[hh].y += 0.35 * sm(u);
            }
            (Transition::U, Half::A) => {
                hands[hh].y += 0.35 * sm(u);
                hands[hh].x += sx * 0.12 * (PI * u).sin();
            }
            (k, Half::B) => {
                // I/b counter-clockwise, U/b clockwise circle of radius 0.15 m, descending.
                let dir = if k == Transition::I { 1.0 } else { -1.0 };
                let start = b0[hh] + lift;
                let circle = Vec3::new(dir * sx * (TAU * u).sin(), 0.0, 1.0 - (TAU * u).cos()) * 0.15;
                hands[hh] = start + (b1[hh] - start) * sm(u) + circle;
                hands[free] = b0[free] + (b1[free] - b0[free]) * sm(u);
            }
        }
        let w = Self::toggle_w(tr, ph);
        if w > 0.0 {
            let bt = bases(tr.to);
            for h in 0..2 {
                hands[h] += (bt[h] - b1[h]) * w;
            }
            hands[hh].x += sx * self.p.toggle_cue_m * (PI * (ph.u - 0.75) / 0.25).sin();
        }
        hands
    }

    /// The follower's frame relative to the couple frame (position, facing the leader).
    fn follower_local(&self, ph: &Phase) -> Planar {
        let tr = &self.trs[ph.tr];
        let (rs, re) = (self.r_of(tr.from), self.r_of(tr.plain));
        let (r, lat, spin) = match (tr.kind, ph.half) {
            (Transition::S, _) => (rs + 0.12 * (TAU * ph.tau / 4.0).sin(), 0.0, 0.0),
            (_, Half::A) => (rs + 0.1 * (re - rs) * sm(ph.u), 0.0, 0.0),
            (k, Half::B) => {
                let dir = if k == Transition::I { 1.0 } else { -1.0 };
                (rs + (0.1 + 0.9 * sm(ph.u)) * (re - rs), dir * 0.25 * (PI * ph.u).sin(), dir * TAU * sm(ph.u))
            }
        };
        Planar::new(lat, r, PI + spin)
    }

    /// Annotation bits at phase `ph`.
    fn annotation(&self, ph: &Phase) -> u64 {
        let tr = &self.trs[ph.tr];
        let late = ph.half == Half::B && ph.u >= 0.5;
        let closed = if late { tr.to.closed() } else { tr.from.closed() };
        let mut bits = if closed { CLOSED } else { 0 };
        let releasing = tr.toggle && ph.half == Half::B && ph.u >= 0.75;
        if !releasing {
            bits |= if tr.from.crosshand() { HOLD_RR } else { HOLD_LR };
        }
        bits
    }
}

/// A planted or swinging foot.
#[derive(Clone, Copy)]
struct Foot {
    planted: Vec3,
}

/// Generates one dance: `patterns` danced in order at `bpm` from `seed`. Errors when a pattern is
/// not grammatical or does not start in the stance the previous one ended in.
pub fn duet_take(p: &DuetParams, patterns: &[Pattern], bpm: f64, seed: u64) -> Result<(Take, DuetTruth)> {
    if patterns.is_empty() || !(bpm.is_finite() && bpm > 0.0) || !(p.rate_hz.is_finite() && p.rate_hz > 0.0) {
        return Err(PcError::BadParameter { name: "duet", msg: "needs patterns, a positive tempo and rate".into() });
    }
    let mut trs = Vec::with_capacity(2 * patterns.len());
    for (k, pat) in patterns.iter().enumerate() {
        let st = pat.stances().ok_or_else(|| PcError::BadParameter {
            name: "patterns",
            msg: format!("pattern {k} ({pat}) is not grammatical"),
        })?;
        if k > 0 && patterns[k - 1].end() != Some(pat.start) {
            return Err(PcError::BadParameter {
                name: "patterns",
                msg: format!("pattern {k} ({pat}) does not start where pattern {} ended", k - 1),
            });
        }
        for i in 0..2 {
            let (kind, toggle) = pat.steps[i];
            let plain = st[i].after(kind, false).expect("grammatical");
            trs.push(Tr { from: st[i], to: st[i + 1], kind, toggle, plain });
        }
    }
    let mut rng = Rng::new(seed);
    let mut r_beat = Rng::stream(seed, 1);
    let period = 60.0 / bpm;
    let nbeats = 4 * trs.len();
    let beats: Vec<f64> = (0..=nbeats)
        .map(|b| if b == 0 { 0.0 } else { b as f64 * period + p.beat_jitter_s * r_beat.normal() })
        .collect();
    let clock = Clock { beats };
    let rate = p.rate_hz;
    let n = (clock.beats[nbeats] * rate).round() as usize + 1;
    let drift = Drift::new(p, n, &mut Rng::stream(seed, 2));
    let mut r_fl = Rng::stream(seed, 3);
    let flourish = (0..2 * trs.len())
        .map(|_| (r_fl.range(p.flourish_m.0, p.flourish_m.1), r_fl.unit_vec3(), r_fl.unit_vec3()))
        .collect();
    let d = Dance { p, trs, clock, drift, flourish };
    let noise: Vec<SmoothNoise> = (0..4).map(|_| SmoothNoise::new(&mut rng, p.noise_m)).collect();
    // Step targets per beat (own frame), both dancers: rock, return, two steps in place.
    let mut r_step = Rng::stream(seed, 4);
    let base_foot = [Vec3::new(0.12, 0.08, 0.0), Vec3::new(-0.12, 0.08, 0.0)];
    let targets: Vec<[Vec3; 2]> = (0..nbeats)
        .map(|b| {
            let mut t = [Vec3::zeros(); 2];
            for (who, v) in t.iter_mut().enumerate() {
                let foot = (b + who) % 2;
                *v = base_foot[foot]
                    + match b % 4 {
                        0 => Vec3::new(0.0, 0.0, -0.25),
                        1 => Vec3::zeros(),
                        _ => Vec3::new(r_step.range(-0.05, 0.05), 0.0, r_step.range(-0.05, 0.05)),
                    };
            }
            t
        })
        .collect();
    let leader_frame = |t: f64| d.drift.at(t);
    let follower_frame = |t: f64| d.drift.at(t).compose(&d.follower_local(&d.clock.phase(t)));
    let mut feet = [[Foot { planted: Vec3::zeros() }; 2]; 2];
    for (who, fr) in [leader_frame(0.0), follower_frame(0.0)].into_iter().enumerate() {
        for f in 0..2 {
            feet[who][f].planted = fr.apply_point(base_foot[f]);
        }
    }
    let mut lead = Vec::with_capacity(4 * n);
    let mut foll = Vec::with_capacity(4 * n);
    let mut ann = Vec::with_capacity(n);
    let mut last_beat = usize::MAX;
    for f in 0..n {
        let t = f as f64 / rate;
        let ph = d.clock.phase(t);
        let b = d.clock.beats.partition_point(|&x| x <= t).saturating_sub(1).min(nbeats - 1);
        let (tb0, tb1) = (d.clock.beats[b], d.clock.beats[b + 1]);
        if b != last_beat {
            // A new beat: the feet that swung in the previous beat are planted at their targets.
            if last_beat != usize::MAX {
                let (l0, l1) = (d.clock.beats[last_beat], d.clock.beats[last_beat + 1]);
                let land = l0 + 0.6 * (l1 - l0);
                for (who, fr) in [leader_frame(land), follower_frame(land)].into_iter().enumerate() {
                    let foot = (last_beat + who) % 2;
                    feet[who][foot].planted = fr.apply_point(targets[last_beat][who]);
                }
            }
            last_beat = b;
        }
        let g = d.drift.at(t);
        let hands = d.leader_hands(&ph);
        let ff = g.compose(&d.follower_local(&ph));
        let mut world_feet = [[Vec3::zeros(); 2]; 2];
        let land_t = tb0 + 0.6 * (tb1 - tb0);
        for who in 0..2 {
            let fr = if who == 0 { leader_frame(land_t) } else { follower_frame(land_t) };
            let swing = (b + who) % 2;
            for foot in 0..2 {
                let planted = feet[who][foot].planted;
                world_feet[who][foot] = if foot == swing && t < land_t {
                    let target = fr.apply_point(targets[b][who]);
                    let s = ((t - tb0) / (land_t - tb0)).clamp(0.0, 1.0);
                    planted + (target - planted) * sm(s) + Vec3::new(0.0, 0.05 * (PI * s).sin(), 0.0)
                } else if foot == swing {
                    fr.apply_point(targets[b][who])
                } else {
                    planted
                };
            }
        }
        // Leader hands (world).
        let lh = [g.apply_point(hands[0]) + noise[0].at(t), g.apply_point(hands[1]) + noise[1].at(t)];
        // Follower right hand: the held leader hand (moving between the leader's hands during a
        // toggle) + its own noise.
        let tr = &d.trs[ph.tr];
        let w = Dance::toggle_w(tr, &ph);
        let (ho, hn) = (held(tr.from), held(tr.to));
        let fr_hand = lh[ho] + (lh[hn] - lh[ho]) * w + noise[2].at(t);
        // Follower left hand: shoulder (closed) or flourish (open), blended during I/b and U/b.
        let seg = 2 * ph.tr + usize::from(ph.half == Half::B);
        let (amp, d1, d2) = d.flourish[seg];
        let open_rest = |fr: &Planar| {
            fr.apply_point(
                Vec3::new(0.25, 1.0, 0.1) + d1 * (amp * (PI * ph.u).sin()) + d2 * (0.3 * amp * (TAU * ph.u).sin()),
            )
        };
        let shoulder = |s: Stance| {
            g.apply_point(if s.crosshand() { Vec3::new(0.18, 1.40, 0.05) } else { Vec3::new(-0.18, 1.40, 0.05) })
        };
        let fl_hand = match (tr.kind, ph.half) {
            (Transition::I, Half::B) => open_rest(&ff) + (shoulder(tr.to) - open_rest(&ff)) * sm(ph.u),
            (Transition::U, Half::B) => shoulder(tr.from) + (open_rest(&ff) - shoulder(tr.from)) * sm(ph.u),
            // A toggle in a closed step moves the resting hand to the other shoulder.
            _ if tr.from.closed() => shoulder(tr.from) + (shoulder(tr.to) - shoulder(tr.from)) * w,
            _ => open_rest(&ff),
        } + noise[3].at(t);
        lead.extend_from_slice(&[lh[0], lh[1], world_feet[0][0], world_feet[0][1]]);
        foll.extend_from_slice(&[fl_hand, fr_hand, world_feet[1][0], world_feet[1][1]]);
        ann.push(d.annotation(&ph));
    }
    // Two-beat segments.
    let mut boundaries = Vec::with_capacity(2 * d.trs.len() + 1);
    let mut labels = Vec::new();
    let mut segments = Vec::new();
    for h in 0..2 * d.trs.len() {
        let (s0, s1) = (d.clock.beats[2 * h], d.clock.beats[2 * h + 2]);
        boundaries.push((s0 * rate).round() as usize);
        let tr = &d.trs[h / 2];
        let half = if h % 2 == 0 { Half::A } else { Half::B };
        let l = DanceLabel { stance: tr.from, transition: tr.kind, half, toggle: half == Half::B && tr.toggle };
        labels.push(segment_label(l, (h / 4) as u16));
        segments.push((s0, s1, l));
    }
    boundaries.push(n - 1);
    let take = Take {
        control: PointTrack::new(rate, 4, lead),
        target: PointTrack::new(rate, 4, foll),
        source: None,
        boundaries,
        labels,
        annotations: Some(ann.clone()),
    };
    let truth = DuetTruth { patterns: patterns.to_vec(), bpm, segments, annotations: ann };
    Ok((take, truth))
}

/// Every order of `patterns` (a multiset) in which each pattern starts in the stance the previous
/// one ended in and which ends with `last` (if given) — the valid training dances.
pub fn chain_orders(patterns: &[Pattern], last: Option<Pattern>) -> Vec<Vec<Pattern>> {
    fn dfs(left: &mut Vec<Pattern>, cur: &mut Vec<Pattern>, last: Option<Pattern>, out: &mut Vec<Vec<Pattern>>) {
        if left.is_empty() {
            if last.is_none_or(|l| cur.last() == Some(&l)) {
                out.push(cur.clone());
            }
            return;
        }
        let mut tried: Vec<Pattern> = Vec::new();
        for i in 0..left.len() {
            let p = left[i];
            if tried.contains(&p) || cur.last().is_some_and(|q| q.end() != Some(p.start)) {
                continue;
            }
            tried.push(p);
            left.remove(i);
            cur.push(p);
            dfs(left, cur, last, out);
            cur.pop();
            left.insert(i, p);
        }
    }
    let mut out = Vec::new();
    dfs(&mut patterns.to_vec(), &mut Vec::new(), last, &mut out);
    out
}

/// The 12 training dances of spec §3.13: tempos evenly spaced over 120–190 bpm, each holding the
/// seven basic patterns in a random valid order ending with `C:U1 I0`; seven of them (drawn at
/// random) hold an eighth pattern, a repeat of `C:S0 S0`, `O:I0 U0` or `O:I0 S0` (91 patterns,
/// 364 two-beat instances).
pub fn training_dances(p: &DuetParams, seed: u64) -> Result<Vec<(Take, DuetTruth)>> {
    let basic = basic_patterns();
    let last = Pattern::parse("C:U1 I0").expect("basic");
    let extras = ["C:S0 S0", "O:I0 U0", "O:I0 S0"].map(|s| Pattern::parse(s).expect("basic"));
    let mut rng = Rng::stream(seed, 10);
    let mut with_extra: Vec<usize> = (0..12).collect();
    rng.shuffle(&mut with_extra);
    with_extra.truncate(7);
    (0..12)
        .map(|k| {
            let mut set = basic.clone();
            if with_extra.contains(&k) {
                set.push(extras[rng.below(3)]);
            }
            let orders = chain_orders(&set, Some(last));
            let order = &orders[rng.below(orders.len())];
            let bpm = 120.0 + 70.0 * k as f64 / 11.0;
            duet_take(p, order, bpm, seed.wrapping_mul(1000).wrapping_add(k as u64))
        })
        .collect()
}

/// A random chain of `n` composable patterns from `start`: with probability 0.5 a basic one (when
/// one starts in the current stance), else a novel one (when one does).
pub fn random_chain(n: usize, start: Stance, rng: &mut Rng) -> Vec<Pattern> {
    let basic = basic_patterns();
    let comp = composable(&basic);
    let mut cur = start;
    let mut out = Vec::with_capacity(n);
    for _ in 0..n {
        let from: Vec<Pattern> = comp.iter().copied().filter(|p| p.start == cur).collect();
        let (b, nv): (Vec<Pattern>, Vec<Pattern>) = from.iter().partition(|p| basic.contains(p));
        let pool = if (!b.is_empty() && rng.chance(0.5)) || nv.is_empty() { b } else { nv };
        let p = pool[rng.below(pool.len())];
        cur = p.end().expect("composable patterns are grammatical");
        out.push(p);
    }
    out
}

/// The 3 test dances of spec §3.13 at 125, 155 and 185 bpm with 30, 30 and 31 patterns (91): random
/// chains over the 21 composable patterns from a closed stance, redrawn until all 21 occur.
/// `max_patterns` keeps only the first patterns of every chain (small test runs).
pub fn test_dances(p: &DuetParams, seed: u64, max_patterns: Option<usize>) -> Result<Vec<(Take, DuetTruth)>> {
    let comp = composable(&basic_patterns());
    let mut rng = Rng::stream(seed, 20);
    let chains = loop {
        let chains: Vec<Vec<Pattern>> = [30, 30, 31].iter().map(|&n| random_chain(n, Stance::C, &mut rng)).collect();
        if comp.iter().all(|c| chains.iter().flatten().any(|p| p == c)) {
            break chains;
        }
    };
    chains
        .iter()
        .zip([125.0, 155.0, 185.0])
        .enumerate()
        .map(|(k, (c, bpm))| {
            let c = &c[..max_patterns.map_or(c.len(), |m| m.clamp(1, c.len()))];
            duet_take(p, c, bpm, seed.wrapping_mul(1000).wrapping_add(100 + k as u64))
        })
        .collect()
}

/// A test-like dance of exactly `secs` seconds at `bpm` (the timing input of PC-5): a random chain
/// of composable patterns long enough, cut to `round(secs·rate) + 1` frames.
pub fn timed_dance(p: &DuetParams, secs: f64, bpm: f64, seed: u64) -> Result<(Take, DuetTruth)> {
    let n_pat = (secs * bpm / 60.0 / 8.0).ceil() as usize + 1;
    let mut rng = Rng::stream(seed, 30);
    let chain = random_chain(n_pat, Stance::C, &mut rng);
    let (mut take, mut truth) = duet_take(p, &chain, bpm, seed)?;
    let n = ((secs * p.rate_hz).round() as usize + 1).min(take.control.len());
    take.control = take.control.window(0, n - 1);
    take.target = take.target.window(0, n - 1);
    let keep = take.boundaries.iter().take_while(|&&b| b < n - 1).count();
    take.boundaries.truncate(keep);
    take.boundaries.push(n - 1);
    take.labels.truncate(keep);
    truth.annotations.truncate(n);
    take.annotations = Some(truth.annotations.clone());
    truth.segments.truncate(keep);
    Ok((take, truth))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::dance::grammar::label_set;

    /// Spec §3.13: 12 training dances at 120–190 bpm holding the 7 basic patterns each, 91
    /// patterns and 364 two-beat segments of 0.63–1.0 s in all, each take a valid chain ending
    /// with `C:U1 I0`; labels, boundaries and annotations consistent with the truth.
    #[test]
    fn training_dances_match_the_spec_counts() {
        let p = DuetParams::default();
        let d = training_dances(&p, 27).unwrap();
        assert_eq!(d.len(), 12);
        let basic = basic_patterns();
        let last = Pattern::parse("C:U1 I0").unwrap();
        let (mut pats, mut segs) = (0, 0);
        for (k, (take, truth)) in d.iter().enumerate() {
            assert!((truth.bpm - (120.0 + 70.0 * k as f64 / 11.0)).abs() < 1e-12);
            assert!(basic.iter().all(|b| truth.patterns.contains(b)), "dance {k} lacks a basic pattern");
            assert!(matches!(truth.patterns.len(), 7 | 8));
            assert_eq!(truth.patterns.last(), Some(&last));
            for w in truth.patterns.windows(2) {
                assert_eq!(w[0].end(), Some(w[1].start), "dance {k} is not a chain");
            }
            pats += truth.patterns.len();
            segs += truth.segments.len();
            assert_eq!(truth.segments.len(), 4 * truth.patterns.len());
            assert_eq!(take.labels.len(), truth.segments.len());
            assert_eq!(take.boundaries.len(), take.labels.len() + 1);
            assert!(take.boundaries.windows(2).all(|w| w[0] < w[1]));
            assert_eq!(*take.boundaries.last().unwrap(), take.control.len() - 1);
            assert_eq!(take.annotations.as_ref().unwrap().len(), take.control.len());
            for (l, s) in take.labels.iter().zip(&truth.segments) {
                assert_eq!(l.dance(), Some(s.2));
                let dur = s.1 - s.0;
                assert!((0.6..=1.05).contains(&dur), "two-beat segment of {dur} s");
            }
            // Annotations: closed at the start of every segment iff its stance is closed.
            for (i, s) in truth.segments.iter().enumerate() {
                let f = take.boundaries[i] + 1;
                assert_eq!(truth.closed(f), s.2.stance.closed(), "dance {k} segment {i}");
            }
        }
        assert_eq!(pats, 91);
        assert_eq!(segs, 364);
        assert_eq!(label_set(&d.iter().flat_map(|t| t.1.patterns.clone()).collect::<Vec<_>>()).len(), 16);
    }

    /// Spec §3.13: 3 test dances (30, 30, 31 patterns at 125, 155, 185 bpm), 21 unique patterns
    /// of which 14 novel; the same seed gives the same dance bit for bit.
    #[test]
    fn test_dances_cover_the_composable_patterns() {
        let p = DuetParams::default();
        let d = test_dances(&p, 271, None).unwrap();
        let lens: Vec<usize> = d.iter().map(|t| t.1.patterns.len()).collect();
        assert_eq!(lens, [30, 30, 31]);
        assert_eq!(d.iter().map(|t| t.1.bpm).collect::<Vec<_>>(), [125.0, 155.0, 185.0]);
        let mut uniq: Vec<Pattern> = d.iter().flat_map(|t| t.1.patterns.clone()).collect();
        uniq.sort();
        uniq.dedup();
        assert_eq!(uniq.len(), 21);
        let basic = basic_patterns();
        assert_eq!(uniq.iter().filter(|p| !basic.contains(p)).count(), 14);
        let again = test_dances(&p, 271, Some(3)).unwrap();
        assert_eq!(again[0].0.control.data[..100], d[0].0.control.data[..100]);
    }

    /// Stance feet are planted exactly (both dancers): a foot that does not move over two frames
    /// is at the same world position to the bit, and every frame has at least one such foot per
    /// dancer (one weight change per beat).
    #[test]
    fn feet_are_planted_and_hands_are_held() {
        let p = DuetParams::default();
        let pats: Vec<Pattern> =
            ["C:S0 U0", "O:I1 U0", "OX:S1 S0"].iter().map(|s| Pattern::parse(s).unwrap()).collect();
        let (take, truth) = duet_take(&p, &pats, 150.0, 3).unwrap();
        let n = take.control.len();
        for t in [&take.control, &take.target] {
            let mut still = 0;
            for f in 1..n {
                let moved = |k: usize| t.frame(f)[k] != t.frame(f - 1)[k];
                still += usize::from(!moved(2) || !moved(3));
            }
            assert!(still as f64 >= 0.9 * (n - 1) as f64, "{still} of {} frames with a planted foot", n - 1);
        }
        // Held hands: the follower's right hand stays within the noise of the holding hand.
        for f in 0..n {
            let a = truth.annotations[f];
            let h = if a & HOLD_LR != 0 {
                0
            } else if a & HOLD_RR != 0 {
                1
            } else {
                continue;
            };
            let gap = (take.control.frame(f)[h] - take.target.frame(f)[1]).norm();
            assert!(gap <= 2.0 * 2.45 * p.noise_m + 1e-12, "frame {f}: held-hand gap {gap}");
        }
        // A chain that does not connect is a typed error.
        let bad = [Pattern::parse("C:S0 S0").unwrap(), Pattern::parse("O:I0 S0").unwrap()];
        assert!(matches!(duet_take(&p, &bad, 150.0, 3), Err(PcError::BadParameter { .. })));
        assert!(duet_take(&p, &pats, f64::NAN, 3).is_err());
    }
}

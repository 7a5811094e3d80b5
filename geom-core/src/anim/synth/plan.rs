//! The synthesiser's time plan (motion-graph.md §3.13.2 steps 1–3, 8–10): a 120 Hz simulation of
//! the root path, the gait clock and the behaviour state machine, producing per-substep samples
//! (path, speed, phase, pelvis offsets, gesture weights, labels) and, per foot, the list of
//! stances (time interval + fixed plant pose).
//!
//! Gait clock: stride frequency `f(v) = clamp(0.6 + 0.25 v, 0.8, 1.6) Hz × cadence`; the left
//! foot is in stance for `φ ∈ [k, k + β)`, the right for `φ ∈ [k + ½, k + ½ + β)`, with the duty
//! factor `β` fixed per stance at its start (0.62 walking … 0.35 running). When a behaviour that
//! needs both feet down starts (stand, jump, pick-up), the clock keeps stepping in place until
//! both feet are in stance (double support), then freezes; it resumes from there.

use super::{bit, Behaviour, GestureKind, Script};
use crate::math::{smoothstep, Planar, Vec3};
use crate::rng::Rng;

/// Simulation substep rate (Hz).
pub(super) const SUB_HZ: f64 = 120.0;
/// Pre-roll (s) simulated before time 0 so a clip starts mid-gait at a random phase.
const PRE_ROLL: f64 = 2.0;
/// Post-roll (s) after the end so a foot in swing at the last frame has its next plant.
const POST_ROLL: f64 = 1.5;
/// Duty factors walking / running (running: 0.35 up to 3 m/s, then −0.02 per m/s down to 0.29 at
/// 6 m/s, which keeps the hip extension at toe-off within −30°).
const BETA_WALK: f64 = 0.62;
const BETA_RUN: f64 = 0.35;
/// Largest distance (m) the pelvis may move ahead of a planted foot before the foot lifts.
const MAX_BEHIND: f64 = 0.45;
/// Gravity (m/s²) for jump flight times.
pub(super) const G: f64 = 9.81;
/// Toe-out of each foot (rad).
const TOE_OUT: f64 = 6.0 * std::f64::consts::PI / 180.0;

/// One simulation substep (all planar quantities in the world after the start transform).
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct Sample {
    pub x: f64,
    pub z: f64,
    /// Path heading (rad, unwrapped).
    pub psi: f64,
    /// Forward speed (m/s).
    pub v: f64,
    /// Gait phase (strides).
    pub phase: f64,
    /// Run blend in [0, 1] (0 walk, 1 run).
    pub run: f64,
    /// Gait activity blend in [0, 1] (bob, sway, arm swing).
    pub gait: f64,
    /// Extra pelvis height (m): crouches, flight, pick-up.
    pub dy: f64,
    /// Extra forward trunk lean (rad).
    pub lean: f64,
    /// Pick-up (right hand to the floor) weight.
    pub pickup: f64,
    /// Wave weight.
    pub wave: f64,
    /// Reach weight.
    pub reach: f64,
    /// Reach target height (m).
    pub reach_h: f64,
    /// Label bits.
    pub labels: u64,
    /// Both feet off the ground in a jump (no leg-reach limit on the pelvis).
    pub airborne: bool,
}

/// A foot stance: the foot is flat and fixed at the plant from `t0` until its toe-off, then pivots
/// about the fixed toe until `t1`.
#[derive(Clone, Copy, Debug)]
pub(super) struct Stance {
    pub t0: f64,
    /// `f64::INFINITY` if the stance lasts past the end of the plan.
    pub t1: f64,
    /// Ankle ground point (x, z) and foot yaw.
    pub x: f64,
    pub z: f64,
    pub yaw: f64,
    /// Swing clearance (m) of the swing that ends at this stance.
    pub clear: f64,
}

impl Stance {
    /// Duration of the toe-off pivot (s): the last 25 % of the stance, at most 0.2 s (so long
    /// standing stances do not rise on the toes for seconds); 0.2 s for a stance open at its start,
    /// 0 for one open at its end.
    pub fn toe_off(&self) -> f64 {
        if !self.t1.is_finite() {
            0.0
        } else if self.t0.is_finite() {
            (0.25 * (self.t1 - self.t0)).min(0.2)
        } else {
            0.2
        }
    }
}

/// The plan of a clip.
pub(super) struct Plan {
    /// Time of `samples[0]` (negative: pre-roll).
    pub t_first: f64,
    pub samples: Vec<Sample>,
    /// Stances of the left (0) and right (1) foot, in time order.
    pub feet: [Vec<Stance>; 2],
    /// Script duration (s), from 0 to the end of the last behaviour.
    pub duration: f64,
}

impl Plan {
    /// Sample at time `t`, linearly interpolated (labels and flags from the nearer substep).
    pub fn at(&self, t: f64) -> Sample {
        let u = ((t - self.t_first) * SUB_HZ).max(0.0);
        let n = self.samples.len();
        let i = (u.floor() as usize).min(n.saturating_sub(2));
        let s = (u - i as f64).clamp(0.0, 1.0);
        let (a, b) = (&self.samples[i], &self.samples[(i + 1).min(n - 1)]);
        let l = |p: f64, q: f64| p + (q - p) * s;
        let near = if s < 0.5 { a } else { b };
        Sample {
            x: l(a.x, b.x),
            z: l(a.z, b.z),
            psi: l(a.psi, b.psi),
            v: l(a.v, b.v),
            phase: l(a.phase, b.phase),
            run: l(a.run, b.run),
            gait: l(a.gait, b.gait),
            dy: l(a.dy, b.dy),
            lean: l(a.lean, b.lean),
            pickup: l(a.pickup, b.pickup),
            wave: l(a.wave, b.wave),
            reach: l(a.reach, b.reach),
            reach_h: l(a.reach_h, b.reach_h),
            labels: near.labels,
            airborne: a.airborne || b.airborne,
        }
    }
}

/// A jump in flight: take-off time, flight time, the two feet's plants `(x, z, yaw)`.
type JumpState = (f64, f64, [(f64, f64, f64); 2]);

/// A behaviour with its durations resolved.
#[derive(Clone, Debug)]
enum Seg {
    Stand(f64),
    Loco(f64, super::Profile, super::Profile),
    Turn(f64, f64),
    Jump(f64, f64),
    Pickup(f64),
}

fn clean(x: f64) -> f64 {
    if x.is_finite() {
        x.max(0.0)
    } else {
        0.0
    }
}

/// Stride frequency (Hz) at speed `v`.
fn stride_freq(v: f64, cadence: f64) -> f64 {
    (0.6 + 0.25 * v).clamp(0.8, 1.6) * cadence
}

/// Per-foot gait state.
#[derive(Clone, Copy, Debug)]
struct FootState {
    in_stance: bool,
    /// Phase at which the current (phase-driven) stance ends; `INFINITY` if not phase-driven.
    end_phase: f64,
    /// Phase at which the next stance starts.
    next_start: f64,
}

struct Sim<'a> {
    t: f64,
    x: f64,
    z: f64,
    psi: f64,
    v: f64,
    /// Heading rate (rad/s) of the last substep.
    omega: f64,
    phase: f64,
    running: bool,
    run: f64,
    gait_on: bool,
    gait: f64,
    kappa_ou: f64,
    feet: [FootState; 2],
    stances: [Vec<Stance>; 2],
    style: &'a super::SynthStyle,
    cadence: f64,
}

impl Sim<'_> {
    fn left_dir(&self, psi: f64) -> (f64, f64) {
        (psi.cos(), -psi.sin())
    }

    /// Plant pose of foot `side` (0 left) predicted around the middle of a stance starting now.
    /// Plant pose of foot `side` (0 left) at the path point `ahead` metres further on, where
    /// the heading has turned by `dpsi` (the chord of the arc is taken along `ψ + dpsi/2`).
    fn plant(&self, side: usize, ahead: f64, dpsi: f64) -> (f64, f64, f64) {
        let sgn = if side == 0 { 1.0 } else { -1.0 };
        let psi = self.psi + dpsi;
        let (lx, lz) = self.left_dir(psi);
        let half = 0.5 * self.style.step_width.clamp(0.0, 0.6);
        let mid = self.psi + 0.5 * dpsi;
        let x = self.x + ahead * mid.sin() + sgn * half * lx;
        let z = self.z + ahead * mid.cos() + sgn * half * lz;
        (x, z, psi + sgn * TOE_OUT)
    }

    fn open_stance(&mut self, side: usize, t0: f64, ahead: f64, dpsi: f64) {
        let (x, z, yaw) = self.plant(side, ahead, dpsi);
        let clear = 0.06 + (0.14 - 0.06) * self.run;
        self.stances[side].push(Stance { t0, t1: f64::INFINITY, x, z, yaw, clear });
        self.feet[side].in_stance = true;
    }

    fn close_stance(&mut self, side: usize, t1: f64) {
        if let Some(s) = self.stances[side].last_mut() {
            if s.t1.is_infinite() {
                s.t1 = t1.max(s.t0 + 1e-6);
            }
        }
        self.feet[side].in_stance = false;
        self.feet[side].end_phase = f64::INFINITY;
    }

    /// Advances the gait clock over one substep at stride frequency `f`, opening and closing
    /// stances at the interpolated crossing times. `settling`: new stances use the walking duty
    /// factor so that double support exists.
    fn step_clock(&mut self, f: f64, dt: f64, settling: bool) {
        let p0 = self.phase;
        let p1 = p0 + f * dt;
        for side in 0..2 {
            let fs = self.feet[side];
            if fs.in_stance && fs.end_phase > p0 && fs.end_phase <= p1 {
                let tc = self.t + (fs.end_phase - p0) / f;
                self.close_stance(side, tc);
            }
            let fs = self.feet[side];
            if !fs.in_stance && fs.next_start > p0 && fs.next_start <= p1 {
                let tc = self.t + (fs.next_start - p0) / f;
                let beta_run = BETA_RUN - 0.02 * (self.v - 3.0).clamp(0.0, 3.0);
                let beta = if settling { BETA_WALK } else { BETA_WALK + (beta_run - BETA_WALK) * self.run };
                // Plant at the predicted mid-stance path point (along the arc of the current
                // turn rate), slightly ahead (0.04 s of travel) to limit hip extension at toe-off.
                let tau = 0.5 * beta / f + 0.04;
                self.open_stance(side, tc, self.v * tau, self.omega * tau);
                self.feet[side].end_phase = fs.next_start + beta;
                self.feet[side].next_start = fs.next_start + 1.0;
            }
        }
        self.phase = p1;
    }

    fn both_down(&self) -> bool {
        self.feet[0].in_stance && self.feet[1].in_stance
    }
}

/// Runs the plan of `script`.
pub(super) fn simulate(script: &Script, seed: u64) -> Plan {
    let dt = 1.0 / SUB_HZ;
    let style = &script.style;
    let (_, _, cadence) = style.effective();
    let cadence = if cadence.is_finite() && cadence > 0.05 { cadence } else { 1.0 };
    let mut rng = Rng::stream(seed, 0x51A7);

    // Resolve behaviours; gestures attach to the next behaviour index.
    let mut segs: Vec<Seg> = Vec::new();
    let mut gestures: Vec<(usize, GestureKind, f64)> = Vec::new();
    for b in &script.behaviours {
        match b {
            Behaviour::Stand { secs } => segs.push(Seg::Stand(clean(*secs))),
            Behaviour::Locomote { secs, speed, curvature } => {
                segs.push(Seg::Loco(clean(*secs), speed.clone(), curvature.clone()))
            }
            Behaviour::TurnInPlace { deg } => {
                let d = if deg.is_finite() { deg.to_radians() } else { 0.0 };
                segs.push(Seg::Turn(d, 0.6 + 1.2 * d.abs() / std::f64::consts::PI));
            }
            Behaviour::Jump { distance, apex } => segs.push(Seg::Jump(clean(*distance), clean(*apex).max(0.02))),
            Behaviour::Pickup { secs } => segs.push(Seg::Pickup(clean(*secs).max(1.6))),
            Behaviour::Gesture { kind, secs } => gestures.push((segs.len(), *kind, clean(*secs))),
        }
    }

    // Initial conditions from the first behaviour.
    let (v0, _k0, gait0) = match segs.first() {
        Some(Seg::Loco(_, sp, cu)) => {
            let v = sp.eval(0.0).max(0.0);
            (if v >= 0.1 { v } else { 0.0 }, cu.eval(0.0), v >= 0.1)
        }
        Some(Seg::Turn(..)) => (0.0, 0.0, true),
        _ => (0.0, 0.0, false),
    };
    let run0 = if v0 > 2.0 { 1.0 } else { 0.0 };
    let beta0 = BETA_WALK + (BETA_RUN - BETA_WALK) * run0;
    let phase0 = if gait0 {
        rng.f64()
    } else if rng.chance(0.5) {
        0.55
    } else {
        0.05
    };
    let mut sim = Sim {
        t: -PRE_ROLL,
        x: 0.0,
        z: 0.0,
        psi: 0.0,
        v: v0,
        omega: 0.0,
        phase: phase0,
        running: run0 > 0.5,
        run: run0,
        gait_on: gait0,
        gait: if gait0 { 1.0 } else { 0.0 },
        kappa_ou: 0.0,
        feet: [FootState { in_stance: false, end_phase: f64::INFINITY, next_start: 0.0 }; 2],
        stances: [Vec::new(), Vec::new()],
        style,
        cadence,
    };
    for side in 0..2 {
        let off = 0.5 * side as f64;
        let local = phase0 - off;
        let k = local.floor();
        let beta = if gait0 { beta0 } else { BETA_WALK };
        let in_st = local - k < beta;
        sim.feet[side].next_start = k + 1.0 + off;
        if in_st {
            sim.open_stance(side, f64::NEG_INFINITY, 0.0, 0.0);
            sim.feet[side].end_phase = k + beta + off;
        } else {
            // Virtual previous stance behind, ended at the start of the pre-roll.
            sim.open_stance(side, -PRE_ROLL - 0.5, -0.3, 0.0);
            sim.close_stance(side, -PRE_ROLL);
        }
    }

    let mut samples: Vec<Sample> = Vec::new();
    let n_pre = (PRE_ROLL * SUB_HZ).round() as usize;
    // Segment cursor.
    let mut seg_i = 0usize;
    let mut seg_t = 0.0f64; // time since the segment started
    let mut ready_t: Option<f64> = None; // time since both feet are down (non-gait segments)
    let mut jump_state: Option<JumpState> = None;
    let mut gesture_abs: Vec<(f64, GestureKind, f64)> = Vec::new();
    let mut end_time: Option<f64> = None;
    let mut step = 0usize;
    let sigma_ou = 0.03;
    let tau_ou = 1.5;
    loop {
        let in_pre = step < n_pre;
        if !in_pre && end_time.is_none() {
            // Attach gestures that start with the current segment.
            while let Some(&(idx, kind, secs)) = gestures.first() {
                if idx <= seg_i && seg_t == 0.0 {
                    gesture_abs.push((sim.t, kind, secs));
                    gestures.remove(0);
                } else {
                    break;
                }
            }
        }
        let post = end_time.is_some_and(|e| sim.t >= e);
        if end_time.is_some_and(|e| sim.t >= e + POST_ROLL) {
            break;
        }
        // Commanded quantities for this substep.
        let mut v_cmd = 0.0;
        let mut kappa = 0.0;
        let mut turn_rate = 0.0;
        let mut gait_want = false;
        let mut dy = 0.0;
        let mut lean = 0.0;
        let mut pickup = 0.0;
        let mut labels = 0u64;
        let mut airborne = false;
        let mut seg_done = false;
        let cur = if in_pre {
            segs.first()
        } else if post {
            segs.last()
        } else {
            segs.get(seg_i)
        };
        match cur {
            Some(Seg::Loco(secs, sp, cu)) => {
                let u = if in_pre {
                    0.0
                } else if post {
                    1.0
                } else if *secs > 0.0 {
                    (seg_t / secs).min(1.0)
                } else {
                    1.0
                };
                let v = sp.eval(u).max(0.0);
                gait_want = v >= 0.1;
                v_cmd = if gait_want { v } else { 0.0 };
                // Ornstein–Uhlenbeck perturbation of the curvature (§3.13.2 step 11).
                if !in_pre && !post {
                    sim.kappa_ou += -sim.kappa_ou / tau_ou * dt + sigma_ou * (2.0 * dt / tau_ou).sqrt() * rng.normal();
                }
                kappa = cu.eval(u) + if in_pre { 0.0 } else { sim.kappa_ou };
                seg_done = !in_pre && seg_t + 0.5 * dt >= *secs;
            }
            Some(Seg::Turn(ang, secs)) => {
                gait_want = true;
                if !in_pre && !post {
                    // ψ(τ) = ψ0 + ang·smoothstep(τ/T): rate = ang·6s(1−s)/T.
                    let s = (seg_t / secs).clamp(0.0, 1.0);
                    turn_rate = ang * 6.0 * s * (1.0 - s) / secs;
                    labels |= bit("turn");
                    seg_done = seg_t + 0.5 * dt >= *secs;
                }
            }
            Some(Seg::Stand(secs)) if !in_pre && !post => {
                if let Some(r) = ready_t {
                    seg_done = r + 0.5 * dt >= *secs;
                }
            }
            Some(Seg::Pickup(secs)) if !in_pre && !post => {
                if let Some(r) = ready_t {
                    let w = smoothstep(0.0, 0.6, r) * (1.0 - smoothstep(secs - 0.6, *secs, r));
                    dy = -0.45 * w;
                    lean = 50f64.to_radians() * w;
                    pickup = w;
                    labels |= bit("pickup");
                    seg_done = r + 0.5 * dt >= *secs;
                }
            }
            Some(Seg::Jump(dist, apex)) if !in_pre && !post => {
                if let Some(r) = ready_t {
                    let v0j = (2.0 * G * apex).sqrt();
                    let tf = 2.0 * v0j / G;
                    let tc = 0.3;
                    if r < tc {
                        let s = r / tc;
                        dy = (s * s * s - s * s) * v0j * tc - 0.1 * (std::f64::consts::PI * s).sin().powi(2);
                    } else if r < tc + tf {
                        let tau = r - tc;
                        if jump_state.is_none() {
                            let plants = [0, 1].map(|s| {
                                let st = sim.stances[s].last().copied();
                                st.map_or((sim.x, sim.z, sim.psi), |st| (st.x, st.z, st.yaw))
                            });
                            let t_off = sim.t - tau;
                            sim.close_stance(0, t_off);
                            sim.close_stance(1, t_off);
                            jump_state = Some((t_off, tf, plants));
                        }
                        dy = v0j * tau - 0.5 * G * tau * tau;
                        v_cmd = dist / tf;
                        airborne = true;
                        labels |= bit("jump");
                    } else if r < 2.0 * tc + tf {
                        if let Some((t_off, tf_, plants)) = jump_state.take() {
                            let t_land = t_off + tf_;
                            let (fx, fz) = (sim.psi.sin() * dist, sim.psi.cos() * dist);
                            for (side, p) in plants.iter().enumerate() {
                                let clear = 0.5 * apex + 0.06;
                                sim.stances[side].push(Stance {
                                    t0: t_land,
                                    t1: f64::INFINITY,
                                    x: p.0 + fx,
                                    z: p.1 + fz,
                                    yaw: p.2,
                                    clear,
                                });
                                sim.feet[side].in_stance = true;
                                // Frozen clock: keep the phase-driven bookkeeping of double support.
                            }
                            // Restore the phase-driven stance ends (the clock is frozen in double support).
                            let ph = sim.phase;
                            for side in 0..2 {
                                let off = 0.5 * side as f64;
                                let k = (ph - off).floor();
                                sim.feet[side].end_phase = k + off + BETA_WALK;
                                sim.feet[side].next_start = k + off + 1.0;
                            }
                        }
                        let s = (r - tc - tf) / tc;
                        dy = -v0j * tc * s * (1.0 - s) * (1.0 - s) - 0.1 * (std::f64::consts::PI * s).sin().powi(2);
                    } else {
                        seg_done = true;
                    }
                }
            }
            _ => {}
        }

        // Gait clock.
        let settling = !gait_want && sim.gait_on;
        if gait_want {
            if !sim.gait_on {
                sim.gait_on = true;
            }
        } else if sim.gait_on && sim.both_down() {
            sim.gait_on = false;
        }
        if !gait_want && ready_t.is_none() && !sim.gait_on && !in_pre && !post {
            ready_t = Some(0.0);
        }
        // Run/walk state with hysteresis, blended.
        if v_cmd > 2.3 {
            sim.running = true;
        } else if v_cmd < 1.8 {
            sim.running = false;
        }
        let run_target = if sim.running { 1.0 } else { 0.0 };
        sim.run += (run_target - sim.run).clamp(-2.5 * dt, 2.5 * dt);
        let gait_target = if sim.gait_on { 1.0 } else { 0.0 };
        sim.gait += (gait_target - sim.gait).clamp(-4.0 * dt, 4.0 * dt);
        sim.v = if settling { 0.0 } else { v_cmd };

        // Labels.
        if airborne {
        } else if sim.gait_on && sim.v >= 0.1 {
            labels |= if sim.run >= 0.5 { bit("run") } else { bit("walk") };
        } else if labels & (bit("pickup") | bit("turn")) == 0 && !matches!(cur, Some(Seg::Jump(..))) {
            labels |= bit("stand");
        }
        if (kappa * sim.v).abs() > 0.6 {
            labels |= bit("turn");
        }
        let (mut wave, mut reach, mut reach_h) = (0.0, 0.0, 1.7);
        for (i, &(t0, kind, secs)) in gesture_abs.iter().enumerate() {
            let tau = sim.t - t0;
            if tau >= 0.0 && tau <= secs {
                let w = smoothstep(0.0, 0.4, tau) * (1.0 - smoothstep(secs - 0.4, secs, tau));
                match kind {
                    GestureKind::Wave => {
                        wave = w.max(wave);
                        labels |= bit("wave");
                    }
                    GestureKind::Reach => {
                        reach = w.max(reach);
                        reach_h = 1.5 + 0.4 * ((i as f64 * 0.618034 + seed as f64 * 0.1).fract());
                        labels |= bit("reach");
                    }
                }
            }
        }
        samples.push(Sample {
            x: sim.x,
            z: sim.z,
            psi: sim.psi,
            v: sim.v,
            phase: sim.phase,
            run: sim.run,
            gait: sim.gait,
            dy,
            lean,
            pickup,
            wave,
            reach,
            reach_h,
            labels,
            airborne,
        });

        // A stance foot left too far behind (the body accelerated faster than the clock) lifts
        // early: the foot stays exactly planted while in stance, and every stance stays
        // reachable.
        if sim.gait_on {
            for side in 0..2 {
                if let (true, Some(st)) = (sim.feet[side].in_stance, sim.stances[side].last()) {
                    let behind = (sim.x - st.x) * sim.psi.sin() + (sim.z - st.z) * sim.psi.cos();
                    if st.t1.is_infinite() && behind > MAX_BEHIND {
                        let t = sim.t;
                        sim.close_stance(side, t);
                    }
                }
            }
        }
        // Advance the clock and the path.
        if sim.gait_on {
            let f = stride_freq(sim.v, sim.cadence);
            sim.step_clock(f, dt, settling);
        }
        sim.omega = kappa * sim.v + turn_rate;
        sim.psi += sim.omega * dt;
        sim.x += sim.v * sim.psi.sin() * dt;
        sim.z += sim.v * sim.psi.cos() * dt;
        sim.t += dt;
        step += 1;
        if !in_pre && !post {
            seg_t += dt;
            if let Some(r) = ready_t.as_mut() {
                *r += dt;
            }
            if seg_done {
                seg_i += 1;
                seg_t = 0.0;
                ready_t = None;
                jump_state = None;
                if seg_i >= segs.len() {
                    end_time = Some(sim.t - dt);
                }
            }
            if segs.is_empty() {
                end_time = Some(0.0);
            }
        }
        // Safety bound: a script cannot run longer than a day of motion.
        if sim.t > 86_400.0 {
            end_time.get_or_insert(sim.t);
        }
    }
    let duration = end_time.unwrap_or(0.0).max(0.0);
    let mut feet = sim.stances;

    // Move everything so that the torso frame at time 0 is the script's start.
    let s0 = &samples[n_pre.min(samples.len() - 1)];
    let w = script.start.compose(&Planar::new(s0.x, s0.z, s0.psi).inverse());
    let w = if w.x.is_finite() && w.z.is_finite() && w.yaw.is_finite() { w } else { Planar::identity() };
    for s in samples.iter_mut() {
        let p = w.apply_point(Vec3::new(s.x, 0.0, s.z));
        s.x = p.x;
        s.z = p.z;
        s.psi += w.yaw;
    }
    for f in feet.iter_mut() {
        for st in f.iter_mut() {
            let p = w.apply_point(Vec3::new(st.x, 0.0, st.z));
            st.x = p.x;
            st.z = p.z;
            st.yaw += w.yaw;
        }
    }
    Plan { t_first: -PRE_ROLL, samples, feet, duration }
}

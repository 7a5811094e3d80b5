//! Inflow emitters and outflow regions (issue 26 item 4; ours — the paper has neither).
//!
//! An [`Emitter`] (a `Box` or a `Disc`) adds finest-size particles at a volume rate `rate`
//! (m³/s) with a given velocity, between `start` and `stop`. The `k`-th particle (volume
//! `(2r)³`, `r = h_min / C_H`, the finest lattice's particles) is due at
//! `t_k = start + (k + 1) (2r)³ / rate`; in the step that reaches `t_k` it appears at the next
//! of the emitter's slots (a fixed pseudo-random order of the lattice points of spacing `2r`
//! inside the box, or in the disc's plane inside its radius), moved by `velocity · (t − t_k)`
//! so that a steady stream is not stacked. The emitted volume is the rate times the elapsed
//! emission time to within one particle. For a steady jet choose `rate ≈ area × speed`.
//!
//! An outflow region (`Scene::outflow`, shapes) deletes every particle whose centre lies in it
//! at the end of a step; their volume is added to the simulator's `deleted_volume`.
//! Both are off (no cost) when the scene lists none.

use geom_core::math::{Pt3, Vec3};
use serde::{Deserialize, Serialize};

use crate::particles::Particles;

/// Where an emitter's particles appear.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum EmitterShape {
    /// Lattice points inside an axis-aligned box (m).
    Box {
        /// Minimum corner (m).
        min: [f64; 3],
        /// Maximum corner (m).
        max: [f64; 3],
    },
    /// Lattice points of the disc's plane within `radius` of `center`.
    Disc {
        /// Centre (m).
        center: [f64; 3],
        /// Normal of the disc's plane (normalised on use).
        normal: [f64; 3],
        /// Radius (m).
        radius: f64,
    },
}

/// An inflow emitter (scene file `emitters: [(shape: Disc(…), velocity: (0, -1, 0), rate: 1e-4)]`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Emitter {
    /// Emission region.
    pub shape: EmitterShape,
    /// Velocity of the emitted liquid (m/s).
    pub velocity: [f64; 3],
    /// Volume rate (m³/s).
    pub rate: f64,
    /// Start time (s).
    #[serde(default)]
    pub start: f64,
    /// Stop time (s; none = never).
    #[serde(default)]
    pub stop: Option<f64>,
}

impl Emitter {
    /// Checks the emitter's numbers; the message names `field`.
    pub fn validate(&self, field: &str) -> std::result::Result<(), String> {
        let fin = |v: &[f64]| v.iter().all(|x| x.is_finite());
        if !(fin(&self.velocity) && self.rate.is_finite() && self.rate > 0.0 && self.start.is_finite()) {
            return Err(format!("{field}: velocity and start must be finite, rate > 0"));
        }
        if let Some(s) = self.stop {
            if !(s.is_finite() && s > self.start) {
                return Err(format!("{field}.stop must be finite and after start"));
            }
        }
        match &self.shape {
            EmitterShape::Box { min, max } => {
                if !(fin(min) && fin(max) && (0..3).all(|a| max[a] > min[a])) {
                    return Err(format!("{field}: Box needs finite corners with max > min"));
                }
            }
            EmitterShape::Disc { center, normal, radius } => {
                if !(fin(center) && fin(normal) && radius.is_finite() && *radius > 0.0) {
                    return Err(format!("{field}: Disc needs a finite centre and normal, radius > 0"));
                }
                if Vec3::new(normal[0], normal[1], normal[2]).norm() == 0.0 {
                    return Err(format!("{field}: Disc normal must be non-zero"));
                }
            }
        }
        Ok(())
    }

    /// The emitter's slot positions for particles of radius `r` (m), in their emission order.
    pub fn slots(&self, r: f64, seed: u64) -> Vec<Pt3> {
        let s = 2.0 * r;
        let mut pts = Vec::new();
        match &self.shape {
            EmitterShape::Box { min, max } => {
                let n = [0, 1, 2].map(|a| (((max[a] - min[a]) / s).floor() as usize).max(1));
                for k in 0..n[2] {
                    for j in 0..n[1] {
                        for i in 0..n[0] {
                            let c = [i, j, k].map(|q| q as f64 + 0.5);
                            pts.push(Pt3::new(
                                min[0] + (max[0] - min[0]) * c[0] / n[0] as f64,
                                min[1] + (max[1] - min[1]) * c[1] / n[1] as f64,
                                min[2] + (max[2] - min[2]) * c[2] / n[2] as f64,
                            ));
                        }
                    }
                }
            }
            EmitterShape::Disc { center, normal, radius } => {
                let nrm = Vec3::new(normal[0], normal[1], normal[2]).normalize();
                let helper = if nrm.x.abs() < 0.9 { Vec3::x() } else { Vec3::y() };
                let e1 = nrm.cross(&helper).normalize();
                let e2 = nrm.cross(&e1);
                let c = Pt3::new(center[0], center[1], center[2]);
                let m = (radius / s).ceil() as i64;
                for j in -m..m {
                    for i in -m..m {
                        let (a, b) = ((i as f64 + 0.5) * s, (j as f64 + 0.5) * s);
                        if a * a + b * b <= radius * radius {
                            pts.push(c + e1 * a + e2 * b);
                        }
                    }
                }
                if pts.is_empty() {
                    pts.push(c);
                }
            }
        }
        // A fixed pseudo-random order (Fisher–Yates with geom-core's RNG), so that consecutive
        // particles do not sweep the slots row by row.
        let mut rng = geom_core::rng::Rng::new(seed);
        for i in (1..pts.len()).rev() {
            let j = (rng.next_u64() % (i as u64 + 1)) as usize;
            pts.swap(i, j);
        }
        pts
    }
}

/// Run-time state of one emitter.
#[derive(Clone, Debug)]
pub struct EmitterState {
    emitter: Emitter,
    slots: Vec<Pt3>,
    r: f64,
    /// Particles emitted so far.
    pub emitted: u64,
    next_slot: usize,
}

impl EmitterState {
    /// The emitter with its slots for particles of radius `r` (m).
    pub fn new(emitter: &Emitter, r: f64, seed: u64) -> Self {
        Self { emitter: emitter.clone(), slots: emitter.slots(r, seed), r, emitted: 0, next_slot: 0 }
    }

    /// Volume emitted so far (m³).
    pub fn emitted_volume(&self) -> f64 {
        self.emitted as f64 * 8.0 * self.r.powi(3)
    }

    /// Emits every particle due by time `t` (s, the end of the step) into `parts`; returns the
    /// number emitted.
    pub fn emit(&mut self, t: f64, parts: &mut Particles) -> usize {
        let e = &self.emitter;
        let vol = 8.0 * self.r.powi(3);
        let v = Vec3::new(e.velocity[0], e.velocity[1], e.velocity[2]);
        let mut n = 0;
        loop {
            let tk = e.start + (self.emitted + 1) as f64 * vol / e.rate;
            if tk > t || e.stop.is_some_and(|s| tk > s) {
                break;
            }
            let x = self.slots[self.next_slot] + v * (t - tk);
            self.next_slot = (self.next_slot + 1) % self.slots.len();
            parts.push(x, v, self.r, -self.r);
            self.emitted += 1;
            n += 1;
        }
        n
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn emitted_volume_follows_the_rate_to_one_particle() {
        let e = Emitter {
            shape: EmitterShape::Disc { center: [0.0; 3], normal: [0.0, 1.0, 0.0], radius: 0.02 },
            velocity: [0.0, -1.0, 0.0],
            rate: 1e-4,
            start: 0.1,
            stop: Some(0.5),
        };
        e.validate("emitters[0]").unwrap();
        let mut st = EmitterState::new(&e, 0.002, 3);
        let mut p = Particles::default();
        let mut t = 0.0;
        while t < 0.7 {
            t += 0.003;
            st.emit(t, &mut p);
        }
        let want = 1e-4 * 0.4;
        assert!((st.emitted_volume() - want).abs() <= 8.0 * 0.002f64.powi(3) + 1e-15);
        assert_eq!(p.len() as u64, st.emitted);
        assert!(p.x.iter().all(|x| x.x.hypot(x.z) <= 0.02 && x.y <= 0.0));
    }

    #[test]
    fn bad_emitter_names_the_field() {
        let e = Emitter {
            shape: EmitterShape::Box { min: [0.0; 3], max: [0.0, 1.0, 1.0] },
            velocity: [0.0; 3],
            rate: 1.0,
            start: 0.0,
            stop: None,
        };
        assert!(e.validate("emitters[2]").unwrap_err().contains("emitters[2]"));
    }
}

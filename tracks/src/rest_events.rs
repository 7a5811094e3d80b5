//! [`RestEvents`]: scheduled changes of a shell's hinge rest angles — Xavier's `CrinkleRest` and
//! `RestoreRest` events (spec §6.4): during the electrocution the cloth's rest shape is crinkled
//! (blended over 0.2 s from 7 s to the hinge angles of the rest mesh offset along its vertex
//! normals by seeded uniform ±4 mm noise), and the shake-off restores it (blended back over 0.2 s
//! from 8.5 s). Applied to both the tracked and the untracked twin, so they see the same material.

use geom_core::math::{smoothstep, Pt3};
use geom_core::mesh::{vertex_normals, NormalWeight, TriMesh};
use geom_core::rng::Rng;
use shells::ShellSim;

/// A crinkle/restore schedule of the hinge rest angles: θ̄(t) = θ̄₀ + w(t)(θ̄₁ − θ̄₀) with
/// w(t) = smoothstep(on)·(1 − smoothstep(off)).
#[derive(Clone, Debug, PartialEq)]
pub struct RestEvents {
    /// Rest angles θ̄₀ before the crinkle (rad, one per hinge of the simulation).
    pub base: Vec<f64>,
    /// Crinkled rest angles θ̄₁ (rad).
    pub target: Vec<f64>,
    /// Blend-in window (s): `CrinkleRest`.
    pub on: (f64, f64),
    /// Blend-out window (s): `RestoreRest`.
    pub off: (f64, f64),
}

impl RestEvents {
    /// Xavier's events for `sim` (built on `rest`): the crinkled angles are those of `rest`
    /// with every vertex moved along its (angle-weighted) normal by a uniform offset in
    /// [−`amplitude`, `amplitude`] m (spec: 4 mm), seeded; blends over [7, 7.2] s and
    /// [8.5, 8.7] s.
    pub fn xavier(sim: &ShellSim, rest: &TriMesh, amplitude: f64, seed: u64) -> Self {
        let normals = vertex_normals(&rest.faces, &rest.positions, NormalWeight::Angle);
        let mut rng = Rng::new(seed);
        let q: Vec<Pt3> =
            rest.positions.iter().zip(&normals).map(|(p, n)| p + n * rng.range(-amplitude, amplitude)).collect();
        Self { base: sim.rest_angles(), target: sim.hinge_angles(&q), on: (7.0, 7.2), off: (8.5, 8.7) }
    }

    /// Blend weight w(t) ∈ [0, 1].
    pub fn weight(&self, t: f64) -> f64 {
        smoothstep(self.on.0, self.on.1, t) * (1.0 - smoothstep(self.off.0, self.off.1, t))
    }

    /// Rest angles at weight `w` (exactly θ̄₀ at 0 and θ̄₁ at 1).
    pub fn angles(&self, w: f64) -> Vec<f64> {
        self.base.iter().zip(&self.target).map(|(a, b)| (1.0 - w) * a + w * b).collect()
    }

    /// Sets `sim`'s rest angles for time `t` when the weight differs from `*last` (the weight
    /// applied before, updated); returns whether it changed them.
    pub fn apply(&self, sim: &mut ShellSim, t: f64, last: &mut f64) -> shells::Result<bool> {
        let w = self.weight(t);
        if w == *last {
            return Ok(false);
        }
        sim.set_rest_angles(&self.angles(w))?;
        *last = w;
        Ok(true)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::procedural::{xavier, xavier_guide, xavier_sim};

    /// The schedule is off before 7 s and after 8.7 s, fully crinkled on [7.2, 8.5] s; the
    /// crinkle changes the rest angles by amounts of the order of 4 mm over the edge length
    /// (mean |Δθ̄| between 0.01 and 1 rad), and `apply` only touches the simulation when the
    /// weight changes.
    #[test]
    fn xavier_schedule() {
        let x = xavier().expect("xavier");
        let g = xavier_guide(&x, 10.0).expect("guide");
        let mut sim = xavier_sim(&x, &g).expect("sim");
        let ev = RestEvents::xavier(&sim, &x.mesh, 0.004, 7);
        assert_eq!(ev.base.len(), ev.target.len());
        for (t, w) in [(0.0, 0.0), (6.99, 0.0), (7.1, 0.5), (7.2, 1.0), (8.0, 1.0), (8.5, 1.0), (8.7, 0.0), (10.0, 0.0)]
        {
            assert!((ev.weight(t) - w).abs() < 1e-12, "w({t}) = {} vs {w}", ev.weight(t));
        }
        let mean: f64 = ev.base.iter().zip(&ev.target).map(|(a, b)| (a - b).abs()).sum::<f64>() / ev.base.len() as f64;
        assert!((0.01..1.0).contains(&mean), "mean |Δθ̄| = {mean}");
        let same = |a: &[f64], b: &[f64]| a.len() == b.len() && a.iter().zip(b).all(|(x, y)| x == y);
        assert!(same(&ev.angles(0.0), &ev.base) && same(&ev.angles(1.0), &ev.target));
        let mut last = 0.0;
        assert!(!ev.apply(&mut sim, 3.0, &mut last).expect("apply"));
        assert!(ev.apply(&mut sim, 8.0, &mut last).expect("apply"));
        assert!(same(&sim.rest_angles(), &ev.target), "crinkled rest angles set");
        assert!(!ev.apply(&mut sim, 8.1, &mut last).expect("apply"));
        assert!(ev.apply(&mut sim, 9.0, &mut last).expect("apply"));
        assert!(same(&sim.rest_angles(), &ev.base), "rest angles restored");
    }
}

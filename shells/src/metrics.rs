//! Every figure a `shells` scene reports.
//!
//! [`Sanity`]: the physical-sanity figures of a cloth simulation, computed after every step (not
//! only on written frames): the invariants that expose a simulation that is not cloth — edges
//! stretched or crushed, vertices inside obstacles, energy from nowhere, NaN. Beside it, the
//! scene figures: the accuracy error of the benchmark ([`rms_distance_rel`]), the crease
//! measurements of plastic-crease ([`max_abs_change`], [`extreme_ratio`], [`max_abs`],
//! [`segment_angle`], [`relative_spread`]), the wind drag ([`wind_drag`]), the pile height
//! ([`height_span`]) and the passive-scene test of `energy_gain_rel` ([`is_passive`]).
//!
//! Every figure is NaN-safe: a NaN anywhere makes it NaN (written as `null`), never 0.
//!
//! ```
//! use shells::metrics::Sanity;
//! use geom_core::math::Pt3;
//! let rest = vec![Pt3::new(0.0, 0.0, 0.0), Pt3::new(1.0, 0.0, 0.0), Pt3::new(0.0, 1.0, 0.0)];
//! let mut s = Sanity::new(&rest, &[[0, 1], [0, 2], [1, 2]], Vec::new(), None);
//! let stretched = vec![Pt3::new(0.0, 0.0, 0.0), Pt3::new(1.1, 0.0, 0.0), Pt3::new(0.0, 1.0, 0.0)];
//! s.observe(&stretched, 0.1, Some(1.0));
//! assert!((s.max_edge_strain - 0.1).abs() < 1e-12);
//! ```

use geom_core::math::{Pt3, Vec3};
use geom_core::stats::nan_max;

use crate::collision::obstacles::{mesh_query, PlacedObstacle};
use crate::effects::Obstacle;
use crate::sim::{ShellSceneDesc, VertexConstraint};
use crate::wind::WindField;

/// Running sanity figures of one simulation.
#[derive(Clone, Debug)]
pub struct Sanity {
    edges: Vec<[u32; 2]>,
    rest_len: Vec<f64>,
    obstacles: Vec<(Obstacle, Option<geom_core::collide::MeshQuery>)>,
    /// m·g·D (J): the cloth's mass times |gravity| times the rest bounding-box diagonal, the
    /// scale of `energy_gain_rel`; `None` when the figure is not defined.
    energy_scale: Option<f64>,
    e_min: f64,
    /// max over edges and steps of ℓ/ℓ̄ − 1.
    pub max_edge_strain: f64,
    /// max over edges and steps of 1 − ℓ/ℓ̄.
    pub max_edge_compression: f64,
    /// Deepest any vertex got inside any obstacle (m; 0 when none).
    pub max_obstacle_penetration_m: f64,
    /// Largest energy rise over any interval, max over t₁ ≤ t₂ of (E(t₂) − E(t₁)), in J.
    pub energy_gain_j: f64,
    /// Steps observed.
    pub steps: u64,
}

impl Sanity {
    /// Monitors a mesh with rest positions `rest` and edges `edges` among `obstacles`;
    /// `energy_scale` = m·g·D for `energy_gain_rel` (passive scenes), `None` otherwise.
    pub fn new(rest: &[Pt3], edges: &[[u32; 2]], obstacles: Vec<Obstacle>, energy_scale: Option<f64>) -> Self {
        let rest_len = edges.iter().map(|e| (rest[e[0] as usize] - rest[e[1] as usize]).norm()).collect();
        let obstacles = obstacles.into_iter().map(|o| {
            let q = mesh_query(&o);
            (o, q)
        });
        Self {
            edges: edges.to_vec(),
            rest_len,
            obstacles: obstacles.collect(),
            energy_scale,
            e_min: f64::INFINITY,
            max_edge_strain: 0.0,
            max_edge_compression: 0.0,
            max_obstacle_penetration_m: 0.0,
            energy_gain_j: 0.0,
            steps: 0,
        }
    }

    /// m·g·D of a cloth: total mass (kg) × |g| (m/s²) × rest bounding-box diagonal (m).
    pub fn passive_energy_scale(rest: &[Pt3], mass: &[f64], g: f64) -> f64 {
        let d = geom_core::mesh::bbox_of(rest).map(|(a, b)| (b - a).norm()).unwrap_or(0.0);
        mass.iter().sum::<f64>() * g * d
    }

    /// Records the state after a step at time `t` with total energy `energy` (J; kinetic +
    /// membrane + bending + gravitational), when the energy figure is tracked.
    pub fn observe(&mut self, q: &[Pt3], t: f64, energy: Option<f64>) {
        self.steps += 1;
        for (e, l0) in self.edges.iter().zip(&self.rest_len) {
            let r = (q[e[0] as usize] - q[e[1] as usize]).norm() / l0;
            self.max_edge_strain = nan_max(self.max_edge_strain, r - 1.0);
            self.max_edge_compression = nan_max(self.max_edge_compression, 1.0 - r);
        }
        for (o, acc) in &self.obstacles {
            let po = PlacedObstacle::new(o, t, 1.0).with_accel(acc.as_ref());
            for p in q {
                let d = po.query(p).distance;
                let depth = if p.iter().any(|c| c.is_nan()) { f64::NAN } else { -d };
                self.max_obstacle_penetration_m = nan_max(self.max_obstacle_penetration_m, depth);
            }
        }
        if let Some(e) = energy {
            if e.is_nan() {
                self.energy_gain_j = f64::NAN;
            } else {
                self.e_min = self.e_min.min(e);
                self.energy_gain_j = nan_max(self.energy_gain_j, e - self.e_min);
            }
        }
    }

    /// (E(t₂) − E(t₁))_max / (m·g·D), or `None` where the figure is not defined.
    pub fn energy_gain_rel(&self) -> Option<f64> {
        self.energy_scale.map(|s| self.energy_gain_j / s)
    }
}

/// True for a passive scene, where `energy_gain_rel` is defined (issue 20): gravity, static pins
/// and static obstacles only — no wind, no user force, no kinematic vertices, no moving
/// obstacle.
pub fn is_passive(desc: &ShellSceneDesc) -> bool {
    desc.effects.gravity.is_some_and(|g| g.norm() > 0.0)
        && desc.effects.wind.is_none()
        && desc.effects.custom.is_empty()
        && desc.effects.obstacles.iter().all(|o| o.motion.is_none())
        && desc.constraints.iter().all(|c| matches!(c, VertexConstraint::Pinned(_)))
}

/// The accuracy error of the benchmark (shells.md §9): mass-weighted RMS distance between the
/// positions `a` and the reference `b` (m), over the bounding-box diagonal of `b`
/// (dimensionless; the diagonal is taken as 1 m for an empty mesh).
pub fn rms_distance_rel(a: &[Pt3], b: &[Pt3], mass: &[f64]) -> f64 {
    let mt: f64 = mass.iter().sum();
    let rms = (a.iter().zip(b).zip(mass).map(|((x, y), w)| w * (x - y).norm_squared()).sum::<f64>() / mt).sqrt();
    let diag = geom_core::mesh::bbox_of(b).map(|(lo, hi)| (hi - lo).norm()).unwrap_or(1.0);
    rms / diag
}

/// max_i |a_i − b_i| (0 for empty slices, NaN if any difference is NaN): plastic-crease's
/// per-hinge crease max|θ̄ − θ̄₀| (rad).
pub fn max_abs_change(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| (x - y).abs()).fold(0.0, nan_max)
}

/// max_i |a_i| (0 for an empty slice, NaN if any is NaN).
pub fn max_abs(a: &[f64]) -> f64 {
    a.iter().map(|x| x.abs()).fold(0.0, nan_max)
}

/// The ratio a_i/b_i farthest from 1 (1 for empty slices, NaN if any ratio is NaN): the
/// hardening of plastic-crease's hinge stiffnesses k/k₀.
pub fn extreme_ratio(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x / y).fold(1.0, |m: f64, r| {
        if m.is_nan() || r.is_nan() {
            f64::NAN
        } else if (r - 1.0).abs() > (m - 1.0).abs() {
            r
        } else {
            m
        }
    })
}

/// The angle between two segment directions (rad, in [0, π]), atan2(|d₀ × d₁|, d₀·d₁).
pub fn segment_angle(d0: &Vec3, d1: &Vec3) -> f64 {
    d0.cross(d1).norm().atan2(d0.dot(d1))
}

/// (max − min)/mean of a sample (NaN if any is NaN or the sample is empty; the mean is floored
/// at 1e-300): the step-size spread of plastic-crease.
pub fn relative_spread(v: &[f64]) -> f64 {
    use geom_core::stats::{max, mean, min};
    (max(v) - min(v)) / mean(v).max(1e-300)
}

/// Highest minus lowest y (m) of the positions (NaN for none or a NaN coordinate).
pub fn height_span(q: &[Pt3]) -> f64 {
    let y: Vec<f64> = q.iter().map(|p| p.y).collect();
    geom_core::stats::max(&y) - geom_core::stats::min(&y)
}

/// The wind force on the cloth (N) along the unit direction `dir`: Σ over triangles of the
/// drag [`WindField::triangle`] gives per vertex (three vertices share it equally), at time `t`.
pub fn wind_drag(wind: &WindField, faces: &[[u32; 3]], q: &[Pt3], v: &[Vec3], t: f64, dir: &Vec3) -> f64 {
    let mut f = Vec3::zeros();
    for tri in faces {
        let x = tri.map(|i| q[i as usize]);
        let vv = tri.map(|i| v[i as usize]);
        f += 3.0 * wind.triangle(&x, &vv, t).0;
    }
    f.dot(dir)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::effects::ObstacleShape;
    use geom_core::math::Vec3;

    fn tri() -> (Vec<Pt3>, Vec<[u32; 2]>) {
        (vec![Pt3::new(0.0, 0.0, 0.0), Pt3::new(1.0, 0.0, 0.0), Pt3::new(0.0, 1.0, 0.0)], vec![[0, 1], [0, 2], [1, 2]])
    }

    #[test]
    fn a_stretched_and_a_crushed_edge_are_seen() {
        let (rest, e) = tri();
        let mut s = Sanity::new(&rest, &e, Vec::new(), None);
        s.observe(&rest, 0.0, None);
        assert_eq!((s.max_edge_strain, s.max_edge_compression), (0.0, 0.0));
        let mut q = rest.clone();
        q[1].x = 1.5;
        s.observe(&q, 0.1, None);
        q[1].x = 0.2;
        s.observe(&q, 0.2, None);
        assert!((s.max_edge_strain - 0.5).abs() < 1e-12);
        assert!((s.max_edge_compression - 0.8).abs() < 1e-12);
        q[2].y = f64::NAN;
        s.observe(&q, 0.3, None);
        assert!(s.max_edge_strain.is_nan() && s.max_edge_compression.is_nan(), "NaN is not 0");
    }

    #[test]
    fn a_vertex_inside_an_obstacle_is_seen() {
        let (rest, e) = tri();
        let floor =
            Obstacle { shape: ObstacleShape::Plane { normal: Vec3::y(), offset: 0.0 }, friction: 0.5, motion: None };
        let ball = Obstacle {
            shape: ObstacleShape::Sphere { center: Pt3::new(0.0, 2.0, 0.0), radius: 0.5 },
            friction: 0.5,
            motion: None,
        };
        let mut s = Sanity::new(&rest, &e, vec![floor, ball], None);
        let mut q = rest.clone();
        q[0].y = 0.25; // above the floor, outside the ball
        s.observe(&q, 0.0, None);
        assert_eq!(s.max_obstacle_penetration_m, 0.0);
        q[1].y = -0.003; // 3 mm below the floor
        q[2].y = 1.6; // 0.1 m inside the ball
        s.observe(&q, 0.0, None);
        assert!((s.max_obstacle_penetration_m - 0.1).abs() < 1e-12, "{}", s.max_obstacle_penetration_m);
    }

    #[test]
    fn an_energy_gain_over_an_interval_is_seen() {
        let (rest, e) = tri();
        let mut s = Sanity::new(&rest, &e, Vec::new(), Some(10.0));
        for (k, en) in [5.0, 3.0, 4.0, 2.0, 2.5].iter().enumerate() {
            s.observe(&rest, k as f64, Some(*en));
        }
        // Largest rise: 3 → 4 (1 J); 2 → 2.5 is smaller; falls do not count.
        assert!((s.energy_gain_rel().unwrap() - 0.1).abs() < 1e-12);
        s.observe(&rest, 9.0, Some(f64::NAN));
        assert!(s.energy_gain_rel().unwrap().is_nan());
        assert!(Sanity::new(&rest, &e, Vec::new(), None).energy_gain_rel().is_none());
    }

    #[test]
    fn scene_figures_propagate_nan() {
        assert_eq!(max_abs_change(&[1.0, 2.0], &[1.5, 0.5]), 1.5);
        assert!(max_abs_change(&[1.0, f64::NAN], &[0.0, 0.0]).is_nan());
        assert!(max_abs(&[f64::NAN, 1.0]).is_nan());
        assert_eq!(extreme_ratio(&[1.1, 0.5, 3.0], &[1.0, 1.0, 1.0]), 3.0);
        assert_eq!(extreme_ratio(&[0.5], &[1.0]), 0.5);
        assert!(extreme_ratio(&[f64::NAN, 3.0], &[1.0, 1.0]).is_nan());
        assert!(extreme_ratio(&[3.0, f64::NAN], &[1.0, 1.0]).is_nan());
        assert!((relative_spread(&[1.0, 2.0, 3.0]) - 1.0).abs() < 1e-15);
        assert!(relative_spread(&[1.0, f64::NAN]).is_nan());
        assert!(height_span(&[Pt3::origin(), Pt3::new(0.0, f64::NAN, 0.0)]).is_nan());
        assert_eq!(height_span(&[Pt3::origin(), Pt3::new(5.0, -2.0, 0.0)]), 2.0);
        let a = segment_angle(&Vec3::x(), &Vec3::new(-1.0, 1.0, 0.0));
        assert!((a - 0.75 * std::f64::consts::PI).abs() < 1e-15);
    }

    #[test]
    fn rms_distance_is_mass_weighted_and_relative() {
        let b = vec![Pt3::origin(), Pt3::new(3.0, 4.0, 0.0)];
        let a = vec![Pt3::new(1.0, 0.0, 0.0), Pt3::new(3.0, 4.0, 0.0)];
        // √(3·1/4) / 5
        assert!((rms_distance_rel(&a, &b, &[3.0, 1.0]) - 0.75f64.sqrt() / 5.0).abs() < 1e-15);
    }
}

//! FLIP particles of varying radius, stored as a structure of arrays (spec §2, §3.8–3.10).

use geom_core::math::{Pt3, Vec3};

/// Per-particle flag bits (spec §2).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ParticleFlags(pub u8);

impl ParticleFlags {
    /// Particle is in free flight (spec §3.8): not transferred to the mesh, falls under gravity.
    pub const BALLISTIC: u8 = 1;
    /// Particle lies within the near-surface band (spec §3.9, §3.11).
    pub const NEAR_SURFACE: u8 = 2;
    /// Particle was created by a split at the last remesh (spec §3.10).
    pub const NEW_THIS_REMESH: u8 = 4;

    /// Whether bit `b` is set.
    pub fn has(self, b: u8) -> bool {
        self.0 & b != 0
    }
}

/// Particles as a structure of arrays. Radius `r` (m) gives the particle volume `(2r)³`.
#[derive(Clone, Debug, Default)]
pub struct Particles {
    /// Positions (m).
    pub x: Vec<Pt3>,
    /// Velocities (m/s).
    pub v: Vec<Vec3>,
    /// Radii (m).
    pub r: Vec<f64>,
    /// Level-set value stored from the previous step (m, negative inside the liquid).
    pub phi: Vec<f64>,
    /// Flag bits, see [`ParticleFlags`].
    pub flags: Vec<ParticleFlags>,
    /// Containing tet (hint for walking), `NONE` when unknown.
    pub tet: Vec<u32>,
}

impl Particles {
    /// Number of particles.
    pub fn len(&self) -> usize {
        self.x.len()
    }

    /// Whether there are no particles.
    pub fn is_empty(&self) -> bool {
        self.x.is_empty()
    }

    /// Volume represented by particle `i`: `(2 r_i)³` (m³).
    pub fn volume(&self, i: usize) -> f64 {
        8.0 * self.r[i].powi(3)
    }
}

use crate::surface::SphereTree;
use rayon::prelude::*;

impl Particles {
    /// Appends one particle.
    pub fn push(&mut self, x: Pt3, v: Vec3, r: f64, phi: f64) {
        self.x.push(x);
        self.v.push(v);
        self.r.push(r);
        self.phi.push(phi);
        self.flags.push(ParticleFlags::default());
        self.tet.push(geom_core::NONE);
    }

    /// Keeps the particles with `keep[i]` (order preserved).
    pub fn retain(&mut self, keep: &[bool]) {
        let mut j = 0;
        for (i, &k) in keep.iter().enumerate().take(self.len()) {
            if k {
                self.x[j] = self.x[i];
                self.v[j] = self.v[i];
                self.r[j] = self.r[i];
                self.phi[j] = self.phi[i];
                self.flags[j] = self.flags[i];
                self.tet[j] = self.tet[i];
                j += 1;
            }
        }
        self.x.truncate(j);
        self.v.truncate(j);
        self.r.truncate(j);
        self.phi.truncate(j);
        self.flags.truncate(j);
        self.tet.truncate(j);
    }

    /// Whether particle `i` is ballistic.
    pub fn is_ballistic(&self, i: usize) -> bool {
        self.flags[i].has(ParticleFlags::BALLISTIC)
    }

    /// Total particle volume `Σ (2r)³` (m³).
    pub fn total_volume(&self) -> f64 {
        (0..self.len()).map(|i| self.volume(i)).sum()
    }

    /// Largest radius (0 when empty).
    pub fn r_max(&self) -> f64 {
        self.r.iter().copied().fold(0.0, f64::max)
    }
}

/// Ballistic classification (spec §3.8): a particle with no other particle centre within
/// `factor · r_p` (closed ball) is ballistic. Returns the number of ballistic particles.
///
/// `tree` is a [`SphereTree`] over `parts.x` (radii unused). One other centre in the ball is
/// enough, so the search stops at the first (nearest boxes first) instead of listing the whole
/// ball; the distance test is the k-d tree's own `|x_i − x_j|² ≤ (factor r_i)²` expression, so
/// the classification equals the radius-query definition exactly.
pub fn classify_ballistic(parts: &mut Particles, tree: &SphereTree, factor: f64, enabled: bool) -> usize {
    let flags: Vec<bool> = (0..parts.len())
        .into_par_iter()
        .map(|i| {
            if !enabled {
                return false;
            }
            let xi = parts.x[i];
            let reach = factor * parts.r[i];
            if reach.is_nan() || reach < 0.0 {
                // The radius query of an invalid radius is empty: no neighbour.
                return true;
            }
            !tree.any_other_within2(&xi, reach * reach, i as u32)
        })
        .collect();
    let mut n = 0;
    for (i, b) in flags.into_iter().enumerate() {
        let f = &mut parts.flags[i].0;
        if b {
            *f |= ParticleFlags::BALLISTIC;
            n += 1;
        } else {
            *f &= !ParticleFlags::BALLISTIC;
        }
    }
    n
}

/// Box walls: clamps centres into `[min + r, max − r]` per axis and zeros the outward normal
/// velocity (spec §3.8). Returns particles that left through an `open` face (`open[2a + side]`).
pub fn apply_walls(parts: &mut Particles, min: &Pt3, max: &Pt3, open: &[bool; 6]) -> Vec<bool> {
    let mut keep = vec![true; parts.len()];
    for (i, kp) in keep.iter_mut().enumerate() {
        let r = parts.r[i];
        for a in 0..3 {
            let lo = min[a] + r;
            let hi = max[a] - r;
            if parts.x[i][a] < min[a] && open[2 * a] || parts.x[i][a] > max[a] && open[2 * a + 1] {
                *kp = false;
            }
            if parts.x[i][a] < lo && !open[2 * a] {
                parts.x[i][a] = lo.min(0.5 * (min[a] + max[a]));
                parts.v[i][a] = parts.v[i][a].max(0.0);
            } else if parts.x[i][a] > hi && !open[2 * a + 1] {
                parts.x[i][a] = hi.max(0.5 * (min[a] + max[a]));
                parts.v[i][a] = parts.v[i][a].min(0.0);
            }
        }
    }
    keep
}

/// Pushes particles out of obstacles (spec §3.8): if `φ_s(x) < r`, move along the SDF gradient
/// by `r − φ_s` and remove the velocity component into the solid.
///
/// With `solid_velocity` (moving obstacles, issue 26) the particle keeps its velocity relative
/// to the obstacle's there: only an approaching relative normal velocity `(v − v_s)·n < 0` is
/// removed, so a particle the obstacle pushes moves with it.
pub fn apply_obstacles(
    parts: &mut Particles,
    sdf: &(dyn Fn(&Pt3) -> f64 + Sync),
    solid_velocity: Option<&(dyn Fn(&Pt3) -> Vec3 + Sync)>,
) {
    parts.x.par_iter_mut().zip(parts.v.par_iter_mut()).zip(parts.r.par_iter()).for_each(|((x, v), &r)| {
        let d = sdf(x);
        if d < r {
            let e = 1e-6 * r.max(1e-9);
            let n = Vec3::new(
                sdf(&(*x + Vec3::x() * e)) - sdf(&(*x - Vec3::x() * e)),
                sdf(&(*x + Vec3::y() * e)) - sdf(&(*x - Vec3::y() * e)),
                sdf(&(*x + Vec3::z() * e)) - sdf(&(*x - Vec3::z() * e)),
            );
            let nn = n.norm();
            if nn > 0.0 {
                let n = n / nn;
                let vs = solid_velocity.map_or_else(Vec3::zeros, |f| f(x));
                *x += n * (r - d);
                let vn = (*v - vs).dot(&n);
                if vn < 0.0 {
                    *v -= n * vn;
                }
            }
        }
    });
}

/// Position correction (spec §3.9), Jacobi style: overlap relief
/// `Δx_i = −γ Σ_j vol_j/(vol_i+vol_j) (R_ij − d_ij)(x_j − x_i)/d_ij` with mirrored copies at the
/// closed box walls, tangential only near the surface (`normal[i]` given, `None` deep inside),
/// clamped to `0.5 r_i`; a mirrored copy at distance `2 d_w` pushes by `γ (r_i − d_w)`. Velocities are unchanged. Coincident centres use a hashed direction.
/// `tree` is the [`SphereTree`] of the particle centres with their radii `parts.r`.
#[allow(clippy::too_many_arguments)] // the wall box and mask, normals and seed are all per-call inputs
pub fn position_correction(
    parts: &mut Particles,
    tree: &SphereTree,
    min: &Pt3,
    max: &Pt3,
    closed: &[bool; 6],
    normal: &[Option<Vec3>],
    gamma: f64,
    seed: u64,
) {
    let dx: Vec<Vec3> = (0..parts.len())
        .into_par_iter()
        .map_init(Vec::new, |buf, i| {
            if parts.is_ballistic(i) {
                return Vec3::zeros();
            }
            let (xi, ri) = (parts.x[i], parts.r[i]);
            let vi = parts.volume(i);
            // Every particle that can overlap `i` (`|x_j − x_i| < r_i + r_j`), indices ascending (the
            // summation order below): the same pairs, in the same order, as the radius query
            // `r_i + r_max` used before, without listing the far small particles.
            tree.touching(&xi, ri, buf);
            let mut d = Vec3::zeros();
            for &j in buf.iter() {
                let j = j as usize;
                if j == i || parts.is_ballistic(j) {
                    continue;
                }
                let rr = ri + parts.r[j];
                let e = parts.x[j] - xi;
                let dist = e.norm();
                if dist >= rr {
                    continue;
                }
                let dir = if dist > 1e-12 * ri {
                    e / dist
                } else {
                    let mut h = seed ^ ((i as u64) << 32) ^ j as u64;
                    let mut rng = geom_core::rng::Rng::new(geom_core::rng::splitmix64(&mut h));
                    let u = rng.unit_vec3();
                    if i < j {
                        u
                    } else {
                        -u
                    }
                };
                let vj = parts.volume(j);
                d -= dir * (gamma * vj / (vi + vj) * (rr - dist));
            }
            for a in 0..3 {
                let dl = xi[a] - min[a];
                if closed[2 * a] && dl < ri {
                    d[a] += gamma * (ri - dl);
                }
                let dh = max[a] - xi[a];
                if closed[2 * a + 1] && dh < ri {
                    d[a] -= gamma * (ri - dh);
                }
            }
            if let Some(n) = normal[i] {
                d -= n * d.dot(&n);
            }
            let l = d.norm();
            if l > 0.5 * ri {
                d *= 0.5 * ri / l;
            }
            d
        })
        .collect();
    for (x, d) in parts.x.iter_mut().zip(dx) {
        *x += d;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use geom_core::rng::Rng;
    use geom_core::spatial::KdTree;

    #[test]
    fn ballistic_classification_equals_the_radius_query_definition() {
        // Clusters, isolated particles, exact duplicates and particles exactly at the reach:
        // the first-hit box-tree test must agree with "no other centre in the closed ball" everywhere.
        let mut rng = Rng::new(4);
        let mut p = Particles::default();
        for _ in 0..400 {
            let x = Pt3::new(rng.range(0.0, 1.0), rng.range(0.0, 1.0), rng.range(0.0, 1.0));
            p.push(x, Vec3::zeros(), rng.range(0.002, 0.03), 0.0);
        }
        let x0 = p.x[0];
        p.push(x0, Vec3::zeros(), 0.01, 0.0); // duplicate of particle 0
        p.push(x0, Vec3::zeros(), 0.01, 0.0); // and another
        p.push(Pt3::new(2.0, 2.0, 2.0), Vec3::zeros(), 0.05, 0.0);
        p.push(Pt3::new(2.25, 2.0, 2.0), Vec3::zeros(), 0.05, 0.0); // exactly 5 r away
        let tree = KdTree::build(&p.x);
        let st = SphereTree::build(&p.x, &vec![0.0; p.len()]);
        for factor in [1.0, 3.0, 5.0, 6.0] {
            let n = classify_ballistic(&mut p, &st, factor, true);
            let mut buf = Vec::new();
            let mut expect = 0;
            for i in 0..p.len() {
                tree.within(&p.x[i], factor * p.r[i], &mut buf);
                let b = !buf.iter().any(|&j| j as usize != i);
                assert_eq!(p.is_ballistic(i), b, "particle {i}, factor {factor}");
                expect += usize::from(b);
            }
            assert_eq!(n, expect);
            assert!(n > 0 && n < p.len(), "factor {factor}: degenerate sample ({n} ballistic)");
        }
        assert_eq!(classify_ballistic(&mut p, &st, 6.0, false), 0);
    }
}

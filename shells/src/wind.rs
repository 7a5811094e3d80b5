//! Aerodynamic forces of a gusty wind on the triangles (shells.md §3.5, reconstructed).
//!
//! Per triangle with current area A, unit normal n̂, mean vertex velocity v_T and wind w at the
//! centroid: v_rel = w − v_T, s = v_rel·n̂, v_t = v_rel − s n̂,
//! f_T = ½ρC_n A s|s| n̂ + ½ρC_t A|v_t| v_t, split equally over the three vertices.
//! Velocity Jacobian (normal part only, negative semidefinite): ∂f_{T→j}/∂v_i = −(1/9)ρC_nA|s|n̂n̂ᵀ.
//! Wind field w(x,t) = gain(t)·base·(1 + a ξ(x,t)), ξ = (1/3)Σ_{m=1..3} sin(k_m·x − ωt + φ_m),
//! |k_m| = 2π/λ, directions and phases from the seed.

use crate::effects::Wind;
use geom_core::math::{Mat3, Pt3, Vec3};
use geom_core::rng::Rng;

/// A wind with its gust modes drawn once from the seed.
#[derive(Clone, Debug)]
pub struct WindField {
    /// The parameters.
    pub wind: Wind,
    k: [Vec3; 3],
    phase: [f64; 3],
}

impl WindField {
    /// Draws the gust directions and phases from `wind.seed`.
    pub fn new(wind: &Wind) -> Self {
        let mut rng = Rng::new(wind.seed);
        let kmag = 2.0 * std::f64::consts::PI / wind.turb_wavelength;
        let k = std::array::from_fn(|_| rng.unit_vec3() * kmag);
        let phase = std::array::from_fn(|_| rng.range(0.0, 2.0 * std::f64::consts::PI));
        Self { wind: wind.clone(), k, phase }
    }

    /// Schedule gain at time t (linear between keys, held outside; 1 without a schedule).
    pub fn gain(&self, t: f64) -> f64 {
        let s = &self.wind.schedule;
        match s.len() {
            0 => 1.0,
            _ if t <= s[0].0 => s[0].1,
            _ if t >= s[s.len() - 1].0 => s[s.len() - 1].1,
            _ => {
                let i = s.partition_point(|k| k.0 <= t);
                let (a, b) = (s[i - 1], s[i]);
                let u = if b.0 > a.0 { (t - a.0) / (b.0 - a.0) } else { 1.0 };
                a.1 + u * (b.1 - a.1)
            }
        }
    }

    /// Wind velocity at x and t (m/s).
    pub fn velocity(&self, x: &Pt3, t: f64) -> Vec3 {
        let w = &self.wind;
        let mut xi = 0.0;
        if w.turbulence != 0.0 {
            for m in 0..3 {
                xi += (self.k[m].dot(&x.coords) - w.turb_freq * t + self.phase[m]).sin();
            }
            xi /= 3.0;
        }
        self.gain(t) * w.base * (1.0 + w.turbulence * xi)
    }

    /// Force on each vertex of triangle `x` with vertex velocities `v` at time t (N, the same
    /// for the three vertices) and the velocity-Jacobian block shared by all (i, j) pairs.
    pub fn triangle(&self, x: &[Pt3; 3], v: &[Vec3; 3], t: f64) -> (Vec3, Mat3) {
        let n2 = (x[1] - x[0]).cross(&(x[2] - x[0]));
        let nn = n2.norm();
        if nn == 0.0 {
            return (Vec3::zeros(), Mat3::zeros());
        }
        let area = 0.5 * nn;
        let n = n2 / nn;
        let c = Pt3::from((x[0].coords + x[1].coords + x[2].coords) / 3.0);
        let vt = (v[0] + v[1] + v[2]) / 3.0;
        let rel = self.velocity(&c, t) - vt;
        let s = rel.dot(&n);
        let tang = rel - s * n;
        let w = &self.wind;
        let q = 0.5 * w.air_density * area;
        let f = q * w.drag_normal * s * s.abs() * n + q * w.drag_tangent * tang.norm() * tang;
        let jv = -(1.0 / 9.0) * w.air_density * w.drag_normal * area * s.abs() * n * n.transpose();
        (f / 3.0, jv)
    }
}

impl WindField {
    /// The wind force on every vertex (N) of the triangles `tris` at positions `q` and vertex
    /// velocities `v` at time t: each triangle's [`WindField::triangle`] force on its three
    /// vertices, summed in triangle order (deterministic). The same forces the assembly adds to
    /// the implicit system's right-hand side.
    pub fn vertex_forces(&self, tris: &[[u32; 3]], q: &[Pt3], v: &[Vec3], t: f64) -> Vec<Vec3> {
        let mut f = vec![Vec3::zeros(); q.len()];
        for tri in tris {
            let x = tri.map(|i| q[i as usize]);
            let vl = tri.map(|i| v[i as usize]);
            let (fw, _) = self.triangle(&x, &vl, t);
            for &i in tri {
                f[i as usize] += fw;
            }
        }
        f
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// §7 test 20: a triangle normal to a steady wind of speed U feels ½ρC_nAU² along n̂; in-plane
    /// wind gives no normal force.
    #[test]
    fn wind_analytic() {
        let u = 8.0;
        let x = [Pt3::new(0.0, 0.0, 0.0), Pt3::new(1.0, 0.0, 0.0), Pt3::new(0.0, 2.0, 0.0)];
        let v = [Vec3::zeros(); 3];
        let wf = WindField::new(&Wind::steady(Vec3::new(0.0, 0.0, u)));
        let (f, jv) = wf.triangle(&x, &v, 0.3);
        let want = 0.5 * 1.2 * 1.0 * 1.0 * u * u;
        assert!((3.0 * f.z - want).abs() <= 1e-12 * want);
        assert!(f.x == 0.0 && f.y == 0.0);
        assert!(jv[(2, 2)] < 0.0);
        let wf2 = WindField::new(&Wind::steady(Vec3::new(u, 0.0, 0.0)));
        let (f2, _) = wf2.triangle(&x, &v, 0.0);
        assert_eq!(f2.z, 0.0);
        assert!(f2.x > 0.0); // tangential drag along the wind
    }

    #[test]
    fn schedule_interpolates() {
        let mut w = Wind::steady(Vec3::x());
        w.schedule = vec![(1.0, 0.0), (2.0, 1.0)];
        let f = WindField::new(&w);
        assert_eq!(f.gain(0.0), 0.0);
        assert_eq!(f.gain(1.5), 0.5);
        assert_eq!(f.gain(3.0), 1.0);
    }
}

//! External loads of the static tests (cantilever): a conservative end moment applied as a
//! follower moment on segments, and a dead point load. Both are [`ExternalForce`]s for
//! `Effects::custom`.
//!
//! ```
//! use shells::loads::EndMoment;
//! use shells::ExternalForce;
//! use geom_core::math::{Pt3, Vec3};
//! let m = EndMoment::new(vec![(1, 0, 1.0)]);
//! m.set_moment(2.0);
//! let q = [Pt3::origin(), Pt3::new(1.0, 0.0, 0.0)];
//! let mut f = vec![Vec3::zeros(); 2];
//! m.add_forces(0.0, &q, &[Vec3::zeros(); 2], &mut f);
//! // M w ∇φ: a force couple of magnitude M/|d| perpendicular to the segment, in the x–z plane.
//! assert_eq!(f[1], Vec3::new(0.0, 0.0, 2.0));
//! assert_eq!(f[0], -f[1]);
//! ```

use std::sync::Mutex;

use geom_core::math::{Mat3, Pt3, Vec3};

use crate::effects::{BlockTriplets, ExternalForce};

/// A conservative end moment M (N·m) on segments (tip, prev, weight w): potential
/// V = −M Σ w φ, φ the angle of the segment tip − prev in the x–z plane (work-conjugate to the
/// end rotation about y; a follower moment). The moment can be ramped between steps.
pub struct EndMoment {
    pairs: Vec<(u32, u32, f64)>,
    moment: Mutex<f64>,
}

impl EndMoment {
    /// Segments (tip vertex, previous vertex, weight); the moment starts at 0.
    pub fn new(pairs: Vec<(u32, u32, f64)>) -> Self {
        Self { pairs, moment: Mutex::new(0.0) }
    }

    /// Sets the moment M (N·m).
    pub fn set_moment(&self, m: f64) {
        *self.moment.lock().unwrap_or_else(|p| p.into_inner()) = m;
    }

    fn moment(&self) -> f64 {
        *self.moment.lock().unwrap_or_else(|p| p.into_inner())
    }
}

impl ExternalForce for EndMoment {
    /// f = M w ∇φ on tip and −M w ∇φ on prev, ∇φ = (−d_z, 0, d_x)/r² (d = tip − prev).
    fn add_forces(&self, _t: f64, q: &[Pt3], _v: &[Vec3], f: &mut [Vec3]) {
        let m = self.moment();
        for &(tip, prev, w) in &self.pairs {
            let d = q[tip as usize] - q[prev as usize];
            let l2 = d.x * d.x + d.z * d.z;
            let g = Vec3::new(-d.z, 0.0, d.x) / l2;
            f[tip as usize] += m * w * g;
            f[prev as usize] -= m * w * g;
        }
    }

    /// J_x = M w ∇²φ (symmetric): with d = tip − prev in the x–z plane and r² = |d|²,
    /// ∂²φ/∂d² = [[2d_xd_z, d_z² − d_x²], [d_z² − d_x², −2d_xd_z]]/r⁴.
    fn add_jacobians(&self, _t: f64, q: &[Pt3], _v: &[Vec3], jx: &mut BlockTriplets, _jv: &mut BlockTriplets) {
        let m = self.moment();
        for &(tip, prev, w) in &self.pairs {
            let d = q[tip as usize] - q[prev as usize];
            let r2 = d.x * d.x + d.z * d.z;
            let (a, b) = (2.0 * d.x * d.z / (r2 * r2), (d.z * d.z - d.x * d.x) / (r2 * r2));
            let mut hd = Mat3::zeros();
            hd[(0, 0)] = a;
            hd[(0, 2)] = b;
            hd[(2, 0)] = b;
            hd[(2, 2)] = -a;
            let k = m * w * hd;
            jx.push(tip, tip, k);
            jx.push(prev, prev, k);
            jx.push(tip, prev, -k);
            jx.push(prev, tip, -k);
        }
    }
}

/// Dead point loads (vertex, force in N).
pub struct TipLoad(pub Vec<(u32, Vec3)>);

impl ExternalForce for TipLoad {
    fn add_forces(&self, _t: f64, _q: &[Pt3], _v: &[Vec3], f: &mut [Vec3]) {
        for &(i, p) in &self.0 {
            f[i as usize] += p;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The end-moment force is −∇V and its Jacobian the derivative of the force (central
    /// differences on a tilted segment).
    #[test]
    fn end_moment_force_and_jacobian_fd() {
        let em = EndMoment::new(vec![(1, 0, 0.7)]);
        em.set_moment(1.3);
        let q = [Pt3::new(0.1, 0.2, -0.05), Pt3::new(0.45, 0.1, 0.3)];
        let v = [Vec3::zeros(); 2];
        let phi = |q: &[Pt3]| {
            let d = q[1] - q[0];
            d.z.atan2(d.x)
        };
        let mut f = vec![Vec3::zeros(); 2];
        em.add_forces(0.0, &q, &v, &mut f);
        let eps = 1e-6;
        let mut jx = BlockTriplets::default();
        let mut jv = BlockTriplets::default();
        em.add_jacobians(0.0, &q, &v, &mut jx, &mut jv);
        for a in 0..2 {
            for c in 0..3 {
                let (mut qp, mut qm) = (q, q);
                qp[a][c] += eps;
                qm[a][c] -= eps;
                // f = −∂V/∂q = M w ∂φ/∂q
                let fd = 1.3 * 0.7 * (phi(&qp) - phi(&qm)) / (2.0 * eps);
                assert!((f[a][c] - fd).abs() < 1e-6, "force {a} {c}: {} vs {fd}", f[a][c]);
                let (mut fp, mut fm) = (vec![Vec3::zeros(); 2], vec![Vec3::zeros(); 2]);
                em.add_forces(0.0, &qp, &v, &mut fp);
                em.add_forces(0.0, &qm, &v, &mut fm);
                for b in 0..2 {
                    let col = (fp[b] - fm[b]) / (2.0 * eps);
                    let blk: Mat3 = jx.blocks.iter().filter(|t| t.0 == b as u32 && t.1 == a as u32).map(|t| t.2).sum();
                    for r in 0..3 {
                        assert!((blk[(r, c)] - col[r]).abs() < 1e-5, "J[{b}{a}]({r},{c})");
                    }
                }
            }
        }
    }
}

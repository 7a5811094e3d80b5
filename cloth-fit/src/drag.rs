//! The paper's nonlinear air drag as a `shells` force hook (Bhat et al. 2003 §3, the drag
//! equation after eq. 1; spec §3.2).
//!
//! For a triangle of area a with unit normal n and mean vertex velocity relative to the air
//! v̄ = (v_a + v_b + v_c)/3 − w, write s = v̄·n, v_N = s n and v_T = v̄ − v_N. Then
//!
//! f = −a [ φ(s) n + k_T v_T ],  φ(s) = k_N s|s| / (1 + k_f s²),
//!
//! quadratic in the normal speed at low speed and saturating at a·k_N/k_f (the paper's nod to
//! drag crisis), linear (Stokes) in the tangential velocity. Each vertex receives f/3.
//!
//! Jacobian with respect to the vertex velocities (normal and area held fixed):
//! ∂f/∂v̄ = −a [φ′(s) n nᵀ + k_T (I − n nᵀ)], φ′(s) = 2k_N|s|/(1 + k_f s²)², and
//! ∂f_i/∂v_j = ∂f/∂v̄ / 9. It is symmetric negative semi-definite, so implicit drag only
//! dissipates.

use std::sync::Arc;

use geom_core::math::{Mat3, Pt3, Vec3};
use shells::{BlockTriplets, ExternalForce};

use crate::params::DragParams;

/// Nonlinear drag on a triangle mesh (spec §2 `DragForce`).
#[derive(Clone, Debug)]
pub struct DragForce {
    /// Coefficients k_N, k_T, k_f.
    pub params: DragParams,
    /// Air velocity (m/s); zero by default.
    pub wind: Vec3,
    /// The triangles the force acts on.
    pub faces: Arc<Vec<[u32; 3]>>,
    /// Add the velocity Jacobian to the implicit system (off = explicit drag, the default).
    pub implicit: bool,
}

/// Force on one triangle and the data its Jacobian needs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TriangleDrag {
    /// Total drag force on the triangle (N).
    pub force: Vec3,
    /// Deformed area a (m²).
    pub area: f64,
    /// Unit normal n (zero for a collapsed triangle).
    pub normal: Vec3,
    /// Normal speed s = v̄·n (m/s).
    pub s: f64,
}

impl DragForce {
    /// Drag with the given coefficients on `faces`, explicit, no wind.
    pub fn new(params: DragParams, faces: Arc<Vec<[u32; 3]>>) -> Self {
        Self { params, wind: Vec3::zeros(), faces, implicit: false }
    }

    /// φ(s) = k_N s|s|/(1 + k_f s²) (N/m² per kg/m³ … i.e. the normal pressure per unit k).
    pub fn phi(&self, s: f64) -> f64 {
        let DragParams { k_n, k_f, .. } = self.params;
        k_n * s * s.abs() / (1.0 + k_f * s * s)
    }

    /// φ′(s) = 2k_N|s|/(1 + k_f s²)².
    pub fn dphi(&self, s: f64) -> f64 {
        let DragParams { k_n, k_f, .. } = self.params;
        let d = 1.0 + k_f * s * s;
        2.0 * k_n * s.abs() / (d * d)
    }

    /// The drag on one triangle with corner positions `x` and velocities `v`.
    pub fn triangle(&self, x: [Pt3; 3], v: [Vec3; 3]) -> TriangleDrag {
        let cr = (x[1] - x[0]).cross(&(x[2] - x[0]));
        let len = cr.norm();
        if !(len > 0.0) || !len.is_finite() {
            return TriangleDrag { force: Vec3::zeros(), area: 0.0, normal: Vec3::zeros(), s: 0.0 };
        }
        let n = cr / len;
        let area = 0.5 * len;
        let vbar = (v[0] + v[1] + v[2]) / 3.0 - self.wind;
        let s = vbar.dot(&n);
        let vt = vbar - s * n;
        let force = -area * (self.phi(s) * n + self.params.k_t * vt);
        TriangleDrag { force, area, normal: n, s }
    }

    /// ∂f/∂v̄ of one triangle (3×3, symmetric negative semi-definite).
    pub fn triangle_jacobian(&self, t: &TriangleDrag) -> Mat3 {
        let nn = t.normal * t.normal.transpose();
        -t.area * (self.dphi(t.s) * nn + self.params.k_t * (Mat3::identity() - nn))
    }

    fn corners(&self, f: &[u32; 3], q: &[Pt3], v: &[Vec3]) -> Option<([Pt3; 3], [Vec3; 3])> {
        if f.iter().any(|&i| i as usize >= q.len() || i as usize >= v.len()) {
            return None;
        }
        Some((f.map(|i| q[i as usize]), f.map(|i| v[i as usize])))
    }
}

impl ExternalForce for DragForce {
    fn add_forces(&self, _t: f64, q: &[Pt3], v: &[Vec3], f: &mut [Vec3]) {
        for face in self.faces.iter() {
            let Some((x, vv)) = self.corners(face, q, v) else { continue };
            let d = self.triangle(x, vv);
            let share = d.force / 3.0;
            for &i in face {
                f[i as usize] += share;
            }
        }
    }

    fn add_jacobians(&self, _t: f64, q: &[Pt3], v: &[Vec3], _jx: &mut BlockTriplets, jv: &mut BlockTriplets) {
        if !self.implicit {
            return;
        }
        for face in self.faces.iter() {
            let Some((x, vv)) = self.corners(face, q, v) else { continue };
            let d = self.triangle(x, vv);
            if d.area == 0.0 {
                continue;
            }
            let block = self.triangle_jacobian(&d) / 9.0;
            for &i in face {
                for &j in face {
                    jv.push(i, j, block);
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use geom_core::rng::Rng;

    fn drag(k_n: f64, k_t: f64, k_f: f64) -> DragForce {
        DragForce::new(DragParams { k_n, k_t, k_f }, Arc::new(vec![[0, 1, 2]]))
    }

    fn tri() -> [Pt3; 3] {
        [Pt3::new(0.0, 0.0, 0.0), Pt3::new(0.3, 0.0, 0.0), Pt3::new(0.0, 0.0, 0.2)]
    }

    /// Spec T12: force against a hand computation.
    #[test]
    fn force_matches_hand_computation() {
        let d = drag(1.5, 0.1, 2.0);
        // Triangle in the x–z plane: n = (0.3,0,0)×(0,0,0.2)/|…| = (0, −1, 0); area 0.03.
        let v = [Vec3::new(0.3, 0.6, 0.0), Vec3::new(0.3, 0.6, 0.0), Vec3::new(0.3, 0.6, 0.0)];
        let t = d.triangle(tri(), v);
        assert!((t.area - 0.03).abs() < 1e-15);
        assert!((t.normal - Vec3::new(0.0, -1.0, 0.0)).norm() < 1e-15);
        let s = -0.6;
        let phi = 1.5 * s * 0.6 / (1.0 + 2.0 * 0.36);
        let expect = -0.03 * (phi * Vec3::new(0.0, -1.0, 0.0) + 0.1 * Vec3::new(0.3, 0.0, 0.0));
        assert!((t.force - expect).norm() <= 1e-12 * expect.norm(), "{:?} vs {expect:?}", t.force);
        // Zero velocity → zero force, exactly.
        let z = d.triangle(tri(), [Vec3::zeros(); 3]);
        assert_eq!(z.force, Vec3::zeros());
    }

    /// Spec T12: the Jacobian against central differences, the power f·v ≤ 0 over random
    /// states, and the saturation of the normal force at a·k_N/k_f.
    #[test]
    fn jacobian_power_and_saturation() {
        let mut rng = Rng::new(12);
        let d = drag(1.2, 0.08, 3.0);
        let faces = [[0u32, 1, 2]];
        for _ in 0..1000 {
            let x = [0, 1, 2].map(|_| Pt3::new(rng.range(-1.0, 1.0), rng.range(-1.0, 1.0), rng.range(-1.0, 1.0)));
            let v = [0, 1, 2].map(|_| Vec3::new(rng.normal(), rng.normal(), rng.normal()) * 2.0);
            let mut f = vec![Vec3::zeros(); 3];
            d.add_forces(0.0, &x, &v, &mut f);
            let power: f64 = f.iter().zip(&v).map(|(a, b)| a.dot(b)).sum();
            assert!(power <= 0.0, "drag must dissipate: {power}");
        }
        let x = tri();
        let v = [Vec3::new(0.2, -0.7, 0.1), Vec3::new(0.1, -0.5, 0.3), Vec3::new(-0.1, -0.9, 0.0)];
        let mut dd = d.clone();
        dd.implicit = true;
        dd.faces = Arc::new(faces.to_vec());
        let mut jv = BlockTriplets::default();
        dd.add_jacobians(0.0, &x, &v, &mut BlockTriplets::default(), &mut jv);
        assert_eq!(jv.blocks.len(), 9);
        let eps = 1e-6;
        for &(i, j, block) in &jv.blocks {
            for c in 0..3 {
                let mut vp = v;
                let mut vm = v;
                vp[j as usize][c] += eps;
                vm[j as usize][c] -= eps;
                let (mut fp, mut fm) = (vec![Vec3::zeros(); 3], vec![Vec3::zeros(); 3]);
                d.add_forces(0.0, &x, &vp, &mut fp);
                d.add_forces(0.0, &x, &vm, &mut fm);
                let fd = (fp[i as usize] - fm[i as usize]) / (2.0 * eps);
                let an = block.column(c).into_owned();
                assert!((fd - an).norm() <= 1e-6 * an.norm().max(1e-12), "block ({i},{j}) col {c}: {fd:?} vs {an:?}");
            }
            assert!((block - block.transpose()).norm() == 0.0);
        }
        // Saturation: |f_N| → a k_N / k_f.
        let t = d.triangle(x, [Vec3::new(0.0, 1e6, 0.0); 3]);
        let limit = t.area * 1.2 / 3.0;
        assert!((t.force.norm() - limit).abs() <= 1e-9 * limit);
    }
}

//! Lagged smoothed Coulomb friction (Li et al. 2020, §5): for every contact active at the start
//! of the step, the normal force magnitude λ, the relative-motion weights c, the tangent frame P
//! and the displacement δ of the obstacle's surface point are frozen; the friction potential is
//! D(x) = μλ f₀(‖u‖) with u = Pᵀ(Σ c_k (x_k − x_kⁿ) − c_o δ) the relative tangential
//! displacement over the step and f₀ the C¹ mollification of |u| below ε = ε_v·h (eq. 14):
//! f₁(y) = 2y/ε − y²/ε² for y < ε, 1 beyond, f₀′ = f₁. Sliding costs μλ per metre (Coulomb);
//! below ε the force fades linearly to zero (static friction approximated by a stiff spring).

use geom_core::math::{Mat3, Pt3, Vec3};
use nalgebra::{Matrix2, Matrix3x2, Vector2};

use super::set::{Contact, Node};

/// One frozen friction contact.
#[derive(Clone, Debug)]
pub(crate) struct FrictionContact {
    /// Cloth vertices of the stencil with their weights c_k.
    pub cloth: Vec<(u32, f64)>,
    /// c_o δ: the weighted displacement of the obstacle's surface over the step (m).
    pub obstacle_shift: Vec3,
    /// Tangent basis (two orthonormal columns ⊥ the normal).
    pub basis: Matrix3x2<f64>,
    /// μλ (N).
    pub mu_lambda: f64,
}

/// f₀(y) with f₀(0) = ε/3 (the constant does not matter; it keeps f₀ continuous at ε).
fn f0(y: f64, eps: f64) -> f64 {
    if y >= eps {
        y
    } else {
        -y * y * y / (3.0 * eps * eps) + y * y / eps + eps / 3.0
    }
}

/// f₁(y)/y, finite at y = 0 (= 2/ε).
fn f1_over_y(y: f64, eps: f64) -> f64 {
    if y >= eps {
        1.0 / y
    } else {
        2.0 / eps - y / (eps * eps)
    }
}

/// A tangent basis of the plane ⊥ n.
fn tangent_basis(n: &Vec3) -> Matrix3x2<f64> {
    let a = if n.x.abs() < 0.9 { Vec3::x() } else { Vec3::y() };
    let t1 = n.cross(&a).normalize();
    let t2 = n.cross(&t1);
    Matrix3x2::from_columns(&[t1, t2])
}

impl FrictionContact {
    /// Freezes contact `c` at the step's start `x0` with normal force magnitude λ (N); `shift`
    /// gives the displacement of an obstacle surface point over the step (m).
    pub fn new(c: &Contact, x0: &[Pt3], lambda: f64, shift: impl Fn(&Pt3) -> Vec3) -> Option<Self> {
        if !(c.mu > 0.0 && lambda > 0.0) {
            return None;
        }
        let (w, n) = c.frame(x0);
        let p = c.points(x0);
        let mut cloth = Vec::new();
        let mut obstacle_shift = Vec3::zeros();
        for k in 0..4 {
            match c.nodes[k] {
                Node::Cloth(i) => cloth.push((i, w[k])),
                Node::Fixed(_) => obstacle_shift += w[k] * shift(&p[k]),
                Node::Unused => {}
            }
        }
        if let super::set::Form::Half { .. } = c.form {
            // A half-space's surface point under the vertex.
            obstacle_shift -= shift(&p[0]);
        }
        Some(Self { cloth, obstacle_shift, basis: tangent_basis(&n), mu_lambda: c.mu * lambda })
    }

    fn u(&self, x: &[Pt3], x0: &[Pt3]) -> Vector2<f64> {
        let mut d = self.obstacle_shift;
        for &(i, w) in &self.cloth {
            d += w * (x[i as usize] - x0[i as usize]);
        }
        self.basis.transpose() * d
    }

    /// The Hessian in u used by Newton: the majorizer μλ f₁(y)/y · I (y = ‖u‖) of the exact
    /// ∇²_u D = μλ[f₁/y (I − ûûᵀ) + f₁′ ûûᵀ]. Both agree across the slip direction; along it
    /// the exact curvature f₁′ is 0 while sliding (y ≥ ε: D is linear in y there) and
    /// f₁′ = 2/ε − 2y/ε² ≤ f₁/y below, so the majorizer is ⪰ the exact Hessian (f₁ is concave
    /// with f₁(0) = 0, hence f₁′ ≤ f₁/y). With the exact form a sliding vertex's Newton step is
    /// bounded by nothing along û, overshoots the stick point u = 0 and the next iteration swings
    /// back (measured on fold-stress's pile: vertices on the floor alternating ±0.3 m/s for 20
    /// iterations); with the majorizer a step along û at most cancels the slip (the quadratic
    /// μλ(y₀/2 + y²/(2y₀)) bounds μλy from above and touches it at y₀: the iteratively
    /// reweighted least-squares bound of a norm), so the iterations approach the stick point
    /// from one side. A Newton direction with an upper-bound Hessian is still a descent
    /// direction; the line search keeps Φ decreasing.
    pub fn hessian_u(&self, u: Vector2<f64>, eps: f64) -> Matrix2<f64> {
        Matrix2::identity() * (self.mu_lambda * f1_over_y(u.norm(), eps))
    }

    /// D(x) (J).
    pub fn energy(&self, x: &[Pt3], x0: &[Pt3], eps: f64) -> f64 {
        self.mu_lambda * f0(self.u(x, x0).norm(), eps)
    }

    /// Adds −∇D to `force` and the PSD Hessian blocks through `block(i, j, m)` (a caller that
    /// scales the Hessian does so in `block`); blocks of vertex pairs outside `in_pattern` are lumped onto both
    /// diagonals as |w_i w_j|·S (see `Ipc::add`).
    pub fn add(
        &self,
        x: &[Pt3],
        x0: &[Pt3],
        eps: f64,
        force: &mut [Vec3],
        in_pattern: &impl Fn(u32, u32) -> bool,
        mut block: impl FnMut(u32, u32, Mat3),
    ) {
        let u = self.u(x, x0);
        let y = u.norm();
        let fy = f1_over_y(y, eps);
        let gu = self.mu_lambda * fy * u;
        let g3 = self.basis * gu;
        for &(i, w) in &self.cloth {
            force[i as usize] -= w * g3;
        }
        let hu = self.hessian_u(u, eps);
        let h3 = self.basis * hu * self.basis.transpose();
        for (a, &(i, wi)) in self.cloth.iter().enumerate() {
            block(i, i, h3 * (wi * wi));
            for &(j, wj) in &self.cloth[a + 1..] {
                if in_pattern(i, j) {
                    block(i, j, h3 * (wi * wj));
                    block(j, i, h3 * (wi * wj));
                } else {
                    let c = (wi * wj).abs();
                    block(i, i, h3 * c);
                    block(j, j, h3 * c);
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::contact::set::{Feat, Form};

    fn plane_contact() -> Contact {
        Contact {
            key: (Feat::V(0), Feat::Half(0)),
            form: Form::Half { normal: Vec3::y(), offset: 0.0 },
            nodes: [Node::Cloth(0), Node::Unused, Node::Unused, Node::Unused],
            xi: 0.0,
            mu: 0.5,
            obstacle: 0,
        }
    }

    #[test]
    fn sliding_force_is_coulomb_and_gradient_matches_energy() {
        let c = plane_contact();
        let x0 = vec![Pt3::new(0.0, 0.001, 0.0)];
        let f = FrictionContact::new(&c, &x0, 2.0, |_| Vec3::zeros()).unwrap();
        let eps = 1e-4;
        // Sliding 1 cm along x: force μλ = 1 N against the motion.
        let x = vec![Pt3::new(0.01, 0.001, 0.0)];
        let mut force = vec![Vec3::zeros()];
        f.add(&x, &x0, eps, &mut force, &|_, _| true, |_, _, _| {});
        assert!((force[0] - Vec3::new(-1.0, 0.0, 0.0)).norm() < 1e-12, "{:?}", force[0]);
        // Energy gradient by finite differences, in the smooth and the sliding regime.
        for dx in [3e-5, 0.01] {
            let x = vec![Pt3::new(dx, 0.001, 0.7 * dx)];
            let mut force = vec![Vec3::zeros()];
            let mut h = Mat3::zeros();
            f.add(&x, &x0, eps, &mut force, &|_, _| true, |_, _, m| h += m);
            for k in 0..3 {
                let e = 1e-9;
                let (mut xp, mut xm) = (x.clone(), x.clone());
                xp[0][k] += e;
                xm[0][k] -= e;
                let fd = (f.energy(&xp, &x0, eps) - f.energy(&xm, &x0, eps)) / (2.0 * e);
                assert!((fd + force[0][k]).abs() < 1e-5, "dx {dx} axis {k}: {fd} vs {}", -force[0][k]);
            }
            let ev = nalgebra::SymmetricEigen::new(h).eigenvalues;
            assert!(ev.iter().all(|&l| l >= -1e-9), "PSD: {ev:?}");
        }
    }

    /// The Newton Hessian majorizes the exact one (FD of the exact gradient): equal across the
    /// slip, ≥ along it, in the smooth (y < ε) and the sliding regime.
    #[test]
    fn friction_hessian_majorizes_the_exact_hessian() {
        let c = plane_contact();
        let x0 = vec![Pt3::new(0.0, 0.001, 0.0)];
        let f = FrictionContact::new(&c, &x0, 2.0, |_| Vec3::zeros()).unwrap();
        let eps = 1e-4;
        let grad = |x: &[Pt3]| {
            let mut force = vec![Vec3::zeros()];
            f.add(x, &x0, eps, &mut force, &|_, _| true, |_, _, _| {});
            -force[0]
        };
        for dx in [2e-5, 7e-5, 3e-4, 0.01] {
            let x = vec![Pt3::new(dx, 0.001, 0.4 * dx)];
            let mut h = Mat3::zeros();
            f.add(&x, &x0, eps, &mut [Vec3::zeros()], &|_, _| true, |_, _, m| h += m);
            // Exact Hessian by central differences of the gradient.
            let e = 1e-6 * dx;
            let mut hfd = Mat3::zeros();
            for k in 0..3 {
                let (mut xp, mut xm) = (x.clone(), x.clone());
                xp[0][k] += e;
                xm[0][k] -= e;
                hfd.set_column(k, &((grad(&xp) - grad(&xm)) / (2.0 * e)));
            }
            let slip = Vec3::new(1.0, 0.0, 0.4).normalize();
            let across = Vec3::new(-0.4, 0.0, 1.0).normalize();
            let scale = h.norm();
            let (ha, hfa) = (across.dot(&(h * across)), across.dot(&(hfd * across)));
            assert!((ha - hfa).abs() < 1e-5 * scale, "across at dx {dx}: {ha} vs {hfa}");
            let (hs, hfs) = (slip.dot(&(h * slip)), slip.dot(&(hfd * slip)));
            assert!(hs >= hfs - 1e-5 * scale, "along at dx {dx}: {hs} vs {hfs}");
            let diff = nalgebra::SymmetricEigen::new(h - 0.5 * (hfd + hfd.transpose())).eigenvalues;
            assert!(diff.iter().all(|&l| l >= -1e-5 * scale), "H − H_exact ⪰ 0 at dx {dx}: {diff:?}");
        }
    }

    #[test]
    fn a_moving_surface_drags_a_resting_vertex() {
        let c = plane_contact();
        let x0 = vec![Pt3::new(0.0, 0.001, 0.0)];
        // The floor slides +x by 1 cm in the step; the vertex stays: relative slip −1 cm.
        let f = FrictionContact::new(&c, &x0, 2.0, |_| Vec3::new(0.01, 0.0, 0.0)).unwrap();
        let mut force = vec![Vec3::zeros()];
        f.add(&x0, &x0, 1e-4, &mut force, &|_, _| true, |_, _, _| {});
        assert!(force[0].x > 0.99, "dragged along: {:?}", force[0]);
    }
}

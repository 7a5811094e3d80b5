//! The signed dihedral angle of a hinge and its exact gradient and Hessian (shells.md §3.2).
//!
//! A hinge is `[a, b, w1, w2]`: triangle 1 = (a, b, w1) holds the directed edge a→b, triangle
//! 2 = (b, a, w2) holds b→a. With u = b − a, ℓ = |u|, ê = u/ℓ, N₁ = u × (w1 − a),
//! N₂ = (w2 − b) × u and n̂ᵢ = Nᵢ/|Nᵢ|,
//!
//!   θ = atan2((n̂₂ × n̂₁)·ê, n̂₁·n̂₂),
//!
//! zero for a flat hinge and positive when w1 moves toward +n̂₁ (the convention shared with
//! `geom_core::mesh::hinge_angle`). atan2 keeps the sign and a finite derivative at 0.
//!
//! Gradient (§3.2): with gᵢ = Nᵢ/|Nᵢ|² and c_{p,r} = ((q_p − q_r)·u)/ℓ,
//! ∂θ/∂w1 = ℓg₁, ∂θ/∂w2 = ℓg₂, ∂θ/∂a = −c_{b,w1}g₁ − c_{b,w2}g₂, ∂θ/∂b = −c_{w1,a}g₁ − c_{w2,a}g₂.
//! The Hessian is the product rule on these blocks: ∂(c g)/∂q = g (∂c/∂q)ᵀ + c Q(N) ∂N/∂q with
//! Q(N) = (I − 2NNᵀ/|N|²)/|N|², symmetrised at the end.

use geom_core::math::{Mat3, Pt3, Vec3};
use nalgebra::SMatrix;

/// 12×12 matrix over the hinge's four vertices (blocks in the order a, b, w1, w2).
pub type Mat12 = SMatrix<f64, 12, 12>;

/// Relative threshold below which a hinge triangle counts as collapsed: |Nᵢ| < `COLLAPSE_REL`·ℓ²
/// (§8 "hinge folded flat"); the hinge is then skipped for the step.
pub const COLLAPSE_REL: f64 = 1e-14;

/// Signed dihedral angle θ ∈ (−π, π] of the hinge `x = [a, b, w1, w2]` (rad).
///
/// Returns 0 for a hinge whose edge or one of whose triangles has zero length/area (callers that
/// need to know use [`hinge_is_collapsed`]).
pub fn hinge_angle(x: &[Pt3; 4]) -> f64 {
    let u = x[1] - x[0];
    let n1 = u.cross(&(x[2] - x[0]));
    let n2 = (x[3] - x[1]).cross(&u);
    let l = u.norm();
    if l == 0.0 {
        return 0.0;
    }
    // atan2 is scale-free: |N₁||N₂| cancels, so the unnormalised normals suffice.
    let sin = n2.cross(&n1).dot(&u) / l;
    let cos = n1.dot(&n2);
    sin.atan2(cos)
}

/// True when the hinge's edge has zero length or a triangle is collapsed (|Nᵢ| < 1e-14·ℓ²);
/// its angle derivatives are then undefined and the hinge is skipped (§8).
pub fn hinge_is_collapsed(x: &[Pt3; 4]) -> bool {
    let u = x[1] - x[0];
    let l2 = u.norm_squared();
    let n1 = u.cross(&(x[2] - x[0])).norm();
    let n2 = (x[3] - x[1]).cross(&u).norm();
    !(l2 > 0.0) || !(n1 >= COLLAPSE_REL * l2) || !(n2 >= COLLAPSE_REL * l2)
}

/// Gradient ∂θ/∂x as four 3-vectors (a, b, w1, w2); they sum to zero (translation invariance).
/// Undefined (non-finite) for collapsed hinges: check [`hinge_is_collapsed`] first.
pub fn hinge_angle_grad(x: &[Pt3; 4]) -> [Vec3; 4] {
    HingeFrame::new(x).grad()
}

/// Exact Hessian ∂²θ/∂x² (12×12, blocks a, b, w1, w2), symmetric to round-off (symmetrised).
/// Undefined for collapsed hinges: check [`hinge_is_collapsed`] first.
pub fn hinge_angle_hessian(x: &[Pt3; 4]) -> Mat12 {
    HingeFrame::new(x).hessian()
}

/// Quantities shared by the angle, its gradient and its Hessian.
pub(crate) struct HingeFrame {
    x: [Pt3; 4],
    u: Vec3,
    l: f64,
    n: [Vec3; 2],
    g: [Vec3; 2],
}

/// Cross-product matrix: `skew(x) * y = x × y`.
#[inline]
fn skew(x: &Vec3) -> Mat3 {
    Mat3::new(0.0, -x.z, x.y, x.z, 0.0, -x.x, -x.y, x.x, 0.0)
}

impl HingeFrame {
    pub(crate) fn new(x: &[Pt3; 4]) -> Self {
        let u = x[1] - x[0];
        let l = u.norm();
        let n1 = u.cross(&(x[2] - x[0]));
        let n2 = (x[3] - x[1]).cross(&u);
        let g1 = n1 / n1.norm_squared();
        let g2 = n2 / n2.norm_squared();
        Self { x: *x, u, l, n: [n1, n2], g: [g1, g2] }
    }

    /// θ from the stored normals (same formula as [`hinge_angle`]).
    pub(crate) fn angle(&self) -> f64 {
        let sin = self.n[1].cross(&self.n[0]).dot(&self.u) / self.l;
        sin.atan2(self.n[0].dot(&self.n[1]))
    }

    /// c_{p,r} = ((q_p − q_r)·u)/ℓ.
    #[inline]
    fn c(&self, p: usize, r: usize) -> f64 {
        (self.x[p] - self.x[r]).dot(&self.u) / self.l
    }

    /// Coefficients of gradient block v on g₁ and g₂.
    fn coeffs(&self) -> [[f64; 2]; 4] {
        [[-self.c(1, 2), -self.c(1, 3)], [-self.c(2, 0), -self.c(3, 0)], [self.l, 0.0], [0.0, self.l]]
    }

    pub(crate) fn grad(&self) -> [Vec3; 4] {
        let k = self.coeffs();
        let mut out = [Vec3::zeros(); 4];
        for (v, kv) in k.iter().enumerate() {
            out[v] = kv[0] * self.g[0] + kv[1] * self.g[1];
        }
        out
    }

    /// Gradient of c_{p,r} with respect to the four vertices (§3.2 "derivatives of the scalar
    /// coefficients").
    fn dc(&self, p: usize, r: usize) -> [Vec3; 4] {
        let ul = self.u / self.l;
        let c = self.c(p, r);
        let d = (self.x[p] - self.x[r]) / self.l - c * self.u / (self.l * self.l);
        let mut out = [Vec3::zeros(); 4];
        out[p] += ul;
        out[r] -= ul;
        out[1] += d;
        out[0] -= d;
        out
    }

    pub(crate) fn hessian(&self) -> Mat12 {
        let [a, b, w1, w2] = self.x;
        let u = self.u;
        // ∂N_T/∂q_v (table of §3.2); None for an exact zero block.
        let dn: [[Option<Mat3>; 4]; 2] = [
            [Some(skew(&(w1 - b))), Some(skew(&(a - w1))), Some(skew(&u)), None],
            [Some(skew(&(b - w2))), Some(skew(&(w2 - a))), None, Some(-skew(&u))],
        ];
        let q: [Mat3; 2] = std::array::from_fn(|t| {
            let n = self.n[t];
            let nn = n.norm_squared();
            (Mat3::identity() - 2.0 * n * n.transpose() / nn) / nn
        });
        let ul = u / self.l;
        let dl = [-ul, ul, Vec3::zeros(), Vec3::zeros()];
        // ∂(coefficient of g_T in block v)/∂q_w for every (v, T).
        let neg = |d: [Vec3; 4]| d.map(|x| -x);
        let dk: [[[Vec3; 4]; 2]; 4] = [
            [neg(self.dc(1, 2)), neg(self.dc(1, 3))],
            [neg(self.dc(2, 0)), neg(self.dc(3, 0))],
            [dl, [Vec3::zeros(); 4]],
            [[Vec3::zeros(); 4], dl],
        ];
        let k = self.coeffs();
        let mut h = Mat12::zeros();
        for v in 0..4 {
            for w in 0..4 {
                let mut blk = Mat3::zeros();
                for t in 0..2 {
                    blk += self.g[t] * dk[v][t][w].transpose();
                    if k[v][t] != 0.0 {
                        if let Some(d) = dn[t][w] {
                            blk += k[v][t] * (q[t] * d);
                        }
                    }
                }
                h.fixed_view_mut::<3, 3>(3 * v, 3 * w).copy_from(&blk);
            }
        }
        let ht = h.transpose();
        (h + ht) * 0.5
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kernels::testutil::TestRng as Rng;

    pub(crate) fn random_hinge(rng: &mut Rng) -> [Pt3; 4] {
        // A flat-ish well-shaped hinge, then random perturbation and a random fold.
        loop {
            let mut p = [
                Pt3::new(0.0, 0.0, 0.0),
                Pt3::new(1.0, 0.0, 0.0),
                Pt3::new(rng.range(0.1, 0.9), rng.range(0.4, 1.2), 0.0),
                Pt3::new(rng.range(0.1, 0.9), -rng.range(0.4, 1.2), 0.0),
            ];
            p[2].z += rng.range(-0.8, 0.8);
            p[3].z += rng.range(-0.8, 0.8);
            for q in p.iter_mut() {
                *q += Vec3::new(rng.range(-0.1, 0.1), rng.range(-0.1, 0.1), rng.range(-0.1, 0.1));
            }
            if !hinge_is_collapsed(&p) && hinge_angle(&p).abs() < 3.0 {
                return p;
            }
        }
    }

    fn max_abs(v: impl Iterator<Item = f64>) -> f64 {
        v.fold(0.0, |m, x| m.max(x.abs()))
    }

    /// §7 test 1: ∇θ against central differences (ε = 1e-6 of the unit edge), 100 hinges.
    #[test]
    fn hinge_grad_fd() {
        let mut rng = Rng::new(1);
        for _ in 0..100 {
            let x = random_hinge(&mut rng);
            let g = hinge_angle_grad(&x);
            let eps = 1e-6;
            let mut fd = [0.0; 12];
            for i in 0..12 {
                let (mut xp, mut xm) = (x, x);
                xp[i / 3][i % 3] += eps;
                xm[i / 3][i % 3] -= eps;
                fd[i] = (hinge_angle(&xp) - hinge_angle(&xm)) / (2.0 * eps);
            }
            let err = max_abs((0..12).map(|i| g[i / 3][i % 3] - fd[i]));
            // Central differences: truncation O(ε²·θ''') ≈ 1e-12, rounding 1e-16/ε ≈ 1e-10.
            assert!(err < 1e-6 * max_abs(fd.iter().copied()), "err {err}");
            let sum: Vec3 = g.iter().sum();
            assert!(sum.norm() < 1e-12 * max_abs(fd.iter().copied()));
        }
    }

    /// §7 test 2: ∇²θ against central differences of ∇θ; symmetry; closed forms of the wing blocks.
    #[test]
    fn hinge_hess_fd() {
        let mut rng = Rng::new(2);
        for _ in 0..100 {
            let x = random_hinge(&mut rng);
            let fr = HingeFrame::new(&x);
            let h = fr.hessian();
            let eps = 1e-6;
            let mut fd = Mat12::zeros();
            for j in 0..12 {
                let (mut xp, mut xm) = (x, x);
                xp[j / 3][j % 3] += eps;
                xm[j / 3][j % 3] -= eps;
                let (gp, gm) = (hinge_angle_grad(&xp), hinge_angle_grad(&xm));
                for i in 0..12 {
                    fd[(i, j)] = (gp[i / 3][i % 3] - gm[i / 3][i % 3]) / (2.0 * eps);
                }
            }
            let scale = fd.amax();
            assert!((h - fd).amax() < 1e-6 * scale, "hessian err {}", (h - fd).amax() / scale);
            // Exact symmetry after symmetrisation; before it, round-off only.
            assert!((h - h.transpose()).amax() <= 1e-12 * h.amax());
            // ∂²θ/∂w1∂w2 = 0 exactly.
            assert_eq!(h.fixed_view::<3, 3>(6, 9).amax(), 0.0);
            // Wing closed form: −(n̂₁t̂₁ᵀ + t̂₁n̂₁ᵀ)/h₁², t̂₁ = n̂₁ × ê, h₁ = |N₁|/ℓ.
            for (t, off) in [(0usize, 6usize), (1, 9)] {
                let n = fr.n[t].normalize();
                let e = fr.u / fr.l;
                let tt = if t == 0 { n.cross(&e) } else { e.cross(&n) };
                let hh = fr.n[t].norm() / fr.l;
                let closed = -(n * tt.transpose() + tt * n.transpose()) / (hh * hh);
                let blk = h.fixed_view::<3, 3>(off, off).into_owned();
                assert!((blk - closed).amax() <= 1e-12 * closed.amax().max(1.0), "wing {t}");
            }
        }
    }

    /// §7 test 3: sign convention on the reference hinge.
    #[test]
    fn hinge_sign() {
        let flat =
            [Pt3::new(0.0, 0.0, 0.0), Pt3::new(1.0, 0.0, 0.0), Pt3::new(0.5, 1.0, 0.0), Pt3::new(0.5, -1.0, 0.0)];
        assert_eq!(hinge_angle(&flat), 0.0);
        let mut up1 = flat;
        up1[2].z += 0.1;
        assert!((hinge_angle(&up1) - 0.1f64.atan()).abs() < 1e-12);
        let mut up2 = flat;
        up2[3].z += 0.1;
        assert!((hinge_angle(&up2) - 0.1f64.atan()).abs() < 1e-12);
        assert!(hinge_angle(&up1) > 0.0);
    }

    #[test]
    fn collapsed_detected() {
        let x = [Pt3::new(0.0, 0.0, 0.0), Pt3::new(1.0, 0.0, 0.0), Pt3::new(0.5, 0.0, 0.0), Pt3::new(0.5, -1.0, 0.0)];
        assert!(hinge_is_collapsed(&x));
        assert_eq!(hinge_angle(&x), 0.0);
    }
}

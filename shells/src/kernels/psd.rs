//! Hessian modes and positive semi-definite projection helpers (shells.md §3.4).

use geom_core::math::{Mat2, Vec2};
use nalgebra::{SMatrix, SymmetricEigen};
use serde::{Deserialize, Serialize};

/// How element Hessians are made usable by the Cholesky solver (§3.4).
///
/// * `ProjectedCheap` (default): membrane geometric term uses the stress clamped to its PSD part
///   S⁺, bending keeps only the Gauss–Newton term 2kω∇θ∇θᵀ. Element matrices are PSD by
///   construction at the price of one 2×2 eigen-decomposition per triangle.
/// * `ProjectedEigen`: exact element Hessians with negative eigenvalues clamped to 0 (the closest
///   PSD matrix per element); 2–10× the assembly cost, used in the accuracy/time study.
/// * `Full`: exact Hessians, no projection; may fail to factor (then the diagonal-shift path of
///   §3.8 is used and reported).
///
/// All three keep each element's translation null space, so the linear solve conserves momentum.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum HessianMode {
    /// Stress-clamped membrane + Gauss–Newton bending (default).
    #[default]
    ProjectedCheap,
    /// Per-element eigenvalue clamping of the exact Hessians.
    ProjectedEigen,
    /// Exact Hessians.
    Full,
}

/// Closed-form eigen-decomposition of a symmetric 2×2 matrix: eigenvalues ascending and the
/// matching unit eigenvectors as columns.
pub fn sym_eig2(m: &Mat2) -> (Vec2, Mat2) {
    let (a, b, d) = (m[(0, 0)], 0.5 * (m[(0, 1)] + m[(1, 0)]), m[(1, 1)]);
    let mean = 0.5 * (a + d);
    let r = (0.25 * (a - d) * (a - d) + b * b).sqrt();
    let (l0, l1) = (mean - r, mean + r);
    if r == 0.0 {
        return (Vec2::new(l0, l1), Mat2::identity());
    }
    // Eigenvector of l1: the better conditioned of (b, l1 − a) and (l1 − d, b).
    let v1 = if a >= d { Vec2::new(l1 - d, b) } else { Vec2::new(b, l1 - a) };
    let v1 = v1.normalize();
    let v0 = Vec2::new(-v1.y, v1.x);
    (Vec2::new(l0, l1), Mat2::from_columns(&[v0, v1]))
}

/// The PSD part of a symmetric 2×2 matrix (negative eigenvalues set to 0).
pub fn psd_part2(m: &Mat2) -> Mat2 {
    let (l, v) = sym_eig2(m);
    if l.x >= 0.0 {
        return *m;
    }
    let l1 = l.y.max(0.0);
    let c1 = v.column(1);
    l1 * c1 * c1.transpose()
}

/// Symmetric matrices whose negative eigenvalues can be clamped (3×3, 9×9, 12×12).
pub trait ProjectPsd: Sized {
    /// The closest PSD matrix (eigenvalues clamped at 0); the input unchanged (bitwise) when it
    /// is already PSD.
    fn project_psd(&self) -> Self;
}

macro_rules! impl_project_psd {
    ($n:literal) => {
        impl ProjectPsd for SMatrix<f64, $n, $n> {
            fn project_psd(&self) -> Self {
                let eig = SymmetricEigen::new(*self);
                if eig.eigenvalues.iter().all(|&l| l >= 0.0) {
                    return *self;
                }
                let mut out = Self::zeros();
                for (k, &l) in eig.eigenvalues.iter().enumerate() {
                    if l > 0.0 {
                        let v = eig.eigenvectors.column(k);
                        out += l * v * v.transpose();
                    }
                }
                (out + out.transpose()) * 0.5
            }
        }
    };
}

impl_project_psd!(3);
impl_project_psd!(9);
impl_project_psd!(12);

/// Clamps the negative eigenvalues of a symmetric matrix to 0 (nalgebra `SymmetricEigen`).
pub fn project_psd<M: ProjectPsd>(m: &M) -> M {
    m.project_psd()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn eig2_reconstructs() {
        for m in [
            Mat2::new(2.0, 1.0, 1.0, -3.0),
            Mat2::new(1.0, 0.0, 0.0, 1.0),
            Mat2::new(-1.0, 1e-9, 1e-9, 5.0),
            Mat2::new(0.0, 2.0, 2.0, 0.0),
            Mat2::new(3.0, 0.0, 0.0, -1.0),
        ] {
            let (l, v) = sym_eig2(&m);
            let r = v * Mat2::from_diagonal(&l) * v.transpose();
            assert!((r - m).amax() < 1e-14 * m.amax().max(1.0), "{m}");
            assert!(l.x <= l.y);
            assert!((v.transpose() * v - Mat2::identity()).amax() < 1e-14);
        }
    }

    #[test]
    fn psd_projection_clamps() {
        let m = Mat2::new(2.0, 1.0, 1.0, -3.0);
        let p = psd_part2(&m);
        let (l, _) = sym_eig2(&p);
        assert!(l.x > -1e-14 && (l.y - sym_eig2(&m).0.y).abs() < 1e-14);
        let big = SMatrix::<f64, 3, 3>::new(1.0, 2.0, 0.0, 2.0, 1.0, 0.0, 0.0, 0.0, -1.0);
        let pb = project_psd(&big);
        let e = SymmetricEigen::new(pb).eigenvalues;
        assert!(e.iter().all(|&x| x > -1e-14));
        assert!((e.max() - 3.0).abs() < 1e-12);
    }
}

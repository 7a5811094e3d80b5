//! Eigen-decomposition of small symmetric matrices: [`sym_eig2`] in closed form and [`sym_eig3`]
//! by cyclic Jacobi rotations (robust for repeated eigenvalues, always orthonormal vectors).
//!
//! Both return eigenvalues in **ascending** order and the eigenvectors as the **columns** of the
//! matrix, so `A = V·diag(λ)·Vᵀ`. The input is symmetrised as `(A + Aᵀ)/2` first.

use super::{Mat2, Mat3, Vec2, Vec3};

/// Eigenvalues (ascending) and orthonormal eigenvectors (columns) of a symmetric 2×2 matrix, in
/// closed form: `λ = m ∓ r` with `m = (a+c)/2`, `r = hypot((a−c)/2, b)`, and the eigenvector of
/// the larger eigenvalue at angle `½·atan2(2b, a−c)`. Exact for diagonal input and for a
/// repeated eigenvalue (returns the identity basis). The input is symmetrised first.
pub fn sym_eig2(m: &Mat2) -> (Vec2, Mat2) {
    let a = m[(0, 0)];
    let c = m[(1, 1)];
    let b = 0.5 * (m[(0, 1)] + m[(1, 0)]);
    let mean = 0.5 * (a + c);
    let r = (0.5 * (a - c)).hypot(b);
    let phi = 0.5 * (2.0 * b).atan2(a - c);
    let (s, co) = phi.sin_cos();
    // Columns: v_small = (−sin φ, cos φ), v_large = (cos φ, sin φ).
    let v = Mat2::new(-s, co, co, s);
    (Vec2::new(mean - r, mean + r), v)
}

/// Eigenvalues (ascending) and orthonormal eigenvectors (columns, right-handed) of a symmetric
/// 3×3 matrix by cyclic Jacobi rotations. Converges quadratically; stops when the off-diagonal
/// part is below `1e-15·‖A‖_F` (or after 50 sweeps, which finite input never needs). Repeated
/// eigenvalues are no special case: the returned basis is orthonormal to rounding. Non-finite
/// input gives non-finite output (no panic). The input is symmetrised first.
pub fn sym_eig3(m: &Mat3) -> (Vec3, Mat3) {
    let mut a = 0.5 * (m + m.transpose());
    let mut v = Mat3::identity();
    let scale = a.norm();
    if scale == 0.0 || !scale.is_finite() {
        let d = Vec3::new(a[(0, 0)], a[(1, 1)], a[(2, 2)]);
        return sort_eig(d, v);
    }
    let tol = 1e-15 * scale;
    for _sweep in 0..50 {
        let off = (a[(0, 1)].powi(2) + a[(0, 2)].powi(2) + a[(1, 2)].powi(2)).sqrt();
        if off <= tol {
            break;
        }
        for (p, q) in [(0usize, 1usize), (0, 2), (1, 2)] {
            let apq = a[(p, q)];
            if apq.abs() <= 1e-300 {
                continue;
            }
            // Rotation angle zeroing a[p][q] (Numerical Recipes §11.1, stable form).
            let theta = (a[(q, q)] - a[(p, p)]) / (2.0 * apq);
            let t = theta.signum() / (theta.abs() + (theta * theta + 1.0).sqrt());
            let c = 1.0 / (t * t + 1.0).sqrt();
            let s = t * c;
            // A ← Jᵀ A J with J the Givens rotation in the (p, q) plane.
            for k in 0..3 {
                let akp = a[(k, p)];
                let akq = a[(k, q)];
                a[(k, p)] = c * akp - s * akq;
                a[(k, q)] = s * akp + c * akq;
            }
            for k in 0..3 {
                let apk = a[(p, k)];
                let aqk = a[(q, k)];
                a[(p, k)] = c * apk - s * aqk;
                a[(q, k)] = s * apk + c * aqk;
            }
            for k in 0..3 {
                let vkp = v[(k, p)];
                let vkq = v[(k, q)];
                v[(k, p)] = c * vkp - s * vkq;
                v[(k, q)] = s * vkp + c * vkq;
            }
        }
    }
    sort_eig(Vec3::new(a[(0, 0)], a[(1, 1)], a[(2, 2)]), v)
}

/// Sorts eigenpairs ascending and makes the basis right-handed (det = +1).
fn sort_eig(d: Vec3, v: Mat3) -> (Vec3, Mat3) {
    let mut idx = [0usize, 1, 2];
    idx.sort_by(|&i, &j| d[i].total_cmp(&d[j]));
    let vals = Vec3::new(d[idx[0]], d[idx[1]], d[idx[2]]);
    let mut vecs = Mat3::from_columns(&[v.column(idx[0]), v.column(idx[1]), v.column(idx[2])]);
    if vecs.determinant() < 0.0 {
        let c = -vecs.column(2);
        vecs.set_column(2, &c);
    }
    (vals, vecs)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Rng;

    fn check3(m: &Mat3, tol: f64) {
        let (l, v) = sym_eig3(m);
        assert!(l[0] <= l[1] && l[1] <= l[2], "{l:?}");
        assert!((v.transpose() * v - Mat3::identity()).norm() < 1e-14, "not orthonormal");
        let recon = v * Mat3::from_diagonal(&l) * v.transpose();
        let s = m.norm().max(1e-300);
        assert!((recon - m).norm() / s < tol, "reconstruction {}", (recon - m).norm() / s);
    }

    #[test]
    fn eig2_closed_form() {
        let m = Mat2::new(2.0, 1.0, 1.0, 2.0);
        let (l, v) = sym_eig2(&m);
        assert!((l - Vec2::new(1.0, 3.0)).norm() < 1e-15);
        assert!((v * Mat2::from_diagonal(&l) * v.transpose() - m).norm() < 1e-14);
        assert!((v.transpose() * v - Mat2::identity()).norm() < 1e-15);
        // Repeated eigenvalue and diagonal input.
        let (l, v) = sym_eig2(&Mat2::new(4.0, 0.0, 0.0, 4.0));
        assert_eq!(l, Vec2::new(4.0, 4.0));
        assert!((v.transpose() * v - Mat2::identity()).norm() < 1e-15);
        let (l, _) = sym_eig2(&Mat2::new(5.0, 0.0, 0.0, -1.0));
        assert_eq!(l, Vec2::new(-1.0, 5.0));
        let mut rng = Rng::new(3);
        for _ in 0..1000 {
            let (a, b, c) = (rng.range(-5.0, 5.0), rng.range(-5.0, 5.0), rng.range(-5.0, 5.0));
            let m = Mat2::new(a, b, b, c);
            let (l, v) = sym_eig2(&m);
            assert!(l[0] <= l[1]);
            assert!((v * Mat2::from_diagonal(&l) * v.transpose() - m).norm() < 1e-13);
        }
    }

    #[test]
    fn eig3_random_and_repeated() {
        let mut rng = Rng::new(11);
        for _ in 0..1000 {
            let mut m = Mat3::zeros();
            for i in 0..3 {
                for j in i..3 {
                    let x = rng.range(-3.0, 3.0);
                    m[(i, j)] = x;
                    m[(j, i)] = x;
                }
            }
            check3(&m, 1e-14);
        }
        // Repeated and triple eigenvalues in a rotated basis.
        for vals in [[1.0, 1.0, 2.0], [2.0, 5.0, 5.0], [3.0, 3.0, 3.0], [0.0, 0.0, 1e-12], [-1.0, 0.0, 0.0]] {
            let q = crate::math::quat_exp(&Vec3::new(0.3, -1.1, 0.7)).to_rotation_matrix().into_inner();
            let m = q * Mat3::from_diagonal(&Vec3::from(vals)) * q.transpose();
            check3(&m, 1e-14);
            let (l, _) = sym_eig3(&m);
            for k in 0..3 {
                assert!((l[k] - vals[k]).abs() < 1e-14 * 5.0, "{l:?} vs {vals:?}");
            }
        }
        // Zero and diagonal matrices.
        let (l, v) = sym_eig3(&Mat3::zeros());
        assert_eq!(l, Vec3::zeros());
        assert_eq!(v, Mat3::identity());
        let (l, _) = sym_eig3(&Mat3::from_diagonal(&Vec3::new(3.0, -2.0, 1.0)));
        assert_eq!(l, Vec3::new(-2.0, 1.0, 3.0));
        // Widely spread magnitudes.
        check3(&Mat3::new(1e8, 1.0, 0.0, 1.0, 1e-8, 1e-9, 0.0, 1e-9, 1.0), 1e-14);
    }

    #[test]
    fn eig3_non_finite_does_not_panic() {
        let (l, _) = sym_eig3(&Mat3::from_element(f64::NAN));
        assert!(l.iter().all(|x| x.is_nan()));
    }
}

//! Unit dual quaternions for rigid transforms (Kavan et al. 2007/2008): `q̂ = r + ε·½(0, t)·r`;
//! the rigid map is `x ↦ R(r)x + t` with `t = 2·(q_ε r*)_vector`. Quaternion order follows
//! nalgebra (`w` is the scalar; Hamilton product). Test 7.3 a pins the convention.

use geom_core::math::{Iso3, Pt3, UnitQuat, Vec3};
use nalgebra::{Quaternion, Translation3};

/// A dual quaternion `real + ε dual` in `f64`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DualQuat {
    /// Rotation part `r`.
    pub real: Quaternion<f64>,
    /// Translation part `½ (0, t) r`.
    pub dual: Quaternion<f64>,
}

impl DualQuat {
    /// The unit dual quaternion of a rigid transform.
    pub fn from_iso(t: &Iso3) -> DualQuat {
        let r = *t.rotation.quaternion();
        let d = Quaternion::from_imag(t.translation.vector) * r * 0.5;
        DualQuat { real: r, dual: d }
    }

    /// Back to a rigid transform (the real part is normalised first, the dual part with it).
    pub fn to_iso(&self) -> Iso3 {
        let n = self.real.norm();
        let r = self.real / n;
        let d = self.dual / n;
        let t = (d * r.conjugate()).imag() * 2.0;
        Iso3::from_parts(Translation3::from(t), UnitQuat::new_unchecked(r))
    }

    /// `s·self` (blend term).
    pub fn scale(&self, s: f64) -> DualQuat {
        DualQuat { real: self.real * s, dual: self.dual * s }
    }

    /// Sum of two dual quaternions.
    pub fn add(&self, o: &DualQuat) -> DualQuat {
        DualQuat { real: self.real + o.real, dual: self.dual + o.dual }
    }

    /// Normalises by ‖real‖ (spec §3.3 step 3). The result is a unit dual quaternion only if
    /// `real·dual = 0`, which holds for any blend of unit dual quaternions up to the first-order
    /// term dropped by Kavan's approximate DLB — the rotation is taken from `real` and the
    /// translation from `2 (dual real*)` as in the paper.
    pub fn normalized(&self) -> DualQuat {
        let n = self.real.norm();
        DualQuat { real: self.real / n, dual: self.dual / n }
    }

    /// Applies the (normalised) transform to a point: `R(c₀) x + 2 (c_ε c₀*)_vector`.
    pub fn transform_point(&self, x: &Pt3) -> Pt3 {
        let r = UnitQuat::new_unchecked(self.real);
        let t = (self.dual * self.real.conjugate()).imag() * 2.0;
        r * x + t
    }

    /// Applies the rotation part to a direction.
    pub fn transform_vector(&self, v: &Vec3) -> Vec3 {
        UnitQuat::new_unchecked(self.real) * v
    }
}

/// Sign of the 4-D dot product of two rotation quaternions (`+1` when `a·b ≥ 0`).
pub fn hemisphere_sign(a: &Quaternion<f64>, b: &Quaternion<f64>) -> f64 {
    if a.coords.dot(&b.coords) < 0.0 {
        -1.0
    } else {
        1.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trip_rigid_transform() {
        // Spec 7.3 a: rigid transform → DQ → matrix, 1e-12.
        for k in 0..50 {
            let f = k as f64;
            let t = Iso3::new(Vec3::new(f.sin(), 2.0 * f.cos(), 0.3 * f), Vec3::new(0.1 * f, -0.7, 0.05 * f * f));
            let back = DualQuat::from_iso(&t).to_iso();
            let e = (t.to_homogeneous() - back.to_homogeneous()).abs().max();
            assert!(e < 1e-12, "k={k}: {e}");
            let x = Pt3::new(0.3, -1.0, 2.0);
            assert!((DualQuat::from_iso(&t).transform_point(&x) - t * x).norm() < 1e-12);
        }
    }

    #[test]
    fn negated_dual_quaternion_is_the_same_transform() {
        let t = Iso3::new(Vec3::new(1.0, 2.0, 3.0), Vec3::new(0.3, 0.2, 0.1));
        let q = DualQuat::from_iso(&t).scale(-1.0);
        let x = Pt3::new(0.5, 0.5, 0.5);
        assert!((q.transform_point(&x) - t * x).norm() < 1e-12);
    }
}

//! Signed dihedral angles of hinges `[a, b, w1, w2]` with the convention of shells.md §3.2,
//! shared by every crate (GEOM-CORE.md §5 item 13).
//!
//! With `u = b − a`, `ℓ = |u|`, `ê = u/ℓ`, `N₁ = u × (w1 − a)`, `N₂ = (w2 − b) × u`:
//! `θ = atan2((n̂₂ × n̂₁)·ê, n̂₁·n̂₂)`. θ = 0 for a flat hinge and θ > 0 when w1 moves toward
//! +n̂₁ (the hinge folds toward the normal side).

use super::Topology;
use crate::math::{AsPt3, Pt3};

/// Relative threshold for a collapsed wing: `|N_i| < 1e-14·ℓ²`, i.e. the wing's height over
/// the edge is below 1e-14 of the edge length (its normal is numerically undefined).
pub const HINGE_COLLAPSE_REL: f64 = 1e-14;

/// Signed dihedral angle (rad, in (−π, π]) of the hinge `x = [a, b, w1, w2]`, or `None` when the
/// hinge edge has zero length or a wing has collapsed (`|N_i| ≤ 1e-14·ℓ²`), where the angle is
/// undefined. Non-finite input gives `None`.
pub fn hinge_angle_checked(x: &[Pt3; 4]) -> Option<f64> {
    let [a, b, w1, w2] = *x;
    let u = b - a;
    let l2 = u.norm_squared();
    let n1 = u.cross(&(w1 - a));
    let n2 = (w2 - b).cross(&u);
    let tol = HINGE_COLLAPSE_REL * l2;
    let (m1, m2) = (n1.norm(), n2.norm());
    // Strict `>` also rejects NaN and the zero-length edge (tol = 0 = m).
    let defined = m1 > tol && m2 > tol && l2.is_finite();
    if !defined {
        return None;
    }
    // atan2 is invariant to the common positive factor |N₁||N₂|ℓ, so use unnormalised vectors:
    // (n̂₂ × n̂₁)·ê = (N₂ × N₁)·u / (|N₁||N₂|ℓ) and n̂₁·n̂₂ = N₁·N₂ / (|N₁||N₂|).
    let s = n2.cross(&n1).dot(&u);
    let c = n1.dot(&n2) * l2.sqrt();
    Some(s.atan2(c))
}

/// Signed dihedral angle (rad) of the hinge `[a, b, w1, w2]` (see the module docs); returns
/// `0.0` — never NaN — when the angle is undefined (collapsed wing or zero-length edge; use
/// [`hinge_angle_checked`] to detect that case).
pub fn hinge_angle(x: &[Pt3; 4]) -> f64 {
    hinge_angle_checked(x).unwrap_or(0.0)
}

/// [`hinge_angle`] of every hinge of `t`, in [`Topology::hinges`] order.
pub fn hinge_angles<P: AsPt3>(t: &Topology, p: &[P]) -> Vec<f64> {
    t.hinges()
        .iter()
        .map(|h| {
            hinge_angle(&[
                p[h[0] as usize].pt3(),
                p[h[1] as usize].pt3(),
                p[h[2] as usize].pt3(),
                p[h[3] as usize].pt3(),
            ])
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// shells.md §7 test 3 (`hinge_sign`).
    #[test]
    fn hinge_sign() {
        let a = Pt3::new(0., 0., 0.);
        let b = Pt3::new(1., 0., 0.);
        let w1 = Pt3::new(0.5, 1., 0.);
        let w2 = Pt3::new(0.5, -1., 0.);
        assert_eq!(hinge_angle(&[a, b, w1, w2]), 0.0);
        let up = crate::math::Vec3::new(0., 0., 0.1);
        let t1 = hinge_angle(&[a, b, w1 + up, w2]);
        let t2 = hinge_angle(&[a, b, w1, w2 + up]);
        // 1e-12 absolute (spec); the computation is a handful of exact products plus one atan2.
        assert!((t1 - 0.1f64.atan()).abs() < 1e-12, "{t1}");
        assert!((t2 - 0.1f64.atan()).abs() < 1e-12, "{t2}");
        assert!(t1 > 0.0 && t2 > 0.0);
    }

    #[test]
    fn collapsed_wing_is_none_not_nan() {
        let a = Pt3::new(0., 0., 0.);
        let b = Pt3::new(1., 0., 0.);
        // w1 on the edge line: wing 1 has zero area.
        let x = [a, b, Pt3::new(0.3, 0., 0.), Pt3::new(0.5, -1., 0.)];
        assert_eq!(hinge_angle_checked(&x), None);
        assert_eq!(hinge_angle(&x), 0.0);
        // Zero-length hinge edge.
        let y = [a, a, Pt3::new(0.5, 1., 0.), Pt3::new(0.5, -1., 0.)];
        assert_eq!(hinge_angle_checked(&y), None);
        // NaN input.
        let z = [a, b, Pt3::new(f64::NAN, 1., 0.), Pt3::new(0.5, -1., 0.)];
        assert_eq!(hinge_angle_checked(&z), None);
        assert_eq!(hinge_angle(&z), 0.0);
    }

    #[test]
    fn full_range_and_sign_symmetry() {
        // Fold w1 around the x axis by angle φ: θ = φ for φ in (−π, π).
        let a = Pt3::new(0., 0., 0.);
        let b = Pt3::new(2., 0., 0.);
        let w2 = Pt3::new(0.7, -1., 0.);
        for i in -17..=17 {
            let phi = i as f64 * 0.18;
            let w1 = Pt3::new(1.3, phi.cos(), phi.sin());
            let th = hinge_angle(&[a, b, w1, w2]);
            // Rotating w1 by φ rotates n̂₁ by φ about ê; 1e-14 covers sin/cos round-off.
            assert!((th - phi).abs() < 1e-14, "phi {phi} theta {th}");
        }
    }
}

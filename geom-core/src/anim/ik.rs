//! Analytic inverse kinematics: [`two_bone`] (hip–knee–ankle, shoulder–elbow–wrist).

use crate::math::{Pt3, Vec3};

/// Places a two-bone chain: from `root`, bones of lengths `l1` (root → mid) and `l2`
/// (mid → end) reaching for `target`; returns `(mid, end)`.
///
/// The reach `d = |target − root|` is clamped to `[|l1 − l2|, l1 + l2]` (fully stretched or fully
/// folded), so `end` lies on the ray from `root` towards `target` at the clamped distance; it
/// equals `target` whenever the target is reachable. The chain bends in the plane spanned by the
/// reach direction and `pole` (a direction, e.g. "knee forward"): `mid` lies on the side `pole`
/// points to, at the law-of-cosines position `a = (l1² − l2² + d²)/(2d)` along the reach and
/// `h = √(l1² − a²)` across it. Degenerate input never panics: a pole parallel to the reach uses
/// any perpendicular direction; a target on the root uses the pole (or +Y) as the reach
/// direction. Lengths are in the caller's units (m), taken as absolute values.
pub fn two_bone(root: &Pt3, l1: f64, l2: f64, target: &Pt3, pole: &Vec3) -> (Pt3, Pt3) {
    let (l1, l2) = (l1.abs(), l2.abs());
    let to = target - root;
    let dist = to.norm();
    let u = if dist > 1e-300 && dist.is_finite() {
        to / dist
    } else if pole.norm() > 0.0 && pole.norm().is_finite() {
        pole.normalize()
    } else {
        Vec3::y()
    };
    let min_reach = (l1 - l2).abs().max(1e-12 * (l1 + l2));
    let d = if dist.is_finite() { dist.clamp(min_reach, (l1 + l2).max(min_reach)) } else { l1 + l2 };
    let end = root + u * d;
    // Bend direction: the pole's component orthogonal to the reach.
    let w0 = pole - u * pole.dot(&u);
    let w = if w0.norm() > 1e-12 * pole.norm().max(1e-300) && w0.norm().is_finite() && w0.norm() > 0.0 {
        w0.normalize()
    } else {
        // Any perpendicular: cross with the coordinate axis least aligned with u.
        let k = if u.x.abs() <= u.y.abs() && u.x.abs() <= u.z.abs() {
            Vec3::x()
        } else if u.y.abs() <= u.z.abs() {
            Vec3::y()
        } else {
            Vec3::z()
        };
        u.cross(&k).normalize()
    };
    if d <= 0.0 {
        // Both bones of zero length.
        return (*root, *root);
    }
    let a = (l1 * l1 - l2 * l2 + d * d) / (2.0 * d);
    let h = (l1 * l1 - a * a).max(0.0).sqrt();
    let mid = root + u * a + w * h;
    (mid, end)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reachable_target_is_hit_with_exact_bone_lengths() {
        let root = Pt3::new(0.1, 0.9, 0.0);
        let target = Pt3::new(0.15, 0.2, 0.3);
        let (mid, end) = two_bone(&root, 0.42, 0.40, &target, &Vec3::z());
        assert!((end - target).norm() < 1e-15);
        assert!(((mid - root).norm() - 0.42).abs() < 1e-14);
        assert!(((end - mid).norm() - 0.40).abs() < 1e-14);
        // Bends towards the pole (knee forward, +Z).
        let along = (target - root).normalize();
        let off = (mid - root) - along * (mid - root).dot(&along);
        assert!(off.z > 0.0);
    }

    #[test]
    fn unreachable_targets_are_clamped() {
        let root = Pt3::origin();
        // Too far: fully stretched along the reach.
        let (mid, end) = two_bone(&root, 1.0, 1.0, &Pt3::new(5.0, 0.0, 0.0), &Vec3::y());
        assert!((end - Pt3::new(2.0, 0.0, 0.0)).norm() < 1e-12);
        assert!((mid - Pt3::new(1.0, 0.0, 0.0)).norm() < 1e-6);
        // Too close for unequal bones: folded, end at distance |l1 − l2|.
        let (mid, end) = two_bone(&root, 1.0, 0.5, &Pt3::new(0.1, 0.0, 0.0), &Vec3::y());
        assert!((end.coords.norm() - 0.5).abs() < 1e-12);
        assert!(((mid - root).norm() - 1.0).abs() < 1e-6);
    }

    #[test]
    fn degenerate_inputs_do_not_panic() {
        let root = Pt3::origin();
        // Pole parallel to the reach.
        let (mid, end) = two_bone(&root, 1.0, 1.0, &Pt3::new(0.0, 1.0, 0.0), &Vec3::y());
        assert!(((mid - root).norm() - 1.0).abs() < 1e-12 && (end - Pt3::new(0.0, 1.0, 0.0)).norm() < 1e-12);
        // Target on the root, zero pole.
        let (mid, end) = two_bone(&root, 1.0, 1.0, &root, &Vec3::zeros());
        assert!(mid.coords.iter().all(|c| c.is_finite()) && end.coords.iter().all(|c| c.is_finite()));
        // Zero-length bones, non-finite target.
        let (mid, end) = two_bone(&root, 0.0, 0.0, &Pt3::new(1.0, 0.0, 0.0), &Vec3::z());
        assert_eq!((mid, end), (root, root));
        let (mid, end) = two_bone(&root, 1.0, 1.0, &Pt3::new(f64::NAN, 0.0, 0.0), &Vec3::z());
        assert!(mid.coords.iter().all(|c| c.is_finite()) && end.coords.iter().all(|c| c.is_finite()));
    }
}

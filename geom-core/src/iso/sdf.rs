//! Analytic signed distance functions (negative inside) and their combinators.
//!
//! The primitives are exact Euclidean distances except [`ellipsoid`] (the usual first-order
//! bound, exact on the surface, Lipschitz ≈ 1 near it). [`smooth_min`] is the polynomial smooth
//! minimum: it equals `min(a, b)` when `|a − b| ≥ k` and lowers the value by at most `k/4`.

use crate::math::{Iso3, Pt3, Vec3};

/// Sphere of centre `c` and radius `r`.
pub fn sphere(p: &Pt3, c: &Pt3, r: f64) -> f64 {
    (p - c).norm() - r
}

/// Capsule: all points within `r` of the segment `ab`.
pub fn capsule(p: &Pt3, a: &Pt3, b: &Pt3, r: f64) -> f64 {
    let (_, q) = crate::query::closest_point_segment(p, a, b);
    (p - q).norm() - r
}

/// Round cone (tapered capsule): the convex hull of the spheres `(a, ra)` and `(b, rb)`; exact
/// distance (Quílez's closed form). When one sphere contains the other, the larger sphere.
pub fn round_cone(p: &Pt3, a: &Pt3, b: &Pt3, ra: f64, rb: f64) -> f64 {
    let ba = b - a;
    let l2 = ba.norm_squared();
    let rr = ra - rb;
    let a2 = l2 - rr * rr;
    if a2 <= 0.0 {
        // One sphere contains the other (or the segment is degenerate).
        return sphere(p, a, ra).min(sphere(p, b, rb));
    }
    let il2 = 1.0 / l2;
    let pa = p - a;
    let y = pa.dot(&ba);
    let z = y - l2;
    let x2 = (pa * l2 - ba * y).norm_squared();
    let y2 = y * y * l2;
    let z2 = z * z * l2;
    let k = rr.signum() * rr * rr * x2;
    if z.signum() * a2 * z2 > k {
        return (x2 + z2).sqrt() * il2 - rb;
    }
    if y.signum() * a2 * y2 < k {
        return (x2 + y2).sqrt() * il2 - ra;
    }
    ((x2 * a2 * il2).sqrt() + y * rr) * il2 - ra
}

/// Ellipsoid with pose `pose` (local → world) and semi-axes `r` (local x, y, z); the standard
/// bound `k0 (k0 − 1) / k1` with `k0 = |q / r|`, `k1 = |q / r²|` (exact on the surface).
pub fn ellipsoid(p: &Pt3, pose: &Iso3, r: &Vec3) -> f64 {
    let q = pose.inverse_transform_point(p);
    let k0 = Vec3::new(q.x / r.x, q.y / r.y, q.z / r.z).norm();
    let k1 = Vec3::new(q.x / (r.x * r.x), q.y / (r.y * r.y), q.z / (r.z * r.z)).norm();
    if k1 == 0.0 {
        return -r.min();
    }
    k0 * (k0 - 1.0) / k1
}

/// Axis-aligned box (in the frame `pose`) with half extents `half`; exact.
pub fn cuboid(p: &Pt3, pose: &Iso3, half: &Vec3) -> f64 {
    let q = pose.inverse_transform_point(p);
    let d = Vec3::new(q.x.abs() - half.x, q.y.abs() - half.y, q.z.abs() - half.z);
    let outside = Vec3::new(d.x.max(0.0), d.y.max(0.0), d.z.max(0.0)).norm();
    outside + d.max().min(0.0)
}

/// Flat-capped cylinder with axis segment `ab` and radius `r`; exact.
pub fn cylinder(p: &Pt3, a: &Pt3, b: &Pt3, r: f64) -> f64 {
    let ba = b - a;
    let l = ba.norm();
    if l == 0.0 {
        return sphere(p, a, r);
    }
    let u = ba / l;
    let t = (p - a).dot(&u);
    let radial = ((p - a) - u * t).norm() - r;
    let axial = (t - l * 0.5).abs() - l * 0.5;
    let o = (radial.max(0.0).powi(2) + axial.max(0.0).powi(2)).sqrt();
    o + radial.max(axial).min(0.0)
}

/// Polynomial smooth minimum with blend width `k` (≥ 0): `min(a, b) − h² k / 4`,
/// `h = max(k − |a − b|, 0) / k`. `k = 0` is the plain minimum.
pub fn smooth_min(a: f64, b: f64, k: f64) -> f64 {
    if k <= 0.0 {
        return a.min(b);
    }
    let h = (k - (a - b).abs()).max(0.0) / k;
    a.min(b) - h * h * k * 0.25
}

/// Union of two solids: `min(a, b)`.
pub fn union(a: f64, b: f64) -> f64 {
    a.min(b)
}

/// Intersection of two solids: `max(a, b)`.
pub fn intersect(a: f64, b: f64) -> f64 {
    a.max(b)
}

/// `a` minus `b`: `max(a, −b)`.
pub fn subtract(a: f64, b: f64) -> f64 {
    a.max(-b)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_cone_matches_capsule_and_spheres() {
        let a = Pt3::new(0.1, -0.2, 0.3);
        let b = Pt3::new(0.7, 0.4, -0.1);
        let mut rng = crate::rng::Rng::new(7);
        for _ in 0..500 {
            let p = Pt3::new(rng.range(-1.0, 1.5), rng.range(-1.0, 1.5), rng.range(-1.0, 1.5));
            // Equal radii: a capsule (the formulas differ, so agreement is to rounding).
            assert!((round_cone(&p, &a, &b, 0.2, 0.2) - capsule(&p, &a, &b, 0.2)).abs() < 1e-12);
            // Tapered: bounded by the two end spheres' union from below and exact on the axis ends.
            let d = round_cone(&p, &a, &b, 0.3, 0.1);
            assert!(d <= sphere(&p, &a, 0.3).min(sphere(&p, &b, 0.1)) + 1e-12);
        }
        // Points beyond the small end along the axis: distance to the small sphere.
        let u = (b - a).normalize();
        let p = b + u * 0.5;
        assert!((round_cone(&p, &a, &b, 0.3, 0.1) - 0.4).abs() < 1e-12);
    }

    #[test]
    fn boxes_cylinders_ellipsoids_and_combinators() {
        let id = Iso3::identity();
        assert!((cuboid(&Pt3::origin(), &id, &Vec3::new(1.0, 2.0, 3.0)) + 1.0).abs() < 1e-15);
        assert!((cuboid(&Pt3::new(2.0, 3.0, 0.0), &id, &Vec3::new(1.0, 2.0, 3.0)) - 2f64.sqrt()).abs() < 1e-15);
        let a = Pt3::origin();
        let b = Pt3::new(0.0, 2.0, 0.0);
        assert!((cylinder(&Pt3::new(0.0, 1.0, 0.0), &a, &b, 0.5) + 0.5).abs() < 1e-15);
        assert!((cylinder(&Pt3::new(0.0, 3.0, 0.0), &a, &b, 0.5) - 1.0).abs() < 1e-15);
        let r = Vec3::new(1.0, 2.0, 3.0);
        for p in [Pt3::new(1.0, 0.0, 0.0), Pt3::new(0.0, 2.0, 0.0), Pt3::new(0.0, 0.0, -3.0)] {
            assert!(ellipsoid(&p, &id, &r).abs() < 1e-15);
        }
        assert!(ellipsoid(&Pt3::origin(), &id, &r) < 0.0);
        assert_eq!(smooth_min(0.0, 5.0, 1.0), 0.0);
        assert!((smooth_min(0.3, 0.3, 1.0) - (0.3 - 0.25)).abs() < 1e-15);
        assert_eq!(union(1.0, 2.0), 1.0);
        assert_eq!(intersect(1.0, 2.0), 2.0);
        assert_eq!(subtract(1.0, 2.0), 1.0);
    }
}

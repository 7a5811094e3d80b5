//! Closest-point routines used by the collision pipeline (Ericson, *Real-Time Collision
//! Detection*, §5.1.5 and §5.1.9). Should move to `geom_core::query` once it provides them with
//! the same conventions (barycentrics, clamped segment parameters).

use geom_core::math::{Pt3, Vec3};

/// Closest point on triangle `t` to `p` and its barycentric weights (w₀, w₁, w₂), summing to 1.
pub fn closest_point_triangle(p: &Pt3, t: &[Pt3; 3]) -> (Pt3, [f64; 3]) {
    let (a, b, c) = (t[0], t[1], t[2]);
    let ab = b - a;
    let ac = c - a;
    let ap = p - a;
    let d1 = ab.dot(&ap);
    let d2 = ac.dot(&ap);
    if d1 <= 0.0 && d2 <= 0.0 {
        return (a, [1.0, 0.0, 0.0]);
    }
    let bp = p - b;
    let d3 = ab.dot(&bp);
    let d4 = ac.dot(&bp);
    if d3 >= 0.0 && d4 <= d3 {
        return (b, [0.0, 1.0, 0.0]);
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        let v = d1 / (d1 - d3);
        return (a + v * ab, [1.0 - v, v, 0.0]);
    }
    let cp = p - c;
    let d5 = ab.dot(&cp);
    let d6 = ac.dot(&cp);
    if d6 >= 0.0 && d5 <= d6 {
        return (c, [0.0, 0.0, 1.0]);
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        let w = d2 / (d2 - d6);
        return (a + w * ac, [1.0 - w, 0.0, w]);
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        let w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        return (b + w * (c - b), [0.0, 1.0 - w, w]);
    }
    let denom = va + vb + vc;
    if !(denom.abs() > 0.0) {
        // Degenerate (collapsed) triangle: fall back to the closest of its edges.
        let mut best = (a, [1.0, 0.0, 0.0], (p - a).norm_squared());
        for (i, j) in [(0usize, 1usize), (1, 2), (2, 0)] {
            let (s, q) = closest_point_segment(p, &t[i], &t[j]);
            let d = (p - q).norm_squared();
            if d < best.2 {
                let mut w = [0.0; 3];
                w[i] = 1.0 - s;
                w[j] = s;
                best = (q, w, d);
            }
        }
        return (best.0, best.1);
    }
    let v = vb / denom;
    let w = vc / denom;
    (a + ab * v + ac * w, [1.0 - v - w, v, w])
}

/// Closest point on segment a–b to p: (parameter s ∈ [0, 1], point).
pub fn closest_point_segment(p: &Pt3, a: &Pt3, b: &Pt3) -> (f64, Pt3) {
    let ab = b - a;
    let l2 = ab.norm_squared();
    if l2 == 0.0 {
        return (0.0, *a);
    }
    let s = ((p - a).dot(&ab) / l2).clamp(0.0, 1.0);
    (s, a + s * ab)
}

/// Closest points of segments p0–p1 and q0–q1: (s, t, point on first, point on second), with
/// s, t ∈ [0, 1]; parallel segments handled by clamping.
pub fn closest_points_segments(p0: &Pt3, p1: &Pt3, q0: &Pt3, q1: &Pt3) -> (f64, f64, Pt3, Pt3) {
    let d1 = p1 - p0;
    let d2 = q1 - q0;
    let r = p0 - q0;
    let a = d1.norm_squared();
    let e = d2.norm_squared();
    let f = d2.dot(&r);
    let (s, t);
    if a <= f64::MIN_POSITIVE && e <= f64::MIN_POSITIVE {
        return (0.0, 0.0, *p0, *q0);
    }
    if a <= f64::MIN_POSITIVE {
        s = 0.0;
        t = (f / e).clamp(0.0, 1.0);
    } else {
        let c = d1.dot(&r);
        if e <= f64::MIN_POSITIVE {
            t = 0.0;
            s = (-c / a).clamp(0.0, 1.0);
        } else {
            let b = d1.dot(&d2);
            let denom = a * e - b * b;
            let mut ss = if denom > 1e-14 * a * e { ((b * f - c * e) / denom).clamp(0.0, 1.0) } else { 0.0 };
            let mut tt = (b * ss + f) / e;
            if tt < 0.0 {
                tt = 0.0;
                ss = (-c / a).clamp(0.0, 1.0);
            } else if tt > 1.0 {
                tt = 1.0;
                ss = ((b - c) / a).clamp(0.0, 1.0);
            }
            s = ss;
            t = tt;
        }
    }
    (s, t, p0 + s * d1, q0 + t * d2)
}

/// A unit vector orthogonal to both inputs when possible, else any unit vector orthogonal to the
/// first non-zero one, else +z: never normalises a zero vector.
pub fn safe_normal(a: &Vec3, b: &Vec3) -> Vec3 {
    let c = a.cross(b);
    let n = c.norm();
    if n > 1e-300 {
        return c / n;
    }
    let base = if a.norm() > 0.0 { *a } else { *b };
    if base.norm() == 0.0 {
        return Vec3::z();
    }
    let other = if base.x.abs() < 0.9 * base.norm() { Vec3::x() } else { Vec3::y() };
    base.cross(&other).normalize()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn triangle_regions() {
        let t = [Pt3::new(0.0, 0.0, 0.0), Pt3::new(1.0, 0.0, 0.0), Pt3::new(0.0, 1.0, 0.0)];
        let (c, w) = closest_point_triangle(&Pt3::new(0.2, 0.3, 1.0), &t);
        assert!((c - Pt3::new(0.2, 0.3, 0.0)).norm() < 1e-15);
        assert!((w[0] - 0.5).abs() < 1e-15 && (w[1] - 0.2).abs() < 1e-15);
        let (c, w) = closest_point_triangle(&Pt3::new(2.0, -1.0, 0.0), &t);
        assert_eq!(c, t[1]);
        assert_eq!(w, [0.0, 1.0, 0.0]);
        let (c, _) = closest_point_triangle(&Pt3::new(1.0, 1.0, 0.5), &t);
        assert!((c - Pt3::new(0.5, 0.5, 0.0)).norm() < 1e-15);
    }

    #[test]
    fn segments() {
        let (s, t, a, b) = closest_points_segments(
            &Pt3::new(0.0, 0.0, 0.0),
            &Pt3::new(1.0, 0.0, 0.0),
            &Pt3::new(0.5, -1.0, 1.0),
            &Pt3::new(0.5, 1.0, 1.0),
        );
        assert!((s - 0.5).abs() < 1e-15 && (t - 0.5).abs() < 1e-15);
        assert!(((a - b).norm() - 1.0).abs() < 1e-15);
        // Parallel.
        let (_, _, a, b) = closest_points_segments(
            &Pt3::new(0.0, 0.0, 0.0),
            &Pt3::new(1.0, 0.0, 0.0),
            &Pt3::new(0.5, 1.0, 0.0),
            &Pt3::new(1.5, 1.0, 0.0),
        );
        assert!(((a - b).norm() - 1.0).abs() < 1e-15);
        assert_eq!(safe_normal(&Vec3::zeros(), &Vec3::zeros()), Vec3::z());
        assert!((safe_normal(&Vec3::x(), &Vec3::x()).norm() - 1.0).abs() < 1e-15);
    }
}

//! Closest points between points, segments and triangles (Ericson, *Real-Time Collision
//! Detection*, 2005, §5.1.2, §5.1.5, §5.1.9).

use crate::math::{Pt3, Vec3};

/// Closest point to `p` on the closed segment `[a, b]`: `(t, a + t (b − a))` with `t ∈ [0, 1]`.
/// A zero-length segment gives `(0, a)`; `t = 1` returns `b` exactly.
pub fn closest_point_segment(p: &Pt3, a: &Pt3, b: &Pt3) -> (f64, Pt3) {
    let ab = b - a;
    let denom = ab.norm_squared();
    if denom <= 0.0 {
        return (0.0, *a);
    }
    let t = ((p - a).dot(&ab) / denom).clamp(0.0, 1.0);
    (t, lerp(a, b, &ab, t))
}

/// `a + t (b − a)`, returning the end points exactly at `t = 0` and `t = 1`.
#[inline]
fn lerp(a: &Pt3, b: &Pt3, ab: &Vec3, t: f64) -> Pt3 {
    if t <= 0.0 {
        *a
    } else if t >= 1.0 {
        *b
    } else {
        a + ab * t
    }
}

/// Closest points between the closed segments `[p0, p1]` and `[q0, q1]`:
/// `(s, t, c1, c2)` with `c1 = p0 + s (p1 − p0)`, `c2 = q0 + t (q1 − q0)`, `s, t ∈ [0, 1]`.
///
/// When the lines are not (nearly) parallel and their closest points fall inside both
/// segments, this is Ericson's closed form. Otherwise the minimum of the convex distance lies on
/// the boundary of `[0, 1]²`, i.e. at an end point of one segment, and the best of the four end
/// point–segment projections is returned (first of p0, p1, q0, q1 on ties). This handles parallel
/// and degenerate (zero-length) segments without a tolerance on the answer: for parallel
/// overlapping segments one valid closest pair is returned.
pub fn closest_points_segments(p0: &Pt3, p1: &Pt3, q0: &Pt3, q1: &Pt3) -> (f64, f64, Pt3, Pt3) {
    let d1 = p1 - p0;
    let d2 = q1 - q0;
    let r = p0 - q0;
    let a = d1.norm_squared();
    let e = d2.norm_squared();
    let b = d1.dot(&d2);
    let c = d1.dot(&r);
    let f = d2.dot(&r);
    let denom = a * e - b * b;
    // Non-parallel: sin²(angle) above ~1e-14 (below it the closed form loses all accuracy).
    if a > 0.0 && e > 0.0 && denom > 1e-14 * a * e {
        let s = (b * f - c * e) / denom;
        let t = (a * f - b * c) / denom;
        if (0.0..=1.0).contains(&s) && (0.0..=1.0).contains(&t) {
            return (s, t, lerp(p0, p1, &d1, s), lerp(q0, q1, &d2, t));
        }
    }
    let mut best: Option<(f64, f64, f64, Pt3, Pt3)> = None;
    let mut consider = |d2: f64, s: f64, t: f64, c1: Pt3, c2: Pt3| {
        if best.as_ref().is_none_or(|b| d2 < b.0) {
            best = Some((d2, s, t, c1, c2));
        }
    };
    for (s, p) in [(0.0, p0), (1.0, p1)] {
        let (t, c2) = closest_point_segment(p, q0, q1);
        consider((p - c2).norm_squared(), s, t, *p, c2);
    }
    for (t, q) in [(0.0, q0), (1.0, q1)] {
        let (s, c1) = closest_point_segment(q, p0, p1);
        consider((q - c1).norm_squared(), s, t, c1, *q);
    }
    // Four candidates were considered, so `best` is set.
    let (_, s, t, c1, c2) = best.expect("four candidates considered");
    (s, t, c1, c2)
}

/// Closest point to `p` on the closed triangle `t = [a, b, c]`, with its barycentric
/// coordinates `[u, v, w]` (`point = u a + v b + w c`, all ≥ 0, summing to 1).
///
/// Ericson's Voronoi-region method: vertex regions, then edge regions, then the face, each
/// decided by dot products, without computing the plane first. Degenerate triangles (zero area,
/// or an angle below 1e-10 rad at the first corner) are treated as the union of their three
/// edges.
pub fn closest_point_triangle(p: &Pt3, t: &[Pt3; 3]) -> (Pt3, [f64; 3]) {
    let (a, b, c) = (&t[0], &t[1], &t[2]);
    let ab = b - a;
    let ac = c - a;
    // Ericson's region tests assume a proper triangle; a (numerically) flat one, with
    // sin²(angle at a) ≤ 1e-20, is the union of its edges.
    let n2 = ab.cross(&ac).norm_squared();
    // (Written so that NaN input also takes the fallback.)
    if n2.partial_cmp(&(1e-20 * ab.norm_squared() * ac.norm_squared())) != Some(std::cmp::Ordering::Greater) {
        return closest_on_edges(p, t);
    }
    let ap = p - a;
    let d1 = ab.dot(&ap);
    let d2 = ac.dot(&ap);
    if d1 <= 0.0 && d2 <= 0.0 {
        return (*a, [1.0, 0.0, 0.0]);
    }
    let bp = p - b;
    let d3 = ab.dot(&bp);
    let d4 = ac.dot(&bp);
    if d3 >= 0.0 && d4 <= d3 {
        return (*b, [0.0, 1.0, 0.0]);
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 && d1 - d3 > 0.0 {
        let v = d1 / (d1 - d3);
        return (lerp(a, b, &ab, v), [1.0 - v, v, 0.0]);
    }
    let cp = p - c;
    let d5 = ab.dot(&cp);
    let d6 = ac.dot(&cp);
    if d6 >= 0.0 && d5 <= d6 {
        return (*c, [0.0, 0.0, 1.0]);
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 && d2 - d6 > 0.0 {
        let w = d2 / (d2 - d6);
        return (lerp(a, c, &ac, w), [1.0 - w, 0.0, w]);
    }
    let va = d3 * d6 - d5 * d4;
    let (e1, e2) = (d4 - d3, d5 - d6);
    if va <= 0.0 && e1 >= 0.0 && e2 >= 0.0 && e1 + e2 > 0.0 {
        let w = e1 / (e1 + e2);
        return (lerp(b, c, &(c - b), w), [0.0, 1.0 - w, w]);
    }
    let denom = va + vb + vc;
    if denom > 0.0 && va >= 0.0 && vb >= 0.0 && vc >= 0.0 {
        let v = vb / denom;
        let w = vc / denom;
        return (a + ab * v + ac * w, [1.0 - v - w, v, w]);
    }
    closest_on_edges(p, t)
}

/// Best of the three edges (degenerate triangles and rounding-inconsistent region tests).
fn closest_on_edges(p: &Pt3, t: &[Pt3; 3]) -> (Pt3, [f64; 3]) {
    let mut best = (f64::INFINITY, t[0], [1.0, 0.0, 0.0]);
    for i in 0..3 {
        let j = (i + 1) % 3;
        let (s, q) = closest_point_segment(p, &t[i], &t[j]);
        let d2 = (p - q).norm_squared();
        if d2 < best.0 {
            let mut bary = [0.0; 3];
            bary[i] = 1.0 - s;
            bary[j] = s;
            best = (d2, q, bary);
        }
    }
    (best.1, best.2)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn triangle_regions() {
        let t = [Pt3::new(0.0, 0.0, 0.0), Pt3::new(1.0, 0.0, 0.0), Pt3::new(0.0, 1.0, 0.0)];
        let (q, b) = closest_point_triangle(&Pt3::new(0.25, 0.25, 3.0), &t);
        assert_eq!(q, Pt3::new(0.25, 0.25, 0.0));
        assert_eq!(b, [0.5, 0.25, 0.25]);
        assert_eq!(closest_point_triangle(&Pt3::new(-1.0, -1.0, 0.5), &t).1, [1.0, 0.0, 0.0]);
        assert_eq!(closest_point_triangle(&Pt3::new(2.0, -1.0, 0.5), &t).1, [0.0, 1.0, 0.0]);
        assert_eq!(closest_point_triangle(&Pt3::new(-1.0, 2.0, 0.5), &t).1, [0.0, 0.0, 1.0]);
        let (q, b) = closest_point_triangle(&Pt3::new(0.5, -1.0, 0.0), &t);
        assert_eq!(q, Pt3::new(0.5, 0.0, 0.0));
        assert_eq!(b, [0.5, 0.5, 0.0]);
        let (q, b) = closest_point_triangle(&Pt3::new(1.0, 1.0, 0.0), &t);
        assert_eq!(q, Pt3::new(0.5, 0.5, 0.0));
        assert_eq!(b, [0.0, 0.5, 0.5]);
    }

    #[test]
    fn degenerate_triangle_uses_edges() {
        let t = [Pt3::new(0.0, 0.0, 0.0), Pt3::new(1.0, 0.0, 0.0), Pt3::new(2.0, 0.0, 0.0)];
        let (q, b) = closest_point_triangle(&Pt3::new(1.5, 1.0, 0.0), &t);
        assert_eq!(q, Pt3::new(1.5, 0.0, 0.0));
        let r = t[0].coords * b[0] + t[1].coords * b[1] + t[2].coords * b[2];
        assert!((r - q.coords).norm() < 1e-15);
        let single = [Pt3::new(1.0, 2.0, 3.0); 3];
        assert_eq!(closest_point_triangle(&Pt3::origin(), &single).0, single[0]);
    }

    #[test]
    fn parallel_and_degenerate_segments() {
        let (p0, p1) = (Pt3::new(0.0, 0.0, 0.0), Pt3::new(2.0, 0.0, 0.0));
        let (q0, q1) = (Pt3::new(1.0, 1.0, 0.0), Pt3::new(3.0, 1.0, 0.0));
        let (s, t, c1, c2) = closest_points_segments(&p0, &p1, &q0, &q1);
        assert_eq!((c1 - c2).norm(), 1.0);
        assert!((c1 - (p0 + (p1 - p0) * s)).norm() < 1e-15 && (c2 - (q0 + (q1 - q0) * t)).norm() < 1e-15);
        let (_, _, c1, c2) = closest_points_segments(&p0, &p0, &q0, &q0);
        assert_eq!((c1, c2), (p0, q0));
        // Crossing segments: distance is the offset along z.
        let (s, t, c1, c2) = closest_points_segments(
            &Pt3::new(-1.0, 0.0, 0.0),
            &Pt3::new(1.0, 0.0, 0.0),
            &Pt3::new(0.0, -1.0, 0.5),
            &Pt3::new(0.0, 1.0, 0.5),
        );
        assert_eq!((s, t), (0.5, 0.5));
        assert_eq!((c1, c2), (Pt3::new(0.0, 0.0, 0.0), Pt3::new(0.0, 0.0, 0.5)));
    }
}

//! Exact triangle–triangle (and segment–triangle) intersection tests built on the orientation
//! predicates only, so that every decision is exact for the given `f64` coordinates.
//!
//! Method. Two closed convex sets in 3-D whose boundaries are made of edges intersect iff an edge
//! of one meets the other: for non-coplanar triangles the intersection is a segment on the line
//! shared by both planes whose end points lie on edges; for coplanar ones either the boundaries
//! cross or one triangle holds a vertex of the other. Segment–triangle tests use the signs of
//! `orient3d` (the segment's end points against the plane, then the segment's line against the
//! three edges, Plücker style); coplanar cases drop the coordinate along which the plane's normal
//! is non-zero (decided exactly by a 2-D orientation) and use `orient2d`. Dropping a coordinate
//! involves no arithmetic, so the projection is exact and preserves incidences.
//! Degenerate triangles (collinear or coincident corners) are treated as the segment or point
//! they are.

use std::cmp::Ordering;

use super::predicates::{orient2d_dropped, orient3d, sign};
use crate::math::Pt3;

/// A triangle reduced to what it actually is.
enum Simplex {
    Point(Pt3),
    Segment(Pt3, Pt3),
    /// Non-degenerate triangle and an axis whose removal projects its plane injectively.
    Triangle([Pt3; 3], usize),
}

/// Lexicographic order on (x, y, z); along a line it is the order of the line parameter (or its
/// reverse), so it orders collinear points exactly. (`-0.0` equals `0.0`; NaN compares equal.)
fn lex(a: &Pt3, b: &Pt3) -> Ordering {
    let c = |x: f64, y: f64| x.partial_cmp(&y).unwrap_or(Ordering::Equal);
    c(a.x, b.x).then(c(a.y, b.y)).then(c(a.z, b.z))
}

fn lex_min<'a>(a: &'a Pt3, b: &'a Pt3) -> &'a Pt3 {
    if lex(a, b) == Ordering::Greater {
        b
    } else {
        a
    }
}

fn lex_max<'a>(a: &'a Pt3, b: &'a Pt3) -> &'a Pt3 {
    if lex(a, b) == Ordering::Greater {
        a
    } else {
        b
    }
}

/// `true` if `a, b, c` are collinear (exact: every component of `(b − a) × (c − a)` is zero).
fn collinear(a: &Pt3, b: &Pt3, c: &Pt3) -> bool {
    (0..3).all(|d| orient2d_dropped(a, b, c, d) == 0)
}

/// For `p` collinear with `a, b`: does `p` lie on the closed segment?
fn between(p: &Pt3, a: &Pt3, b: &Pt3) -> bool {
    lex(lex_min(a, b), p) != Ordering::Greater && lex(p, lex_max(a, b)) != Ordering::Greater
}

fn classify(t: &[Pt3; 3]) -> Simplex {
    if let Some(drop) = (0..3).find(|&d| orient2d_dropped(&t[0], &t[1], &t[2], d) != 0) {
        return Simplex::Triangle(*t, drop);
    }
    // Collinear: the extreme points in lexicographic order span the segment.
    let mut lo = &t[0];
    let mut hi = &t[0];
    for p in &t[1..] {
        lo = lex_min(lo, p);
        hi = lex_max(hi, p);
    }
    if lo == hi {
        Simplex::Point(*lo)
    } else {
        Simplex::Segment(*lo, *hi)
    }
}

/// 2-D closed point-in-triangle test in the projection dropping `drop` (`p` in the plane).
fn point_in_tri_2d(p: &Pt3, t: &[Pt3; 3], drop: usize) -> bool {
    let s = orient2d_dropped(&t[0], &t[1], &t[2], drop);
    (0..3).all(|i| orient2d_dropped(&t[i], &t[(i + 1) % 3], p, drop) != -s)
}

/// 2-D closed segment–segment test in the projection dropping `drop` (all points coplanar and
/// the projection injective on their plane).
fn seg_seg_2d(p1: &Pt3, q1: &Pt3, p2: &Pt3, q2: &Pt3, drop: usize) -> bool {
    let d1 = orient2d_dropped(p2, q2, p1, drop);
    let d2 = orient2d_dropped(p2, q2, q1, drop);
    let d3 = orient2d_dropped(p1, q1, p2, drop);
    let d4 = orient2d_dropped(p1, q1, q2, drop);
    if d1 * d2 < 0 && d3 * d4 < 0 {
        return true;
    }
    (d1 == 0 && between(p1, p2, q2))
        || (d2 == 0 && between(q1, p2, q2))
        || (d3 == 0 && between(p2, p1, q1))
        || (d4 == 0 && between(q2, p1, q1))
}

/// Closed segment–segment test in 3-D (segments non-degenerate).
fn seg_seg_3d(p1: &Pt3, q1: &Pt3, p2: &Pt3, q2: &Pt3) -> bool {
    if orient3d(p1, q1, p2, q2) != 0.0 {
        return false;
    }
    // Coplanar. Find a non-collinear triple and an axis along which its normal is non-zero.
    for r in [p2, q2] {
        if let Some(drop) = (0..3).find(|&d| orient2d_dropped(p1, q1, r, d) != 0) {
            return seg_seg_2d(p1, q1, p2, q2, drop);
        }
    }
    // All four points collinear: compare the intervals along the line.
    lex(lex_max(lex_min(p1, q1), lex_min(p2, q2)), lex_min(lex_max(p1, q1), lex_max(p2, q2))) != Ordering::Greater
}

fn point_on_segment(p: &Pt3, a: &Pt3, b: &Pt3) -> bool {
    collinear(a, b, p) && between(p, a, b)
}

fn point_in_triangle(p: &Pt3, t: &[Pt3; 3], drop: usize) -> bool {
    orient3d(&t[0], &t[1], &t[2], p) == 0.0 && point_in_tri_2d(p, t, drop)
}

/// Closed segment–triangle test (segment may be degenerate; triangle non-degenerate).
fn seg_tri(p: &Pt3, q: &Pt3, t: &[Pt3; 3], drop: usize) -> bool {
    let sp = sign(orient3d(&t[0], &t[1], &t[2], p));
    let sq = sign(orient3d(&t[0], &t[1], &t[2], q));
    if sp * sq > 0 {
        return false;
    }
    if sp == 0 && sq == 0 {
        return point_in_tri_2d(p, t, drop)
            || point_in_tri_2d(q, t, drop)
            || (0..3).any(|i| seg_seg_2d(p, q, &t[i], &t[(i + 1) % 3], drop));
    }
    // The segment meets the plane in one point, inside the closed triangle iff the segment's
    // line does not pass strictly on both sides of the edges.
    let mut pos = false;
    let mut neg = false;
    for i in 0..3 {
        match sign(orient3d(p, q, &t[i], &t[(i + 1) % 3])) {
            1 => pos = true,
            -1 => neg = true,
            _ => {}
        }
    }
    !(pos && neg)
}

/// Closed test for two non-degenerate triangles.
fn tri_tri(a: &[Pt3; 3], da: usize, b: &[Pt3; 3], db: usize) -> bool {
    let sb: [i8; 3] = std::array::from_fn(|i| sign(orient3d(&a[0], &a[1], &a[2], &b[i])));
    if sb.iter().all(|&s| s > 0) || sb.iter().all(|&s| s < 0) {
        return false;
    }
    let sa: [i8; 3] = std::array::from_fn(|i| sign(orient3d(&b[0], &b[1], &b[2], &a[i])));
    if sa.iter().all(|&s| s > 0) || sa.iter().all(|&s| s < 0) {
        return false;
    }
    if sb.iter().all(|&s| s == 0) {
        // Coplanar: boundaries cross, or one holds a vertex of the other.
        return (0..3).any(|i| (0..3).any(|j| seg_seg_2d(&a[i], &a[(i + 1) % 3], &b[j], &b[(j + 1) % 3], da)))
            || point_in_tri_2d(&a[0], b, da)
            || point_in_tri_2d(&b[0], a, da);
    }
    (0..3).any(|i| seg_tri(&a[i], &a[(i + 1) % 3], b, db)) || (0..3).any(|i| seg_tri(&b[i], &b[(i + 1) % 3], a, da))
}

/// Exact test whether two closed triangles share a point.
///
/// Coplanar triangles are included, and touching counts as intersecting (a shared vertex, a
/// shared edge, a vertex on the other's edge or face all return `true`). Degenerate triangles
/// (collinear or coincident corners) are tested as the segment or point they are. Exact for
/// finite coordinates: every decision is the sign of an exact orientation predicate; results
/// for NaN or infinite coordinates are unspecified.
pub fn tri_tri_intersect(a: &[Pt3; 3], b: &[Pt3; 3]) -> bool {
    use Simplex::*;
    match (classify(a), classify(b)) {
        (Triangle(ta, da), Triangle(tb, db)) => tri_tri(&ta, da, &tb, db),
        (Triangle(t, d), Segment(p, q)) | (Segment(p, q), Triangle(t, d)) => seg_tri(&p, &q, &t, d),
        (Triangle(t, d), Point(p)) | (Point(p), Triangle(t, d)) => point_in_triangle(&p, &t, d),
        (Segment(p1, q1), Segment(p2, q2)) => seg_seg_3d(&p1, &q1, &p2, &q2),
        (Segment(a, b), Point(p)) | (Point(p), Segment(a, b)) => point_on_segment(&p, &a, &b),
        (Point(p), Point(q)) => p == q,
    }
}

/// Exact test whether the closed segment `[p, q]` and the closed triangle `t` share a point
/// (touching included; degenerate inputs handled as in [`tri_tri_intersect`]).
pub fn segment_triangle_intersect(p: &Pt3, q: &Pt3, t: &[Pt3; 3]) -> bool {
    tri_tri_intersect(&[*p, *q, *q], t)
}

//! Exact orientation predicates (Shewchuk's adaptive arithmetic via the `robust` crate).

use robust::{Coord, Coord3D};

use crate::math::{Pt2, Pt3};

/// Twice the signed area of the 2-D triangle `(a, b, c)`: positive if `a, b, c` run
/// counter-clockwise (in a frame with y up), negative if clockwise, zero if collinear.
///
/// The **sign is exact** (Shewchuk's adaptive predicate); the magnitude is a close
/// approximation of `(b − a) × (c − a)`.
#[inline]
pub fn orient2d(a: &Pt2, b: &Pt2, c: &Pt2) -> f64 {
    robust::orient2d(Coord { x: a.x, y: a.y }, Coord { x: b.x, y: b.y }, Coord { x: c.x, y: c.y })
}

/// Six times the signed volume of the tetrahedron `(a, b, c, d)` in Shewchuk's convention:
/// `det[a − d, b − d, c − d]`, **positive when `d` lies below** the plane through `a, b, c`
/// (the side opposite to the normal `(b − a) × (c − a)`), negative above, zero if coplanar.
///
/// Equivalently `orient3d(a, b, c, d) = −(d − a) · ((b − a) × (c − a))`. The **sign is exact**.
#[inline]
pub fn orient3d(a: &Pt3, b: &Pt3, c: &Pt3, d: &Pt3) -> f64 {
    let k = |p: &Pt3| Coord3D { x: p.x, y: p.y, z: p.z };
    robust::orient3d(k(a), k(b), k(c), k(d))
}

/// Sign of a predicate value as −1, 0 or +1.
#[inline]
pub(crate) fn sign(x: f64) -> i8 {
    if x > 0.0 {
        1
    } else if x < 0.0 {
        -1
    } else {
        0
    }
}

/// Exact sign of the 2-D orientation of `a, b, c` after dropping coordinate `drop` (0, 1 or 2):
/// the projection onto the plane of the two remaining axes, kept in cyclic order
/// (drop x → (y, z), drop y → (z, x), drop z → (x, y)) so that the sign equals the sign of
/// component `drop` of `(b − a) × (c − a)`.
#[inline]
pub(crate) fn orient2d_dropped(a: &Pt3, b: &Pt3, c: &Pt3, drop: usize) -> i8 {
    let (u, v) = ((drop + 1) % 3, (drop + 2) % 3);
    let k = |p: &Pt3| Coord { x: p[u], y: p[v] };
    sign(robust::orient2d(k(a), k(b), k(c)))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn signs_match_conventions() {
        let o = Pt3::origin();
        let (x, y, z) = (Pt3::new(1.0, 0.0, 0.0), Pt3::new(0.0, 1.0, 0.0), Pt3::new(0.0, 0.0, 1.0));
        // Normal of (o, x, y) is +z; a point above (+z) gives a negative value.
        assert!(orient3d(&o, &x, &y, &z) < 0.0);
        assert!(orient3d(&o, &y, &x, &z) > 0.0);
        assert_eq!(orient3d(&o, &x, &y, &Pt3::new(3.0, -7.0, 0.0)), 0.0);
        assert!(orient2d(&Pt2::new(0.0, 0.0), &Pt2::new(1.0, 0.0), &Pt2::new(0.0, 1.0)) > 0.0);
        for drop in 0..3 {
            let n = (x - o).cross(&(z - o));
            assert_eq!(orient2d_dropped(&o, &x, &z, drop), sign(n[drop]));
        }
    }

    #[test]
    fn exact_on_nearly_collinear_points() {
        // Naive evaluation of this classic case returns inconsistent signs under tiny shifts.
        let a = Pt2::new(0.5, 0.5);
        let b = Pt2::new(12.0, 12.0);
        let c = Pt2::new(24.0, 24.0);
        assert_eq!(orient2d(&a, &b, &c), 0.0);
        let c2 = Pt2::new(24.0, 24.0 + 24.0 * f64::EPSILON);
        assert!(orient2d(&a, &b, &c2) > 0.0);
    }
}

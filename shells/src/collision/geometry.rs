//! Contact normals that never normalise a zero vector (shells.md §8, coincident contacts).
//! Closest points come from `geom_core::query`.

use geom_core::math::Vec3;

/// Closest-point routines, re-exported from geom-core (these paths predate geom-core's `query`).
pub use geom_core::query::{closest_point_segment, closest_point_triangle, closest_points_segments};

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
    fn never_zero() {
        assert_eq!(safe_normal(&Vec3::zeros(), &Vec3::zeros()), Vec3::z());
        assert!((safe_normal(&Vec3::x(), &Vec3::x()).norm() - 1.0).abs() < 1e-15);
    }
}

//! Rigid obstacles: signed distance, outward normal and surface velocity at a point, for shapes
//! placed by their kinematic path at a given time (shells.md §3.9 step 4).
//!
//! Plane, sphere and capsule are evaluated analytically (exact, cheaper than a generic contact
//! query); triangle meshes by the closest triangle with the sign of its face normal.

use super::geometry::{closest_point_segment, closest_point_triangle};
use crate::effects::{Obstacle, ObstacleShape};
use geom_core::math::{Iso3, Pt3, Vec3};

/// An obstacle with its motion resolved at the start and end of a step.
pub struct PlacedObstacle<'a> {
    /// The obstacle.
    pub obstacle: &'a Obstacle,
    /// Transform at the end of the step.
    pub pose: Iso3,
    /// Transform at the start of the step.
    pub pose_prev: Iso3,
}

/// Result of a distance query.
#[derive(Clone, Copy, Debug)]
pub struct Proximity {
    /// Signed distance to the surface (m), negative inside.
    pub distance: f64,
    /// Outward unit normal at the closest point.
    pub normal: Vec3,
    /// Closest point on the surface (world).
    pub point: Pt3,
}

impl<'a> PlacedObstacle<'a> {
    /// Places `o` for the step [t − h, t].
    pub fn new(o: &'a Obstacle, t: f64, h: f64) -> Self {
        let (pose, pose_prev) = match &o.motion {
            Some(m) => (m.transform(t), m.transform(t - h)),
            None => (Iso3::identity(), Iso3::identity()),
        };
        Self { obstacle: o, pose, pose_prev }
    }

    /// Signed distance of world point p at the end pose.
    pub fn query(&self, p: &Pt3) -> Proximity {
        let local = self.pose.inverse_transform_point(p);
        let (d, n, c) = local_query(&self.obstacle.shape, &local);
        Proximity { distance: d, normal: self.pose.rotation * n, point: self.pose * c }
    }

    /// Velocity of the obstacle's material point currently at world point p (m/s).
    pub fn velocity_at(&self, p: &Pt3, h: f64) -> Vec3 {
        if self.obstacle.motion.is_none() {
            return Vec3::zeros();
        }
        let local = self.pose.inverse_transform_point(p);
        (p - self.pose_prev * local) / h
    }

    /// True for thin shapes (capsule/sphere radius < `thin` m) that need edge tests.
    pub fn is_thin(&self, thin: f64) -> bool {
        match self.obstacle.shape {
            ObstacleShape::Capsule { radius, .. } | ObstacleShape::Sphere { radius, .. } => radius < thin,
            _ => false,
        }
    }

    /// For a capsule: the closest point on its axis to segment a–b (world), with radius.
    pub fn capsule_axis(&self) -> Option<(Pt3, Pt3, f64)> {
        match self.obstacle.shape {
            ObstacleShape::Capsule { a, b, radius } => Some((self.pose * a, self.pose * b, radius)),
            ObstacleShape::Sphere { center, radius } => Some((self.pose * center, self.pose * center, radius)),
            _ => None,
        }
    }
}

fn local_query(s: &ObstacleShape, p: &Pt3) -> (f64, Vec3, Pt3) {
    match s {
        ObstacleShape::Plane { normal, offset } => {
            let n = normal.normalize();
            let d = n.dot(&p.coords) - offset;
            (d, n, p - d * n)
        }
        ObstacleShape::Sphere { center, radius } => round(p, center, *radius),
        ObstacleShape::Capsule { a, b, radius } => {
            let (_, c) = closest_point_segment(p, a, b);
            round(p, &c, *radius)
        }
        ObstacleShape::Mesh { verts, tris } => {
            let mut best = (f64::INFINITY, Vec3::z(), *p);
            for t in tris {
                let x = t.map(|v| verts[v as usize]);
                let (c, _) = closest_point_triangle(p, &x);
                let d = (p - c).norm();
                if d < best.0.abs() {
                    let fnrm = (x[1] - x[0]).cross(&(x[2] - x[0]));
                    let sgn = if fnrm.dot(&(p - c)) < 0.0 { -1.0 } else { 1.0 };
                    let n = if d > 1e-12 { sgn * (p - c) / d } else { fnrm.normalize() };
                    best = (sgn * d, n, c);
                }
            }
            (best.0, best.1, best.2)
        }
    }
}

fn round(p: &Pt3, c: &Pt3, r: f64) -> (f64, Vec3, Pt3) {
    let d = p - c;
    let l = d.norm();
    let n = if l > 0.0 { d / l } else { Vec3::y() };
    (l - r, n, c + r * n)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::effects::KinematicPath;

    #[test]
    fn analytic_distances() {
        let o = Obstacle {
            shape: ObstacleShape::Capsule { a: Pt3::new(0.0, 0.0, -1.0), b: Pt3::new(0.0, 0.0, 1.0), radius: 0.1 },
            friction: 0.5,
            motion: None,
        };
        let po = PlacedObstacle::new(&o, 0.0, 0.1);
        let q = po.query(&Pt3::new(0.5, 0.0, 0.3));
        assert!((q.distance - 0.4).abs() < 1e-15 && (q.normal - Vec3::x()).norm() < 1e-15);
        let pl = Obstacle {
            shape: ObstacleShape::Plane { normal: Vec3::y(), offset: 0.0 },
            friction: 0.5,
            motion: Some(KinematicPath::Translate { velocity: Vec3::new(0.0, 1.0, 0.0) }),
        };
        let pp = PlacedObstacle::new(&pl, 1.0, 0.5);
        assert!((pp.query(&Pt3::new(3.0, 0.5, 0.0)).distance + 0.5).abs() < 1e-15);
        assert!((pp.velocity_at(&Pt3::new(0.0, 1.0, 0.0), 0.5) - Vec3::y()).norm() < 1e-12);
    }
}

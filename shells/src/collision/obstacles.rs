//! Rigid obstacles: signed distance, outward normal and surface velocity at a point, for shapes
//! placed by their kinematic path at a given time (shells.md §3.9 step 4).
//!
//! Plane, sphere and capsule are evaluated analytically (exact, cheaper than a generic contact
//! query). Closed triangle meshes go through geom-core's [`MeshQuery`] (parry's BVH, sign from
//! angle-weighted pseudo-normals); open meshes, which have no inside, through the closest
//! triangle with the sign of its face normal.

use crate::effects::{Obstacle, ObstacleShape};
use geom_core::collide::MeshQuery;
use geom_core::math::{Iso3, Pt3, Vec3};
use geom_core::mesh::TriMesh;
use geom_core::query::{closest_point_segment, closest_point_triangle};

/// The accelerated query structure of a mesh obstacle, when its mesh is closed (`None` for other
/// shapes and for open or invalid meshes, which use the brute-force closest triangle).
pub fn mesh_query(o: &Obstacle) -> Option<MeshQuery> {
    match &o.shape {
        ObstacleShape::Mesh { verts, tris } => {
            TriMesh::new(verts.clone(), tris.clone()).ok().and_then(|m| MeshQuery::new(&m).ok())
        }
        _ => None,
    }
}

/// An obstacle with its motion resolved at the start and end of a step.
pub struct PlacedObstacle<'a> {
    /// The obstacle.
    pub obstacle: &'a Obstacle,
    /// Transform at the end of the step.
    pub pose: Iso3,
    /// Transform at the start of the step.
    pub pose_prev: Iso3,
    /// Query structure of a closed mesh obstacle (see [`mesh_query`]).
    pub accel: Option<&'a MeshQuery>,
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
        Self { obstacle: o, pose, pose_prev, accel: None }
    }

    /// Uses `accel` (from [`mesh_query`] of the same obstacle) for distance queries.
    pub fn with_accel(mut self, accel: Option<&'a MeshQuery>) -> Self {
        self.accel = accel;
        self
    }

    /// Signed distance of world point p at the end pose.
    pub fn query(&self, p: &Pt3) -> Proximity {
        let local = self.pose.inverse_transform_point(p);
        let (d, n, c) = match self.accel {
            Some(mq) => closed_mesh_query(mq, &local),
            None => local_query(&self.obstacle.shape, &local),
        };
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

/// Signed distance, outward normal and closest point of a closed mesh (local frame).
fn closed_mesh_query(mq: &MeshQuery, p: &Pt3) -> (f64, Vec3, Pt3) {
    let (c, sd) = mq.closest_signed(p);
    let n = if c.distance > 1e-12 { sd.signum() * (p - c.point) / c.distance } else { mq.face_normal(c.face) };
    (sd, n, c.point)
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

    /// A closed mesh queried through MeshQuery agrees with the brute-force closest triangle:
    /// same signed distance (1e-12) and normal outside; negative inside.
    #[test]
    fn closed_mesh_matches_brute_force() {
        let m = geom_core::procedural::icosphere(0.3, 1).unwrap();
        let o = Obstacle {
            shape: ObstacleShape::Mesh { verts: m.positions.clone(), tris: m.faces.clone() },
            friction: 0.5,
            motion: None,
        };
        let mq = mesh_query(&o).expect("icosphere is closed");
        let fast = PlacedObstacle::new(&o, 0.0, 0.1).with_accel(Some(&mq));
        let slow = PlacedObstacle::new(&o, 0.0, 0.1);
        let mut r = geom_core::rng::Rng::new(5);
        for _ in 0..200 {
            let p = Pt3::new(r.range(-0.6, 0.6), r.range(-0.6, 0.6), r.range(-0.6, 0.6));
            let (a, b) = (fast.query(&p), slow.query(&p));
            assert!((a.distance - b.distance).abs() < 1e-12, "{p:?}: {} vs {}", a.distance, b.distance);
            if b.distance > 1e-9 {
                assert!((a.normal - b.normal).norm() < 1e-9);
            }
        }
        assert!(fast.query(&Pt3::origin()).distance < 0.0);
    }
}

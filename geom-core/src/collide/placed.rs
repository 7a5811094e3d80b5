//! [`Shape`] and [`Placed`]: obstacles (half-spaces, balls, capsules, boxes, closed meshes) at
//! a pose, optionally rounded, with point projection, ray casts and contacts against triangles
//! and segments.

use std::sync::Arc;

use parry3d_f64::query::{self as pq, PointQuery, Ray};
use parry3d_f64::shape::{self as ps, RoundShape};

use super::convert::{pose, pt, to_pt, to_vec, vec};
use super::mesh_query::MeshQuery;
use crate::math::{Iso3, Pt3, Vec3};
use crate::query::{
    closest_point_segment, closest_point_triangle, closest_points_segments, segment_triangle_intersect,
};

/// An obstacle shape in its local frame.
#[derive(Clone, Debug)]
pub enum Shape {
    /// The solid half-space `{x : n̂ · x ≤ 0}`: boundary plane through the local origin, `normal`
    /// pointing out of the solid (any length; normalised when used).
    HalfSpace {
        /// Outward normal of the boundary plane (local frame).
        normal: Vec3,
    },
    /// A solid ball of `radius` (m) centred at the local origin.
    Ball {
        /// Radius (m).
        radius: f64,
    },
    /// The set of points within `radius` of the segment `[a, b]` (local frame).
    Capsule {
        /// First end of the axis.
        a: Pt3,
        /// Second end of the axis.
        b: Pt3,
        /// Radius (m).
        radius: f64,
    },
    /// The box `[−half, half]` (local frame).
    Cuboid {
        /// Half side lengths (m).
        half: Vec3,
    },
    /// A closed triangle mesh (local frame), solid inside.
    Mesh(Arc<MeshQuery>),
}

/// A shape at a pose, grown by a rounding radius: the solid is
/// `pose(shape) ⊕ ball(rounding)` (Minkowski sum).
#[derive(Clone, Debug)]
pub struct Placed {
    /// The shape in its local frame.
    pub shape: Shape,
    /// Local-to-world transform.
    pub pose: Iso3,
    /// Rounding radius (m) added around the shape, 0 for none. [`Placed::inflated`] folds
    /// inflation into the radii of balls and capsules and the offset of half-spaces, and puts it
    /// here for cuboids and meshes.
    pub rounding: f64,
}

/// Result of [`Placed::project_point`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Projection {
    /// Closest point on the surface (world).
    pub point: Pt3,
    /// Signed distance (m): negative inside the solid.
    pub signed_distance: f64,
    /// `signed_distance < 0`.
    pub inside: bool,
}

/// A closest pair (or deepest penetration) between a shape and another object.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Contact {
    /// Point on the shape's surface (world).
    pub on_shape: Pt3,
    /// Point on the other object (world).
    pub on_other: Pt3,
    /// Unit contact normal pointing from the shape towards the other object.
    pub normal: Vec3,
    /// Signed separation along `normal` (m): negative when penetrating.
    pub distance: f64,
}

/// Any unit vector perpendicular to `v` (or `x̂` for `v = 0`).
fn any_perpendicular(v: &Vec3) -> Vec3 {
    let k = v.iamin();
    v.cross(&Vec3::ith(k, 1.0)).try_normalize(0.0).unwrap_or_else(Vec3::x)
}

/// Local projection of the un-rounded shape: `(closest point, signed distance, unit outward
/// normal)`. The normal is the direction from the surface point towards an outside query point
/// (away from an inside one), or the surface normal when the point is on the surface.
fn project_local(shape: &Shape, p: &Pt3) -> (Pt3, f64, Vec3) {
    match shape {
        Shape::HalfSpace { normal } => {
            let n = normal.try_normalize(0.0).unwrap_or_else(Vec3::z);
            let d = n.dot(&p.coords);
            (p - n * d, d, n)
        }
        Shape::Ball { radius } => {
            let r = p.coords.norm();
            let u = if r > 0.0 { p.coords / r } else { Vec3::x() };
            (Pt3::from(u * *radius), r - radius, u)
        }
        Shape::Capsule { a, b, radius } => {
            let (_, c) = closest_point_segment(p, a, b);
            let v = p - c;
            let d = v.norm();
            let u = if d > 0.0 { v / d } else { any_perpendicular(&(b - a)) };
            (c + u * *radius, d - radius, u)
        }
        Shape::Cuboid { half } => {
            let proj = ps::Cuboid::new(vec(half)).project_local_point(pt(p), false);
            let q = to_pt(proj.point);
            let d = (p - q).norm();
            let u = if d > 0.0 {
                if proj.is_inside {
                    (q - p) / d
                } else {
                    (p - q) / d
                }
            } else {
                // On the surface: the face whose plane the point is closest to.
                let k = (0..3).max_by(|&i, &j| (q[i].abs() - half[i]).total_cmp(&(q[j].abs() - half[j]))).unwrap_or(0);
                Vec3::ith(k, q[k].signum())
            };
            (q, if proj.is_inside { -d } else { d }, u)
        }
        Shape::Mesh(m) => {
            let (c, sd) = m.closest_signed(p);
            let d = c.distance;
            let u = if d > 0.0 { (p - c.point) * (sd.signum() / d) } else { m.face_normal(c.face) };
            (c.point, sd, u)
        }
    }
}

impl Placed {
    /// A shape at a pose, without rounding.
    pub fn new(shape: Shape, pose: Iso3) -> Self {
        Self { shape, pose, rounding: 0.0 }
    }

    /// The shape grown by `h` (m): balls and capsules get radius `+ h`, a half-space's plane moves
    /// `h` along its normal, cuboids and meshes get rounding `+ h` (their Minkowski sum with a
    /// ball). `h` should be ≥ 0 for cuboids and meshes; for the others it may shrink the shape as
    /// long as radii stay non-negative.
    pub fn inflated(&self, h: f64) -> Placed {
        let mut out = self.clone();
        match &mut out.shape {
            Shape::HalfSpace { normal } => {
                let n = normal.try_normalize(0.0).unwrap_or_else(Vec3::z);
                out.pose.translation.vector += self.pose.rotation * (n * h);
            }
            Shape::Ball { radius } | Shape::Capsule { radius, .. } => *radius += h,
            Shape::Cuboid { .. } | Shape::Mesh(_) => out.rounding += h,
        }
        out
    }

    /// Closest surface point, signed distance (negative inside) and inside flag for the world
    /// point `p`. Exact for convex shapes with rounding; for a rounded mesh the offset surface
    /// is approximated by moving the mesh's closest point by `rounding` along the outward
    /// direction (exact unless the offset surface folds over itself).
    pub fn project_point(&self, p: &Pt3) -> Projection {
        let pl = self.pose.inverse_transform_point(p);
        let (q, sd, n) = project_local(&self.shape, &pl);
        let sd = sd - self.rounding;
        Projection { point: self.pose * (q + n * self.rounding), signed_distance: sd, inside: sd < 0.0 }
    }

    /// First hit of the ray `o + t d`, `0 ≤ t ≤ max_t`, with the solid: `(t, outward unit normal
    /// at the hit)` in world coordinates, `t` in units of `|d|`. A ray starting inside or on the
    /// surface hits at `t = 0` with the normal of the closest surface point.
    pub fn cast_ray(&self, o: &Pt3, d: &Vec3, max_t: f64) -> Option<(f64, Vec3)> {
        let ol = self.pose.inverse_transform_point(o);
        let dl = self.pose.inverse_transform_vector(d);
        let h = self.rounding;
        let (_, sd, n0) = project_local(&self.shape, &ol);
        if sd - h <= 0.0 {
            return Some((0.0, self.pose.rotation * n0));
        }
        if max_t.is_nan() || max_t < 0.0 {
            return None;
        }
        let hit: Option<(f64, Vec3)> = match &self.shape {
            Shape::HalfSpace { normal } => {
                let n = normal.try_normalize(0.0).unwrap_or_else(Vec3::z);
                let denom = n.dot(&dl);
                (denom < 0.0).then(|| (-(sd - h) / denom, n))
            }
            Shape::Ball { radius } => {
                let r = radius + h;
                let (a, b, c) = (dl.norm_squared(), ol.coords.dot(&dl), ol.coords.norm_squared() - r * r);
                let disc = b * b - a * c;
                if a > 0.0 && b < 0.0 && disc >= 0.0 {
                    // Stable smaller root of a t² + 2 b t + c = 0 (c > 0: the origin is outside).
                    let t = c / (-b + disc.sqrt());
                    let x = ol + dl * t;
                    Some((t, x.coords.try_normalize(0.0).unwrap_or_else(|| -dl.normalize())))
                } else {
                    None
                }
            }
            Shape::Capsule { a, b, radius } => {
                let cap = ps::Capsule::new(pt(a), pt(b), radius + h);
                ray_hit(&cap, &ol, &dl, max_t)
            }
            Shape::Cuboid { half } => {
                let cub = ps::Cuboid::new(vec(half));
                if h > 0.0 {
                    ray_hit(&RoundShape { inner_shape: cub, border_radius: h }, &ol, &dl, max_t)
                } else {
                    ray_hit(&cub, &ol, &dl, max_t)
                }
            }
            Shape::Mesh(m) => {
                if h > 0.0 {
                    rounded_mesh_ray(m, h, &ol, &dl, max_t)
                } else {
                    m.ray_cast_normal(&ol, &dl, max_t).map(|(t, f, _)| (t, m.face_normal(f)))
                }
            }
        };
        hit.filter(|&(t, _)| t <= max_t).map(|(t, n)| (t, self.pose.rotation * n))
    }

    /// Contact between the solid and the triangle `t` (world), reported when the signed
    /// distance is at most `margin`.
    ///
    /// Half-space: the deepest corner (first on ties). Ball: closed form from the closest point
    /// of the triangle to the centre. Capsule: closed form (segment–triangle closest points)
    /// when the axis misses the triangle (exact test), parry's EPA when it crosses it. Cuboid:
    /// parry's GJK/EPA (tolerance about 1e-8 relative). Mesh: if a corner lies inside the mesh, the deepest corner and its
    /// closest surface point; otherwise parry's closest pair between the triangle and the
    /// mesh's triangles (negative when a mesh triangle crosses it). Rounding shifts the contact
    /// point on the shape by `rounding` along the normal and lowers the distance by it.
    /// A degenerate (zero-area) triangle is treated as its longest edge.
    pub fn contact_triangle(&self, t: &[Pt3; 3], margin: f64) -> Option<Contact> {
        let n = (t[1] - t[0]).cross(&(t[2] - t[0]));
        if n.norm_squared() == 0.0 || n.norm_squared().is_nan() {
            let (mut a, mut b) = (0, 1);
            for (i, j) in [(1, 2), (2, 0)] {
                if (t[j] - t[i]).norm_squared() > (t[b] - t[a]).norm_squared() {
                    (a, b) = (i, j);
                }
            }
            return self.contact_segment(&t[a], &t[b], margin);
        }
        let h = self.rounding;
        let base = match &self.shape {
            Shape::HalfSpace { .. } => self.halfspace_deepest(t),
            Shape::Ball { radius } => {
                let c = Pt3::from(self.pose.translation.vector);
                let (q, _) = closest_point_triangle(&c, t);
                Some(ball_contact(&c, *radius, &q, &n))
            }
            Shape::Capsule { a, b, radius } => {
                let (wa, wb) = (self.pose * a, self.pose * b);
                if segment_triangle_intersect(&wa, &wb, t) {
                    // Penetration depth needs EPA.
                    let tri = ps::Triangle::new(pt(&t[0]), pt(&t[1]), pt(&t[2]));
                    self.parry_contact(&ps::Capsule::new(pt(a), pt(b), *radius), &tri, margin + h)
                } else {
                    let (c1, c2) = closest_segment_triangle_apart(&wa, &wb, t);
                    Some(ball_contact(&c1, *radius, &c2, &n))
                }
            }
            Shape::Cuboid { half } => {
                let tri = ps::Triangle::new(pt(&t[0]), pt(&t[1]), pt(&t[2]));
                self.parry_contact(&ps::Cuboid::new(vec(half)), &tri, margin + h)
            }
            Shape::Mesh(m) => self.mesh_deepest_corner(m, t).or_else(|| {
                let tri = ps::Triangle::new(pt(&t[0]), pt(&t[1]), pt(&t[2]));
                self.parry_contact(m.parry_mesh(), &tri, margin + h)
            }),
        };
        self.finish(base, margin)
    }

    /// Contact between the solid and the segment `[a, b]` (world), reported when the signed
    /// distance is at most `margin`. As [`Placed::contact_triangle`]; capsules use the closed
    /// form of [`closest_points_segments`] (crossing axes: normal along the common
    /// perpendicular), and a zero-length segment is a point.
    pub fn contact_segment(&self, a: &Pt3, b: &Pt3, margin: f64) -> Option<Contact> {
        let h = self.rounding;
        let base = if a == b {
            let pl = self.pose.inverse_transform_point(a);
            let (q, sd, n) = project_local(&self.shape, &pl);
            Some(Contact { on_shape: self.pose * q, on_other: *a, normal: self.pose.rotation * n, distance: sd })
        } else {
            match &self.shape {
                Shape::HalfSpace { .. } => self.halfspace_deepest(&[*a, *b]),
                Shape::Ball { radius } => {
                    let c = Pt3::from(self.pose.translation.vector);
                    let (_, q) = closest_point_segment(&c, a, b);
                    Some(ball_contact(&c, *radius, &q, &any_perpendicular(&(b - a))))
                }
                Shape::Capsule { a: ca, b: cb, radius } => {
                    let (wa, wb) = (self.pose * ca, self.pose * cb);
                    let (_, _, c1, c2) = closest_points_segments(&wa, &wb, a, b);
                    let v = c2 - c1;
                    let d = v.norm();
                    let normal = if d > 0.0 {
                        v / d
                    } else {
                        (wb - wa).cross(&(b - a)).try_normalize(0.0).unwrap_or_else(|| any_perpendicular(&(wb - wa)))
                    };
                    Some(Contact { on_shape: c1 + normal * *radius, on_other: c2, normal, distance: d - radius })
                }
                Shape::Cuboid { half } => {
                    self.parry_contact(&ps::Cuboid::new(vec(half)), &ps::Segment::new(pt(a), pt(b)), margin + h)
                }
                Shape::Mesh(m) => self
                    .mesh_deepest_corner(m, &[*a, *b])
                    .or_else(|| self.parry_contact(m.parry_mesh(), &ps::Segment::new(pt(a), pt(b)), margin + h)),
            }
        };
        self.finish(base, margin)
    }

    /// Applies the rounding and the margin test.
    fn finish(&self, base: Option<Contact>, margin: f64) -> Option<Contact> {
        let h = self.rounding;
        base.map(|c| Contact { on_shape: c.on_shape + c.normal * h, distance: c.distance - h, ..c })
            .filter(|c| c.distance <= margin)
    }

    /// Deepest of the points `pts` (world) against the half-space.
    fn halfspace_deepest(&self, pts: &[Pt3]) -> Option<Contact> {
        let Shape::HalfSpace { normal } = &self.shape else { return None };
        let n = self.pose.rotation * normal.try_normalize(0.0).unwrap_or_else(Vec3::z);
        let o = Pt3::from(self.pose.translation.vector);
        let mut best: Option<(f64, Pt3)> = None;
        for q in pts {
            let d = n.dot(&(q - o));
            if best.is_none_or(|(bd, _)| d < bd) {
                best = Some((d, *q));
            }
        }
        best.map(|(d, q)| Contact { on_shape: q - n * d, on_other: q, normal: n, distance: d })
    }

    /// If a point of `pts` (world) is inside the mesh, the contact of the deepest one.
    fn mesh_deepest_corner(&self, m: &MeshQuery, pts: &[Pt3]) -> Option<Contact> {
        let mut best: Option<(f64, Contact)> = None;
        for q in pts {
            let ql = self.pose.inverse_transform_point(q);
            let (c, sd) = m.closest_signed(&ql);
            if sd < 0.0 && best.as_ref().is_none_or(|(bd, _)| sd < *bd) {
                let normal = self.pose.rotation * ((c.point - ql) / c.distance);
                best = Some((sd, Contact { on_shape: self.pose * c.point, on_other: *q, normal, distance: sd }));
            }
        }
        best.map(|(_, c)| c)
    }

    /// parry's contact between the local shape `g` at our pose and `other` (world coordinates).
    fn parry_contact(&self, g: &dyn ps::Shape, other: &dyn ps::Shape, prediction: f64) -> Option<Contact> {
        let id = super::convert::DPose3::IDENTITY;
        // Every pair used here (support map vs support map, composite vs support map) is
        // supported by parry's default dispatcher, so `Err(Unsupported)` cannot occur.
        let c = pq::contact(&pose(&self.pose), g, &id, other, prediction).ok()??;
        Some(Contact {
            on_shape: to_pt(c.point1),
            on_other: to_pt(c.point2),
            normal: to_vec(c.normal1),
            distance: c.dist,
        })
    }
}

/// Ball (centre `c`, radius `r`) against the closest point `q` of the other object; `fallback`
/// gives the normal direction when `q` is the centre.
fn ball_contact(c: &Pt3, r: f64, q: &Pt3, fallback: &Vec3) -> Contact {
    let v = q - c;
    let d = v.norm();
    let normal = if d > 0.0 { v / d } else { fallback.try_normalize(0.0).unwrap_or_else(Vec3::z) };
    Contact { on_shape: c + normal * r, on_other: *q, normal, distance: d - r }
}

/// Closest points `(on segment, on triangle)` of a segment and a triangle that do not meet:
/// the minimum is attained at a segment end point against the triangle or between the segment
/// and a triangle edge (Ericson §5.1.10), all closed forms.
fn closest_segment_triangle_apart(p: &Pt3, q: &Pt3, t: &[Pt3; 3]) -> (Pt3, Pt3) {
    let mut best = (f64::INFINITY, *p, t[0]);
    let mut consider = |c1: Pt3, c2: Pt3| {
        let d2 = (c2 - c1).norm_squared();
        if d2 < best.0 {
            best = (d2, c1, c2);
        }
    };
    for e in [p, q] {
        consider(*e, closest_point_triangle(e, t).0);
    }
    for i in 0..3 {
        let (_, _, c1, c2) = closest_points_segments(p, q, &t[i], &t[(i + 1) % 3]);
        consider(c1, c2);
    }
    (best.1, best.2)
}

/// parry ray cast against a solid local shape, returning `(t, unit normal)`.
fn ray_hit(s: &dyn ps::Shape, o: &Pt3, d: &Vec3, max_t: f64) -> Option<(f64, Vec3)> {
    let ray = Ray::new(pt(o), vec(d));
    s.cast_local_ray_and_get_normal(&ray, max_t, true).map(|hit| (hit.time_of_impact, to_vec(hit.normal)))
}

/// Ray against a mesh rounded by `h` (the ray starts outside): the first hit among the
/// rounded triangles whose boxes meet the ray's swept box. The solid interior of the mesh is
/// reached only through its surface, so the rounded triangles suffice.
fn rounded_mesh_ray(m: &MeshQuery, h: f64, o: &Pt3, d: &Vec3, max_t: f64) -> Option<(f64, Vec3)> {
    let end = if max_t.is_finite() { o + d * max_t } else { o + d * f64::MAX.sqrt() };
    let sweep = crate::spatial::Aabb::from_points(&[*o, end]).grow(h);
    let mut best: Option<(f64, Vec3)> = None;
    m.faces_overlapping(&sweep, |f| {
        let [a, b, c] = m.faces()[f as usize].map(|v| pt(&m.positions()[v as usize]));
        let tri = RoundShape { inner_shape: ps::Triangle::new(a, b, c), border_radius: h };
        let limit = best.map_or(max_t, |(t, _)| t);
        if let Some(hit) = ray_hit(&tri, o, d, limit) {
            if best.is_none_or(|(t, _)| hit.0 < t) {
                best = Some(hit);
            }
        }
    });
    best
}

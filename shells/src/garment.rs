//! Garments generated around a body (issue 23 item 5): a skirt as a flared open tube of rings
//! around a vertical axis, hugging the body at the waist and clear of it below.
//!
//! The body's outer surface at each ring height is found by casting rays from a cylinder of
//! radius `reach` around the axis inward toward it ([`MeshQuery::ray_cast`]): the first hit is
//! the outermost surface within `reach` (parts farther out — hands held away from the body —
//! are ignored). Each ring is a circle of radius max(waist radius + (y_w − y)·tan(flare),
//! body radius at y + clearance), so the skirt never starts inside the body.

use geom_core::collide::MeshQuery;
use geom_core::math::{Pt3, Vec3};
use geom_core::mesh::TriMesh;
use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};

/// A skirt's shape (lengths in the body's units, y up).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SkirtSpec {
    /// Height of the waistband (m).
    pub waist_y: f64,
    /// Height of the hem (m), below the waist.
    pub hem_y: f64,
    /// The axis's (x, z) (m).
    pub axis: [f64; 2],
    /// Gap kept from the body everywhere (m).
    pub clearance: f64,
    /// Flare: the cone's half-angle (degrees).
    pub flare_deg: f64,
    /// Vertices around a ring.
    pub segments: u32,
    /// Largest distance from the axis at which the body counts (m).
    pub reach: f64,
}

/// A generated garment: an open triangle mesh and the vertices attached to the body.
#[derive(Clone, Debug)]
pub struct Garment {
    /// Vertex positions (m).
    pub positions: Vec<Pt3>,
    /// Triangles.
    pub faces: Vec<[u32; 3]>,
    /// Vertices that follow the body (the waistband).
    pub attached: Vec<u32>,
}

/// The body's outermost surface radius around `axis` at height `y` (m): the largest, over
/// `segments` directions, of the distance from the axis to the first surface hit by a ray
/// cast inward from radius `reach`; 0 where no ray hits.
pub fn body_radius(mq: &MeshQuery, axis: [f64; 2], y: f64, reach: f64, segments: u32) -> f64 {
    (0..segments)
        .map(|k| {
            let th = 2.0 * std::f64::consts::PI * k as f64 / segments as f64;
            let dir = Vec3::new(th.cos(), 0.0, th.sin());
            let o = Pt3::new(axis[0], y, axis[1]) + reach * dir;
            mq.ray_cast(&o, &-dir, reach).map_or(0.0, |(t, _)| reach - t)
        })
        .fold(0.0, f64::max)
}

/// A skirt around the closed `body` mesh. Errors: a spec out of range (non-finite, hem not
/// below the waist, fewer than 8 segments), an open body mesh, or a waist where no body is
/// found within `reach`.
pub fn skirt(body: &TriMesh, s: &SkirtSpec) -> Result<Garment> {
    let bad = |m: String| Err(Error::BadParameter(format!("skirt: {m}")));
    let vals = [s.waist_y, s.hem_y, s.axis[0], s.axis[1], s.clearance, s.flare_deg, s.reach];
    if vals.iter().any(|v| !v.is_finite()) {
        return Err(Error::NonFinite("skirt spec"));
    }
    if !(s.hem_y < s.waist_y) || s.segments < 8 || !(s.clearance > 0.0) || !(s.reach > 0.0) {
        return bad(format!(
            "needs hem_y < waist_y, ≥ 8 segments, clearance > 0 and reach > 0; got hem {} waist {}, {} segments, clearance {}, reach {}",
            s.hem_y, s.waist_y, s.segments, s.clearance, s.reach
        ));
    }
    if !(0.0..80.0).contains(&s.flare_deg) {
        return bad(format!("flare_deg {} must be in [0, 80)", s.flare_deg));
    }
    let mq = MeshQuery::new(body)?;
    let probe = 4 * s.segments;
    let r_waist = body_radius(&mq, s.axis, s.waist_y, s.reach, probe);
    if !(r_waist > 0.0) {
        return bad(format!("no body within reach {} of the axis at the waist height {}", s.reach, s.waist_y));
    }
    let r0 = r_waist + s.clearance;
    // Rings about as far apart as the vertices around the waist (near-equilateral triangles).
    let spacing = 2.0 * std::f64::consts::PI * r0 / s.segments as f64;
    let rings = (((s.waist_y - s.hem_y) / spacing).round() as u32).max(2) + 1;
    let tan = s.flare_deg.to_radians().tan();
    let n = s.segments;
    let mut positions = Vec::with_capacity((rings * n) as usize);
    for i in 0..rings {
        let y = s.waist_y - (s.waist_y - s.hem_y) * i as f64 / (rings - 1) as f64;
        // The waist within the band's own clearance; below, flared and clear of the body.
        let r_body = if i == 0 { r_waist } else { body_radius(&mq, s.axis, y, s.reach, probe) };
        let r = (r0 + (s.waist_y - y) * tan).max(r_body + s.clearance);
        for k in 0..n {
            // Alternate rings are turned by half a segment (better-shaped triangles).
            let th = 2.0 * std::f64::consts::PI * (k as f64 + 0.5 * (i % 2) as f64) / n as f64;
            positions.push(Pt3::new(s.axis[0] + r * th.cos(), y, s.axis[1] + r * th.sin()));
        }
    }
    let id = |i: u32, k: u32| i * n + k % n;
    let mut faces = Vec::with_capacity((2 * (rings - 1) * n) as usize);
    for i in 0..rings - 1 {
        for k in 0..n {
            // Outward normals (counter-clockwise seen from outside, y up, angle growing toward +z).
            if i % 2 == 0 {
                faces.push([id(i, k), id(i, k + 1), id(i + 1, k)]);
                faces.push([id(i, k + 1), id(i + 1, k + 1), id(i + 1, k)]);
            } else {
                faces.push([id(i, k), id(i + 1, k + 1), id(i + 1, k)]);
                faces.push([id(i, k), id(i, k + 1), id(i + 1, k + 1)]);
            }
        }
    }
    Ok(Garment { positions, faces, attached: (0..n).collect() })
}

#[cfg(test)]
mod tests {
    use super::*;
    use geom_core::procedural::{box_surface, Diagonals};

    #[test]
    fn a_skirt_around_a_box_clears_it_and_hugs_the_waist() {
        let b =
            box_surface(Pt3::new(-0.1, 0.0, -0.1), Pt3::new(0.1, 1.0, 0.1), [4, 8, 4], Diagonals::Alternating).unwrap();
        let s = SkirtSpec {
            waist_y: 0.9,
            hem_y: 0.4,
            axis: [0.0, 0.0],
            clearance: 0.01,
            flare_deg: 10.0,
            segments: 24,
            reach: 0.5,
        };
        let g = skirt(&b, &s).unwrap();
        let mq = MeshQuery::new(&b).unwrap();
        let min_sd = g.positions.iter().map(|p| mq.signed_distance(p)).fold(f64::INFINITY, f64::min);
        assert!(min_sd >= 0.01 - 1e-9, "closest garment vertex {min_sd} m from the body");
        // The waist: the box's corner radius 0.1·√2 plus the clearance.
        let r0 = (g.positions[0].x.powi(2) + g.positions[0].z.powi(2)).sqrt();
        assert!((r0 - (0.1 * 2f64.sqrt() + 0.01)).abs() < 2e-3, "{r0}");
        assert_eq!(g.attached.len(), 24);
        let m = TriMesh::new(g.positions.clone(), g.faces.clone()).unwrap();
        assert_eq!(m.topology().n_boundary_edges(), 48, "an open tube: two boundary loops");
        let bad = SkirtSpec { hem_y: 1.0, ..s };
        assert!(skirt(&b, &bad).is_err());
    }
}

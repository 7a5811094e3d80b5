//! Triangle meshes of the obstacle shapes, for pictures and exports (previews, the report, a
//! user's own renders). The contact code never uses them: it works on the exact shapes.

use geom_core::math::Pt3;
use geom_core::procedural::{icosphere, tube, Caps, TubeSpec};

use crate::effects::ObstacleShape;
use crate::error::Result;

/// Segments around a capsule's axis in [`ObstacleShape::surface_mesh`].
pub const CAPSULE_AROUND: u32 = 16;

/// Subdivision level of a ball's icosphere in [`ObstacleShape::surface_mesh`] (3: 642 vertices).
pub const SPHERE_LEVEL: u32 = 3;

/// Positions (m) and outward triangles of a drawn obstacle.
pub type SurfaceMesh = (Vec<Pt3>, Vec<[u32; 3]>);

impl ObstacleShape {
    /// A closed triangle mesh (positions in m, outward faces) that draws the shape: an
    /// icosphere for a ball, a tube with flat fan caps for a capsule ([`CAPSULE_AROUND`]
    /// segments; the hemispherical ends are drawn flat), the mesh itself for a mesh. `None`
    /// for a plane, which has no finite surface (previews draw a ground grid for it).
    pub fn surface_mesh(&self) -> Result<Option<SurfaceMesh>> {
        Ok(match self {
            ObstacleShape::Plane { .. } => None,
            ObstacleShape::Sphere { center, radius } => {
                let m = icosphere(*radius, SPHERE_LEVEL)?;
                Some((m.positions.iter().map(|p| p + center.coords).collect(), m.faces.clone()))
            }
            ObstacleShape::Capsule { a, b, radius } => {
                let axis = b - a;
                let t = tube(&TubeSpec {
                    radius: *radius,
                    length: axis.norm(),
                    around: CAPSULE_AROUND,
                    along: 1,
                    start: *a,
                    axis,
                    caps: Caps::Fan,
                })?;
                let m = t.triangulate_fan()?.0;
                Some((m.positions.clone(), m.faces.clone()))
            }
            ObstacleShape::Mesh { verts, tris } => Some((verts.clone(), tris.clone())),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use geom_core::math::Vec3;

    /// Every vertex of a capsule's mesh lies on the capsule's cylinder or cap discs: at distance
    /// `radius` from the axis (ring vertices) or on the axis ends (fan centres).
    #[test]
    fn capsule_mesh_lies_on_the_capsule() {
        let (a, b, r) = (Pt3::new(0.1, 0.2, 0.3), Pt3::new(0.5, 0.2, -0.1), 0.07);
        let (p, f) = ObstacleShape::Capsule { a, b, radius: r }.surface_mesh().unwrap().unwrap();
        assert!(!f.is_empty());
        let u = (b - a).normalize();
        for q in &p {
            let d = q - a;
            let along = d.dot(&u);
            let radial = (d - along * u).norm();
            assert!((-1e-12..=(b - a).norm() + 1e-12).contains(&along), "{along}");
            assert!(radial < 1e-12 || (radial - r).abs() < 1e-12, "radial {radial}");
        }
    }

    /// A ball's mesh is centred on the ball with every vertex at the radius; a plane has none.
    #[test]
    fn sphere_on_its_radius_and_plane_has_no_mesh() {
        let c = Pt3::new(1.0, -2.0, 0.5);
        let (p, _) = ObstacleShape::Sphere { center: c, radius: 0.3 }.surface_mesh().unwrap().unwrap();
        assert!(p.iter().all(|q| ((q - c).norm() - 0.3).abs() < 1e-12));
        assert!(ObstacleShape::Plane { normal: Vec3::y(), offset: 0.0 }.surface_mesh().unwrap().is_none());
    }
}

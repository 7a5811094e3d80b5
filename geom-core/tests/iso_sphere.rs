//! `iso` contract tests (GEOM-CORE.md §7): marching tetrahedra of a sphere is a closed, oriented,
//! connected 2-manifold close to the true surface; the polygonizer is deterministic and hits a
//! vertex-count target.

use geom_core::iso::{polygonize, polygonize_to_count, sdf, PolygonizeOptions};
use geom_core::math::Pt3;
use geom_core::mesh::signed_volume;
use geom_core::spatial::Aabb;

#[test]
fn sphere_is_closed_oriented_manifold_near_the_surface() {
    let c = Pt3::new(0.1, -0.2, 0.05);
    let r = 0.7;
    let f = |p: &Pt3| sdf::sphere(p, &c, r);
    let h = 0.05;
    let o = PolygonizeOptions {
        bounds: Aabb::new(c - nalgebra::Vector3::repeat(1.0), c + nalgebra::Vector3::repeat(1.0)),
        h,
    };
    let m = polygonize(&f, &o).expect("sphere meshes");
    let t = m.topology();
    // TriMesh::new already rejects non-manifold edges/vertices and flipped neighbours.
    assert!(t.is_closed());
    assert_eq!(t.face_components().0, 1);
    assert_eq!(t.euler_characteristic(), 2, "genus 0");
    // Outward: positive volume, close to 4/3 π r³ (linear interpolation of a convex field is
    // inside the sphere up to O(h²): allow 3 %).
    let v = signed_volume(&m.faces, &m.positions);
    let exact = 4.0 / 3.0 * std::f64::consts::PI * r * r * r;
    assert!(v > 0.0 && (v - exact).abs() < 0.03 * exact, "volume {v} vs {exact}");
    // Vertices lie on grid edges at the linear-interpolation root: within h²/(2r) of the sphere
    // (the chord sagitta bound for an edge of length h).
    for p in &m.positions {
        assert!(f(p).abs() <= h * h / (2.0 * r) + 1e-12, "vertex off the surface by {}", f(p));
    }
    // Deterministic (parallel field sampling writes disjoint slabs).
    let m2 = polygonize(&f, &o).expect("again");
    assert_eq!(m.positions, m2.positions);
    assert_eq!(m.faces, m2.faces);
}

#[test]
fn two_tangent_blobs_and_vertex_target() {
    // A smooth union of two spheres: one component, genus 0.
    let a = Pt3::new(-0.3, 0.0, 0.0);
    let b = Pt3::new(0.3, 0.0, 0.0);
    let f = |p: &Pt3| sdf::smooth_min(sdf::sphere(p, &a, 0.35), sdf::sphere(p, &b, 0.3), 0.1);
    let bounds = Aabb::new(Pt3::new(-0.7, -0.4, -0.4), Pt3::new(0.65, 0.4, 0.4));
    let (m, h) = polygonize_to_count(&f, bounds, 3000, 0.1).expect("meshes");
    assert!((m.n_vertices() as f64 - 3000.0).abs() <= 300.0, "{} vertices at h = {h}", m.n_vertices());
    assert_eq!(m.topology().euler_characteristic(), 2);
    assert!(signed_volume(&m.faces, &m.positions) > 0.0);
}

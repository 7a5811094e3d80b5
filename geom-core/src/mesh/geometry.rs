//! Per-element geometry over `(faces, positions)`: areas, normals, vertex normals and enclosed
//! volume. All functions are generic over [`AsPt3`] so they run on `Pt3`, `Vec3`, `[f64; 3]` or
//! `[f32; 3]` data, and on any deformed positions sharing the faces.

use serde::{Deserialize, Serialize};

use super::Topology;
use crate::math::{AsPt3, Pt3, Vec3};

/// Relative threshold under which a face normal is treated as undefined (zero): |N| below this
/// times the squared longest edge, i.e. the height is below 1e-14 of the longest edge.
const NORMAL_REL_EPS: f64 = 1e-14;

#[inline]
pub(crate) fn tri<P: AsPt3>(p: &[P], t: &[u32; 3]) -> [Pt3; 3] {
    [p[t[0] as usize].pt3(), p[t[1] as usize].pt3(), p[t[2] as usize].pt3()]
}

/// Unnormalised face normal `(b − a) × (c − a)` (length = twice the area).
#[inline]
pub(crate) fn area_vector(x: &[Pt3; 3]) -> Vec3 {
    (x[1] - x[0]).cross(&(x[2] - x[0]))
}

/// Triangle areas (m²).
pub fn face_areas<P: AsPt3>(faces: &[[u32; 3]], p: &[P]) -> Vec<f64> {
    faces.iter().map(|t| 0.5 * area_vector(&tri(p, t)).norm()).collect()
}

/// Unit face normals (right-hand rule over the face's vertex order); the zero vector for a
/// degenerate face (height below 1e-14 of its longest edge, or any zero-length result).
pub fn face_normals<P: AsPt3>(faces: &[[u32; 3]], p: &[P]) -> Vec<Vec3> {
    faces.iter().map(|t| unit_normal(&tri(p, t))).collect()
}

fn unit_normal(x: &[Pt3; 3]) -> Vec3 {
    let n = area_vector(x);
    let l2 = (x[1] - x[0]).norm_squared().max((x[2] - x[1]).norm_squared()).max((x[0] - x[2]).norm_squared());
    let len = n.norm();
    if len > NORMAL_REL_EPS * l2 && len.is_finite() {
        n / len
    } else {
        Vec3::zeros()
    }
}

/// How face normals are weighted when averaged to the vertices.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum NormalWeight {
    /// Weight by face area (sum of unnormalised normals).
    #[default]
    Area,
    /// Weight by the corner angle at the vertex (Thürmer & Wüthrich 1998): independent of the
    /// tessellation of flat regions.
    Angle,
    /// Every incident (non-degenerate) face counts once.
    Uniform,
}

/// Unit vertex normals, the weighted average of the incident unit face normals; the zero vector
/// for vertices in no (non-degenerate) face or where the weighted sum vanishes.
pub fn vertex_normals<P: AsPt3>(faces: &[[u32; 3]], p: &[P], w: NormalWeight) -> Vec<Vec3> {
    let mut acc = vec![Vec3::zeros(); p.len()];
    for t in faces {
        let x = tri(p, t);
        let n = unit_normal(&x);
        if n == Vec3::zeros() {
            continue;
        }
        match w {
            NormalWeight::Area => {
                let a = area_vector(&x);
                for &v in t {
                    acc[v as usize] += a;
                }
            }
            NormalWeight::Uniform => {
                for &v in t {
                    acc[v as usize] += n;
                }
            }
            NormalWeight::Angle => {
                for k in 0..3 {
                    let e1 = x[(k + 1) % 3] - x[k];
                    let e2 = x[(k + 2) % 3] - x[k];
                    let ang = e1.cross(&e2).norm().atan2(e1.dot(&e2));
                    acc[t[k] as usize] += ang * n;
                }
            }
        }
    }
    for a in &mut acc {
        let l = a.norm();
        *a = if l > 0.0 && l.is_finite() { *a / l } else { Vec3::zeros() };
    }
    acc
}

/// Signed enclosed volume (m³) by the divergence theorem, `Σ (a−c)·((b−c)×(d−c))/6` over faces
/// with a reference point `c` at the bounding-box centre (same value as the origin-based formula
/// for closed meshes, better conditioned far from the origin). Positive for a closed mesh with
/// outward (counter-clockwise seen from outside) faces. For open meshes the value depends on `c`;
/// use [`signed_volume_capped`] instead.
pub fn signed_volume<P: AsPt3>(faces: &[[u32; 3]], p: &[P]) -> f64 {
    let c = match super::bbox_of(p) {
        Some((lo, hi)) => Pt3::from((lo.coords + hi.coords) * 0.5),
        None => return 0.0,
    };
    faces
        .iter()
        .map(|t| {
            let [a, b, d] = tri(p, t);
            (a - c).dot(&(b - c).cross(&(d - c)))
        })
        .sum::<f64>()
        / 6.0
}

/// Signed volume of the mesh with every boundary loop closed by a fan of triangles from the
/// loop's centroid (oriented consistently with the faces), for open meshes such as a body
/// without its neck hole closed. Equals [`signed_volume`] for closed meshes.
pub fn signed_volume_capped<P: AsPt3>(t: &Topology, faces: &[[u32; 3]], p: &[P]) -> f64 {
    let mut v = signed_volume(faces, p) * 6.0;
    let c = match super::bbox_of(p) {
        Some((lo, hi)) => Pt3::from((lo.coords + hi.coords) * 0.5),
        None => return 0.0,
    };
    for lp in t.boundary_loops() {
        let n = lp.len() as f64;
        let centroid = Pt3::from(lp.iter().fold(Vec3::zeros(), |s, &i| s + p[i as usize].pt3().coords) / n);
        for k in 0..lp.len() {
            // The loop runs a→b along the faces' boundary half-edges: the cap traverses b→a.
            let a = p[lp[k] as usize].pt3();
            let b = p[lp[(k + 1) % lp.len()] as usize].pt3();
            v += (centroid - c).dot(&(b - c).cross(&(a - c)));
        }
    }
    v / 6.0
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tetra() -> (Vec<Pt3>, Vec<[u32; 3]>) {
        let p = vec![Pt3::new(0., 0., 0.), Pt3::new(1., 0., 0.), Pt3::new(0., 1., 0.), Pt3::new(0., 0., 1.)];
        let f = vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]];
        (p, f)
    }

    #[test]
    fn tetra_volume_area_normals() {
        let (p, f) = tetra();
        // Exact: 1/6; all arithmetic here is on small dyadic/integer values, so 1e-15 is round-off.
        assert!((signed_volume(&f, &p) - 1.0 / 6.0).abs() < 1e-15);
        let a = face_areas(&f, &p);
        assert!((a[0] - 0.5).abs() < 1e-15 && (a[3] - 3f64.sqrt() / 2.0).abs() < 1e-15);
        let n = face_normals(&f, &p);
        assert_eq!(n[0], Vec3::new(0., 0., -1.));
        // f32 input gives the same volume up to f32 rounding of exactly representable inputs.
        let p32: Vec<[f32; 3]> = p.iter().map(|q| [q.x as f32, q.y as f32, q.z as f32]).collect();
        assert_eq!(signed_volume(&f, &p32), signed_volume(&f, &p));
        // Reversed faces: negative volume.
        let rf: Vec<[u32; 3]> = f.iter().map(|t| [t[0], t[2], t[1]]).collect();
        assert!((signed_volume(&rf, &p) + 1.0 / 6.0).abs() < 1e-15);
    }

    #[test]
    fn degenerate_face_normal_is_zero() {
        let p = vec![Pt3::new(0., 0., 0.), Pt3::new(1., 0., 0.), Pt3::new(2., 0., 0.)];
        assert_eq!(face_normals(&[[0, 1, 2]], &p)[0], Vec3::zeros());
        assert_eq!(vertex_normals(&[[0, 1, 2]], &p, NormalWeight::Angle)[0], Vec3::zeros());
    }

    #[test]
    fn capped_volume_of_open_tetra() {
        let (p, f) = tetra();
        let t = Topology::new(4, &f[..3]).expect("three faces of a tetrahedron are a valid open fan");
        // The cap of the single triangular hole is the missing face (fan from its centroid).
        assert!((signed_volume_capped(&t, &f[..3], &p) - 1.0 / 6.0).abs() < 1e-15);
    }

    #[test]
    fn vertex_normals_point_out_on_tetra() {
        let (p, f) = tetra();
        for w in [NormalWeight::Area, NormalWeight::Angle, NormalWeight::Uniform] {
            let n = vertex_normals(&f, &p, w);
            assert!((n[0] - Vec3::new(-1., -1., -1.).normalize()).norm() < 1e-15, "{w:?}");
            for v in &n {
                assert!((v.norm() - 1.0).abs() < 1e-15);
            }
        }
    }
}

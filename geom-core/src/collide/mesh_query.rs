//! [`MeshQuery`]: distance, closest-point, inside/outside and ray queries against a closed
//! triangle mesh, on a parry `TriMesh` with pseudo-normals.

use parry3d_f64::query::{PointQueryWithLocation, Ray, RayCast};
use parry3d_f64::shape::{TriMesh as ParryTriMesh, TriMeshFlags};

use super::convert::{pt, to_pt, to_vec, vec};
use crate::error::{Error, Result};
use crate::math::{Pt3, Vec3};
use crate::mesh::TriMesh;
use crate::spatial::{Aabb, AabbTree};

/// The closest surface point of a mesh to a query point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Closest {
    /// The closest point on the surface.
    pub point: Pt3,
    /// The face it lies on (an index into the mesh's faces).
    pub face: u32,
    /// Its barycentric coordinates in that face (corner order of the face).
    pub bary: [f64; 3],
    /// Unsigned distance from the query point (m).
    pub distance: f64,
}

/// Point and ray queries against a closed, consistently oriented triangle mesh (RG BN FT):
/// closest point with face and barycentrics, signed distance (negative inside) and ray casts.
///
/// Inside/outside is decided by the **angle-weighted pseudo-normal** of the closest feature (face,
/// edge or vertex; Bærentzen & Aanæs 2005), never by ray parity, so it is exact for points
/// whose closest feature is unambiguous and robust near edges and vertices. The mesh is held
/// outward-oriented: an inward-oriented input (negative volume) is flipped internally, face
/// indices and barycentric corner order stay those of the input.
#[derive(Clone)]
pub struct MeshQuery {
    mesh: ParryTriMesh,
    faces: Vec<[u32; 3]>,
    positions: Vec<Pt3>,
    /// The input was inward oriented; parry holds faces `[a, c, b]`.
    flipped: bool,
    bbox: Aabb,
    /// Face boxes for the rounded-mesh ray cast of [`super::Placed`].
    tree: AabbTree,
}

impl std::fmt::Debug for MeshQuery {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("MeshQuery")
            .field("n_vertices", &self.positions.len())
            .field("n_faces", &self.faces.len())
            .field("flipped", &self.flipped)
            .field("bbox", &self.bbox)
            .finish()
    }
}

impl MeshQuery {
    /// Builds the query structure for a closed mesh.
    ///
    /// Errors: `NotClosed { boundary_edges }` if the mesh has a boundary; `InvalidParameter` if it
    /// has no faces or encloses zero volume.
    pub fn new(m: &TriMesh) -> Result<Self> {
        let topo = m.topology();
        if !topo.is_closed() {
            return Err(Error::NotClosed { boundary_edges: topo.n_boundary_edges() });
        }
        if m.faces.is_empty() {
            return Err(Error::InvalidParameter("MeshQuery: the mesh has no faces".into()));
        }
        // Orientation from the signed volume (divergence theorem, about the first vertex to limit
        // cancellation).
        let o = m.positions[m.faces[0][0] as usize];
        let vol6: f64 = m
            .faces
            .iter()
            .map(|f| {
                let [a, b, c] = f.map(|v| m.positions[v as usize] - o);
                a.dot(&b.cross(&c))
            })
            .sum();
        if !(vol6 != 0.0 && vol6.is_finite()) {
            return Err(Error::InvalidParameter(format!("MeshQuery: enclosed volume is {}", vol6 / 6.0)));
        }
        let flipped = vol6 < 0.0;
        let vertices = m.positions.iter().map(pt).collect();
        let indices = m.faces.iter().map(|&[a, b, c]| if flipped { [a, c, b] } else { [a, b, c] }).collect();
        let mesh = ParryTriMesh::with_flags(vertices, indices, TriMeshFlags::ORIENTED)
            .map_err(|e| Error::InvalidParameter(format!("MeshQuery: parry rejected the mesh: {e:?}")))?;
        let boxes: Vec<Aabb> = m.faces.iter().map(|f| Aabb::from_points(&f.map(|v| m.positions[v as usize]))).collect();
        Ok(Self {
            mesh,
            faces: m.faces.clone(),
            positions: m.positions.clone(),
            flipped,
            bbox: Aabb::from_points(&m.positions),
            tree: AabbTree::build(&boxes),
        })
    }

    /// The mesh's vertex positions.
    pub fn positions(&self) -> &[Pt3] {
        &self.positions
    }

    /// The mesh's faces (as given, whatever the orientation).
    pub fn faces(&self) -> &[[u32; 3]] {
        &self.faces
    }

    /// Bounding box of the vertices.
    pub fn bbox(&self) -> Aabb {
        self.bbox
    }

    /// Unit outward normal of face `f` (zero for a degenerate face).
    pub fn face_normal(&self, f: u32) -> Vec3 {
        let [a, b, c] = self.faces[f as usize].map(|v| self.positions[v as usize]);
        let n = (b - a).cross(&(c - a)).try_normalize(0.0).unwrap_or_else(Vec3::zeros);
        if self.flipped {
            -n
        } else {
            n
        }
    }

    /// Closest point, its face and barycentrics, and whether `p` is inside (pseudo-normal test).
    fn project(&self, p: &Pt3) -> (Closest, bool) {
        let (proj, (face, loc)) = self.mesh.project_local_point_and_get_location(pt(p), false);
        let point = to_pt(proj.point);
        // `OnSolid` only arises for solid queries; the fallback is the face's first corner.
        let b = loc.barycentric_coordinates().unwrap_or([1.0, 0.0, 0.0]);
        let bary = if self.flipped { [b[0], b[2], b[1]] } else { b };
        let distance = (p - point).norm();
        (Closest { point, face, bary, distance }, proj.is_inside)
    }

    /// The closest surface point to `p`.
    pub fn closest(&self, p: &Pt3) -> Closest {
        self.project(p).0
    }

    /// Signed distance from `p` to the surface: negative inside, positive outside, the sign from
    /// the pseudo-normal of the closest feature (never ray parity).
    pub fn signed_distance(&self, p: &Pt3) -> f64 {
        let (c, inside) = self.project(p);
        if inside && c.distance > 0.0 {
            -c.distance
        } else {
            c.distance
        }
    }

    /// Closest point and signed distance together (one projection).
    pub fn closest_signed(&self, p: &Pt3) -> (Closest, f64) {
        let (c, inside) = self.project(p);
        let sd = if inside && c.distance > 0.0 { -c.distance } else { c.distance };
        (c, sd)
    }

    /// First intersection of the ray `o + t d`, `0 ≤ t ≤ max_t`, with the surface (front or back
    /// faces): `(t, face)`, or `None`. `t` is in units of `|d|`.
    pub fn ray_cast(&self, o: &Pt3, d: &Vec3, max_t: f64) -> Option<(f64, u32)> {
        let ray = Ray::new(pt(o), vec(d));
        self.mesh.cast_local_ray_and_get_normal(&ray, max_t, false).map(|hit| (hit.time_of_impact, hit.subshape))
    }

    /// Like [`MeshQuery::ray_cast`], also returning parry's hit normal (unit; the face normal,
    /// sign as parry reports it).
    pub(crate) fn ray_cast_normal(&self, o: &Pt3, d: &Vec3, max_t: f64) -> Option<(f64, u32, Vec3)> {
        let ray = Ray::new(pt(o), vec(d));
        self.mesh
            .cast_local_ray_and_get_normal(&ray, max_t, false)
            .map(|hit| (hit.time_of_impact, hit.subshape, to_vec(hit.normal)))
    }

    /// Calls `f` for every face whose bounding box overlaps `b`.
    pub(crate) fn faces_overlapping(&self, b: &Aabb, f: impl FnMut(u32)) {
        self.tree.query(b, f);
    }

    /// The parry mesh (for the contact queries of [`super::Placed`]).
    pub(crate) fn parry_mesh(&self) -> &ParryTriMesh {
        &self.mesh
    }
}

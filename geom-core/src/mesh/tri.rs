//! [`TriMesh`]: a validated manifold, consistently oriented triangle mesh with optional UVs and
//! its shared half-edge [`Topology`].

use std::sync::Arc;

use super::Topology;
use crate::error::{Error, Result};
use crate::math::{AsPt3, Pt2, Pt3};
use crate::spatial::Aabb;

/// Texture coordinates in metres of material space (GEOM-CORE.md §3.6).
#[derive(Clone, Debug, PartialEq)]
pub enum Uv {
    /// One UV per vertex (no seams).
    PerVertex(Vec<Pt2>),
    /// Three UVs per face, one per corner in face order (seams allowed).
    PerCorner(Vec<[Pt2; 3]>),
}

impl Uv {
    /// The UV of corner `k` of face `f` with vertex indices `face`.
    pub fn corner(&self, f: usize, face: &[u32; 3], k: usize) -> Pt2 {
        match self {
            Uv::PerVertex(uv) => uv[face[k] as usize],
            Uv::PerCorner(uv) => uv[f][k],
        }
    }
}

/// A manifold, consistently oriented triangle mesh (faces counter-clockwise seen from the front).
///
/// `positions`, `faces` and `uv` are public for reading and for moving vertices; do not change
/// `faces` in place (the cached [`Topology`] would no longer match): build a new mesh instead.
#[derive(Clone, Debug)]
pub struct TriMesh {
    /// Vertex positions (m).
    pub positions: Vec<Pt3>,
    /// Triangles as vertex index triples, counter-clockwise seen from the front.
    pub faces: Vec<[u32; 3]>,
    /// Optional texture coordinates.
    pub uv: Option<Uv>,
    topo: Arc<Topology>,
}

impl PartialEq for TriMesh {
    fn eq(&self, o: &Self) -> bool {
        self.positions == o.positions && self.faces == o.faces && self.uv == o.uv
    }
}

/// Degenerate-face threshold: a face is degenerate when its area is below this times the squared
/// bounding-box diagonal (GEOM-CORE.md §3.4).
pub const DEGENERATE_REL_AREA: f64 = 1e-14;

impl TriMesh {
    /// Validates and builds a mesh. Strict: nothing is repaired (see [`TriMesh::repair`]).
    ///
    /// Errors, each naming the offending element, checked in this order:
    /// [`Error::NonFiniteVertex`] (NaN/∞ coordinate), [`Error::IndexOutOfRange`] (index out of
    /// range or repeated within a face), [`Error::DegenerateFace`] (area < 1e-14·(bbox
    /// diagonal)²), then the topology checks of [`Topology::new`]: [`Error::NonManifoldEdge`],
    /// [`Error::InconsistentOrientation`], [`Error::NonManifoldVertex`]. A mesh with no faces is
    /// valid; vertices in no face are allowed.
    pub fn new(positions: Vec<Pt3>, faces: Vec<[u32; 3]>) -> Result<Self> {
        check_finite(&positions)?;
        let n = positions.len();
        for (f, t) in faces.iter().enumerate() {
            for k in 0..3 {
                let v = t[k];
                if v as usize >= n || t[(k + 1) % 3] == v {
                    return Err(Error::IndexOutOfRange { face: f as u32, vertex: v });
                }
            }
        }
        if let Some(f) = first_degenerate(&positions, &faces) {
            return Err(Error::DegenerateFace { face: f });
        }
        let topo = Topology::new(n, &faces)?;
        Ok(Self { positions, faces, uv: None, topo: Arc::new(topo) })
    }

    /// Builds a mesh from parts already known to be valid for `topo` (same faces).
    pub(crate) fn from_parts(positions: Vec<Pt3>, faces: Vec<[u32; 3]>, uv: Option<Uv>, topo: Arc<Topology>) -> Self {
        debug_assert_eq!(positions.len(), topo.n_vertices());
        debug_assert_eq!(faces.len(), topo.n_faces());
        Self { positions, faces, uv, topo }
    }

    /// Attaches texture coordinates. Errors: [`Error::DimensionMismatch`] when a per-vertex list
    /// does not have one entry per vertex or a per-corner list one entry per face;
    /// [`Error::NonFinite`] for NaN/∞ UVs.
    pub fn with_uv(mut self, uv: Uv) -> Result<Self> {
        let (what, expected, got, finite) = match &uv {
            Uv::PerVertex(v) => (
                "per-vertex UVs",
                self.positions.len(),
                v.len(),
                v.iter().all(|p| p.coords.iter().all(|c| c.is_finite())),
            ),
            Uv::PerCorner(c) => (
                "per-corner UVs",
                self.faces.len(),
                c.len(),
                c.iter().flatten().all(|p| p.coords.iter().all(|c| c.is_finite())),
            ),
        };
        if expected != got {
            return Err(Error::DimensionMismatch { what, expected, got });
        }
        if !finite {
            return Err(Error::NonFinite(what));
        }
        self.uv = Some(uv);
        Ok(self)
    }

    /// A mesh with the same faces, UVs and (shared, not copied) topology but new positions.
    /// Errors: [`Error::TopologyMismatch`] if the vertex count differs, [`Error::NonFiniteVertex`].
    /// Degeneracy is not re-checked: deformed meshes may pass through flat triangles.
    pub fn with_positions(&self, positions: Vec<Pt3>) -> Result<Self> {
        if positions.len() != self.positions.len() {
            return Err(Error::TopologyMismatch { expected: self.positions.len(), got: positions.len() });
        }
        check_finite(&positions)?;
        Ok(Self { positions, faces: self.faces.clone(), uv: self.uv.clone(), topo: Arc::clone(&self.topo) })
    }

    /// The half-edge connectivity.
    pub fn topology(&self) -> &Topology {
        &self.topo
    }

    /// The shared topology handle (cheap to clone).
    pub fn topology_arc(&self) -> &Arc<Topology> {
        &self.topo
    }

    /// Number of vertices.
    pub fn n_vertices(&self) -> usize {
        self.positions.len()
    }

    /// Number of faces.
    pub fn n_faces(&self) -> usize {
        self.faces.len()
    }

    /// Axis-aligned bounding box of all positions (including vertices in no face) as
    /// `(min, max)`; `None` for a mesh without vertices. See also [`TriMesh::aabb`].
    pub fn bbox(&self) -> Option<(Pt3, Pt3)> {
        bbox_of(&self.positions)
    }

    /// The bounding box as a [`crate::spatial::Aabb`] (the empty box for a mesh without vertices).
    pub fn aabb(&self) -> Aabb {
        Aabb::from_points(&self.positions)
    }
}

/// Axis-aligned bounding box `(min, max)` of points; `None` when empty (see also
/// [`Aabb::from_points`]).
pub fn bbox_of<P: AsPt3>(p: &[P]) -> Option<(Pt3, Pt3)> {
    let first = p.first()?.pt3();
    Some(p.iter().fold((first, first), |(lo, hi), q| {
        let q = q.pt3();
        (lo.inf(&q), hi.sup(&q))
    }))
}

fn check_finite(p: &[Pt3]) -> Result<()> {
    match p.iter().position(|q| !q.coords.iter().all(|c| c.is_finite())) {
        Some(v) => Err(Error::NonFiniteVertex { vertex: v as u32 }),
        None => Ok(()),
    }
}

/// Squared bounding-box diagonal of `p` (0 when empty).
pub(crate) fn bbox_diag2<P: AsPt3>(p: &[P]) -> f64 {
    bbox_of(p).map(|(lo, hi)| (hi - lo).norm_squared()).unwrap_or(0.0)
}

/// True when the face's area is below [`DEGENERATE_REL_AREA`]·`diag2`.
pub(crate) fn is_degenerate(p: &[Pt3], t: &[u32; 3], diag2: f64) -> bool {
    let (a, b, c) = (p[t[0] as usize], p[t[1] as usize], p[t[2] as usize]);
    let area = 0.5 * (b - a).cross(&(c - a)).norm();
    // Written so that a NaN area also counts as degenerate.
    let ok = area >= DEGENERATE_REL_AREA * diag2 && area > 0.0;
    !ok
}

/// Index of the first degenerate face (indices must be in range).
fn first_degenerate(p: &[Pt3], faces: &[[u32; 3]]) -> Option<u32> {
    let d2 = bbox_diag2(p);
    faces.iter().position(|t| is_degenerate(p, t, d2)).map(|f| f as u32)
}

//! [`MeshOut`]: a borrowed view of what a writer should put in a file, so that callers write
//! meshes, deformed frames and f32 bulk output without copying into an owned mesh type.

use crate::error::{Error, Result};
use crate::graph::Ragged;
use crate::math::{Pt3, Vec3};
use crate::mesh::{PolyMesh, TriMesh, Uv};

/// Vertex positions to write: f64 points, or f32 triples for bulk output (curve-skin, barnet).
#[derive(Clone, Copy, Debug)]
pub enum Positions<'a> {
    /// Double-precision positions (m).
    F64(&'a [Pt3]),
    /// Single-precision positions (m).
    F32(&'a [[f32; 3]]),
}

impl Positions<'_> {
    /// Number of vertices.
    pub fn len(&self) -> usize {
        match self {
            Positions::F64(p) => p.len(),
            Positions::F32(p) => p.len(),
        }
    }

    /// True when there are no vertices.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Vertex `i` as f64 (exact for f32 input).
    pub fn get(&self, i: usize) -> [f64; 3] {
        match self {
            Positions::F64(p) => [p[i].x, p[i].y, p[i].z],
            Positions::F32(p) => p[i].map(f64::from),
        }
    }

    /// Index of the first vertex with a NaN or infinite coordinate.
    pub(crate) fn first_non_finite(&self) -> Option<usize> {
        (0..self.len()).find(|&i| self.get(i).iter().any(|c| !c.is_finite()))
    }
}

/// Faces to write: triangles or polygons (each row at least three vertices).
#[derive(Clone, Copy, Debug)]
pub enum Faces<'a> {
    /// Triangles.
    Tri(&'a [[u32; 3]]),
    /// Polygons, one row of vertex indices per face.
    Poly(&'a Ragged<u32>),
}

impl<'a> Faces<'a> {
    /// Number of faces.
    pub fn len(&self) -> usize {
        match self {
            Faces::Tri(f) => f.len(),
            Faces::Poly(f) => f.len(),
        }
    }

    /// True when there are no faces.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Vertex indices of face `i`.
    pub fn row(&self, i: usize) -> &'a [u32] {
        match *self {
            Faces::Tri(f) => &f[i],
            Faces::Poly(f) => f.row(i),
        }
    }
}

/// What a mesh writer writes: borrowed positions, faces, optional UVs and optional per-vertex
/// normals (unit vectors, one per vertex).
///
/// Build with [`MeshOut::tri`], [`MeshOut::poly`], [`MeshOut::tri_f32`],
/// [`MeshOut::from_tri_mesh`] or [`MeshOut::from_poly_mesh`], then add [`MeshOut::with_uv`] /
/// [`MeshOut::with_normals`]. [`MeshOut::validate`] (called by every writer) checks that sizes
/// and indices agree, so no writer produces a file that its own reader would refuse.
#[derive(Clone, Copy, Debug)]
pub struct MeshOut<'a> {
    /// Vertex positions.
    pub positions: Positions<'a>,
    /// Faces (may be empty: a point set).
    pub faces: Faces<'a>,
    /// Texture coordinates: per vertex, or per corner (triangles only).
    pub uv: Option<&'a Uv>,
    /// Per-vertex normals.
    pub normals: Option<&'a [Vec3]>,
}

impl<'a> MeshOut<'a> {
    /// Triangles over f64 positions, no UVs or normals.
    pub fn tri(positions: &'a [Pt3], faces: &'a [[u32; 3]]) -> Self {
        Self { positions: Positions::F64(positions), faces: Faces::Tri(faces), uv: None, normals: None }
    }

    /// Triangles over f32 positions.
    pub fn tri_f32(positions: &'a [[f32; 3]], faces: &'a [[u32; 3]]) -> Self {
        Self { positions: Positions::F32(positions), faces: Faces::Tri(faces), uv: None, normals: None }
    }

    /// Polygons over f64 positions.
    pub fn poly(positions: &'a [Pt3], faces: &'a Ragged<u32>) -> Self {
        Self { positions: Positions::F64(positions), faces: Faces::Poly(faces), uv: None, normals: None }
    }

    /// A [`TriMesh`] with its UVs (if any).
    pub fn from_tri_mesh(m: &'a TriMesh) -> Self {
        Self { uv: m.uv.as_ref(), ..Self::tri(&m.positions, &m.faces) }
    }

    /// A [`PolyMesh`]'s positions and faces. Its per-vertex UVs are a `Vec<Pt2>`, not a [`Uv`],
    /// so they are not attached here (a `MeshOut` borrows, it cannot wrap them); pass
    /// `Uv::PerVertex(uv.clone())` to [`MeshOut::with_uv`] to write them.
    pub fn from_poly_mesh(m: &'a PolyMesh) -> Self {
        Self::poly(&m.positions, &m.faces)
    }

    /// Adds texture coordinates.
    pub fn with_uv(self, uv: &'a Uv) -> Self {
        Self { uv: Some(uv), ..self }
    }

    /// Adds per-vertex normals.
    pub fn with_normals(self, normals: &'a [Vec3]) -> Self {
        Self { normals: Some(normals), ..self }
    }

    /// Checks what every writer needs: finite positions ([`Error::NonFiniteVertex`]), faces of at
    /// least three in-range vertices ([`Error::InvalidParameter`], [`Error::IndexOutOfRange`]),
    /// one UV per vertex or per triangle and one normal per vertex ([`Error::DimensionMismatch`]),
    /// per-corner UVs only with triangle faces ([`Error::InvalidParameter`]), finite UVs and
    /// normals ([`Error::NonFinite`]).
    pub fn validate(&self) -> Result<()> {
        if let Some(v) = self.positions.first_non_finite() {
            return Err(Error::NonFiniteVertex { vertex: v as u32 });
        }
        let n = self.positions.len();
        if n > u32::MAX as usize {
            return Err(Error::InvalidParameter(format!("{n} vertices do not fit u32 indices")));
        }
        for f in 0..self.faces.len() {
            let row = self.faces.row(f);
            if row.len() < 3 {
                return Err(Error::InvalidParameter(format!(
                    "face {f} has {} vertices; mesh files need at least 3 per face",
                    row.len()
                )));
            }
            if let Some(&v) = row.iter().find(|&&v| v as usize >= n) {
                return Err(Error::IndexOutOfRange { face: f as u32, vertex: v });
            }
        }
        match self.uv {
            None => {}
            Some(Uv::PerVertex(uv)) => {
                if uv.len() != n {
                    return Err(Error::DimensionMismatch { what: "per-vertex UVs", expected: n, got: uv.len() });
                }
                if uv.iter().any(|p| !(p.x.is_finite() && p.y.is_finite())) {
                    return Err(Error::NonFinite("UVs to write"));
                }
            }
            Some(Uv::PerCorner(uv)) => {
                if !matches!(self.faces, Faces::Tri(_)) {
                    return Err(Error::InvalidParameter(
                        "per-corner UVs ([Pt2; 3] per face) need triangle faces, got polygons".into(),
                    ));
                }
                if uv.len() != self.faces.len() {
                    return Err(Error::DimensionMismatch {
                        what: "per-corner UVs",
                        expected: self.faces.len(),
                        got: uv.len(),
                    });
                }
                if uv.iter().flatten().any(|p| !(p.x.is_finite() && p.y.is_finite())) {
                    return Err(Error::NonFinite("UVs to write"));
                }
            }
        }
        if let Some(nr) = self.normals {
            if nr.len() != n {
                return Err(Error::DimensionMismatch { what: "per-vertex normals", expected: n, got: nr.len() });
            }
            if nr.iter().any(|v| v.iter().any(|c| !c.is_finite())) {
                return Err(Error::NonFinite("normals to write"));
            }
        }
        Ok(())
    }
}

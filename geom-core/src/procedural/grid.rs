//! [`grid`]: a rectangular, triangulated planar sheet.

use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};
use crate::math::{Pt2, Pt3, Vec3};
use crate::mesh::{TriMesh, Uv};

/// The coordinate plane a [`grid`] lies in; the first named axis is the grid's first (`u`) axis.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum Plane {
    /// `u` along +X, `v` along +Y; faces point to +Z.
    #[default]
    XY,
    /// `u` along +X, `v` along +Z; faces point to +Y (a ground-parallel sheet facing up).
    XZ,
    /// `u` along +Y, `v` along +Z; faces point to +X.
    YZ,
}

impl Plane {
    /// `(u axis, v axis, front normal)`.
    pub fn axes(self) -> (Vec3, Vec3, Vec3) {
        match self {
            Plane::XY => (Vec3::x(), Vec3::y(), Vec3::z()),
            Plane::XZ => (Vec3::x(), Vec3::z(), Vec3::y()),
            Plane::YZ => (Vec3::y(), Vec3::z(), Vec3::x()),
        }
    }
}

/// How each quad is split into two triangles. With corners `v00 = (i, j)`, `v10 = (i+1, j)`,
/// `v01 = (i, j+1)`, `v11 = (i+1, j+1)`:
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum Diagonals {
    /// Forward where `i + j` is even, Backward where odd (no preferred shear direction).
    #[default]
    Alternating,
    /// Diagonal `v00–v11` in every quad.
    Forward,
    /// Diagonal `v10–v01` in every quad.
    Backward,
}

impl Diagonals {
    /// Whether quad `(i, j)` uses the forward diagonal `v00–v11`.
    pub fn forward(self, i: u32, j: u32) -> bool {
        match self {
            Diagonals::Alternating => (i + j) & 1 == 0,
            Diagonals::Forward => true,
            Diagonals::Backward => false,
        }
    }
}

/// A planar grid of `quads[0] × quads[1]` quads, `size` metres, centred at `center`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct GridSpec {
    /// Quads along `u` and `v` (vertices per side are one more), each ≥ 1.
    pub quads: [u32; 2],
    /// Extent along `u` and `v` (m), each > 0.
    pub size: [f64; 2],
    /// The plane and orientation.
    pub plane: Plane,
    /// Quad split pattern.
    pub diagonals: Diagonals,
    /// Centre of the sheet (m).
    pub center: Pt3,
}

impl Default for GridSpec {
    /// A 1 m × 1 m, 10 × 10-quad sheet in the XY plane at the origin, alternating diagonals.
    fn default() -> Self {
        Self {
            quads: [10, 10],
            size: [1.0, 1.0],
            plane: Plane::XY,
            diagonals: Diagonals::Alternating,
            center: Pt3::origin(),
        }
    }
}

/// Triangulated grid: `(quads[0]+1)·(quads[1]+1)` vertices in row-major order from the min corner
/// (vertex `(i, j)` has index `j·(quads[0]+1) + i`, `i` along `u`), two triangles per quad in
/// row-major quad order, faces pointing along the plane's normal (see [`Plane`]), per-vertex UVs
/// `(u, v) ∈ [0, size[0]] × [0, size[1]]` in metres from the min corner.
///
/// Errors: [`Error::InvalidParameter`] for zero quads, non-positive or non-finite size or
/// centre, or more than 2³¹ vertices.
pub fn grid(s: &GridSpec) -> Result<TriMesh> {
    let [nx, ny] = s.quads;
    if nx == 0 || ny == 0 {
        return Err(Error::InvalidParameter(format!("grid quads must be ≥ 1, got {:?}", s.quads)));
    }
    if !s.size.iter().all(|v| *v > 0.0 && v.is_finite()) {
        return Err(Error::InvalidParameter(format!("grid size must be positive and finite, got {:?}", s.size)));
    }
    if !s.center.coords.iter().all(|c| c.is_finite()) {
        return Err(Error::InvalidParameter("grid center must be finite".into()));
    }
    let nv = (nx as u64 + 1) * (ny as u64 + 1);
    if nv > 1 << 31 {
        return Err(Error::InvalidParameter(format!("grid with {nv} vertices is too large")));
    }
    let (ax, ay, _) = s.plane.axes();
    let (w, h) = (s.size[0], s.size[1]);
    let row = nx + 1;
    let mut positions = Vec::with_capacity(nv as usize);
    let mut uv = Vec::with_capacity(nv as usize);
    for j in 0..=ny {
        let v = h * j as f64 / ny as f64;
        for i in 0..=nx {
            let u = w * i as f64 / nx as f64;
            positions.push(s.center + (u - 0.5 * w) * ax + (v - 0.5 * h) * ay);
            uv.push(Pt2::new(u, v));
        }
    }
    // (u, v) → (x, z) is left-handed about +Y: reverse the winding so XZ faces point to +Y.
    let flip = s.plane == Plane::XZ;
    let mut faces = Vec::with_capacity(2 * (nx * ny) as usize);
    for j in 0..ny {
        for i in 0..nx {
            let v00 = j * row + i;
            let (v10, v01, v11) = (v00 + 1, v00 + row, v00 + row + 1);
            let (t1, t2) = if s.diagonals.forward(i, j) {
                ([v00, v10, v11], [v00, v11, v01])
            } else {
                ([v00, v10, v01], [v10, v11, v01])
            };
            for t in [t1, t2] {
                faces.push(if flip { [t[0], t[2], t[1]] } else { t });
            }
        }
    }
    TriMesh::new(positions, faces)?.with_uv(Uv::PerVertex(uv))
}

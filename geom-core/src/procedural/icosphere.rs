//! [`icosphere`]: a sphere from a repeatedly subdivided icosahedron.

use crate::error::{Error, Result};
use crate::math::Pt3;
use crate::mesh::{subdivide_linear, TriMesh};

/// Largest accepted subdivision level (10·4¹⁰ + 2 ≈ 10.5 M vertices).
pub const ICOSPHERE_MAX_LEVEL: u32 = 10;

/// Sphere of `radius` (m) centred at the origin: the regular icosahedron (level 0: 12 vertices,
/// 20 faces) subdivided `level` times by midpoint quadrisection, every vertex projected onto the
/// sphere after each level: `10·4^level + 2` vertices, `20·4^level` faces, outward. Coarse
/// vertices keep their indices at every level (the numbering of
/// [`crate::mesh::subdivide_linear`]).
///
/// Errors: [`Error::InvalidParameter`] for a non-positive or non-finite radius or
/// `level > ICOSPHERE_MAX_LEVEL`.
pub fn icosphere(radius: f64, level: u32) -> Result<TriMesh> {
    if !(radius > 0.0 && radius.is_finite()) {
        return Err(Error::InvalidParameter(format!("icosphere radius must be positive and finite, got {radius}")));
    }
    if level > ICOSPHERE_MAX_LEVEL {
        return Err(Error::InvalidParameter(format!("icosphere level {level} exceeds {ICOSPHERE_MAX_LEVEL}")));
    }
    let t = (1.0 + 5f64.sqrt()) / 2.0;
    let raw = [
        [-1.0, t, 0.0],
        [1.0, t, 0.0],
        [-1.0, -t, 0.0],
        [1.0, -t, 0.0],
        [0.0, -1.0, t],
        [0.0, 1.0, t],
        [0.0, -1.0, -t],
        [0.0, 1.0, -t],
        [t, 0.0, -1.0],
        [t, 0.0, 1.0],
        [-t, 0.0, -1.0],
        [-t, 0.0, 1.0],
    ];
    let faces = vec![
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    let project = |p: &Pt3| Pt3::from(p.coords * (radius / p.coords.norm()));
    let positions = raw.iter().map(|c| project(&Pt3::new(c[0], c[1], c[2]))).collect();
    let mut m = TriMesh::new(positions, faces)?;
    for _ in 0..level {
        let (fine, _) = subdivide_linear(&m, 1);
        let p = fine.positions.iter().map(project).collect();
        m = fine.with_positions(p)?;
    }
    Ok(m)
}

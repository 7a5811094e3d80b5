//! [`box_surface`]: the closed, outward-oriented, subdivided surface of an axis-aligned box.

use std::collections::HashMap;

use super::Diagonals;
use crate::error::{Error, Result};
use crate::math::Pt3;
use crate::mesh::TriMesh;

/// Closed triangulated surface of the box `[min, max]` with `segments[a]` quads along axis `a`
/// on every side, shared vertices along the edges and corners (a watertight manifold), faces
/// outward. Each side is a grid split by `d` (pattern indices `(i, j)` along the side's two
/// axes). Vertices are numbered in order of first use, sides in the order −X, +X, −Y, +Y, −Z,
/// +Z; lattice coordinates hit `min`/`max` exactly on the extreme planes.
///
/// Errors: [`Error::InvalidParameter`] for `min ≥ max` on any axis, non-finite corners or a
/// zero segment count.
pub fn box_surface(min: Pt3, max: Pt3, segments: [u32; 3], d: Diagonals) -> Result<TriMesh> {
    if !(0..3).all(|a| min[a].is_finite() && max[a].is_finite() && min[a] < max[a]) {
        return Err(Error::InvalidParameter(format!("box needs finite min < max on every axis, got {min:?}, {max:?}")));
    }
    if segments.contains(&0) || segments.iter().map(|&s| s as u64 + 1).product::<u64>() > 1 << 31 {
        return Err(Error::InvalidParameter(format!("box segments must be ≥ 1 (and not huge), got {segments:?}")));
    }
    let coord = |a: usize, i: u32| -> f64 {
        if i == segments[a] {
            max[a]
        } else {
            min[a] + (max[a] - min[a]) * (i as f64 / segments[a] as f64)
        }
    };
    // (fixed axis, at max?, u axis, v axis) with u × v = outward normal.
    let sides: [(usize, bool, usize, usize); 6] =
        [(0, false, 2, 1), (0, true, 1, 2), (1, false, 0, 2), (1, true, 2, 0), (2, false, 1, 0), (2, true, 0, 1)];
    let mut index: HashMap<[u32; 3], u32> = HashMap::new();
    let mut positions = Vec::new();
    let mut faces = Vec::new();
    for (fixed, at_max, ua, va) in sides {
        let (nu, nv) = (segments[ua], segments[va]);
        let mut id = |i: u32, j: u32| -> u32 {
            let mut key = [0u32; 3];
            key[fixed] = if at_max { segments[fixed] } else { 0 };
            key[ua] = i;
            key[va] = j;
            *index.entry(key).or_insert_with(|| {
                positions.push(Pt3::new(coord(0, key[0]), coord(1, key[1]), coord(2, key[2])));
                (positions.len() - 1) as u32
            })
        };
        for j in 0..nv {
            for i in 0..nu {
                let (v00, v10, v01, v11) = (id(i, j), id(i + 1, j), id(i, j + 1), id(i + 1, j + 1));
                if d.forward(i, j) {
                    faces.push([v00, v10, v11]);
                    faces.push([v00, v11, v01]);
                } else {
                    faces.push([v00, v10, v01]);
                    faces.push([v10, v11, v01]);
                }
            }
        }
    }
    TriMesh::new(positions, faces)
}

//! Mesh self-intersection: an [`AabbTree`] broad phase over the faces, then the exact
//! [`tri_tri_intersect`] test on every candidate pair that shares no vertex.

use rayon::prelude::*;

use super::tri_tri::tri_tri_intersect;
use crate::math::{AsPt3, Pt3};
use crate::spatial::{Aabb, AabbTree};

/// All pairs `(i, j)`, `i < j`, of faces that share no vertex index and intersect (touching
/// counts), sorted. Faces sharing a vertex are adjacent in the mesh and skipped: their contact
/// is by construction. The narrow phase is exact (see [`tri_tri_intersect`]), and runs in
/// parallel with a deterministic result.
///
/// # Panics
/// If a face refers to a vertex index outside `p` (validated meshes never do).
pub fn self_intersecting_pairs<P: AsPt3>(faces: &[[u32; 3]], p: &[P]) -> Vec<(u32, u32)> {
    let tri = |f: &[u32; 3]| -> [Pt3; 3] { f.map(|v| p[v as usize].pt3()) };
    let boxes: Vec<Aabb> = faces.iter().map(|f| Aabb::from_points(&tri(f))).collect();
    let tree = AabbTree::build(&boxes);
    let mut candidates = Vec::new();
    tree.self_pairs(|i, j| {
        let (a, b) = (&faces[i as usize], &faces[j as usize]);
        if !a.iter().any(|v| b.contains(v)) {
            candidates.push((i, j));
        }
    });
    candidates.sort_unstable();
    candidates
        .into_par_iter()
        .filter(|&(i, j)| tri_tri_intersect(&tri(&faces[i as usize]), &tri(&faces[j as usize])))
        .collect()
}

/// Number of intersecting face pairs that share no vertex (see [`self_intersecting_pairs`]).
pub fn count_self_intersections<P: AsPt3>(faces: &[[u32; 3]], p: &[P]) -> usize {
    self_intersecting_pairs(faces, p).len()
}

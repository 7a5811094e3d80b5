//! From polygons as read from a file to a validated [`TriMesh`]: fan triangulation that keeps
//! track of polygon corners (so per-corner UVs follow their triangles), the per-vertex /
//! per-corner UV decision, and optional explicit vertex welding ([`super::ReadOptions`]).
//!
//! The fan is done here rather than through `PolyMesh::triangulate_fan` because the readers need
//! each triangle corner's position in the polygon list to carry per-corner UVs; the fan itself is
//! the same, polygon `(v0, …, v(n−1))` → triangles `(v0, vi, v(i+1))`, `i = 1 … n−2`.

use crate::error::{Error, Result};
use crate::graph::Ragged;
use crate::math::{Pt2, Pt3};
use crate::mesh::{TriMesh, Uv};

use super::ReadOptions;

/// Texture coordinates as a reader found them.
#[derive(Clone, Debug)]
pub(crate) enum SourceUv {
    /// No texture coordinates (or not on every corner).
    None,
    /// One UV per vertex.
    PerVertex(Vec<Pt2>),
    /// One UV per polygon corner, aligned with `faces.items`.
    PerCorner(Vec<Pt2>),
}

/// Fan triangulation of `faces`; returns the triangles and, per triangle, the indices into
/// `faces.items` of its three corners. Rows with fewer than three vertices give no triangle
/// (the readers never produce them).
pub(crate) fn fan(faces: &Ragged<u32>) -> (Vec<[u32; 3]>, Vec<[u32; 3]>) {
    let n_tri: usize = faces.rows().map(|r| r.len().saturating_sub(2)).sum();
    let mut tris = Vec::with_capacity(n_tri);
    let mut corners = Vec::with_capacity(n_tri);
    for f in 0..faces.len() {
        let o = faces.offsets[f];
        let row = faces.row(f);
        for i in 1..row.len().saturating_sub(1) {
            tris.push([row[0], row[i], row[i + 1]]);
            corners.push([o, o + i as u32, o + i as u32 + 1]);
        }
    }
    (tris, corners)
}

/// One UV per vertex if every corner at a vertex carries the same UV (bitwise equal
/// coordinates); `None` when some vertex has two different UVs (a seam), or when the inputs
/// disagree (lengths differ, a vertex index out of range). Vertices in no face get `(0, 0)`.
pub(crate) fn consistent_vertex_uv(n_vertices: usize, corner_vertex: &[u32], corner_uv: &[Pt2]) -> Option<Vec<Pt2>> {
    if corner_vertex.len() != corner_uv.len() {
        return None;
    }
    let mut uv = vec![Pt2::origin(); n_vertices];
    let mut seen = vec![false; n_vertices];
    for (&v, t) in corner_vertex.iter().zip(corner_uv) {
        let v = v as usize;
        if v >= n_vertices {
            return None;
        }
        if seen[v] {
            if uv[v].x.to_bits() != t.x.to_bits() || uv[v].y.to_bits() != t.y.to_bits() {
                return None;
            }
        } else {
            seen[v] = true;
            uv[v] = *t;
        }
    }
    Some(uv)
}

/// Triangulates and validates (strict [`TriMesh::new`]); UVs become [`Uv::PerVertex`] when each
/// vertex has one consistent UV, [`Uv::PerCorner`] otherwise. With `opts.weld = Some(eps)`,
/// vertices closer than `eps` are merged first (see [`weld_tris`]).
pub(crate) fn build_tri(positions: Vec<Pt3>, faces: &Ragged<u32>, uv: SourceUv, opts: &ReadOptions) -> Result<TriMesh> {
    build_tri_mapped(positions, faces, uv, opts).map(|(m, _)| m)
}

/// As [`build_tri`], also returning the old → new vertex map when welding was done.
pub(crate) fn build_tri_mapped(
    positions: Vec<Pt3>,
    faces: &Ragged<u32>,
    uv: SourceUv,
    opts: &ReadOptions,
) -> Result<(TriMesh, Option<Vec<u32>>)> {
    // ObjData / PlyMesh have public fields: check what the lookups below index with.
    if let Some(f) = (0..faces.len()).find(|&f| faces.row(f).iter().any(|&v| v as usize >= positions.len())) {
        let vertex = faces.row(f).iter().copied().find(|&v| v as usize >= positions.len()).unwrap_or_default();
        return Err(Error::IndexOutOfRange { face: f as u32, vertex });
    }
    match &uv {
        SourceUv::PerVertex(v) if v.len() != positions.len() => {
            return Err(Error::DimensionMismatch { what: "per-vertex UVs", expected: positions.len(), got: v.len() })
        }
        SourceUv::PerCorner(c) if c.len() != faces.items.len() => {
            return Err(Error::DimensionMismatch { what: "per-corner UVs", expected: faces.items.len(), got: c.len() })
        }
        _ => {}
    }
    let (tris, corners) = fan(faces);
    // Per-triangle corner UVs (when any), computed before welding renumbers vertices.
    let tri_uv: Option<Vec<[Pt2; 3]>> = match &uv {
        SourceUv::None => None,
        SourceUv::PerVertex(v) => Some(tris.iter().map(|t| t.map(|i| v[i as usize])).collect()),
        SourceUv::PerCorner(c) => Some(corners.iter().map(|t| t.map(|i| c[i as usize])).collect()),
    };
    let (positions, tris, tri_uv, map) = match opts.weld {
        None => (positions, tris, tri_uv, None),
        Some(eps) => {
            let w = weld_tris(&positions, &tris, tri_uv, eps)?;
            (w.0, w.1, w.2, Some(w.3))
        }
    };
    let mesh = TriMesh::new(positions, tris)?;
    let Some(tri_uv) = tri_uv else { return Ok((mesh, map)) };
    let corner_vertex: Vec<u32> = mesh.faces.iter().flatten().copied().collect();
    let flat: Vec<Pt2> = tri_uv.iter().flatten().copied().collect();
    let uv = match consistent_vertex_uv(mesh.n_vertices(), &corner_vertex, &flat) {
        Some(v) => Uv::PerVertex(v),
        None => Uv::PerCorner(tri_uv),
    };
    Ok((mesh.with_uv(uv)?, map))
}

/// Welded positions, triangles, their corner UVs and the old → new vertex map.
type Welded = (Vec<Pt3>, Vec<[u32; 3]>, Option<Vec<[Pt2; 3]>>, Vec<u32>);

/// Merges vertices closer than `eps` (m) with [`crate::mesh::weld`] and renumbers the
/// triangles. As in `mesh::weld`, triangles that collapse (two corners welded together) are
/// dropped, and their corner UVs with them; the others keep their order.
pub(crate) fn weld_tris(
    positions: &[Pt3],
    tris: &[[u32; 3]],
    tri_uv: Option<Vec<[Pt2; 3]>>,
    eps: f64,
) -> Result<Welded> {
    if !(eps.is_finite() && eps >= 0.0) {
        return Err(Error::InvalidParameter(format!("weld distance must be finite and >= 0, got {eps} m")));
    }
    let (p, _, map) = crate::mesh::weld(positions, tris, eps);
    let mut out = Vec::with_capacity(tris.len());
    let mut out_uv = tri_uv.as_ref().map(|_| Vec::with_capacity(tris.len()));
    for (f, t) in tris.iter().enumerate() {
        let t = t.map(|v| map[v as usize]);
        if t[0] == t[1] || t[1] == t[2] || t[2] == t[0] {
            continue;
        }
        out.push(t);
        if let (Some(o), Some(uv)) = (out_uv.as_mut(), tri_uv.as_ref()) {
            o.push(uv[f]);
        }
    }
    Ok((p, out, out_uv, map))
}

/// Per-vertex values after welding: each new vertex takes the value of the first (lowest
/// index) old vertex mapped to it.
pub(crate) fn remap_first(values: &[f64], map: &[u32], n_new: usize) -> Vec<f64> {
    let mut out = vec![f64::NAN; n_new];
    let mut set = vec![false; n_new];
    for (old, &new) in map.iter().enumerate() {
        let new = new as usize;
        if !set[new] {
            set[new] = true;
            out[new] = values[old];
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fan_covers_polygon_corners_in_order() {
        let faces = Ragged::from_rows([vec![0u32, 1, 2, 3, 4], vec![5, 6, 7]]);
        let (t, c) = fan(&faces);
        assert_eq!(t, vec![[0, 1, 2], [0, 2, 3], [0, 3, 4], [5, 6, 7]]);
        assert_eq!(c, vec![[0, 1, 2], [0, 2, 3], [0, 3, 4], [5, 6, 7]]);
    }

    #[test]
    fn welding_merges_duplicates_and_keeps_corner_uvs_aligned() {
        let p = vec![
            Pt3::new(0.0, 0.0, 0.0),
            Pt3::new(1.0, 0.0, 0.0),
            Pt3::new(1.0, 1.0, 0.0),
            Pt3::new(0.0, 0.0, 0.0),
            Pt3::new(1.0, 1.0, 0.0),
            Pt3::new(0.0, 1.0, 0.0),
            // A sliver that collapses when welded.
            Pt3::new(0.0, 1.0, 1e-12),
        ];
        let faces = Ragged::from_rows([vec![0u32, 1, 2], vec![6, 5, 4], vec![3, 4, 5]]);
        let uv: Vec<Pt2> = (0..9).map(|i| Pt2::new(i as f64, 0.0)).collect();
        let opts = ReadOptions { weld: Some(1e-9) };
        let (m, map) = build_tri_mapped(p, &faces, SourceUv::PerCorner(uv), &opts).unwrap();
        assert_eq!(m.n_vertices(), 4);
        assert_eq!(m.faces, vec![[0, 1, 2], [0, 2, 3]]);
        assert_eq!(map.unwrap(), vec![0, 1, 2, 0, 2, 3, 3]);
        // The surviving second triangle is the file's third one: corners 6, 7, 8.
        match m.uv {
            Some(Uv::PerCorner(c)) => assert_eq!(c[1], [Pt2::new(6.0, 0.0), Pt2::new(7.0, 0.0), Pt2::new(8.0, 0.0)]),
            other => panic!("expected per-corner UVs, got {other:?}"),
        }
        assert_eq!(
            remap_first(&[10.0, 11.0, 12.0, 13.0, 14.0, 15.0, 16.0], &[0, 1, 2, 0, 2, 3, 3], 4),
            vec![10.0, 11.0, 12.0, 15.0]
        );
        let bad = ReadOptions { weld: Some(-1.0) };
        let faces = Ragged::from_rows([vec![0u32, 1, 2]]);
        let p = vec![Pt3::origin(), Pt3::new(1.0, 0.0, 0.0), Pt3::new(0.0, 1.0, 0.0)];
        assert!(matches!(build_tri(p, &faces, SourceUv::None, &bad), Err(Error::InvalidParameter(_))));
    }

    #[test]
    fn vertex_uv_detects_seams() {
        let a = Pt2::new(0.0, 0.0);
        let b = Pt2::new(1.0, 0.0);
        assert!(consistent_vertex_uv(2, &[0, 1, 0], &[a, b, a]).is_some());
        assert!(consistent_vertex_uv(2, &[0, 1, 0], &[a, b, b]).is_none());
        // Unreferenced vertex 2 gets (0, 0).
        assert_eq!(consistent_vertex_uv(3, &[1], &[b]).unwrap(), vec![a, b, a]);
        // Inconsistent inputs give None, not a panic.
        assert!(consistent_vertex_uv(1, &[3], &[b]).is_none());
        assert!(consistent_vertex_uv(2, &[0, 1], &[b]).is_none());
    }

    #[test]
    fn inconsistent_hand_built_inputs_are_errors() {
        let faces = Ragged::from_rows([vec![0u32, 1, 5]]);
        let p = vec![Pt3::origin(), Pt3::new(1.0, 0.0, 0.0), Pt3::new(0.0, 1.0, 0.0)];
        let o = ReadOptions::default();
        assert!(matches!(
            build_tri(p.clone(), &faces, SourceUv::None, &o),
            Err(Error::IndexOutOfRange { face: 0, vertex: 5 })
        ));
        let faces = Ragged::from_rows([vec![0u32, 1, 2]]);
        assert!(matches!(
            build_tri(p.clone(), &faces, SourceUv::PerVertex(vec![Pt2::origin()]), &o),
            Err(Error::DimensionMismatch { .. })
        ));
        assert!(matches!(
            build_tri(p, &faces, SourceUv::PerCorner(vec![Pt2::origin()]), &o),
            Err(Error::DimensionMismatch { .. })
        ));
    }
}

//! Input validation, repair and normalization (rigging spec §3.0, §8 hard cases).
//!
//! Real-world meshes fail bone heat for a handful of classic reasons; this module fixes what is
//! safely fixable and refuses the rest with an error naming the vertices:
//! duplicate (unwelded) vertices are welded (1e-9 × bbox diagonal); zero-area and duplicate
//! faces are dropped; orientation is made consistent and outward; holes (boundary edges) and
//! non-manifold edges are refused (`NotClosed`, `NonManifold`, with example vertex pairs); several
//! components are refused (`NotConnected`) unless the caller keeps the largest.

use std::collections::HashMap;

use geom_core::math::{Pt3, Vec3};
use geom_core::mesh::{RepairOptions, TriMesh};
use nalgebra::{Similarity3, Translation3, UnitQuaternion};

use crate::error::{Result, RigError};

/// What preprocessing changed.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PrepReport {
    /// Vertices merged by welding.
    pub welded_vertices: usize,
    /// Zero-area or collapsed faces dropped.
    pub dropped_degenerate: usize,
    /// Duplicate faces dropped.
    pub dropped_duplicate: usize,
    /// Faces whose orientation was flipped.
    pub flipped_faces: usize,
    /// Components discarded (only with `keep_largest_component`).
    pub dropped_components: usize,
    /// Non-manifold vertices (several fans of faces meeting at one point) split into one vertex
    /// per fan.
    pub split_vertices: usize,
    /// Input vertex → vertex of the prepared mesh (`u32::MAX` for a vertex dropped with a
    /// discarded component). A split vertex maps to its first copy.
    pub vertex_map: Vec<u32>,
}

/// Splits every non-manifold vertex — one where the faces around it form several fans (groups
/// connected through edges at that vertex), e.g. two cones touching at their tips — into one
/// vertex per fan; the copies are appended after the existing vertices. Returns the number of
/// vertices split. Assumes every edge has at most two faces.
pub fn split_nonmanifold_vertices(positions: &mut Vec<Pt3>, faces: &mut [[u32; 3]]) -> usize {
    let n = positions.len();
    let mut around: Vec<Vec<u32>> = vec![Vec::new(); n];
    for (f, t) in faces.iter().enumerate() {
        for &v in t {
            around[v as usize].push(f as u32);
        }
    }
    let mut split = 0;
    for v in 0..n {
        let fs = &around[v];
        if fs.len() < 2 {
            continue;
        }
        // Union-find over the faces at v, joined when they share an edge (v, w).
        let mut parent: Vec<usize> = (0..fs.len()).collect();
        fn find(p: &mut [usize], mut x: usize) -> usize {
            while p[x] != x {
                p[x] = p[p[x]];
                x = p[x];
            }
            x
        }
        let mut by_other: HashMap<u32, usize> = HashMap::new();
        for (k, &f) in fs.iter().enumerate() {
            for &w in &faces[f as usize] {
                if w as usize == v {
                    continue;
                }
                if let Some(&k2) = by_other.get(&w) {
                    let (a, b) = (find(&mut parent, k), find(&mut parent, k2));
                    parent[a.max(b)] = a.min(b);
                } else {
                    by_other.insert(w, k);
                }
            }
        }
        let roots: Vec<usize> = (0..fs.len()).map(|k| find(&mut parent, k)).collect();
        let mut fans: Vec<usize> = roots.clone();
        fans.sort_unstable();
        fans.dedup();
        if fans.len() < 2 {
            continue;
        }
        split += 1;
        // The fan of the lowest face keeps v; every other fan gets a copy.
        for &fan in &fans[1..] {
            let copy = positions.len() as u32;
            positions.push(positions[v]);
            for (k, &f) in fs.iter().enumerate() {
                if roots[k] == fan {
                    for x in faces[f as usize].iter_mut() {
                        if *x as usize == v {
                            *x = copy;
                        }
                    }
                }
            }
        }
    }
    split
}

/// Welds, checks and orients a raw triangle soup into a closed, connected, outward-oriented
/// manifold. `keep_largest_component` keeps the component with the most faces instead of
/// failing with `NotConnected`.
pub fn prepare(positions: &[Pt3], faces: &[[u32; 3]], keep_largest_component: bool) -> Result<(TriMesh, PrepReport)> {
    if faces.is_empty() || positions.is_empty() {
        return Err(RigError::EmptyMesh);
    }
    if positions.iter().any(|p| !p.coords.iter().all(|c| c.is_finite())) {
        return Err(RigError::NonFinite("mesh"));
    }
    if let Some((f, t)) = faces.iter().enumerate().find(|(_, t)| t.iter().any(|&v| v as usize >= positions.len())) {
        return Err(RigError::Degenerate(format!("face {f} indexes vertex {:?} of {}", t, positions.len())));
    }
    // Weld first: unwelded duplicates would otherwise look like holes.
    let diag = geom_core::spatial::Aabb::from_points(positions).diag();
    let (mut wp, mut wf, map) = geom_core::mesh::weld(positions, faces, 1e-9 * diag);
    let mut rep = PrepReport { welded_vertices: positions.len() - wp.len(), vertex_map: map, ..Default::default() };
    let collapsed = faces.len() - wf.len();
    // Edge use counts (undirected) on the welded soup, ignoring exact duplicate faces.
    let mut seen = std::collections::HashSet::new();
    let mut uniq = Vec::with_capacity(wf.len());
    for t in &wf {
        let mut k = *t;
        k.sort_unstable();
        if seen.insert(k) {
            uniq.push(*t);
        }
    }
    let mut count: HashMap<[u32; 2], u32> = HashMap::new();
    for t in &uniq {
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            *count.entry([a.min(b), a.max(b)]).or_insert(0) += 1;
        }
    }
    let mut nonmanifold: Vec<[u32; 2]> = count.iter().filter(|(_, &c)| c > 2).map(|(e, _)| *e).collect();
    nonmanifold.sort_unstable();
    if !nonmanifold.is_empty() {
        return Err(RigError::NonManifold {
            edges: nonmanifold.len(),
            example: nonmanifold.into_iter().take(8).collect(),
        });
    }
    let mut boundary: Vec<[u32; 2]> = count.iter().filter(|(_, &c)| c == 1).map(|(e, _)| *e).collect();
    boundary.sort_unstable();
    if !boundary.is_empty() {
        return Err(RigError::NotClosed {
            boundary_edges: boundary.len(),
            example: boundary.into_iter().take(8).collect(),
        });
    }
    // A non-manifold vertex (two fans touching at a point) is split into one vertex per fan:
    // the surface stays closed and each fan becomes a proper disc.
    rep.split_vertices = split_nonmanifold_vertices(&mut wp, &mut wf);
    let o = RepairOptions { weld_rel: None, drop_degenerate: true, drop_duplicates: true, orient: true, outward: true };
    let (mut m, r) = TriMesh::repair(wp, wf, &o)?;
    rep.dropped_degenerate = collapsed + r.dropped_degenerate;
    rep.dropped_duplicate = r.dropped_duplicate;
    rep.flipped_faces = r.flipped_faces;
    if !m.topology().is_closed() {
        // Dropping degenerate faces can open the surface.
        let b = m.topology().n_boundary_edges();
        let ex = m.topology().boundary_loops().first().map(|l| l.windows(2).take(8).map(|w| [w[0], w[1]]).collect());
        return Err(RigError::NotClosed { boundary_edges: b, example: ex.unwrap_or_default() });
    }
    let (nc, comp) = m.topology().face_components();
    if nc > 1 {
        if !keep_largest_component {
            return Err(RigError::NotConnected { components: nc });
        }
        let mut size = vec![0usize; nc];
        for &c in &comp {
            size[c as usize] += 1;
        }
        // Largest, ties to the lowest component index.
        let best = (0..nc).max_by_key(|&c| (size[c], std::cmp::Reverse(c))).expect("nc > 1");
        let faces: Vec<[u32; 3]> =
            m.faces.iter().zip(&comp).filter(|(_, &c)| c as usize == best).map(|(f, _)| *f).collect();
        let mut remap = vec![u32::MAX; m.positions.len()];
        let mut pos = Vec::new();
        let faces: Vec<[u32; 3]> = faces
            .iter()
            .map(|f| {
                f.map(|v| {
                    if remap[v as usize] == u32::MAX {
                        remap[v as usize] = pos.len() as u32;
                        pos.push(m.positions[v as usize]);
                    }
                    remap[v as usize]
                })
            })
            .collect();
        m = TriMesh::new(pos, faces)?;
        rep.dropped_components = nc - 1;
        for x in rep.vertex_map.iter_mut() {
            *x = remap.get(*x as usize).copied().unwrap_or(u32::MAX);
        }
    }
    let vol = geom_core::mesh::signed_volume(&m.faces, &m.positions);
    if !(vol > 0.0) {
        return Err(RigError::Degenerate(format!("enclosed volume {vol} after orientation")));
    }
    Ok((m, rep))
}

/// Normalization (spec §3.0.2): scale `s = 0.9 / (largest bbox extent)`, translate the bbox
/// centre to (0.5, 0.5, 0.5). Returns the normalized mesh and the similarity original →
/// normalized.
pub fn normalize(mesh: &TriMesh) -> Result<(TriMesh, Similarity3<f64>)> {
    let b = mesh.aabb();
    let ext = b.size().max();
    if !(ext > 0.0 && ext.is_finite()) {
        return Err(RigError::Degenerate(format!("bounding box extent {ext}")));
    }
    let s = 0.9 / ext;
    let c = b.center();
    let sim =
        Similarity3::from_parts(Translation3::from(Vec3::repeat(0.5) - c.coords * s), UnitQuaternion::identity(), s);
    let pos = mesh.positions.iter().map(|p| sim.transform_point(p)).collect();
    Ok((mesh.with_positions(pos)?, sim))
}

#[cfg(test)]
mod tests {
    use super::*;
    use geom_core::procedural::icosphere;

    #[test]
    fn refusals_name_vertices_and_repairs_work() {
        let s = icosphere(1.0, 2).expect("icosphere");
        // Hole: drop one face.
        let err = prepare(&s.positions, &s.faces[1..], false).expect_err("hole");
        assert!(matches!(err, RigError::NotClosed { boundary_edges: 3, ref example } if example.len() == 3));
        // Non-manifold edge: a fin sharing edge (a, b) of face 0.
        let mut p = s.positions.clone();
        p.push(Pt3::new(3.0, 3.0, 3.0));
        let mut f = s.faces.clone();
        let [a, b, _] = f[0];
        f.push([a, b, (p.len() - 1) as u32]);
        f.push([b, a, (p.len() - 1) as u32]);
        assert!(matches!(prepare(&p, &f, false), Err(RigError::NonManifold { edges: 1, .. })));
        // Duplicate vertices: split every face onto its own copies, then weld back.
        let mut p = Vec::new();
        let mut f = Vec::new();
        for t in &s.faces {
            let base = p.len() as u32;
            p.extend(t.iter().map(|&v| s.positions[v as usize]));
            f.push([base, base + 1, base + 2]);
        }
        let (m, rep) = prepare(&p, &f, false).expect("welds");
        assert_eq!(m.n_vertices(), s.n_vertices());
        assert!(rep.welded_vertices > 0);
        // Inverted: flipped back outward.
        let inv: Vec<[u32; 3]> = s.faces.iter().map(|t| [t[0], t[2], t[1]]).collect();
        let (m, _) = prepare(&s.positions, &inv, false).expect("orients");
        assert!(geom_core::mesh::signed_volume(&m.faces, &m.positions) > 0.0);
        // Two components.
        let mut p = s.positions.clone();
        let n = p.len() as u32;
        p.extend(s.positions.iter().map(|q| q + Vec3::new(5.0, 0.0, 0.0)));
        let mut f = s.faces.clone();
        f.extend(s.faces.iter().map(|t| t.map(|v| v + n)));
        assert!(matches!(prepare(&p, &f, false), Err(RigError::NotConnected { components: 2 })));
        assert_eq!(prepare(&p, &f, true).expect("keeps largest").0.n_vertices(), s.n_vertices());
        assert!(matches!(prepare(&[], &[], false), Err(RigError::EmptyMesh)));
        let mut bad = s.positions.clone();
        bad[0].x = f64::NAN;
        assert!(matches!(prepare(&bad, &s.faces, false), Err(RigError::NonFinite(_))));
    }

    #[test]
    fn normalize_fits_the_unit_cube() {
        let s = icosphere(3.0, 2).expect("icosphere");
        let (m, sim) = normalize(&s).expect("normalizes");
        let b = m.aabb();
        assert!((b.size().max() - 0.9).abs() < 1e-12);
        assert!((b.center() - Pt3::new(0.5, 0.5, 0.5)).norm() < 1e-12);
        assert!((sim.inverse_transform_point(&m.positions[7]) - s.positions[7]).norm() < 1e-12);
    }
}

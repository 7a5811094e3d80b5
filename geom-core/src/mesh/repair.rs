//! [`TriMesh::repair`]: turns "almost valid" triangle soup (OBJ input, procedural output) into a
//! valid [`TriMesh`]: welding, dropping degenerate and duplicate faces, orienting every connected
//! component consistently and closed components outward.

use std::collections::VecDeque;

use serde::{Deserialize, Serialize};

use super::hash::FxSet;
use super::topology::for_each_edge_group;
use super::tri::{bbox_diag2, is_degenerate};
use super::{weld, TriMesh};
use crate::error::{Error, Result};
use crate::math::Pt3;
use crate::NONE;

/// What [`TriMesh::repair`] may change.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct RepairOptions {
    /// Weld vertices closer than this fraction of the bounding-box diagonal (`None`: no welding).
    pub weld_rel: Option<f64>,
    /// Drop faces with repeated indices or area < 1e-14·(bbox diagonal)².
    pub drop_degenerate: bool,
    /// Drop faces with the same vertex set as an earlier face (either orientation).
    pub drop_duplicates: bool,
    /// Flip faces so that every connected component is consistently oriented.
    pub orient: bool,
    /// Flip closed components with negative signed volume (make them face outward).
    pub outward: bool,
}

impl Default for RepairOptions {
    /// Weld at 1e-9 of the bbox diagonal and everything else on (GEOM-CORE.md §3.4).
    fn default() -> Self {
        Self { weld_rel: Some(1e-9), drop_degenerate: true, drop_duplicates: true, orient: true, outward: true }
    }
}

/// What [`TriMesh::repair`] changed.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct RepairReport {
    /// Vertices removed by welding (input count − output count).
    pub welded_vertices: usize,
    /// Faces dropped as degenerate (repeated index, also after welding, or zero area).
    pub dropped_degenerate: usize,
    /// Faces dropped as duplicates of an earlier face.
    pub dropped_duplicate: usize,
    /// Faces whose orientation differs from the input.
    pub flipped_faces: usize,
    /// Closed components that had to be reversed to face outward (after consistent orientation).
    pub reversed_components: usize,
    /// Number of connected components (across edges) of the result.
    pub components: usize,
}

impl TriMesh {
    /// Repairs and builds a mesh (see [`RepairOptions`]), in this order: finite check
    /// ([`Error::NonFiniteVertex`]) and index range check ([`Error::IndexOutOfRange`]; not
    /// repairable), weld, drop degenerate faces, drop duplicates, orient each component by
    /// breadth-first flipping from its lowest face, flip closed components with negative volume.
    ///
    /// Errors that cannot be repaired name the culprit: [`Error::NonManifoldEdge`] (an edge
    /// with more than two faces, all listed), [`Error::InconsistentOrientation`] (the component
    /// is not orientable, e.g. a Möbius strip: the two faces where the propagated orientation
    /// contradicts itself), [`Error::NonManifoldVertex`]. With `orient = false` a flipped
    /// neighbour is an [`Error::InconsistentOrientation`] as in [`TriMesh::new`].
    pub fn repair(positions: Vec<Pt3>, faces: Vec<[u32; 3]>, o: &RepairOptions) -> Result<(TriMesh, RepairReport)> {
        if let Some(v) = positions.iter().position(|q| !q.coords.iter().all(|c| c.is_finite())) {
            return Err(Error::NonFiniteVertex { vertex: v as u32 });
        }
        for (f, t) in faces.iter().enumerate() {
            if let Some(&v) = t.iter().find(|&&v| v as usize >= positions.len()) {
                return Err(Error::IndexOutOfRange { face: f as u32, vertex: v });
            }
        }
        let mut rep = RepairReport::default();
        let n_in = positions.len();
        let (positions, mut faces) = match o.weld_rel {
            Some(rel) if rel > 0.0 => {
                let eps = rel * bbox_diag2(&positions).sqrt();
                let n_faces = faces.len();
                let (p, f, _) = weld(&positions, &faces, eps);
                // weld drops faces that collapse to a repeated index.
                rep.dropped_degenerate += n_faces - f.len();
                (p, f)
            }
            _ => (positions, faces),
        };
        rep.welded_vertices = n_in - positions.len();
        if o.drop_degenerate {
            let d2 = bbox_diag2(&positions);
            let before = faces.len();
            faces.retain(|t| t[0] != t[1] && t[1] != t[2] && t[2] != t[0] && !is_degenerate(&positions, t, d2));
            rep.dropped_degenerate += before - faces.len();
        }
        if o.drop_duplicates {
            let mut seen: FxSet<(u32, u32, u32)> = FxSet::default();
            seen.reserve(faces.len());
            let before = faces.len();
            faces.retain(|t| {
                let mut k = *t;
                k.sort_unstable();
                seen.insert((k[0], k[1], k[2]))
            });
            rep.dropped_duplicate = before - faces.len();
        }
        if o.orient {
            let (flipped, reversed) = orient(&positions, &mut faces, o.outward)?;
            rep.flipped_faces = flipped;
            rep.reversed_components = reversed;
        }
        let m = TriMesh::new(positions, faces)?;
        rep.components = m.topology().face_components().0;
        Ok((m, rep))
    }
}

/// Orients every component consistently (BFS from its lowest face); then, if `outward`, closed
/// components face outward (positive volume), and open components keep the orientation of the
/// majority of their input faces. Returns (faces whose orientation changed, closed components
/// that were reversed to face outward). Index validity is assumed (checked by the caller).
fn orient(p: &[Pt3], faces: &mut [[u32; 3]], outward: bool) -> Result<(usize, usize)> {
    let nf = faces.len();
    // Neighbour across half-edge h (NONE on the boundary).
    let corners: Vec<u32> = faces.iter().flatten().copied().collect();
    let mut nbr = vec![NONE; 3 * nf];
    for_each_edge_group(p.len(), &corners, |a, b, group| {
        if group.len() > 2 {
            return Err(Error::NonManifoldEdge { a, b, faces: group.iter().map(|&(_, h)| h / 3).collect() });
        }
        if let [(_, h0), (_, h1)] = *group {
            nbr[h0 as usize] = h1;
            nbr[h1 as usize] = h0;
        }
        Ok(())
    })?;
    let origin = |faces: &[[u32; 3]], h: u32| faces[(h / 3) as usize][(h % 3) as usize];
    // flip[f]: whether face f is reversed relative to its input orientation.
    let mut flip = vec![false; nf];
    let mut comp = vec![NONE; nf];
    let mut n_comp = 0u32;
    let mut queue = VecDeque::new();
    for seed in 0..nf {
        if comp[seed] != NONE {
            continue;
        }
        comp[seed] = n_comp;
        queue.push_back(seed as u32);
        while let Some(f) = queue.pop_front() {
            for k in 0..3 {
                let h = 3 * f + k;
                let g = nbr[h as usize];
                if g == NONE {
                    continue;
                }
                // Same direction in the input ⇒ the two faces need different flip states.
                let same = origin(faces, h) == origin(faces, g);
                let want = flip[f as usize] ^ same;
                let fg = (g / 3) as usize;
                if comp[fg] == NONE {
                    comp[fg] = n_comp;
                    flip[fg] = want;
                    queue.push_back(fg as u32);
                } else if flip[fg] != want {
                    return Err(Error::InconsistentOrientation { face: f, neighbour: fg as u32 });
                }
            }
        }
        n_comp += 1;
    }
    // Per component: size, faces flipped by propagation, closedness, signed volume (with the
    // propagated orientation, about one shared reference point: exact for closed components).
    let nc = n_comp as usize;
    let mut size = vec![0usize; nc];
    let mut n_flip = vec![0usize; nc];
    let mut closed = vec![true; nc];
    let mut vol = vec![0.0f64; nc];
    let c0 = super::bbox_of(p).map_or(Pt3::origin(), |(lo, hi)| Pt3::from((lo.coords + hi.coords) * 0.5));
    for f in 0..nf {
        let c = comp[f] as usize;
        size[c] += 1;
        n_flip[c] += flip[f] as usize;
        if (0..3).any(|k| nbr[3 * f + k] == NONE) {
            closed[c] = false;
        }
        let t = faces[f];
        let (a, b, d) = (p[t[0] as usize] - c0, p[t[1] as usize] - c0, p[t[2] as usize] - c0);
        let v = a.dot(&b.cross(&d));
        vol[c] += if flip[f] { -v } else { v };
    }
    // Whether to reverse each component as a whole after propagation: closed ones to face
    // outward (if asked), open ones when that changes fewer input faces.
    let mut reversed = 0;
    let invert: Vec<bool> = (0..nc)
        .map(|c| {
            if closed[c] && outward {
                let r = vol[c] < 0.0;
                reversed += r as usize;
                r
            } else {
                2 * n_flip[c] > size[c]
            }
        })
        .collect();
    let mut flipped = 0;
    for (f, t) in faces.iter_mut().enumerate() {
        if flip[f] ^ invert[comp[f] as usize] {
            t.swap(1, 2);
            flipped += 1;
        }
    }
    Ok((flipped, reversed))
}

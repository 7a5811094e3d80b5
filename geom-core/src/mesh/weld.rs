//! Vertex welding with a uniform hash grid (expected O(n)).

use super::hash::FxMap;
use crate::math::{AsPt3, Pt3};
use crate::NONE;

/// Merges vertices closer than `eps` (m, Euclidean, inclusive) and remaps the faces.
///
/// Deterministic greedy clustering in index order: each vertex joins the lowest-index kept
/// representative within `eps` (searched in the 27 neighbouring cells of a grid with cell size
/// `eps`), otherwise it becomes a new representative; representatives keep their own position
/// (no averaging), new indices follow the order of first appearance. With `eps ≤ 0` (or not
/// finite) only bitwise-identical positions merge. Faces that collapse (a repeated index after
/// remapping) are dropped; vertices in no face are kept. Non-finite points never merge.
///
/// Returns `(positions, faces, old → new vertex map)`.
pub fn weld<P: AsPt3>(p: &[P], faces: &[[u32; 3]], eps: f64) -> (Vec<Pt3>, Vec<[u32; 3]>, Vec<u32>) {
    let mut out: Vec<Pt3> = Vec::new();
    let mut map = Vec::with_capacity(p.len());
    if eps > 0.0 && eps.is_finite() {
        let inv = 1.0 / eps;
        let cell = |q: &Pt3| ((q.x * inv).floor() as i64, (q.y * inv).floor() as i64, (q.z * inv).floor() as i64);
        // Cell → most recently added representative; `link[r]` chains the cell's earlier ones.
        let mut head: FxMap<(i64, i64, i64), u32> = FxMap::default();
        let mut link: Vec<u32> = Vec::new();
        let eps2 = eps * eps;
        for q in p {
            let q = q.pt3();
            let finite = q.coords.iter().all(|c| c.is_finite());
            let c = cell(&q);
            let mut best = NONE;
            if finite {
                for dx in -1..=1 {
                    for dy in -1..=1 {
                        for dz in -1..=1 {
                            let key = (c.0.saturating_add(dx), c.1.saturating_add(dy), c.2.saturating_add(dz));
                            let mut r = head.get(&key).copied().unwrap_or(NONE);
                            while r != NONE {
                                if r < best && (out[r as usize] - q).norm_squared() <= eps2 {
                                    best = r;
                                }
                                r = link[r as usize];
                            }
                        }
                    }
                }
            }
            if best == NONE {
                best = out.len() as u32;
                out.push(q);
                link.push(NONE);
                if finite {
                    if let Some(prev) = head.insert(c, best) {
                        link[best as usize] = prev;
                    }
                }
            }
            map.push(best);
        }
    } else {
        let mut seen: FxMap<(u64, u64, u64), u32> = FxMap::default();
        for q in p {
            let q = q.pt3();
            // +0.0 and −0.0 are the same point.
            let key = ((q.x + 0.0).to_bits(), (q.y + 0.0).to_bits(), (q.z + 0.0).to_bits());
            let finite = q.coords.iter().all(|c| c.is_finite());
            let id = match seen.get(&key) {
                Some(&r) if finite => r,
                _ => {
                    let r = out.len() as u32;
                    out.push(q);
                    if finite {
                        seen.insert(key, r);
                    }
                    r
                }
            };
            map.push(id);
        }
    }
    let f = faces
        .iter()
        .map(|t| [map[t[0] as usize], map[t[1] as usize], map[t[2] as usize]])
        .filter(|t| t[0] != t[1] && t[1] != t[2] && t[2] != t[0])
        .collect();
    (out, f, map)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn welds_within_eps_and_drops_collapsed_faces() {
        let p = vec![
            Pt3::new(0., 0., 0.),
            Pt3::new(1., 0., 0.),
            Pt3::new(0., 1., 0.),
            Pt3::new(1.0 + 1e-12, 0., 0.), // duplicate of 1
            Pt3::new(1., 1., 0.),
            Pt3::new(0., 0., 1e-13), // duplicate of 0
        ];
        let faces = vec![[0, 1, 2], [3, 4, 2], [5, 1, 0]];
        let (q, f, map) = weld(&p, &faces, 1e-9);
        assert_eq!(map, vec![0, 1, 2, 1, 3, 0]);
        assert_eq!(q.len(), 4);
        assert_eq!(f, vec![[0, 1, 2], [1, 3, 2]]);
        // Exact mode merges only identical points.
        let (q0, _, m0) = weld(&p, &faces, 0.0);
        assert_eq!(q0.len(), 6);
        assert_eq!(m0, vec![0, 1, 2, 3, 4, 5]);
    }

    #[test]
    fn chain_is_greedy_not_transitive() {
        // 0 — 0.6 — 1.2 with eps 1: 0.6 joins 0, 1.2 is 1.2 from rep 0 → new representative.
        let p = vec![Pt3::new(0., 0., 0.), Pt3::new(0.6, 0., 0.), Pt3::new(1.2, 0., 0.)];
        let (_, _, map) = weld(&p, &[], 1.0);
        assert_eq!(map, vec![0, 0, 1]);
    }
}

//! Broad phase (shells.md §3.9): geom-core [`AabbTree`]s over the swept, inflated boxes of the
//! cloth's vertices, triangles and edges. The trees are built once, refitted on every query (O(n))
//! and rebuilt every [`REBUILD_EVERY`] steps, when refitted boxes have drifted far from the
//! build-time layout. Candidate pairs come out without duplicates in the trees' fixed traversal
//! order (deterministic for any thread count); callers sort what they keep (the few hits)
//! rather than every candidate.

use geom_core::spatial::{Aabb, AabbTree};

/// Steps between full rebuilds of the trees (refit in between; spec §3.9).
pub const REBUILD_EVERY: u32 = 50;

/// Index pairs (unique, in a deterministic but unspecified order).
pub type Pairs = Vec<(u32, u32)>;

/// Vertex, triangle and edge trees with their refit/rebuild bookkeeping.
#[derive(Default)]
pub struct BroadPhase {
    trees: Option<[AabbTree; 3]>,
    steps_since_build: u32,
}

impl BroadPhase {
    /// Marks the start of a step: after [`REBUILD_EVERY`] steps the next query rebuilds.
    pub fn next_step(&mut self) {
        self.steps_since_build += 1;
        if self.steps_since_build >= REBUILD_EVERY {
            self.trees = None;
        }
    }

    /// Refits the trees to the given boxes, or builds them when there are none (first query or
    /// after [`REBUILD_EVERY`] steps).
    fn refit_or_build(&mut self, vbox: &[Aabb], tbox: &[Aabb], ebox: &[Aabb]) {
        match &mut self.trees {
            Some([v, t, e]) => {
                v.refit(vbox);
                t.refit(tbox);
                e.refit(ebox);
            }
            None => {
                self.trees = Some([AabbTree::build(vbox), AabbTree::build(tbox), AabbTree::build(ebox)]);
                self.steps_since_build = 0;
            }
        }
    }

    /// True once the trees exist (they are built on the first query).
    pub fn is_built(&self) -> bool {
        self.trees.is_some()
    }

    /// Candidate (vertex, triangle) and (edge, edge) pairs whose boxes overlap, each once (edge
    /// pairs as (e, f) with e < f), without pairs that share a vertex, in traversal order. `vbox`, `tbox`, `ebox` are the boxes of the vertices, of
    /// `tris` and of `edges`; their lengths must not change between calls.
    pub fn candidate_pairs(
        &mut self,
        tris: &[[u32; 3]],
        edges: &[[u32; 2]],
        vbox: &[Aabb],
        tbox: &[Aabb],
        ebox: &[Aabb],
    ) -> (Pairs, Pairs) {
        self.refit_or_build(vbox, tbox, ebox);
        let [vt_tree, t_tree, e_tree] = self.trees.as_ref().expect("built just above");
        // The two traversals are independent: run them side by side (each list is produced by
        // one sequential traversal, so the result does not depend on the thread count).
        rayon::join(
            || {
                let mut vt = Vec::new();
                vt_tree.pairs_with(t_tree, |v, t| {
                    if !tris[t as usize].contains(&v) {
                        vt.push((v, t));
                    }
                });
                vt
            },
            || {
                let mut ee = Vec::new();
                e_tree.self_pairs(|e, f| {
                    let (ea, eb) = (edges[e as usize], edges[f as usize]);
                    if !eb.contains(&ea[0]) && !eb.contains(&ea[1]) {
                        ee.push((e, f));
                    }
                });
                ee
            },
        )
    }
}

impl BroadPhase {
    /// The candidate pairs of [`BroadPhase::candidate_pairs`] that involve at least one vertex
    /// with `changed[v]`, found by refitting the trees and querying only the boxes of changed
    /// vertices, of triangles and of edges with a changed vertex (same boxes, same closed-box
    /// overlap test, hence exactly the subset of the full list, each pair once, edge pairs as
    /// (e, f) with e < f; in query order). A pair reachable from several changed primitives is
    /// kept only from the first of them in a fixed rule (vertex boxes before triangle boxes; the
    /// smaller edge index), so no sorting or deduplication is needed.
    pub fn candidate_pairs_touching(
        &mut self,
        tris: &[[u32; 3]],
        edges: &[[u32; 2]],
        bx: (&[Aabb], &[Aabb], &[Aabb]),
        changed: &[bool],
    ) -> (Pairs, Pairs) {
        let (vbox, tbox, ebox) = bx;
        self.refit_or_build(vbox, tbox, ebox);
        let [v_tree, t_tree, e_tree] = self.trees.as_ref().expect("built just above");
        // Vertex–triangle and edge–edge queries side by side (each list sequential, so the
        // result does not depend on the thread count).
        let vt_part = || {
            let mut vt = Vec::new();
            for (v, b) in vbox.iter().enumerate().filter(|&(v, _)| changed[v]) {
                let v = v as u32;
                t_tree.query(b, |t| {
                    if !tris[t as usize].contains(&v) {
                        vt.push((v, t));
                    }
                });
            }
            for (t, tri) in tris.iter().enumerate() {
                if tri.iter().any(|&i| changed[i as usize]) {
                    v_tree.query(&tbox[t], |v| {
                        // Changed vertices found this pair from their own box above.
                        if !changed[v as usize] && !tri.contains(&v) {
                            vt.push((v, t as u32));
                        }
                    });
                }
            }
            vt
        };
        let ee_part = || {
            let touches = |e: &[u32; 2]| e.iter().any(|&i| changed[i as usize]);
            let mut ee = Vec::new();
            for (e, ea) in edges.iter().enumerate() {
                if touches(ea) {
                    e_tree.query(&ebox[e], |f| {
                        let eb = edges[f as usize];
                        // A pair of two changed edges is kept from its smaller index only.
                        let first = !touches(&eb) || (f as usize) > e;
                        if first && f as usize != e && !eb.contains(&ea[0]) && !eb.contains(&ea[1]) {
                            let e = e as u32;
                            ee.push((e.min(f), e.max(f)));
                        }
                    });
                }
            }
            ee
        };
        rayon::join(vt_part, ee_part)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use geom_core::math::Pt3;

    /// The pairs sorted, asserting that the broad phase listed none twice.
    fn sorted_unique(mut v: Vec<(u32, u32)>, round: usize) -> Vec<(u32, u32)> {
        let n = v.len();
        v.sort_unstable();
        v.dedup();
        assert_eq!(v.len(), n, "round {round}: duplicate pairs");
        v
    }

    /// Tree candidates equal the brute-force list of overlapping, non-adjacent pairs, before and
    /// after a refit with moved boxes.
    #[test]
    fn matches_brute_force() {
        let mut rng = geom_core::rng::Rng::new(7);
        let n = 60;
        let mut pts: Vec<Pt3> =
            (0..n).map(|_| Pt3::new(rng.range(0.0, 1.0), rng.range(0.0, 1.0), rng.range(0.0, 0.3))).collect();
        let tris: Vec<[u32; 3]> = (0..40).map(|i| [i, (i + 7) % n as u32, (i + 19) % n as u32]).collect();
        let edges: Vec<[u32; 2]> = (0..50).map(|i| [i, (i + 3) % n as u32]).collect();
        let mut bp = BroadPhase::default();
        for round in 0..2 {
            let vb: Vec<Aabb> = pts.iter().map(|p| Aabb::from_points(&[*p]).grow(0.05)).collect();
            let tb: Vec<Aabb> = tris.iter().map(|t| Aabb::from_points(&t.map(|i| pts[i as usize]))).collect();
            let eb: Vec<Aabb> = edges.iter().map(|e| Aabb::from_points(&e.map(|i| pts[i as usize]))).collect();
            let (vt, ee) = bp.candidate_pairs(&tris, &edges, &vb, &tb, &eb);
            let (vt, ee) = (sorted_unique(vt, round), sorted_unique(ee, round));
            let mut bvt = Vec::new();
            for (v, b) in vb.iter().enumerate() {
                for (t, c) in tb.iter().enumerate() {
                    if b.overlaps(c) && !tris[t].contains(&(v as u32)) {
                        bvt.push((v as u32, t as u32));
                    }
                }
            }
            let mut bee = Vec::new();
            for e in 0..edges.len() {
                for f in e + 1..edges.len() {
                    let shared = edges[f].contains(&edges[e][0]) || edges[f].contains(&edges[e][1]);
                    if !shared && eb[e].overlaps(&eb[f]) {
                        bee.push((e as u32, f as u32));
                    }
                }
            }
            assert_eq!(vt, bvt, "round {round}");
            assert_eq!(ee, bee, "round {round}");
            // The changed-vertex subset equals the full list filtered to pairs touching them.
            let changed: Vec<bool> = (0..n).map(|i| i % 7 == round).collect();
            let (svt, see) = bp.candidate_pairs_touching(&tris, &edges, (&vb, &tb, &eb), &changed);
            let (svt, see) = (sorted_unique(svt, round), sorted_unique(see, round));
            let c = |i: u32| changed[i as usize];
            let fvt: Vec<_> =
                bvt.iter().copied().filter(|&(v, t)| c(v) || tris[t as usize].iter().any(|&i| c(i))).collect();
            let fee: Vec<_> = bee
                .iter()
                .copied()
                .filter(|&(e, f)| edges[e as usize].iter().chain(&edges[f as usize]).any(|&i| c(i)))
                .collect();
            assert!(!fvt.is_empty() && !fee.is_empty(), "the subset test must see pairs");
            assert_eq!(svt, fvt, "round {round}");
            assert_eq!(see, fee, "round {round}");
            assert!(bp.is_built());
            for p in &mut pts {
                p.x = 1.0 - p.x * p.x;
            }
        }
    }
}

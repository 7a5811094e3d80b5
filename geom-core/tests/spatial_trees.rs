//! AabbTree and KdTree against brute force.

use geom_core::math::{Pt3, Vec3};
use geom_core::rng::Rng;
use geom_core::spatial::{Aabb, AabbTree, KdTree};
use proptest::prelude::*;

fn random_boxes(rng: &mut Rng, n: usize, world: f64, size: f64) -> Vec<Aabb> {
    (0..n)
        .map(|_| {
            let c = Pt3::new(rng.range(0.0, world), rng.range(0.0, world), rng.range(0.0, world));
            let h = Vec3::new(rng.range(0.0, size), rng.range(0.0, size), rng.range(0.0, size));
            Aabb::new(c - h, c + h)
        })
        .collect()
}

fn brute_pairs(b: &[Aabb]) -> Vec<(u32, u32)> {
    let mut out = Vec::new();
    for i in 0..b.len() {
        for j in i + 1..b.len() {
            if b[i].overlaps(&b[j]) {
                out.push((i as u32, j as u32));
            }
        }
    }
    out
}

fn tree_pairs(t: &AabbTree) -> Vec<(u32, u32)> {
    let mut out = Vec::new();
    t.self_pairs(|i, j| {
        assert!(i < j, "pair ({i}, {j}) not ordered");
        out.push((i, j));
    });
    let n = out.len();
    out.sort_unstable();
    out.dedup();
    assert_eq!(n, out.len(), "a pair was reported twice");
    out
}

#[test]
fn self_pairs_equal_brute_force_on_random_boxes() {
    let mut rng = Rng::new(7);
    for (n, size) in [(0, 1.0), (1, 1.0), (5, 1.0), (300, 0.6), (1000, 0.3), (200, 3.0)] {
        let boxes = random_boxes(&mut rng, n, 10.0, size);
        let tree = AabbTree::build(&boxes);
        assert_eq!(tree_pairs(&tree), brute_pairs(&boxes), "n = {n}");
    }
}

#[test]
fn identical_and_touching_boxes() {
    // All centres equal: the median split must still terminate and report all pairs.
    let b = vec![Aabb::new(Pt3::origin(), Pt3::new(1.0, 1.0, 1.0)); 37];
    assert_eq!(tree_pairs(&AabbTree::build(&b)).len(), 37 * 36 / 2);
    // A row of unit boxes touching face to face: neighbours overlap (closed boxes), others not.
    let row: Vec<Aabb> =
        (0..20).map(|i| Aabb::new(Pt3::new(i as f64, 0.0, 0.0), Pt3::new(i as f64 + 1.0, 1.0, 1.0))).collect();
    let pairs = tree_pairs(&AabbTree::build(&row));
    assert_eq!(pairs, (0..19).map(|i| (i, i + 1)).collect::<Vec<_>>());
}

#[test]
fn refit_follows_moving_boxes() {
    let mut rng = Rng::new(11);
    let boxes = random_boxes(&mut rng, 400, 10.0, 0.5);
    let mut tree = AabbTree::build(&boxes);
    // Move every box by a random offset (large motion: the tree gets worse, never wrong).
    let moved: Vec<Aabb> = boxes
        .iter()
        .map(|b| {
            let d = rng.unit_vec3() * rng.range(0.0, 3.0);
            Aabb::new(b.min + d, b.max + d)
        })
        .collect();
    tree.refit(&moved);
    assert_eq!(tree_pairs(&tree), brute_pairs(&moved));
    let q = Aabb::new(Pt3::new(2.0, 2.0, 2.0), Pt3::new(5.0, 4.0, 6.0));
    let mut hits = Vec::new();
    tree.query(&q, |i| hits.push(i));
    hits.sort_unstable();
    let brute: Vec<u32> = (0..moved.len() as u32).filter(|&i| moved[i as usize].overlaps(&q)).collect();
    assert_eq!(hits, brute);
    assert_eq!(tree.root_aabb(), moved.iter().fold(Aabb::empty(), |a, b| a.union(b)));
}

#[test]
fn pairs_with_equals_brute_force() {
    let mut rng = Rng::new(3);
    let a = random_boxes(&mut rng, 250, 10.0, 0.7);
    let b = random_boxes(&mut rng, 170, 10.0, 0.4);
    let (ta, tb) = (AabbTree::build(&a), AabbTree::build(&b));
    let mut got = Vec::new();
    ta.pairs_with(&tb, |i, j| got.push((i, j)));
    let n = got.len();
    got.sort_unstable();
    got.dedup();
    assert_eq!(n, got.len());
    let mut brute = Vec::new();
    for (i, x) in a.iter().enumerate() {
        for (j, y) in b.iter().enumerate() {
            if x.overlaps(y) {
                brute.push((i as u32, j as u32));
            }
        }
    }
    assert_eq!(got, brute);
}

#[test]
fn traversal_order_is_deterministic() {
    let mut rng = Rng::new(5);
    let boxes = random_boxes(&mut rng, 500, 10.0, 0.5);
    let run = || {
        let mut v = Vec::new();
        AabbTree::build(&boxes).self_pairs(|i, j| v.push((i, j)));
        v
    };
    assert_eq!(run(), run());
}

fn brute_knn(pts: &[Pt3], q: &Pt3, k: usize) -> Vec<(u32, f64)> {
    let mut all: Vec<(f64, u32)> = pts
        .iter()
        .enumerate()
        .map(|(i, p)| {
            let d = p - q;
            (d.x * d.x + d.y * d.y + d.z * d.z, i as u32)
        })
        .collect();
    all.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
    all.truncate(k);
    all.into_iter().map(|(d2, i)| (i, d2.sqrt())).collect()
}

#[test]
fn knn_nearest_within_equal_brute_force() {
    let mut rng = Rng::new(19);
    // Points on a coarse integer lattice (many exact distance ties) plus random ones.
    let mut pts: Vec<Pt3> =
        (0..300).map(|_| Pt3::new(rng.below(6) as f64, rng.below(6) as f64, rng.below(6) as f64)).collect();
    pts.extend((0..300).map(|_| Pt3::new(rng.range(0.0, 5.0), rng.range(0.0, 5.0), rng.range(0.0, 5.0))));
    pts.push(pts[3]); // an exact duplicate
    let tree = KdTree::build(&pts);
    let mut out = Vec::new();
    let mut within = Vec::new();
    for s in 0..200 {
        let q = if s % 2 == 0 {
            Pt3::new(rng.below(6) as f64 + 0.5, rng.below(6) as f64, rng.below(6) as f64 - 0.5)
        } else {
            Pt3::new(rng.range(-1.0, 6.0), rng.range(-1.0, 6.0), rng.range(-1.0, 6.0))
        };
        for k in [1, 2, 7, 30] {
            tree.knn(&q, k, &mut out);
            assert_eq!(out, brute_knn(&pts, &q, k), "query {q:?}, k = {k}");
        }
        assert_eq!(tree.nearest(&q), brute_knn(&pts, &q, 1).first().copied());
        let r = rng.range(0.0, 1.5);
        tree.within(&q, r, &mut within);
        let brute: Vec<u32> = (0..pts.len() as u32)
            .filter(|&i| {
                let d = pts[i as usize] - q;
                d.x * d.x + d.y * d.y + d.z * d.z <= r * r
            })
            .collect();
        assert_eq!(within, brute);
    }
    tree.knn(&Pt3::origin(), 10_000, &mut out);
    assert_eq!(out.len(), pts.len());
    assert!(KdTree::build(&[]).nearest(&Pt3::origin()).is_none());
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    #[test]
    fn prop_self_pairs_match(coords in prop::collection::vec((0i32..20, 0i32..20, 0i32..20, 0i32..4), 0..80)) {
        let boxes: Vec<Aabb> = coords
            .iter()
            .map(|&(x, y, z, s)| {
                let c = Pt3::new(x as f64, y as f64, z as f64);
                let h = Vec3::repeat(s as f64);
                Aabb::new(c - h, c + h)
            })
            .collect();
        prop_assert_eq!(tree_pairs(&AabbTree::build(&boxes)), brute_pairs(&boxes));
    }

    #[test]
    fn prop_knn_match(
        coords in prop::collection::vec((0i32..8, 0i32..8, 0i32..8), 1..60),
        q in (0i32..16, 0i32..16, 0i32..16),
        k in 1usize..10,
    ) {
        let pts: Vec<Pt3> = coords.iter().map(|&(x, y, z)| Pt3::new(x as f64, y as f64, z as f64)).collect();
        let q = Pt3::new(q.0 as f64 * 0.5, q.1 as f64 * 0.5, q.2 as f64 * 0.5);
        let mut out = Vec::new();
        KdTree::build(&pts).knn(&q, k, &mut out);
        prop_assert_eq!(out, brute_knn(&pts, &q, k));
    }
}

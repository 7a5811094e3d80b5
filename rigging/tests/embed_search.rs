//! Discrete search tests (spec §7.3 c–f): best-first branch and bound equals exhaustive
//! enumeration under the same rejection rules; hints; k-best ordering.

use geom_core::math::Pt3;
use geom_core::rng::Rng;
use rigging::embed::{basis_penalties, k_best_embeddings, Problem};
use rigging::template::{SkeletonTemplate, TemplateJoint};
use rigging::{EmbedGraph, RigError, RigOptions};

fn tj(name: &str, rest: [f64; 3], parent: Option<usize>) -> TemplateJoint {
    TemplateJoint { name: name.into(), rest, parent, symmetric_to: None, foot: false, fat: false, role: None }
}

/// A Y-shaped 4-joint template: root, two arms and a leg (r = 4).
fn small_template() -> SkeletonTemplate {
    let mut s = SkeletonTemplate {
        joints: vec![
            tj("root", [0.0, 0.0, 0.0], None),
            tj("l_arm", [0.5, 0.3, 0.0], Some(0)),
            tj("r_arm", [-0.5, 0.3, 0.0], Some(0)),
            tj("leg", [0.0, -0.6, 0.0], Some(0)),
        ],
    };
    s.joints[2].symmetric_to = Some(1);
    s.joints[3].foot = true;
    s
}

fn random_graph(rng: &mut Rng, n: usize) -> EmbedGraph {
    let verts: Vec<Pt3> =
        (0..n).map(|_| Pt3::new(rng.range(0.2, 0.8), rng.range(0.2, 0.8), rng.range(0.45, 0.55))).collect();
    let radius: Vec<f64> = (0..n).map(|_| rng.range(0.01, 0.06)).collect();
    let mut adj = vec![Vec::new(); n];
    for i in 0..n {
        let mut d: Vec<(f64, usize)> = (0..n).filter(|&j| j != i).map(|j| ((verts[i] - verts[j]).norm(), j)).collect();
        d.sort_by(|a, b| a.0.total_cmp(&b.0));
        for &(_, j) in d.iter().take(3) {
            if !adj[i].contains(&(j as u32)) {
                adj[i].push(j as u32);
                adj[j].push(i as u32);
            }
        }
    }
    EmbedGraph::from_adjacency(verts, radius, adj)
}

fn rec(pr: &Problem, cand: &[Vec<u32>], o: &RigOptions, pv: &mut Vec<u32>, best: &mut Option<f64>) {
    if pv.len() == cand.len() {
        let f = basis_penalties(pr, pv).expect("every prefix passed");
        let v: f64 = (0..9).map(|k| o.gamma[k] * f[k]).sum();
        if v <= o.reject_bound && best.is_none_or(|b| v < b) {
            *best = Some(v);
        }
        return;
    }
    for &v in &cand[pv.len()] {
        pv.push(v);
        if let Some(f) = basis_penalties(pr, pv) {
            let g: f64 = (0..9).map(|k| o.gamma[k] * f[k]).sum();
            if g <= o.reject_bound {
                rec(pr, cand, o, pv, best);
            }
        }
        pv.pop();
    }
}

/// Exhaustive depth-first enumeration with the same increments and rejection rules.
fn brute(pr: &Problem, cand: &[Vec<u32>], o: &RigOptions) -> Option<f64> {
    let mut best = None;
    rec(pr, cand, o, &mut Vec::new(), &mut best);
    best
}

#[test]
fn best_first_equals_exhaustive_enumeration() {
    let sk = small_template();
    let rs = sk.reduced();
    assert_eq!(rs.len(), 4);
    let o = RigOptions { skeleton_scale: 0.3, ..Default::default() };
    let mut rng = Rng::new(11);
    let mut compared = 0;
    for _ in 0..25 {
        let g = random_graph(&mut rng, 14);
        let cand: Vec<Vec<u32>> = (0..rs.len()).map(|_| (0..g.len() as u32).collect()).collect();
        let pr = Problem::new(&g, &sk, &rs, &cand, &o);
        let exact = brute(&pr, &cand, &o);
        match k_best_embeddings(&pr, 3) {
            Ok(list) => {
                let best = exact.expect("A* found one, so enumeration must too");
                assert!((list[0].penalty - best).abs() <= 1e-12, "A* {} vs brute {best}", list[0].penalty);
                assert!(list[0].certified_optimal);
                for w in list.windows(2) {
                    assert!(w[0].penalty <= w[1].penalty + 1e-15);
                    assert_ne!(w[0].verts, w[1].verts);
                }
                compared += 1;
            }
            Err(RigError::NoEmbedding { .. }) => assert!(exact.is_none()),
            Err(e) => panic!("unexpected error {e}"),
        }
    }
    assert!(compared >= 5, "only {compared} instances had an embedding");
}

#[test]
fn hints_restrict_and_unsatisfiable_hints_fail() {
    let sk = small_template();
    let rs = sk.reduced();
    let o = RigOptions { skeleton_scale: 0.3, ..Default::default() };
    let mut rng = Rng::new(5);
    for _ in 0..20 {
        let g = random_graph(&mut rng, 14);
        let mut cand: Vec<Vec<u32>> = (0..rs.len()).map(|_| (0..g.len() as u32).collect()).collect();
        let pr = Problem::new(&g, &sk, &rs, &cand, &o);
        let Ok(free) = k_best_embeddings(&pr, 1) else { continue };
        // Force the leg elsewhere: the result respects the restriction.
        let leg = rs.full_index.iter().position(|&f| f == 3).expect("leg is reduced");
        let other: Vec<u32> = (0..g.len() as u32).filter(|&v| v != free[0].verts[leg]).collect();
        cand[leg] = other.clone();
        let pr = Problem::new(&g, &sk, &rs, &cand, &o);
        if let Ok(h) = k_best_embeddings(&pr, 1) {
            assert!(other.contains(&h[0].verts[leg]));
            assert!(h[0].penalty >= free[0].penalty - 1e-15);
        }
        cand[leg] = Vec::new();
        let pr = Problem::new(&g, &sk, &rs, &cand, &o);
        assert!(matches!(k_best_embeddings(&pr, 1), Err(RigError::NoEmbedding { .. })));
        return;
    }
    panic!("no instance with an embedding");
}

/// APSP equals Floyd–Warshall (1e-6 relative, f32 storage) and next-hop paths have length
/// `dist` (spec §7.2 d).
#[test]
fn shortest_paths_match_floyd_warshall() {
    let mut rng = Rng::new(2);
    let g = random_graph(&mut rng, 40);
    let n = g.len();
    let mut d = vec![f64::INFINITY; n * n];
    for i in 0..n {
        d[i * n + i] = 0.0;
        for &j in &g.adj[i] {
            d[i * n + j as usize] = (g.verts[i] - g.verts[j as usize]).norm();
        }
    }
    for k in 0..n {
        for i in 0..n {
            for j in 0..n {
                let via = d[i * n + k] + d[k * n + j];
                if via < d[i * n + j] {
                    d[i * n + j] = via;
                }
            }
        }
    }
    for i in 0..n {
        for j in 0..n {
            let a = g.d(i as u32, j as u32);
            let b = d[i * n + j];
            if b.is_infinite() {
                assert!(a.is_infinite());
                continue;
            }
            assert!((a - b).abs() <= 1e-6 * b.max(1e-12), "{a} vs {b}");
            let p = g.path(i as u32, j as u32);
            let len: f64 = p.windows(2).map(|w| (g.verts[w[0] as usize] - g.verts[w[1] as usize]).norm()).sum();
            assert!((len - b).abs() <= 1e-6 * b.max(1e-12));
        }
    }
    for (i, a) in g.adj.iter().enumerate() {
        for &j in a {
            assert!(g.adj[j as usize].contains(&(i as u32)), "symmetric adjacency");
        }
    }
}

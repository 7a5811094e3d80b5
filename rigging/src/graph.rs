//! The embedding graph on sphere centres (rigging spec §3.4): an edge joins two spheres that
//! intersect, or that satisfy the Gabriel condition (no other centre strictly inside the ball on
//! their segment as diameter) with the whole segment at depth ≥ `edge_depth_factor` × the smaller
//! radius. All-pairs shortest paths (Dijkstra per source, Euclidean edge lengths) with a next-hop
//! table for path extraction.

use std::cmp::Ordering;
use std::collections::BinaryHeap;

use geom_core::math::Pt3;
use geom_core::spatial::KdTree;

use crate::df::DistanceField;
use crate::medial::Sphere;

/// The graph the discrete embedding searches (normalized units).
#[derive(Clone, Debug)]
pub struct EmbedGraph {
    /// Sphere centres.
    pub verts: Vec<Pt3>,
    /// Sphere radii.
    pub radius: Vec<f64>,
    /// Symmetric adjacency, sorted.
    pub adj: Vec<Vec<u32>>,
    /// `b × b` shortest path lengths (`f32::INFINITY` if unreachable).
    pub dist: Vec<f32>,
    /// `b × b` next hop from `i` towards `j` (`u32::MAX` if unreachable or `i = j`).
    pub next: Vec<u32>,
    /// Number of connected components.
    pub components: usize,
}

#[derive(PartialEq)]
struct Item(f64, u32);
impl Eq for Item {}
impl PartialOrd for Item {
    fn partial_cmp(&self, o: &Self) -> Option<Ordering> {
        Some(self.cmp(o))
    }
}
impl Ord for Item {
    fn cmp(&self, o: &Self) -> Ordering {
        o.0.total_cmp(&self.0).then(o.1.cmp(&self.1))
    }
}

impl EmbedGraph {
    /// Number of vertices.
    pub fn len(&self) -> usize {
        self.verts.len()
    }

    /// Whether the graph is empty.
    pub fn is_empty(&self) -> bool {
        self.verts.is_empty()
    }

    /// Shortest path length from `i` to `j`.
    pub fn d(&self, i: u32, j: u32) -> f64 {
        self.dist[i as usize * self.len() + j as usize] as f64
    }

    /// The vertices of a shortest path from `i` to `j`, both included (empty if unreachable).
    pub fn path(&self, i: u32, j: u32) -> Vec<u32> {
        let n = self.len();
        let mut p = vec![i];
        let mut x = i;
        while x != j {
            let nx = self.next[x as usize * n + j as usize];
            if nx == u32::MAX || p.len() > n {
                return Vec::new();
            }
            p.push(nx);
            x = nx;
        }
        p
    }

    /// Builds the graph from packed spheres (spec §3.4).
    pub fn build(df: &DistanceField, spheres: &[Sphere], edge_depth_factor: f64, edge_samples: usize) -> Self {
        let n = spheres.len();
        let verts: Vec<Pt3> = spheres.iter().map(|s| s.c).collect();
        let radius: Vec<f64> = spheres.iter().map(|s| s.r).collect();
        let tree = KdTree::build(&verts);
        let mut adj = vec![Vec::new(); n];
        let mut near = Vec::new();
        for i in 0..n {
            for j in i + 1..n {
                let d = (verts[i] - verts[j]).norm();
                let ok = if d < radius[i] + radius[j] {
                    true
                } else {
                    let mid = Pt3::from((verts[i].coords + verts[j].coords) * 0.5);
                    tree.knn(&mid, 3, &mut near);
                    let gabriel = near.iter().all(|&(k, dk)| k as usize == i || k as usize == j || dk >= 0.5 * d);
                    gabriel && {
                        let need = -edge_depth_factor * radius[i].min(radius[j]);
                        (0..edge_samples).all(|s| {
                            let t = s as f64 / (edge_samples - 1).max(1) as f64;
                            df.eval(&(verts[i] + (verts[j] - verts[i]) * t)) <= need
                        })
                    }
                };
                if ok {
                    adj[i].push(j as u32);
                    adj[j].push(i as u32);
                }
            }
        }
        Self::from_adjacency(verts, radius, adj)
    }

    /// A graph from explicit vertices, radii and symmetric adjacency: computes the all-pairs
    /// shortest paths (Dijkstra per source, Euclidean edge lengths), next hops and components.
    pub fn from_adjacency(verts: Vec<Pt3>, radius: Vec<f64>, adj: Vec<Vec<u32>>) -> Self {
        let n = verts.len();
        let mut dist = vec![f32::INFINITY; n * n];
        let mut next = vec![u32::MAX; n * n];
        let mut dd = vec![f64::INFINITY; n];
        let mut first = vec![u32::MAX; n];
        for s in 0..n {
            dd.iter_mut().for_each(|x| *x = f64::INFINITY);
            first.iter_mut().for_each(|x| *x = u32::MAX);
            dd[s] = 0.0;
            let mut heap = BinaryHeap::new();
            heap.push(Item(0.0, s as u32));
            while let Some(Item(d, u)) = heap.pop() {
                if d > dd[u as usize] {
                    continue;
                }
                for &v in &adj[u as usize] {
                    let nd = d + (verts[u as usize] - verts[v as usize]).norm();
                    if nd < dd[v as usize] {
                        dd[v as usize] = nd;
                        first[v as usize] = if u as usize == s { v } else { first[u as usize] };
                        heap.push(Item(nd, v));
                    }
                }
            }
            for t in 0..n {
                dist[s * n + t] = dd[t] as f32;
                next[s * n + t] = first[t];
            }
        }
        let mut uf = geom_core::graph::UnionFind::new(n);
        for (i, a) in adj.iter().enumerate() {
            for &j in a {
                uf.union(i as u32, j);
            }
        }
        let components = (0..n).filter(|&i| uf.find(i as u32) == i as u32).count();
        EmbedGraph { verts, radius, adj, dist, next, components }
    }
}

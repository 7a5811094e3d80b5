//! [`Topology`]: the immutable half-edge connectivity of a manifold, consistently oriented
//! triangle mesh, built once and shared through `Arc` by every [`super::TriMesh`] with the same
//! faces. Construction is O(n): counting sorts of the half-edges by vertex plus tiny per-vertex
//! sorts (no global sort, no hashing).
//!
//! Layout: half-edge `h = 3f + k` runs from `faces[f][k]` to `faces[f][(k + 1) % 3]`, so
//! `face(h) = h / 3` and `next(h) = 3f + (k + 1) % 3` need no storage; `origin` and `twin` are
//! stored (`twin = NONE` on the boundary).

use crate::error::{Error, Result};
use crate::graph::{Ragged, UnionFind};
use crate::NONE;

/// Handle of a vertex (index into positions).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct VertexId(pub u32);
/// Handle of a face (index into faces).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct FaceId(pub u32);
/// Handle of a half-edge: `3·face + corner`, running from corner `k` to corner `k + 1`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct HalfEdgeId(pub u32);
/// Handle of an undirected edge (index into [`Topology::edges`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct EdgeId(pub u32);

/// Half-edge connectivity of a manifold, consistently oriented triangle mesh.
///
/// Invariants (checked by [`Topology::new`]): every undirected edge has one or two faces, two
/// faces on an edge traverse it in opposite directions, and the faces around every vertex form a
/// single fan (closed, or open with exactly one boundary gap). Isolated vertices (in no face) are
/// allowed and have empty rows.
#[derive(Clone, Debug, PartialEq)]
pub struct Topology {
    n_vertices: usize,
    origin: Vec<u32>,
    twin: Vec<u32>,
    he_edge: Vec<u32>,
    edges: Vec<[u32; 2]>,
    edge_he: Vec<[u32; 2]>,
    vertex_he: Vec<u32>,
    vertex_faces: Ragged<u32>,
    vertex_neighbors: Ragged<u32>,
}

impl Topology {
    /// Builds the connectivity of `faces` over `n_vertices` vertices.
    ///
    /// Errors, each naming the offending element: [`Error::IndexOutOfRange`] (index ≥
    /// `n_vertices` or repeated within a face), [`Error::NonManifoldEdge`] (edge with more than two
    /// faces; `faces` lists them all), [`Error::InconsistentOrientation`] (two faces traverse
    /// their shared edge in the same direction), [`Error::NonManifoldVertex`] (faces around a
    /// vertex form more than one fan).
    pub fn new(n_vertices: usize, faces: &[[u32; 3]]) -> Result<Self> {
        if faces.len() >= (u32::MAX / 3) as usize {
            return Err(Error::InvalidParameter(format!("too many faces for u32 half-edge ids: {}", faces.len())));
        }
        for (f, t) in faces.iter().enumerate() {
            for k in 0..3 {
                let v = t[k];
                if v as usize >= n_vertices || t[(k + 1) % 3] == v {
                    return Err(Error::IndexOutOfRange { face: f as u32, vertex: v });
                }
            }
        }
        let nh = faces.len() * 3;
        let origin: Vec<u32> = faces.iter().flat_map(|t| t.iter().copied()).collect();

        let mut twin = vec![NONE; nh];
        let mut he_edge = vec![NONE; nh];
        let mut edges = Vec::with_capacity(nh / 2 + 1);
        let mut edge_he = Vec::with_capacity(nh / 2 + 1);
        for_each_edge_group(n_vertices, &origin, |a, b, group| {
            if group.len() > 2 {
                let faces: Vec<u32> = group.iter().map(|&(_, h)| h / 3).collect();
                return Err(Error::NonManifoldEdge { a, b, faces });
            }
            let e = edges.len() as u32;
            edges.push([a, b]);
            let h0 = group[0].1;
            let h1 = if group.len() == 2 { group[1].1 } else { NONE };
            if h1 != NONE {
                if origin[h0 as usize] == origin[h1 as usize] {
                    return Err(Error::InconsistentOrientation { face: h0 / 3, neighbour: h1 / 3 });
                }
                twin[h0 as usize] = h1;
                twin[h1 as usize] = h0;
                he_edge[h1 as usize] = e;
            }
            he_edge[h0 as usize] = e;
            edge_he.push([h0, h1]);
            Ok(())
        })?;

        // Fans: walk counter-clockwise around each vertex from its boundary half-edge (if any).
        let (out_off, out_items) = bucket(n_vertices, nh, |h| origin[h as usize]);
        let mut vertex_he = vec![NONE; n_vertices];
        let mut vf = Ragged { offsets: Vec::with_capacity(n_vertices + 1), items: Vec::with_capacity(nh) };
        let mut vn = Ragged { offsets: Vec::with_capacity(n_vertices + 1), items: Vec::with_capacity(nh + n_vertices) };
        vf.offsets.push(0);
        vn.offsets.push(0);
        for (v, vh) in vertex_he.iter_mut().enumerate() {
            let out = &out_items[out_off[v] as usize..out_off[v + 1] as usize];
            if !out.is_empty() {
                let start = out.iter().copied().find(|&h| twin[h as usize] == NONE).unwrap_or(out[0]);
                *vh = start;
                let mut h = start;
                let mut count = 0usize;
                loop {
                    vf.items.push(h / 3);
                    vn.items.push(origin[next_raw(h) as usize]);
                    count += 1;
                    let p = prev_raw(h);
                    let t = twin[p as usize];
                    if t == NONE {
                        // Open fan: close the neighbour list with the far end of the last edge.
                        vn.items.push(origin[p as usize]);
                        break;
                    }
                    if t == start || count > out.len() {
                        break;
                    }
                    h = t;
                }
                if count != out.len() {
                    return Err(Error::NonManifoldVertex { vertex: v as u32 });
                }
            }
            vf.offsets.push(vf.items.len() as u32);
            vn.offsets.push(vn.items.len() as u32);
        }

        Ok(Self {
            n_vertices,
            origin,
            twin,
            he_edge,
            edges,
            edge_he,
            vertex_he,
            vertex_faces: vf,
            vertex_neighbors: vn,
        })
    }

    /// Number of vertices (including isolated ones).
    pub fn n_vertices(&self) -> usize {
        self.n_vertices
    }
    /// Number of faces.
    pub fn n_faces(&self) -> usize {
        self.origin.len() / 3
    }
    /// Number of undirected edges.
    pub fn n_edges(&self) -> usize {
        self.edges.len()
    }
    /// Number of half-edges (3 per face; boundary edges have a single half-edge).
    pub fn n_half_edges(&self) -> usize {
        self.origin.len()
    }

    /// The next half-edge around the same face (counter-clockwise).
    #[inline]
    pub fn next(&self, h: HalfEdgeId) -> HalfEdgeId {
        HalfEdgeId(next_raw(h.0))
    }
    /// The previous half-edge around the same face.
    #[inline]
    pub fn prev(&self, h: HalfEdgeId) -> HalfEdgeId {
        HalfEdgeId(prev_raw(h.0))
    }
    /// The opposite half-edge in the neighbouring face, `None` on the boundary.
    #[inline]
    pub fn twin(&self, h: HalfEdgeId) -> Option<HalfEdgeId> {
        let t = self.twin[h.0 as usize];
        (t != NONE).then_some(HalfEdgeId(t))
    }
    /// The vertex the half-edge starts at.
    #[inline]
    pub fn origin(&self, h: HalfEdgeId) -> VertexId {
        VertexId(self.origin[h.0 as usize])
    }
    /// The vertex the half-edge ends at.
    #[inline]
    pub fn target(&self, h: HalfEdgeId) -> VertexId {
        VertexId(self.origin[next_raw(h.0) as usize])
    }
    /// The face the half-edge belongs to.
    #[inline]
    pub fn face(&self, h: HalfEdgeId) -> FaceId {
        FaceId(h.0 / 3)
    }
    /// The undirected edge of a half-edge.
    #[inline]
    pub fn edge(&self, h: HalfEdgeId) -> EdgeId {
        EdgeId(self.he_edge[h.0 as usize])
    }
    /// The vertex indices of face `f` (as in the faces the topology was built from).
    #[inline]
    pub fn face_vertices(&self, f: FaceId) -> [u32; 3] {
        let h = 3 * f.0 as usize;
        [self.origin[h], self.origin[h + 1], self.origin[h + 2]]
    }
    /// The faces as vertex index triples (a copy of the faces the topology was built from).
    pub fn face_list(&self) -> Vec<[u32; 3]> {
        self.origin.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect()
    }
    /// The half-edge of face `f` that starts at corner `k` (0..3).
    #[inline]
    pub fn face_half_edge(&self, f: FaceId, k: usize) -> HalfEdgeId {
        HalfEdgeId(3 * f.0 + k as u32)
    }
    /// One outgoing half-edge of `v`: the boundary one for boundary vertices (the start of the
    /// counter-clockwise fan), `None` for isolated vertices.
    pub fn vertex_half_edge(&self, v: VertexId) -> Option<HalfEdgeId> {
        let h = self.vertex_he[v.0 as usize];
        (h != NONE).then_some(HalfEdgeId(h))
    }

    /// Undirected edges `[a, b]` with `a < b`, sorted lexicographically; [`EdgeId`] indexes this.
    pub fn edges(&self) -> &[[u32; 2]] {
        &self.edges
    }
    /// The two faces of edge `e` in increasing order; the second is [`NONE`] on the boundary.
    pub fn edge_faces(&self, e: EdgeId) -> [u32; 2] {
        let [h0, h1] = self.edge_he[e.0 as usize];
        [h0 / 3, if h1 == NONE { NONE } else { h1 / 3 }]
    }
    /// The half-edges of edge `e` (lower index first); the second is `None` on the boundary.
    pub fn edge_half_edges(&self, e: EdgeId) -> (HalfEdgeId, Option<HalfEdgeId>) {
        let [h0, h1] = self.edge_he[e.0 as usize];
        (HalfEdgeId(h0), (h1 != NONE).then_some(HalfEdgeId(h1)))
    }
    /// True when edge `e` has a single face.
    pub fn is_boundary_edge(&self, e: EdgeId) -> bool {
        self.edge_he[e.0 as usize][1] == NONE
    }
    /// The edge joining vertices `a` and `b` (either order), found by binary search (O(log n)).
    pub fn edge_between(&self, a: u32, b: u32) -> Option<EdgeId> {
        let key = if a < b { [a, b] } else { [b, a] };
        self.edges.binary_search(&key).ok().map(|e| EdgeId(e as u32))
    }
    /// The faces across the three edges of face `f`: entry `k` is the neighbour opposite corner
    /// `k` (across edge `(k+1, k+2)`), [`NONE`] on the boundary.
    pub fn face_neighbors(&self, f: FaceId) -> [u32; 3] {
        let mut n = [NONE; 3];
        for (k, nk) in n.iter_mut().enumerate() {
            let h = 3 * f.0 + ((k as u32 + 1) % 3);
            let t = self.twin[h as usize];
            *nk = if t == NONE { NONE } else { t / 3 };
        }
        n
    }
    /// Faces around each vertex in counter-clockwise order (seen from the front side); for a
    /// boundary vertex the first face is the one on the boundary edge leaving the vertex.
    pub fn vertex_faces(&self) -> &Ragged<u32> {
        &self.vertex_faces
    }
    /// One-ring neighbours of each vertex in counter-clockwise order; a boundary vertex with `k`
    /// faces has `k + 1` neighbours, starting and ending with its two boundary neighbours.
    pub fn vertex_neighbors(&self) -> &Ragged<u32> {
        &self.vertex_neighbors
    }
    /// True when `v` lies on the boundary (has a boundary edge). Isolated vertices are not.
    pub fn is_boundary_vertex(&self, v: VertexId) -> bool {
        let h = self.vertex_he[v.0 as usize];
        h != NONE && self.twin[h as usize] == NONE
    }
    /// True when no edge is a boundary edge (an empty mesh is closed).
    pub fn is_closed(&self) -> bool {
        self.twin.iter().all(|&t| t != NONE)
    }
    /// Number of boundary edges.
    pub fn n_boundary_edges(&self) -> usize {
        self.twin.iter().filter(|&&t| t == NONE).count()
    }

    /// Interior edges as hinges `[a, b, w1, w2]` (shells.md §3.1), one per interior edge in
    /// [`Self::edges`] order with `a < b`: triangle 1 = (a, b, w1) contains the directed edge a→b,
    /// triangle 2 = (b, a, w2) contains b→a.
    pub fn hinges(&self) -> Vec<[u32; 4]> {
        let mut out = Vec::with_capacity(self.edges.len());
        for (e, &[h0, h1]) in self.edge_he.iter().enumerate() {
            if h1 == NONE {
                continue;
            }
            let [a, b] = self.edges[e];
            let (h_ab, h_ba) = if self.origin[h0 as usize] == a { (h0, h1) } else { (h1, h0) };
            let w1 = self.origin[prev_raw(h_ab) as usize];
            let w2 = self.origin[prev_raw(h_ba) as usize];
            out.push([a, b, w1, w2]);
        }
        out
    }

    /// Boundary loops as vertex lists, each following the face orientation (so a loop runs
    /// counter-clockwise around the surface seen from the front); loops are ordered by their
    /// lowest boundary half-edge and start at its origin.
    pub fn boundary_loops(&self) -> Vec<Vec<u32>> {
        let mut seen = vec![false; self.twin.len()];
        let mut loops = Vec::new();
        for h in 0..self.twin.len() {
            if self.twin[h] != NONE || seen[h] {
                continue;
            }
            let mut lp = Vec::new();
            let mut c = h as u32;
            while !seen[c as usize] {
                seen[c as usize] = true;
                lp.push(self.origin[c as usize]);
                // The boundary half-edge leaving the target vertex starts that vertex's fan.
                let t = self.origin[next_raw(c) as usize];
                c = self.vertex_he[t as usize];
            }
            loops.push(lp);
        }
        loops
    }

    /// Connected components of faces across edges: `(count, label per face)`, labels numbered by
    /// each component's lowest face.
    pub fn face_components(&self) -> (usize, Vec<u32>) {
        let mut uf = UnionFind::new(self.n_faces());
        for (h, &t) in self.twin.iter().enumerate() {
            if t != NONE && (t as usize) > h {
                uf.union(h as u32 / 3, t / 3);
            }
        }
        uf.labels()
    }

    /// V − E + F (isolated vertices count as vertices).
    pub fn euler_characteristic(&self) -> i64 {
        self.n_vertices as i64 - self.edges.len() as i64 + self.n_faces() as i64
    }

    /// Iterator over all vertex handles.
    pub fn vertices(&self) -> impl Iterator<Item = VertexId> {
        (0..self.n_vertices as u32).map(VertexId)
    }
    /// Iterator over all face handles.
    pub fn faces(&self) -> impl Iterator<Item = FaceId> {
        (0..self.n_faces() as u32).map(FaceId)
    }
    /// Iterator over all edge handles.
    pub fn edge_ids(&self) -> impl Iterator<Item = EdgeId> {
        (0..self.edges.len() as u32).map(EdgeId)
    }
    /// The one-ring of `v` (neighbour vertices, counter-clockwise).
    pub fn one_ring(&self, v: VertexId) -> &[u32] {
        self.vertex_neighbors.row(v.0 as usize)
    }
    /// Outgoing half-edges of `v` in counter-clockwise order, starting at
    /// [`Self::vertex_half_edge`].
    pub fn outgoing(&self, v: VertexId) -> impl Iterator<Item = HalfEdgeId> + '_ {
        let start = self.vertex_he[v.0 as usize];
        let mut cur = start;
        std::iter::from_fn(move || {
            if cur == NONE {
                return None;
            }
            let h = cur;
            let t = self.twin[prev_raw(h) as usize];
            cur = if t == start { NONE } else { t };
            Some(HalfEdgeId(h))
        })
    }
}

/// Calls `f(a, b, group)` for every undirected edge `a < b` of the faces whose corners are
/// `origin` (half-edge `h = 3f + k` starts at `origin[h]`), in lexicographic `(a, b)` order, with
/// `group` = the `(b, h)` pairs of the edge's half-edges in ascending `h`. O(n): half-edges are
/// bucketed by their lower endpoint (counting sort), then each small bucket is sorted. Stops at
/// the first error. Indices must be `< n_vertices`.
pub(crate) fn for_each_edge_group(
    n_vertices: usize,
    origin: &[u32],
    mut f: impl FnMut(u32, u32, &[(u32, u32)]) -> Result<()>,
) -> Result<()> {
    let ends = |h: u32| {
        let (a, b) = (origin[h as usize], origin[next_raw(h) as usize]);
        if a < b {
            (a, b)
        } else {
            (b, a)
        }
    };
    let (off, items) = bucket(n_vertices, origin.len(), |h| ends(h).0);
    let mut scratch: Vec<(u32, u32)> = Vec::new();
    for a in 0..n_vertices {
        scratch.clear();
        scratch.extend(items[off[a] as usize..off[a + 1] as usize].iter().map(|&h| (ends(h).1, h)));
        scratch.sort_unstable();
        let mut i = 0;
        while i < scratch.len() {
            let b = scratch[i].0;
            let mut j = i + 1;
            while j < scratch.len() && scratch[j].0 == b {
                j += 1;
            }
            f(a as u32, b, &scratch[i..j])?;
            i = j;
        }
    }
    Ok(())
}

/// Counting sort of the half-edges `0..nh` into `n` buckets by `key`: `(offsets, items)` with
/// the half-edges of bucket `k` in `items[offsets[k]..offsets[k + 1]]`, ascending.
fn bucket(n: usize, nh: usize, key: impl Fn(u32) -> u32) -> (Vec<u32>, Vec<u32>) {
    let mut off = vec![0u32; n + 1];
    for h in 0..nh as u32 {
        off[key(h) as usize + 1] += 1;
    }
    for i in 0..n {
        off[i + 1] += off[i];
    }
    let mut cursor = off.clone();
    let mut items = vec![0u32; nh];
    for h in 0..nh as u32 {
        let c = &mut cursor[key(h) as usize];
        items[*c as usize] = h;
        *c += 1;
    }
    (off, items)
}

#[inline]
fn next_raw(h: u32) -> u32 {
    if h % 3 == 2 {
        h - 2
    } else {
        h + 1
    }
}

#[inline]
fn prev_raw(h: u32) -> u32 {
    match h % 3 {
        0 => h + 2,
        _ => h - 1,
    }
}

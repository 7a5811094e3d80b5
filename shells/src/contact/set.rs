//! The contact set of a configuration: every pair of non-adjacent primitives closer than the
//! activation distance d̂, as one [`Contact`] per pair of closest features (Li et al. 2020,
//! §4.1: point–triangle and edge–edge pairs, each classified into point–point, point–edge,
//! point–plane or line–line by where the closest points fall, and counted once).
//!
//! Self-contact pairs come from cloth vertex × triangle and edge × edge candidates of the broad
//! phase; obstacle pairs from cloth vertex × obstacle triangle, cloth edge × obstacle edge and
//! cloth triangle × obstacle point, plus cloth vertex × half-space. A pair found from several
//! candidates (a vertex near a triangle's edge is also near that edge's other triangle) has one
//! key — its two closest features — and is kept once; the set is sorted by key, so it does not
//! depend on the thread count.

use geom_core::math::{Pt3, Vec3};
use geom_core::query::{closest_point_segment, closest_point_triangle, closest_points_segments};
use geom_core::spatial::Aabb;
use geom_core::NONE;
use nalgebra::SVector;
use rayon::prelude::*;

use super::distance::{self, EeKind, PtKind};
use super::obstacle::{Core, Placed};
use crate::collision::broad::BroadPhase;

/// A feature of a contact pair: cloth vertex, edge, triangle; obstacle o's point, edge,
/// triangle; or obstacle o as a half-space.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub(crate) enum Feat {
    V(u32),
    E(u32),
    T(u32),
    OP(u32, u32),
    OE(u32, u32),
    OT(u32, u32),
    Half(u32),
}

impl Feat {
    /// A user-facing name of the feature (cloth ids are vertex indices of the scene's mesh).
    pub(crate) fn describe(self, edges: &[[u32; 2]]) -> String {
        match self {
            Feat::V(i) => format!("cloth vertex {i}"),
            Feat::E(i) => {
                let e = edges.get(i as usize).copied().unwrap_or([NONE, NONE]);
                format!("cloth edge {}–{}", e[0], e[1])
            }
            Feat::T(i) => format!("cloth triangle {i}"),
            Feat::OP(o, i) => format!("obstacle {o} (its point {i})"),
            Feat::OE(o, i) => format!("obstacle {o} (its edge {i})"),
            Feat::OT(o, i) => format!("obstacle {o} (its triangle {i})"),
            Feat::Half(o) => format!("obstacle {o} (plane)"),
        }
    }

    /// A u64 with the same order as the derived `Ord` (variant in declaration order, then the
    /// fields), for sorting contact keys as integers.
    fn code(self) -> u64 {
        let (tag, a, b) = match self {
            Feat::V(i) => (0u64, 0, i),
            Feat::E(i) => (1, 0, i),
            Feat::T(i) => (2, 0, i),
            Feat::OP(o, i) => (3, o, i),
            Feat::OE(o, i) => (4, o, i),
            Feat::OT(o, i) => (5, o, i),
            Feat::Half(o) => (6, o, 0),
        };
        debug_assert!(a < 1 << 29, "obstacle index {a} beyond the key's 29 bits");
        tag << 61 | (a as u64) << 32 | b as u64
    }
}

/// A point of a contact stencil: a cloth vertex (a degree of freedom) or a fixed obstacle point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Node {
    Cloth(u32),
    Fixed(Pt3),
    Unused,
}

/// The distance form of a contact (which slots of the stencil it uses).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Form {
    /// Slots 0, 1.
    PointPoint,
    /// Point (slot 0) and the line through slots 1, 2.
    PointLine,
    /// Point (slot 0) and the plane through slots 1, 2, 3.
    PointPlane,
    /// Lines through slots 0–1 and 2–3.
    LineLine,
    /// Slot 0 against the plane n̂·x = offset (gap n̂·x − offset).
    Half { normal: Vec3, offset: f64 },
}

/// One active contact pair.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Contact {
    /// The pair's closest features (sort and deduplication key).
    pub key: (Feat, Feat),
    pub form: Form,
    pub nodes: [Node; 4],
    /// Thickness subtracted from the distance (m).
    pub xi: f64,
    /// Coulomb friction coefficient.
    pub mu: f64,
    /// The obstacle (`NONE` for self-contact).
    pub obstacle: u32,
}

/// The gap of a contact and its gradient over the stencil's 12 coordinates.
pub(crate) struct Gap {
    /// d = distance − ξ (m).
    pub d: f64,
    /// ∂d/∂x over the four slots (unused slots zero).
    pub grad: SVector<f64, 12>,
}

impl Contact {
    /// Positions of the stencil's slots in configuration `x`.
    pub fn points(&self, x: &[Pt3]) -> [Pt3; 4] {
        self.nodes.map(|n| match n {
            Node::Cloth(i) => x[i as usize],
            Node::Fixed(p) => p,
            Node::Unused => Pt3::origin(),
        })
    }

    /// The cloth vertex of each stencil slot (`NONE` for obstacle points and unused slots).
    pub fn cloth_nodes(&self) -> [u32; 4] {
        self.nodes.map(|n| if let Node::Cloth(i) = n { i } else { NONE })
    }

    /// The gap and its gradient at `x`.
    pub fn gap(&self, x: &[Pt3]) -> Gap {
        let p = self.points(x);
        let (d2, g) = match self.form {
            Form::Half { normal, offset } => {
                let mut grad = SVector::<f64, 12>::zeros();
                grad.fixed_rows_mut::<3>(0).copy_from(&normal);
                return Gap { d: normal.dot(&p[0].coords) - offset, grad };
            }
            Form::PointPoint => distance::grad::point_point(&p[0], &p[1]),
            Form::PointLine => distance::grad::point_line(&p[0], &p[1], &p[2]),
            Form::PointPlane => distance::grad::point_plane(&p[0], &p[1], &p[2], &p[3]),
            Form::LineLine => distance::grad::line_line(&p[0], &p[1], &p[2], &p[3]),
        };
        let dist = d2.max(0.0).sqrt();
        let mut grad = SVector::<f64, 12>::zeros();
        if dist > 0.0 {
            for (k, gk) in g.iter().enumerate() {
                grad.fixed_rows_mut::<3>(3 * k).copy_from(&(gk / (2.0 * dist)));
            }
        }
        Gap { d: dist - self.xi, grad }
    }

    /// Relative-motion weights c (the pair's relative displacement is Σ c_k Δx_k) and the unit
    /// normal from the second feature toward the first, at `x` (friction's tangent frame).
    pub fn frame(&self, x: &[Pt3]) -> ([f64; 4], Vec3) {
        let p = self.points(x);
        let (c, r): ([f64; 4], Vec3) = match self.form {
            Form::Half { normal, .. } => return ([1.0, 0.0, 0.0, 0.0], normal),
            Form::PointPoint => ([1.0, -1.0, 0.0, 0.0], p[0] - p[1]),
            Form::PointLine => {
                let (s, c) = closest_point_segment(&p[0], &p[1], &p[2]);
                ([1.0, -(1.0 - s), -s, 0.0], p[0] - c)
            }
            Form::PointPlane => {
                let (c, w) = closest_point_triangle(&p[0], &[p[1], p[2], p[3]]);
                ([1.0, -w[0], -w[1], -w[2]], p[0] - c)
            }
            Form::LineLine => {
                let (s, t, pa, pb) = closest_points_segments(&p[0], &p[1], &p[2], &p[3]);
                ([1.0 - s, s, -(1.0 - t), -t], pa - pb)
            }
        };
        let n = r.try_normalize(0.0).unwrap_or_else(|| self.gap(x).grad.fixed_rows::<3>(0).normalize());
        (c, n)
    }
}

/// Everything the set builder needs that does not change during a step.
pub(crate) struct Topo<'a> {
    pub tris: &'a [[u32; 3]],
    pub edges: &'a [[u32; 2]],
    /// Mean rest edge length (m).
    pub mean_edge: f64,
    pub mu_self: f64,
}

/// Index of edge (a, b) in a sorted unique edge list.
pub(crate) fn edge_id(edges: &[[u32; 2]], a: u32, b: u32) -> u32 {
    let key = [a.min(b), a.max(b)];
    edges.binary_search(&key).map(|i| i as u32).unwrap_or(NONE)
}

fn vv(a: Feat, b: Feat) -> (Feat, Feat) {
    if a <= b {
        (a, b)
    } else {
        (b, a)
    }
}

/// A point–triangle contact between point `p` (node `pn`, feature `pf`) and triangle nodes `tn`
/// with features from `tf` (the triangle's vertex, edge and face features), if closer than
/// ξ + d̂.
#[allow(clippy::too_many_arguments)]
fn point_tri(
    p: &Pt3,
    t: &[Pt3; 3],
    pn: Node,
    pf: Feat,
    tn: [Node; 3],
    tf: impl Fn(PtKind) -> Feat,
    xi: f64,
    dhat: f64,
    mu: f64,
    obstacle: u32,
) -> Option<Contact> {
    let (c, _) = closest_point_triangle(p, t);
    if (p - c).norm() - xi >= dhat {
        return None;
    }
    let kind = distance::point_triangle_kind(p, t);
    let key = vv(pf, tf(kind));
    let (form, nodes) = match kind {
        PtKind::Face => (Form::PointPlane, [pn, tn[0], tn[1], tn[2]]),
        PtKind::Edge(k) => (Form::PointLine, [pn, tn[k as usize], tn[(k as usize + 1) % 3], Node::Unused]),
        PtKind::Vertex(k) => (Form::PointPoint, [pn, tn[k as usize], Node::Unused, Node::Unused]),
    };
    Some(Contact { key, form, nodes, xi, mu, obstacle })
}

/// An edge–edge contact between edges with nodes `an`, `bn` and features from `af`, `bf`
/// (vertex i of the edge, or the edge itself for `None`).
#[allow(clippy::too_many_arguments)]
fn edge_edge(
    a: [&Pt3; 2],
    b: [&Pt3; 2],
    an: [Node; 2],
    bn: [Node; 2],
    af: impl Fn(Option<u8>) -> Feat,
    bf: impl Fn(Option<u8>) -> Feat,
    xi: f64,
    dhat: f64,
    mu: f64,
    obstacle: u32,
) -> Option<Contact> {
    let (_, _, pa, pb) = closest_points_segments(a[0], a[1], b[0], b[1]);
    if (pa - pb).norm() - xi >= dhat {
        return None;
    }
    let kind = distance::edge_edge_kind(a[0], a[1], b[0], b[1]);
    let u = Node::Unused;
    let (key, form, nodes) = match kind {
        EeKind::Lines => (vv(af(None), bf(None)), Form::LineLine, [an[0], an[1], bn[0], bn[1]]),
        EeKind::PointA(i) => (vv(af(Some(i)), bf(None)), Form::PointLine, [an[i as usize], bn[0], bn[1], u]),
        EeKind::PointB(j) => (vv(af(None), bf(Some(j))), Form::PointLine, [bn[j as usize], an[0], an[1], u]),
        EeKind::Points(i, j) => {
            (vv(af(Some(i)), bf(Some(j))), Form::PointPoint, [an[i as usize], bn[j as usize], u, u])
        }
    };
    Some(Contact { key, form, nodes, xi, mu, obstacle })
}

/// True when the point sets are farther apart than `d` along some coordinate axis (then no
/// two of their convex hulls' points are within `d`): a cheap rejection before closest points.
fn far(a: &[Pt3], b: &[Pt3], d: f64) -> bool {
    (0..3).any(|k| {
        let (amin, amax) = a.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |m, p| (m.0.min(p[k]), m.1.max(p[k])));
        let (bmin, bmax) = b.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |m, p| (m.0.min(p[k]), m.1.max(p[k])));
        amin - bmax > d || bmin - amax > d
    })
}

/// Self-contacts of the candidate pairs at `x` closer than d̂.
pub(crate) fn self_contacts(topo: &Topo, x: &[Pt3], vt: &[(u32, u32)], ee: &[(u32, u32)], dhat: f64) -> Vec<Contact> {
    let (tris, edges, mu) = (topo.tris, topo.edges, topo.mu_self);
    let mut out: Vec<Contact> = vt
        .par_iter()
        .with_min_len(1024)
        .filter_map(|&(v, t)| {
            let tri = tris[t as usize];
            let tp = tri.map(|i| x[i as usize]);
            if far(&[x[v as usize]], &tp, dhat) {
                return None;
            }
            let tf = |k: PtKind| match k {
                PtKind::Face => Feat::T(t),
                PtKind::Edge(k) => Feat::E(edge_id(edges, tri[k as usize], tri[(k as usize + 1) % 3])),
                PtKind::Vertex(k) => Feat::V(tri[k as usize]),
            };
            point_tri(&x[v as usize], &tp, Node::Cloth(v), Feat::V(v), tri.map(Node::Cloth), tf, 0.0, dhat, mu, NONE)
        })
        .collect();
    out.par_extend(ee.par_iter().with_min_len(1024).filter_map(|&(e, f)| {
        let (a, b) = (edges[e as usize], edges[f as usize]);
        if far(&a.map(|i| x[i as usize]), &b.map(|i| x[i as usize]), dhat) {
            return None;
        }
        let af = |i: Option<u8>| i.map_or(Feat::E(e), |i| Feat::V(a[i as usize]));
        let bf = |j: Option<u8>| j.map_or(Feat::E(f), |j| Feat::V(b[j as usize]));
        edge_edge(
            [&x[a[0] as usize], &x[a[1] as usize]],
            [&x[b[0] as usize], &x[b[1] as usize]],
            a.map(Node::Cloth),
            b.map(Node::Cloth),
            af,
            bf,
            0.0,
            dhat,
            mu,
            NONE,
        )
    }));
    out
}

/// Candidate pairs of the cloth with one core obstacle: cloth vertex × obstacle triangle, cloth
/// edge × obstacle edge, cloth triangle × obstacle point, cloth vertex × obstacle point.
#[derive(Clone, Debug, Default)]
pub(crate) struct CoreCands {
    pub v_ot: Vec<(u32, u32)>,
    pub e_oe: Vec<(u32, u32)>,
    pub t_op: Vec<(u32, u32)>,
    pub v_op: Vec<(u32, u32)>,
}

/// Every pair the contact set or the CCD may need for one obstacle, from the boxes of the
/// cloth's primitives (grown by d̂, swept over a step) against the obstacle's trees (boxes
/// grown by ξ). Which pair kinds a core obstacle gets: meshes their vertices × triangles, edges
/// × edges and triangles × vertices; round obstacles (sphere, capsule) edges × axis and
/// vertices × core points, plus triangles × core points only when the radius is at most the
/// cloth's mean edge. A large sphere is met by vertices and edges: its face contacts would
/// measure the distance to a plane from a centre far beyond the triangle (a lever of r/ℓ² in
/// the curvature that the Gauss–Newton Hessian misses; Newton then crawls), while the sagitta
/// ℓ²/8r a triangle can dip between its vertices stays far below d̂.
pub(crate) fn core_candidates(topo: &Topo, core: &Core, vb: &[Aabb], eb: &[Aabb], tb: &[Aabb]) -> CoreCands {
    let [pt_tree, e_tree, t_tree] = &core.trees;
    let mut c = CoreCands::default();
    if !core.tris.is_empty() {
        for (v, b) in vb.iter().enumerate() {
            t_tree.query(b, |t| c.v_ot.push((v as u32, t)));
        }
    } else {
        for (v, b) in vb.iter().enumerate() {
            pt_tree.query(b, |p| c.v_op.push((v as u32, p)));
        }
    }
    if !core.edges.is_empty() {
        for (e, b) in eb.iter().enumerate() {
            e_tree.query(b, |f| c.e_oe.push((e as u32, f)));
        }
    }
    if !core.tris.is_empty() || core.xi <= topo.mean_edge {
        for (t, b) in tb.iter().enumerate() {
            pt_tree.query(b, |p| c.t_op.push((t as u32, p)));
        }
    }
    c
}

/// Contacts of the cloth at `x` with obstacle `o` closer than d̂, from its candidates.
#[allow(clippy::too_many_arguments)]
pub(crate) fn obstacle_contacts(
    topo: &Topo,
    x: &[Pt3],
    o: u32,
    placed: &Placed,
    cands: &CoreCands,
    mu: f64,
    dhat: f64,
) -> Vec<Contact> {
    match placed {
        Placed::Half { normal, offset } => (0..x.len() as u32)
            .filter(|&v| normal.dot(&x[v as usize].coords) - offset < dhat)
            .map(|v| Contact {
                key: (Feat::V(v), Feat::Half(o)),
                form: Form::Half { normal: *normal, offset: *offset },
                nodes: [Node::Cloth(v), Node::Unused, Node::Unused, Node::Unused],
                xi: 0.0,
                mu,
                obstacle: o,
            })
            .collect(),
        Placed::Core(core) => core_contacts(topo, x, o, core, cands, mu, dhat),
    }
}

fn core_contacts(topo: &Topo, x: &[Pt3], o: u32, core: &Core, c: &CoreCands, mu: f64, dhat: f64) -> Vec<Contact> {
    let (tris, edges) = (topo.tris, topo.edges);
    let xi = core.xi;
    let fixed = |i: u32| Node::Fixed(core.points[i as usize]);
    let mut out = Vec::new();
    for &(v, t) in &c.v_ot {
        let ot = core.tris[t as usize];
        let tp = ot.map(|i| core.points[i as usize]);
        let tf = |k: PtKind| match k {
            PtKind::Face => Feat::OT(o, t),
            PtKind::Edge(k) => Feat::OE(o, edge_id(&core.edges, ot[k as usize], ot[(k as usize + 1) % 3])),
            PtKind::Vertex(k) => Feat::OP(o, ot[k as usize]),
        };
        out.extend(point_tri(&x[v as usize], &tp, Node::Cloth(v), Feat::V(v), ot.map(fixed), tf, xi, dhat, mu, o));
    }
    for &(e, f) in &c.e_oe {
        let a = edges[e as usize];
        let ob = core.edges[f as usize];
        let af = |i: Option<u8>| i.map_or(Feat::E(e), |i| Feat::V(a[i as usize]));
        let bf = |j: Option<u8>| j.map_or(Feat::OE(o, f), |j| Feat::OP(o, ob[j as usize]));
        out.extend(edge_edge(
            [&x[a[0] as usize], &x[a[1] as usize]],
            [&core.points[ob[0] as usize], &core.points[ob[1] as usize]],
            a.map(Node::Cloth),
            ob.map(fixed),
            af,
            bf,
            xi,
            dhat,
            mu,
            o,
        ));
    }
    for &(v, p) in &c.v_op {
        let (x0, cp) = (x[v as usize], core.points[p as usize]);
        if (x0 - cp).norm() - xi < dhat {
            out.push(Contact {
                key: vv(Feat::V(v), Feat::OP(o, p)),
                form: Form::PointPoint,
                nodes: [Node::Cloth(v), fixed(p), Node::Unused, Node::Unused],
                xi,
                mu,
                obstacle: o,
            });
        }
    }
    for &(t, p) in &c.t_op {
        let tri = tris[t as usize];
        let tp = tri.map(|i| x[i as usize]);
        let tf = |k: PtKind| match k {
            PtKind::Face => Feat::T(t),
            PtKind::Edge(k) => Feat::E(edge_id(edges, tri[k as usize], tri[(k as usize + 1) % 3])),
            PtKind::Vertex(k) => Feat::V(tri[k as usize]),
        };
        out.extend(point_tri(
            &core.points[p as usize],
            &tp,
            fixed(p),
            Feat::OP(o, p),
            tri.map(Node::Cloth),
            tf,
            xi,
            dhat,
            mu,
            o,
        ));
    }
    out
}

/// Sorts by key and keeps one contact per key (the first of each key in input order: a stable
/// sort of (key, index) pairs, so the large contacts themselves are moved once, not by the sort).
pub(crate) fn dedup(c: Vec<Contact>) -> Vec<Contact> {
    let mut order: Vec<(u128, u32)> = c
        .iter()
        .enumerate()
        .map(|(i, a)| ((a.key.0.code() as u128) << 64 | a.key.1.code() as u128, i as u32))
        .collect();
    order.sort_unstable();
    order.dedup_by(|a, b| a.0 == b.0);
    order.into_iter().map(|(_, i)| c[i as usize]).collect()
}

/// Vertex, edge and triangle boxes of the cloth at `x`, grown by `margin`, or swept to `x + dx`
/// when `dx` is given.
pub(crate) fn boxes(
    x: &[Pt3],
    dx: Option<&[Vec3]>,
    tris: &[[u32; 3]],
    edges: &[[u32; 2]],
    margin: f64,
) -> (Vec<Aabb>, Vec<Aabb>, Vec<Aabb>) {
    let vb: Vec<Aabb> = match dx {
        Some(d) => x.iter().zip(d).map(|(p, w)| Aabb::from_points(&[*p, p + w]).grow(margin)).collect(),
        None => x.iter().map(|p| Aabb::from_points(&[*p]).grow(margin)).collect(),
    };
    let eb = edges.iter().map(|e| vb[e[0] as usize].union(&vb[e[1] as usize])).collect();
    let tb = tris.iter().map(|t| vb[t[0] as usize].union(&vb[t[1] as usize]).union(&vb[t[2] as usize])).collect();
    (vb, eb, tb)
}

/// Candidate pairs: (vertex, triangle) and (edge, edge) indices.
pub(crate) type CandidatePairs = (Vec<(u32, u32)>, Vec<(u32, u32)>);

/// Self-contact candidate pairs (vertex–triangle, edge–edge) of the given boxes.
pub(crate) fn self_candidates(
    bp: &mut BroadPhase,
    topo: &Topo,
    vb: &[Aabb],
    eb: &[Aabb],
    tb: &[Aabb],
) -> CandidatePairs {
    bp.candidate_pairs(topo.tris, topo.edges, vb, tb, eb)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gap_gradient_matches_finite_differences_for_every_form() {
        let x =
            vec![Pt3::new(0.1, 0.2, 0.05), Pt3::new(0.0, 0.0, 0.0), Pt3::new(1.0, 0.1, 0.0), Pt3::new(0.2, 1.0, 0.1)];
        let forms = [Form::PointPoint, Form::PointLine, Form::PointPlane, Form::LineLine];
        for form in forms {
            let c = Contact {
                key: (Feat::V(0), Feat::V(1)),
                form,
                nodes: [Node::Cloth(0), Node::Cloth(1), Node::Cloth(2), Node::Fixed(x[3])],
                xi: 0.01,
                mu: 0.0,
                obstacle: NONE,
            };
            let g = c.gap(&x);
            for i in 0..3 {
                for k in 0..3 {
                    let e = 1e-7;
                    let mut xp = x.clone();
                    let mut xm = x.clone();
                    xp[i][k] += e;
                    xm[i][k] -= e;
                    let fd = (c.gap(&xp).d - c.gap(&xm).d) / (2.0 * e);
                    assert!(
                        (fd - g.grad[3 * i + k]).abs() < 1e-6,
                        "{form:?} slot {i} axis {k}: {fd} vs {}",
                        g.grad[3 * i + k]
                    );
                }
            }
            // The fixed slot has no degree of freedom, but its gradient entry is still the
            // distance's (used by nobody): only cloth slots are assembled.
        }
    }

    #[test]
    fn feature_codes_keep_the_key_order() {
        let f = [
            Feat::V(3),
            Feat::V(70_000),
            Feat::E(0),
            Feat::T(u32::MAX),
            Feat::OP(0, 5),
            Feat::OP(1, 0),
            Feat::OE(2, 9),
            Feat::OT(0, 1),
            Feat::Half(0),
            Feat::Half(4),
        ];
        for a in &f {
            for b in &f {
                assert_eq!(a.cmp(b), a.code().cmp(&b.code()), "{a:?} vs {b:?}");
            }
        }
    }

    #[test]
    fn duplicate_keys_are_kept_once_in_key_order() {
        let c = |v: u32| Contact {
            key: (Feat::V(v), Feat::T(1)),
            form: Form::PointPoint,
            nodes: [Node::Cloth(v), Node::Cloth(9), Node::Unused, Node::Unused],
            xi: 0.0,
            mu: 0.0,
            obstacle: NONE,
        };
        let d = dedup(vec![c(3), c(1), c(3), c(2)]);
        let keys: Vec<u32> = d.iter().map(|c| if let Feat::V(v) = c.key.0 { v } else { 99 }).collect();
        assert_eq!(keys, vec![1, 2, 3]);
    }
}

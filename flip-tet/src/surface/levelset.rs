//! Level set of the liquid on the mesh nodes from particles of varying radius (spec §3.11.3):
//! triplet-hull union near the surface, coarse sphere union elsewhere, interior redistancing by
//! edge-path distance, mirrored particles at closed box walls, extension into obstacles.

use std::borrow::Cow;
use std::cmp::Reverse;
use std::collections::BinaryHeap;
use std::sync::OnceLock;

use geom_core::graph::Ragged;
use geom_core::math::Pt3;
use geom_core::spatial::KdTree;
use rayon::prelude::*;

use super::hull::{facet_distance, pair_distance};
use super::spheretree::SphereTree;
use super::volume::tet_volume;
use super::{SurfaceMethod, SurfaceParams};
use crate::bcc::TetMesh;
use crate::particles::{ParticleFlags, Particles};

/// Box walls and obstacles as seen by the level set (spec §3.11.3, §12 G16).
#[derive(Clone, Copy, Debug)]
pub struct Walls<'a> {
    /// Domain box minimum corner (m).
    pub min: Pt3,
    /// Domain box maximum corner (m).
    pub max: Pt3,
    /// Closed walls that mirror particles, order −x, +x, −y, +y, −z, +z (open faces: `false`).
    pub mirror: [bool; 6],
    /// Per-node flag "inside a solid obstacle"; such nodes take the average φ of their non-solid
    /// edge neighbours (one sweep) so the liquid sees no free surface along the obstacle.
    pub node_in_solid: Option<&'a [bool]>,
}

impl Walls<'_> {
    /// Walls that mirror nothing and no obstacles (a free-standing particle set).
    pub fn none() -> Walls<'static> {
        Walls { min: Pt3::origin(), max: Pt3::origin(), mirror: [false; 6], node_in_solid: None }
    }
}

/// Relative rounding margin (× band) of the exact pruning bounds.
const PRUNE_EPS: f64 = 1e-9;

/// One source sphere of the level set (a particle or a mirrored copy).
#[derive(Clone, Copy, Debug)]
struct Source {
    x: Pt3,
    /// Radius used for the shapes: `r_temp = max(r, −k φ_p)` (m).
    r: f64,
    near: bool,
}

/// Evaluates the particle level set at arbitrary points (spec §3.11.3, without the interior
/// redistancing, which needs mesh edges): build once per particle configuration, then query.
#[derive(Debug)]
pub struct LevelSetSampler {
    src: Vec<Source>,
    /// k-d tree over all sources, built on first use (only the exhaustive reference and the
    /// Zhu–Bridson method need it).
    all: OnceLock<KdTree>,
    near_idx: Vec<u32>,
    near: KdTree,
    /// All sources with their radii `r_temp`, for the pruned sphere-union query.
    tree: SphereTree,
    /// Largest `r_temp` among the near-surface sources (m): every shape of [`Self::hulls`] has
    /// signed distance `≥ −near_r_max`, so a node with a sphere-union value below it needs no hulls.
    near_r_max: f64,
    /// Largest particle radius (original `r`, not `r_temp`): sets the band and search radius.
    r_max: f64,
    params: SurfaceParams,
}

impl LevelSetSampler {
    /// Collects the non-ballistic particles with their interior radii `max(r, −k φ_p)` (`φ_p` from
    /// `parts.phi`; missing or non-finite values count as surface particles, `r_temp = r`) and their
    /// mirror copies across the closed walls within `2 l r_p` (spec §3.11.3).
    pub fn new(parts: &Particles, params: &SurfaceParams, walls: &Walls) -> Self {
        let mut src = Vec::with_capacity(parts.len());
        let mut r_max: f64 = 0.0;
        for i in 0..parts.len() {
            if parts.flags.get(i).is_some_and(|f| f.has(ParticleFlags::BALLISTIC)) {
                continue;
            }
            let r = parts.r[i];
            let phi = parts.phi.get(i).copied().filter(|v| v.is_finite());
            let r_temp = phi.map_or(r, |p| r.max(-params.interior_k * p));
            let near = phi.is_none_or(|p| p > -params.near_surface_band * r);
            src.push(Source { x: parts.x[i], r: r_temp, near });
            r_max = r_max.max(r);
        }
        // Mirror axis by axis so particles near an edge or corner get all their images.
        for axis in 0..3 {
            let n0 = src.len();
            for s in 0..n0 {
                let Source { x, r, near } = src[s];
                let reach = 2.0 * params.hull_l * r;
                for (side, wall) in [(0, walls.min[axis]), (1, walls.max[axis])] {
                    if walls.mirror[2 * axis + side] && (x[axis] - wall).abs() < reach {
                        let mut y = x;
                        y[axis] = 2.0 * wall - x[axis];
                        src.push(Source { x: y, r, near });
                    }
                }
            }
        }
        let pts: Vec<Pt3> = src.iter().map(|s| s.x).collect();
        let all = OnceLock::new();
        let near_idx: Vec<u32> = (0..src.len() as u32).filter(|&i| src[i as usize].near).collect();
        let near_pts: Vec<Pt3> = near_idx.iter().map(|&i| pts[i as usize]).collect();
        let near = KdTree::build(&near_pts);
        let radii: Vec<f64> = src.iter().map(|s| s.r).collect();
        let tree = SphereTree::build(&pts, &radii);
        let near_r_max = near_idx.iter().map(|&i| src[i as usize].r).fold(0.0, f64::max);
        Self { src, all, near_idx, near, tree, near_r_max, r_max, params: params.clone() }
    }

    /// Number of source spheres (particles plus mirror images).
    pub fn n_sources(&self) -> usize {
        self.src.len()
    }

    /// Largest particle radius `r` (not the interior radius) among the sources (m).
    pub fn r_max(&self) -> f64 {
        self.r_max
    }

    /// The band half-width at a node of local mesh size `h` (m): `max(3 h, 6 r_max)`.
    pub fn band(&self, h: f64) -> f64 {
        (3.0 * h).max(6.0 * self.r_max)
    }

    /// Level-set value at `q` (m, negative inside) for a point whose local mesh size is `h` (m);
    /// values beyond the band are clamped to `±band` (spec §3.11.3). With no sources, `+band`.
    ///
    /// Fast path: the sphere-union part by the pruned [`SphereTree`] query, the triplet hulls only
    /// where they can lower the value (`φ_s > −max r_temp` of the near-surface sources), and pairs
    /// and triplets skipped when a bounding-ball lower bound cannot beat the current minimum. Every
    /// skip is exact (a skipped term is provably not below the minimum, with a `1e−9 band` rounding
    /// margin), so the result equals [`Self::value_exhaustive`] bitwise (tested on random sets).
    pub fn value(&self, q: &Pt3, h: f64) -> f64 {
        let band = self.band(h);
        if self.src.is_empty() {
            return band;
        }
        if self.params.method == SurfaceMethod::ZhuBridson {
            return self.value_exhaustive(q, h);
        }
        let eps = PRUNE_EPS * band;
        let search = 2.0 * self.params.hull_l * self.r_max + band;
        let phi_s = self.tree.min_value(q, search, band, eps);
        if phi_s.is_nan() || phi_s.abs() > band {
            return phi_s.clamp(-band, band);
        }
        match self.params.method {
            SurfaceMethod::Hulls if phi_s > -self.near_r_max - eps => phi_s.min(self.hulls_pruned(q, phi_s, eps, None)),
            _ => phi_s,
        }
    }

    /// Reach of the hulls beyond the spheres (m): `δ = (4 l + 2)/3 · max r_temp` over the
    /// near-surface sources. Every point of a valid pair or triplet hull lies within `δ` of the
    /// union of its balls (take the vertex of largest barycentric weight `λ_k ≥ 1/3`: the centre
    /// offset is `≤ (2/3)` of an edge `< 2 l r_max`, the radius change `≤ (2/3) r_max`), so the
    /// hull value at any point is at least the sphere-union value minus `δ`.
    pub fn hull_reach(&self) -> f64 {
        (4.0 * self.params.hull_l + 2.0) / 3.0 * self.near_r_max
    }

    /// The node value used by [`level_set_on_nodes`]: [`Self::value`], except that the triplet
    /// hulls are evaluated only where the sphere-union value `φ_s ≤ h + δ` ([`Self::hull_reach`];
    /// per node, `δ` uses the largest radius among the `K` nearest near-surface sources, which
    /// are the only ones the hulls are built from).
    ///
    /// Where they are skipped, the exact value is `≥ φ_s − δ > h`, so both values exceed the local
    /// mesh size `h`: every node of a tet cut by the surface, of the first air layer and of the
    /// liquid gets exactly the value of [`Self::value`]; farther air nodes keep `φ_s`, which differs
    /// from the exact value by at most `δ` (both positive, same clamp). Tested in
    /// `tests/surface_fast.rs`.
    pub fn value_on_node(&self, q: &Pt3, h: f64) -> f64 {
        let band = self.band(h);
        if self.src.is_empty() || self.params.method != SurfaceMethod::Hulls {
            return self.value(q, h);
        }
        let eps = PRUNE_EPS * band;
        let search = 2.0 * self.params.hull_l * self.r_max + band;
        let phi_s = self.tree.min_value(q, search, band, eps);
        if phi_s.is_nan() || phi_s.abs() > band {
            return phi_s.clamp(-band, band);
        }
        if phi_s > -self.near_r_max - eps && phi_s <= h + self.hull_reach() {
            phi_s.min(self.hulls_pruned(q, phi_s, eps, Some(h)))
        } else {
            phi_s
        }
    }

    /// [`Self::value_on_node`] for a caller that needs only the sign of nodes strictly inside the
    /// sphere union: returns `(v, true)` with `v` bitwise equal to [`Self::value_on_node`], or
    /// `(v, false)` with some `v < 0` when a source sphere contains `q` (`|q − x_s| − r_s < 0`,
    /// so the exact value is negative too: the hulls and the clamp only lower it or keep it
    /// below zero). The sphere search stops at the first such source instead of finding the
    /// minimum, and no hulls are evaluated: deep liquid nodes cost one leaf scan.
    pub fn value_on_node_or_inside(&self, q: &Pt3, h: f64) -> (f64, bool) {
        let band = self.band(h);
        if self.src.is_empty() || self.params.method != SurfaceMethod::Hulls {
            return (self.value_on_node(q, h), true);
        }
        let eps = PRUNE_EPS * band;
        let search = 2.0 * self.params.hull_l * self.r_max + band;
        let phi_s = self.tree.min_value_until(q, search, band, eps, 0.0);
        if phi_s < 0.0 {
            return (phi_s.max(-band), false);
        }
        // `φ_s ≥ 0` (or NaN): the search did not stop early, so `φ_s` is `min_value`'s result and
        // the rest is `value_on_node` verbatim.
        if phi_s.is_nan() || phi_s.abs() > band {
            return (phi_s.clamp(-band, band), true);
        }
        if phi_s > -self.near_r_max - eps && phi_s <= h + self.hull_reach() {
            (phi_s.min(self.hulls_pruned(q, phi_s, eps, Some(h))), true)
        } else {
            (phi_s, true)
        }
    }

    /// The reference evaluation of [`Self::value`]: the sphere union over every source in the
    /// search ball (k-d tree radius query) and every pair and triplet of the `K` nearest
    /// near-surface sources, without pruning. Kept for tests and for the Zhu–Bridson method.
    pub fn value_exhaustive(&self, q: &Pt3, h: f64) -> f64 {
        let band = self.band(h);
        if self.src.is_empty() {
            return band;
        }
        let l = self.params.hull_l;
        let search = 2.0 * l * self.r_max + band;
        let mut buf = Vec::new();
        let all = self.all.get_or_init(|| KdTree::build(&self.src.iter().map(|s| s.x).collect::<Vec<_>>()));
        all.within(q, search, &mut buf);
        let phi_s = buf.iter().map(|&i| {
            let s = &self.src[i as usize];
            (q - s.x).norm() - s.r
        });
        let phi_s = phi_s.fold(f64::INFINITY, f64::min);
        if phi_s.is_nan() || phi_s.abs() > band {
            return phi_s.clamp(-band, band);
        }
        match self.params.method {
            SurfaceMethod::SphereUnion => phi_s,
            SurfaceMethod::ZhuBridson => self.zhu_bridson(q, &buf).unwrap_or(phi_s),
            SurfaceMethod::Hulls => phi_s.min(self.hulls(q)),
        }
    }

    /// Zhu–Bridson averaged sphere (the fixed-radius comparison, spec S8): kernel
    /// `w = (1 − d²/R²)³` with `R = 2 r_max`, `φ = |q − x̄| − r̄`; `None` when no particle is
    /// within `R`.
    fn zhu_bridson(&self, q: &Pt3, cand: &[u32]) -> Option<f64> {
        let big_r = 2.0 * self.r_max;
        let (mut wsum, mut xs, mut rs) = (0.0, Pt3::origin().coords, 0.0);
        for &i in cand {
            let s = &self.src[i as usize];
            let d2 = (q - s.x).norm_squared() / (big_r * big_r);
            if d2 < 1.0 {
                let w = (1.0 - d2).powi(3);
                wsum += w;
                xs += s.x.coords * w;
                rs += s.r * w;
            }
        }
        (wsum > 0.0).then(|| (q.coords - xs / wsum).norm() - rs / wsum)
    }

    /// Union of spheres, round cones of connected pairs and valid triplet hulls among the `K`
    /// nearest near-surface sources (spec §3.11.1–3.11.3), every shape evaluated (no pruning).
    fn hulls(&self, q: &Pt3) -> f64 {
        self.hull_union(q, f64::INFINITY, 0.0, None, false)
    }

    /// [`Self::hull_union`] with pruning: see there.
    fn hulls_pruned(&self, q: &Pt3, best0: f64, eps: f64, skip_above: Option<f64>) -> f64 {
        self.hull_union(q, best0, eps, skip_above, true)
    }

    /// The union value of [`Self::hulls`], starting from the known upper bound `best0` (the
    /// sphere-union value), with exact pruning when `prune`: a round cone lies in the ball of radius `|a − b|/2 + max(r_a, r_b)`
    /// about the segment midpoint and a triplet hull in the ball `R + max r_k` about the centroid
    /// (`R` = largest centroid-to-centre distance). Outside such a ball every candidate of the
    /// shape (cone distance, valid facet value) is `≥` the distance to the ball, so the shape is
    /// skipped when that positive bound, minus `eps`, is not below the current minimum.
    ///
    /// With `skip_above = Some(h)` the shapes are not evaluated at all when
    /// `best0 > h + (4 l + 2)/3 · max r` over the `K` nearest sources (the local form of
    /// [`Self::hull_reach`], valid because the hulls are built from exactly these sources), and
    /// `best0` is returned ([`Self::value_on_node`]).
    fn hull_union(&self, q: &Pt3, best0: f64, eps: f64, skip_above: Option<f64>, prune: bool) -> f64 {
        let mut knn = Vec::new();
        self.near.knn(q, self.params.neighbours as usize, &mut knn);
        let s: Vec<Source> = knn.iter().map(|&(j, _)| self.src[self.near_idx[j as usize] as usize]).collect();
        let k = s.len();
        let l = self.params.hull_l;
        if let Some(h) = skip_above {
            let reach = (4.0 * l + 2.0) / 3.0 * s.iter().map(|a| a.r).fold(0.0, f64::max);
            if best0 > h + reach {
                return best0;
            }
        }
        let mut best = best0;
        for a in &s {
            best = best.min((q - a.x).norm() - a.r);
        }
        let skip = |lb: f64, best: f64| {
            let lb = lb - eps;
            prune && lb > 0.0 && lb >= best
        };
        let mut conn = vec![false; k * k];
        for i in 0..k {
            for j in (i + 1)..k {
                let (a, b) = (&s[i], &s[j]);
                let d = (a.x - b.x).norm();
                if d < l * (a.r + b.r) && d > 0.0 {
                    conn[i * k + j] = true;
                    let mid = Pt3::from((a.x.coords + b.x.coords) * 0.5);
                    if !skip((q - mid).norm() - 0.5 * d - a.r.max(b.r), best) {
                        best = best.min(pair_distance(q, &a.x, &b.x, a.r, b.r));
                    }
                }
            }
        }
        for i in 0..k {
            for j in (i + 1)..k {
                if !conn[i * k + j] {
                    continue;
                }
                for m in (j + 1)..k {
                    if conn[i * k + m] && conn[j * k + m] {
                        let (a, b, c) = (&s[i], &s[j], &s[m]);
                        let cen = Pt3::from((a.x.coords + b.x.coords + c.x.coords) / 3.0);
                        let rad = (a.x - cen).norm().max((b.x - cen).norm()).max((c.x - cen).norm());
                        if skip((q - cen).norm() - rad - a.r.max(b.r).max(c.r), best) {
                            continue;
                        }
                        if let Some(f) = facet_distance(q, &[a.x, b.x, c.x], &[a.r, b.r, c.r]) {
                            best = best.min(f);
                        }
                    }
                }
            }
        }
        best
    }
}

/// Local mesh size per node: the largest `(12 V)^{1/3}` over its incident tets (the cube edge of
/// a regular BCC tet), m. Nodes in no tet get 0.
pub fn node_sizes(mesh: &TetMesh) -> Vec<f64> {
    let mut h = vec![0.0f64; mesh.nodes.len()];
    for t in &mesh.tets {
        let [a, b, c, d] = t.map(|i| mesh.nodes[i as usize]);
        let s = (12.0 * tet_volume(&a, &b, &c, &d)).cbrt();
        for &i in t {
            h[i as usize] = h[i as usize].max(s);
        }
    }
    h
}

/// Node adjacency along the mesh edges (sorted, deduplicated rows).
pub fn node_edges(mesh: &TetMesh) -> Ragged<u32> {
    let mut pairs: Vec<(u32, u32)> = Vec::with_capacity(mesh.tets.len() * 12);
    for t in &mesh.tets {
        for a in 0..4 {
            for b in 0..4 {
                if a != b {
                    pairs.push((t[a], t[b]));
                }
            }
        }
    }
    pairs.sort_unstable();
    pairs.dedup();
    Ragged::from_pairs(mesh.nodes.len(), &pairs)
}

/// The node sizes and edge lists the level set needs: the mesh's caches (`node_h`, `node_nbrs`,
/// filled by `compute_geometry`), or computed here for meshes built without them.
fn sizes_and_edges(mesh: &TetMesh) -> (Cow<'_, [f64]>, Cow<'_, Ragged<u32>>) {
    let n = mesh.nodes.len();
    let h = if mesh.node_h.len() == n { Cow::Borrowed(&mesh.node_h[..]) } else { Cow::Owned(node_sizes(mesh)) };
    let e = if mesh.node_nbrs.len() == n { Cow::Borrowed(&mesh.node_nbrs) } else { Cow::Owned(node_edges(mesh)) };
    (h, e)
}

/// Liquid level set at every mesh node (m, negative inside), spec §3.11.3: the method of
/// `params.method` within the band `max(3 h, 6 r_max)`, clamped outside it, then interior
/// redistancing (every value `≤ −band` replaced by minus the multi-source shortest edge-path
/// distance from the band nodes, §12 G19), then one extension sweep into solid nodes.
///
/// Only the non-ballistic particles contribute (`parts.flags`); `parts.phi` supplies the stored
/// level set for the interior radii. Parallel per node, bitwise deterministic.
///
/// Node values come from [`LevelSetSampler::value_on_node`]: exact (equal to
/// [`LevelSetSampler::value`]) wherever the value is `≤ h` (liquid, interface tets, first air
/// layer); air nodes farther out may carry the sphere-union value, at most
/// [`LevelSetSampler::hull_reach`] above the hull value. Mesh sizes and edges come from the mesh's
/// caches (`node_h`, `node_nbrs`) when filled.
pub fn level_set_on_nodes(mesh: &TetMesh, parts: &Particles, params: &SurfaceParams, walls: &Walls) -> Vec<f64> {
    let sampler = LevelSetSampler::new(parts, params, walls);
    let (h, edges) = sizes_and_edges(mesh);
    let (h, edges) = (&h[..], &*edges);
    let mut phi: Vec<f64> =
        mesh.nodes.par_iter().zip(h.par_iter()).map(|(q, &hq)| sampler.value_on_node(q, hq)).collect();
    let bands: Vec<f64> = h.iter().map(|&hq| sampler.band(hq)).collect();
    redistance_interior(&mesh.nodes, edges, &bands, &mut phi);
    if let Some(solid) = walls.node_in_solid {
        extend_into_solids(edges, solid, &mut phi);
    }
    phi
}

/// [`level_set_on_nodes`] for a caller that redistances the liquid interior itself (the
/// simulator: `sim::redistance_first_layer` then `sim::redistance_interior`), which overwrites
/// every liquid node that has no air neighbour (`φ ≥ 0`) and is connected along liquid edges to
/// one that has. Such nodes only need their sign, so nodes inside a source sphere get a cheap
/// negative stand-in ([`LevelSetSampler::value_on_node_or_inside`]) unless they are needed:
///
/// 1. liquid nodes with an air neighbour (the first layer: the seeds of the caller's
///    redistancing) get their exact value;
/// 2. liquid components with no first-layer node (the caller cannot reach them) get exact values;
/// 3. if a first-layer node lies at or below its band (`φ ≤ −band`, which the 1-Lipschitz level
///    set rules out in practice), the band redistancing below would read stand-ins: every node is
///    then computed exactly.
///
/// Every other node (air, first layer, unreachable liquid) carries exactly the value of
/// [`level_set_on_nodes`], and the signs of all nodes are the same, so after the caller's two
/// redistancing passes both give bitwise equal fields (tested in `sim`). With obstacles
/// (`walls.node_in_solid`) the solid extension reads interior values: this falls back to
/// [`level_set_on_nodes`].
pub fn level_set_on_nodes_sign_inside(
    mesh: &TetMesh,
    parts: &Particles,
    params: &SurfaceParams,
    walls: &Walls,
) -> Vec<f64> {
    if walls.node_in_solid.is_some() || params.method != SurfaceMethod::Hulls {
        return level_set_on_nodes(mesh, parts, params, walls);
    }
    let sampler = LevelSetSampler::new(parts, params, walls);
    let n = mesh.nodes.len();
    let (h, edges) = sizes_and_edges(mesh);
    let (h, edges) = (&h[..], &*edges);
    let first: Vec<(f64, bool)> =
        mesh.nodes.par_iter().zip(h.par_iter()).map(|(q, &hq)| sampler.value_on_node_or_inside(q, hq)).collect();
    let mut phi: Vec<f64> = first.iter().map(|v| v.0).collect();
    let mut exact: Vec<bool> = first.iter().map(|v| v.1).collect();
    let fill = |phi: &mut [f64], exact: &mut [bool], idx: &[usize]| {
        let vals: Vec<f64> = idx.par_iter().map(|&i| sampler.value_on_node(&mesh.nodes[i], h[i])).collect();
        for (&i, v) in idx.iter().zip(vals) {
            phi[i] = v;
            exact[i] = true;
        }
    };
    // 1. First layer. Stand-ins are negative, so every air node (`φ ≥ 0`) already has its exact
    // value and a stand-in's exact value is negative too: signs are final after this.
    let need: Vec<usize> =
        (0..n).filter(|&i| !exact[i] && edges.row(i).iter().any(|&j| phi[j as usize] >= 0.0)).collect();
    fill(&mut phi, &mut exact, &need);
    // 2. Liquid reachable from the first layer, with the caller's traversal rule (`φ < 0` or NaN).
    let first_layer = |phi: &[f64], i: usize| phi[i] < 0.0 && edges.row(i).iter().any(|&j| phi[j as usize] >= 0.0);
    let mut seen = vec![false; n];
    let mut stack: Vec<usize> = (0..n).filter(|&i| first_layer(&phi, i)).collect();
    for &i in &stack {
        seen[i] = true;
    }
    while let Some(i) = stack.pop() {
        for &j in edges.row(i) {
            let j = j as usize;
            if !seen[j] && (phi[j] < 0.0 || phi[j].is_nan()) {
                seen[j] = true;
                stack.push(j);
            }
        }
    }
    let need: Vec<usize> = (0..n).filter(|&i| !exact[i] && !seen[i]).collect();
    fill(&mut phi, &mut exact, &need);
    let bands: Vec<f64> = h.iter().map(|&hq| sampler.band(hq)).collect();
    // 3. Guard: a first-layer node at or below its band would be rewritten from stand-ins.
    if (0..n).any(|i| phi[i] <= -bands[i] && first_layer(&phi, i)) {
        let need: Vec<usize> = (0..n).filter(|&i| !exact[i]).collect();
        fill(&mut phi, &mut exact, &need);
    }
    redistance_interior(&mesh.nodes, edges, &bands, &mut phi);
    phi
}

/// Replaces every `φ_i ≤ −band_i` by `−d_i`, `d` the multi-source Dijkstra distance along mesh
/// edges seeded with `−φ` at the band nodes (`−band < φ ≤ 0`). Unreached nodes keep their value.
pub fn redistance_interior(nodes: &[Pt3], edges: &Ragged<u32>, band: &[f64], phi: &mut [f64]) {
    let deep: Vec<bool> = phi.iter().zip(band).map(|(&p, &b)| p <= -b).collect();
    if !deep.iter().any(|&d| d) {
        return;
    }
    let mut dist = vec![f64::INFINITY; phi.len()];
    // Distances are non-negative, so their IEEE bit patterns order like the values.
    let mut heap = BinaryHeap::new();
    for i in 0..phi.len() {
        if !deep[i] && phi[i] <= 0.0 {
            dist[i] = -phi[i];
            heap.push(Reverse((dist[i].to_bits(), i as u32)));
        }
    }
    while let Some(Reverse((bits, i))) = heap.pop() {
        let d = f64::from_bits(bits);
        if d > dist[i as usize] {
            continue;
        }
        for &j in edges.row(i as usize) {
            if !deep[j as usize] {
                continue;
            }
            let nd = d + (nodes[j as usize] - nodes[i as usize]).norm();
            if nd < dist[j as usize] {
                dist[j as usize] = nd;
                heap.push(Reverse((nd.to_bits(), j)));
            }
        }
    }
    for i in 0..phi.len() {
        if deep[i] && dist[i].is_finite() {
            phi[i] = -dist[i];
        }
    }
}

/// One Jacobi sweep: every solid node takes the average φ of its non-solid edge neighbours
/// (spec §3.11.3 "Obstacles"); solid nodes with no such neighbour keep their value.
pub fn extend_into_solids(edges: &Ragged<u32>, solid: &[bool], phi: &mut [f64]) {
    let old = phi.to_vec();
    for (i, p) in phi.iter_mut().enumerate() {
        if !solid.get(i).copied().unwrap_or(false) {
            continue;
        }
        let (s, n) = edges
            .row(i)
            .iter()
            .filter(|&&j| !solid.get(j as usize).copied().unwrap_or(false))
            .fold((0.0, 0usize), |(s, n), &j| (s + old[j as usize], n + 1));
        if n > 0 {
            *p = s / n as f64;
        }
    }
}

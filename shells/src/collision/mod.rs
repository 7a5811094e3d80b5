//! Collision handling after Bridson, Fedkiw & Anderson 2002 (shells.md §3.9): a velocity filter
//! applied after the linear solve, so the system matrix and its symbolic factorisation never
//! change.
//!
//! Invariant: q_k is collision-free; [`Collider::filter`] edits the end-of-step velocities so the
//! straight motion q_k → q_k + h v stays collision-free:
//! 1. proximity at q_k (vertex–triangle, edge–edge closer than h_c): inelastic impulse, then a
//!    capped repulsion, with Coulomb friction;
//! 2. rigid obstacles (infinite mass): vertices, plus edges against thin capsules/spheres;
//! 3. continuous detection (coplanarity cubics) with inelastic impulses that leave a small
//!    separating speed, up to `ccd_passes` passes;
//! 4. rigid impact zones for what remains, and as a last resort freezing the offending vertices
//!    at q_k (collision-free by the invariant), reported in the statistics.
//!
//! The CCD broad phase works in a frame translating with the mean velocity, keeps one
//! candidate superset per filter call and re-tests only pairs whose velocities changed; pairs
//! inside one rigid impact zone are not re-tested (they cannot approach). None of this changes
//! a hit: see [`Collider::ccd_pairs`] and [`Collider::skip_rigid`].
//!
//! Impulses of one pass are accumulated (Jacobi) in the sorted pair order and each pair's
//! impulse is scaled by 1/(largest number of pairs of any of its vertices), which keeps every
//! impulse equal and opposite, hence linear momentum is conserved.

pub mod broad;
pub mod ccd;
pub mod geometry;
pub mod obstacles;

use crate::effects::{CollisionSettings, Effects, Obstacle};
use crate::integrator::StepStats;
use crate::mesh::ShellMesh;
use broad::BroadPhase;
use geom_core::graph::UnionFind;
use geom_core::math::{Mat3, Pt3, Vec3};
use geom_core::query::{closest_point_triangle, closest_points_segments};
use geom_core::spatial::Aabb;
use geometry::safe_normal;
use obstacles::PlacedObstacle;
use rayon::prelude::*;

/// A contact stencil: up to four vertices with weights c_i (relative velocity Σc_i v_i) and a
/// unit normal.
#[derive(Clone, Copy, Debug)]
struct Stencil {
    v: [u32; 4],
    c: [f64; 4],
    n: Vec3,
}

impl Stencil {
    fn rel(&self, vel: &[Vec3]) -> Vec3 {
        (0..4).map(|k| self.c[k] * vel[self.v[k] as usize]).sum()
    }
    fn denom(&self, im: &[f64]) -> f64 {
        (0..4).map(|k| self.c[k] * self.c[k] * im[self.v[k] as usize]).sum()
    }
}

/// One requested velocity change: raise v_N by `dn` (≥ 0) and apply friction μ.
struct Request {
    s: Stencil,
    dn: f64,
    mu: f64,
}

/// The collision pipeline of one simulation (built only when `effects.collision` is set).
pub(crate) struct Collider {
    tris: Vec<[u32; 3]>,
    edges: Vec<[u32; 2]>,
    mass: Vec<f64>,
    h_c: f64,
    mu: f64,
    k_rep: f64,
    settings: CollisionSettings,
    delta_ccd: f64,
    self_collision: bool,
    obstacles: Vec<Obstacle>,
    /// Query structures of closed mesh obstacles (`None` for the others), built once.
    obstacle_accel: Vec<Option<geom_core::collide::MeshQuery>>,
    thin: f64,
    broad: BroadPhase,
    /// Velocities and hits of the last CCD of the current [`Collider::filter`] call.
    ccd_cache: Option<CcdCache>,
    /// Per vertex, the root of the rigid impact zone whose velocities are currently an exact
    /// rigid motion v = v_c + ω × (q − x_c) (`NONE` otherwise); valid within one filter call.
    rigid_zone: Vec<u32>,
    /// Incremented whenever zones are rigidified (to know when the superset was last pruned).
    zone_gen: u64,
    /// Pairs closer than [`NEAR_FACTOR`]·δ_ccd at q (from the proximity pass, sorted): they keep
    /// their full CCD test even inside one rigid zone.
    near: Vec<PairKey>,
    /// CCD candidate superset of the current filter call (see [`Collider::ccd_pairs`]).
    superset: Option<Superset>,
    /// Velocity u of the translating frame in which the CCD broad phase sweeps its boxes
    /// (fixed at the first CCD of a filter call; see [`Collider::ccd_pairs`]).
    frame: Option<Vec3>,
    /// When set, the velocities after every stage of [`Collider::filter`] (diagnostics: which
    /// stage adds energy or lets vertices through; see `examples/contact_stages.rs`).
    pub(crate) trace: Option<Vec<(&'static str, Vec<Vec3>)>>,
}

/// Candidate pairs of swept boxes grown by an extra slack s around the end points q + h v_ref:
/// while a vertex's end point stays within s/2 of q + h v_ref (max norm), its exact swept box
/// lies inside the grown one, so the superset holds every exact candidate pair of it.
///
/// Pairs inside one rigid zone (see [`Collider::skip_rigid`]) are pruned from it once zones
/// exist: zones only grow and stay rigid during the impact-zone iterations, so such a pair is
/// skipped in every later call anyway. Whenever a vertex loses its rigid mark (a zone that
/// joins a constrained one, the freezing failsafe), the superset is dropped and rebuilt.
struct Superset {
    v_ref: Vec<Vec3>,
    slack: f64,
    /// `zone_gen` of the last pruning of rigid-zone pairs.
    zone_gen: u64,
    vt: broad::Pairs,
    ee: broad::Pairs,
}

/// CCD boxes are grown by this multiple of δ_ccd: δ_ccd itself plus room for the rounding of
/// the moving-frame end points q + h (v − u) (any margin ≥ δ_ccd only changes how many
/// candidates the narrow phase rejects, never its hits).
const FRAME_MARGIN: f64 = 2.0;

/// Pairs inside one rigid zone closer than this multiple of δ_ccd at q are still CCD-tested
/// (a safety margin over the exact bound d(t) ≥ d(0) > δ_ccd; see [`Collider::skip_rigid`]).
const NEAR_FACTOR: f64 = 2.0;

/// A CCD pair: (0, vertex, triangle) or (1, edge, edge); sorting by it gives the hit order.
type PairKey = (u8, u32, u32);

/// The velocities the last CCD ran with and its keyed hits (see [`Collider::ccd_hits`]).
struct CcdCache {
    v: Vec<Vec3>,
    hits: Vec<(PairKey, Stencil)>,
}

impl Collider {
    pub(crate) fn new(mesh: &ShellMesh, effects: &Effects, cs: &CollisionSettings, membrane_stiffness: f64) -> Self {
        let mean_edge = mesh.mean_edge_length();
        let h_c = if cs.thickness > 0.0 { cs.thickness } else { (0.1 * mean_edge).clamp(1e-3, 1e-2) };
        let l = geom_core::mesh::bbox_of(&mesh.rest).map(|(a, b)| (b - a).norm()).unwrap_or(1.0);
        Self {
            tris: mesh.tris.clone(),
            edges: mesh.edges.clone(),
            mass: mesh.mass.clone(),
            h_c,
            mu: cs.friction,
            k_rep: cs.repulsion_stiffness.unwrap_or(membrane_stiffness),
            settings: cs.clone(),
            delta_ccd: 1e-6 * l,
            self_collision: effects.self_collision,
            obstacles: effects.obstacles.clone(),
            obstacle_accel: effects.obstacles.iter().map(obstacles::mesh_query).collect(),
            thin: 2.0 * mean_edge,
            broad: BroadPhase::default(),
            ccd_cache: None,
            rigid_zone: Vec::new(),
            zone_gen: 0,
            near: Vec::new(),
            superset: None,
            frame: None,
            trace: None,
        }
    }

    fn snap(&mut self, stage: &'static str, v: &[Vec3]) {
        if let Some(t) = self.trace.as_mut() {
            t.push((stage, v.to_vec()));
        }
    }

    /// Filters the end-of-step velocities `v` (motion q → q + h v) in place; `im` holds inverse
    /// masses (0 for pinned/kinematic vertices, whose velocities are never changed).
    pub(crate) fn filter(&mut self, q: &[Pt3], v: &mut [Vec3], h: f64, t_next: f64, im: &[f64], st: &mut StepStats) {
        let n = q.len();
        if n == 0 {
            return;
        }
        self.broad.next_step();
        self.reset_call_state(n);
        if let Some(t) = self.trace.as_mut() {
            t.clear();
        }
        self.snap("solve", v);
        if self.self_collision {
            self.proximity(q, v, h, im, st);
            self.snap("proximity", v);
        }
        self.obstacle_pass(q, v, h, t_next, im, st);
        self.snap("obstacles", v);
        if !self.self_collision {
            return;
        }
        let mut remaining = Vec::new();
        if self.settings.ccd {
            for _ in 0..self.settings.ccd_passes.max(1) {
                let hits = self.ccd_hits(q, v, h);
                if hits.is_empty() {
                    return;
                }
                st.n_ccd += hits.len() as u32;
                let target = self.settings.separation_speed_frac * self.h_c / h;
                let reqs: Vec<Request> = hits
                    .into_iter()
                    .filter_map(|s| {
                        let vn = s.rel(v).dot(&s.n);
                        (vn < target).then_some(Request { s, dn: target - vn, mu: 0.0 })
                    })
                    .collect();
                apply(&reqs, v, im, n);
                self.snap("ccd", v);
            }
            remaining = self.ccd_hits(q, v, h);
        }
        if !remaining.is_empty() {
            self.impact_zones(q, v, h, im, remaining, st);
        }
    }

    /// Forgets everything that is valid within one [`Collider::filter`] call only (q changes
    /// between calls): the CCD cache, the candidate superset and its frame, the rigid zones.
    fn reset_call_state(&mut self, n: usize) {
        self.ccd_cache = None;
        self.superset = None;
        self.frame = None;
        self.rigid_zone.clear();
        self.rigid_zone.resize(n, geom_core::NONE);
        self.near.clear();
    }

    /// Candidate (vertex, triangle) and (edge, edge) pairs for the motion q → q + h v: swept
    /// boxes inflated by `margin`, through the refitted trees of the broad phase.
    fn candidates(&mut self, q: &[Pt3], v: Option<&[Vec3]>, h: f64, margin: f64) -> (broad::Pairs, broad::Pairs) {
        let (vb, tb, eb) = self.swept_boxes(q, v, h, margin, &Vec3::zeros());
        self.broad.candidate_pairs(&self.tris, &self.edges, &vb, &tb, &eb)
    }

    /// Boxes of the vertices (swept over q → q + h (v − u) when `v` is given: the motion seen
    /// from a frame translating with velocity u), triangles and edges, inflated by `margin`.
    fn swept_boxes(
        &self,
        q: &[Pt3],
        v: Option<&[Vec3]>,
        h: f64,
        margin: f64,
        u: &Vec3,
    ) -> (Vec<Aabb>, Vec<Aabb>, Vec<Aabb>) {
        // Vertex boxes first; triangle and edge boxes are unions of their vertices' boxes.
        let vb: Vec<Aabb> = match v {
            Some(v) => q.iter().zip(v).map(|(p, w)| Aabb::from_points(&[*p, p + h * (w - u)]).grow(margin)).collect(),
            None => q.iter().map(|p| Aabb::from_points(&[*p]).grow(margin)).collect(),
        };
        let tb: Vec<Aabb> =
            self.tris.iter().map(|t| vb[t[0] as usize].union(&vb[t[1] as usize]).union(&vb[t[2] as usize])).collect();
        let eb: Vec<Aabb> = self.edges.iter().map(|e| vb[e[0] as usize].union(&vb[e[1] as usize])).collect();
        (vb, tb, eb)
    }

    /// Step 1: proximity at q with inelastic + repulsion impulses and friction.
    fn proximity(&mut self, q: &[Pt3], v: &mut [Vec3], h: f64, im: &[f64], st: &mut StepStats) {
        let hc = self.h_c;
        // Boxes grown by h_c/2 each overlap exactly when the points may be closer than h_c.
        let (vt, ee) = self.candidates(q, None, h, 0.5 * hc);
        // Narrow phase in parallel; `collect` keeps the sorted pair order (deterministic).
        let vel: &[Vec3] = v;
        let mut stencils: Vec<(PairKey, Stencil, f64)> = par_filter_map(&vt, |&(p, t)| {
            let tri = self.tris[t as usize];
            let x = tri.map(|i| q[i as usize]);
            let (c, w) = closest_point_triangle(&q[p as usize], &x);
            let d = (q[p as usize] - c).norm();
            if d >= hc {
                return None;
            }
            let tn = (x[1] - x[0]).cross(&(x[2] - x[0]));
            let nrm = if d > 1e-12 * hc {
                (q[p as usize] - c) / d
            } else {
                // Coincident: the triangle normal, on the vertex's side of motion.
                let n0 = safe_normal(&(x[1] - x[0]), &(x[2] - x[0]));
                if tn.dot(&(vel[p as usize])) > 0.0 {
                    -n0
                } else {
                    n0
                }
            };
            Some(((0, p, t), Stencil { v: [p, tri[0], tri[1], tri[2]], c: [1.0, -w[0], -w[1], -w[2]], n: nrm }, d))
        });
        let ee_st: Vec<(PairKey, Stencil, f64)> = par_filter_map(&ee, |&(e, f)| {
            let (a, b) = (self.edges[e as usize], self.edges[f as usize]);
            let (s, u, pa, pb) =
                closest_points_segments(&q[a[0] as usize], &q[a[1] as usize], &q[b[0] as usize], &q[b[1] as usize]);
            let d = (pa - pb).norm();
            if d >= hc {
                return None;
            }
            let nrm = if d > 1e-12 * hc {
                (pa - pb) / d
            } else {
                safe_normal(&(q[a[1] as usize] - q[a[0] as usize]), &(q[b[1] as usize] - q[b[0] as usize]))
            };
            Some(((1, e, f), Stencil { v: [a[0], a[1], b[0], b[1]], c: [1.0 - s, s, -(1.0 - u), -u], n: nrm }, d))
        });
        stencils.extend(ee_st);
        // Candidates come in traversal order: sort the (few) contacts by pair, the order in
        // which the impulses are accumulated.
        stencils.sort_unstable_by_key(|x| x.0);
        let near_d = NEAR_FACTOR * self.delta_ccd;
        self.near.extend(stencils.iter().filter(|x| x.2 <= near_d).map(|x| x.0));
        st.n_proximity += stencils.len() as u32;
        let fsep = self.settings.separation_speed_frac;
        let reqs: Vec<Request> = stencils
            .into_iter()
            .filter_map(|(_, s, d)| {
                let den = s.denom(im);
                if den <= 0.0 {
                    return None;
                }
                let vn = s.rel(v).dot(&s.n);
                let mut dn = if vn < 0.0 { -vn } else { 0.0 };
                let vn1 = vn + dn;
                let gap = hc - d;
                let want = fsep * gap / h;
                if vn1 < want {
                    let meff = 1.0 / den;
                    dn += (h * self.k_rep * gap / meff).min(want - vn1);
                }
                (dn > 0.0).then_some(Request { s, dn, mu: self.mu })
            })
            .collect();
        apply(&reqs, v, im, q.len());
    }

    /// Step 2 (and final clamp): obstacles, infinite mass.
    fn obstacle_pass(&self, q: &[Pt3], v: &mut [Vec3], h: f64, t_next: f64, im: &[f64], st: &mut StepStats) {
        if self.obstacles.is_empty() {
            return;
        }
        let hc = self.h_c;
        let fsep = self.settings.separation_speed_frac;
        for (o, accel) in self.obstacles.iter().zip(&self.obstacle_accel) {
            let po = PlacedObstacle::new(o, t_next, h).with_accel(accel.as_ref());
            // Vertices (each independent: obstacle impulses go entirely to the cloth).
            let hits: Vec<(usize, Vec3)> = (0..q.len())
                .into_par_iter()
                .filter_map(|i| {
                    if im[i] == 0.0 {
                        return None;
                    }
                    let p0 = po.query(&q[i]);
                    let pe = po.query(&(q[i] + h * v[i]));
                    if p0.distance >= hc && pe.distance >= hc {
                        return None;
                    }
                    let nrm = if p0.distance < hc { p0.normal } else { pe.normal };
                    let vo = po.velocity_at(&q[i], h);
                    let rel = v[i] - vo;
                    let vn = rel.dot(&nrm);
                    // Below h_c: no approach plus a small separation; farther: stop at 0.9 h_c.
                    // (A former extra clamp, max(vn_min, min(h_c(1 − f) − min(d₀, d_end), 0)/h),
                    // was 0 whenever the end point came within 0.9 h_c, stopping vertices up to a
                    // whole step's travel away: the first source of energy in fold-stress.)
                    let vn_min = if p0.distance < hc {
                        (fsep * (hc - p0.distance) / h).max(0.0)
                    } else {
                        (0.9 * hc - p0.distance) / h
                    };
                    if vn >= vn_min {
                        return None;
                    }
                    let dn = vn_min - vn;
                    let vt = rel - vn * nrm;
                    let tl = vt.norm();
                    let red = (o.friction * dn).min(tl);
                    let new_rel = rel + dn * nrm - if tl > 0.0 { red * vt / tl } else { Vec3::zeros() };
                    Some((i, vo + new_rel))
                })
                .collect();
            st.n_proximity += hits.len() as u32;
            for (i, w) in hits {
                v[i] = w;
            }
            // Edges against thin round shapes (a branch between two vertices).
            if let (true, Some((a, b, r))) = (po.is_thin(self.thin), po.capsule_axis()) {
                let mut reqs: Vec<(usize, usize, f64, Vec3, f64)> = Vec::new();
                for e in &self.edges {
                    let (i, j) = (e[0] as usize, e[1] as usize);
                    for (pi, pj) in [(q[i], q[j]), (q[i] + h * v[i], q[j] + h * v[j])] {
                        let (s, _, pe, pa) = closest_points_segments(&pi, &pj, &a, &b);
                        let d = (pe - pa).norm() - r;
                        if d < hc && s > 0.0 && s < 1.0 {
                            let nrm = if (pe - pa).norm() > 0.0 { (pe - pa).normalize() } else { Vec3::y() };
                            let rel = (1.0 - s) * v[i] + s * v[j] - po.velocity_at(&pe, h);
                            let vn = rel.dot(&nrm);
                            let d0 = {
                                let (_, _, p0, a0) = closest_points_segments(&q[i], &q[j], &a, &b);
                                (p0 - a0).norm() - r
                            };
                            let vn_min = if d0 < hc { (fsep * (hc - d0) / h).max(0.0) } else { (0.9 * hc - d0) / h };
                            if vn < vn_min {
                                reqs.push((i, j, s, nrm, vn_min - vn));
                            }
                            break;
                        }
                    }
                }
                for (i, j, s, nrm, dn) in reqs {
                    let den = (1.0 - s) * (1.0 - s) * im[i] + s * s * im[j];
                    if den > 0.0 {
                        let jn = dn / den;
                        v[i] += (1.0 - s) * jn * im[i] * nrm;
                        v[j] += s * jn * im[j] * nrm;
                    }
                }
            }
        }
    }

    /// All CCD hits of the motion q → q + h v, as stencils with separating normals, in the order
    /// of the sorted (vertex, triangle) pairs, then the sorted (edge, edge) pairs.
    ///
    /// Within one [`Collider::filter`] call q is fixed and only some velocities change between
    /// calls (CCD passes, impact-zone iterations, freezing), so after the first call only pairs
    /// with a vertex whose velocity changed are tested again; every other pair has the same
    /// swept boxes and the same motion, hence the same result as in the previous call. The hit
    /// list is therefore identical (same stencils, same order) to a full recomputation — checked
    /// by `incremental_ccd_equals_full` — at a cost proportional to what moved.
    fn ccd_hits(&mut self, q: &[Pt3], v: &[Vec3], h: f64) -> Vec<Stencil> {
        let mut keyed: Vec<(PairKey, Stencil)> = match self.ccd_cache.take() {
            Some(cache) if cache.v.len() == v.len() => {
                let changed: Vec<bool> = cache.v.iter().zip(v).map(|(a, b)| a != b).collect();
                if !changed.contains(&true) {
                    cache.hits
                } else {
                    let mut out: Vec<(PairKey, Stencil)> =
                        cache.hits.into_iter().filter(|(_, s)| s.v.iter().all(|&i| !changed[i as usize])).collect();
                    out.extend(self.ccd_pairs(q, v, h, Some(&changed)));
                    out
                }
            }
            _ => self.ccd_pairs(q, v, h, None),
        };
        // Candidates come in traversal order: sorting the (few) hits by pair gives the order of
        // a sorted candidate list, in which impulses are accumulated.
        keyed.sort_unstable_by_key(|&(k, _)| k);
        let hits = keyed.iter().map(|&(_, s)| s).collect();
        self.ccd_cache = Some(CcdCache { v: v.to_vec(), hits: keyed });
        hits
    }

    /// CCD hits (unsorted) of every candidate pair with a `changed` vertex (all pairs when
    /// `None`).
    ///
    /// Broad phase in a translating frame: the boxes sweep q → q + h (v − u), with u the
    /// mass-weighted mean velocity at the first CCD of the filter call, grown by 2δ_ccd. CCD is
    /// Galilean invariant: subtracting t h u from every point at time t changes no distance at
    /// that time, so a pair that comes within δ_ccd at some t has overlapping boxes in that
    /// frame too, and the hits are those of the fixed frame. A flag flying at 2–3 m/s sweeps
    /// boxes of ~2 cm per step in the fixed frame, most of it common motion; in the moving
    /// frame far fewer boxes overlap (1.9 M instead of 3.2 M superset pairs over ten tangled
    /// steps of `tracks/flag`).
    ///
    /// Few changed vertices: tree queries with their boxes. Otherwise the candidates come from
    /// a superset traversed once per filter call with boxes grown by a slack s = h_c around
    /// reference end points q + h v_ref ([`Superset`]): while a vertex's end point stays within
    /// s/2 of its reference (max norm), its exact swept box lies inside the grown one, so every
    /// exact candidate pair of such vertices is in the superset and is found there by the exact
    /// box test. Pairs of vertices that moved farther come from tree queries with the exact
    /// boxes, and when a quarter of the vertices did, the superset is traversed again around
    /// the current velocities. Either way the pairs tested are exactly the overlapping,
    /// non-adjacent pairs of the exact swept boxes that touch a changed vertex, each once
    /// (minus pairs inside one rigid zone, which cannot hit: [`Collider::skip_rigid`]).
    fn ccd_pairs(&mut self, q: &[Pt3], v: &[Vec3], h: f64, changed: Option<&[bool]>) -> Vec<(PairKey, Stencil)> {
        let n = v.len();
        let u = *self.frame.get_or_insert_with(|| {
            let m: f64 = self.mass.iter().sum();
            let p: Vec3 = self.mass.iter().zip(v).map(|(m, w)| *m * w).sum();
            if m > 0.0 && p.iter().all(|x| x.is_finite()) {
                p / m
            } else {
                Vec3::zeros()
            }
        });
        let margin = FRAME_MARGIN * self.delta_ccd;
        let (vb, tb, eb) = self.swept_boxes(q, Some(v), h, margin, &u);
        if let Some(c) = changed {
            if 4 * c.iter().filter(|&&x| x).count() < n {
                let (vt, ee) = self.broad.candidate_pairs_touching(&self.tris, &self.edges, (&vb, &tb, &eb), c);
                return self.narrow_ccd(q, v, h, &vt, &ee);
            }
        }
        let slack = self.h_c;
        let mut exceeded: Vec<bool> = match &self.superset {
            Some(ss) => v.iter().zip(&ss.v_ref).map(|(a, b)| (h * (a - b)).amax() > 0.5 * ss.slack).collect(),
            None => vec![true; n],
        };
        if 4 * exceeded.iter().filter(|&&x| x).count() >= n {
            let (gvb, gtb, geb) = self.swept_boxes(q, Some(v), h, margin + slack, &u);
            let (vt, ee) = self.broad.candidate_pairs(&self.tris, &self.edges, &gvb, &gtb, &geb);
            self.superset = Some(Superset { v_ref: v.to_vec(), slack, zone_gen: 0, vt, ee });
            exceeded.iter_mut().for_each(|x| *x = false);
        }
        if let Some(mut ss) = self.superset.take() {
            if ss.zone_gen != self.zone_gen {
                ss.vt.retain(|&(p, t)| {
                    let tri = self.tris[t as usize];
                    !self.skip_rigid([p, tri[0], tri[1], tri[2]], (0, p, t))
                });
                ss.ee.retain(|&(e, f)| {
                    let (a, b) = (self.edges[e as usize], self.edges[f as usize]);
                    !self.skip_rigid([a[0], a[1], b[0], b[1]], (1, e, f))
                });
                ss.zone_gen = self.zone_gen;
            }
            self.superset = Some(ss);
        }
        // Per-vertex flags: 1 = changed (pair must be tested), 2 = end point left the slack.
        let flags: Vec<u8> = (0..n).map(|i| changed.is_none_or(|c| c[i]) as u8 | (exceeded[i] as u8) << 1).collect();
        let mut hits = Vec::new();
        if exceeded.contains(&true) {
            let (mut vt, mut ee) =
                self.broad.candidate_pairs_touching(&self.tris, &self.edges, (&vb, &tb, &eb), &exceeded);
            let any = |vs: &[u32]| vs.iter().fold(0u8, |a, &i| a | flags[i as usize]) & 1 != 0;
            vt.retain(|&(p, t)| any(&[p]) || any(&self.tris[t as usize]));
            ee.retain(|&(e, f)| any(&self.edges[e as usize]) || any(&self.edges[f as usize]));
            hits = self.narrow_ccd(q, v, h, &vt, &ee);
        }
        let ss = self.superset.as_ref().expect("built above when missing");
        // Superset pairs: tested when a vertex changed, none left the slack, and the exact
        // swept boxes overlap; one fused pass with the narrow phase.
        let ok = |f: u8| f & 3 == 1;
        hits.extend(par_filter_map(&ss.vt, |&(p, t)| {
            let tri = self.tris[t as usize];
            let f = flags[p as usize] | flags[tri[0] as usize] | flags[tri[1] as usize] | flags[tri[2] as usize];
            if !ok(f) || !overlap(&vb[p as usize], &tb[t as usize]) {
                return None;
            }
            self.ccd_vt(q, v, h, p, t)
        }));
        hits.extend(par_filter_map(&ss.ee, |&(e, f)| {
            let (a, b) = (self.edges[e as usize], self.edges[f as usize]);
            let fl = flags[a[0] as usize] | flags[a[1] as usize] | flags[b[0] as usize] | flags[b[1] as usize];
            if !ok(fl) || !overlap(&eb[e as usize], &eb[f as usize]) {
                return None;
            }
            self.ccd_ee(q, v, h, e, f)
        }));
        hits
    }

    /// True when all four vertices of a pair move with one rigid impact zone and the pair is
    /// farther apart than [`NEAR_FACTOR`]·δ_ccd at q: then it cannot be a CCD hit. Within a zone,
    /// x_i(t) = q_i + t h (v_c + ω × (q_i − x_c)), so every difference vector maps by
    /// A(t) = I + t h [ω]ₓ, and |A(t) r|² = |r|² + t²h²|ω × r|² ≥ |r|²: the distance between
    /// any two points of the zone's primitives never shrinks during the step (and the signed
    /// volume, hence coplanarity, only scales by det A(t) = 1 + t²h²|ω|² > 0). A pair farther
    /// than δ_ccd at q therefore stays so, and the full test could only report a hit through
    /// rounding (Bridson et al. 2002: rigid zones do not collide internally).
    fn skip_rigid(&self, vs: [u32; 4], key: PairKey) -> bool {
        let Some(&z) = self.rigid_zone.get(vs[0] as usize) else { return false };
        z != geom_core::NONE
            && vs[1..].iter().all(|&i| self.rigid_zone[i as usize] == z)
            && self.near.binary_search(&key).is_err()
    }

    /// Narrow-phase CCD of the given candidate pairs (vertex–triangle, edge–edge), keyed by
    /// pair, in the input order (vt first).
    fn narrow_ccd(
        &self,
        q: &[Pt3],
        v: &[Vec3],
        h: f64,
        vt: &[(u32, u32)],
        ee: &[(u32, u32)],
    ) -> Vec<(PairKey, Stencil)> {
        let mut hits = par_filter_map(vt, |&(p, t)| self.ccd_vt(q, v, h, p, t));
        hits.extend(par_filter_map(ee, |&(e, f)| self.ccd_ee(q, v, h, e, f)));
        hits
    }

    /// CCD of vertex `p` against triangle `t` (a hit with the normal oriented from the triangle
    /// toward the vertex's starting side).
    fn ccd_vt(&self, q: &[Pt3], v: &[Vec3], h: f64, p: u32, t: u32) -> Option<(PairKey, Stencil)> {
        let tri = self.tris[t as usize];
        if self.skip_rigid([p, tri[0], tri[1], tri[2]], (0, p, t)) {
            return None;
        }
        let dv = |i: u32| h * v[i as usize];
        let x = tri.map(|i| q[i as usize]);
        let d = tri.map(dv);
        let (tc, w) = ccd::vertex_triangle(&q[p as usize], &dv(p), &x, &d, self.delta_ccd)?;
        let xt: [Pt3; 3] = std::array::from_fn(|k| x[k] + tc * d[k]);
        let mut nrm = safe_normal(&(xt[1] - xt[0]), &(xt[2] - xt[0]));
        // Orient from the triangle toward the vertex's starting side.
        let (c0, _) = closest_point_triangle(&q[p as usize], &x);
        let side = (q[p as usize] - c0).dot(&nrm);
        let rel = dv(p) - (w[0] * d[0] + w[1] * d[1] + w[2] * d[2]);
        if side < 0.0 || (side == 0.0 && rel.dot(&nrm) > 0.0) {
            nrm = -nrm;
        }
        Some(((0, p, t), Stencil { v: [p, tri[0], tri[1], tri[2]], c: [1.0, -w[0], -w[1], -w[2]], n: nrm }))
    }

    /// CCD of edges `e` and `f` (normal from the second edge toward the first at the start).
    fn ccd_ee(&self, q: &[Pt3], v: &[Vec3], h: f64, e: u32, f: u32) -> Option<(PairKey, Stencil)> {
        let (a, b) = (self.edges[e as usize], self.edges[f as usize]);
        if self.skip_rigid([a[0], a[1], b[0], b[1]], (1, e, f)) {
            return None;
        }
        let dv = |i: u32| h * v[i as usize];
        let xa = [q[a[0] as usize], q[a[1] as usize]];
        let xb = [q[b[0] as usize], q[b[1] as usize]];
        let da = [dv(a[0]), dv(a[1])];
        let db = [dv(b[0]), dv(b[1])];
        let (tc, s, u) = ccd::edge_edge(&xa, &da, &xb, &db, self.delta_ccd)?;
        let ya: [Pt3; 2] = std::array::from_fn(|k| xa[k] + tc * da[k]);
        let yb: [Pt3; 2] = std::array::from_fn(|k| xb[k] + tc * db[k]);
        let mut nrm = safe_normal(&(ya[1] - ya[0]), &(yb[1] - yb[0]));
        let (_, _, p0, q0) = closest_points_segments(&xa[0], &xa[1], &xb[0], &xb[1]);
        let side = (p0 - q0).dot(&nrm);
        let rel = (1.0 - s) * da[0] + s * da[1] - (1.0 - u) * db[0] - u * db[1];
        if side < 0.0 || (side == 0.0 && rel.dot(&nrm) > 0.0) {
            nrm = -nrm;
        }
        Some(((1, e, f), Stencil { v: [a[0], a[1], b[0], b[1]], c: [1.0 - s, s, -(1.0 - u), -u], n: nrm }))
    }

    /// Step 4: rigid impact zones, then freezing as the failsafe.
    fn impact_zones(
        &mut self,
        q: &[Pt3],
        v: &mut [Vec3],
        h: f64,
        im: &[f64],
        mut hits: Vec<Stencil>,
        st: &mut StepStats,
    ) {
        let n = q.len();
        let mut uf = UnionFind::new(n);
        let mut in_zone = vec![false; n];
        for _ in 0..self.settings.impact_zone_iters.max(1) {
            // Only the vertices that take part in the contact (weight ≠ 0) join the zone: a
            // vertex–triangle hit at an edge or corner of the triangle does not drag the
            // triangle's third vertex (and everything it is connected to) into the zone.
            let mut touched = Vec::new();
            for s in &hits {
                let mut first = None;
                for k in 0..4 {
                    if s.c[k] == 0.0 {
                        continue;
                    }
                    in_zone[s.v[k] as usize] = true;
                    touched.push(s.v[k]);
                    match first {
                        None => first = Some(s.v[k]),
                        Some(f) => {
                            uf.union(f, s.v[k]);
                        }
                    }
                }
            }
            // Zones no hit touched in this iteration already move rigidly: recomputing their
            // rigid motion would only change the last bits of their velocities (and make the
            // incremental CCD re-test all their pairs), so only touched zones are rigidified.
            let mut dirty = vec![false; n];
            for &x in &touched {
                dirty[uf.find(x) as usize] = true;
            }
            self.rigidify(q, v, im, &mut uf, &in_zone, &dirty, st);
            self.snap("zones", v);
            hits = self.ccd_hits(q, v, h);
            if hits.is_empty() {
                return;
            }
        }
        // Failsafe: freeze offending free vertices at q (v = 0) until nothing collides. Frozen
        // vertices break the zones' rigid motion, so every pair is tested in full again.
        self.rigid_zone.iter_mut().for_each(|z| *z = geom_core::NONE);
        self.superset = None;
        let mut frozen = vec![false; n];
        loop {
            let mut changed = false;
            for s in &hits {
                for &x in &s.v {
                    let x = x as usize;
                    if im[x] > 0.0 && !frozen[x] {
                        frozen[x] = true;
                        v[x] = Vec3::zeros();
                        changed = true;
                    }
                }
            }
            // Also freeze whole zones that contain a frozen vertex.
            if !changed {
                break;
            }
            hits = self.ccd_hits(q, v, h);
            if hits.is_empty() {
                break;
            }
        }
        st.n_frozen += frozen.iter().filter(|&&f| f).count() as u32;
        self.snap("freeze", v);
    }

    /// Sets the velocities of every zone whose root is `dirty` to its rigid motion (constrained
    /// vertices impose theirs).
    #[allow(clippy::too_many_arguments)]
    fn rigidify(
        &mut self,
        q: &[Pt3],
        v: &mut [Vec3],
        im: &[f64],
        uf: &mut UnionFind,
        in_zone: &[bool],
        dirty: &[bool],
        st: &mut StepStats,
    ) {
        let n = q.len();
        let mut members: std::collections::BTreeMap<u32, Vec<usize>> = std::collections::BTreeMap::new();
        for i in 0..n {
            if in_zone[i] {
                members.entry(uf.find(i as u32)).or_default().push(i);
            }
        }
        st.n_impact_zones = st.n_impact_zones.max(members.len() as u32);
        for (&root, zone) in &members {
            st.max_zone_size = st.max_zone_size.max(zone.len() as u32);
            if !dirty[root as usize] {
                continue;
            }
            // Marked rigid again below only when the zone gets an exact rigid motion; a zone
            // that had rigid vertices and does not invalidates the pruned superset.
            let was_rigid = zone.iter().any(|&i| self.rigid_zone[i] != geom_core::NONE);
            for &i in zone {
                self.rigid_zone[i] = geom_core::NONE;
            }
            let constrained: Vec<usize> = zone.iter().copied().filter(|&i| im[i] == 0.0).collect();
            if !constrained.is_empty() {
                // Move with the prescribed velocity (mean if they disagree).
                let vm: Vec3 = constrained.iter().map(|&i| v[i]).sum::<Vec3>() / constrained.len() as f64;
                for &i in zone {
                    if im[i] > 0.0 {
                        v[i] = vm;
                    }
                }
                if was_rigid {
                    self.superset = None;
                }
                continue;
            }
            let m: f64 = zone.iter().map(|&i| self.mass[i]).sum();
            if !(m > 0.0) {
                if was_rigid {
                    self.superset = None;
                }
                continue;
            }
            let xc: Vec3 = zone.iter().map(|&i| self.mass[i] * q[i].coords).sum::<Vec3>() / m;
            let vc: Vec3 = zone.iter().map(|&i| self.mass[i] * v[i]).sum::<Vec3>() / m;
            let mut l = Vec3::zeros();
            let mut inertia = Mat3::zeros();
            for &i in zone {
                let r = q[i].coords - xc;
                l += self.mass[i] * r.cross(&(v[i] - vc));
                inertia += self.mass[i] * (r.norm_squared() * Mat3::identity() - r * r.transpose());
            }
            let omega = pinv3(&inertia) * l;
            for &i in zone {
                v[i] = vc + omega.cross(&(q[i].coords - xc));
                self.rigid_zone[i] = root;
            }
            self.zone_gen += 1;
        }
    }
}

/// Below this many pairs a narrow phase runs on the calling thread: a few thousand
/// closest-point or cubic tests take well under a millisecond, less than a fork-join costs on a
/// loaded machine.
const PAR_MIN_PAIRS: usize = 8192;

/// `filter_map` over `items`, in parallel for long lists; the output keeps the input order
/// either way (deterministic).
fn par_filter_map<T: Sync, R: Send>(items: &[T], f: impl Fn(&T) -> Option<R> + Sync + Send) -> Vec<R> {
    if items.len() < PAR_MIN_PAIRS {
        items.iter().filter_map(f).collect()
    } else {
        items.par_iter().filter_map(f).collect()
    }
}

/// Closed-box overlap, as `Aabb::overlaps` (touching counts), inlined for the candidate
/// filters that run over every superset pair.
#[inline(always)]
fn overlap(a: &Aabb, b: &Aabb) -> bool {
    a.min.x <= b.max.x
        && b.min.x <= a.max.x
        && a.min.y <= b.max.y
        && b.min.y <= a.max.y
        && a.min.z <= b.max.z
        && b.min.z <= a.max.z
}

/// Pseudo-inverse of a symmetric PSD 3×3 matrix (eigenvalues below 1e-12·max dropped).
fn pinv3(m: &Mat3) -> Mat3 {
    let e = nalgebra::SymmetricEigen::new(*m);
    let mx = e.eigenvalues.amax();
    let mut out = Mat3::zeros();
    for k in 0..3 {
        let l = e.eigenvalues[k];
        if l > 1e-12 * mx && l > 0.0 {
            let c = e.eigenvectors.column(k);
            out += c * c.transpose() / l;
        }
    }
    out
}

/// Applies a batch of requests together (Jacobi): each pair's impulse scaled by 1/(largest
/// number of requests touching any of its vertices).
fn apply(reqs: &[Request], v: &mut [Vec3], im: &[f64], n: usize) {
    if reqs.is_empty() {
        return;
    }
    let mut count = vec![0u32; n];
    for r in reqs {
        for k in 0..4 {
            if r.s.c[k] != 0.0 {
                count[r.s.v[k] as usize] += 1;
            }
        }
    }
    let mut dv = vec![Vec3::zeros(); n];
    for r in reqs {
        let den = r.s.denom(im);
        if !(den > 0.0) {
            continue;
        }
        let scale = 1.0
            / (0..4).filter(|&k| r.s.c[k] != 0.0).map(|k| count[r.s.v[k] as usize]).max().unwrap_or(1).max(1) as f64;
        let mut imp = (r.dn / den) * r.s.n;
        if r.mu > 0.0 {
            let rel = r.s.rel(v);
            let vt = rel - rel.dot(&r.s.n) * r.s.n;
            let tl = vt.norm();
            if tl > 0.0 {
                imp -= ((r.mu * r.dn).min(tl) / den) * (vt / tl);
            }
        }
        for k in 0..4 {
            let i = r.s.v[k] as usize;
            dv[i] += scale * r.s.c[k] * im[i] * imp;
        }
    }
    for (vi, d) in v.iter_mut().zip(&dv) {
        *vi += d;
    }
}

/// Number of intersecting pairs of non-adjacent triangles (shared vertex ⇒ adjacent), for the
/// `max_intersections` figure: geom-core's AABB-tree broad phase and exact triangle–triangle
/// predicates ([`geom_core::query::count_self_intersections`]; touching counts).
pub fn count_self_intersections(q: &[Pt3], tris: &[[u32; 3]]) -> usize {
    geom_core::query::count_self_intersections(tris, q)
}

/// Exact triangle–triangle intersection test (touching counts), from geom-core.
pub use geom_core::query::tri_tri_intersect;

#[cfg(test)]
mod tests {
    use super::*;

    /// Triangles of an n × n vertex grid (row-major vertices, two triangles per cell).
    fn grid_triangles(n: usize) -> Vec<[u32; 3]> {
        let mut f = Vec::new();
        for j in 0..n - 1 {
            for i in 0..n - 1 {
                let a = (j * n + i) as u32;
                f.push([a, a + 1, a + n as u32 + 1]);
                f.push([a, a + n as u32 + 1, a + n as u32]);
            }
        }
        f
    }

    /// The incremental CCD of later calls in one filter call equals a full recomputation (same
    /// stencils bit for bit, same order), on a crumpled, self-overlapping random sheet whose
    /// velocities change on a few vertices between calls, as CCD passes and impact zones do.
    #[test]
    fn incremental_ccd_equals_full() {
        use crate::material::Material;
        let n = 12;
        let mut rng = geom_core::rng::Rng::new(3);
        // An n × n grid folded onto itself (z = sin), so many pairs are close.
        let mut p = Vec::new();
        for j in 0..n {
            for i in 0..n {
                let (x, y) = (i as f64 / (n - 1) as f64, j as f64 / (n - 1) as f64);
                p.push(Pt3::new(x, 0.3 * (6.0 * y).sin(), 0.05 * (y * 9.0).cos() + 0.01 * rng.range(-1.0, 1.0)));
            }
        }
        let f = grid_triangles(n);
        let mesh = ShellMesh::new(p.clone(), &f, None, &Material::cotton()).expect("valid grid");
        let effects = Effects { self_collision: true, ..Effects::default() };
        let cs = CollisionSettings::default();
        let mut inc = Collider::new(&mesh, &effects, &cs, 1.0);
        let mut full = Collider::new(&mesh, &effects, &cs, 1.0);
        let mut v: Vec<Vec3> =
            (0..p.len()).map(|_| Vec3::new(rng.range(-1.0, 1.0), rng.range(-1.0, 1.0), rng.range(-3.0, 3.0))).collect();
        let h = 0.05;
        let mut total = 0;
        for call in 0..6 {
            let a = inc.ccd_hits(&p, &v, h);
            full.reset_call_state(p.len());
            let b = full.ccd_hits(&p, &v, h);
            let c = brute_force_ccd(&full, &p, &v, h);
            assert_eq!(a.len(), b.len(), "call {call}");
            assert_eq!(a.len(), c.len(), "call {call}: brute force");
            for ((x, y), z) in a.iter().zip(&b).zip(&c) {
                assert!(x.v == y.v && x.c == y.c && x.n == y.n, "call {call}: hit lists differ");
                assert!(x.v == z.v && x.c == z.c && x.n == z.n, "call {call}: differs from brute force");
            }
            total += a.len();
            // Change half of the velocities once (the bulk path), else a few (the query path).
            if call == 2 {
                for k in (0..p.len()).step_by(2) {
                    v[k] *= 0.5;
                }
            }
            for _ in 0..5 {
                let k = (rng.range(0.0, 1.0) * p.len() as f64) as usize % p.len();
                v[k] = if call % 2 == 0 { Vec3::zeros() } else { Vec3::new(0.0, 0.0, rng.range(-5.0, 5.0)) };
            }
        }
        assert!(total > 20, "the test must see hits: {total}");
    }

    /// Every non-adjacent vertex–triangle and edge–edge pair through the narrow phase, no broad
    /// phase: the reference for the candidate superset, the moving frame and the tree queries.
    fn brute_force_ccd(c: &Collider, q: &[Pt3], v: &[Vec3], h: f64) -> Vec<Stencil> {
        let mut hits = Vec::new();
        for p in 0..q.len() as u32 {
            for (t, tri) in c.tris.iter().enumerate() {
                if !tri.contains(&p) {
                    hits.extend(c.ccd_vt(q, v, h, p, t as u32));
                }
            }
        }
        for (e, a) in c.edges.iter().enumerate() {
            for (f, b) in c.edges.iter().enumerate().skip(e + 1) {
                if !b.contains(&a[0]) && !b.contains(&a[1]) {
                    hits.extend(c.ccd_ee(q, v, h, e as u32, f as u32));
                }
            }
        }
        hits.into_iter().map(|(_, s)| s).collect()
    }

    /// The premise of `skip_rigid`: a sheet folded onto itself (two layers 2 cm apart) whose
    /// velocities are one rigid motion v = v_c + ω × (q − x_c) has no CCD hit at all (fast
    /// spins: the linearised rotation stretches it by up to 1 + t²h²|ω|² over the step), tested
    /// with every pair and no zone marks; pushing the upper layer through the lower one does
    /// collide (control).
    #[test]
    fn rigid_motion_has_no_hits() {
        use crate::material::Material;
        let n = 10;
        let d = 0.5 / (n / 2) as f64;
        let mut p = Vec::new();
        for j in 0..n {
            for i in 0..n {
                let x = i as f64 / (n - 1) as f64;
                let (y, z) = if j < n / 2 { (0.0, j as f64 * d) } else { (0.02, (n - 1 - j) as f64 * d) };
                p.push(Pt3::new(x, y, z));
            }
        }
        let f = grid_triangles(n);
        let mesh = ShellMesh::new(p.clone(), &f, None, &Material::cotton()).expect("valid folded grid");
        let effects = Effects { self_collision: true, ..Effects::default() };
        let c = Collider::new(&mesh, &effects, &CollisionSettings::default(), 1.0);
        let (xc, h) = (Vec3::new(0.5, 0.01, 0.2), 0.01);
        for (vc, w) in
            [(Vec3::new(1.0, -2.0, 0.5), Vec3::new(3.0, 40.0, -7.0)), (Vec3::zeros(), Vec3::new(0.0, 0.0, 90.0))]
        {
            let v: Vec<Vec3> = p.iter().map(|x| vc + w.cross(&(x.coords - xc))).collect();
            assert!(brute_force_ccd(&c, &p, &v, h).is_empty(), "rigid motion {w:?} collided");
        }
        let v: Vec<Vec3> =
            (0..p.len()).map(|k| if k >= n * n / 2 { Vec3::new(0.0, -5.0, 0.0) } else { Vec3::zeros() }).collect();
        assert!(!brute_force_ccd(&c, &p, &v, h).is_empty(), "the control must collide");
    }

    /// Two crossing triangles count once; sharing a vertex makes them adjacent (not counted).
    #[test]
    fn counts_crossing_pairs() {
        let q = vec![
            Pt3::new(0.0, 0.0, 0.0),
            Pt3::new(1.0, 0.0, 0.0),
            Pt3::new(0.0, 1.0, 0.0),
            Pt3::new(0.2, 0.2, -1.0),
            Pt3::new(0.2, 0.2, 1.0),
            Pt3::new(0.3, 0.5, 0.0),
        ];
        assert_eq!(count_self_intersections(&q, &[[0, 1, 2], [3, 4, 5]]), 1);
        assert_eq!(count_self_intersections(&q, &[[0, 1, 2], [0, 4, 5]]), 0);
        let far: Vec<Pt3> =
            q.iter().enumerate().map(|(i, p)| if i >= 3 { p + Vec3::new(5.0, 0.0, 0.0) } else { *p }).collect();
        assert_eq!(count_self_intersections(&far, &[[0, 1, 2], [3, 4, 5]]), 0);
    }

    /// Equal-and-opposite impulses: Jacobi application conserves momentum.
    #[test]
    fn impulses_conserve_momentum() {
        let mut v = vec![Vec3::new(0.0, 0.0, -1.0), Vec3::zeros(), Vec3::zeros(), Vec3::new(0.0, 0.0, 0.5), Vec3::x()];
        let m = [1.0, 2.0, 0.5, 1.5, 1.0];
        let im: Vec<f64> = m.iter().map(|x| 1.0 / x).collect();
        let p0: Vec3 = v.iter().zip(&m).map(|(a, b)| *b * a).sum();
        let reqs = vec![
            Request { s: Stencil { v: [0, 1, 2, 3], c: [1.0, -0.2, -0.3, -0.5], n: Vec3::z() }, dn: 1.3, mu: 0.3 },
            Request { s: Stencil { v: [4, 1, 0, 3], c: [0.4, 0.6, -0.5, -0.5], n: Vec3::y() }, dn: 0.7, mu: 0.5 },
        ];
        apply(&reqs, &mut v, &im, 5);
        let p1: Vec3 = v.iter().zip(&m).map(|(a, b)| *b * a).sum();
        assert!((p1 - p0).norm() < 1e-14);
    }
}

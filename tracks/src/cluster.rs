//! Animation-aware variational shape approximation (spec §3.3c, seed §4.1): Lloyd / VSA region
//! growing over the guide's triangles with a proxy per region and per sampled frame, distortion
//! E(T_j, P_k) = max_f A_j^f (μ‖x_j^f − x_k^f‖²/A^f + (1−μ)‖n_j^f − n_k^f‖²), and the static
//! L²,¹ VSA metric (rest pose, normals only) as the Fig. 7 comparison.

use std::cmp::Reverse;
use std::collections::BinaryHeap;
use std::time::Instant;

use geom_core::math::{Pt3, Vec3};
use geom_core::mesh::TriMesh;
use geom_core::rng::Rng;
use geom_core::NONE;
use rayon::prelude::*;

use crate::error::{Result, TrackError};
use crate::guide::GuideAnimation;

/// Seed placement.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Deserialize, serde::Serialize)]
pub enum ClusterInit {
    /// Seed triangles drawn at random (the seed paper's choice).
    #[default]
    Random,
    /// Farthest-point sampling on rest centroids.
    FarthestPoint,
}

/// Distortion metric.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Deserialize, serde::Serialize)]
pub enum ClusterMetric {
    /// Sup over sampled frames of the position + normal term (seed §4.1).
    #[default]
    AnimationAware,
    /// Original VSA normal metric A_j‖n_j − n_k‖² on the rest pose only.
    StaticVsaL21,
}

/// Clustering options (spec §4 defaults: 200 regions, μ = 0.98, 32 frames, seed 1, 64 iterations).
#[derive(Clone, Debug, PartialEq, serde::Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields)]
pub struct ClusterOptions {
    /// Number of regions r (≥ 1).
    pub regions: usize,
    /// Compactness weight μ ∈ [0, 1] (→1 compact, →0 flat).
    pub mu: f64,
    /// Sampled frames F (≥ 1; frame 0 always included).
    pub frames: usize,
    /// Seed of the frame sampling and of random seeds.
    pub seed: u64,
    /// Lloyd iteration cap.
    pub max_iters: usize,
    /// Seed placement.
    pub init: ClusterInit,
    /// Metric.
    pub metric: ClusterMetric,
}

impl Default for ClusterOptions {
    fn default() -> Self {
        Self {
            regions: 200,
            mu: 0.98,
            frames: 32,
            seed: 1,
            max_iters: 64,
            init: ClusterInit::Random,
            metric: ClusterMetric::AnimationAware,
        }
    }
}

/// Result of [`cluster`].
#[derive(Clone, Debug, PartialEq)]
pub struct Clustering {
    /// Region of every triangle (`NONE` outside the clustered subset).
    pub tri_labels: Vec<u32>,
    /// Region of every vertex after the majority-area rule (`NONE` for vertices of no clustered
    /// triangle); regions renumbered after merges.
    pub vertex_labels: Vec<u32>,
    /// Number of triangle regions.
    pub regions_tri: usize,
    /// Number of vertex test functions K (≤ regions_tri: regions without a vertex are merged).
    pub regions: usize,
    /// Lloyd iterations performed.
    pub iterations: usize,
    /// Final total distortion Σ_j E(T_j, P_label(j)).
    pub distortion: f64,
    /// Total distortion after the first iteration.
    pub first_distortion: f64,
    /// Mean of the position and normal terms over triangles (final), to rebalance μ (§12.4).
    pub mean_terms: (f64, f64),
    /// Wall time (s).
    pub time_s: f64,
}

/// Per-frame triangle data.
struct FrameData {
    c: Vec<Pt3>,
    n: Vec<Vec3>,
    a: Vec<f64>,
    total: f64,
}

fn frame_data(m: &TriMesh, p: &[Pt3]) -> FrameData {
    let (c, (n, a)): (Vec<Pt3>, (Vec<Vec3>, Vec<f64>)) = m
        .faces
        .par_iter()
        .map(|f| {
            let [x0, x1, x2] = f.map(|v| p[v as usize]);
            let cr = (x1 - x0).cross(&(x2 - x0));
            let len = cr.norm();
            let n = if len > 0.0 { cr / len } else { Vec3::zeros() };
            (Pt3::from((x0.coords + x1.coords + x2.coords) / 3.0), (n, 0.5 * len))
        })
        .unzip();
    let total = a.iter().sum();
    FrameData { c, n, a, total }
}

/// Sampled frame times: F distinct frame times (guide fps; 30 fps for procedural guides), frame 0
/// always included, chosen by a seeded partial shuffle.
pub fn sample_frame_times(guide: &GuideAnimation, f: usize, seed: u64) -> Vec<f64> {
    let fps = guide.fps;
    let nf = (guide.duration() * fps + 1e-9).floor() as usize + 1;
    let mut idx: Vec<usize> = (0..nf).collect();
    let mut rng = Rng::new(seed);
    let take = f.clamp(1, nf);
    for i in 1..take {
        let j = i + rng.below(nf - i);
        idx.swap(i, j);
    }
    let mut chosen: Vec<usize> = idx[..take].to_vec();
    chosen.sort_unstable();
    chosen.iter().map(|&i| i as f64 / fps).collect()
}

/// Clusters the guide's triangles (all, or `subset`) into `opts.regions` edge-connected regions.
///
/// Errors: `regions` = 0 or larger than the number of triangles, μ outside [0, 1], F = 0.
pub fn cluster(guide: &GuideAnimation, opts: &ClusterOptions, subset: Option<&[u32]>) -> Result<Clustering> {
    let t0 = Instant::now();
    let m = &guide.rest;
    let nt = m.n_faces();
    let tris: Vec<u32> = subset.map_or_else(|| (0..nt as u32).collect(), <[u32]>::to_vec);
    if opts.regions == 0 || opts.regions > tris.len() {
        return Err(TrackError::BadParameter(format!(
            "cluster regions = {} must be in 1..={} (triangles)",
            opts.regions,
            tris.len()
        )));
    }
    if !(0.0..=1.0).contains(&opts.mu) || opts.frames == 0 || opts.max_iters == 0 {
        return Err(TrackError::BadParameter(format!(
            "cluster options: mu = {} in [0,1], frames = {} ≥ 1, max_iters = {} ≥ 1",
            opts.mu, opts.frames, opts.max_iters
        )));
    }
    // Frames: per-triangle centroid, normal, area.
    let (frames, mu): (Vec<FrameData>, f64) = match opts.metric {
        ClusterMetric::AnimationAware => {
            let times = sample_frame_times(guide, opts.frames, opts.seed);
            let mut buf = vec![Pt3::origin(); m.n_vertices()];
            let fd = times
                .iter()
                .map(|&t| {
                    guide.sample(t, &mut buf);
                    frame_data(m, &buf)
                })
                .collect();
            (fd, opts.mu)
        }
        ClusterMetric::StaticVsaL21 => (vec![frame_data(m, &m.positions)], 0.0),
    };
    let nfr = frames.len();
    let in_set = {
        let mut s = vec![false; nt];
        tris.iter().for_each(|&f| s[f as usize] = true);
        s
    };
    let topo = m.topology();
    let neighbours = |f: u32| topo.face_neighbors(geom_core::mesh::FaceId(f));
    // Distortion of triangle j to proxy (per frame centroid and normal).
    let dist = |j: usize, px: &[Pt3], pn: &[Vec3]| -> f64 {
        let mut e = 0.0f64;
        for (f, fd) in frames.iter().enumerate() {
            let v = fd.a[j]
                * (mu * (fd.c[j] - px[f]).norm_squared() / fd.total + (1.0 - mu) * (fd.n[j] - pn[f]).norm_squared());
            e = e.max(v);
        }
        e
    };
    // Initial seeds: one per connected component of the subset, then random / farthest point.
    let mut rng = Rng::new(opts.seed ^ 0x9e37_79b9_7f4a_7c15);
    let mut comp = vec![NONE; nt];
    let mut comps: Vec<Vec<u32>> = Vec::new();
    for &s in &tris {
        if comp[s as usize] != NONE {
            continue;
        }
        let id = comps.len() as u32;
        let mut stack = vec![s];
        comp[s as usize] = id;
        let mut members = Vec::new();
        while let Some(f) = stack.pop() {
            members.push(f);
            for g in neighbours(f) {
                if g != NONE && in_set[g as usize] && comp[g as usize] == NONE {
                    comp[g as usize] = id;
                    stack.push(g);
                }
            }
        }
        members.sort_unstable();
        comps.push(members);
    }
    let r = opts.regions.max(comps.len());
    let mut seeds: Vec<u32> = comps.iter().map(|c| c[rng.below(c.len())]).collect();
    let mut is_seed = vec![false; nt];
    seeds.iter().for_each(|&s| is_seed[s as usize] = true);
    let rest_c = &frames[0].c;
    let mut dmin: Vec<f64> = vec![f64::INFINITY; nt];
    while seeds.len() < r {
        let s = match opts.init {
            ClusterInit::Random => {
                let c = tris[rng.below(tris.len())];
                if is_seed[c as usize] {
                    continue;
                }
                c
            }
            ClusterInit::FarthestPoint => {
                for &f in &tris {
                    let d = (rest_c[f as usize] - rest_c[*seeds.last().expect("≥ 1 seed") as usize]).norm_squared();
                    dmin[f as usize] = dmin[f as usize].min(d);
                }
                *tris
                    .iter()
                    .filter(|&&f| !is_seed[f as usize])
                    .max_by(|&&a, &&b| dmin[a as usize].total_cmp(&dmin[b as usize]).then(b.cmp(&a)))
                    .expect("fewer seeds than triangles")
            }
        };
        is_seed[s as usize] = true;
        seeds.push(s);
    }
    // Proxies: per region, per frame (centroid, normal).
    let mut px: Vec<Vec<Pt3>> = seeds.iter().map(|&s| frames.iter().map(|fd| fd.c[s as usize]).collect()).collect();
    let mut pn: Vec<Vec<Vec3>> = seeds.iter().map(|&s| frames.iter().map(|fd| fd.n[s as usize]).collect()).collect();
    let mut labels = vec![NONE; nt];
    let mut prev_labels: Vec<u32>;
    let mut iterations = 0;
    let mut distortion = f64::INFINITY;
    let mut first_distortion = f64::NAN;
    let mut e_tri = vec![0.0; nt];
    loop {
        iterations += 1;
        prev_labels = std::mem::replace(&mut labels, vec![NONE; nt]);
        // 1. Grow regions from the seeds.
        let mut heap: BinaryHeap<Reverse<(Ord64, u32, u32)>> = BinaryHeap::new();
        for (k, &s) in seeds.iter().enumerate() {
            labels[s as usize] = k as u32;
            for g in neighbours(s) {
                if g != NONE && in_set[g as usize] && labels[g as usize] == NONE {
                    heap.push(Reverse((Ord64(dist(g as usize, &px[k], &pn[k])), g, k as u32)));
                }
            }
        }
        while let Some(Reverse((_, f, k))) = heap.pop() {
            if labels[f as usize] != NONE {
                continue;
            }
            labels[f as usize] = k;
            for g in neighbours(f) {
                if g != NONE && in_set[g as usize] && labels[g as usize] == NONE {
                    heap.push(Reverse((Ord64(dist(g as usize, &px[k as usize], &pn[k as usize])), g, k)));
                }
            }
        }
        // 2. Fit proxies.
        for k in 0..r {
            for f in 0..nfr {
                px[k][f] = Pt3::origin();
            }
        }
        let mut wsum = vec![vec![0.0; nfr]; r];
        let mut nsum = vec![vec![Vec3::zeros(); nfr]; r];
        let mut csum = vec![vec![Vec3::zeros(); nfr]; r];
        for &f in &tris {
            let k = labels[f as usize] as usize;
            for (fi, fd) in frames.iter().enumerate() {
                let a = fd.a[f as usize];
                wsum[k][fi] += a;
                csum[k][fi] += a * fd.c[f as usize].coords;
                nsum[k][fi] += a * fd.n[f as usize];
            }
        }
        for k in 0..r {
            for fi in 0..nfr {
                if wsum[k][fi] > 0.0 {
                    px[k][fi] = Pt3::from(csum[k][fi] / wsum[k][fi]);
                }
                let l = nsum[k][fi].norm();
                if l >= 1e-12 {
                    pn[k][fi] = nsum[k][fi] / l;
                }
            }
        }
        // Distortion and next seeds (smallest E in each region).
        let mut best = vec![(f64::INFINITY, NONE); r];
        let mut total = 0.0;
        for &f in &tris {
            let k = labels[f as usize] as usize;
            let e = dist(f as usize, &px[k], &pn[k]);
            e_tri[f as usize] = e;
            total += e;
            if e < best[k].0 || (e == best[k].0 && f < best[k].1) {
                best[k] = (e, f);
            }
        }
        if iterations == 1 {
            first_distortion = total;
        }
        let converged = labels == prev_labels || (distortion - total).abs() <= 1e-6 * total.abs();
        distortion = total;
        if converged || iterations >= opts.max_iters {
            break;
        }
        for (k, b) in best.iter().enumerate() {
            if b.1 != NONE {
                seeds[k] = b.1;
            }
        }
    }
    // Mean magnitude of both terms (frame 0), for the clustering report (§12.4).
    let mut terms = (0.0, 0.0);
    let fd = &frames[0];
    for &f in &tris {
        let k = labels[f as usize] as usize;
        let j = f as usize;
        terms.0 += fd.a[j] * mu * (fd.c[j] - px[k][0]).norm_squared() / fd.total;
        terms.1 += fd.a[j] * (1.0 - mu) * (fd.n[j] - pn[k][0]).norm_squared();
    }
    let nts = tris.len() as f64;
    let (vertex_labels, regions) = vertex_labels_from_triangles(m, &labels, r);
    Ok(Clustering {
        tri_labels: labels,
        vertex_labels,
        regions_tri: r,
        regions,
        iterations,
        distortion,
        first_distortion,
        mean_terms: (terms.0 / nts, terms.1 / nts),
        time_s: t0.elapsed().as_secs_f64(),
    })
}

/// Total order on f64 for the heap (distortions are finite and ≥ 0).
#[derive(Clone, Copy, Debug, PartialEq)]
struct Ord64(f64);
impl Eq for Ord64 {}
impl PartialOrd for Ord64 {
    fn partial_cmp(&self, o: &Self) -> Option<std::cmp::Ordering> {
        Some(self.cmp(o))
    }
}
impl Ord for Ord64 {
    fn cmp(&self, o: &Self) -> std::cmp::Ordering {
        self.0.total_cmp(&o.0)
    }
}

/// Vertex test functions from triangle labels (spec §3.3c, reconstructed): each vertex goes to the
/// region with the largest total rest area among its incident labelled triangles (ties → lower
/// index). A region left without a vertex takes the vertex of its triangles with the largest area
/// share for it from an owner that keeps ≥ 1 vertex; if none exists it is merged away. Returns
/// the labels (renumbered densely) and K.
pub fn vertex_labels_from_triangles(m: &TriMesh, tri_labels: &[u32], k: usize) -> (Vec<u32>, usize) {
    let n = m.n_vertices();
    let areas = geom_core::mesh::face_areas(&m.faces, &m.positions);
    let vf = m.topology().vertex_faces();
    let share = |v: usize, region: u32| -> f64 {
        vf.row(v).iter().filter(|&&f| tri_labels[f as usize] == region).map(|&f| areas[f as usize]).sum()
    };
    let mut labels = vec![NONE; n];
    for (v, lab) in labels.iter_mut().enumerate() {
        let mut best = (0.0f64, NONE);
        for &f in vf.row(v) {
            let l = tri_labels[f as usize];
            if l == NONE {
                continue;
            }
            let a = share(v, l);
            if best.1 == NONE || a > best.0 || (a == best.0 && l < best.1) {
                best = (a, l);
            }
        }
        *lab = best.1;
    }
    let mut count = vec![0usize; k];
    labels.iter().filter(|&&l| l != NONE).for_each(|&l| count[l as usize] += 1);
    for region in 0..k as u32 {
        if count[region as usize] > 0 {
            continue;
        }
        let mut cand: Option<(f64, usize)> = None;
        for (f, &l) in tri_labels.iter().enumerate() {
            if l != region {
                continue;
            }
            for &v in &m.faces[f] {
                let v = v as usize;
                let owner = labels[v];
                if owner != NONE && count[owner as usize] <= 1 {
                    continue;
                }
                let a = share(v, region);
                if cand.is_none_or(|(b, bv)| a > b || (a == b && v < bv)) {
                    cand = Some((a, v));
                }
            }
        }
        if let Some((_, v)) = cand {
            if labels[v] != NONE {
                count[labels[v] as usize] -= 1;
            }
            labels[v] = region;
            count[region as usize] += 1;
        }
    }
    // Renumber densely (regions still empty are merged away).
    let mut map = vec![NONE; k];
    let mut next = 0u32;
    for (r, c) in count.iter().enumerate() {
        if *c > 0 {
            map[r] = next;
            next += 1;
        }
    }
    for l in labels.iter_mut().filter(|l| **l != NONE) {
        *l = map[*l as usize];
    }
    (labels, next as usize)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::guide::TimeInterp;
    use crate::testfn::{build_test_functions, TestFunctionSpec};
    use geom_core::mesh::subdivide_linear;
    use geom_core::procedural::{grid, GridSpec};

    /// A sheet bending progressively over 20 frames.
    fn bending_sheet() -> GuideAnimation {
        let m = grid(&GridSpec { quads: [16, 8], size: [2.0, 1.0], ..GridSpec::default() }).expect("grid");
        let frames = (0..20)
            .map(|k| {
                let a = k as f64 / 19.0;
                m.positions.iter().map(|p| Pt3::new(p.x, p.y, a * 0.5 * (3.0 * p.x).sin())).collect()
            })
            .collect();
        GuideAnimation::from_frames(m, frames, 10.0, TimeInterp::CatmullRom).expect("guide")
    }

    /// §7.13: every triangle labelled; each region edge-connected; exactly r non-empty regions;
    /// same seed ⇒ identical labels; final distortion ≤ first-iteration distortion.
    #[test]
    fn cluster_valid() {
        let g = bending_sheet();
        for init in [ClusterInit::Random, ClusterInit::FarthestPoint] {
            let o = ClusterOptions { regions: 12, frames: 8, init, ..ClusterOptions::default() };
            let c = cluster(&g, &o, None).expect("cluster");
            assert!(c.tri_labels.iter().all(|&l| (l as usize) < 12));
            let topo = g.rest.topology();
            for r in 0..12u32 {
                let tris: Vec<u32> = (0..g.rest.n_faces() as u32).filter(|&f| c.tri_labels[f as usize] == r).collect();
                assert!(!tris.is_empty(), "region {r} empty");
                let mut seen = vec![false; g.rest.n_faces()];
                let mut stack = vec![tris[0]];
                seen[tris[0] as usize] = true;
                let mut count = 0;
                while let Some(f) = stack.pop() {
                    count += 1;
                    for nb in topo.face_neighbors(geom_core::mesh::FaceId(f)) {
                        if nb != NONE && !seen[nb as usize] && c.tri_labels[nb as usize] == r {
                            seen[nb as usize] = true;
                            stack.push(nb);
                        }
                    }
                }
                assert_eq!(count, tris.len(), "region {r} not edge-connected");
            }
            assert!(c.distortion <= c.first_distortion * (1.0 + 1e-12));
            let c2 = cluster(&g, &o, None).expect("cluster");
            assert_eq!(c.tri_labels, c2.tri_labels);
            assert_eq!(c.regions, 12);
        }
    }

    /// §7.14: a patch flat in frame 0 and folded in frame 1: the animation-aware metric (F = 2)
    /// sees the fold (larger distortion than with frame 0 only), the static metric does not.
    #[test]
    fn cluster_sup_over_time() {
        let m = grid(&GridSpec { quads: [8, 4], size: [2.0, 1.0], ..GridSpec::default() }).expect("grid");
        let folded: Vec<Pt3> = m.positions.iter().map(|p| Pt3::new(p.x, p.y, 0.8 * p.x.abs())).collect();
        let g = GuideAnimation::from_frames(m.clone(), vec![m.positions.clone(), folded], 1.0, TimeInterp::Linear)
            .expect("guide");
        let one = ClusterOptions { regions: 1, frames: 2, mu: 0.0, max_iters: 1, ..ClusterOptions::default() };
        let both = cluster(&g, &one, None).expect("cluster");
        let st =
            cluster(&g, &ClusterOptions { metric: ClusterMetric::StaticVsaL21, ..one.clone() }, None).expect("cluster");
        assert!(st.distortion < 1e-20, "flat rest pose: static metric zero, got {}", st.distortion);
        assert!(both.distortion > 1e-3, "the fold in frame 1 must count, got {}", both.distortion);
    }

    /// §7.13 (last part): F = 1, μ = 0 gives E = A_j‖n_j − n_k‖² (the static VSA metric) on the
    /// rest pose: identical labels for a static guide.
    #[test]
    fn static_equivalence() {
        let g = bending_sheet();
        let still =
            GuideAnimation::from_frames(g.rest.clone(), vec![g.frames[19].clone()], 10.0, TimeInterp::CatmullRom)
                .expect("guide");
        let mut rest_bent = g.rest.clone();
        rest_bent.positions = g.frames[19].clone();
        let still_bent = GuideAnimation { rest: rest_bent, ..still.clone() };
        let o = ClusterOptions { regions: 6, frames: 1, mu: 0.0, ..ClusterOptions::default() };
        let a = cluster(&still_bent, &o, None).expect("cluster");
        let b =
            cluster(&still_bent, &ClusterOptions { metric: ClusterMetric::StaticVsaL21, ..o }, None).expect("cluster");
        assert_eq!(a.tri_labels, b.tri_labels);
    }

    /// §7.5: Σ_i φ_i = 1 at every tracked vertex for SubdivisionBasis and Clustered.
    #[test]
    fn partition_of_unity() {
        let g = bending_sheet();
        let (fine, p) = subdivide_linear(&g.rest, 2);
        let tf = build_test_functions(&TestFunctionSpec::SubdivisionBasis, &g, &fine, Some(&p)).expect("tf");
        let mut s = vec![0.0; fine.n_vertices()];
        tf.s.tr_mul_vec(&vec![1.0; tf.len()], &mut s);
        assert!(s.iter().all(|x| (x - 1.0).abs() < 1e-14));
        let o = ClusterOptions { regions: 20, frames: 4, ..ClusterOptions::default() };
        let tf = build_test_functions(&TestFunctionSpec::Clustered(o), &g, &g.rest, None).expect("tf");
        let mut s = vec![0.0; g.n_vertices()];
        tf.s.tr_mul_vec(&vec![1.0; tf.len()], &mut s);
        assert!(s.iter().all(|x| (x - 1.0).abs() < 1e-14));
    }
}

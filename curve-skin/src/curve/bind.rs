//! Binding (spec §3.4.5): every skin vertex gets, per bound curve, the curve parameter σ, local
//! Cartesian coordinates `ℓ = F_rest(σ)ᵀ (x − c_rest(σ)) / s_rest(σ)` and a weight.
//!
//! Order: (1) project every vertex onto each curve's rest skeleton polyline (independent of L);
//! (2) per curve, skin distance d = 95th percentile of the candidates' distances; (3) rest L and
//! rest frames; (4) local coordinates and weights. Candidates are the curves whose domain holds
//! the projection foot (not clamped at a domain end, tolerance 1e-6); the weights are
//! `w̃_i = (1/max(d_i, 1e-9))·smoothstep((1 + band − d_i/d_min)/band)` over the distances `d_i` to
//! the rest curve geometry (arcs included), the largest `max_curves_per_vertex` kept, normalised.
//! Addition to the spec: an in-domain curve farther from the point than `(1 + band)` times the
//! nearest skeleton part (domain clamped or not) is not a candidate — otherwise a point beyond a
//! leaf (a fingertip) could bind to a distant curve whose domain happens to contain its foot.
//! A vertex with no candidate (beyond a leaf, or with only zero-length domains) binds rigidly to
//! the nearest clamped curve end and is counted in [`BindStats::clamped`].

use geom_core::anim::skin::SkinSkeleton;
use geom_core::math::{smoothstep, AsPt3, Iso3, Pt3, Vec3};

use super::frame::{CurveFrame, CurveRig, FrameHistory, TwistChoice};
use super::types::{CentreMode, CurveOptions, CurveSkeleton};
use crate::error::{Result, SkinError};

/// Tolerance on σ for "inside the domain".
const DOMAIN_TOL: f64 = 1e-6;

/// Binding statistics.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct BindStats {
    /// Vertices with no candidate curve (bound to a clamped domain end).
    pub clamped: usize,
    /// `histogram[k]` = vertices bound to `k` curves.
    pub histogram: Vec<usize>,
}

/// The binding of a mesh to a curve skeleton (compressed rows, one row per vertex). Stored in
/// `f64` so the exact path reproduces the bind pose to 1e-12; the fast skinner packs an `f32`
/// copy.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct CurveBinding {
    /// Row offsets (`len = vertices + 1`), at most `max_curves_per_vertex` entries per row.
    pub offsets: Vec<u32>,
    /// Curve index per entry.
    pub curve: Vec<u16>,
    /// Curve parameter σ ∈ [0, 1] per entry.
    pub sigma: Vec<f64>,
    /// Local coordinates per entry (m, in the rest frame at σ, divided by the rest volume scale).
    pub local: Vec<[f64; 3]>,
    /// Local rest normal per entry (present when normals were given).
    pub normal_local: Option<Vec<[f64; 3]>>,
    /// Weight per entry (rows sum to 1).
    pub w: Vec<f64>,
    /// Skin distance d per curve used by the floating rule (m).
    pub skin_dist: Vec<f64>,
    /// Statistics.
    pub stats: BindStats,
}

impl CurveBinding {
    /// Number of vertices.
    pub fn len(&self) -> usize {
        self.offsets.len().saturating_sub(1)
    }

    /// True when no vertex is bound.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Entry range of vertex `v`.
    pub fn row(&self, v: usize) -> std::ops::Range<usize> {
        self.offsets[v] as usize..self.offsets[v + 1] as usize
    }

    /// Mean number of curves per vertex.
    pub fn mean_curves(&self) -> f64 {
        if self.is_empty() {
            0.0
        } else {
            self.curve.len() as f64 / self.len() as f64
        }
    }
}

/// Projection of a point on a curve's rest skeleton polyline.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Projection {
    pub sigma: f64,
    pub dist: f64,
    pub clamped: bool,
}

/// Projects `x` on the polyline (far end of bone 1) → J → (far end of bone 2) of `f`.
pub(crate) fn project_skeleton(f: &CurveFrame, x: &Pt3) -> Projection {
    let total = f.length();
    if total <= 1e-12 {
        return Projection { sigma: 0.0, dist: (x - f.j).norm(), clamped: true };
    }
    // Segment 1: from far_in (s = 0) to J (s = l_in), direction -u_in.
    let far_in = f.j + f.u_in * f.l_in;
    let t1 = -f.u_in;
    let raw1 = (x - far_in).dot(&t1);
    let s1 = raw1.clamp(0.0, f.l_in);
    let d1 = (far_in + t1 * s1 - x).norm();
    let raw2 = (x - f.j).dot(&f.u_out);
    let s2 = raw2.clamp(0.0, f.l_out);
    let d2 = (f.j + f.u_out * s2 - x).norm();
    let (s, d, raw) =
        if f.l_in > 0.0 && (d1 < d2 || f.l_out <= 0.0) { (s1, d1, raw1) } else { (f.l_in + s2, d2, f.l_in + raw2) };
    let sigma = s / total;
    let raw_sigma = raw / total;
    let clamped = !(-DOMAIN_TOL..=1.0 + DOMAIN_TOL).contains(&raw_sigma);
    Projection { sigma, dist: d, clamped }
}

/// Rest frames of all curves with the given skin distances.
pub(crate) fn rest_frames(sk: &SkinSkeleton, cs: &CurveSkeleton, rigs: &[CurveRig]) -> Vec<CurveFrame> {
    cs.curves
        .iter()
        .zip(rigs)
        .map(|(c, r)| {
            CurveFrame::new(c, r, &sk.rest_world, &FrameHistory::default(), TwistChoice::Principal, Default::default())
                .0
        })
        .collect()
}

/// One bound entry before packing.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Entry {
    pub curve: usize,
    pub sigma: f64,
    pub w: f64,
}

/// Candidate curves and weights of one point (spec §3.4.5), given its projections.
pub(crate) fn weights_for_point(
    x: &Pt3,
    frames: &[CurveFrame],
    proj: &[Projection],
    opts: &CurveOptions,
    out: &mut Vec<Entry>,
) -> bool {
    out.clear();
    // (curve, curve distance, σ). A curve whose domain holds the foot but which is much farther
    // than the nearest skeleton part (e.g. the neck curve seen from beyond a hand) is not a
    // candidate.
    let mut cands: Vec<(usize, f64, f64)> = Vec::new();
    let band = opts.blend_band.max(1e-6);
    let near =
        frames.iter().zip(proj).filter(|(f, _)| f.length() > 1e-12).map(|(_, p)| p.dist).fold(f64::INFINITY, f64::min);
    for (i, (f, p)) in frames.iter().zip(proj).enumerate() {
        if p.clamped || f.length() <= 1e-12 || p.dist > near * (1.0 + band) + 1e-12 {
            continue;
        }
        let (dc, u) = f.closest_on_curve(x);
        let sigma = match f.centre {
            CentreMode::OnSkeleton => p.sigma,
            CentreMode::OnCurve => {
                let total = f.curve_length();
                if total > 0.0 {
                    u / total
                } else {
                    0.0
                }
            }
        };
        cands.push((i, dc, sigma));
    }
    let clamped = cands.is_empty();
    if clamped {
        // Rigid with the nearest clamped domain end.
        let best = frames
            .iter()
            .zip(proj)
            .enumerate()
            .filter(|(_, (f, _))| f.length() > 1e-12)
            .min_by(|a, b| a.1 .1.dist.total_cmp(&b.1 .1.dist).then(a.0.cmp(&b.0)));
        if let Some((i, (_, p))) = best {
            out.push(Entry { curve: i, sigma: p.sigma, w: 1.0 });
        }
        return true;
    }
    let d_min = cands.iter().map(|c| c.1).fold(f64::INFINITY, f64::min).max(1e-9);
    let mut ws: Vec<(f64, usize, f64)> = cands
        .iter()
        .map(|&(i, d, s)| {
            let d = d.max(1e-9);
            let w = smoothstep(0.0, 1.0, (1.0 + band - d / d_min) / band) / d;
            (w, i, s)
        })
        .filter(|e| e.0 > 0.0)
        .collect();
    ws.sort_by(|a, b| b.0.total_cmp(&a.0).then(a.1.cmp(&b.1)));
    ws.truncate(opts.max_curves_per_vertex.clamp(1, 3));
    let total: f64 = ws.iter().map(|e| e.0).sum();
    for (w, i, s) in ws {
        out.push(Entry { curve: i, sigma: s, w: w / total });
    }
    false
}

/// Computes the per-curve rigs (with skin distances) and the binding of `rest` (spec §3.4.5).
/// `normals` are the rest normals (optional). Errors: empty skeleton, a curve naming a joint out
/// of range, more than 65 535 curves, non-finite positions.
pub fn bind<P: AsPt3>(
    rest: &[P],
    normals: Option<&[[f32; 3]]>,
    sk: &SkinSkeleton,
    cs: &CurveSkeleton,
    opts: &CurveOptions,
) -> Result<(CurveBinding, Vec<CurveRig>)> {
    if sk.is_empty() {
        return Err(SkinError::EmptySkeleton);
    }
    sk.validate()?;
    if cs.curves.len() > u16::MAX as usize {
        return Err(SkinError::Param(format!("{} curves (at most 65535)", cs.curves.len())));
    }
    for (i, c) in cs.curves.iter().enumerate() {
        for j in [c.joint, c.bone_in.far, c.bone_in.owner, c.bone_out.far, c.bone_out.owner] {
            if j >= sk.len() {
                return Err(SkinError::Param(format!("curve {i} names joint {j}, skeleton has {}", sk.len())));
            }
        }
    }
    if let Some(n) = normals {
        if n.len() != rest.len() {
            return Err(SkinError::Size { what: "rest normals", expected: rest.len(), got: n.len() });
        }
    }
    let pts: Vec<Pt3> = rest.iter().map(|p| p.pt3()).collect();
    if let Some(v) = pts.iter().position(|p| !p.coords.iter().all(|c| c.is_finite())) {
        return Err(SkinError::Param(format!("rest position {v} is not finite")));
    }
    // (1) projections on the rest skeleton (independent of L): frames with a provisional d.
    let mut rigs: Vec<CurveRig> = cs.curves.iter().map(|c| CurveRig::new(sk, c, 0.0)).collect();
    let frames0 = rest_frames(sk, cs, &rigs);
    let mut dists: Vec<Vec<f64>> = vec![Vec::new(); cs.curves.len()];
    for x in &pts {
        for (i, f) in frames0.iter().enumerate() {
            let p = project_skeleton(f, x);
            if !p.clamped && f.length() > 1e-12 {
                dists[i].push(p.dist);
            }
        }
    }
    // (2) d = 95th percentile per curve.
    for (r, d) in rigs.iter_mut().zip(dists.iter_mut()) {
        if d.is_empty() {
            r.skin_dist = 0.0;
        } else {
            d.sort_by(|a, b| a.total_cmp(b));
            let k = ((0.95 * (d.len() - 1) as f64).round() as usize).min(d.len() - 1);
            r.skin_dist = d[k];
        }
    }
    // (3) rest frames with the rest L.
    let frames = rest_frames(sk, cs, &rigs);
    // (4) local coordinates and weights.
    let mut b = CurveBinding {
        offsets: Vec::with_capacity(pts.len() + 1),
        normal_local: normals.map(|_| Vec::new()),
        skin_dist: rigs.iter().map(|r| r.skin_dist).collect(),
        ..Default::default()
    };
    b.offsets.push(0);
    let mut hist = vec![0usize; 4];
    let mut entries = Vec::new();
    let mut proj = Vec::with_capacity(frames.len());
    for (v, x) in pts.iter().enumerate() {
        proj.clear();
        proj.extend(frames.iter().map(|f| project_skeleton(f, x)));
        if weights_for_point(x, &frames, &proj, opts, &mut entries) {
            b.stats.clamped += 1;
        }
        hist[entries.len().min(3)] += 1;
        for e in &entries {
            let c = &cs.curves[e.curve];
            let (centre, rot, scale) = frames[e.curve].eval(e.sigma, &c.twist);
            let l = rot.inverse() * (x - centre) / scale;
            b.curve.push(e.curve as u16);
            b.sigma.push(e.sigma);
            b.local.push([l.x, l.y, l.z]);
            b.w.push(e.w);
            if let (Some(nl), Some(n)) = (b.normal_local.as_mut(), normals) {
                let nn = rot.inverse() * Vec3::new(n[v][0] as f64, n[v][1] as f64, n[v][2] as f64);
                nl.push([nn.x, nn.y, nn.z]);
            }
        }
        b.offsets.push(b.curve.len() as u32);
    }
    b.stats.histogram = hist;
    Ok((b, rigs))
}

/// Binds one point on the fly against precomputed rest frames and deforms it with posed frames:
/// the analytic map used for fold analysis (spec §7.4 c).
pub(crate) fn map_point(
    x: &Pt3,
    cs: &CurveSkeleton,
    rest: &[CurveFrame],
    posed: &[CurveFrame],
    opts: &CurveOptions,
) -> Pt3 {
    let proj: Vec<Projection> = rest.iter().map(|f| project_skeleton(f, x)).collect();
    let mut entries = Vec::new();
    weights_for_point(x, rest, &proj, opts, &mut entries);
    let mut acc = Vec3::zeros();
    for e in &entries {
        let tw = &cs.curves[e.curve].twist;
        let (c0, r0, s0) = rest[e.curve].eval(e.sigma, tw);
        let l = r0.inverse() * (x - c0) / s0;
        let (c1, r1, s1) = posed[e.curve].eval(e.sigma, tw);
        acc += (c1 + r1 * l * s1).coords * e.w;
    }
    Pt3::from(acc)
}

/// Posed joint frames moved by one rigid motion `g` (helper for invariance checks).
pub fn move_rigidly(posed: &[Iso3], g: &Iso3) -> Vec<Iso3> {
    posed.iter().map(|p| g * p).collect()
}

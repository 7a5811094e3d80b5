//! Wrinkling coefficients (spec §3.5, paper: reconstructed) and their precomputation by
//! adaptive quadrature with gradient-sample compression (spec §3.12).
//!
//! With `W = √(1+|g|²)`:
//! `C1 = ∫(1+g_y²)/W`, `C2 = −∫g_x g_y/W`, `C3 = ∫(1+g_x²)/W`, `C4 = ∫|g|²/W`,
//! `K = [[C1, C2], [C2, C3]]`, `A_T^w = ∫W`, `C4_k = ∫λ_k|g|²/W`.

use geom_core::math::{Mat2, Pt2, Vec2};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::error::{Result, WrinkleError};
use crate::frames::{rest_frames, RestFrame, RestMesh};
use crate::pattern::{Normalization, WrinklePattern};
use crate::quadrature::adaptive;

/// Precomputation options (spec §2, §4).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct PrecomputeOptions {
    /// Absolute integrand tolerance per unit rest area (> 0).
    pub tolerance: f64,
    /// Adaptive subdivision depth cap (1–12).
    pub max_depth: u32,
    /// Gradient-sample compression K (0 = keep every quadrature point), see [`GradientSamples`].
    pub gradient_bins: usize,
    /// Keep gradient samples at all (needed by the exact modes and the area report).
    pub gradient_samples: bool,
}

impl Default for PrecomputeOptions {
    fn default() -> Self {
        Self { tolerance: 1e-4, max_depth: 7, gradient_bins: 72, gradient_samples: true }
    }
}

/// Quality flag of a triangle's coefficients for one pattern (spec §3.7).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum CoeffStatus {
    /// Converged.
    Ok,
    /// The pattern is constant on the triangle (C4 = 0).
    ConstantPattern,
    /// The rest triangle has (near) zero area.
    DegenerateRest,
    /// The UV map of the triangle is singular.
    DegenerateUv,
    /// The adaptive quadrature hit `max_depth` somewhere (coefficients finite, see `quad_error`).
    Unconverged,
}

impl CoeffStatus {
    /// Whether the pattern can drive the triangle (not constant/degenerate).
    pub fn is_active(self) -> bool {
        matches!(self, CoeffStatus::Ok | CoeffStatus::Unconverged)
    }
}

/// Gradient samples `(g_s, w_s)` of a triangle for the exact modes (spec §3.12 step 3): the
/// exact integrands depend on x only through g (and g ≡ −g), so points are folded into the upper
/// half-plane and binned into (radial quantile) × (angular) bins; each bin keeps its weight, its
/// weight-averaged direction and its weighted RMS |g|.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct GradientSamples {
    /// Representative gradients (local rest frame).
    pub g: Vec<Vec2>,
    /// Weights (m²), summing to `area_flat`.
    pub w: Vec<f64>,
    /// Σ w_s (= A_T up to round-off).
    pub area_flat: f64,
    /// Σ w_s √(1+|g_s|²): A_T^w as seen by these samples.
    pub area_wrinkled: f64,
}

impl GradientSamples {
    fn from_points(g: Vec<Vec2>, w: Vec<f64>) -> Self {
        let area_flat = w.iter().sum();
        let area_wrinkled = g.iter().zip(&w).map(|(g, w)| w * (1.0 + g.norm_squared()).sqrt()).sum();
        Self { g, w, area_flat, area_wrinkled }
    }

    /// Compresses into about `bins` bins: `nr = max(1, round(√(bins/2)))` radial × `bins/nr`
    /// angular (72 → 6 × 12). `bins = 0` keeps every point.
    pub fn binned(g: &[Vec2], w: &[f64], bins: usize) -> Self {
        if bins == 0 || g.len() <= bins {
            return Self::from_points(g.to_vec(), w.to_vec());
        }
        let nr = ((bins as f64 / 2.0).sqrt().round() as usize).max(1);
        let na = (bins / nr).max(1);
        // Radial quantile edges by weight.
        let mut order: Vec<usize> = (0..g.len()).collect();
        order.sort_by(|&a, &b| g[a].norm_squared().total_cmp(&g[b].norm_squared()).then(a.cmp(&b)));
        let total: f64 = w.iter().sum();
        let mut rbin = vec![0usize; g.len()];
        let mut acc = 0.0;
        for &i in &order {
            rbin[i] = (((acc + 0.5 * w[i]) / total * nr as f64) as usize).min(nr - 1);
            acc += w[i];
        }
        let n = nr * na;
        let (mut bw, mut bg2, mut bdir) = (vec![0.0; n], vec![0.0; n], vec![Vec2::zeros(); n]);
        for i in 0..g.len() {
            let mut gi = g[i];
            if gi.y < 0.0 || (gi.y == 0.0 && gi.x < 0.0) {
                gi = -gi;
            }
            let ang = gi.y.atan2(gi.x).clamp(0.0, std::f64::consts::PI);
            let a = ((ang / std::f64::consts::PI * na as f64) as usize).min(na - 1);
            let b = rbin[i] * na + a;
            bw[b] += w[i];
            let l2 = gi.norm_squared();
            bg2[b] += w[i] * l2;
            if l2 > 0.0 {
                bdir[b] += gi * (w[i] / l2.sqrt());
            }
        }
        let (mut og, mut ow) = (Vec::new(), Vec::new());
        for b in 0..n {
            if bw[b] > 0.0 {
                let d = bdir[b].try_normalize(0.0).unwrap_or(Vec2::x());
                og.push(d * (bg2[b] / bw[b]).sqrt());
                ow.push(bw[b]);
            }
        }
        Self::from_points(og, ow)
    }
}

/// Coefficients of one triangle for one pattern (spec §2).
#[derive(Clone, Debug)]
pub struct TriCoeffs {
    /// `K = [[C1, C2], [C2, C3]]` (m²).
    pub k: Mat2,
    /// C4 (m²).
    pub c4: f64,
    /// C4 split by barycentric weight, `C4_k = ∫λ_k|g|²/W` (sums to C4).
    pub c4_vertex: [f64; 3],
    /// Flat rest area A_T (m²).
    pub area_flat: f64,
    /// `A_T^w = ∫W`: the rest triangle carrying the pattern at h = 1 (m²).
    pub area_wrinkled: f64,
    /// `∫1/W` (for the invariant C1 + C3 − C4 = 2∫1/W).
    pub inv_w: f64,
    /// Gradient samples for the exact modes (empty when not kept).
    pub grad_samples: GradientSamples,
    /// Accumulated quadrature error estimate (m²).
    pub quad_error: f64,
    /// Number of integrand evaluations kept as leaves.
    pub n_points: usize,
    /// Largest rest slope |g| seen at the quadrature points.
    pub max_slope: f64,
    /// Status.
    pub status: CoeffStatus,
}

impl TriCoeffs {
    fn inactive(area: f64, status: CoeffStatus) -> Self {
        Self {
            k: Mat2::zeros(),
            c4: 0.0,
            c4_vertex: [0.0; 3],
            area_flat: area,
            area_wrinkled: area,
            inv_w: area,
            grad_samples: GradientSamples::from_points(vec![Vec2::zeros()], vec![area]),
            quad_error: 0.0,
            n_points: 0,
            max_slope: 0.0,
            status,
        }
    }
}

/// Rest slope `g(x) = η·Jᵀ∇_uv S(uv(x))` at barycentric point `b` of triangle `f`.
pub(crate) fn slope_at(
    mesh: &RestMesh,
    rf: &RestFrame,
    f: usize,
    pat: &WrinklePattern,
    eta: f64,
    b: [f64; 3],
) -> (f64, Vec2) {
    let uv = Pt2::from(mesh.uv(f, 0).coords * b[0] + mesh.uv(f, 1).coords * b[1] + mesh.uv(f, 2).coords * b[2]);
    let (s, g) = pat.eval_grad(&uv);
    (eta * s, rf.j.transpose() * g * eta)
}

/// Coefficients of triangle `f` for one pattern of scale `eta`; `slope_per_eta` is the pattern's
/// largest rest slope per metre of η over the mesh (only used to scale the subdivision test).
pub fn triangle_coeffs(
    mesh: &RestMesh,
    rf: &RestFrame,
    f: usize,
    pat: &WrinklePattern,
    eta: f64,
    slope_per_eta: f64,
    o: &PrecomputeOptions,
) -> TriCoeffs {
    if rf.degenerate {
        return TriCoeffs::inactive(rf.area, CoeffStatus::DegenerateRest);
    }
    if rf.degenerate_uv {
        return TriCoeffs::inactive(rf.area, CoeffStatus::DegenerateUv);
    }
    if pat.is_constant() {
        return TriCoeffs::inactive(rf.area, CoeffStatus::ConstantPattern);
    }
    // Integrand: [W, (1+gy²)/W, −gx gy/W, (1+gx²)/W, |g|²/W, λ0|g|²/W, λ1|g|²/W, λ2|g|²/W, 1/W,
    // ĝx², ĝx ĝy, ĝy²] with ĝ = g/(η·slope_per_eta) (max |ĝ| ≈ 1). The last three are
    // η-free: they make the subdivision resolve the pattern's shape even when the slopes are
    // tiny (W ≈ 1 everywhere), which the exact modes need at large h (spec §8 "tiny η").
    let inv_ref = if slope_per_eta > 0.0 { 1.0 / (eta * slope_per_eta) } else { 0.0 };
    let mut integrand = |b: [f64; 3], out: &mut [f64]| {
        let (_, g) = slope_at(mesh, rf, f, pat, eta, b);
        let gh = g * inv_ref;
        out[9] = gh.x * gh.x;
        out[10] = gh.x * gh.y;
        out[11] = gh.y * gh.y;
        let g2 = g.norm_squared();
        let w = (1.0 + g2).sqrt();
        out[0] = w;
        out[1] = (1.0 + g.y * g.y) / w;
        out[2] = -g.x * g.y / w;
        out[3] = (1.0 + g.x * g.x) / w;
        out[4] = g2 / w;
        out[5] = b[0] * g2 / w;
        out[6] = b[1] * g2 / w;
        out[7] = b[2] * g2 / w;
        out[8] = 1.0 / w;
    };
    let r = adaptive(rf.area, 12, &mut integrand, o.tolerance, o.max_depth);
    let i = &r.integral;
    let mut max_slope: f64 = 0.0;
    let grad_samples = if o.gradient_samples {
        let (mut gs, mut ws) = (Vec::with_capacity(r.points.len()), Vec::with_capacity(r.points.len()));
        for p in &r.points {
            let (_, g) = slope_at(mesh, rf, f, pat, eta, p.bary);
            max_slope = max_slope.max(g.norm());
            gs.push(g);
            ws.push(p.weight);
        }
        GradientSamples::binned(&gs, &ws, o.gradient_bins)
    } else {
        for p in &r.points {
            max_slope = max_slope.max(slope_at(mesh, rf, f, pat, eta, p.bary).1.norm());
        }
        GradientSamples::default()
    };
    // C4 numerically zero (relative to the area): the pattern does not vary on this triangle.
    let status = if i[4].is_nan() || i[4] <= 1e-14 * rf.area {
        CoeffStatus::ConstantPattern
    } else if r.unconverged {
        CoeffStatus::Unconverged
    } else {
        CoeffStatus::Ok
    };
    TriCoeffs {
        k: Mat2::new(i[1], i[2], i[2], i[3]),
        c4: i[4],
        c4_vertex: [i[5], i[6], i[7]],
        area_flat: rf.area,
        area_wrinkled: i[0],
        inv_w: i[8],
        grad_samples,
        quad_error: r.error,
        n_points: r.points.len(),
        max_slope,
        status,
    }
}

/// Everything computed once per rest mesh and pattern set.
#[derive(Clone, Debug)]
pub struct WrinkleRig {
    /// The rest mesh.
    pub mesh: RestMesh,
    /// Rest frames, one per triangle.
    pub frames: Vec<RestFrame>,
    /// The patterns.
    pub patterns: Vec<WrinklePattern>,
    /// Height scale η per pattern (m).
    pub eta: Vec<f64>,
    /// Coefficients, `coeffs[t·P + i]`.
    pub coeffs: Vec<TriCoeffs>,
    /// Largest rest slope per pattern over the mesh (quadrature points).
    pub max_slope: Vec<f64>,
    /// Faces incident to each vertex.
    pub vertex_faces: Vec<Vec<u32>>,
    /// Unique undirected edges `[a, b]`, `a < b`, sorted.
    pub edges: Vec<[u32; 2]>,
    /// The options used.
    pub options: PrecomputeOptions,
}

impl WrinkleRig {
    /// Number of patterns P.
    pub fn n_patterns(&self) -> usize {
        self.patterns.len()
    }
    /// Coefficients of triangle `t`, pattern `i`.
    pub fn coeff(&self, t: usize, i: usize) -> &TriCoeffs {
        &self.coeffs[t * self.patterns.len() + i]
    }
}

fn sigma_max(j: &Mat2) -> f64 {
    let m = j.transpose() * j;
    geom_core::math::sym_eig2(&m).0[1].max(0.0).sqrt()
}

/// Resolves η of a pattern on a mesh (spec §3.2 item 3). `TargetRestSlope`: for single waves the
/// exact `max_t |J_tᵀc|`; otherwise `max_t σ_max(J_t) · max_uv |∇S|` (exact for uniform UV maps,
/// an upper bound of the slope otherwise, so the realised max slope is ≤ the target).
fn resolve_eta(mesh: &RestMesh, frames: &[RestFrame], pat: &WrinklePattern) -> (f64, f64) {
    let active = frames.iter().filter(|f| !f.degenerate && !f.degenerate_uv);
    let slope = if let Some(c) = pat.wave_vector_uv() {
        active.map(|f| (f.j.transpose() * c).norm()).fold(0.0, f64::max)
    } else {
        let smax = active.map(|f| sigma_max(&f.j)).fold(0.0, f64::max);
        let (mut lo, mut hi) = (Pt2::new(f64::INFINITY, f64::INFINITY), Pt2::new(f64::NEG_INFINITY, f64::NEG_INFINITY));
        for (f, _) in mesh.faces.iter().enumerate() {
            for k in 0..3 {
                let u = mesh.uv(f, k);
                lo = Pt2::new(lo.x.min(u.x), lo.y.min(u.y));
                hi = Pt2::new(hi.x.max(u.x), hi.y.max(u.y));
            }
        }
        if smax > 0.0 && lo.x.is_finite() {
            smax * pat.max_grad_uv(lo, hi)
        } else {
            0.0
        }
    };
    let eta = match pat.options.normalization {
        Normalization::Metres(e) => e,
        Normalization::FractionOfEdge(phi) => {
            let (mut s, mut n) = (0.0, 0usize);
            for t in &mesh.faces {
                for k in 0..3 {
                    s += (mesh.positions[t[k] as usize] - mesh.positions[t[(k + 1) % 3] as usize]).norm();
                    n += 1;
                }
            }
            if n == 0 {
                1.0
            } else {
                phi * s / n as f64
            }
        }
        // A constant pattern has slope 0: η is irrelevant (every coefficient vanishes).
        Normalization::TargetRestSlope(s0) => {
            if slope > 0.0 {
                s0 / slope
            } else {
                1.0
            }
        }
    };
    (eta, slope)
}

/// Precomputes rest frames, η, and the coefficients of every triangle for every pattern, in
/// parallel over triangles (deterministic: triangles are independent).
///
/// Errors: [`WrinkleError::InvalidOption`] for a non-positive tolerance or `max_depth` outside
/// 1–12.
pub fn precompute(rest: &RestMesh, patterns: &[WrinklePattern], o: &PrecomputeOptions) -> Result<WrinkleRig> {
    if !(o.tolerance > 0.0 && o.tolerance.is_finite()) {
        return Err(WrinkleError::InvalidOption(format!("precompute.tolerance must be > 0, got {}", o.tolerance)));
    }
    if !(1..=12).contains(&o.max_depth) {
        return Err(WrinkleError::InvalidOption(format!(
            "precompute.max_depth must be in 1..=12, got {}",
            o.max_depth
        )));
    }
    let frames = rest_frames(rest);
    let (eta, slope_per_eta): (Vec<f64>, Vec<f64>) = patterns.iter().map(|p| resolve_eta(rest, &frames, p)).unzip();
    let np = patterns.len();
    let coeffs: Vec<TriCoeffs> = (0..rest.faces.len() * np)
        .into_par_iter()
        .map(|ti| {
            let (t, i) = (ti / np, ti % np);
            triangle_coeffs(rest, &frames[t], t, &patterns[i], eta[i], slope_per_eta[i], o)
        })
        .collect();
    let max_slope =
        (0..np).map(|i| (0..rest.faces.len()).map(|t| coeffs[t * np + i].max_slope).fold(0.0, f64::max)).collect();
    let mut vertex_faces = vec![Vec::new(); rest.positions.len()];
    let mut edges = Vec::with_capacity(3 * rest.faces.len());
    for (f, t) in rest.faces.iter().enumerate() {
        for k in 0..3 {
            vertex_faces[t[k] as usize].push(f as u32);
            let (a, b) = (t[k], t[(k + 1) % 3]);
            edges.push([a.min(b), a.max(b)]);
        }
    }
    edges.sort_unstable();
    edges.dedup();
    Ok(WrinkleRig {
        mesh: rest.clone(),
        frames,
        patterns: patterns.to_vec(),
        eta,
        coeffs,
        max_slope,
        vertex_faces,
        edges,
        options: o.clone(),
    })
}

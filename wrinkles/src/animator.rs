//! Per-frame modulation (spec §3.5–§3.11) and output surfaces (spec §3.13).

use std::time::Instant;

use geom_core::math::{Mat2, Pt2, Pt3, Vec2, Vec3};
use geom_core::mesh::{vertex_normals, NormalWeight};
use nalgebra::{Matrix3, SVD};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::blend::{pattern_weights, BlendOptions};
use crate::coeffs::{slope_at, WrinkleRig};
use crate::displaced::{refined_uv, DisplacedMesh, Refinement};
use crate::error::{Result, WrinkleError};
use crate::frames::Deformation;
use crate::modulation::{h_linear, modulate, wrinkled_area, ModulationMode, StrainMeasure};
use crate::smoothing::{vertex_average, AreaConsistentLsq, Smoothing};

/// Amplitude cap ("pattern range", spec §4).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub enum HMax {
    /// `h_max = max_slope / (largest rest slope of the pattern over the mesh)`.
    Auto {
        /// Largest allowed wrinkled slope (> 0).
        max_slope: f64,
    },
    /// A fixed cap (> 0).
    Fixed(f64),
}

/// The paper's user transform `m = clamp(scale·y + bias, min, max)` applied per sample after
/// interpolation (spec §3.8).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct MapTransform {
    /// Scale.
    pub scale: f64,
    /// Bias.
    pub bias: f64,
    /// Lower clip.
    pub min: f64,
    /// Upper clip.
    pub max: f64,
}

impl Default for MapTransform {
    fn default() -> Self {
        Self::identity()
    }
}

impl MapTransform {
    /// `(1, 0, 0, ∞)`: the paper's default look (h is already capped at h_max).
    pub fn identity() -> Self {
        Self { scale: 1.0, bias: 0.0, min: 0.0, max: f64::INFINITY }
    }
    /// `(s, −s, 0, ∞)`: 0 at rest and under stretch in the linear mode, growing with compression.
    pub fn flat_at_rest(s: f64) -> Self {
        Self { scale: s, bias: -s, min: 0.0, max: f64::INFINITY }
    }
    /// Value and derivative.
    fn apply(&self, y: f64) -> (f64, f64) {
        let m = self.scale * y + self.bias;
        if m < self.min {
            (self.min, 0.0)
        } else if m > self.max {
            (self.max, 0.0)
        } else {
            (m, self.scale)
        }
    }
}

/// Per-frame options (spec §2, §4).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct ModulationOptions {
    /// The modulation law.
    pub mode: ModulationMode,
    /// Amplitude cap.
    pub h_max: HMax,
    /// User transform.
    pub transform: MapTransform,
    /// Across-triangle smoothing.
    pub smoothing: Smoothing,
    /// Pattern blending.
    pub blend: BlendOptions,
    /// Temporal low-pass α ∈ (0, 1] (1 = off).
    pub temporal_alpha: f64,
    /// Newton relative residual tolerance.
    pub newton_tol: f64,
    /// Newton iteration cap (then bisection).
    pub newton_max_iter: u32,
}

impl Default for ModulationOptions {
    fn default() -> Self {
        Self {
            mode: ModulationMode::ExactFlatRest,
            h_max: HMax::Auto { max_slope: 1.5 },
            transform: MapTransform::identity(),
            smoothing: Smoothing::default(),
            blend: BlendOptions::default(),
            temporal_alpha: 1.0,
            newton_tol: 1e-12,
            newton_max_iter: 30,
        }
    }
}

/// Counts and timings of one frame.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct FrameDiagnostics {
    /// Triangle-pattern pairs clipped at h_max.
    pub clipped: usize,
    /// Linear-mode factors clipped at 0 (stretch beyond the linear range).
    pub clipped_zero: usize,
    /// Triangles with zero deformed area.
    pub collapsed: usize,
    /// Triangles flipped against their corners' vertex normals.
    pub inverted: usize,
    /// Degenerate rest triangles.
    pub degenerate_rest: usize,
    /// Exact solves with no visible variation (h = 0).
    pub no_solution: usize,
    /// Largest Newton iteration count.
    pub max_newton_iters: u32,
    /// Seconds spent on per-triangle modulation.
    pub t_modulate: f64,
    /// Seconds spent on smoothing.
    pub t_smooth: f64,
}

/// The result of one frame (spec §2).
#[derive(Clone, Debug)]
pub struct FrameModulation {
    /// T × P modulation factors (clipped to [0, h_max]).
    pub tri_h: Vec<f64>,
    /// T × P linearised factors (Green unless the mode asks PaperAbd), unclipped.
    pub tri_mf_lin: Vec<f64>,
    /// T × P pattern weights.
    pub tri_weight: Vec<f64>,
    /// V × P smoothed modulation (before the transform).
    pub vertex_mod: Vec<f64>,
    /// V × P smoothed weights.
    pub vertex_weight: Vec<f64>,
    /// Deformed unit vertex normals (area-weighted; fallbacks for collapsed neighbourhoods).
    pub vertex_normals: Vec<Vec3>,
    /// Diagnostics.
    pub diag: FrameDiagnostics,
}

/// What [`WrinkleAnimator::area_report`] measures.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum AreaCheck {
    /// `A_t(C, h_t)` with the triangle's own factor, from its gradient samples.
    PerTriangle,
    /// The rendered surface (smoothed, blended, transformed), integrated with the degree-5 rule
    /// on a uniform subdivision of the given level.
    Rendered {
        /// Subdivision level (4^level sub-triangles).
        level: u32,
    },
}

/// Per-triangle areas against targets.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct AreaReport {
    /// Wrinkled deformed area per triangle (m²).
    pub area: Vec<f64>,
    /// Target per triangle: A_T (flat modes) or A_T^w (paper modes) (m²).
    pub target: Vec<f64>,
    /// Mean |A − A*|/A* over non-degenerate triangles.
    pub mean_rel: f64,
    /// Max |A − A*|/A*.
    pub max_rel: f64,
}

/// The per-frame engine: rig, options, temporal state, prefactored LSQ system.
#[derive(Clone, Debug)]
pub struct WrinkleAnimator {
    rig: WrinkleRig,
    opts: ModulationOptions,
    h_max: Vec<f64>,
    lsq: Option<AreaConsistentLsq>,
    prev: Option<(Vec<f64>, Vec<f64>)>,
    rest_normals: Vec<Vec3>,
}

fn check_positions(p: &[Pt3], n: usize) -> Result<()> {
    if p.len() != n {
        return Err(WrinkleError::TopologyMismatch { expected: n, got: p.len() });
    }
    if let Some(v) = p.iter().position(|x| !x.coords.iter().all(|c| c.is_finite())) {
        return Err(WrinkleError::NonFinitePosition { vertex: v });
    }
    Ok(())
}

impl WrinkleAnimator {
    /// Validates options, resolves h_max per pattern, factorises the LSQ system if requested.
    ///
    /// Errors: [`WrinkleError::InvalidOption`] (non-positive h_max or Newton tolerance, α outside
    /// (0, 1], negative variance, power < 1, NaN transform), [`WrinkleError::SingularSmoothingSystem`].
    pub fn new(rig: WrinkleRig, opts: ModulationOptions) -> Result<Self> {
        let bad = |m: String| Err(WrinkleError::InvalidOption(m));
        match opts.h_max {
            HMax::Auto { max_slope: v } | HMax::Fixed(v) if !(v > 0.0 && v.is_finite()) => {
                return bad(format!("h_max must be positive and finite, got {v}"));
            }
            _ => {}
        }
        if !(opts.temporal_alpha > 0.0 && opts.temporal_alpha <= 1.0) {
            return bad(format!("temporal_alpha must be in (0, 1], got {}", opts.temporal_alpha));
        }
        if !(opts.newton_tol > 0.0 && opts.newton_tol < 1.0) || opts.newton_max_iter == 0 {
            return bad(format!(
                "newton_tol must be in (0, 1) and newton_max_iter ≥ 1, got {} / {}",
                opts.newton_tol, opts.newton_max_iter
            ));
        }
        let b = &opts.blend;
        if b.variance.is_nan() || b.variance < 0.0 || b.variance.is_infinite() || b.power.is_nan() || b.power < 1.0 {
            return bad(format!("blend: variance must be ≥ 0 and power ≥ 1, got {:?}", opts.blend));
        }
        let t = &opts.transform;
        if !(t.scale.is_finite() && t.bias.is_finite() && !t.min.is_nan() && !t.max.is_nan() && t.min <= t.max) {
            return bad(format!("transform must be finite with min ≤ max, got {t:?}"));
        }
        let exact = !matches!(opts.mode, ModulationMode::Linearized { .. });
        if exact && !rig.options.gradient_samples && rig.coeffs.iter().any(|c| c.status.is_active()) {
            return bad("exact modes need PrecomputeOptions::gradient_samples = true".into());
        }
        let h_max = (0..rig.n_patterns())
            .map(|i| match opts.h_max {
                HMax::Fixed(v) => v,
                HMax::Auto { max_slope } => {
                    if rig.max_slope[i] > 0.0 {
                        max_slope / rig.max_slope[i]
                    } else {
                        1.0
                    }
                }
            })
            .collect();
        let lsq = match opts.smoothing {
            Smoothing::AreaConsistent { mu } => Some(AreaConsistentLsq::new(&rig, mu)?),
            _ => None,
        };
        let rest_normals = vertex_normals(&rig.mesh.faces, &rig.mesh.positions, NormalWeight::Area);
        Ok(Self { rig, opts, h_max, lsq, prev: None, rest_normals })
    }

    /// The rig.
    pub fn rig(&self) -> &WrinkleRig {
        &self.rig
    }
    /// The options.
    pub fn options(&self) -> &ModulationOptions {
        &self.opts
    }
    /// h_max per pattern.
    pub fn h_max(&self) -> &[f64] {
        &self.h_max
    }
    /// Number of LSQ factorisations done so far (0 without `AreaConsistent`).
    pub fn n_factorizations(&self) -> usize {
        self.lsq.as_ref().map_or(0, |l| l.n_factorizations)
    }
    /// Forgets the temporal filter state.
    pub fn reset_temporal(&mut self) {
        self.prev = None;
    }

    /// Deformed vertex normals with fallbacks (spec §8): a zero normal (collapsed neighbourhood)
    /// becomes the rest normal rotated by the best-fit rotation of the 1-ring (Kabsch).
    fn normals(&self, p: &[Pt3]) -> Vec<Vec3> {
        let mut n = vertex_normals(&self.rig.mesh.faces, p, NormalWeight::Area);
        let mesh = &self.rig.mesh;
        for v in 0..n.len() {
            if n[v] != Vec3::zeros() {
                continue;
            }
            let mut h = Matrix3::zeros();
            for &f in &self.rig.vertex_faces[v] {
                for &u in &mesh.faces[f as usize] {
                    let r = mesh.positions[u as usize] - mesh.positions[v];
                    let d = p[u as usize] - p[v];
                    h += r * d.transpose();
                }
            }
            let svd = SVD::new(h, true, true);
            n[v] = match (svd.u, svd.v_t) {
                (Some(u), Some(vt)) if h.norm() > 0.0 => {
                    let mut r = vt.transpose() * u.transpose();
                    if r.determinant() < 0.0 {
                        let mut vv = vt.transpose();
                        vv.column_mut(2).neg_mut();
                        r = vv * u.transpose();
                    }
                    (r * self.rest_normals[v]).try_normalize(0.0).unwrap_or(self.rest_normals[v])
                }
                _ => self.rest_normals[v],
            };
        }
        n
    }

    /// Modulation of one frame from deformed positions (spec §3.5–§3.11).
    ///
    /// Errors: [`WrinkleError::TopologyMismatch`], [`WrinkleError::NonFinitePosition`].
    pub fn frame(&mut self, deformed: &[Point3]) -> Result<FrameModulation> {
        let rig = &self.rig;
        check_positions(deformed, rig.mesh.positions.len())?;
        let p = rig.n_patterns();
        let nt = rig.mesh.faces.len();
        let nv = rig.mesh.positions.len();
        let mode = self.opts.mode;
        let strain = match mode {
            ModulationMode::Linearized { strain } => strain,
            _ => StrainMeasure::Green,
        };
        let t0 = Instant::now();
        let vn = self.normals(deformed);
        let h_max = &self.h_max;
        let opts = &self.opts;
        // Flat outputs written in place (no per-triangle allocation); width 1 when P = 0 so the
        // per-triangle flags are still computed, truncated afterwards.
        let pw = p.max(1);
        let (mut tri_h, mut tri_m, mut tri_w) = (vec![0.0; nt * pw], vec![0.0; nt * pw], vec![1.0; nt * pw]);
        let mut flags = vec![([0usize; 6], 0u32); nt];
        tri_h
            .par_chunks_mut(pw)
            .zip(tri_m.par_chunks_mut(pw))
            .zip(tri_w.par_chunks_mut(pw))
            .zip(flags.par_iter_mut())
            .enumerate()
            .for_each_init(
                || (Vec::new(), Vec::new()),
                |(q, active), (t, (((hs, ms), w), fl))| {
                    let rf = &rig.frames[t];
                    let face = rig.mesh.faces[t];
                    let d = Deformation::new(
                        rf,
                        [&deformed[face[0] as usize], &deformed[face[1] as usize], &deformed[face[2] as usize]],
                    );
                    let nsum = vn[face[0] as usize] + vn[face[1] as usize] + vn[face[2] as usize];
                    // Deformed area ratio below 1e-14: collapsed (round-off level of a flattened triangle).
                    let collapsed_area = !rf.degenerate && d.area_vector.norm() <= 2e-14 * rf.area;
                    let inverted = !rf.degenerate && !collapsed_area && d.area_vector.dot(&nsum) < 0.0;
                    let flags = &mut fl.0;
                    flags[2] = collapsed_area as usize;
                    flags[3] = inverted as usize;
                    flags[4] = rf.degenerate as usize;
                    active.clear();
                    for i in 0..p {
                        let c = rig.coeff(t, i);
                        active.push(c.status.is_active());
                        ms[i] = h_linear(c, &d, strain);
                        let (mut h, it, nosol) = if inverted && active[i] && c.grad_samples.w.is_empty() {
                            (h_max[i], 0, false) // linear mode without samples: fully compressed
                        } else {
                            modulate(mode, c, &d, inverted, opts.newton_tol, opts.newton_max_iter, q)
                        };
                        fl.1 = fl.1.max(it);
                        flags[5] += nosol as usize;
                        if h > h_max[i] {
                            h = h_max[i];
                            flags[0] += 1;
                        } else if h < 0.0 {
                            h = 0.0;
                            flags[1] += 1;
                        }
                        hs[i] = h;
                    }
                    if p > 1 {
                        pattern_weights(ms, active, &opts.blend, w);
                    }
                },
            );
        tri_h.truncate(nt * p);
        tri_m.truncate(nt * p);
        tri_w.truncate(nt * p);
        let mut diag = FrameDiagnostics::default();
        for (f, it) in &flags {
            diag.clipped += f[0];
            diag.clipped_zero += f[1];
            diag.collapsed += f[2];
            diag.inverted += f[3];
            diag.degenerate_rest += f[4];
            diag.no_solution += f[5];
            diag.max_newton_iters = diag.max_newton_iters.max(*it);
        }
        let t1 = Instant::now();
        let ident = mode.identity_value();
        let mut vmod = vec![0.0; nv * p];
        let mut vw = vec![0.0; nv * p];
        let weights = match opts.smoothing {
            Smoothing::VertexAverage { weights } => weights,
            _ => crate::smoothing::VertexWeights::Area,
        };
        vertex_average(rig, weights, &tri_w, 1.0 / p.max(1) as f64, &mut vw);
        match (&opts.smoothing, &self.lsq) {
            (Smoothing::AreaConsistent { .. }, Some(lsq)) => {
                for i in 0..p {
                    lsq.solve(rig, i, &tri_h, &mut vmod)?;
                    for v in 0..nv {
                        vmod[v * p + i] = vmod[v * p + i].clamp(0.0, h_max[i]);
                    }
                }
            }
            _ => vertex_average(rig, weights, &tri_h, ident, &mut vmod),
        }
        let a = opts.temporal_alpha;
        if a < 1.0 {
            if let Some((pm, pw)) = &self.prev {
                for (y, y0) in vmod.iter_mut().zip(pm) {
                    *y = y0 + a * (*y - y0);
                }
                for (y, y0) in vw.iter_mut().zip(pw) {
                    *y = y0 + a * (*y - y0);
                }
            }
            self.prev = Some((vmod.clone(), vw.clone()));
        }
        diag.t_modulate = (t1 - t0).as_secs_f64();
        diag.t_smooth = t1.elapsed().as_secs_f64();
        Ok(FrameModulation {
            tri_h,
            tri_mf_lin: tri_m,
            tri_weight: tri_w,
            vertex_mod: vmod,
            vertex_weight: vw,
            vertex_normals: vn,
            diag,
        })
    }

    /// `D` and its rest-local gradient `∇_x D` at barycentric point `b` of triangle `t`:
    /// `D = Σ_i W_i·M_i·f_i` (spec §3.10).
    pub fn displacement_grad(&self, fm: &FrameModulation, t: usize, b: [f64; 3]) -> (f64, Vec2) {
        let rig = &self.rig;
        let p = rig.n_patterns();
        let rf = &rig.frames[t];
        let face = rig.mesh.faces[t];
        let per_tri = matches!(self.opts.smoothing, Smoothing::PerTriangle);
        let (mut d, mut gd) = (0.0, Vec2::zeros());
        for i in 0..p {
            let (w, gw, y, gy) = if per_tri {
                (fm.tri_weight[t * p + i], Vec2::zeros(), fm.tri_h[t * p + i], Vec2::zeros())
            } else {
                let (mut w, mut gw, mut y, mut gy) = (0.0, Vec2::zeros(), 0.0, Vec2::zeros());
                for k in 0..3 {
                    let v = face[k] as usize;
                    w += b[k] * fm.vertex_weight[v * p + i];
                    gw += rf.grad_bary[k] * fm.vertex_weight[v * p + i];
                    y += b[k] * fm.vertex_mod[v * p + i];
                    gy += rf.grad_bary[k] * fm.vertex_mod[v * p + i];
                }
                (w, gw, y, gy)
            };
            let (m, dm) = self.opts.transform.apply(y);
            let (f, g) = slope_at(&rig.mesh, rf, t, &rig.patterns[i], rig.eta[i], b);
            d += w * m * f;
            gd += gw * (m * f) + gy * (w * dm * f) + g * (w * m);
        }
        (d, gd)
    }

    /// Displacement `D` (m) at barycentric point `b` of triangle `t` (panics if `t` is out of
    /// range, like slice indexing).
    pub fn displacement(&self, fm: &FrameModulation, t: usize, b: [f64; 3]) -> f64 {
        self.displacement_grad(fm, t, b).0
    }

    /// Interpolated unit normal N at a point (falls back to the face normal, then the rest normal).
    fn blended_normal(&self, deformed: &[Point3], fm: &FrameModulation, t: usize, b: [f64; 3]) -> Vec3 {
        let face = self.rig.mesh.faces[t];
        let n = face.iter().zip(b).fold(Vec3::zeros(), |a, (&v, w)| a + fm.vertex_normals[v as usize] * w);
        n.try_normalize(0.0)
            .or_else(|| {
                let p = |k: usize| deformed[face[k] as usize];
                (p(1) - p(0)).cross(&(p(2) - p(0))).try_normalize(0.0)
            })
            .unwrap_or(self.rig.frames[t].n)
    }

    /// Bump-mapped normal `n′ = unit(N − F C⁺ ∇_x D)` (spec §3.13); a collapsed triangle uses N.
    ///
    /// Panics if `t` is not a triangle index or `deformed`/`fm` belong to another mesh (index
    /// misuse, not data: frames are validated by [`Self::frame`]).
    pub fn bump_normal(&self, deformed: &[Point3], fm: &FrameModulation, t: usize, b: [f64; 3]) -> Vec3 {
        let n = self.blended_normal(deformed, fm, t, b);
        let face = self.rig.mesh.faces[t];
        let rf = &self.rig.frames[t];
        if rf.degenerate {
            return n;
        }
        let d = Deformation::new(
            rf,
            [&deformed[face[0] as usize], &deformed[face[1] as usize], &deformed[face[2] as usize]],
        );
        let det = d.c.determinant();
        let tr = d.c.trace();
        if det.is_nan() || det <= 1e-12 * tr * tr {
            return n;
        }
        let (_, gd) = self.displacement_grad(fm, t, b);
        let cinv = d.c.try_inverse().unwrap_or(Mat2::zeros());
        (n - d.f * (cinv * gd)).try_normalize(0.0).unwrap_or(n)
    }

    /// The displaced refined surface at level L (spec §3.13): conforming, watertight; each vertex
    /// `X = Σλ_k p_k + D·N` with D averaged over all coarse faces sharing the vertex (seams).
    pub fn displaced_mesh(&self, deformed: &[Point3], fm: &FrameModulation, level: u32) -> Result<DisplacedMesh> {
        check_positions(deformed, self.rig.mesh.positions.len())?;
        if level == 0 || level > 256 {
            return Err(WrinkleError::InvalidOption(format!("subdivision level must be in 1..=256, got {level}")));
        }
        let r = Refinement::new(self.rig.mesh.positions.len(), &self.rig.mesh.faces, &self.rig.edges, level);
        Ok(self.displaced_on(&r, deformed, fm))
    }

    /// [`Self::displaced_mesh`] on a prebuilt refinement (reuse across frames).
    pub fn displaced_on(&self, r: &Refinement, deformed: &[Point3], fm: &FrameModulation) -> DisplacedMesh {
        let l = r.level;
        let nv = r.n_vertices;
        let mut base = vec![Pt3::origin(); nv];
        let mut normal = vec![Vec3::zeros(); nv];
        let mut seen = vec![false; nv];
        let mut dsum = vec![0.0; nv];
        let mut dcnt = vec![0u32; nv];
        let faces = &self.rig.mesh.faces;
        // Per-face lattice values in parallel, then a deterministic serial scatter.
        let vals: Vec<Vec<(f64, Pt3, Vec3)>> = (0..faces.len())
            .into_par_iter()
            .map(|t| {
                let face = faces[t];
                let mut out = Vec::with_capacity(r.lattice[t].len());
                for j in 0..=l {
                    for i in 0..=(l - j) {
                        let b = [(l - i - j) as f64 / l as f64, i as f64 / l as f64, j as f64 / l as f64];
                        let d = self.displacement(fm, t, b);
                        let x = Pt3::from(
                            deformed[face[0] as usize].coords * b[0]
                                + deformed[face[1] as usize].coords * b[1]
                                + deformed[face[2] as usize].coords * b[2],
                        );
                        out.push((d, x, self.blended_normal(deformed, fm, t, b)));
                    }
                }
                out
            })
            .collect();
        for (t, v) in vals.into_iter().enumerate() {
            for (idx, (d, x, n)) in v.into_iter().enumerate() {
                let g = r.lattice[t][idx] as usize;
                if !seen[g] {
                    seen[g] = true;
                    base[g] = x;
                    normal[g] = n;
                }
                dsum[g] += d;
                dcnt[g] += 1;
            }
        }
        let positions = (0..nv).map(|g| base[g] + normal[g] * (dsum[g] / dcnt[g].max(1) as f64)).collect();
        DisplacedMesh { positions, faces: r.faces.clone(), uv: refined_uv(r, |f, k| self.rig.mesh.uv(f, k)) }
    }

    /// Per-triangle wrinkled area against the mode's target (spec §9 metric 1).
    pub fn area_report(&self, deformed: &[Point3], fm: &FrameModulation, check: AreaCheck) -> Result<AreaReport> {
        check_positions(deformed, self.rig.mesh.positions.len())?;
        let rig = &self.rig;
        let p = rig.n_patterns();
        let flat = matches!(self.opts.mode, ModulationMode::ExactFlatRest | ModulationMode::PrincipalLength);
        let mut rep = AreaReport::default();
        let (mut sum, mut n) = (0.0, 0usize);
        for (t, face) in rig.mesh.faces.iter().enumerate() {
            let rf = &rig.frames[t];
            let d = Deformation::new(
                rf,
                [&deformed[face[0] as usize], &deformed[face[1] as usize], &deformed[face[2] as usize]],
            );
            let (area, target) = match check {
                AreaCheck::PerTriangle => {
                    // Weighted over patterns; with one pattern (or a fully selected one) exact.
                    let (mut a, mut tg) = (0.0, 0.0);
                    for i in 0..p {
                        let c = rig.coeff(t, i);
                        let w = fm.tri_weight[t * p + i];
                        a += w * wrinkled_area(&c.grad_samples, &d.c, fm.tri_h[t * p + i]);
                        tg += w * if flat { c.grad_samples.area_flat } else { c.grad_samples.area_wrinkled };
                    }
                    (a, tg)
                }
                AreaCheck::Rendered { level } => {
                    let adj = Mat2::new(d.c[(1, 1)], -d.c[(0, 1)], -d.c[(1, 0)], d.c[(0, 0)]);
                    let det = d.c.determinant().max(0.0);
                    let mut f = |b: [f64; 3], o: &mut [f64]| {
                        let (_, g) = self.displacement_grad(fm, t, b);
                        o[0] = (det + (g.transpose() * adj * g)[(0, 0)].max(0.0)).sqrt();
                    };
                    let a = crate::quadrature::uniform(rf.area, 1, &mut f, level)[0];
                    let mut tg = 0.0;
                    for i in 0..p {
                        let c = rig.coeff(t, i);
                        tg += fm.tri_weight[t * p + i] * if flat { c.area_flat } else { c.area_wrinkled };
                    }
                    (a, tg)
                }
            };
            if !rf.degenerate && target > 0.0 {
                let e = (area - target).abs() / target;
                sum += e;
                n += 1;
                rep.max_rel = rep.max_rel.max(e);
            }
            rep.area.push(area);
            rep.target.push(target);
        }
        rep.mean_rel = if n > 0 { sum / n as f64 } else { 0.0 };
        Ok(rep)
    }

    /// The transformed modulation of pattern `i` rasterised into UV space (the mesh's UV bounding
    /// box mapped to the image, v up): the paper's "modulation map" for external renderers.
    pub fn bake_modulation_map(
        &self,
        fm: &FrameModulation,
        pattern: usize,
        width: u32,
        height: u32,
    ) -> Result<geom_core::image::ImageF32> {
        let rig = &self.rig;
        if pattern >= rig.n_patterns() || width == 0 || height == 0 || width > 16384 || height > 16384 {
            return Err(WrinkleError::InvalidOption(format!(
                "bake_modulation_map: pattern {pattern} of {}, size {width}×{height} (1…16384)",
                rig.n_patterns()
            )));
        }
        let nf = rig.mesh.faces.len();
        let (mut lo, mut hi) = (Pt2::new(f64::INFINITY, f64::INFINITY), Pt2::new(f64::NEG_INFINITY, f64::NEG_INFINITY));
        for f in 0..nf {
            for k in 0..3 {
                let u = rig.mesh.uv(f, k);
                lo = Pt2::new(lo.x.min(u.x), lo.y.min(u.y));
                hi = Pt2::new(hi.x.max(u.x), hi.y.max(u.y));
            }
        }
        let sx = if hi.x > lo.x { 1.0 / (hi.x - lo.x) } else { 1.0 };
        let sy = if hi.y > lo.y { 1.0 / (hi.y - lo.y) } else { 1.0 };
        let tris: Vec<[Pt2; 3]> = (0..nf)
            .map(|f| {
                [0, 1, 2].map(|k| {
                    let u = rig.mesh.uv(f, k);
                    Pt2::new((u.x - lo.x) * sx * width as f64 - 0.5, (1.0 - (u.y - lo.y) * sy) * height as f64 - 0.5)
                })
            })
            .collect();
        let gb = geom_core::raster::rasterize_uv(width, height, &tris, 1);
        let p = rig.n_patterns();
        Ok(gb.resolve(
            |face, b| {
                let t = face as usize;
                let bb = [b[0] as f64, b[1] as f64, b[2] as f64];
                let y = if matches!(self.opts.smoothing, Smoothing::PerTriangle) {
                    fm.tri_h[t * p + pattern]
                } else {
                    let fcs = rig.mesh.faces[t];
                    (0..3).map(|k| bb[k] * fm.vertex_mod[fcs[k] as usize * p + pattern]).sum()
                };
                self.opts.transform.apply(y).0 as f32
            },
            0.0,
        ))
    }
}

/// Shorthand for positions.
type Point3 = Pt3;

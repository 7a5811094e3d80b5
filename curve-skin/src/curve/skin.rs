//! The curve-skeleton skinner (spec §3.4.6, paper Eq. 3: `P = Σ_i w_i M(i, t)·P_L(u, d)`).
//!
//! `prepare` builds each curve's posed state (β, b, L, θ) and, with `table_samples = K > 0`, a
//! table of `K + 1` uniform samples plus the three kinks (σ_J, s_J ± L; four more inside a
//! B-spline's zone) holding the centre, the frame quaternion (hemisphere-aligned along the table)
//! and the volume scale, in `f32`. `deform` locates σ through a per-cell index (at most seven
//! extra samples per curve, so ≤ 7 extra steps), lerps the centre and scale, nlerps the
//! quaternion and rotates the local offset: `x' = Σ w (c + R(q)·s·ℓ)`. With `table_samples = 0`
//! the closed form is evaluated per vertex in `f64`. [`CurveSkin::deform_f64`] is the exact
//! `f64` path of the tests.

use std::ops::Range;

use geom_core::anim::skin::SkinSkeleton;
use geom_core::math::{AsPt3, Iso3, Pt3, Vec3};

use super::bind::{bind, map_point, CurveBinding};
use super::frame::{CurveFrame, CurveRig, FrameHistory, TwistChoice};
use super::types::{CurveOptions, CurveSkeleton};
use crate::dqs::qrot;
use crate::error::{Result, SkinError};
use crate::skinner::{normalize3, DeformOutput, Skinner};

/// Non-uniform table samples per curve: the three kinks plus four inside a B-spline's zone.
const MAX_EXTRA: usize = 7;

/// Per-frame diagnostics.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct CurveDiagnostics {
    /// Curves whose fold-free Bone_CP distance exceeds its cap this frame (folding possible).
    pub cap_hits: usize,
    /// Largest bend angle over the curves (rad).
    pub max_beta: f64,
}

/// Flat per-curve frame tables.
#[derive(Clone, Debug, Default)]
struct Tables {
    k: usize,
    stride: usize,
    count: Vec<u32>,
    cell: Vec<u32>,
    sig: Vec<f32>,
    centre: Vec<[f32; 3]>,
    quat: Vec<[f32; 4]>,
    scale: Vec<f32>,
}

/// Curve-skeleton skinning: curves, binding, options and per-frame state.
#[derive(Clone, Debug)]
pub struct CurveSkin {
    /// The curve skeleton.
    pub skeleton: CurveSkeleton,
    /// The binding (f64).
    pub binding: CurveBinding,
    /// Options.
    pub opts: CurveOptions,
    /// Authored twist angle per joint (rad), used instead of the swing–twist value for every curve
    /// through that joint (spec §3.4.4); set before `prepare`.
    pub twist_hint: Vec<Option<f64>>,
    rigs: Vec<CurveRig>,
    rest_frames: Vec<CurveFrame>,
    frames: Vec<CurveFrame>,
    hist: Vec<FrameHistory>,
    diag: CurveDiagnostics,
    // f32 packed binding
    e_curve: Vec<u16>,
    e_sigma: Vec<f32>,
    e_local: Vec<[f32; 3]>,
    e_nlocal: Option<Vec<[f32; 3]>>,
    e_w: Vec<f32>,
    tab: Tables,
}

impl CurveSkin {
    /// Binds `rest` (and optional rest normals) to the curve skeleton `cs` of `sk` and prepares
    /// the bind pose. Errors: see [`bind`].
    pub fn new<P: AsPt3>(
        sk: &SkinSkeleton,
        cs: CurveSkeleton,
        rest: &[P],
        normals: Option<&[[f32; 3]]>,
        opts: CurveOptions,
    ) -> Result<CurveSkin> {
        let (binding, rigs) = bind(rest, normals, sk, &cs, &opts)?;
        let rest_frames = super::bind::rest_frames(sk, &cs, &rigs);
        let hist: Vec<FrameHistory> =
            rest_frames.iter().map(|f| FrameHistory { b_local: f.f_in.inverse() * f.b, theta: f.theta }).collect();
        let f32v = |a: &[f64; 3]| [a[0] as f32, a[1] as f32, a[2] as f32];
        let mut s = CurveSkin {
            e_curve: binding.curve.clone(),
            e_sigma: binding.sigma.iter().map(|&x| x as f32).collect(),
            e_local: binding.local.iter().map(f32v).collect(),
            e_nlocal: binding.normal_local.as_ref().map(|n| n.iter().map(f32v).collect()),
            e_w: binding.w.iter().map(|&x| x as f32).collect(),
            skeleton: cs,
            binding,
            twist_hint: vec![None; sk.len()],
            rigs,
            frames: rest_frames.clone(),
            rest_frames,
            hist,
            diag: CurveDiagnostics::default(),
            tab: Tables::default(),
            opts,
        };
        s.prepare(sk, &sk.rest_world)?;
        Ok(s)
    }

    /// Per-curve rest data (bone offsets, lengths, skin distance).
    pub fn rigs(&self) -> &[CurveRig] {
        &self.rigs
    }

    /// The posed curves of the last `prepare`.
    pub fn frames(&self) -> &[CurveFrame] {
        &self.frames
    }

    /// The rest curves.
    pub fn rest_frames(&self) -> &[CurveFrame] {
        &self.rest_frames
    }

    /// Diagnostics of the last `prepare`.
    pub fn diagnostics(&self) -> &CurveDiagnostics {
        &self.diag
    }

    /// Resets the twist-unwrap and binormal history to the bind pose (start of a new clip).
    pub fn reset_history(&mut self) {
        for (h, f) in self.hist.iter_mut().zip(&self.rest_frames) {
            *h = FrameHistory { b_local: f.f_in.inverse() * f.b, theta: f.theta };
        }
    }

    /// Exact `f64` deformation (closed-form frames, f64 binding) of every vertex.
    pub fn deform_f64(&self, out: &mut [Pt3]) {
        assert_eq!(out.len(), self.binding.len(), "deform_f64: output length");
        for (v, o) in out.iter_mut().enumerate() {
            let mut acc = Vec3::zeros();
            for e in self.binding.row(v) {
                let c = self.binding.curve[e] as usize;
                let (centre, rot, scale) = self.frames[c].eval(self.binding.sigma[e], &self.skeleton.curves[c].twist);
                let l = Vec3::from(self.binding.local[e]);
                acc += (centre + rot * l * scale).coords * self.binding.w[e];
            }
            *o = Pt3::from(acc);
        }
    }

    /// Exact `f64` normals: `normalize(Σ w R(σ) n_local)`. Panics if no normals were bound.
    pub fn normals_f64(&self, out: &mut [Vec3]) {
        let nl = self.binding.normal_local.as_ref().expect("normals_f64: bind with rest normals");
        for (v, o) in out.iter_mut().enumerate() {
            let mut acc = Vec3::zeros();
            for e in self.binding.row(v) {
                let c = self.binding.curve[e] as usize;
                let (_, rot, _) = self.frames[c].eval(self.binding.sigma[e], &self.skeleton.curves[c].twist);
                acc += rot * Vec3::from(nl[e]) * self.binding.w[e];
            }
            *o = acc.normalize();
        }
    }

    /// The analytic map of the current pose at an arbitrary rest point (bound on the fly); used
    /// for the fold-fraction analysis (spec §7.4 c).
    pub fn map_point(&self, x: &Pt3) -> Pt3 {
        map_point(x, &self.skeleton, &self.rest_frames, &self.frames, &self.opts)
    }

    fn build_tables(&mut self) {
        let k = self.opts.table_samples;
        let nc = self.frames.len();
        // K + 1 uniform samples, 3 kinks and, for the B-spline, 4 more inside the zone s_J ± L.
        let stride = k + 1 + MAX_EXTRA;
        let t = &mut self.tab;
        if t.k != k || t.count.len() != nc {
            *t = Tables {
                k,
                stride,
                count: vec![0; nc],
                cell: vec![0; nc * k],
                sig: vec![0.0; nc * stride],
                centre: vec![[0.0; 3]; nc * stride],
                quat: vec![[0.0; 4]; nc * stride],
                scale: vec![0.0; nc * stride],
            };
        }
        if k == 0 {
            return;
        }
        for c in 0..self.frames.len() {
            let (frame, twist) = (&self.frames[c], &self.skeleton.curves[c].twist);
            // Samples: uniform plus kinks, sorted, without near-duplicates (no allocation).
            let mut kinks = [0f64; MAX_EXTRA];
            let mut nk = 0usize;
            if self.opts.kink_samples {
                let kk = frame.kinks();
                let mut add = |s: f64| {
                    if s > 0.0 && s < 1.0 {
                        kinks[nk] = s;
                        nk += 1;
                    }
                };
                kk.iter().for_each(|&s| add(s));
                if frame.quad.is_some() {
                    // The B-spline's swing rate peaks at the joint: resolve the short zone
                    // (§3.4.6 bound of 2e-3 R at K = 64 holds with these, not without).
                    for j in [1.0, 2.0, 4.0, 5.0] {
                        add(kk[0] + (kk[2] - kk[0]) * j / 6.0);
                    }
                }
            }
            kinks[..nk].sort_by(|a, b| a.total_cmp(b));
            let base = c * stride;
            let mut n = 0usize;
            let mut ki = 0usize;
            let mut last = -1.0f64;
            let mut prev_q: Option<[f32; 4]> = None;
            for u in 0..=k {
                let su = u as f64 / k as f64;
                while ki < nk && kinks[ki] < su {
                    let s = kinks[ki];
                    ki += 1;
                    if (s - last).abs() < 1e-7 || (su - s).abs() < 1e-7 {
                        continue;
                    }
                    push_sample(frame, twist, &mut self.tab, base + n, s, &mut prev_q);
                    last = s;
                    n += 1;
                }
                if u < k {
                    self.tab.cell[c * k + u] = n as u32;
                }
                push_sample(frame, twist, &mut self.tab, base + n, su, &mut prev_q);
                last = su;
                n += 1;
            }
            self.tab.count[c] = n as u32;
        }
    }

    /// Table lookup: centre, unit quaternion and scale at σ for curve `c`.
    #[inline(always)]
    fn lookup(&self, c: usize, s: f32) -> ([f32; 3], [f32; 4], f32) {
        let t = &self.tab;
        let k = t.k;
        let base = c * t.stride;
        let last = base + t.count[c] as usize - 1;
        let cell = ((s * k as f32) as usize).min(k - 1);
        let mut i = base + t.cell[c * k + cell] as usize;
        while i + 1 < last && t.sig[i + 1] <= s {
            i += 1;
        }
        let (s0, s1) = (t.sig[i], t.sig[i + 1]);
        let h = s1 - s0;
        let a = if h > 0.0 { ((s - s0) / h).clamp(0.0, 1.0) } else { 0.0 };
        let (c0, c1) = (&t.centre[i], &t.centre[i + 1]);
        let (q0, q1) = (&t.quat[i], &t.quat[i + 1]);
        let cen = [c0[0] + a * (c1[0] - c0[0]), c0[1] + a * (c1[1] - c0[1]), c0[2] + a * (c1[2] - c0[2])];
        let mut q = [
            q0[0] + a * (q1[0] - q0[0]),
            q0[1] + a * (q1[1] - q0[1]),
            q0[2] + a * (q1[2] - q0[2]),
            q0[3] + a * (q1[3] - q0[3]),
        ];
        let inv = 1.0 / (q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]).sqrt();
        for x in q.iter_mut() {
            *x *= inv;
        }
        let sc = t.scale[i] + a * (t.scale[i + 1] - t.scale[i]);
        (cen, q, sc)
    }

    /// Exact evaluation in f64, returned in f32 (the `table_samples = 0` path).
    fn exact(&self, c: usize, s: f32) -> ([f32; 3], [f32; 4], f32) {
        let (centre, rot, scale) = self.frames[c].eval(s as f64, &self.skeleton.curves[c].twist);
        let q = rot.quaternion();
        (
            [centre.x as f32, centre.y as f32, centre.z as f32],
            [q.w as f32, q.i as f32, q.j as f32, q.k as f32],
            scale as f32,
        )
    }
}

impl Skinner for CurveSkin {
    fn prepare(&mut self, sk: &SkinSkeleton, posed: &[Iso3]) -> Result<()> {
        if sk.is_empty() {
            return Err(SkinError::EmptySkeleton);
        }
        if posed.len() != sk.len() {
            return Err(SkinError::Size { what: "posed frames", expected: sk.len(), got: posed.len() });
        }
        let mut diag = CurveDiagnostics::default();
        for (i, c) in self.skeleton.curves.iter().enumerate() {
            let choice = match self.twist_hint.get(c.joint).copied().flatten() {
                Some(h) => TwistChoice::Hint(h),
                None if self.opts.twist_unwrap => TwistChoice::Unwrap,
                None => TwistChoice::Principal,
            };
            let (f, h) = CurveFrame::new(c, &self.rigs[i], posed, &self.hist[i], choice, self.opts.volume_comp);
            if f.cap_hit {
                diag.cap_hits += 1;
            }
            diag.max_beta = diag.max_beta.max(f.beta);
            self.frames[i] = f;
            self.hist[i] = h;
        }
        self.diag = diag;
        self.build_tables();
        Ok(())
    }

    fn len(&self) -> usize {
        self.binding.len()
    }

    fn deform_range(&self, range: Range<usize>, out: DeformOutput<'_>) {
        assert_eq!(out.positions.len(), range.len(), "curve skin: output length");
        let offs = &self.binding.offsets;
        let table = self.tab.k > 0;
        let mut nout = out.normals;
        for (i, v) in range.enumerate() {
            let (a, b) = (offs[v] as usize, offs[v + 1] as usize);
            let mut p = [0f32; 3];
            let mut n = [0f32; 3];
            for e in a..b {
                let c = self.e_curve[e] as usize;
                let s = self.e_sigma[e];
                let (cen, q, sc) = if table { self.lookup(c, s) } else { self.exact(c, s) };
                let l = self.e_local[e];
                let r = qrot(&q, [l[0] * sc, l[1] * sc, l[2] * sc]);
                let w = self.e_w[e];
                p[0] += w * (cen[0] + r[0]);
                p[1] += w * (cen[1] + r[1]);
                p[2] += w * (cen[2] + r[2]);
                if nout.is_some() {
                    if let Some(nl) = &self.e_nlocal {
                        let rn = qrot(&q, nl[e]);
                        n[0] += w * rn[0];
                        n[1] += w * rn[1];
                        n[2] += w * rn[2];
                    }
                }
            }
            out.positions[i] = p;
            if let Some(no) = nout.as_deref_mut() {
                no[i] = normalize3(n);
            }
        }
    }
}

/// Writes one table sample (centre, hemisphere-aligned quaternion, scale) at `idx`.
fn push_sample(
    frame: &CurveFrame,
    twist: &super::types::TwistDistribution,
    t: &mut Tables,
    idx: usize,
    s: f64,
    prev_q: &mut Option<[f32; 4]>,
) {
    let (centre, rot, scale) = frame.eval(s, twist);
    let q = rot.quaternion();
    let mut qa = [q.w as f32, q.i as f32, q.j as f32, q.k as f32];
    if let Some(p) = prev_q {
        if p[0] * qa[0] + p[1] * qa[1] + p[2] * qa[2] + p[3] * qa[3] < 0.0 {
            qa = [-qa[0], -qa[1], -qa[2], -qa[3]];
        }
    }
    *prev_q = Some(qa);
    t.sig[idx] = s as f32;
    t.centre[idx] = [centre.x as f32, centre.y as f32, centre.z as f32];
    t.quat[idx] = qa;
    t.scale[idx] = scale as f32;
}

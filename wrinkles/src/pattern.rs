//! Wrinkle patterns (spec §3.2): a scalar height field `S(uv)` given as an image approximated by
//! a C² cubic B-spline (or C¹ Catmull–Rom), or as an analytic procedural function, with its
//! analytic gradient `∇_uv S`. The physical wrinkle function on a triangle is `f = η·(S − offset)`,
//! with `η` fixed by [`Normalization`] at precomputation time ([`crate::precompute`]).

use std::path::PathBuf;

use geom_core::image::{gaussian_blur, read_png, Border, ImageF32};
use geom_core::math::{Pt2, Vec2};
use geom_core::rng::Rng;
use serde::{Deserialize, Serialize};

use crate::error::{Result, WrinkleError};

/// Where a pattern's height field comes from.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub enum PatternSource {
    /// A PNG file (8/16-bit gray or RGB, converted to luminance in [0, 1]).
    Png {
        /// File path.
        path: PathBuf,
    },
    /// An image already in memory (luminance, any range).
    #[serde(skip)]
    Image(ImageF32),
    /// An analytic pattern.
    Procedural(Procedural),
}

/// Analytic patterns (unit amplitude; wavelengths in transformed-UV units, angles in degrees from
/// the u axis, phases in radians).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum Procedural {
    /// `S = sin(2π k̂·uv/λ + phase)`, `k̂ = (cos angle, sin angle)` (wave vector; crests are
    /// perpendicular to it).
    Sinusoid {
        /// Wavelength λ (> 0).
        wavelength_uv: f64,
        /// Direction of the wave vector (degrees).
        angle_deg: f64,
        /// Phase (radians).
        phase: f64,
    },
    /// `count` sinusoids with wave vectors spread by ±`spread_deg` around `angle_deg`, wavelengths
    /// and amplitudes jittered by ±`irregularity`/2, random phases (seeded [`Rng`]), multiplied by a
    /// smooth envelope `1 + ½·irregularity·sin(…)` varying along the crests over 3λ, so folds fade
    /// in and out. Normalised by the sum of amplitudes.
    Folds {
        /// Mean wavelength λ (> 0).
        wavelength_uv: f64,
        /// Mean wave-vector direction (degrees).
        angle_deg: f64,
        /// Half-range of the direction jitter (degrees).
        spread_deg: f64,
        /// Number of sinusoids (≥ 1).
        count: u32,
        /// Jitter of wavelength/amplitude and envelope depth, in [0, 1].
        irregularity: f64,
        /// Seed of the jitter.
        seed: u64,
    },
    /// Rings around a tube whose UV `v` runs along its axis: `S = sin(2π v/λ)`.
    Rings {
        /// Wavelength λ (> 0).
        wavelength_uv: f64,
    },
    /// An affine ramp `S = gradient·uv` (constant gradient; closed-form coefficients, test T1).
    /// Offsets are not applied to it (its mean and minimum are unbounded).
    Ramp {
        /// ∇_uv S.
        gradient: [f64; 2],
    },
    /// A constant (no wrinkles): the degenerate case of spec §8.
    Constant {
        /// The value.
        value: f64,
    },
}

/// How the height scale η (m) is chosen (spec §3.2 item 3).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub enum Normalization {
    /// η given in metres.
    Metres(f64),
    /// η = slope / (largest rest slope of S over the mesh), so that max |g| = the given slope.
    TargetRestSlope(f64),
    /// η = φ · mean rest edge length.
    FractionOfEdge(f64),
}

/// Image pattern interpolant. Bilinear is deliberately absent: its gradient is discontinuous.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum SplineKind {
    /// Uniform cubic B-spline with the texels as control values: C², smoothing.
    #[default]
    CubicBSpline,
    /// Catmull–Rom: C¹, interpolates the texels.
    CatmullRom,
}

/// Texture addressing of image patterns.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum Wrap {
    /// Periodic.
    #[default]
    Repeat,
    /// Edge texels extend outward.
    Clamp,
}

/// Displacement sidedness: what constant is subtracted from `S`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum Offset {
    /// Subtract the mean (bulges on both sides).
    #[default]
    ZeroMean,
    /// Subtract the minimum (f ≥ 0: outward only).
    OutwardOnly,
}

/// Affine map applied to mesh UVs before the pattern is evaluated: `uv' = R(rotation)·(scale ⊙ uv)
/// + offset`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct UvTransform {
    /// Per-axis scale (non-zero).
    pub scale: [f64; 2],
    /// Rotation (degrees, counter-clockwise).
    pub rotation_deg: f64,
    /// Offset after rotation.
    pub offset: [f64; 2],
}

impl Default for UvTransform {
    fn default() -> Self {
        Self { scale: [1.0, 1.0], rotation_deg: 0.0, offset: [0.0, 0.0] }
    }
}

impl UvTransform {
    fn apply(&self, uv: &Pt2) -> Vec2 {
        let (s, c) = self.rotation_deg.to_radians().sin_cos();
        let x = self.scale[0] * uv.x;
        let y = self.scale[1] * uv.y;
        Vec2::new(c * x - s * y + self.offset[0], s * x + c * y + self.offset[1])
    }
    /// `∇_uv = diag(scale)·Rᵀ·∇_uv'`.
    fn pull_grad(&self, g: &Vec2) -> Vec2 {
        let (s, c) = self.rotation_deg.to_radians().sin_cos();
        Vec2::new(self.scale[0] * (c * g.x + s * g.y), self.scale[1] * (-s * g.x + c * g.y))
    }
}

/// Pattern options (spec §2).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct PatternOptions {
    /// Height scale rule.
    pub normalization: Normalization,
    /// Gaussian pre-blur σ of image patterns (texels, ≥ 0; 0 = none).
    pub blur_texels: f64,
    /// Image interpolant.
    pub spline: SplineKind,
    /// Image addressing.
    pub wrap: Wrap,
    /// UV transform.
    pub uv_transform: UvTransform,
    /// Sidedness.
    pub offset: Offset,
}

impl Default for PatternOptions {
    fn default() -> Self {
        Self {
            normalization: Normalization::TargetRestSlope(0.5),
            blur_texels: 1.0,
            spline: SplineKind::CubicBSpline,
            wrap: Wrap::Repeat,
            uv_transform: UvTransform::default(),
            offset: Offset::ZeroMean,
        }
    }
}

#[derive(Clone, Debug)]
enum Kind {
    /// Single sinusoid with wave vector `k` (rad per uv' unit) and phase.
    Wave {
        k: Vec2,
        phase: f64,
    },
    Folds {
        comps: Vec<(Vec2, f64, f64)>,
        env_k: Vec2,
        env_phase: f64,
        env_amp: f64,
        norm: f64,
    },
    Ramp(Vec2),
    Constant(f64),
    Image {
        img: ImageF32,
        spline: SplineKind,
        wrap: Wrap,
    },
}

/// A pattern ready for evaluation: `eval(uv) = S(uv) − offset`, `grad_uv(uv) = ∇_uv S`.
#[derive(Clone, Debug)]
pub struct WrinklePattern {
    kind: Kind,
    /// The options the pattern was built with.
    pub options: PatternOptions,
    offset_value: f64,
}

fn check_pos(name: &str, v: f64) -> Result<()> {
    if v > 0.0 && v.is_finite() {
        Ok(())
    } else {
        Err(WrinkleError::InvalidOption(format!("{name} must be positive and finite, got {v}")))
    }
}

/// Spline weights and derivative weights at fraction τ ∈ [0, 1) for taps i0−1 … i0+2.
fn basis(kind: SplineKind, t: f64) -> ([f64; 4], [f64; 4]) {
    let (t2, t3) = (t * t, t * t * t);
    match kind {
        SplineKind::CubicBSpline => {
            let u = 1.0 - t;
            (
                [
                    u * u * u / 6.0,
                    (3.0 * t3 - 6.0 * t2 + 4.0) / 6.0,
                    (-3.0 * t3 + 3.0 * t2 + 3.0 * t + 1.0) / 6.0,
                    t3 / 6.0,
                ],
                [-0.5 * u * u, 1.5 * t2 - 2.0 * t, -1.5 * t2 + t + 0.5, 0.5 * t2],
            )
        }
        SplineKind::CatmullRom => (
            [
                0.5 * (-t3 + 2.0 * t2 - t),
                0.5 * (3.0 * t3 - 5.0 * t2 + 2.0),
                0.5 * (-3.0 * t3 + 4.0 * t2 + t),
                0.5 * (t3 - t2),
            ],
            [
                0.5 * (-3.0 * t2 + 4.0 * t - 1.0),
                0.5 * (9.0 * t2 - 10.0 * t),
                0.5 * (-9.0 * t2 + 8.0 * t + 1.0),
                0.5 * (3.0 * t2 - 2.0 * t),
            ],
        ),
    }
}

fn tap(i: i64, n: u32, wrap: Wrap) -> u32 {
    match wrap {
        Wrap::Repeat => i.rem_euclid(n as i64) as u32,
        Wrap::Clamp => i.clamp(0, n as i64 - 1) as u32,
    }
}

/// Spline value and gradient in texture units (the image spans [0, 1]², texel `(i, j)` centred at
/// `((i+½)/W, (j+½)/H)`, row 0 at t = 0).
fn spline_eval(img: &ImageF32, kind: SplineKind, wrap: Wrap, s: f64, t: f64) -> (f64, Vec2) {
    let x = s * img.width as f64 - 0.5;
    let y = t * img.height as f64 - 0.5;
    let (ix, iy) = (x.floor(), y.floor());
    let (bx, dbx) = basis(kind, x - ix);
    let (by, dby) = basis(kind, y - iy);
    let (ix, iy) = (ix as i64, iy as i64);
    let (mut v, mut gx, mut gy) = (0.0, 0.0, 0.0);
    for b in 0..4 {
        let row = tap(iy + b as i64 - 1, img.height, wrap);
        let (mut r, mut dr) = (0.0, 0.0);
        for a in 0..4 {
            let c = img.at(tap(ix + a as i64 - 1, img.width, wrap), row) as f64;
            r += bx[a] * c;
            dr += dbx[a] * c;
        }
        v += by[b] * r;
        gx += by[b] * dr;
        gy += dby[b] * r;
    }
    (v, Vec2::new(gx * img.width as f64, gy * img.height as f64))
}

impl WrinklePattern {
    /// Builds a pattern: loads/blurs images, draws the `Folds` jitter, fixes the offset constant.
    ///
    /// Errors: [`WrinkleError::PatternIo`] for unreadable files, [`WrinkleError::InvalidOption`]
    /// for non-positive wavelengths, zero `count`, negative blur, empty images, zero UV scale.
    pub fn new(source: &PatternSource, options: PatternOptions) -> Result<Self> {
        if !(options.blur_texels >= 0.0 && options.blur_texels.is_finite()) {
            return Err(WrinkleError::InvalidOption(format!("blur_texels must be ≥ 0, got {}", options.blur_texels)));
        }
        let tr = &options.uv_transform;
        if !tr.scale.iter().all(|s| *s != 0.0 && s.is_finite())
            || !tr.rotation_deg.is_finite()
            || !tr.offset.iter().all(|o| o.is_finite())
        {
            return Err(WrinkleError::InvalidOption(format!(
                "uv_transform must be finite with non-zero scale, got {tr:?}"
            )));
        }
        match options.normalization {
            Normalization::Metres(v) | Normalization::TargetRestSlope(v) | Normalization::FractionOfEdge(v) => {
                check_pos("normalization value", v)?
            }
        }
        let dir = |deg: f64| {
            let (s, c) = deg.to_radians().sin_cos();
            Vec2::new(c, s)
        };
        let tau = std::f64::consts::TAU;
        let (kind, mean, min) = match source {
            PatternSource::Procedural(Procedural::Sinusoid { wavelength_uv, angle_deg, phase }) => {
                check_pos("Sinusoid.wavelength_uv", *wavelength_uv)?;
                if !angle_deg.is_finite() || !phase.is_finite() {
                    return Err(WrinkleError::InvalidOption("Sinusoid angle/phase must be finite".into()));
                }
                (Kind::Wave { k: dir(*angle_deg) * (tau / wavelength_uv), phase: *phase }, 0.0, -1.0)
            }
            PatternSource::Procedural(Procedural::Rings { wavelength_uv }) => {
                check_pos("Rings.wavelength_uv", *wavelength_uv)?;
                (Kind::Wave { k: Vec2::new(0.0, tau / wavelength_uv), phase: 0.0 }, 0.0, -1.0)
            }
            PatternSource::Procedural(Procedural::Ramp { gradient }) => {
                if !gradient.iter().all(|g| g.is_finite()) {
                    return Err(WrinkleError::InvalidOption(format!("Ramp.gradient must be finite, got {gradient:?}")));
                }
                (Kind::Ramp(Vec2::new(gradient[0], gradient[1])), 0.0, 0.0)
            }
            PatternSource::Procedural(Procedural::Constant { value }) => {
                if !value.is_finite() {
                    return Err(WrinkleError::InvalidOption(format!("Constant.value must be finite, got {value}")));
                }
                (Kind::Constant(*value), *value, *value)
            }
            PatternSource::Procedural(Procedural::Folds {
                wavelength_uv,
                angle_deg,
                spread_deg,
                count,
                irregularity,
                seed,
            }) => {
                check_pos("Folds.wavelength_uv", *wavelength_uv)?;
                if *count == 0 {
                    return Err(WrinkleError::InvalidOption("Folds.count must be ≥ 1".into()));
                }
                if !(0.0..=1.0).contains(irregularity) || !angle_deg.is_finite() || !spread_deg.is_finite() {
                    return Err(WrinkleError::InvalidOption(format!(
                        "Folds: irregularity must be in [0, 1] and angles finite, got irregularity {irregularity}"
                    )));
                }
                let mut rng = Rng::new(*seed);
                let mut comps = Vec::new();
                let mut norm = 0.0;
                for _ in 0..*count {
                    let ang = angle_deg + spread_deg * rng.range(-1.0, 1.0);
                    let lam = wavelength_uv * (1.0 + irregularity * rng.range(-0.5, 0.5));
                    let phase = tau * rng.f64();
                    let amp = 1.0 + irregularity * rng.range(-0.5, 0.5);
                    norm += amp;
                    comps.push((dir(ang) * (tau / lam), phase, amp));
                }
                let env_k = dir(angle_deg + 90.0) * (tau / (3.0 * wavelength_uv));
                let env_phase = tau * rng.f64();
                let env_amp = 0.5 * irregularity;
                // Mean 0 by construction (sinusoids with random phases); min bounded by −(1 + env_amp).
                (Kind::Folds { comps, env_k, env_phase, env_amp, norm }, 0.0, -(1.0 + env_amp))
            }
            PatternSource::Png { path } => {
                let img = read_png(path).map_err(|e| WrinkleError::PatternIo(format!("{}: {e}", path.display())))?;
                Self::image_kind(img, &options)?
            }
            PatternSource::Image(img) => Self::image_kind(img.clone(), &options)?,
        };
        let offset_value = match options.offset {
            Offset::ZeroMean => mean,
            Offset::OutwardOnly => min,
        };
        Ok(Self { kind, options, offset_value })
    }

    fn image_kind(img: ImageF32, o: &PatternOptions) -> Result<(Kind, f64, f64)> {
        if img.width == 0 || img.height == 0 || img.data.len() != (img.width * img.height) as usize {
            return Err(WrinkleError::InvalidOption("pattern image is empty or malformed".into()));
        }
        if let Some(i) = img.data.iter().position(|v| !v.is_finite()) {
            return Err(WrinkleError::InvalidOption(format!("pattern image texel {i} is not finite")));
        }
        let border = match o.wrap {
            Wrap::Repeat => Border::Wrap,
            Wrap::Clamp => Border::Clamp,
        };
        let img = if o.blur_texels > 0.0 { gaussian_blur(&img, o.blur_texels, border) } else { img };
        let mean = img.data.iter().map(|v| *v as f64).sum::<f64>() / img.data.len() as f64;
        let min = img.data.iter().fold(f64::INFINITY, |m, v| m.min(*v as f64));
        Ok((Kind::Image { img, spline: o.spline, wrap: o.wrap }, mean, min))
    }

    /// `S(uv) − offset` and `∇_uv S` at mesh UV `uv`.
    pub fn eval_grad(&self, uv: &Pt2) -> (f64, Vec2) {
        let tr = &self.options.uv_transform;
        let p = tr.apply(uv);
        let (v, g) = match &self.kind {
            Kind::Wave { k, phase } => {
                let (s, c) = (k.dot(&p) + phase).sin_cos();
                (s, k * c)
            }
            Kind::Folds { comps, env_k, env_phase, env_amp, norm } => {
                let (mut s, mut gs) = (0.0, Vec2::zeros());
                for (k, ph, a) in comps {
                    let (sn, cs) = (k.dot(&p) + ph).sin_cos();
                    s += a * sn;
                    gs += k * (a * cs);
                }
                let (es, ec) = (env_k.dot(&p) + env_phase).sin_cos();
                let e = 1.0 + env_amp * es;
                let ge = env_k * (env_amp * ec);
                (e * s / norm, (gs * e + ge * s) / *norm)
            }
            Kind::Ramp(g) => (g.dot(&p), *g),
            Kind::Constant(c) => (*c, Vec2::zeros()),
            Kind::Image { img, spline, wrap } => spline_eval(img, *spline, *wrap, p.x, p.y),
        };
        (v - self.offset_value, tr.pull_grad(&g))
    }

    /// `S(uv) − offset`.
    pub fn eval(&self, uv: &Pt2) -> f64 {
        self.eval_grad(uv).0
    }

    /// `∇_uv S`.
    pub fn grad_uv(&self, uv: &Pt2) -> Vec2 {
        self.eval_grad(uv).1
    }

    /// Whether the pattern is constant everywhere (all coefficients vanish).
    pub fn is_constant(&self) -> bool {
        match &self.kind {
            Kind::Constant(_) => true,
            Kind::Ramp(g) => *g == Vec2::zeros(),
            Kind::Image { img, .. } => img.data.iter().all(|v| *v == img.data[0]),
            _ => false,
        }
    }

    /// For single-direction patterns, the constant gradient direction scale `c` with
    /// `∇_uv S = c·cos(…)` (so max |Jᵀ∇S| = |Jᵀc| exactly); `None` otherwise.
    pub(crate) fn wave_vector_uv(&self) -> Option<Vec2> {
        match &self.kind {
            Kind::Wave { k, .. } | Kind::Ramp(k) => Some(self.options.uv_transform.pull_grad(k)),
            _ => None,
        }
    }

    /// Largest |∇_uv S| over the UV box `[lo, hi]`, sampled on a grid of spacing ≤ ¼ of the
    /// pattern's feature length (texel or shortest wavelength), at most 512² samples so the cost
    /// stays a few ms: an estimate within a few per cent for smooth patterns. Exact for single
    /// waves and ramps.
    pub fn max_grad_uv(&self, lo: Pt2, hi: Pt2) -> f64 {
        if let Some(c) = self.wave_vector_uv() {
            return c.norm();
        }
        let tr = &self.options.uv_transform;
        let smax = tr.scale[0].abs().max(tr.scale[1].abs());
        let feature = match &self.kind {
            Kind::Constant(_) => return 0.0,
            Kind::Folds { comps, .. } => {
                comps.iter().map(|(k, _, _)| std::f64::consts::TAU / k.norm()).fold(f64::INFINITY, f64::min)
            }
            Kind::Image { img, .. } => 1.0 / img.width.max(img.height) as f64,
            Kind::Wave { .. } | Kind::Ramp(_) => unreachable!("handled above by wave_vector_uv"),
        } / smax;
        let (w, h) = ((hi.x - lo.x).max(0.0), (hi.y - lo.y).max(0.0));
        let nx = ((4.0 * w / feature).ceil() as usize).clamp(1, 512);
        let ny = ((4.0 * h / feature).ceil() as usize).clamp(1, 512);
        let mut m: f64 = 0.0;
        for j in 0..=ny {
            for i in 0..=nx {
                let uv = Pt2::new(lo.x + w * i as f64 / nx as f64, lo.y + h * j as f64 / ny as f64);
                m = m.max(self.grad_uv(&uv).norm());
            }
        }
        m
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn img_pattern(w: u32, h: u32, f: impl Fn(u32, u32) -> f32, spline: SplineKind, wrap: Wrap) -> WrinklePattern {
        let mut img = ImageF32::new(w, h, 0.0);
        for y in 0..h {
            for x in 0..w {
                img.set(x, y, f(x, y));
            }
        }
        let o = PatternOptions { blur_texels: 0.0, spline, wrap, ..Default::default() };
        WrinklePattern::new(&PatternSource::Image(img), o).unwrap()
    }

    /// T19: the B-spline reproduces constants and linear ramps exactly (away from clamped borders);
    /// its gradient is continuous across texel cells.
    #[test]
    fn t19_bspline_reproduces_linear_and_is_continuous() {
        let n = 16;
        let p =
            img_pattern(n, n, |x, y| 0.3 + 0.01 * x as f32 + 0.02 * y as f32, SplineKind::CubicBSpline, Wrap::Clamp);
        // Mean of the ramp is subtracted (ZeroMean); compare differences and the gradient.
        let at = |s: f64, t: f64| p.eval_grad(&Pt2::new(s, t));
        let (v0, _) = at(0.5, 0.5);
        for (s, t) in [(0.3, 0.4), (0.61, 0.7), (0.45, 0.33)] {
            let (v, g) = at(s, t);
            // value in texel units: 0.01·(s·16 − 0.5) + 0.02·(t·16 − 0.5)
            let dv = 0.01 * (s - 0.5) * 16.0 + 0.02 * (t - 0.5) * 16.0;
            assert!((v - v0 - dv).abs() < 1e-6, "ramp {v} {v0} {dv}"); // f32 texels: 1e-6
            assert!((g - Vec2::new(0.16, 0.32)).norm() < 1e-6);
        }
        // Constant reproduced exactly, and flagged constant.
        let c = img_pattern(8, 8, |_, _| 0.7, SplineKind::CubicBSpline, Wrap::Repeat);
        assert!(c.is_constant());
        assert!(c.eval(&Pt2::new(0.37, 0.81)).abs() < 1e-10);
        // Continuity of the gradient across a cell boundary (x = 5 + ½ texel centres → s = 6/16).
        let r = img_pattern(16, 16, |x, y| ((x * 7 + y * 3) % 5) as f32 * 0.2, SplineKind::CubicBSpline, Wrap::Repeat);
        let eps = 1e-9;
        for kind in [SplineKind::CubicBSpline, SplineKind::CatmullRom] {
            let r = WrinklePattern {
                kind: match &r.kind {
                    Kind::Image { img, wrap, .. } => Kind::Image { img: img.clone(), spline: kind, wrap: *wrap },
                    _ => unreachable!(),
                },
                ..r.clone()
            };
            let s = 6.0 / 16.0;
            let (va, ga) = r.eval_grad(&Pt2::new(s - eps, 0.41));
            let (vb, gb) = r.eval_grad(&Pt2::new(s + eps, 0.41));
            assert!((va - vb).abs() < 1e-6);
            assert!((ga - gb).norm() < 1e-5 * ga.norm().max(1.0), "{kind:?}");
        }
    }

    #[test]
    fn procedural_gradients_match_finite_differences() {
        let srcs = [
            Procedural::Sinusoid { wavelength_uv: 0.1, angle_deg: 30.0, phase: 0.3 },
            Procedural::Folds {
                wavelength_uv: 0.08,
                angle_deg: 10.0,
                spread_deg: 8.0,
                count: 4,
                irregularity: 0.3,
                seed: 7,
            },
            Procedural::Rings { wavelength_uv: 0.05 },
        ];
        let o = PatternOptions {
            uv_transform: UvTransform { scale: [1.3, 0.7], rotation_deg: 20.0, offset: [0.1, 0.2] },
            ..Default::default()
        };
        for s in srcs {
            let p = WrinklePattern::new(&PatternSource::Procedural(s.clone()), o.clone()).unwrap();
            let uv = Pt2::new(0.23, 0.41);
            let h = 1e-6;
            let g = p.grad_uv(&uv);
            let fd = Vec2::new(
                (p.eval(&Pt2::new(uv.x + h, uv.y)) - p.eval(&Pt2::new(uv.x - h, uv.y))) / (2.0 * h),
                (p.eval(&Pt2::new(uv.x, uv.y + h)) - p.eval(&Pt2::new(uv.x, uv.y - h))) / (2.0 * h),
            );
            // Central difference error O(h²·|S'''|) ≈ 1e-12·(2π/0.05)³ ≈ 2e-6, plus round-off 1e-10/h.
            assert!((g - fd).norm() < 1e-5 * g.norm().max(1.0), "{s:?}: {g} vs {fd}");
        }
    }

    #[test]
    fn bad_options_are_errors() {
        let bad = PatternSource::Procedural(Procedural::Sinusoid { wavelength_uv: 0.0, angle_deg: 0.0, phase: 0.0 });
        assert!(matches!(WrinklePattern::new(&bad, PatternOptions::default()), Err(WrinkleError::InvalidOption(_))));
        let missing = PatternSource::Png { path: "/nonexistent/pattern.png".into() };
        assert!(matches!(WrinklePattern::new(&missing, PatternOptions::default()), Err(WrinkleError::PatternIo(_))));
    }
}

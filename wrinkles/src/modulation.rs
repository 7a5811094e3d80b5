//! Per-triangle modulation factors: the paper's linearised area conservation (spec §3.5) and
//! the exact modes (spec §3.6, ours).

use geom_core::math::{sym_eig2, Mat2};
use serde::{Deserialize, Serialize};

use crate::coeffs::{CoeffStatus, GradientSamples, TriCoeffs};
use crate::frames::Deformation;

/// Strain measure of the linearised mode.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum StrainMeasure {
    /// `h = 1 − ⟨K, E⟩/C4`, E the Green strain: frame-free (default).
    #[default]
    Green,
    /// The paper's `h = 1 − [C1(a−1) + C2 b + C3(d−1)]/C4` with edge 0 as x axis.
    PaperAbd,
}

/// The modulation law.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub enum ModulationMode {
    /// Paper: first-order area conservation about the wrinkled rest state (h = 1 at rest).
    Linearized {
        /// Strain measure.
        strain: StrainMeasure,
    },
    /// The paper's condition `A_t(C, h) = A_T^w` solved exactly (ours).
    ExactWrinkledRest,
    /// Flat at rest, conserve the flat rest area `A_t(C, h) = A_T` (ours; garment default).
    ExactFlatRest,
    /// Conserve the mean length along the most compressed principal direction (ours).
    PrincipalLength,
}

impl ModulationMode {
    /// The modulation of an unaffected (constant/degenerate) triangle: 1 in paper modes, 0 in
    /// flat modes (spec §3.7).
    pub fn identity_value(self) -> f64 {
        match self {
            ModulationMode::Linearized { .. } | ModulationMode::ExactWrinkledRest => 1.0,
            ModulationMode::ExactFlatRest | ModulationMode::PrincipalLength => 0.0,
        }
    }
}

/// Linearised modulation factor (unclipped). Constant/degenerate triangles give 1.
pub fn h_linear(c: &TriCoeffs, d: &Deformation, strain: StrainMeasure) -> f64 {
    if !c.status.is_active() {
        return 1.0;
    }
    match strain {
        StrainMeasure::Green => {
            let e = d.green();
            let ke = c.k[(0, 0)] * e[(0, 0)] + 2.0 * c.k[(0, 1)] * e[(0, 1)] + c.k[(1, 1)] * e[(1, 1)];
            1.0 - ke / c.c4
        }
        StrainMeasure::PaperAbd => {
            let (a, b, dd) = d.paper_abd();
            1.0 - (c.k[(0, 0)] * (a - 1.0) + c.k[(0, 1)] * b + c.k[(1, 1)] * (dd - 1.0)) / c.c4
        }
    }
}

/// Outcome of one exact solve.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ExactSolve {
    /// The root h ≥ 0 (before clipping to h_max).
    pub h: f64,
    /// Newton iterations used.
    pub iterations: u32,
    /// The Newton cap was hit and bisection finished the job.
    pub bisected: bool,
    /// No variation of the pattern is visible under this deformation (h = 0 returned).
    pub no_solution: bool,
    /// |Φ(h)|/A*.
    pub rel_residual: f64,
}

/// `Φ(h) = Σ w_s √(δ + h² q_s) − A*` and `Φ'(h)`.
fn phi(w: &[f64], q: &[f64], delta: f64, a_star: f64, h: f64) -> (f64, f64) {
    let (mut v, mut dv) = (0.0, 0.0);
    for (w, q) in w.iter().zip(q) {
        let r = (delta + h * h * q).sqrt();
        v += w * r;
        if r > 0.0 {
            dv += w * h * q / r;
        }
    }
    (v - a_star, dv)
}

/// Solves `Φ(h) = 0`, h ≥ 0 (spec §3.6 steps 1–4): 0 when Φ(0) ≥ 0; otherwise Newton from
/// `h_hi = A*/Σw√q` (monotone from the right by convexity), bisection on [0, h_hi] if the cap
/// is hit. `trace` receives every Newton iterate.
pub fn solve_exact(
    w: &[f64],
    q: &[f64],
    delta: f64,
    a_star: f64,
    tol: f64,
    max_iter: u32,
    mut trace: Option<&mut Vec<f64>>,
) -> ExactSolve {
    let delta = delta.max(0.0);
    let area: f64 = w.iter().sum();
    let phi0 = delta.sqrt() * area - a_star;
    // A deficit below the solver tolerance needs no wrinkles: h = 0 already meets |Φ| ≤ tol·A*
    // (makes h exactly 0 under area-preserving shear despite det C rounding to 1 − ε).
    if phi0 >= -tol * a_star {
        return ExactSolve {
            h: 0.0,
            iterations: 0,
            bisected: false,
            no_solution: false,
            rel_residual: phi0.max(0.0) / a_star,
        };
    }
    let den: f64 = w.iter().zip(q).map(|(w, q)| w * q.max(0.0).sqrt()).sum();
    if den.is_nan() || den <= 0.0 {
        return ExactSolve {
            h: 0.0,
            iterations: 0,
            bisected: false,
            no_solution: true,
            rel_residual: phi0.abs() / a_star,
        };
    }
    let h_hi = a_star / den;
    let mut h = h_hi;
    let mut it = 0;
    if let Some(t) = trace.as_deref_mut() {
        t.push(h);
    }
    loop {
        let (v, dv) = phi(w, q, delta, a_star, h);
        if v.abs() <= tol * a_star {
            return ExactSolve {
                h,
                iterations: it,
                bisected: false,
                no_solution: false,
                rel_residual: v.abs() / a_star,
            };
        }
        if it >= max_iter || dv.is_nan() || dv <= 0.0 {
            break;
        }
        // Convexity: the step from the right never overshoots; clamp at 0 against round-off.
        h = (h - v / dv).max(0.0);
        it += 1;
        if let Some(t) = trace.as_deref_mut() {
            t.push(h);
        }
    }
    let (mut lo, mut hi) = (0.0, h_hi);
    let mut v = 0.0;
    for _ in 0..200 {
        let m = 0.5 * (lo + hi);
        v = phi(w, q, delta, a_star, m).0;
        if v < 0.0 {
            lo = m;
        } else {
            hi = m;
        }
        if v.abs() <= tol * a_star || hi - lo <= f64::EPSILON * hi {
            break;
        }
    }
    ExactSolve {
        h: 0.5 * (lo + hi),
        iterations: it,
        bisected: true,
        no_solution: false,
        rel_residual: v.abs() / a_star,
    }
}

/// The `(δ, q_s, A*)` of an exact mode for triangle samples `gs` under right Cauchy–Green tensor
/// `c` (spec §3.6 table); `collapsed` forces δ = 0 (inverted triangles, §3.7).
pub fn exact_terms(
    mode: ModulationMode,
    gs: &GradientSamples,
    c: &Mat2,
    collapsed: bool,
    q: &mut Vec<f64>,
) -> (f64, f64) {
    q.clear();
    match mode {
        ModulationMode::PrincipalLength => {
            let (l, v) = sym_eig2(c);
            let r2 = v.column(0).into_owned();
            q.extend(gs.g.iter().map(|g| g.dot(&r2).powi(2)));
            (if collapsed { 0.0 } else { l[0].max(0.0) }, gs.area_flat)
        }
        _ => {
            let adj = Mat2::new(c[(1, 1)], -c[(0, 1)], -c[(1, 0)], c[(0, 0)]);
            q.extend(gs.g.iter().map(|g| (g.transpose() * adj * g)[(0, 0)].max(0.0)));
            let delta = if collapsed { 0.0 } else { c.determinant().max(0.0) };
            let a_star = if mode == ModulationMode::ExactWrinkledRest { gs.area_wrinkled } else { gs.area_flat };
            (delta, a_star)
        }
    }
}

/// Exact area `A_t(C, h) = ∫√(det C + h² gᵀ adj(C) g)` from gradient samples (spec §3.4).
pub fn wrinkled_area(gs: &GradientSamples, c: &Mat2, h: f64) -> f64 {
    let adj = Mat2::new(c[(1, 1)], -c[(0, 1)], -c[(1, 0)], c[(0, 0)]);
    let det = c.determinant().max(0.0);
    gs.g.iter().zip(&gs.w).map(|(g, w)| w * (det + h * h * (g.transpose() * adj * g)[(0, 0)].max(0.0)).sqrt()).sum()
}

/// Raw (unclipped for the linear mode's upper side) modulation of one triangle and pattern.
/// Returns `(h, newton iterations, no_solution)`; inactive coefficients give the mode's identity.
pub fn modulate(
    mode: ModulationMode,
    c: &TriCoeffs,
    d: &Deformation,
    collapsed: bool,
    tol: f64,
    max_iter: u32,
    q: &mut Vec<f64>,
) -> (f64, u32, bool) {
    if !c.status.is_active() {
        return (mode.identity_value(), 0, false);
    }
    match mode {
        ModulationMode::Linearized { strain } if !collapsed => (h_linear(c, d, strain), 0, false),
        _ => {
            // The linear mode treats an inverted triangle as fully compressed (§3.7): the
            // wrinkled-rest root with δ = 0.
            let m = if matches!(mode, ModulationMode::Linearized { .. }) {
                ModulationMode::ExactWrinkledRest
            } else {
                mode
            };
            let (delta, a_star) = exact_terms(m, &c.grad_samples, &d.c, collapsed, q);
            let s = solve_exact(&c.grad_samples.w, q, delta, a_star, tol, max_iter, None);
            (s.h, s.iterations, s.no_solution)
        }
    }
}

/// Whether a status makes a triangle count for smoothing (only degenerate rest is excluded).
pub fn counts_for_smoothing(s: CoeffStatus) -> bool {
    s != CoeffStatus::DegenerateRest
}

//! Analytic solutions the scenes' figures are compared with: the bending-energy densities of the
//! calibration (Grinspun et al. 2003, Discrete Shells; shells.md §3.2), Euler–Bernoulli
//! cantilever formulas and plate rigidities (the cantilever scene).
//!
//! ```
//! use shells::reference::*;
//! // A moment 2πEI/L bends a beam of length L into a full circle (curvature M/EI = 2π/L).
//! let (ei, l) = (0.3, 0.95);
//! assert!((circle_moment(ei, l) / ei * l - 2.0 * std::f64::consts::PI).abs() < 1e-12);
//! // The load that deflects the tip by δ deflects it by δ.
//! let p = tip_load_for_deflection(0.01, l, ei);
//! assert!((tip_deflection(p, l, ei) - 0.01).abs() < 1e-15);
//! ```

/// Interior bending-energy density of a surface wrapped on a cylinder of radius R, in units of
/// k_B/R²: 3 (hinge energy k_B·3|ē|²/(Ā₁+Ā₂)·(Δθ)², eq. 3 of Grinspun et al. 2003, summed per
/// area; shells.md §3.2).
pub const CYLINDER_DENSITY: f64 = 3.0;

/// The same on a sphere of radius R: 4 k_B/R² (both principal curvatures 1/R).
pub const SPHERE_DENSITY: f64 = 4.0;

/// Plate rigidity EI = 6 k_B w (N·m²) of a strip of width w (m) bending cylindrically
/// (k_B = D/6 for plate rigidity D, shells.md §3.2).
pub fn plate_rigidity(k_b: f64, width: f64) -> f64 {
    6.0 * k_b * width
}

/// Rigidity EI = c k_B w (N·m²) of a free narrow strip with the lattice's own factor c
/// (`calib::strip_rigidity_factor`: 16/3 for equilateral Discrete Shells, whose bending Poisson
/// ratio is −1/3).
pub fn strip_rigidity(factor: f64, k_b: f64, width: f64) -> f64 {
    factor * k_b * width
}

/// End moment M = 2πEI/L (N·m) that bends a clamped beam of free length L (m) into a full
/// circle (Euler–Bernoulli: curvature M/EI).
pub fn circle_moment(ei: f64, length: f64) -> f64 {
    2.0 * std::f64::consts::PI * ei / length
}

/// Tip deflection δ = PL³/(3EI) (m) of a clamped beam of length L under a small tip load P (N).
pub fn tip_deflection(load: f64, length: f64, ei: f64) -> f64 {
    load * length.powi(3) / (3.0 * ei)
}

/// The tip load P = 3EIδ/L³ (N) that deflects a clamped beam's tip by δ (m).
pub fn tip_load_for_deflection(delta: f64, length: f64, ei: f64) -> f64 {
    3.0 * ei * delta / length.powi(3)
}

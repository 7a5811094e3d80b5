//! Shared fixtures for the integration tests.
#![allow(dead_code)]

use geom_core::math::Mat2;
use wrinkles::*;

/// A square of side `l` in the XY plane made of two triangles whose edge 0 is axis-aligned
/// (`wrinkles::presets::two_triangle_square`).
pub fn two_triangle_square(l: f64) -> RestMesh {
    presets::two_triangle_square(l).unwrap()
}

/// An `n × n` grid of side `l` in the XY plane, UV = (x, y) (`wrinkles::presets::sheet`).
pub fn grid_mesh(n: u32, l: f64) -> RestMesh {
    presets::sheet(n, l).unwrap()
}

/// A sinusoid of wavelength `lambda`, wave-vector angle `angle_deg`, phase 0, rest slope `s`.
pub fn sinusoid(lambda: f64, angle_deg: f64, s: f64) -> WrinklePattern {
    presets::sinusoid(lambda, angle_deg, s).unwrap()
}

/// Precompute options with all samples kept and a tight tolerance.
pub fn exact_opts(tol: f64) -> PrecomputeOptions {
    PrecomputeOptions { tolerance: tol, max_depth: 8, gradient_bins: 0, gradient_samples: true }
}

/// Deformed positions `p' = F·(x, y)` (z kept).
pub use wrinkles::presets::uniform as deform;

/// Modulation options for a mode with per-triangle output (no smoothing, one pattern).
pub fn mod_opts(mode: ModulationMode) -> ModulationOptions {
    ModulationOptions { mode, smoothing: Smoothing::PerTriangle, h_max: HMax::Fixed(1e6), ..Default::default() }
}

/// h of triangle `t`, pattern 0, for deformation `f` in a given mode.
pub fn h_of(rig: &WrinkleRig, mode: ModulationMode, f: &Mat2, t: usize) -> f64 {
    let mut a = WrinkleAnimator::new(rig.clone(), mod_opts(mode)).unwrap();
    let fm = a.frame(&deform(&rig.mesh, f)).unwrap();
    fm.tri_h[t * rig.n_patterns()]
}

/// The 1-D buckled-strip amplitude ratio A/λ (the one copy, in the crate).
#[allow(unused_imports)] // used by some of the test binaries that include this module
pub use wrinkles::reference::strip_amplitude;

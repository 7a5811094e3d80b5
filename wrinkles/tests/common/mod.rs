//! Shared fixtures for the integration tests.
#![allow(dead_code)]

use geom_core::math::{Mat2, Pt2, Pt3};
use geom_core::mesh::Uv;
use geom_core::procedural::{grid, Diagonals, GridSpec, Plane};
use wrinkles::*;

/// A square of side `l` in the XY plane made of two triangles whose edge 0 is axis-aligned
/// (`[0,1,2]` along +x, `[2,3,0]` along −x), UV = (x, y).
pub fn two_triangle_square(l: f64) -> RestMesh {
    let p = vec![Pt3::new(0.0, 0.0, 0.0), Pt3::new(l, 0.0, 0.0), Pt3::new(l, l, 0.0), Pt3::new(0.0, l, 0.0)];
    let uv = Uv::PerVertex(p.iter().map(|p| Pt2::new(p.x, p.y)).collect());
    RestMesh::new(p, vec![[0, 1, 2], [2, 3, 0]], uv).unwrap()
}

/// An `n × n` grid of side `l` in the XY plane, UV = (x, y) from the min corner.
pub fn grid_mesh(n: u32, l: f64) -> RestMesh {
    let m = grid(&GridSpec {
        quads: [n, n],
        size: [l, l],
        plane: Plane::XY,
        diagonals: Diagonals::Alternating,
        center: Pt3::new(0.5 * l, 0.5 * l, 0.0),
    })
    .unwrap();
    RestMesh::from_trimesh(&m).unwrap()
}

/// A sinusoid of wavelength `lambda`, wave-vector angle `angle_deg`, phase 0, rest slope `s`.
pub fn sinusoid(lambda: f64, angle_deg: f64, s: f64) -> WrinklePattern {
    WrinklePattern::new(
        &PatternSource::Procedural(Procedural::Sinusoid { wavelength_uv: lambda, angle_deg, phase: 0.0 }),
        PatternOptions { normalization: Normalization::TargetRestSlope(s), ..Default::default() },
    )
    .unwrap()
}

/// Precompute options with all samples kept and a tight tolerance.
pub fn exact_opts(tol: f64) -> PrecomputeOptions {
    PrecomputeOptions { tolerance: tol, max_depth: 8, gradient_bins: 0, gradient_samples: true }
}

/// Deformed positions `p' = F·(x, y)` (z kept).
pub fn deform(mesh: &RestMesh, f: &Mat2) -> Vec<Pt3> {
    mesh.positions
        .iter()
        .map(|p| {
            let q = f * geom_core::math::Vec2::new(p.x, p.y);
            Pt3::new(q.x, q.y, p.z)
        })
        .collect()
}

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

/// The 1-D buckled-strip amplitude ratio A/λ for compression c (flat rest, arc length kept):
/// mean_θ √(c² + (2πA/λ)² cos²θ) = 1 by bisection, with a 4096-point periodic midpoint rule
/// (spectrally accurate for this analytic periodic integrand).
pub fn strip_amplitude(c: f64) -> f64 {
    let n = 4096;
    let mean = |k: f64| {
        (0..n)
            .map(|i| {
                let th = std::f64::consts::TAU * (i as f64 + 0.5) / n as f64;
                (c * c + k * k * th.cos().powi(2)).sqrt()
            })
            .sum::<f64>()
            / n as f64
    };
    let (mut lo, mut hi) = (0.0, 10.0);
    for _ in 0..200 {
        let m = 0.5 * (lo + hi);
        if mean(m) < 1.0 {
            lo = m
        } else {
            hi = m
        }
    }
    0.5 * (lo + hi) / std::f64::consts::TAU
}

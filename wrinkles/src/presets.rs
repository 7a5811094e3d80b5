//! The spec's setups (§6 W1, W2, W5, W6, §9): flat sheets with UV = (x, y), the two-triangle W1
//! square, sinusoid and fold patterns with a target rest slope, and the prescribed deformations
//! the scenes drive them with (uniform F, the four-stage corner pull, the travelling wave, the
//! benchmark's gather).
//!
//! ```
//! use wrinkles::presets::{sheet, sinusoid, uniform};
//! use geom_core::math::Mat2;
//! let mesh = sheet(4, 0.1).unwrap();
//! assert_eq!(mesh.faces.len(), 32);
//! let pattern = sinusoid(0.0125, 0.0, 0.5).unwrap();
//! let squeezed = uniform(&mesh, &Mat2::new(0.8, 0.0, 0.0, 1.0));
//! assert!((squeezed[mesh.positions.len() - 1].x - 0.08).abs() < 1e-15);
//! # let _ = pattern;
//! ```

use geom_core::math::{Mat2, Pt2, Pt3, Vec2};
use geom_core::mesh::Uv;
use geom_core::procedural::{grid, Diagonals, GridSpec, Plane};

use crate::error::Result;
use crate::frames::RestMesh;
use crate::pattern::{Normalization, PatternOptions, PatternSource, Procedural, WrinklePattern};

/// An `n × n` grid of side `l` (m) in the XY plane from the origin, alternating diagonals,
/// UV = (x, y).
pub fn sheet(n: u32, l: f64) -> Result<RestMesh> {
    let m = grid(&GridSpec {
        quads: [n, n],
        size: [l, l],
        plane: Plane::XY,
        diagonals: Diagonals::Alternating,
        center: Pt3::new(0.5 * l, 0.5 * l, 0.0),
    })?;
    RestMesh::from_trimesh(&m)
}

/// A square of side `l` (m) made of two triangles whose edge 0 is axis-aligned (`[0,1,2]` along
/// +x, `[2,3,0]` along −x), UV = (x, y): the W1 fixture.
pub fn two_triangle_square(l: f64) -> Result<RestMesh> {
    let p = vec![Pt3::new(0.0, 0.0, 0.0), Pt3::new(l, 0.0, 0.0), Pt3::new(l, l, 0.0), Pt3::new(0.0, l, 0.0)];
    let uv = Uv::PerVertex(p.iter().map(|p| Pt2::new(p.x, p.y)).collect());
    RestMesh::new(p, vec![[0, 1, 2], [2, 3, 0]], uv)
}

/// A sinusoid of wavelength `lambda` (UV m), wave-vector angle `angle_deg`, phase 0, normalised to
/// the rest slope `slope`.
pub fn sinusoid(lambda: f64, angle_deg: f64, slope: f64) -> Result<WrinklePattern> {
    WrinklePattern::new(
        &PatternSource::Procedural(Procedural::Sinusoid { wavelength_uv: lambda, angle_deg, phase: 0.0 }),
        PatternOptions { normalization: Normalization::TargetRestSlope(slope), ..Default::default() },
    )
}

/// The procedural folds of the scenes: four sinusoids of wavelength `wavelength` (UV m) about
/// `angle_deg` (± 8°), irregularity 0.3, seeded by `seed`.
pub fn folds_source(wavelength: f64, angle_deg: f64, seed: u64) -> PatternSource {
    PatternSource::Procedural(Procedural::Folds {
        wavelength_uv: wavelength,
        angle_deg,
        spread_deg: 8.0,
        count: 4,
        irregularity: 0.3,
        seed,
    })
}

/// [`folds_source`] normalised to the rest slope `slope`.
pub fn folds(wavelength: f64, angle_deg: f64, seed: u64, slope: f64) -> Result<WrinklePattern> {
    WrinklePattern::new(
        &folds_source(wavelength, angle_deg, seed),
        PatternOptions { normalization: Normalization::TargetRestSlope(slope), ..Default::default() },
    )
}

/// Deformed positions `p' = F·(x, y)`, z kept (a uniform in-plane deformation).
pub fn uniform(mesh: &RestMesh, f: &Mat2) -> Vec<Pt3> {
    mesh.positions
        .iter()
        .map(|p| {
            let q = f * Vec2::new(p.x, p.y);
            Pt3::new(q.x, q.y, p.z)
        })
        .collect()
}

fn smooth01(x: f64) -> f64 {
    let x = x.clamp(0.0, 1.0);
    x * x * (3.0 - 2.0 * x)
}

/// The W2 driver: the bottom-corner displacement (m) at time `t` (s) of the four stages of
/// `stage_seconds` each — rest, pull to `(−|corner.x|, corner.y)`, back, pull to
/// `(|corner.x|, corner.y)` — with a smoothstep over the first `transition` of each stage.
pub fn four_stage_corner(corner: [f64; 2], stage_seconds: f64, transition: f64, t: f64) -> Vec2 {
    let st = (t / stage_seconds).floor() as i64;
    let u = smooth01((t / stage_seconds - st as f64) / transition);
    let left = Vec2::new(-corner[0].abs(), corner[1]);
    let right = Vec2::new(corner[0].abs(), corner[1]);
    match st {
        0 => Vec2::zeros(),
        1 => left * u,
        2 => left * (1.0 - u),
        _ => right * u,
    }
}

/// The W2 smooth shear of a sheet of side `l`: top edge fixed, bottom edge carried by the
/// corners, `u(x, y) = (1 − y/l)²·d`.
pub fn sheared(mesh: &RestMesh, l: f64, d: Vec2) -> Vec<Pt3> {
    mesh.positions
        .iter()
        .map(|p| {
            let w = (1.0 - p.y / l).powi(2);
            Pt3::new(p.x + w * d.x, p.y + w * d.y, p.z)
        })
        .collect()
}

/// The W6 driver: a compression wave travelling along x with a sideways sway, on a sheet of side
/// `l` at time `t` (s).
pub fn travelling_wave(mesh: &RestMesh, l: f64, t: f64) -> Vec<Pt3> {
    let k = std::f64::consts::TAU / l;
    mesh.positions
        .iter()
        .map(|p| {
            let ux = -0.04 * l * ((k * p.x - 2.0 * t).sin() + 1.0) * 0.5 * (p.x / l);
            Pt3::new(p.x + ux, p.y + 0.02 * l * (1.5 * t).sin() * (p.x / l), 0.05 * l * (k * p.y + t).sin())
        })
        .collect()
}

/// The benchmark's gather on a sheet of side `l`: x squeezed towards the top edge (up to 40 %)
/// with a gentle bulge of 2 cm.
pub fn gather(mesh: &RestMesh, l: f64) -> Vec<Pt3> {
    mesh.positions
        .iter()
        .map(|p| {
            let s = 1.0 - 0.4 * p.y / l;
            Pt3::new(0.5 * l + (p.x - 0.5 * l) * s, p.y, 0.02 * (std::f64::consts::PI * p.x / l).sin())
        })
        .collect()
}

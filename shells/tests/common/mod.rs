//! Shared helpers of the integration tests: small grid scenes.

#![allow(dead_code)]

use geom_core::math::{Pt3, Vec3};
use geom_core::procedural::{grid, Diagonals, GridSpec, Plane};
use shells::{Damping, Effects, IntegratorSettings, Material, MembraneLaw, ShellSceneDesc, VertexConstraint};

/// An `n × n`-vertex grid of `size` metres in the XZ plane at height `y`.
pub fn sheet(n: u32, size: f64, y: f64) -> (Vec<Pt3>, Vec<[u32; 3]>) {
    let g = grid(&GridSpec {
        quads: [n - 1, n - 1],
        size: [size, size],
        plane: Plane::XZ,
        diagonals: Diagonals::Alternating,
        center: Pt3::new(0.0, y, 0.0),
    })
    .expect("valid grid spec");
    (g.positions.clone(), g.faces.clone())
}

/// Cotton-like material with the given damping.
pub fn cloth(damping: Damping) -> Material {
    Material {
        density: 0.15,
        membrane: MembraneLaw::Isotropic { young_thickness: 2000.0, poisson: 0.3, compression_softening: None },
        bending: 5e-6,
        damping,
        plasticity: None,
    }
}

/// A scene description with defaults: no effects, no constraints.
pub fn desc(rest: Vec<Pt3>, faces: Vec<[u32; 3]>, material: Material) -> ShellSceneDesc {
    ShellSceneDesc {
        rest,
        faces,
        uv: None,
        initial: None,
        initial_velocity: None,
        material,
        effects: Effects::default(),
        constraints: Vec::<VertexConstraint>::new(),
        integrator: IntegratorSettings::default(),
        t0: 0.0,
    }
}

/// Gravity vector (m/s²).
pub fn g() -> Vec3 {
    Vec3::new(0.0, -9.81, 0.0)
}

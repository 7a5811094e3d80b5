//! Per-phase timing of the `shells/drape` configuration (33 × 33 cotton square, two corners
//! pinned, gravity, self-collision, h = 1/120 s): prints the mean wall time per step of assembly,
//! factorisation, solve and collisions. Run with
//! `cargo run --release -p shells --example drape_profile [-- <steps>]`.

use geom_core::math::{Pt3, Vec3};
use geom_core::procedural::{grid, Diagonals, GridSpec, Plane};
use shells::{
    CollisionSettings, Damping, Effects, IntegratorSettings, Material, MembraneLaw, ShellSceneDesc, ShellSim,
    VertexConstraint,
};
use std::time::Instant;

fn main() -> Result<(), shells::Error> {
    let steps: usize = std::env::args().nth(1).and_then(|s| s.parse().ok()).unwrap_or(360);
    let n = 33u32;
    let g = grid(&GridSpec {
        quads: [n - 1, n - 1],
        size: [1.0, 1.0],
        plane: Plane::XZ,
        diagonals: Diagonals::Alternating,
        center: Pt3::new(0.0, 1.0, 0.0),
    })?;
    let effects = Effects {
        gravity: Some(Vec3::new(0.0, -9.81, 0.0)),
        self_collision: true,
        collision: Some(CollisionSettings { thickness: 0.004, ..CollisionSettings::default() }),
        ..Default::default()
    };
    let material = Material {
        density: 0.15,
        membrane: MembraneLaw::Isotropic { young_thickness: 2000.0, poisson: 0.3, compression_softening: None },
        bending: 5e-6,
        damping: Damping::Rayleigh { alpha: 0.0, beta: 1e-4 },
        plasticity: None,
    };
    let desc = ShellSceneDesc {
        rest: g.positions.clone(),
        faces: g.faces.clone(),
        uv: None,
        initial: None,
        initial_velocity: None,
        material,
        effects,
        constraints: vec![VertexConstraint::Pinned(vec![(n - 1) * n, n * n - 1])],
        integrator: IntegratorSettings::default(),
        t0: 0.0,
    };
    let mut sim = ShellSim::new(desc)?;
    let h = 1.0 / 120.0;
    let (mut ta, mut tf, mut ts, mut tc) = (0.0, 0.0, 0.0, 0.0);
    let wall = Instant::now();
    for _ in 0..steps {
        let st = sim.step(h)?;
        ta += st.t_assembly;
        tf += st.t_factor;
        ts += st.t_solve;
        tc += st.t_collision;
    }
    let w = wall.elapsed().as_secs_f64();
    let k = 1e3 / steps as f64;
    println!(
        "{} vertices, {} threads, {steps} steps: {:.2} ms/step (assembly {:.2}, factor {:.2}, solve {:.2}, collisions {:.2})",
        g.positions.len(),
        rayon::current_num_threads(),
        w * k,
        ta * k,
        tf * k,
        ts * k,
        tc * k
    );
    Ok(())
}

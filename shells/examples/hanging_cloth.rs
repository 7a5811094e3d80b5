//! A small cloth square pinned at two corners, falling under gravity with self-collision, for one
//! second: prints energies and timings. Run with `cargo run -p shells --example hanging_cloth`.

use geom_core::math::{Pt3, Vec3};
use geom_core::procedural::{grid, Diagonals, GridSpec, Plane};
use shells::{CollisionSettings, Effects, IntegratorSettings, Material, ShellSceneDesc, ShellSim, VertexConstraint};

fn main() -> Result<(), shells::Error> {
    let n = 17u32;
    let g = grid(&GridSpec {
        quads: [n - 1, n - 1],
        size: [0.5, 0.5],
        plane: Plane::XZ,
        diagonals: Diagonals::Alternating,
        center: Pt3::new(0.0, 1.0, 0.0),
    })?;
    let effects = Effects {
        gravity: Some(Vec3::new(0.0, -9.81, 0.0)),
        self_collision: true,
        collision: Some(CollisionSettings::default()),
        ..Default::default()
    };
    let desc = ShellSceneDesc {
        rest: g.positions.clone(),
        faces: g.faces.clone(),
        uv: None,
        initial: None,
        initial_velocity: None,
        material: Material::cotton(),
        effects,
        constraints: vec![VertexConstraint::Pinned(vec![0, n - 1])],
        integrator: IntegratorSettings::default(),
        t0: 0.0,
    };
    let mut sim = ShellSim::new(desc)?;
    let h = 1.0 / 120.0;
    for frame in 1..=30 {
        let mut wall = 0.0;
        for _ in 0..4 {
            let st = sim.step(h)?;
            wall += st.t_assembly + st.t_factor + st.t_solve + st.t_collision;
        }
        if frame % 5 == 0 {
            let e = sim.energies();
            println!(
                "t = {:.3} s  kinetic {:.4e} J  membrane {:.4e} J  bending {:.4e} J  ({:.2} ms/frame)",
                sim.state().t,
                e.kinetic,
                e.membrane,
                e.bending,
                1e3 * wall
            );
        }
    }
    Ok(())
}

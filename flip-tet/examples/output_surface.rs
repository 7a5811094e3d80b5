//! Collapse a water column (the dam break of spec S2 at a small size), then write the simulation
//! surface and the high-resolution output surface (spec §3.11.6) of the last frame as OBJ files
//! and print their sizes and build times.
//!
//! `cargo run --release -p flip-tet --example output_surface -- [finest = 32] [t_end = 0.1 s] [out dir = out/examples/flip-tet]`
use std::time::Instant;

use flip_tet::scene::Scene;
use flip_tet::sim::FlipTetSim;
use geom_core::io::{obj, MeshOut};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let finest: u32 = args.next().map_or(Ok(32), |s| s.parse())?;
    let t_end: f64 = args.next().map_or(Ok(0.1), |s| s.parse())?;
    let dir = std::path::PathBuf::from(args.next().unwrap_or_else(|| "out/examples/flip-tet".into()));
    std::fs::create_dir_all(&dir)?;
    let text = format!(
        "(domain: (min: (0.0, 0.0, 0.0), max: (0.2813538461538462, 0.1406769230769231, 0.03516923076923077)),
          resolution: (coarsest: 8, finest: {finest}), duration: {t_end}, fps: 100.0,
          liquid: [Box(min: (0.0, 0.0, 0.0), max: (0.05715, 0.1143, 0.03516923076923077))],
          sizing: (depth_floor: Some(0.25), surface_band: Some(3.0)))"
    );
    let scene: Scene = ron::from_str(&text)?;
    let mut sim = FlipTetSim::new(&scene)?;
    let t0 = Instant::now();
    sim.advance_to(t_end)?;
    println!(
        "simulated {t_end} s at finest {finest}: {} particles, {:.2} s",
        sim.particles().len(),
        t0.elapsed().as_secs_f64()
    );
    let t1 = Instant::now();
    let coarse = sim.surface().ok_or("the column has no surface")?;
    let t_sim = t1.elapsed().as_secs_f64();
    let t2 = Instant::now();
    let fine = sim.output_surface()?;
    let t_out = t2.elapsed().as_secs_f64();
    obj::write(dir.join("simulation_surface.obj"), &MeshOut::from_tri_mesh(&coarse))?;
    obj::write(dir.join("output_surface.obj"), &MeshOut::from_tri_mesh(&fine.mesh))?;
    println!(
        "simulation surface: {} triangles ({t_sim:.3} s); output surface: {} triangles on {} tets, h_out {:.2e} m ({t_out:.2} s); written to {}",
        coarse.n_faces(),
        fine.mesh.n_faces(),
        fine.tets,
        fine.h_out,
        dir.display()
    );
    Ok(())
}

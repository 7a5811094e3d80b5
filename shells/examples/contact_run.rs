//! Runs a shell scene file and prints, per frame, the sanity figures (edge strain and
//! compression, obstacle penetration, energy), the contact statistics and the time per step;
//! optionally writes OBJ frames. For looking at a contact scene while tuning it.
//!
//! `cargo run --release -p shells --example contact_run -- <scene.ron> [frames] [--bridson] [--obj DIR]`

use std::time::Instant;

use serde::Deserialize;
use shells::metrics::Sanity;
use shells::scene::ShellScene;
use shells::ShellSim;

#[derive(Deserialize)]
struct Params {
    shell: ShellScene,
}

#[derive(Deserialize)]
struct File {
    params: Params,
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let path = args.get(1).ok_or("usage: contact_run <scene.ron> [frames] [--bridson] [--obj DIR]")?;
    let text = std::fs::read_to_string(path)?;
    let file: File =
        ron::Options::default().with_default_extension(ron::extensions::Extensions::IMPLICIT_SOME).from_str(&text)?;
    let mut shell = file.params.shell;
    if args.iter().any(|a| a == "--bridson") {
        if let Some(c) = shell.effects.collision.as_mut() {
            c.method = shells::ContactMethod::Bridson;
        }
    }
    let obj_dir = args.iter().position(|a| a == "--obj").and_then(|i| args.get(i + 1)).map(std::path::PathBuf::from);
    let it = shell.integrator.clone();
    let h = it.h();
    let frames: usize = args.get(2).and_then(|s| s.parse().ok()).unwrap_or((shell.duration * it.fps).round() as usize);
    let built = shell.build(std::path::Path::new("."))?;
    let faces = built.desc.faces.clone();
    let obstacles = built.desc.effects.obstacles.clone();
    let g = built.desc.effects.gravity.map(|g| g.norm()).unwrap_or(0.0);
    let mut sim = ShellSim::new(built.desc)?;
    let scale = Sanity::passive_energy_scale(&sim.mesh().rest, &sim.mesh().mass, g);
    let mut sanity = Sanity::new(&sim.mesh().rest, &sim.mesh().edges, obstacles, Some(scale));
    println!(
        "method {:?}, barrier {:?}, {} vertices, h = {h:.5} s",
        sim.contact_method(),
        sim.barrier_parameters(),
        sim.state().q.len()
    );
    if let Some(d) = &obj_dir {
        std::fs::create_dir_all(d)?;
    }
    let t_all = Instant::now();
    let mut steps = 0usize;
    for f in 1..=frames {
        let tf = Instant::now();
        let mut iters = 0;
        let mut last = None;
        for _ in 0..it.substeps {
            match sim.step(h) {
                Ok(st) => {
                    iters += st.newton_iters;
                    last = Some(st);
                }
                Err(e) => {
                    println!("frame {f}: {e}");
                    return Ok(());
                }
            }
            steps += 1;
            let e = sim.energies().total();
            sanity.observe(&sim.state().q, sim.state().t, Some(e));
        }
        let st = last.expect("at least one substep");
        let inter = shells::collision::count_self_intersections(&sim.state().q, &faces);
        println!(
            "f{f:3} t={:.3} E={:9.4} strain {:.4} comp {:.3} pen {:.2e} gain {:.4} | iters {iters:3} active {:5} min_gap {:.2e} κ {:.2e} clamps {} lsfail {} unconv {} | inter {inter} | {:.1} ms/step",
            sim.state().t,
            sim.energies().total(),
            sanity.max_edge_strain,
            sanity.max_edge_compression,
            sanity.max_obstacle_penetration_m,
            sanity.energy_gain_rel().unwrap_or(f64::NAN),
            st.contact.active,
            st.contact.min_gap,
            st.contact.kappa,
            st.contact.ccd_clamps,
            st.contact.line_search_failures,
            st.contact.unconverged,
            1e3 * tf.elapsed().as_secs_f64() / it.substeps as f64,
        );
        if let Some(d) = &obj_dir {
            geom_core::io::obj::write(
                geom_core::io::frame_path(d, f),
                &geom_core::io::MeshOut::tri(&sim.state().q, &faces),
            )?;
        }
    }
    println!("{steps} steps, {:.4} s/step", t_all.elapsed().as_secs_f64() / steps as f64);
    Ok(())
}

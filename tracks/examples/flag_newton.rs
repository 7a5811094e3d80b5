//! Newton iterations of the untracked 1617-vertex flag under IPC, with wind / damping toggled:
//! `cargo run --release -p tracks --example flag_newton -- [steps] [wind 0|1] [beta]`.
use geom_core::mesh::subdivide_linear;
use shells::{ContactMethod, Damping, ShellSim};
use tracks::presets::flag_desc;
use tracks::procedural::flag_coarse;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let a: Vec<String> = std::env::args().collect();
    let steps: usize = match a.get(1) {
        Some(s) => s.parse().map_err(|e| format!("steps (argument 1) {s:?}: {e}"))?,
        None => 8,
    };
    let wind = a.get(2).is_none_or(|s| s == "1");
    let beta: f64 = match a.get(3) {
        Some(s) => s.parse().map_err(|e| format!("beta (argument 3) {s:?}: {e}"))?,
        None => 1e-4,
    };
    let (fine, _) = subdivide_linear(&flag_coarse()?, 3);
    let mut d = flag_desc(&fine, 2.8, 2.0, true, ContactMethod::Ipc);
    if !wind {
        d.effects.wind = None;
    }
    d.material.damping = Damping::Rayleigh { alpha: 0.0, beta };
    let mut sim = ShellSim::new(d)?;
    for _ in 0..steps {
        let t = std::time::Instant::now();
        let st = sim.step(1.0 / 120.0)?;
        println!(
            "newton {} ls_fail {} halvings {} unconv {} {:.3} s",
            st.newton_iters,
            st.contact.line_search_failures,
            st.line_search_halvings,
            st.contact.unconverged,
            t.elapsed().as_secs_f64()
        );
    }
    Ok(())
}

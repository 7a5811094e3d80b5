//! Newton iterations of the untracked 1617-vertex flag under IPC, with wind / damping toggled:
//! `cargo run --release -p tracks --example flag_newton -- [steps] [wind 0|1] [beta]`.
use geom_core::mesh::subdivide_linear;
use shells::{ContactMethod, Damping, ShellSim};
use tracks::presets::flag_desc;
use tracks::procedural::flag_coarse;

fn main() {
    let a: Vec<String> = std::env::args().collect();
    let steps: usize = a.get(1).map_or(8, |s| s.parse().unwrap());
    let wind = a.get(2).is_none_or(|s| s == "1");
    let beta: f64 = a.get(3).map_or(1e-4, |s| s.parse().unwrap());
    let (fine, _) = subdivide_linear(&flag_coarse().unwrap(), 3);
    let mut d = flag_desc(&fine, 2.8, 2.0, true, ContactMethod::Ipc);
    if !wind {
        d.effects.wind = None;
    }
    d.material.damping = Damping::Rayleigh { alpha: 0.0, beta };
    let mut sim = ShellSim::new(d).unwrap();
    for _ in 0..steps {
        let t = std::time::Instant::now();
        let st = sim.step(1.0 / 120.0).unwrap();
        println!(
            "newton {} ls_fail {} halvings {} unconv {} {:.3} s",
            st.newton_iters,
            st.contact.line_search_failures,
            st.line_search_halvings,
            st.contact.unconverged,
            t.elapsed().as_secs_f64()
        );
    }
}

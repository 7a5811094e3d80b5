//! Where does a contact step go wrong? Runs a shell scene file (e.g. `scenes/shells/fold-stress.ron`)
//! and, for every step, measures the end-of-step state after each stage of the collision filter
//! (linear solve, proximity, obstacles, CCD passes, impact zones, freezing): total energy
//! E = kinetic + membrane + bending + gravity (J), the deepest vertex inside an obstacle (m) and
//! the largest edge strain ℓ/ℓ̄ − 1. Prints, per stage, how much energy it added over the run and
//! how often it was the stage that put a vertex inside an obstacle; with `-v`, every step where a
//! stage adds more than 1 mJ.
//!
//! `cargo run --release -p shells --example contact_stages -- scenes/shells/fold-stress.ron [steps] [-v]`

use std::collections::BTreeMap;

use geom_core::math::{Pt3, Vec3};
use serde::Deserialize;
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
    let path = args.get(1).ok_or("usage: contact_stages <scene.ron> [steps] [-v]")?;
    let verbose = args.iter().any(|a| a == "-v");
    let text = std::fs::read_to_string(path)?;
    let file: File =
        ron::Options::default().with_default_extension(ron::extensions::Extensions::IMPLICIT_SOME).from_str(&text)?;
    let mut shell = file.params.shell;
    // The stage trace belongs to the seed's velocity filter.
    if let Some(c) = shell.effects.collision.as_mut() {
        c.method = shells::ContactMethod::Bridson;
    }
    let h = shell.integrator.h();
    let steps: usize = args.get(2).and_then(|s| s.parse().ok()).unwrap_or((shell.duration / h).round() as usize);
    let built = shell.build(std::path::Path::new("."))?;
    let obstacles = built.desc.effects.obstacles.clone();
    let mut sim = ShellSim::new(built.desc)?;
    sim.trace_collision_stages(true);
    let edges = sim.mesh().edges.clone();
    let rest: Vec<f64> =
        edges.iter().map(|e| (sim.mesh().rest[e[0] as usize] - sim.mesh().rest[e[1] as usize]).norm()).collect();
    let placed: Vec<_> = obstacles.iter().map(|o| (o.clone(), shells::collision::obstacles::mesh_query(o))).collect();
    let depth = |q: &[Pt3], t: f64| -> f64 {
        let mut worst: f64 = 0.0;
        for (o, acc) in &placed {
            let po = shells::collision::obstacles::PlacedObstacle::new(o, t, h).with_accel(acc.as_ref());
            for p in q {
                worst = worst.max(-po.query(p).distance);
            }
        }
        worst
    };
    let strain = |q: &[Pt3]| -> f64 {
        edges.iter().zip(&rest).map(|(e, l)| (q[e[0] as usize] - q[e[1] as usize]).norm() / l - 1.0).fold(0.0, f64::max)
    };
    let mut added: BTreeMap<&'static str, (f64, u32, u32)> = BTreeMap::new();
    let mut split: BTreeMap<&'static str, (f64, f64)> = BTreeMap::new();
    let mut e_prev = sim.energies().total();
    for k in 0..steps {
        let q0 = sim.state().q.clone();
        let t_next = sim.state().t + h;
        if let Err(e) = sim.step(h) {
            println!("step {k}: {e}");
            break;
        }
        let trace: Vec<(&'static str, Vec<Vec3>)> = sim.collision_trace().to_vec();
        let mut e_before = e_prev;
        let mut parts_before = sim.energies_of(&q0, &sim.state().v);
        let _ = &mut parts_before;
        let mut first = true;
        let mut d_before = depth(&q0, t_next - h);
        let mut v_before: Option<&Vec<Vec3>> = None;
        for (stage, v) in &trace {
            let q: Vec<Pt3> = q0.iter().zip(v).map(|(p, w)| p + h * w).collect();
            let parts = sim.energies_of(&q, v);
            let e = parts.total();
            if !first {
                let sp = split.entry(stage).or_insert((0.0, 0.0));
                sp.0 += parts.kinetic - parts_before.kinetic;
                sp.1 += (parts.membrane + parts.bending) - (parts_before.membrane + parts_before.bending);
            }
            first = false;
            parts_before = parts;
            let d = depth(&q, t_next);
            let entry = added.entry(stage).or_insert((0.0, 0, 0));
            entry.0 += e - e_before;
            entry.1 += 1;
            if d > 1e-4 && d > d_before + 1e-6 {
                entry.2 += 1;
            }
            if verbose && e - e_before > 1e-3 {
                println!(
                    "step {k:4} t={t_next:.3} {stage:>9}: ΔE {:+.4} J, depth {d:.2e} m, strain {:.3}",
                    e - e_before,
                    strain(&q)
                );
                if let (Some(vb), true) = (v_before, e - e_before > 1.0) {
                    // The vertex whose velocity this stage changed most, and where it is.
                    let (i, dv) = vb
                        .iter()
                        .zip(v)
                        .map(|(a, b)| (b - a).norm())
                        .enumerate()
                        .fold((0, 0.0), |a, (i, x)| if x > a.1 { (i, x) } else { a });
                    let dists: Vec<String> = placed
                        .iter()
                        .map(|(o, acc)| {
                            let po = shells::collision::obstacles::PlacedObstacle::new(o, t_next, h)
                                .with_accel(acc.as_ref());
                            format!("{:.4}", po.query(&q0[i]).distance)
                        })
                        .collect();
                    println!(
                        "      vertex {i}: |Δv| {dv:.3} m/s, v {:?} -> {:?}, start {:?}, obstacle distances at start {:?}",
                        vb[i].as_slice(), v[i].as_slice(), q0[i].coords.as_slice(), dists
                    );
                }
            }
            v_before = Some(v);
            e_before = e;
            d_before = d;
        }
        let e_now = sim.energies().total();
        e_prev = e_now;
        if k % 15 == 14 {
            println!(
                "step {k:4} t={:.3}: E {e_now:.4} J, depth {:.2e} m, strain {:.3}",
                sim.state().t,
                depth(&sim.state().q, sim.state().t),
                strain(&sim.state().q)
            );
        }
    }
    println!("stage      energy added over the run (J)   calls   steps where it deepened a penetration > 0.1 mm");
    for (s, (e, n, d)) in &added {
        println!("{s:>9}  {e:+14.4}  {n:8}  {d:8}");
    }
    println!("stage      kinetic added (J)   elastic (membrane + bending) added (J), excluding the solve stage");
    for (s, (k, el)) in &split {
        println!("{s:>9}  {k:+14.4}  {el:+14.4}");
    }
    Ok(())
}

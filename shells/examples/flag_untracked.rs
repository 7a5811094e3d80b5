//! The untracked fine flag of `tracks/flag` (spec tracks.md §6.1) without the tracking machinery:
//! the 7 × 5 coarse grid (alternating diagonals, 1.2 × 0.8 m, centred at (0, 2, 0)) subdivided
//! linearly three times (1617 vertices), cotton, gravity, steady wind (1.5, 0, 0) m/s, the branch
//! capsule (friction 0.8), self-collision with the default settings, initial velocity
//! (2.8, 2.0, 0) m/s plus a spin of 1.5 rad/s about z, h = 1/120 s. This is the scene's untracked
//! twin step for step (the design loop picks (2.8, 2.0)); the flag tangles on itself from
//! t ≈ 1 s on and its collision filter dominates the step.
//!
//! `cargo run --release -p shells --example flag_untracked -- [from] [steps] [checkpoint]`:
//! runs `steps` steps starting at step `from`. With a checkpoint file, the state at step `from`
//! is read from it when it exists (else simulated from t = 0 and written there), so the tangled
//! phase can be profiled repeatedly. Prints per-phase times and a checksum of the final state's
//! bits (equal checksums = bitwise equal results).

use geom_core::math::{Pt3, Vec3};
use geom_core::mesh::subdivide_linear;
use geom_core::procedural::{grid, Diagonals, GridSpec, Plane};
use shells::{
    CollisionSettings, Effects, IntegratorSettings, Material, Obstacle, ObstacleShape, ShellSceneDesc, ShellSim,
    ShellState, Wind,
};
use std::time::Instant;

fn desc() -> Result<ShellSceneDesc, shells::Error> {
    let coarse = grid(&GridSpec {
        quads: [6, 4],
        size: [1.2, 0.8],
        plane: Plane::XZ,
        diagonals: Diagonals::Alternating,
        center: Pt3::new(0.0, 2.0, 0.0),
    })?;
    let (fine, _) = subdivide_linear(&coarse, 3);
    let branch = Obstacle {
        shape: ObstacleShape::Capsule { a: Pt3::new(2.0, 1.2, -1.0), b: Pt3::new(2.0, 1.2, 1.0), radius: 0.03 },
        friction: 0.8,
        motion: None,
    };
    let effects = Effects {
        gravity: Some(Vec3::new(0.0, -9.81, 0.0)),
        wind: Some(Wind::steady(Vec3::new(1.5, 0.0, 0.0))),
        obstacles: vec![branch],
        self_collision: true,
        collision: Some(CollisionSettings::default()),
        ..Effects::default()
    };
    let c = Vec3::new(0.0, 2.0, 0.0);
    let w = Vec3::new(0.0, 0.0, 1.5);
    let v0 = fine.positions.iter().map(|x| Vec3::new(2.8, 2.0, 0.0) + w.cross(&(x.coords - c))).collect();
    Ok(ShellSceneDesc {
        rest: fine.positions.clone(),
        faces: fine.faces.clone(),
        uv: None,
        initial: None,
        initial_velocity: Some(v0),
        material: Material::cotton(),
        effects,
        constraints: vec![],
        integrator: IntegratorSettings::default(),
        t0: 0.0,
    })
}

/// Raw little-endian f64s: t, then q, then v.
fn write_state(path: &str, s: &ShellState) -> std::io::Result<()> {
    let mut b = Vec::new();
    let mut put = |x: f64| b.extend_from_slice(&x.to_le_bytes());
    put(s.t);
    s.q.iter().for_each(|p| p.iter().for_each(|&x| put(x)));
    s.v.iter().for_each(|p| p.iter().for_each(|&x| put(x)));
    std::fs::write(path, b)
}

fn read_state(path: &str, n: usize) -> Option<ShellState> {
    let b = std::fs::read(path).ok()?;
    if b.len() != 8 * (1 + 6 * n) {
        return None;
    }
    let f: Vec<f64> = b.chunks_exact(8).map(|c| f64::from_le_bytes(c.try_into().expect("8-byte chunk"))).collect();
    let p3 = |k: usize| [f[k], f[k + 1], f[k + 2]];
    let q = (0..n).map(|i| Pt3::from(p3(1 + 3 * i))).collect();
    let v = (0..n).map(|i| Vec3::from(p3(1 + 3 * n + 3 * i))).collect();
    Some(ShellState { t: f[0], q, v })
}

/// CPU time (user + system) of this process in seconds, from /proc/self/stat (Linux; 0 when
/// unavailable): less sensitive than wall time to other processes on a shared machine.
fn cpu_seconds() -> f64 {
    let Ok(stat) = std::fs::read_to_string("/proc/self/stat") else { return 0.0 };
    // Fields after the parenthesised command name; utime and stime are fields 14 and 15.
    let rest = stat.rsplit_once(')').map_or("", |x| x.1);
    let f: Vec<f64> = rest.split_whitespace().skip(11).take(2).filter_map(|x| x.parse().ok()).collect();
    f.iter().sum::<f64>() / 100.0
}

fn main() -> Result<(), shells::Error> {
    let arg = |k: usize, d: usize| std::env::args().nth(k).and_then(|s| s.parse().ok()).unwrap_or(d);
    let (from, steps) = (arg(1, 0), arg(2, 480));
    let ckpt = std::env::args().nth(3);
    let h = 1.0 / 120.0;
    let mut sim = ShellSim::new(desc()?)?;
    let n = sim.state().q.len();
    match ckpt.as_deref().and_then(|p| read_state(p, n)) {
        Some(s) if from > 0 => sim.set_state(s)?,
        _ => {
            for _ in 0..from {
                sim.step(h)?;
            }
            if let (Some(p), true) = (ckpt.as_deref(), from > 0) {
                write_state(p, sim.state()).map_err(|e| shells::Error::BadParameter(format!("checkpoint {p}: {e}")))?;
            }
        }
    }
    let (mut ta, mut tf, mut ts, mut tc) = (0.0, 0.0, 0.0, 0.0);
    let (mut ccd, mut prox, mut zone, mut frozen) = (0u64, 0u64, 0u32, 0u64);
    let wall = Instant::now();
    let cpu0 = cpu_seconds();
    for _ in 0..steps {
        let st = sim.step(h)?;
        ta += st.t_assembly;
        tf += st.t_factor;
        ts += st.t_solve;
        tc += st.t_collision;
        ccd += st.n_ccd as u64;
        prox += st.n_proximity as u64;
        zone = zone.max(st.max_zone_size);
        frozen += st.n_frozen as u64;
    }
    let w = wall.elapsed().as_secs_f64();
    let cpu = cpu_seconds() - cpu0;
    let k = 1e3 / steps.max(1) as f64;
    let s = sim.state();
    // FNV-1a over the bits of q and v.
    let mut hash = 0xcbf2_9ce4_8422_2325u64;
    for x in s.q.iter().flat_map(|p| p.iter()).chain(s.v.iter().flat_map(|p| p.iter())) {
        for byte in x.to_bits().to_le_bytes() {
            hash = (hash ^ byte as u64).wrapping_mul(0x100_0000_01b3);
        }
    }
    let isect = shells::collision::count_self_intersections(&s.q, &sim.mesh().tris);
    println!(
        "{n} vertices, {} threads, steps {from}..{}: {:.1} ms/step, cpu {:.1} ms/step (assembly {:.1}, factor {:.1}, solve {:.1}, \
         collisions {:.1}); ccd hits {ccd}, proximity {prox}, max zone {zone}, frozen {frozen}, \
         intersections {isect}, t = {:.4}, checksum {hash:016x}",
        rayon::current_num_threads(),
        from + steps,
        w * k,
        cpu * k,
        ta * k,
        tf * k,
        ts * k,
        tc * k,
        s.t
    );
    Ok(())
}

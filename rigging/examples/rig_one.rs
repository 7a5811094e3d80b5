//! Rigs one procedural test character and prints the stage timings and score:
//! `cargo run -p rigging --example rig_one -- <seed> <target_vertices> [tau]`.

use geom_core::collide::MeshQuery;
use geom_core::procedural::character::{build_mesh, humanoid};
use rigging::characters::test_params;
use rigging::eval::score;
use rigging::{autorig, RigOptions, SkeletonTemplate};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let seed: u64 = args.get(1).map_or(Ok(1000), |s| s.parse())?;
    let nv: usize = args.get(2).map_or(Ok(10000), |s| s.parse())?;
    let tau: f64 = args.get(3).map_or(Ok(0.003), |s| s.parse())?;
    let t0 = std::time::Instant::now();
    let (sdf, truth) = humanoid(&test_params(seed))?;
    let mesh = build_mesh(&sdf, nv)?;
    println!("mesh {} vertices in {:.2}s", mesh.n_vertices(), t0.elapsed().as_secs_f64());
    let sk = SkeletonTemplate::human();
    let o = RigOptions { tau, ..Default::default() };
    let rig = autorig(&mesh.positions, &mesh.faces, &sk, &[], &o)?;
    println!("{:?}", rig.timings);
    println!("{:?}", rig.diagnostics);
    println!("discrete {:?}", rig.discrete);
    let q = MeshQuery::new(&mesh)?;
    let s = score(&sk, &rig.joints, &truth.rest, &q);
    println!("score {s:?}");
    let s0 = score(&sk, &rig.joints_unrefined, &truth.rest, &q);
    println!("unrefined {s0:?}");
    for (j, (a, t)) in rig.joints.iter().zip(&truth.rest).enumerate() {
        println!("{:12} {:?} truth {:?}", sk.joints[j].name, a.coords.as_slice(), t.coords.as_slice());
    }
    Ok(())
}

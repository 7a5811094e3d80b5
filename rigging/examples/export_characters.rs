//! Writes procedural characters as OBJ files to try `cargo xtask rig` on:
//! `cargo run -p rigging --example export_characters -- <dir> [vertices]` writes
//! `human.obj` (test character 1000, +Y up, facing +Z, 1.7 units tall), `human_zup.obj` (Z up,
//! facing −Y), `human_back.obj` (facing −Z), `human_side.obj` (facing +X), `human_cm.obj`
//! (the first, scaled to centimetres), `human_pinched.obj` (one non-manifold vertex),
//! `quadruped.obj` and `giraffe.obj` (the long-necked quadruped).

use geom_core::io::{obj, MeshOut};
use geom_core::math::Pt3;
use rigging::characters::test_params;
use rigging::orient::{Axis, Orientation};
use rigging::presets::{humanoid_character, long_necked_quadruped, quadruped_character};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let dir = std::path::PathBuf::from(args.get(1).map_or("out/characters", |s| s.as_str()));
    let nv: usize = args.get(2).map_or(Ok(10000), |s| s.parse())?;
    std::fs::create_dir_all(&dir)?;
    let (m, _) = humanoid_character(&test_params(1000), nv)?;
    let k = 1.7 / m.aabb().size().y;
    let p: Vec<Pt3> = m.positions.iter().map(|x| x * k).collect();
    let write = |name: &str, p: &[Pt3], f: &[[u32; 3]]| obj::write(dir.join(name), &MeshOut::tri(p, f));
    write("human.obj", &p, &m.faces)?;
    for (name, up, front) in [
        ("human_zup.obj", Axis::PosZ, Axis::NegY),
        ("human_back.obj", Axis::PosY, Axis::NegZ),
        ("human_side.obj", Axis::PosY, Axis::PosX),
    ] {
        let o = Orientation::new(up, front)?;
        let q: Vec<Pt3> = p.iter().map(|x| o.point_from_canonical(x)).collect();
        write(name, &q, &m.faces)?;
    }
    let cm: Vec<Pt3> = p.iter().map(|x| x * 100.0).collect();
    write("human_cm.obj", &cm, &m.faces)?;
    // Pinch: the vertex nearest the left wrist's surface merged with one three rings away.
    let v = 0u32;
    let mut near: std::collections::BTreeSet<u32> = [v].into();
    for _ in 0..3 {
        let cur = near.clone();
        for t in &m.faces {
            if t.iter().any(|x| cur.contains(x)) {
                near.extend(t.iter().copied());
            }
        }
    }
    let w = (0..p.len() as u32)
        .filter(|x| !near.contains(x))
        .min_by(|a, b| (p[*a as usize] - p[v as usize]).norm().total_cmp(&(p[*b as usize] - p[v as usize]).norm()))
        .ok_or("no far vertex")?;
    let mut pp = p.clone();
    pp[w as usize] = pp[v as usize];
    let pf: Vec<[u32; 3]> = m.faces.iter().map(|t| t.map(|x| if x == w { v } else { x })).collect();
    write("human_pinched.obj", &pp, &pf)?;
    let (q, _) = quadruped_character(3, nv)?;
    write("quadruped.obj", &q.positions, &q.faces)?;
    let (g, _) = long_necked_quadruped(3, 0.5, nv)?;
    write("giraffe.obj", &g.positions, &g.faces)?;
    println!("wrote {}", dir.display());
    Ok(())
}

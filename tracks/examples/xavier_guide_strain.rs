//! Edge strain of the Xavier guide (linear blend skinning of the rest mesh) against the rest
//! mesh, the worst edge's vertex with its rig data, and how far the feet move relative to the
//! body's centroid (the limbs' animation), at the given times:
//! `cargo run --release -p tracks --example xavier_guide_strain -- [t...]`.
use geom_core::math::Pt3;
use tracks::procedural::{xavier, xavier_guide};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let ts: Vec<f64> = std::env::args().skip(1).map(|s| s.parse()).collect::<Result<_, _>>()?;
    let x = xavier()?;
    let g = xavier_guide(&x, 10.0)?;
    let rest = &x.mesh.positions;
    let edges = x.mesh.topology().edges();
    let mut p = vec![Pt3::origin(); rest.len()];
    let mut p0 = vec![Pt3::origin(); rest.len()];
    g.sample(0.0, &mut p0);
    let feet = tracks::presets::xavier_feet(&x);
    for t in ts {
        g.sample(t, &mut p);
        // How far the feet move relative to the body's centroid (m): the limbs' animation.
        let centroid = |q: &[Pt3]| q.iter().fold(geom_core::math::Vec3::zeros(), |a, b| a + b.coords) / q.len() as f64;
        let (c, c0) = (centroid(&p), centroid(&p0));
        let feet_move = feet.iter().map(|&v| ((p[v as usize] - c) - (p0[v as usize] - c0)).norm()).sum::<f64>()
            / feet.len().max(1) as f64;
        println!("t {t:.4}: feet move {feet_move:.4} m relative to the centroid");
        let (mut smax, mut cmax, mut worst) = (0.0f64, 0.0f64, 0u32);
        for &[a, b] in edges {
            let s = (p[b as usize] - p[a as usize]).norm() / (rest[b as usize] - rest[a as usize]).norm() - 1.0;
            if s > smax {
                worst = a;
            }
            smax = smax.max(s);
            cmax = cmax.max(-s);
        }
        let (w, m) = (worst as usize, x.membership[worst as usize]);
        println!(
            "t {t:.4}: guide edge strain max {smax:.4}, compression max {cmax:.4}; worst edge at vertex {w} \
             (rest {:.3?}, radial s {:.3}, limb membership {m:.2?})",
            rest[w], x.s[w]
        );
    }
    Ok(())
}

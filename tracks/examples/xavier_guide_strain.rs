//! Edge strain of the Xavier guide (linear blend skinning of the rest mesh) against the rest
//! mesh, at the given times: `cargo run --release -p tracks --example xavier_guide_strain -- [t...]`.
use geom_core::math::Pt3;
use tracks::procedural::{xavier, xavier_guide};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let ts: Vec<f64> = std::env::args().skip(1).map(|s| s.parse()).collect::<Result<_, _>>()?;
    let x = xavier()?;
    let g = xavier_guide(&x, 10.0)?;
    let rest = &x.mesh.positions;
    let edges = x.mesh.topology().edges();
    let mut p = vec![Pt3::origin(); rest.len()];
    for t in ts {
        g.sample(t, &mut p);
        let (mut smax, mut cmax) = (0.0f64, 0.0f64);
        for &[a, b] in edges {
            let s = (p[b as usize] - p[a as usize]).norm() / (rest[b as usize] - rest[a as usize]).norm() - 1.0;
            smax = smax.max(s);
            cmax = cmax.max(-s);
        }
        println!("t {t:.4}: guide edge strain max {smax:.4}, compression max {cmax:.4}");
    }
    Ok(())
}

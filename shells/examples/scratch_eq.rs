use geom_core::math::{Pt3, Vec3};
use shells::*;
use std::sync::Arc;
struct TipLoad(Vec<(u32, Vec3)>);
impl ExternalForce for TipLoad {
    fn add_forces(&self, _t: f64, _q: &[Pt3], _v: &[Vec3], f: &mut [Vec3]) { for &(i, p) in &self.0 { f[i as usize] += p; } }
}
fn main() {
    for (ell, rows, rotated) in [(0.025f64, 3usize, false), (0.0125, 5, false), (0.0125, 9, false), (0.025, 3, true), (0.0125, 7, true)] {
        let (l, kb) = (1.0, 1e-3);
        // Strip: equilateral lattice clipped to [0, l] × [0, w].
        let (p0, f0) = shells::calib::equilateral_patch(2.0, ell, rotated);
        let dy = if rotated { ell } else { ell * 3f64.sqrt() / 2.0 };
        let w = dy * (rows - 1) as f64 + 1e-9;
        let xmin = -1.0 + if rotated { 0.0 } else { 0.0 };
        let keep: Vec<bool> = p0.iter().map(|p| p.x >= xmin - 1e-9 && p.x <= xmin + l + 1e-9 && p.y >= -1.0 - 1e-9 && p.y <= -1.0 + w).collect();
        let mut map = vec![u32::MAX; p0.len()]; let mut p = vec![];
        for (i, q) in p0.iter().enumerate() { if keep[i] { map[i] = p.len() as u32; p.push(*q); } }
        let f: Vec<[u32;3]> = f0.iter().filter(|t| t.iter().all(|&v| keep[v as usize])).map(|t| t.map(|v| map[v as usize])).collect();
        let used: std::collections::BTreeSet<u32> = f.iter().flatten().copied().collect();
        let xs = p.iter().enumerate().filter(|(i, _)| used.contains(&(*i as u32))).map(|(_, q)| q.x);
        let xmax = xs.fold(f64::NEG_INFINITY, f64::max);
        let x0 = xmin;
        let pins: Vec<u32> = (0..p.len() as u32).filter(|&i| used.contains(&i) && p[i as usize].x <= x0 + 1.01 * ell).collect();
        let tips: Vec<u32> = (0..p.len() as u32).filter(|&i| used.contains(&i) && p[i as usize].x >= xmax - 0.51 * ell).collect();
        let lf = xmax - (x0 + ell * 0.75);
        let wd = w;
        let ei = 6.0 * kb * wd;
        let dw = 0.01 * lf;
        let pl = 3.0 * ei * dw / lf.powi(3);
        let loads = tips.iter().map(|&i| (i, Vec3::new(0.0, 0.0, -pl / tips.len() as f64))).collect();
        // Drop unused vertices from being free: pin them too.
        let mut allpins = pins.clone(); for i in 0..p.len() as u32 { if !used.contains(&i) { allpins.push(i); } }
        let mut eff = Effects::default(); eff.custom.push(Arc::new(TipLoad(loads)));
        let desc = ShellSceneDesc { rest: p.clone(), faces: f.clone(), uv: None, initial: None, initial_velocity: None,
            material: Material { density: 0.01, membrane: MembraneLaw::Isotropic { young_thickness: 1e5, poisson: 0.0, compression_softening: None }, bending: kb, damping: Damping::None, plasticity: None },
            effects: eff, constraints: vec![VertexConstraint::Pinned(allpins)], integrator: IntegratorSettings { newton_iters: 4, ..Default::default() }, t0: 0.0 };
        let mut sim = ShellSim::new(desc).unwrap();
        for _ in 0..8 { sim.step(1e3).unwrap(); }
        let d = -tips.iter().map(|&i| sim.state().q[i as usize].z).sum::<f64>() / tips.len() as f64;
        println!("ell {ell} rows {rows} rot {rotated} nverts {} tips {}: defl ratio {:.4}", used.len(), tips.len(), d / dw);
    }
}

use geom_core::math::{Pt3, Vec3};
use geom_core::procedural::{grid, Diagonals, GridSpec, Plane};
use shells::*;
use std::sync::Arc;
struct TipLoad(Vec<(u32, Vec3)>);
impl ExternalForce for TipLoad {
    fn add_forces(&self, _t: f64, _q: &[Pt3], _v: &[Vec3], f: &mut [Vec3]) {
        for &(i, p) in &self.0 { f[i as usize] += p; }
    }
}
fn main() {
    for (nx, ny, w) in [(81u32, 9u32, 0.1f64), (41, 21, 0.5), (41, 41, 1.0)] {
        let (l, kb, h, it) = (1.0, 1e-3, 1e3, 4u32);
        let g = grid(&GridSpec { quads: [nx - 1, ny - 1], size: [l, w], plane: Plane::XY, diagonals: Diagonals::Alternating, center: Pt3::origin() }).unwrap();
        let mut pins = Vec::new();
        for j in 0..ny { pins.extend([j * nx, j * nx + 1]); }
        let ei = 6.0 * kb * w;
        let dx = l / (nx - 1) as f64;
        let lf = l - dx;
        let dw = 0.01 * lf;
        let p = 3.0 * ei * dw / lf.powi(3);
        let wts: Vec<f64> = (0..ny).map(|j| if j == 0 || j == ny - 1 { 0.5 } else { 1.0 } / (ny - 1) as f64).collect();
        let loads = (0..ny).map(|j| (j * nx + nx - 1, Vec3::new(0.0, 0.0, -p * wts[j as usize]))).collect();
        let mut eff = Effects::default();
        eff.custom.push(Arc::new(TipLoad(loads)));
        let desc = ShellSceneDesc { rest: g.positions.clone(), faces: g.faces.clone(), uv: None, initial: None, initial_velocity: None,
            material: Material { density: 0.01, membrane: MembraneLaw::Isotropic { young_thickness: 1e5, poisson: 0.0, compression_softening: None }, bending: kb, damping: Damping::None, plasticity: None },
            effects: eff, constraints: vec![VertexConstraint::Pinned(pins)], integrator: IntegratorSettings { newton_iters: it, ..Default::default() }, t0: 0.0 };
        let mut sim = ShellSim::new(desc).unwrap();
        let mut out = vec![];
        for k in 0..10 { sim.step(h).unwrap(); if k % 8 == 0 || k == 9 {
            let d = -(0..ny).map(|j| sim.state().q[(j * nx + nx - 1) as usize].z * wts[j as usize]).sum::<f64>();
            out.push(d / dw); } }
        println!("nx {nx} ny {ny} h {h} it {it}: {:?}", out);
    }
}

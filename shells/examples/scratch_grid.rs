use geom_core::math::Pt3;
use geom_core::procedural::{grid, Diagonals, GridSpec, Plane};
use shells::*;
fn main() {
    for (d, a, b) in [(Diagonals::Alternating, 41u32, 41u32), (Diagonals::Alternating, 41, 81), (Diagonals::Forward, 41, 41)] {
        let g = grid(&GridSpec { quads: [a - 1, b - 1], size: [0.4, 0.4], plane: Plane::XY, diagonals: d, center: Pt3::origin() }).unwrap();
        let mut m = Material::cotton(); m.bending = 1.0;
        let mesh = ShellMesh::new(g.positions.clone(), &g.faces, None, &m).unwrap();
        let r = 0.5;
        let qx = shells::calib::wrap_cylinder(&g.positions, r);
        let qy: Vec<Pt3> = g.positions.iter().map(|p| Pt3::new(p.x, r * (p.y / r).sin(), r * (1.0 - (p.y / r).cos()))).collect();
        let dx = shells::calib::interior_energy_density(&mesh, &qx, 0.03) * r * r;
        let dy = shells::calib::interior_energy_density(&mesh, &qy, 0.03) * r * r;
        let sf = shells::calib::strip_rigidity_factor(&g.positions, &g.faces, 2.0, 0.03).unwrap();
        println!("{d:?} {a}x{b}: bend along x (axis y) {dx:.4}, along y {dy:.4} strip factor {sf:.4} -> defl {:.4}", 6.0 / sf);
    }
}

//! Discrete operators on the tet mesh (spec §3.3): P1 pressure on nodes, P0 velocity per tet.
//!
//! - Gradient `G` (3m × n): `(G q)_t = Σ_{a∈t} q_a ∇λ_a^t`.
//! - Weights `W = diag(V_t w_t)` (`w_t` fluid fraction, 1 without obstacles; spec §12 G1).
//! - Divergence `D = Gᵀ W`: `(D u)_i = Σ_{t∋i} V_t w_t ∇λ_i^t · u_t` (weak form, no-flux walls).
//! - Stiffness `K = Gᵀ W G`, local `K^t_ij = V_t w_t ∇λ_i·∇λ_j` (the cotangent matrix).

use geom_core::linalg::{Csr, Triplets};
use geom_core::math::Vec3;
use rayon::prelude::*;

use crate::bcc::TetMesh;

/// Fluid fraction of tet `t` (1 without obstacles).
pub fn fluid_fraction(mesh: &TetMesh, t: usize) -> f64 {
    mesh.solid_frac.as_ref().map_or(1.0, |w| w[t])
}

/// Local 4×4 stiffness `K^t_ij = V_t w_t ∇λ_i · ∇λ_j` of tet `t` (spec §3.3).
pub fn local_stiffness(mesh: &TetMesh, t: usize) -> [[f64; 4]; 4] {
    let g = &mesh.grad_bary[t];
    let vw = mesh.volume[t] * fluid_fraction(mesh, t);
    let mut k = [[0.0; 4]; 4];
    for i in 0..4 {
        for j in i..4 {
            let v = vw * g[i].dot(&g[j]);
            k[i][j] = v;
            k[j][i] = v;
        }
    }
    k
}

/// Per-tet gradient of the nodal field `q` (spec §3.3), in parallel.
pub fn gradient(mesh: &TetMesh, q: &[f64]) -> Vec<Vec3> {
    mesh.tets
        .par_iter()
        .zip(mesh.grad_bary.par_iter())
        .map(|(t, g)| (0..4).fold(Vec3::zeros(), |acc, a| acc + g[a] * q[t[a] as usize]))
        .collect()
}

/// Weak divergence `D u = Gᵀ W u` per node (spec §3.3), gathered per node (deterministic).
pub fn divergence(mesh: &TetMesh, u: &[Vec3]) -> Vec<f64> {
    (0..mesh.nodes.len())
        .into_par_iter()
        .map(|i| {
            mesh.node_tets.row(i).iter().fold(0.0, |acc, &t| {
                let ti = t as usize;
                let a = mesh.tets[ti].iter().position(|&v| v as usize == i).unwrap_or(0);
                acc + mesh.volume[ti] * fluid_fraction(mesh, ti) * mesh.grad_bary[ti][a].dot(&u[ti])
            })
        })
        .collect()
}

/// Global stiffness `K = Gᵀ W G` over all nodes (tests and diagnostics; the pressure solve
/// assembles the liquid block directly, [`crate::pressure`]).
pub fn stiffness(mesh: &TetMesh) -> Csr {
    let n = mesh.nodes.len();
    let mut tr = Triplets::with_capacity(n, n, mesh.tets.len() * 16);
    for (t, tv) in mesh.tets.iter().enumerate() {
        let k = local_stiffness(mesh, t);
        for i in 0..4 {
            for j in 0..4 {
                tr.push(tv[i], tv[j], k[i][j]);
            }
        }
    }
    Csr::from_triplets(&tr)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bcc::tetrahedralize;
    use crate::octree::{build_octree, Octree, OctreeSpec, SizeDemand};
    use geom_core::math::Pt3;

    fn graded() -> TetMesh {
        let sp = OctreeSpec::new(Pt3::origin(), Pt3::new(1.0, 1.0, 0.5), 2, 8).unwrap();
        let d = [SizeDemand { center: Pt3::new(0.3, 0.6, 0.2), pad: 0.1, level: 2 }];
        tetrahedralize(&build_octree(sp, &d)).unwrap()
    }

    /// T-GRAD-LINEAR: the gradient of a linear field is exact in every tet (1e−12 relative).
    #[test]
    fn gradient_of_linear_field_is_exact() {
        let m = graded();
        let a = Vec3::new(0.3, -1.7, 2.2);
        let q: Vec<f64> = m.nodes.iter().map(|p| a.dot(&p.coords) + 0.4).collect();
        for g in gradient(&m, &q) {
            assert!((g - a).norm() <= 1e-12 * a.norm());
        }
    }

    /// T-K-PROPS: symmetric, rows sum to zero, regular BCC tet matrix `(h/12)[…]`, and the local
    /// entries equal the cotangent formula `−(1/6) ℓ_kl cot β_kl`.
    #[test]
    fn stiffness_properties() {
        let m = graded();
        let k = stiffness(&m);
        let kmax = k.max_abs();
        assert!(k.is_symmetric(1e-14 * kmax));
        let ones = vec![1.0; m.nodes.len()];
        let mut y = vec![0.0; m.nodes.len()];
        k.mul_vec(&ones, &mut y);
        assert!(y.iter().all(|v| v.abs() <= 1e-13 * kmax));
        // Cotangent formula per tet.
        for t in 0..m.tets.len() {
            let kt = local_stiffness(&m, t);
            let ang = crate::bcc::dihedral_angles(&m.grad_bary[t]);
            let pairs = [(0, 1), (0, 2), (0, 3), (1, 2), (1, 3), (2, 3)];
            for (e, &(i, j)) in pairs.iter().enumerate() {
                let (kk, ll) = pairs[5 - e];
                let len = (m.nodes[m.tets[t][kk] as usize] - m.nodes[m.tets[t][ll] as usize]).norm();
                let cot = 1.0 / ang[5 - e].tan();
                let want = -len * cot / 6.0;
                assert!((kt[i][j] - want).abs() <= 1e-12 * kt[i][i].abs(), "{} vs {want}", kt[i][j]);
            }
        }
        // Regular BCC tet of a uniform mesh: vertex order (centre, centre, corner, corner).
        let sp = OctreeSpec::new(Pt3::origin(), Pt3::new(1.0, 1.0, 1.0), 4, 4).unwrap();
        let u = tetrahedralize(&Octree::uniform(sp, 0)).unwrap();
        let h = 0.25;
        let t = (0..u.tets.len()).find(|&t| u.tets[t].iter().all(|&i| u.node_boundary[i as usize] == 0)).unwrap();
        let kt = local_stiffness(&u, t);
        let want = [[2.0, 0.0, -1.0, -1.0], [0.0, 2.0, -1.0, -1.0], [-1.0, -1.0, 2.0, 0.0], [-1.0, -1.0, 0.0, 2.0]];
        for i in 0..4 {
            for j in 0..4 {
                assert!((kt[i][j] - h / 12.0 * want[i][j]).abs() < 1e-14);
            }
        }
    }

    /// T-DIV-ADJOINT: ⟨D u, q⟩ = ⟨u, G q⟩_W (1e−12 relative).
    #[test]
    fn divergence_is_adjoint_of_gradient() {
        let m = graded();
        let mut rng = geom_core::rng::Rng::new(4);
        let q: Vec<f64> = (0..m.nodes.len()).map(|_| rng.range(-1.0, 1.0)).collect();
        let u: Vec<Vec3> = (0..m.tets.len()).map(|_| rng.unit_vec3()).collect();
        let du = divergence(&m, &u);
        let gq = gradient(&m, &q);
        let lhs: f64 = du.iter().zip(&q).map(|(a, b)| a * b).sum();
        let rhs: f64 = (0..m.tets.len()).map(|t| m.volume[t] * u[t].dot(&gq[t])).sum();
        assert!((lhs - rhs).abs() <= 1e-12 * lhs.abs().max(rhs.abs()));
    }
}

//! Cotan stiffness, masses, mean curvature and smoothing (GEOM-CORE.md §3.4, §7).

use geom_core::linalg::Csr;
use geom_core::math::{Pt3, Vec3};
use geom_core::mesh::{
    cotan_stiffness, face_areas, mass_barycentric, mass_p1, mass_voronoi, mean_curvature_normal, signed_volume,
    taubin_smooth, SmoothWeight, TriMesh,
};
use geom_core::procedural::{box_surface, grid, icosphere, Diagonals, GridSpec};
use geom_core::rng::Rng;
use proptest::prelude::*;

fn max_diag(l: &Csr) -> f64 {
    (0..l.nrows).map(|i| l.get(i, i).abs()).fold(0.0, f64::max)
}

/// `max_i |(L·1)_i| / max |L_ii|` and the largest asymmetry `|L_ij − L_ji| / max |L_ii|`.
fn row_sum_and_asymmetry(l: &Csr) -> (f64, f64) {
    let d = max_diag(l);
    let mut rs: f64 = 0.0;
    let mut asym: f64 = 0.0;
    for i in 0..l.nrows {
        let (c, v) = l.row(i);
        rs = rs.max(v.iter().sum::<f64>().abs());
        for (&j, &x) in c.iter().zip(v) {
            asym = asym.max((x - l.get(j as usize, i)).abs());
        }
    }
    (rs / d, asym / d)
}

fn noisy_grid(seed: u64, quads: [u32; 2], z_amp: f64, xy_amp: f64) -> TriMesh {
    let g = grid(&GridSpec { quads, size: [1.0, 0.8], ..Default::default() }).expect("valid grid");
    let mut rng = Rng::new(seed);
    let h = [1.0 / quads[0] as f64, 0.8 / quads[1] as f64];
    let p = g
        .positions
        .iter()
        .map(|q| {
            q + Vec3::new(
                rng.range(-xy_amp, xy_amp) * h[0],
                rng.range(-xy_amp, xy_amp) * h[1],
                rng.range(-z_amp, z_amp),
            )
        })
        .collect();
    g.with_positions(p).expect("same vertex count")
}

#[test]
fn cotan_rows_sum_to_zero_and_symmetric() {
    let meshes = [
        noisy_grid(1, [7, 5], 0.05, 0.3),
        icosphere(0.3, 2).expect("valid icosphere"),
        box_surface(Pt3::new(0., 0., 0.), Pt3::new(1., 2., 0.5), [3, 2, 4], Diagonals::Alternating).expect("valid box"),
    ];
    for m in &meshes {
        for clamp in [None, Some(2.0)] {
            let l = cotan_stiffness(&m.faces, &m.positions, clamp);
            let (rs, asym) = row_sum_and_asymmetry(&l);
            // The diagonal is −Σ off-diagonals of the same row: only summation round-off remains.
            assert!(rs < 1e-12, "row sums {rs}");
            // Both triangles of an edge push the same value to (i, j) and (j, i) in the same order.
            assert_eq!(asym, 0.0);
        }
    }
}

#[test]
fn unit_cube_diagonal_is_three_at_all_scales() {
    for s in [1.0, 1e-8, 1e8] {
        for d in [Diagonals::Alternating, Diagonals::Forward, Diagonals::Backward] {
            let b = box_surface(Pt3::new(0., 0., 0.), Pt3::new(s, s, s), [1, 1, 1], d).expect("unit cube");
            let l = cotan_stiffness(&b.faces, &b.positions, None);
            for i in 0..8 {
                // Each of the vertex's three square sides contributes ½(cot 45° + cot 45°) or
                // ½(cot 45° + cot 45°) via the right angle: exactly 1; 1e-12 covers cot round-off.
                assert!((l.get(i, i) - 3.0).abs() < 1e-12, "scale {s}: L_ii = {}", l.get(i, i));
            }
        }
    }
}

#[test]
fn cotan_annihilates_linear_functions_on_flat_meshes() {
    let m = noisy_grid(7, [9, 8], 0.0, 0.35);
    let l = cotan_stiffness(&m.faces, &m.positions, None);
    let f: Vec<f64> = m.positions.iter().map(|p| 0.7 * p.x - 1.3 * p.y + 0.25).collect();
    let mut lf = vec![0.0; f.len()];
    l.mul_vec(&f, &mut lf);
    let t = m.topology();
    let scale = max_diag(&l) * f.iter().fold(0.0f64, |a, v| a.max(v.abs()));
    let mut n_interior = 0;
    for v in t.vertices() {
        if !t.is_boundary_vertex(v) {
            n_interior += 1;
            assert!(lf[v.0 as usize].abs() < 1e-12 * scale, "vertex {}: {}", v.0, lf[v.0 as usize]);
        }
    }
    assert_eq!(n_interior, 8 * 7);
}

#[test]
fn cotan_is_positive_semidefinite() {
    let m = noisy_grid(3, [6, 6], 0.2, 0.3);
    let l = cotan_stiffness(&m.faces, &m.positions, None);
    let mut rng = Rng::new(11);
    let mut y = vec![0.0; l.nrows];
    for _ in 0..50 {
        let x: Vec<f64> = (0..l.nrows).map(|_| rng.range(-1.0, 1.0)).collect();
        l.mul_vec(&x, &mut y);
        let q: f64 = x.iter().zip(&y).map(|(a, b)| a * b).sum();
        let xx: f64 = x.iter().map(|a| a * a).sum();
        assert!(q >= -1e-12 * max_diag(&l) * xx, "xᵀLx = {q}");
    }
    // Energy identity: xᵀLx = ½ Σ_T ∫|∇x|² equals Σ_edges w_ij (x_i − x_j)² ≥ 0 with
    // w_ij = −L_ij; check on one vector.
    let x: Vec<f64> = m.positions.iter().map(|p| p.x * p.x).collect();
    l.mul_vec(&x, &mut y);
    let q: f64 = x.iter().zip(&y).map(|(a, b)| a * b).sum();
    let mut e = 0.0;
    for &[i, j] in m.topology().edges() {
        e += -l.get(i as usize, j as usize) * (x[i as usize] - x[j as usize]).powi(2);
    }
    assert!((q - e).abs() < 1e-12 * e.abs());
}

#[test]
fn masses_sum_to_area() {
    for m in [noisy_grid(5, [6, 4], 0.1, 0.3), icosphere(1.7, 2).expect("valid icosphere")] {
        let area: f64 = face_areas(&m.faces, &m.positions).iter().sum();
        let mb: f64 = mass_barycentric(&m.faces, &m.positions).iter().sum();
        let mv = mass_voronoi(&m.faces, &m.positions);
        assert!(mv.iter().all(|&v| v > 0.0));
        let mv: f64 = mv.iter().sum();
        // Every face distributes exactly its area; 1e-12 relative covers summation order.
        assert!((mb - area).abs() < 1e-12 * area);
        assert!((mv - area).abs() < 1e-12 * area, "{mv} vs {area}");
        let mp = mass_p1(&m.faces, &m.positions);
        let ones = vec![1.0; mp.nrows];
        let mut r = vec![0.0; mp.nrows];
        mp.mul_vec(&ones, &mut r);
        let lumped = mass_barycentric(&m.faces, &m.positions);
        for (a, b) in r.iter().zip(&lumped) {
            assert!((a - b).abs() < 1e-14 * area);
        }
        assert!((r.iter().sum::<f64>() - area).abs() < 1e-12 * area);
    }
}

#[test]
fn voronoi_mass_on_known_triangles() {
    // Equilateral: each vertex gets A/3 (circumcentre = centroid).
    let s3 = 3f64.sqrt();
    let p = vec![Pt3::new(0., 0., 0.), Pt3::new(1., 0., 0.), Pt3::new(0.5, s3 / 2., 0.)];
    let m = mass_voronoi(&[[0, 1, 2]], &p);
    for v in m {
        assert!((v - s3 / 12.0).abs() < 1e-15);
    }
    // Obtuse at vertex 2: A/2 there, A/4 at the others (Meyer et al. 2003 mixed area).
    let p = vec![Pt3::new(0., 0., 0.), Pt3::new(4., 0., 0.), Pt3::new(2., 0.5, 0.)];
    let m = mass_voronoi(&[[0, 1, 2]], &p);
    assert_eq!(m, vec![0.25, 0.25, 0.5]);
    // Right isoceles: the circumcentre is the hypotenuse midpoint; the right-angle vertex gets A/2.
    let p = vec![Pt3::new(0., 0., 0.), Pt3::new(1., 0., 0.), Pt3::new(0., 1., 0.)];
    let m = mass_voronoi(&[[0, 1, 2]], &p);
    for (a, b) in m.iter().zip([0.25, 0.125, 0.125]) {
        assert!((a - b).abs() < 1e-16);
    }
}

#[test]
fn mean_curvature_normal_on_sphere() {
    let r = 0.8;
    let s = icosphere(r, 4).expect("valid icosphere");
    let h = mean_curvature_normal(&s.faces, &s.positions);
    for (p, hn) in s.positions.iter().zip(&h) {
        let radial = p.coords / r;
        // Points inward with length 2/R; the discretisation error on a level-4 icosphere is well
        // below 1% (measured ~0.3%).
        assert!((hn.dot(&radial) + 2.0 / r).abs() < 0.01 * 2.0 / r, "{}", hn.dot(&radial));
        assert!((hn - hn.dot(&radial) * radial).norm() < 0.01 * 2.0 / r);
    }
    // Flat interior vertices have zero mean curvature.
    let g = noisy_grid(2, [5, 5], 0.0, 0.3);
    let h = mean_curvature_normal(&g.faces, &g.positions);
    for v in g.topology().vertices().filter(|&v| !g.topology().is_boundary_vertex(v)) {
        assert!(h[v.0 as usize].norm() < 1e-10);
    }
}

#[test]
fn taubin_smooths_without_shrinking_and_respects_fixed() {
    let s = icosphere(1.0, 3).expect("valid icosphere");
    let mut rng = Rng::new(4);
    let noisy: Vec<Pt3> = s.positions.iter().map(|p| p + 0.02 * rng.range(-1.0, 1.0) * p.coords).collect();
    let rough = |p: &[Pt3]| p.iter().map(|q| (q.coords.norm() - 1.0).powi(2)).sum::<f64>();
    let vol0 = signed_volume(&s.faces, &noisy);
    for w in [SmoothWeight::Uniform, SmoothWeight::Cotan] {
        let mut p = noisy.clone();
        taubin_smooth(s.topology(), &mut p, 10, 0.5, -0.53, w, None);
        // Radial noise drops (to well under a third) while the volume changes by < 1 %.
        let mean_r = p.iter().map(|q| q.coords.norm()).sum::<f64>() / p.len() as f64;
        let dev: f64 = p.iter().map(|q| (q.coords.norm() - mean_r).powi(2)).sum();
        assert!(dev < rough(&noisy) / 3.0, "{w:?}: {dev} vs {}", rough(&noisy));
        let vol = signed_volume(&s.faces, &p);
        assert!((vol - vol0).abs() < 0.01 * vol0, "{w:?}: volume {vol} vs {vol0}");
    }
    // Fixed vertices stay bitwise; a flat grid stays flat.
    let g = noisy_grid(9, [6, 6], 0.0, 0.3);
    let fixed: Vec<bool> = g.topology().vertices().map(|v| g.topology().is_boundary_vertex(v)).collect();
    let mut p = g.positions.clone();
    taubin_smooth(g.topology(), &mut p, 5, 0.5, -0.53, SmoothWeight::Cotan, Some(&fixed));
    for (i, (a, b)) in p.iter().zip(&g.positions).enumerate() {
        if fixed[i] {
            assert_eq!(a, b);
        }
        assert_eq!(a.z, 0.0);
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 32, ..ProptestConfig::default() })]
    /// Random grids and perturbations keep L·1 = 0 and symmetry.
    #[test]
    fn cotan_invariants_on_random_grids(nx in 1u32..7, ny in 1u32..7, seed in any::<u64>(), z in 0.0f64..0.5, xy in 0.0f64..0.45,
                                        scale in prop::sample::select(vec![1e-6, 1.0, 1e6])) {
        let m = noisy_grid(seed, [nx, ny], z, xy);
        let p: Vec<Pt3> = m.positions.iter().map(|q| q * scale).collect();
        let l = cotan_stiffness(&m.faces, &p, None);
        let (rs, asym) = row_sum_and_asymmetry(&l);
        prop_assert!(rs < 1e-12);
        prop_assert_eq!(asym, 0.0);
    }
}

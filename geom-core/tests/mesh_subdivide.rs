//! Linear subdivision and its prolongation P (GEOM-CORE.md §3.4; §7 contract PᵀMP = M̄).

use geom_core::linalg::Csr;
use geom_core::math::{Pt2, Pt3};
use geom_core::mesh::{face_areas, mass_p1, subdivide_linear, TriMesh, Uv};
use geom_core::procedural::{box_surface, grid, icosphere, tube, Diagonals, GridSpec, TubeSpec};
use geom_core::rng::Rng;

fn test_meshes() -> Vec<(&'static str, TriMesh, i64)> {
    let g = grid(&GridSpec { quads: [3, 2], size: [1.5, 1.0], ..Default::default() }).expect("valid grid");
    let b =
        box_surface(Pt3::new(-1., 0., 0.), Pt3::new(1., 1., 2.), [1, 2, 1], Diagonals::Alternating).expect("valid box");
    let s = icosphere(1.0, 0).expect("valid icosphere");
    // A bumpy open surface (non-planar faces) to exercise curved-surface area/mass identities.
    let mut rng = Rng::new(5);
    let (t, _) = tube(&TubeSpec { around: 5, along: 2, ..Default::default() })
        .expect("valid tube")
        .triangulate_fan()
        .expect("tube triangulates");
    let tp = t.positions.iter().map(|p| p + 0.01 * rng.unit_vec3()).collect();
    let t = t.with_positions(tp).expect("same count");
    vec![("grid", g, 1), ("box", b, 2), ("sphere", s, 2), ("tube", t, 0)]
}

fn apply(p: &Csr, x: &[Pt3]) -> Vec<Pt3> {
    let mut out = vec![Pt3::origin(); p.nrows];
    for d in 0..3 {
        let src: Vec<f64> = x.iter().map(|q| q[d]).collect();
        let mut dst = vec![0.0; p.nrows];
        p.mul_vec(&src, &mut dst);
        for (o, v) in out.iter_mut().zip(dst) {
            o[d] = v;
        }
    }
    out
}

#[test]
fn prolongation_reproduces_fine_positions_exactly() {
    for (name, m, _) in test_meshes() {
        for levels in 0..=3 {
            let (f, p) = subdivide_linear(&m, levels);
            assert_eq!((p.nrows, p.ncols), (f.positions.len(), m.positions.len()));
            assert_eq!(apply(&p, &m.positions), f.positions, "{name} L{levels}: bitwise");
            // Coarse vertices keep their indices and positions.
            assert_eq!(&f.positions[..m.positions.len()], &m.positions[..]);
            // Rows are convex combinations (dyadic weights: exact sums).
            for i in 0..p.nrows {
                let (_, v) = p.row(i);
                assert_eq!(v.iter().sum::<f64>(), 1.0);
                assert!(v.iter().all(|&w| w > 0.0));
            }
        }
    }
}

#[test]
fn counts_euler_and_area_preserved() {
    for (name, m, chi) in test_meshes() {
        let a0: f64 = face_areas(&m.faces, &m.positions).iter().sum();
        let t0 = m.topology();
        for levels in 1..=3u32 {
            let (f, _) = subdivide_linear(&m, levels);
            let t = f.topology();
            assert_eq!(f.faces.len(), m.faces.len() * 4usize.pow(levels), "{name}");
            assert_eq!(t.euler_characteristic(), chi, "{name} L{levels}");
            assert_eq!(t.boundary_loops().len(), t0.boundary_loops().len());
            // Midpoint children tile their (flat) parent: total area is unchanged up to
            // summation round-off.
            let a: f64 = face_areas(&f.faces, &f.positions).iter().sum();
            assert!((a - a0).abs() < 1e-13 * a0, "{name} L{levels}: {a} vs {a0}");
            // The strict constructor accepts the result.
            TriMesh::new(f.positions.clone(), f.faces.clone()).expect("subdivided mesh is valid");
        }
        let (f1, _) = subdivide_linear(&m, 1);
        assert_eq!(f1.positions.len(), m.positions.len() + t0.n_edges());
    }
}

/// Pᵀ M_fine P = M_coarse for the consistent P1 mass after 1–4 levels (TR's contract), to 1e-12
/// relative to the largest entry.
#[test]
fn galerkin_mass_identity() {
    for (name, m, _) in test_meshes() {
        let mc = mass_p1(&m.faces, &m.positions);
        let scale = mc.val.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        for levels in 1..=4 {
            let (f, p) = subdivide_linear(&m, levels);
            let mf = mass_p1(&f.faces, &f.positions);
            let n = m.positions.len();
            let mut col = vec![0.0; n];
            let mut pe = vec![0.0; p.nrows];
            let mut mpe = vec![0.0; p.nrows];
            for j in 0..n {
                col.iter_mut().for_each(|c| *c = 0.0);
                col[j] = 1.0;
                p.mul_vec(&col, &mut pe);
                mf.mul_vec(&pe, &mut mpe);
                // (Pᵀ y)_i = Σ_r P_ri y_r
                let mut ptm = vec![0.0; n];
                for (r, &y) in mpe.iter().enumerate() {
                    let (c, v) = p.row(r);
                    for (&i, &w) in c.iter().zip(v) {
                        ptm[i as usize] += w * y;
                    }
                }
                for (i, &x) in ptm.iter().enumerate() {
                    let e = mc.get(i, j);
                    assert!((x - e).abs() < 1e-12 * scale, "{name} L{levels} ({i},{j}): {x} vs {e}");
                }
            }
        }
    }
}

#[test]
fn uvs_are_carried() {
    let g = grid(&GridSpec { quads: [2, 3], size: [2.0, 3.0], ..Default::default() }).expect("valid grid");
    // Per-vertex: grid UVs are an affine function of position, so they stay one.
    let (f, _) = subdivide_linear(&g, 2);
    let Some(Uv::PerVertex(uv)) = &f.uv else { panic!("per-vertex UVs carried") };
    assert_eq!(uv.len(), f.positions.len());
    for (u, p) in uv.iter().zip(&f.positions) {
        assert!((u.x - (p.x + 1.0)).abs() < 1e-15 && (u.y - (p.y + 1.5)).abs() < 1e-15);
    }
    // Per-corner built from the same UVs gives the same values corner by corner.
    let Some(Uv::PerVertex(guv)) = &g.uv else { panic!("grid has per-vertex UVs") };
    let corners: Vec<[Pt2; 3]> =
        g.faces.iter().map(|t| [guv[t[0] as usize], guv[t[1] as usize], guv[t[2] as usize]]).collect();
    let gc = g.clone().with_uv(Uv::PerCorner(corners)).expect("one triple per face");
    let (fc, _) = subdivide_linear(&gc, 2);
    let Some(Uv::PerCorner(cuv)) = &fc.uv else { panic!("per-corner UVs carried") };
    assert_eq!(cuv.len(), fc.faces.len());
    for (t, c) in fc.faces.iter().zip(cuv) {
        for k in 0..3 {
            assert!((c[k] - uv[t[k] as usize]).norm() < 1e-15);
        }
    }
}

//! Spec §7 mesh tests: T-MESH-VALID, T-MESH-UNIFORM, T-MESH-GRADED, T-MESH-BALANCE, T-LOCATE.

use std::collections::HashMap;

use flip_tet::bcc::{dihedral_angles, tetrahedralize, TetMesh};
use flip_tet::octree::{build_octree, Octree, OctreeSpec, SizeDemand};
use geom_core::math::Pt3;
use geom_core::rng::Rng;
use geom_core::NONE;

fn random_octree(seed: u64, levels: u32) -> Octree {
    let sp = OctreeSpec::new(Pt3::origin(), Pt3::new(1.0, 0.5, 0.75), 4, 4 << (levels - 1)).unwrap();
    let mut rng = Rng::new(seed);
    let demands: Vec<SizeDemand> = (0..6)
        .map(|_| SizeDemand {
            center: Pt3::new(rng.range(0.0, 1.0), rng.range(0.0, 0.5), rng.range(0.0, 0.75)),
            pad: rng.range(0.0, 0.15),
            level: rng.below(levels as usize) as u8,
        })
        .collect();
    build_octree(sp, &demands)
}

fn check_valid(mesh: &TetMesh, box_vol: f64) {
    // Positive volumes and exact volume sum (1e-12 relative).
    assert!(mesh.volume.iter().all(|&v| v > 0.0));
    let s: f64 = mesh.volume.iter().sum();
    assert!((s - box_vol).abs() <= 1e-12 * box_vol, "volume {s} vs {box_vol}");
    // Every face is shared by exactly 2 tets, or lies on the box boundary.
    let mut count: HashMap<[u32; 3], u32> = HashMap::new();
    for t in &mesh.tets {
        for a in 0..4 {
            let mut f = [t[(a + 1) % 4], t[(a + 2) % 4], t[(a + 3) % 4]];
            f.sort_unstable();
            *count.entry(f).or_default() += 1;
        }
    }
    for (f, c) in &count {
        assert!(*c <= 2, "face used {c} times");
        if *c == 1 {
            let common = f.iter().fold(0xffu8, |m, &i| m & mesh.node_boundary[i as usize]);
            assert_ne!(common, 0, "interior face used once: {f:?}");
        }
    }
    assert_eq!(mesh.quality_report().unmatched_interior_faces, 0);
    // Lattice keys unique.
    let mut keys = mesh.node_key.clone();
    keys.sort();
    keys.dedup();
    assert_eq!(keys.len(), mesh.nodes.len());
}

#[test]
fn t_mesh_valid_random_octrees() {
    for seed in 0..20 {
        let oct = random_octree(seed, 1 + (seed % 4) as u32);
        let mesh = tetrahedralize(&oct).unwrap();
        check_valid(&mesh, 0.375);
    }
}

#[test]
fn t_mesh_uniform_counts_and_angles() {
    for n in [4usize, 8] {
        let sp = OctreeSpec::new(Pt3::origin(), Pt3::new(1.0, 1.0, 1.0), n as u32, n as u32).unwrap();
        let mesh = tetrahedralize(&Octree::uniform(sp, 0)).unwrap();
        assert_eq!(mesh.tets.len(), 12 * n.pow(3) + 12 * n.pow(2));
        assert_eq!(mesh.nodes.len(), 2 * n.pow(3) + 9 * n.pow(2) + 3 * n + 1);
        check_valid(&mesh, 1.0);
        for (t, g) in mesh.grad_bary.iter().enumerate() {
            let boundary =
                mesh.tets[t].iter().any(|&i| mesh.node_boundary[i as usize] != 0) && mesh.face_nbr[t].contains(&NONE);
            for a in dihedral_angles(g) {
                let d = a.to_degrees();
                let ok = [60.0, 90.0].iter().any(|x| (d - x).abs() < 1e-9) || (boundary && (d - 45.0).abs() < 1e-9);
                assert!(ok, "tet {t} dihedral {d}");
            }
        }
        // Interior node valence 14 (edges), i.e. distinct neighbours.
        for i in 0..mesh.nodes.len() {
            if mesh.node_boundary[i] != 0 {
                continue;
            }
            let mut nb: Vec<u32> =
                mesh.node_tets.row(i).iter().flat_map(|&t| mesh.tets[t as usize]).filter(|&j| j != i as u32).collect();
            nb.sort_unstable();
            nb.dedup();
            assert_eq!(nb.len(), 14);
        }
        // m ≈ 6n only asymptotically: 4.25 at N = 8 (spec §7).
        if n == 8 {
            assert!((mesh.quality_report().tets_per_node - 4.25).abs() < 0.02);
        }
    }
}

#[test]
fn t_mesh_graded_dihedrals_and_positive_couplings() {
    let mut n_trans = 0usize;
    let mut n_obtuse = 0usize;
    for seed in 0..6 {
        let oct = random_octree(seed, 3);
        let mesh = tetrahedralize(&oct).unwrap();
        for (t, g) in mesh.grad_bary.iter().enumerate() {
            let ang = dihedral_angles(g).map(f64::to_degrees);
            for &d in &ang {
                assert!((30.0 - 1e-6..=135.0 + 1e-6).contains(&d), "dihedral {d}");
            }
            // Transition tets: the two "centre" vertices come from cubes of different levels.
            let transition = mesh.is_transition(t, &oct.spec);
            let v = mesh.volume[t];
            let kii = v * g[0].norm_squared();
            let positive =
                (0..4).any(|i| (i + 1..4).any(|j| v * g[i].dot(&g[j]) > 1e-12 * kii.max(v * g[j].norm_squared())));
            if positive {
                assert!(transition, "non-transition tet {t} has a positive coupling, angles {ang:?}");
            }
            if transition {
                n_trans += 1;
                if ang.iter().any(|&d| (d - 135.0).abs() < 1e-6) {
                    n_obtuse += 1;
                }
            }
        }
    }
    assert!(n_trans > 0);
    assert_eq!(2 * n_obtuse, n_trans, "half of the transition tets have a 135° angle");
}

#[test]
fn t_mesh_balance_one_midpoint_per_edge() {
    for seed in 0..10 {
        let oct = random_octree(100 + seed, 4);
        let sp = oct.spec;
        for a in &oct.leaves {
            for b in &oct.leaves {
                let (sa, sb) = (sp.size_units(a.level), sp.size_units(b.level));
                if (0..3).all(|k| a.origin.0[k] <= b.origin.0[k] + sb && b.origin.0[k] <= a.origin.0[k] + sa) {
                    assert!((a.level as i32 - b.level as i32).abs() <= 1);
                }
            }
        }
        tetrahedralize(&oct).unwrap();
    }
}

#[test]
fn t_locate_agrees_with_brute_force_and_walk() {
    let oct = random_octree(3, 3);
    let mesh = tetrahedralize(&oct).unwrap();
    let mut rng = Rng::new(9);
    for i in 0..3000 {
        let x = Pt3::new(rng.range(0.0, 1.0), rng.range(0.0, 0.5), rng.range(0.0, 0.75));
        let (t, l) = mesh.locate(&oct, &x).unwrap();
        assert!(l.iter().all(|&v| v >= -1e-12), "point {x:?} in tet {t}: {l:?}");
        let brute =
            (0..mesh.tets.len() as u32).find(|&s| mesh.barycentric(s, &x).iter().all(|&v| v >= -1e-12)).unwrap();
        let lb = mesh.barycentric(brute, &x);
        assert!(lb.iter().all(|&v| v >= -1e-12));
        let start = (i * 7919 % mesh.tets.len()) as u32;
        let (tw, lw) = mesh.walk(&oct, start, &x).unwrap();
        assert!(lw.iter().all(|&v| v >= -1e-12), "walk ended in {tw}");
    }
    // Points on shared faces: a face centroid.
    for t in 0..200usize {
        let tt = mesh.tets[t];
        let x = Pt3::from(
            (mesh.nodes[tt[1] as usize].coords + mesh.nodes[tt[2] as usize].coords + mesh.nodes[tt[3] as usize].coords)
                / 3.0,
        );
        let (_, l) = mesh.locate(&oct, &x).unwrap();
        assert!(l.iter().copied().fold(f64::INFINITY, f64::min) >= -1e-12);
    }
}

#[test]
fn cached_node_neighbours_and_sizes_equal_the_surface_functions() {
    // `compute_geometry` caches the edge rows and node sizes the level set needs every step; they
    // must equal the reference functions of `surface` exactly (bitwise sizes, identical rows).
    for seed in [3, 8] {
        let mesh = tetrahedralize(&random_octree(seed, 4)).expect("mesh");
        let edges = flip_tet::surface::node_edges(&mesh);
        assert_eq!(mesh.node_nbrs.len(), mesh.nodes.len());
        for i in 0..mesh.nodes.len() {
            assert_eq!(mesh.node_nbrs.row(i), edges.row(i), "node {i}");
        }
        let h = flip_tet::surface::node_sizes(&mesh);
        assert_eq!(h.len(), mesh.node_h.len());
        assert!(h.iter().zip(&mesh.node_h).all(|(a, b)| a.to_bits() == b.to_bits()));
    }
}

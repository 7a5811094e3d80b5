//! `TriMesh::new` rejects each kind of bad input with an error naming the offending element;
//! `TriMesh::repair` fixes what is fixable (GEOM-CORE.md §3.4, §7 contract test).

use geom_core::math::{Pt2, Pt3};
use geom_core::mesh::{signed_volume, RepairOptions, TriMesh, Uv};
use geom_core::procedural::{box_surface, grid, Diagonals, GridSpec};
use geom_core::Error;

/// Unit square split into two triangles, CCW seen from +Z.
fn square() -> (Vec<Pt3>, Vec<[u32; 3]>) {
    let p = vec![Pt3::new(0., 0., 0.), Pt3::new(1., 0., 0.), Pt3::new(1., 1., 0.), Pt3::new(0., 1., 0.)];
    (p, vec![[0, 1, 2], [0, 2, 3]])
}

#[test]
fn valid_and_empty_meshes() {
    let (p, f) = square();
    let m = TriMesh::new(p, f).expect("square is valid");
    assert_eq!(m.topology().n_edges(), 5);
    let e = TriMesh::new(vec![], vec![]).expect("empty mesh is valid");
    assert_eq!(e.topology().n_faces(), 0);
    assert!(e.topology().is_closed());
    // Isolated vertices are allowed.
    let iso = TriMesh::new(vec![Pt3::origin()], vec![]).expect("a lone vertex is valid");
    assert_eq!(iso.topology().vertex_faces().row(0).len(), 0);
}

#[test]
fn index_out_of_range_names_face_and_vertex() {
    let (p, mut f) = square();
    f[1] = [0, 2, 7];
    match TriMesh::new(p, f) {
        Err(Error::IndexOutOfRange { face, vertex }) => assert_eq!((face, vertex), (1, 7)),
        r => panic!("expected IndexOutOfRange, got {r:?}"),
    }
}

#[test]
fn repeated_index_names_face_and_vertex() {
    let (p, mut f) = square();
    f[1] = [3, 2, 3];
    match TriMesh::new(p, f) {
        Err(Error::IndexOutOfRange { face, vertex }) => assert_eq!((face, vertex), (1, 3)),
        r => panic!("expected IndexOutOfRange, got {r:?}"),
    }
}

#[test]
fn non_finite_vertex_is_named() {
    let (mut p, f) = square();
    p[2].y = f64::NAN;
    match TriMesh::new(p, f) {
        Err(Error::NonFiniteVertex { vertex }) => assert_eq!(vertex, 2),
        r => panic!("expected NonFiniteVertex, got {r:?}"),
    }
}

#[test]
fn degenerate_face_is_named() {
    let (mut p, mut f) = square();
    // Face 2: collinear points on the x axis (zero area), also adjacent nowhere problematic.
    p.push(Pt3::new(2., 0., 0.));
    p.push(Pt3::new(3., 0., 0.));
    f.push([1, 4, 5]);
    match TriMesh::new(p, f) {
        Err(Error::DegenerateFace { face }) => assert_eq!(face, 2),
        r => panic!("expected DegenerateFace, got {r:?}"),
    }
    // Area just above the threshold (1e-14·diag²) passes, just below fails.
    let diag2 = 2.0; // bbox of the unit square plus a tiny sliver point inside it
    let ok = 2.0 * 1e-14 * diag2 * 1.01; // height for area = 1.01e-14·diag² over a base of 1
    let bad = 2.0 * 1e-14 * diag2 * 0.99;
    for (h, valid) in [(ok, true), (bad, false)] {
        let p = vec![Pt3::new(0., 0., 0.), Pt3::new(1., 0., 0.), Pt3::new(0.5, h, 0.), Pt3::new(1., 1., 0.)];
        let r = TriMesh::new(p, vec![[0, 1, 2]]);
        assert_eq!(r.is_ok(), valid, "height {h}: {r:?}");
    }
}

#[test]
fn non_manifold_edge_lists_all_faces() {
    // Three triangles on edge 0–1.
    let p = vec![
        Pt3::new(0., 0., 0.),
        Pt3::new(1., 0., 0.),
        Pt3::new(0.5, 1., 0.),
        Pt3::new(0.5, -1., 0.),
        Pt3::new(0.5, 0., 1.),
    ];
    let f = vec![[0, 1, 2], [1, 0, 3], [0, 1, 4]];
    match TriMesh::new(p, f) {
        Err(Error::NonManifoldEdge { a, b, mut faces }) => {
            faces.sort();
            assert_eq!((a, b, faces), (0, 1, vec![0, 1, 2]));
        }
        r => panic!("expected NonManifoldEdge, got {r:?}"),
    }
}

#[test]
fn inconsistent_orientation_names_both_faces() {
    let (p, mut f) = square();
    f[1] = [0, 3, 2];
    // Face 0 = (0,1,2) has 2→0; flipped face 1 = (0,3,2) has 2→0 too.
    match TriMesh::new(p, f) {
        Err(Error::InconsistentOrientation { face, neighbour }) => assert_eq!((face, neighbour), (0, 1)),
        r => panic!("expected InconsistentOrientation, got {r:?}"),
    }
}

#[test]
fn non_manifold_vertex_is_named() {
    // Two triangles touching only at vertex 0 (a bow tie).
    let p = vec![
        Pt3::new(0., 0., 0.),
        Pt3::new(1., 0., 0.),
        Pt3::new(1., 1., 0.),
        Pt3::new(-1., 0., 0.),
        Pt3::new(-1., -1., 0.),
    ];
    let f = vec![[0, 1, 2], [0, 3, 4]];
    match TriMesh::new(p, f) {
        Err(Error::NonManifoldVertex { vertex }) => assert_eq!(vertex, 0),
        r => panic!("expected NonManifoldVertex, got {r:?}"),
    }
    // Two closed cones sharing their apex (double cone): every edge is fine, the apex is not.
    let mut p = vec![Pt3::origin()];
    let mut f = Vec::new();
    for (s, base) in [(1.0, 1u32), (-1.0, 5u32)] {
        for k in 0..4 {
            let a = std::f64::consts::FRAC_PI_2 * k as f64;
            p.push(Pt3::new(a.cos(), a.sin(), s));
        }
        for k in 0..4 {
            let (i, j) = (base + k, base + (k + 1) % 4);
            f.push(if s > 0.0 { [0, i, j] } else { [0, j, i] });
        }
        // Close each cone's base with two triangles.
        f.push(if s > 0.0 { [base, base + 2, base + 1] } else { [base, base + 1, base + 2] });
        f.push(if s > 0.0 { [base, base + 3, base + 2] } else { [base, base + 2, base + 3] });
    }
    match TriMesh::new(p, f) {
        Err(Error::NonManifoldVertex { vertex }) => assert_eq!(vertex, 0),
        r => panic!("expected NonManifoldVertex, got {r:?}"),
    }
}

#[test]
fn uv_and_positions_checked() {
    let (p, f) = square();
    let m = TriMesh::new(p.clone(), f).expect("square is valid");
    let bad = m.clone().with_uv(Uv::PerVertex(vec![Pt2::origin(); 3]));
    assert!(matches!(bad, Err(Error::DimensionMismatch { expected: 4, got: 3, .. })));
    let m = m.with_uv(Uv::PerCorner(vec![[Pt2::origin(); 3]; 2])).expect("one UV triple per face");
    let moved = m.with_positions(p.iter().map(|q| q + geom_core::math::Vec3::z()).collect()).expect("same count");
    assert!(std::ptr::eq(moved.topology(), m.topology()), "topology shared, not rebuilt");
    assert!(matches!(m.with_positions(vec![]), Err(Error::TopologyMismatch { expected: 4, got: 0 })));
}

#[test]
fn repair_reorients_and_makes_outward() {
    let b =
        box_surface(Pt3::new(0., 0., 0.), Pt3::new(1., 2., 3.), [2, 3, 4], Diagonals::Alternating).expect("valid box");
    let vol = signed_volume(&b.faces, &b.positions);
    // Flip every third face and the whole thing inside out: repair must restore the original.
    let mut f: Vec<[u32; 3]> = b.faces.iter().map(|t| [t[0], t[2], t[1]]).collect();
    for t in f.iter_mut().step_by(3) {
        t.swap(1, 2);
    }
    assert!(TriMesh::new(b.positions.clone(), f.clone()).is_err());
    let (m, rep) = TriMesh::repair(b.positions.clone(), f, &RepairOptions::default()).expect("orientable closed box");
    assert_eq!(m.faces, b.faces);
    assert_eq!(rep.components, 1);
    assert_eq!(rep.flipped_faces, b.faces.len() - b.faces.len().div_ceil(3));
    // 1e-12 relative: the same faces, summed in the same order.
    assert!((signed_volume(&m.faces, &m.positions) - vol).abs() < 1e-12 * vol);
    assert!((vol - 6.0).abs() < 1e-12);
}

#[test]
fn repair_open_mesh_keeps_majority_orientation() {
    let g = grid(&GridSpec { quads: [4, 3], ..Default::default() }).expect("valid grid");
    let mut f = g.faces.clone();
    f[5].swap(1, 2);
    f[9].swap(1, 2);
    let (m, rep) = TriMesh::repair(g.positions.clone(), f, &RepairOptions::default()).expect("orientable");
    assert_eq!(m.faces, g.faces);
    assert_eq!(rep.flipped_faces, 2);
    assert_eq!(rep.reversed_components, 0);
}

#[test]
fn repair_welds_drops_degenerate_and_duplicates() {
    // Two triangles of a square given as soup (6 vertices), plus a duplicate and a sliver.
    let p = vec![
        Pt3::new(0., 0., 0.),
        Pt3::new(1., 0., 0.),
        Pt3::new(1., 1., 0.),
        Pt3::new(0., 0., 0.),
        Pt3::new(1., 1., 1e-12),
        Pt3::new(0., 1., 0.),
        Pt3::new(0.5, 0., 0.),
    ];
    let f = vec![[0, 1, 2], [3, 4, 5], [2, 1, 0], [0, 6, 1]];
    let (m, rep) = TriMesh::repair(p, f, &RepairOptions::default()).expect("repairable");
    assert_eq!(rep.welded_vertices, 2);
    assert_eq!(rep.dropped_duplicate, 1);
    assert_eq!(rep.dropped_degenerate, 1);
    assert_eq!(m.faces, vec![[0, 1, 2], [0, 2, 3]]);
    assert_eq!(m.positions.len(), 5);
}

/// A Möbius strip: orientation propagation must contradict itself.
#[test]
fn moebius_strip_is_inconsistent() {
    let n = 12u32;
    let mut p = Vec::new();
    for k in 0..n {
        let t = 2.0 * std::f64::consts::PI * k as f64 / n as f64;
        for s in [-0.3, 0.3] {
            let r = 1.0 + s * (t / 2.0).cos();
            p.push(Pt3::new(r * t.cos(), r * t.sin(), s * (t / 2.0).sin()));
        }
    }
    let mut f = Vec::new();
    for k in 0..n {
        let (a0, a1) = (2 * k, 2 * k + 1);
        // The last strip segment reconnects with the two sides swapped (the half twist).
        let (b0, b1) = if k + 1 < n { (2 * k + 2, 2 * k + 3) } else { (1, 0) };
        f.push([a0, b0, b1]);
        f.push([a0, b1, a1]);
    }
    match TriMesh::repair(p.clone(), f.clone(), &RepairOptions::default()) {
        Err(Error::InconsistentOrientation { .. }) => {}
        r => panic!("expected InconsistentOrientation, got {r:?}"),
    }
    assert!(matches!(TriMesh::new(p, f), Err(Error::InconsistentOrientation { .. })));
}

#[test]
fn repair_reports_non_manifold_edge() {
    let p = vec![
        Pt3::new(0., 0., 0.),
        Pt3::new(1., 0., 0.),
        Pt3::new(0.5, 1., 0.),
        Pt3::new(0.5, -1., 0.),
        Pt3::new(0.5, 0., 1.),
    ];
    let f = vec![[0, 1, 2], [1, 0, 3], [0, 1, 4]];
    assert!(matches!(TriMesh::repair(p, f, &RepairOptions::default()), Err(Error::NonManifoldEdge { a: 0, b: 1, .. })));
}

#[test]
fn bbox_covers_all_vertices() {
    let (mut p, f) = square();
    p.push(Pt3::new(-2., 0.5, 3.)); // isolated vertex still counts
    let m = TriMesh::new(p, f).expect("square plus a lone vertex is valid");
    let b = m.aabb();
    assert_eq!((b.min, b.max), (Pt3::new(-2., 0., 0.), Pt3::new(1., 1., 3.)));
    assert_eq!(m.bbox(), Some((b.min, b.max)));
    let empty = TriMesh::new(vec![], vec![]).expect("empty mesh");
    assert!(empty.aabb().is_empty());
    assert_eq!(empty.bbox(), None);
}

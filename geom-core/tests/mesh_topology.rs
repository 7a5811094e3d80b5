//! Half-edge topology: hinge convention (shells.md §3.1), boundary loops, one-rings, counts.

use geom_core::math::{Pt3, Vec3};
use geom_core::mesh::{face_normals, hinge_angles, TriMesh, VertexId};
use geom_core::procedural::{box_surface, grid, icosphere, tube, Caps, Diagonals, GridSpec, Plane, TubeSpec};
use geom_core::NONE;

fn meshes() -> Vec<(&'static str, TriMesh)> {
    let g = grid(&GridSpec { quads: [5, 4], size: [2.0, 1.0], ..Default::default() }).expect("valid grid");
    let b =
        box_surface(Pt3::new(-1., -1., -1.), Pt3::new(1., 2., 3.), [2, 1, 3], Diagonals::Forward).expect("valid box");
    let s = icosphere(1.0, 2).expect("valid icosphere");
    let t = tube(&TubeSpec { around: 7, along: 3, ..Default::default() }).expect("valid tube");
    let (t, _) = t.triangulate_fan().expect("tube quads triangulate");
    vec![("grid", g), ("box", b), ("sphere", s), ("tube", t)]
}

#[test]
fn hinges_follow_the_shells_convention() {
    for (name, m) in meshes() {
        let topo = m.topology();
        let hinges = topo.hinges();
        let interior = topo.edge_ids().filter(|&e| !topo.is_boundary_edge(e)).count();
        assert_eq!(hinges.len(), interior, "{name}");
        let has = |t: &[u32; 3], a: u32, b: u32| (0..3).any(|k| t[k] == a && t[(k + 1) % 3] == b);
        for &[a, b, w1, w2] in &hinges {
            assert!(a < b, "{name}: hinge edges are listed with a < b");
            let e = topo.edge_between(a, b).expect("hinge edge exists");
            let [f1, f2] = topo.edge_faces(e);
            assert_ne!(f2, NONE);
            let (t1, t2) = (m.faces[f1 as usize], m.faces[f2 as usize]);
            // tri1 = (a, b, w1) holds a→b, tri2 = (b, a, w2) holds b→a.
            let (ta, tb) = if has(&t1, a, b) { (t1, t2) } else { (t2, t1) };
            assert!(has(&ta, a, b) && has(&ta, b, w1) && has(&ta, w1, a), "{name}: {ta:?} is not (a, b, w1)");
            assert!(has(&tb, b, a) && has(&tb, a, w2) && has(&tb, w2, b), "{name}: {tb:?} is not (b, a, w2)");
        }
    }
}

#[test]
fn boundary_loops_and_euler() {
    let expect = [("grid", 1usize, 1i64), ("box", 0, 2), ("sphere", 0, 2), ("tube", 2, 0)];
    for ((name, m), (n2, loops, chi)) in meshes().into_iter().zip(expect) {
        assert_eq!(name, n2);
        let t = m.topology();
        let bl = t.boundary_loops();
        assert_eq!(bl.len(), loops, "{name}");
        assert_eq!(t.is_closed(), loops == 0, "{name}");
        assert_eq!(t.euler_characteristic(), chi, "{name}");
        assert_eq!(t.face_components().0, 1, "{name}");
        let nb: usize = bl.iter().map(Vec::len).sum();
        assert_eq!(nb, t.n_boundary_edges(), "{name}");
        // Consecutive loop vertices are joined by boundary edges.
        for lp in &bl {
            for k in 0..lp.len() {
                let e = t.edge_between(lp[k], lp[(k + 1) % lp.len()]).expect("loop edge exists");
                assert!(t.is_boundary_edge(e));
                assert!(t.is_boundary_vertex(VertexId(lp[k])));
            }
        }
    }
    // Grid: the outline has 2(nx + ny) vertices and runs counter-clockwise (seen from +Z).
    let g = grid(&GridSpec { quads: [5, 4], ..Default::default() }).expect("valid grid");
    let lp = &g.topology().boundary_loops()[0];
    assert_eq!(lp.len(), 18);
    let area2: f64 = (0..lp.len())
        .map(|k| {
            let (p, q) = (g.positions[lp[k] as usize], g.positions[lp[(k + 1) % lp.len()] as usize]);
            p.x * q.y - q.x * p.y
        })
        .sum();
    assert!(area2 > 0.0, "boundary loop follows the face orientation (CCW)");
}

#[test]
fn icosphere_counts_and_shape() {
    for (level, nv) in [(0u32, 12usize), (1, 42), (2, 162), (3, 642)] {
        let s = icosphere(2.5, level).expect("valid icosphere");
        assert_eq!(s.positions.len(), nv);
        assert_eq!(s.faces.len(), 20 * 4usize.pow(level));
        assert_eq!(s.topology().n_edges(), 30 * 4usize.pow(level));
        for p in &s.positions {
            // Projected onto the sphere: |p| = r up to one rounding of the scaling.
            assert!((p.coords.norm() - 2.5).abs() < 1e-14 * 2.5 * 4.0);
        }
        // Outward: every face normal points away from the centre.
        for (t, n) in s.faces.iter().zip(face_normals(&s.faces, &s.positions)) {
            assert!(n.dot(&s.positions[t[0] as usize].coords) > 0.0);
        }
        // Convex: all dihedral angles fold toward the normal side... i.e. away: negative.
        assert!(hinge_angles(s.topology(), &s.positions).iter().all(|&a| a < 0.0));
    }
}

#[test]
fn one_rings_are_ccw_and_consistent() {
    for (name, m) in meshes() {
        let t = m.topology();
        let vf = t.vertex_faces();
        let vn = t.vertex_neighbors();
        for v in t.vertices() {
            let faces = vf.row(v.0 as usize);
            let ring = vn.row(v.0 as usize);
            let boundary = t.is_boundary_vertex(v);
            assert_eq!(ring.len(), faces.len() + boundary as usize, "{name} v{}", v.0);
            for (k, &f) in faces.iter().enumerate() {
                // Face k of the fan is (v, ring[k], ring[k+1]) in face order: CCW about v.
                let (a, b) = (ring[k], ring[(k + 1) % ring.len()]);
                let tri = m.faces[f as usize];
                let pos = (0..3).find(|&i| tri[i] == v.0).expect("vertex in its face");
                assert_eq!([tri[(pos + 1) % 3], tri[(pos + 2) % 3]], [a, b], "{name} v{} face {f}", v.0);
            }
            let outgoing: Vec<u32> = t.outgoing(v).map(|h| t.target(h).0).collect();
            assert_eq!(&outgoing[..], &ring[..faces.len()]);
        }
        // face_neighbors: entry k is across the edge opposite corner k.
        for f in t.faces() {
            let tri = m.faces[f.0 as usize];
            for (k, &g) in t.face_neighbors(f).iter().enumerate() {
                let (a, b) = (tri[(k + 1) % 3], tri[(k + 2) % 3]);
                let e = t.edge_between(a, b).expect("face edge exists");
                let ef = t.edge_faces(e);
                let other = if ef[0] == f.0 { ef[1] } else { ef[0] };
                assert_eq!(g, other, "{name}");
            }
        }
        // Edges sorted, unique, a < b, and edge(h) agrees with edge_between.
        let edges = t.edges();
        assert!(edges.windows(2).all(|w| w[0] < w[1]) && edges.iter().all(|e| e[0] < e[1]));
        for f in t.faces() {
            for k in 0..3 {
                let h = t.face_half_edge(f, k);
                let e = t.edge(h);
                let (o, d) = (t.origin(h).0, t.target(h).0);
                assert_eq!(Some(e), t.edge_between(o, d));
                assert_eq!(t.face(h), f);
                if let Some(tw) = t.twin(h) {
                    assert_eq!((t.origin(tw).0, t.target(tw).0), (d, o));
                    assert_eq!(t.twin(tw), Some(h));
                }
            }
        }
    }
}

#[test]
fn grid_layout_planes_and_uvs() {
    for plane in [Plane::XY, Plane::XZ, Plane::YZ] {
        let c = Pt3::new(1., 2., 3.);
        let g =
            grid(&GridSpec { quads: [3, 2], size: [3.0, 4.0], plane, diagonals: Diagonals::Alternating, center: c })
                .expect("valid grid");
        let (ax, ay, n) = plane.axes();
        assert_eq!(g.positions.len(), 12);
        assert_eq!(g.faces.len(), 12);
        // Vertex (i, j) = j·4 + i from the min corner.
        let p = |i: usize, j: usize| g.positions[j * 4 + i];
        assert!((p(0, 0) - (c - 1.5 * ax - 2.0 * ay)).norm() < 1e-15);
        assert!((p(3, 2) - (c + 1.5 * ax + 2.0 * ay)).norm() < 1e-15);
        for nf in face_normals(&g.faces, &g.positions) {
            assert!((nf - n).norm() < 1e-15, "{plane:?}: faces point along the plane normal");
        }
        match &g.uv {
            Some(geom_core::mesh::Uv::PerVertex(uv)) => {
                assert_eq!(uv[0], geom_core::math::Pt2::new(0.0, 0.0));
                assert_eq!(uv[11], geom_core::math::Pt2::new(3.0, 4.0));
            }
            u => panic!("grid has per-vertex UVs, got {u:?}"),
        }
    }
}

#[test]
fn tube_layout_and_caps() {
    let s = TubeSpec {
        radius: 0.5,
        length: 2.0,
        around: 6,
        along: 4,
        start: Pt3::new(1., 0., 0.),
        axis: Vec3::z(),
        caps: Caps::Fan,
    };
    let t = tube(&s).expect("valid tube");
    assert_eq!(t.positions.len(), 5 * 6 + 2);
    assert_eq!(t.faces.len(), 4 * 6 + 2 * 6);
    // Vertex (r, k) = r·around + k: ring 2, k = 0 sits at start + 1·ẑ + 0.5·x̂.
    assert!((t.positions[12] - Pt3::new(1.5, 0., 1.)).norm() < 1e-15);
    let (m, parent) = t.triangulate_fan().expect("capped tube is a closed manifold");
    assert!(m.topology().is_closed());
    assert_eq!(m.topology().euler_characteristic(), 2);
    assert_eq!(parent.len(), m.faces.len());
    let v = geom_core::mesh::signed_volume(&m.faces, &m.positions);
    // Inscribed hexagonal prism: (3√3/2) r² · length, positive (outward).
    let exact = 1.5 * 3f64.sqrt() * 0.25 * 2.0;
    assert!((v - exact).abs() < 1e-13, "{v} vs {exact}");
    // Open tube: two boundary loops, quads only.
    let open = tube(&TubeSpec { caps: Caps::Open, ..s }).expect("valid tube");
    assert!(open.faces.rows().all(|r| r.len() == 4));
    let (m, _) = open.triangulate_fan().expect("open tube is a manifold");
    assert_eq!(m.topology().boundary_loops().len(), 2);
}

#[test]
fn box_counts() {
    let b =
        box_surface(Pt3::new(0., 0., 0.), Pt3::new(1., 1., 1.), [1, 1, 1], Diagonals::Alternating).expect("unit cube");
    assert_eq!((b.positions.len(), b.faces.len()), (8, 12));
    let b = box_surface(Pt3::new(0., 0., 0.), Pt3::new(1., 1., 1.), [2, 3, 4], Diagonals::Backward).expect("valid box");
    // V = 2(ab + bc + ca) + 2: a closed genus-0 lattice surface.
    assert_eq!(b.positions.len(), 2 * (6 + 12 + 8) + 2);
    assert_eq!(b.faces.len(), 4 * (6 + 12 + 8));
    assert!((geom_core::mesh::signed_volume(&b.faces, &b.positions) - 1.0).abs() < 1e-15);
    assert!(box_surface(Pt3::new(0., 0., 0.), Pt3::new(1., 0., 1.), [1, 1, 1], Diagonals::Forward).is_err());
    assert!(box_surface(Pt3::new(0., 0., 0.), Pt3::new(1., 1., 1.), [1, 0, 1], Diagonals::Forward).is_err());
}

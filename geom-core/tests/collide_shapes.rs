//! The parry boundary: conversions, MeshQuery on closed meshes, and the obstacle shapes.
#![cfg(feature = "parry")]

use std::sync::Arc;

use geom_core::collide::{convert, Contact, MeshQuery, Placed, Shape};
use geom_core::math::{Iso3, Pt3, UnitQuat, Vec3};
use geom_core::mesh::TriMesh;
use geom_core::procedural::{box_surface, icosphere, Diagonals};
use geom_core::rng::Rng;
use geom_core::Error;

fn rand_pt(rng: &mut Rng, r: f64) -> Pt3 {
    Pt3::new(rng.range(-r, r), rng.range(-r, r), rng.range(-r, r))
}

fn rand_iso(rng: &mut Rng) -> Iso3 {
    let axis = rng.unit_vec3();
    let q = UnitQuat::from_scaled_axis(axis * rng.range(-3.0, 3.0));
    Iso3::from_parts(rand_pt(rng, 2.0).coords.into(), q)
}

/// Exact signed distance to the box `[−h, h]`.
fn box_sdf(p: &Pt3, h: &Vec3) -> f64 {
    let q = p.coords.abs() - h;
    let outside = q.map(|v| v.max(0.0)).norm();
    outside + q.max().min(0.0)
}

/// The unit cube `[−½, ½]³` as a closed mesh (2 segments per side).
fn cube() -> TriMesh {
    box_surface(Pt3::new(-0.5, -0.5, -0.5), Pt3::new(0.5, 0.5, 0.5), [2, 2, 2], Diagonals::Alternating).expect("box")
}

#[test]
fn convert_round_trips_exactly() {
    let mut rng = Rng::new(1);
    for _ in 0..1000 {
        let iso = rand_iso(&mut rng);
        let back = convert::to_iso(&convert::pose(&iso));
        assert_eq!(back.translation.vector, iso.translation.vector);
        assert_eq!(back.rotation.coords, iso.rotation.coords);
        let p = rand_pt(&mut rng, 1e3);
        assert_eq!(convert::to_pt(convert::pt(&p)), p);
        let v = rng.unit_vec3() * 1e-7;
        assert_eq!(convert::to_vec(convert::vec(&v)), v);
        // The converted pose acts the same (up to rounding of the two quaternion products).
        let a = convert::to_pt(convert::pose(&iso) * convert::pt(&p));
        assert!((a - iso * p).norm() < 1e-12 * (1.0 + p.coords.norm()));
    }
}

#[test]
fn mesh_query_signed_distance_on_a_box_is_exact() {
    let q = MeshQuery::new(&cube()).expect("closed");
    let h = Vec3::repeat(0.5);
    let mut rng = Rng::new(2);
    for _ in 0..2000 {
        let p = rand_pt(&mut rng, 1.2);
        let sd = q.signed_distance(&p);
        // Flat faces: the polyhedral distance is the box distance, to rounding.
        assert!((sd - box_sdf(&p, &h)).abs() < 1e-12, "{p:?}: {sd} vs {}", box_sdf(&p, &h));
        let c = q.closest(&p);
        assert!((c.distance - sd.abs()).abs() < 1e-15);
        let f = q.faces()[c.face as usize];
        let r = f.iter().zip(c.bary).fold(Vec3::zeros(), |acc, (&v, b)| acc + q.positions()[v as usize].coords * b);
        assert!((r - c.point.coords).norm() < 1e-12, "barycentrics do not reproduce the closest point");
    }
    // Points near edges and corners, where the pseudo-normal matters.
    for p in
        [Pt3::new(0.5 + 1e-9, 0.5 + 1e-9, 0.0), Pt3::new(0.5 - 1e-9, 0.5 - 1e-9, 0.5 - 1e-9), Pt3::new(0.6, 0.6, 0.6)]
    {
        let sd = q.signed_distance(&p);
        assert_eq!(sd < 0.0, box_sdf(&p, &h) < 0.0, "{p:?}");
    }
}

#[test]
fn mesh_query_sphere_inside_negative_and_inverted_input() {
    let r = 1.0;
    let m = icosphere(r, 3).expect("sphere");
    let q = MeshQuery::new(&m).expect("closed");
    // Inverted orientation: same answers.
    let flipped =
        TriMesh::new(m.positions.clone(), m.faces.iter().map(|f| [f[0], f[2], f[1]]).collect()).expect("valid mesh");
    let qf = MeshQuery::new(&flipped).expect("closed");
    // The convex icosphere lies between the sphere of radius `inner` (its smallest face-plane
    // distance) and the sphere of radius r, so its signed distance differs from the sphere's by
    // at most `gap = r − inner` (≈ 3e-3 at level 3).
    let inner = m
        .faces
        .iter()
        .map(|f| {
            let [a, b, c] = f.map(|v| m.positions[v as usize]);
            let n = (b - a).cross(&(c - a)).normalize();
            n.dot(&a.coords)
        })
        .fold(f64::INFINITY, f64::min);
    let gap = r - inner;
    assert!(gap > 0.0 && gap < 5e-3, "{gap}");
    let mut rng = Rng::new(3);
    for _ in 0..500 {
        let p = Pt3::from(rng.unit_vec3() * rng.range(0.0, 2.0));
        let exact = p.coords.norm() - r;
        let sd = q.signed_distance(&p);
        assert!((sd - exact).abs() <= gap + 1e-12, "{sd} vs {exact}");
        if exact.abs() > gap {
            assert_eq!(sd < 0.0, exact < 0.0);
        }
        assert_eq!(qf.signed_distance(&p), sd);
        let (a, b) = (q.closest(&p), qf.closest(&p));
        assert_eq!((a.point, a.face), (b.point, b.face));
        let f = flipped.faces[b.face as usize];
        let rb =
            f.iter().zip(b.bary).fold(Vec3::zeros(), |acc, (&v, w)| acc + flipped.positions[v as usize].coords * w);
        assert!((rb - b.point.coords).norm() < 1e-12);
    }
    // A ray through the centre enters between radii r and inner.
    let (t, f) = q.ray_cast(&Pt3::new(3.0, 0.0, 0.0), &Vec3::new(-2.0, 0.0, 0.0), 10.0).expect("hit");
    assert!(t >= (3.0 - r) / 2.0 - 1e-12 && t <= (3.0 - inner) / 2.0 + 1e-12, "{t}");
    assert!((f as usize) < m.faces.len());
    assert!(q.ray_cast(&Pt3::new(3.0, 0.0, 0.0), &Vec3::new(1.0, 0.0, 0.0), 10.0).is_none());
}

#[test]
fn open_mesh_is_rejected() {
    let m = cube();
    let open = TriMesh::new(m.positions.clone(), m.faces[1..].to_vec()).expect("valid open mesh");
    match MeshQuery::new(&open) {
        Err(Error::NotClosed { boundary_edges }) => assert_eq!(boundary_edges, 3),
        other => panic!("expected NotClosed, got {other:?}"),
    }
}

/// An exact world-space signed distance function.
type Sdf = Box<dyn Fn(&Pt3) -> f64>;

fn shapes(rng: &mut Rng) -> Vec<(Placed, Sdf)> {
    // Each shape with an exact world-space signed distance function.
    let mut out: Vec<(Placed, Sdf)> = Vec::new();
    let iso = rand_iso(rng);
    let n = rng.unit_vec3();
    let (pose, nn) = (iso, n);
    out.push((
        Placed::new(Shape::HalfSpace { normal: n * 3.0 }, iso),
        Box::new(move |p: &Pt3| (pose.rotation * nn).dot(&(p - Pt3::from(pose.translation.vector)))),
    ));
    let iso = rand_iso(rng);
    out.push((
        Placed::new(Shape::Ball { radius: 0.7 }, iso),
        Box::new(move |p: &Pt3| (p.coords - iso.translation.vector).norm() - 0.7),
    ));
    let iso = rand_iso(rng);
    let (a, b) = (Pt3::new(-0.4, 0.1, 0.0), Pt3::new(0.5, -0.2, 0.3));
    out.push((
        Placed::new(Shape::Capsule { a, b, radius: 0.3 }, iso),
        Box::new(move |p: &Pt3| {
            let pl = iso.inverse_transform_point(p);
            (pl - geom_core::query::closest_point_segment(&pl, &a, &b).1).norm() - 0.3
        }),
    ));
    let iso = rand_iso(rng);
    let h = Vec3::new(0.3, 0.5, 0.7);
    out.push((
        Placed::new(Shape::Cuboid { half: h }, iso),
        Box::new(move |p: &Pt3| box_sdf(&iso.inverse_transform_point(p), &h)),
    ));
    let iso = rand_iso(rng);
    let hr = 0.15;
    out.push((
        Placed::new(Shape::Cuboid { half: h }, iso).inflated(hr),
        Box::new(move |p: &Pt3| box_sdf(&iso.inverse_transform_point(p), &h) - hr),
    ));
    let iso = rand_iso(rng);
    let cube = Arc::new(MeshQuery::new(&cube()).expect("closed"));
    out.push((
        Placed::new(Shape::Mesh(cube.clone()), iso),
        Box::new(move |p: &Pt3| box_sdf(&iso.inverse_transform_point(p), &Vec3::repeat(0.5))),
    ));
    let iso = rand_iso(rng);
    out.push((
        Placed::new(Shape::Mesh(cube), iso).inflated(0.1),
        Box::new(move |p: &Pt3| box_sdf(&iso.inverse_transform_point(p), &Vec3::repeat(0.5)) - 0.1),
    ));
    out
}

#[test]
fn project_point_matches_exact_distances() {
    let mut rng = Rng::new(4);
    for _ in 0..5 {
        for (k, (s, sdf)) in shapes(&mut rng).into_iter().enumerate() {
            for _ in 0..200 {
                let p = Pt3::from(s.pose.translation.vector) + rand_pt(&mut rng, 1.5).coords;
                let pr = s.project_point(&p);
                let exact = sdf(&p);
                assert!((pr.signed_distance - exact).abs() < 1e-9, "shape {k}: {} vs {exact}", pr.signed_distance);
                assert_eq!(pr.inside, pr.signed_distance < 0.0);
                // The projection lies on the surface, at |signed distance| from p.
                assert!(sdf(&pr.point).abs() < 1e-9, "shape {k}: projection off the surface by {}", sdf(&pr.point));
                assert!(((p - pr.point).norm() - exact.abs()).abs() < 1e-9, "shape {k}");
            }
        }
    }
}

/// First root of `sdf` along the ray by dense sampling and bisection (reference).
fn march(sdf: &dyn Fn(&Pt3) -> f64, o: &Pt3, d: &Vec3, max_t: f64) -> Option<f64> {
    if sdf(o) <= 0.0 {
        return Some(0.0);
    }
    let n = 4000;
    let mut prev = 0.0;
    for i in 1..=n {
        let t = max_t * i as f64 / n as f64;
        if sdf(&(o + d * t)) <= 0.0 {
            let (mut lo, mut hi) = (prev, t);
            for _ in 0..80 {
                let mid = 0.5 * (lo + hi);
                if sdf(&(o + d * mid)) <= 0.0 {
                    hi = mid;
                } else {
                    lo = mid;
                }
            }
            return Some(hi);
        }
        prev = t;
    }
    None
}

#[test]
fn ray_casts_match_marching_on_the_exact_sdf() {
    let mut rng = Rng::new(5);
    let mut hits = 0;
    for _ in 0..4 {
        for (k, (s, sdf)) in shapes(&mut rng).into_iter().enumerate() {
            for _ in 0..60 {
                let c = Pt3::from(s.pose.translation.vector);
                let o = c + rng.unit_vec3() * rng.range(0.2, 3.0);
                // Aim near the shape's centre so that most rays hit.
                let d = (c + rand_pt(&mut rng, 0.5).coords - o).normalize() * 0.5;
                let got = s.cast_ray(&o, &d, 10.0);
                let want = march(&*sdf, &o, &d, 10.0);
                match (got, want) {
                    (Some((t, n)), Some(tw)) => {
                        // Marching resolves the root to 10/4000 before bisection; grazing rays
                        // may be missed by it, hence the loose 1e-6 on t.
                        assert!((t - tw).abs() < 1e-6, "shape {k}: t {t} vs {tw}");
                        assert!((n.norm() - 1.0).abs() < 1e-9, "shape {k}: normal not unit");
                        if t > 0.0 {
                            // Outward: the SDF grows along the normal at the hit.
                            let x = o + d * t;
                            assert!(sdf(&(x + n * 1e-6)) > sdf(&(x - n * 1e-6)), "shape {k}");
                            hits += 1;
                        }
                    }
                    (None, None) => {}
                    (g, w) => {
                        // Only tangent (grazing) rays may disagree: the SDF minimum along the ray ~ 0.
                        let min = (0..=4000)
                            .map(|i| sdf(&(o + d * (10.0 * i as f64 / 4000.0))))
                            .fold(f64::INFINITY, f64::min);
                        assert!(min.abs() < 1e-3, "shape {k}: {g:?} vs {w:?} (closest approach {min})");
                    }
                }
            }
        }
    }
    assert!(hits > 500, "{hits}");
}

/// Brute-force minimum of `sdf` over a triangle (barycentric grid).
fn min_over_triangle(sdf: &dyn Fn(&Pt3) -> f64, t: &[Pt3; 3], n: usize) -> f64 {
    let mut best = f64::INFINITY;
    for i in 0..=n {
        for j in 0..=n - i {
            let (u, v) = (i as f64 / n as f64, j as f64 / n as f64);
            best = best.min(sdf(&(t[0] + (t[1] - t[0]) * u + (t[2] - t[0]) * v)));
        }
    }
    best
}

/// Shapes 5 and 6 of [`shapes`] are meshes.
fn is_mesh(k: usize) -> bool {
    k >= 5
}

fn check_contact(k: usize, c: &Contact, sdf: &dyn Fn(&Pt3) -> f64, brute: f64, tol: f64) {
    assert!((c.normal.norm() - 1.0).abs() < 1e-9, "shape {k}: normal not unit");
    if brute > 0.0 {
        // Separated: the exact distance, a closest pair on the surface, normal along it.
        assert!((c.distance - brute).abs() < tol, "shape {k}: distance {} vs {brute}", c.distance);
        assert!(sdf(&c.on_shape).abs() < tol, "shape {k}: on_shape off the surface");
        assert!(((c.on_other - c.on_shape).norm() - c.distance).abs() < tol, "shape {k}");
        assert!((c.on_other - c.on_shape - c.normal * c.distance).norm() < 10.0 * tol, "shape {k}: normal");
    } else {
        assert!(c.distance <= tol, "shape {k}: penetrating but distance {}", c.distance);
    }
}

#[test]
fn triangle_and_segment_contacts() {
    let mut rng = Rng::new(6);
    let mut separated = 0;
    for _ in 0..2 {
        for (k, (s, sdf)) in shapes(&mut rng).into_iter().enumerate() {
            for _ in 0..40 {
                let c = Pt3::from(s.pose.translation.vector);
                let base = c + rng.unit_vec3() * rng.range(0.3, 2.0);
                let t = [base, base + rand_pt(&mut rng, 0.6).coords, base + rand_pt(&mut rng, 0.6).coords];
                // The brute-force minimum of the SDF over the triangle is its distance to the
                // solid when positive (sampling error ≤ grid spacing · |∇sdf| ≈ 1.2/300).
                let brute = min_over_triangle(&*sdf, &t, 300);
                let tol = if brute > 0.0 { 5e-3 } else { 1e-9 };
                match s.contact_triangle(&t, 10.0) {
                    Some(ct) => {
                        // The sampled minimum bounds the distance from above when separated, and
                        // for convex shapes also when penetrating (depth ≥ deepest point). Meshes
                        // report a local (triangle-pair or corner) depth when penetrating.
                        if brute > 0.0 || !is_mesh(k) {
                            assert!(ct.distance <= brute + 1e-9, "shape {k}: {} > sampled {brute}", ct.distance);
                        }
                        check_contact(k, &ct, &*sdf, brute, tol);
                        if brute > 0.0 {
                            separated += 1;
                        }
                    }
                    None => panic!("shape {k}: no contact with margin 10"),
                }
                // Margin filter.
                if brute > 0.1 {
                    assert!(s.contact_triangle(&t, 0.0).is_none(), "shape {k}");
                }
                // Segment = degenerate triangle; compare with sampling along it.
                let (a, b) = (t[0], t[1]);
                let seg_brute =
                    (0..=2000).map(|i| sdf(&(a + (b - a) * (i as f64 / 2000.0)))).fold(f64::INFINITY, f64::min);
                let cs = s.contact_segment(&a, &b, 10.0).expect("contact within margin 10");
                if seg_brute > 0.0 || !is_mesh(k) {
                    assert!(cs.distance <= seg_brute + 1e-9, "shape {k}: segment {} > {seg_brute}", cs.distance);
                }
                let tol = if seg_brute > 0.0 { 1e-3 } else { 1e-9 };
                check_contact(k, &cs, &*sdf, seg_brute, tol);
            }
        }
    }
    assert!(separated > 150, "{separated}");
}

#[test]
fn inflation_grows_every_shape() {
    let mut rng = Rng::new(7);
    for (k, (s, sdf)) in shapes(&mut rng).into_iter().enumerate() {
        let g = s.inflated(0.2);
        for _ in 0..50 {
            let p = Pt3::from(s.pose.translation.vector) + rand_pt(&mut rng, 1.5).coords;
            let (a, b) = (g.project_point(&p).signed_distance, sdf(&p) - 0.2);
            // Exact for half-spaces, balls, capsules and rounded boxes; meshes here are boxes.
            assert!((a - b).abs() < 1e-9, "shape {k}: {a} vs {b}");
        }
    }
}

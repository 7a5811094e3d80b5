//! Exact triangle–triangle intersection against an independent exact reference: the
//! separating-axis theorem evaluated in integer arithmetic (i128) on small-integer and dyadic
//! coordinates, on random and deliberately degenerate configurations.

use geom_core::math::Pt3;
use geom_core::query::{
    count_self_intersections, segment_triangle_intersect, self_intersecting_pairs, tri_tri_intersect,
};
use geom_core::rng::Rng;

type I3 = [i128; 3];

fn sub(a: I3, b: I3) -> I3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
fn cross(a: I3, b: I3) -> I3 {
    [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
}
fn dot(a: I3, b: I3) -> i128 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// SAT for two non-degenerate closed triangles: axes are both normals, the nine edge cross
/// products and the in-plane edge normals `n × e` (complete for coplanar and non-coplanar
/// pairs). Touching (equal interval ends) counts as intersecting.
fn sat_intersect(a: &[I3; 3], b: &[I3; 3]) -> bool {
    let ea = [sub(a[1], a[0]), sub(a[2], a[1]), sub(a[0], a[2])];
    let eb = [sub(b[1], b[0]), sub(b[2], b[1]), sub(b[0], b[2])];
    let (na, nb) = (cross(ea[0], ea[1]), cross(eb[0], eb[1]));
    assert!(na != [0; 3] && nb != [0; 3], "reference needs non-degenerate triangles");
    let mut axes = vec![na, nb];
    for e in &ea {
        for f in &eb {
            axes.push(cross(*e, *f));
        }
        axes.push(cross(na, *e));
    }
    for f in &eb {
        axes.push(cross(nb, *f));
    }
    for ax in axes {
        if ax == [0; 3] {
            continue;
        }
        let pa: Vec<i128> = a.iter().map(|p| dot(*p, ax)).collect();
        let pb: Vec<i128> = b.iter().map(|p| dot(*p, ax)).collect();
        let (amin, amax) = (*pa.iter().min().unwrap(), *pa.iter().max().unwrap());
        let (bmin, bmax) = (*pb.iter().min().unwrap(), *pb.iter().max().unwrap());
        if amax < bmin || bmax < amin {
            return false;
        }
    }
    true
}

/// Integer triangle → f64 triangle with coordinates `k · scale + offset` (exact for the scales
/// and offsets used: powers of two and small integers).
fn to_f64(t: &[I3; 3], scale: f64, offset: f64) -> [Pt3; 3] {
    t.map(|p| Pt3::new(p[0] as f64 * scale + offset, p[1] as f64 * scale + offset, p[2] as f64 * scale + offset))
}

fn degenerate(t: &[I3; 3]) -> bool {
    cross(sub(t[1], t[0]), sub(t[2], t[0])) == [0; 3]
}

fn rand_pt(rng: &mut Rng, r: i128) -> I3 {
    std::array::from_fn(|_| rng.below((2 * r + 1) as usize) as i128 - r)
}

fn check(a: &[I3; 3], b: &[I3; 3], counts: &mut [usize; 2]) {
    let expect = sat_intersect(a, b);
    counts[expect as usize] += 1;
    for (scale, offset) in [(1.0, 0.0), (0.0009765625, 0.0), (0.125, 1024.0)] {
        let (fa, fb) = (to_f64(a, scale, offset), to_f64(b, scale, offset));
        assert_eq!(tri_tri_intersect(&fa, &fb), expect, "a = {a:?}, b = {b:?}, scale {scale}, offset {offset}");
        assert_eq!(tri_tri_intersect(&fb, &fa), expect, "swapped: a = {a:?}, b = {b:?}");
        // Corner order and orientation do not matter.
        let fa2 = [fa[1], fa[0], fa[2]];
        let fb2 = [fb[2], fb[0], fb[1]];
        assert_eq!(tri_tri_intersect(&fa2, &fb2), expect, "permuted: a = {a:?}, b = {b:?}");
    }
}

#[test]
fn random_small_integer_triangles_match_sat() {
    let mut rng = Rng::new(2024);
    let mut counts = [0usize; 2];
    let mut n = 0;
    while n < 20_000 {
        let r = if n % 2 == 0 { 2 } else { 6 };
        let a: [I3; 3] = std::array::from_fn(|_| rand_pt(&mut rng, r));
        let b: [I3; 3] = std::array::from_fn(|_| rand_pt(&mut rng, r));
        if degenerate(&a) || degenerate(&b) {
            continue;
        }
        check(&a, &b, &mut counts);
        n += 1;
    }
    // Both outcomes must be well represented for the comparison to mean anything.
    assert!(counts[0] > 2000 && counts[1] > 2000, "{counts:?}");
}

#[test]
fn degenerate_configurations_match_sat() {
    let mut rng = Rng::new(99);
    let mut counts = [0usize; 2];
    let mut n = 0;
    while n < 20_000 {
        let a: [I3; 3] = std::array::from_fn(|_| rand_pt(&mut rng, 4));
        if degenerate(&a) {
            continue;
        }
        let b: [I3; 3] = match n % 6 {
            // Shared edge (either direction), third corner anywhere (coplanar or not).
            0 => [a[1], a[0], rand_pt(&mut rng, 4)],
            // Shared vertex.
            1 => [a[2], rand_pt(&mut rng, 4), rand_pt(&mut rng, 4)],
            // Coplanar: everything in z = 0.
            2 => {
                let mut q: [I3; 3] = std::array::from_fn(|_| rand_pt(&mut rng, 3));
                for v in &mut q {
                    v[2] = 0;
                }
                q
            }
            // Vertex of b on an edge of a (midpoint with even coordinates doubled).
            3 => {
                let m = [(a[0][0] + a[1][0]), (a[0][1] + a[1][1]), (a[0][2] + a[1][2])];
                let a2 = a.map(|v| v.map(|c| 2 * c));
                let b = [m, rand_pt(&mut rng, 8), rand_pt(&mut rng, 8)];
                if !degenerate(&b) {
                    check(&a2, &b, &mut counts);
                    n += 1;
                }
                continue;
            }
            // b in the plane of a: an affine combination of a's corners, doubled to stay integral.
            4 => {
                let a2 = a.map(|v| v.map(|c| 2 * c));
                let mut b = [[0i128; 3]; 3];
                for v in &mut b {
                    let (s, t) = (rng.below(5) as i128 - 1, rng.below(5) as i128 - 1);
                    // 2a0 + s(a1 − a0) + t(a2 − a0): in the plane of 2a.
                    for k in 0..3 {
                        v[k] = 2 * a[0][k] + s * (a[1][k] - a[0][k]) + t * (a[2][k] - a[0][k]);
                    }
                }
                if !degenerate(&b) {
                    check(&a2, &b, &mut counts);
                    n += 1;
                }
                continue;
            }
            // Coplanar with a z = 0 triangle too.
            _ => {
                let mut a0 = a;
                for v in &mut a0 {
                    v[2] = 0;
                }
                let mut q: [I3; 3] = std::array::from_fn(|_| rand_pt(&mut rng, 4));
                for v in &mut q {
                    v[2] = 0;
                }
                if !degenerate(&a0) && !degenerate(&q) {
                    check(&a0, &q, &mut counts);
                    n += 1;
                }
                continue;
            }
        };
        if !degenerate(&b) {
            check(&a, &b, &mut counts);
            n += 1;
        }
    }
    assert!(counts[0] > 1000 && counts[1] > 1000, "{counts:?}");
}

#[test]
fn hand_made_cases() {
    let p = |x: f64, y: f64, z: f64| Pt3::new(x, y, z);
    let t = [p(0.0, 0.0, 0.0), p(1.0, 0.0, 0.0), p(0.0, 1.0, 0.0)];
    // Touching at a single vertex, apart by one ulp.
    assert!(tri_tri_intersect(&t, &[p(1.0, 0.0, 0.0), p(2.0, 0.0, 1.0), p(2.0, 1.0, -1.0)]));
    let e = 1.0 + f64::EPSILON;
    assert!(!tri_tri_intersect(&t, &[p(e, 0.0, 0.0), p(2.0, 0.0, 1.0), p(2.0, 1.0, -1.0)]));
    // A triangle standing on the hypotenuse (touching along a segment).
    assert!(tri_tri_intersect(&t, &[p(0.75, 0.25, 0.0), p(0.25, 0.75, 0.0), p(0.5, 0.5, 1.0)]));
    // Piercing through the interior.
    assert!(tri_tri_intersect(&t, &[p(0.2, 0.2, -1.0), p(0.3, 0.2, 1.0), p(0.2, 0.3, 1.0)]));
    // Parallel planes.
    assert!(!tri_tri_intersect(&t, &[p(0.0, 0.0, 1e-300), p(1.0, 0.0, 1e-300), p(0.0, 1.0, 1e-300)]));
    // Degenerate triangles: a segment crossing the face, a segment beside it, a point on it.
    let seg_in = [p(0.25, 0.25, -1.0), p(0.25, 0.25, 1.0), p(0.25, 0.25, 0.0)];
    assert!(tri_tri_intersect(&t, &seg_in));
    let seg_out = [p(0.75, 0.75, -1.0), p(0.75, 0.75, 1.0), p(0.75, 0.75, 0.5)];
    assert!(!tri_tri_intersect(&t, &seg_out));
    assert!(tri_tri_intersect(&[p(0.5, 0.5, 0.0); 3], &t));
    assert!(!tri_tri_intersect(&[p(0.5, 0.5 + 1e-16, 0.0); 3], &t));
    // Segment–segment and point–segment (both degenerate).
    let s1 = [p(0.0, 0.0, 0.0), p(2.0, 2.0, 2.0), p(1.0, 1.0, 1.0)];
    let s2 = [p(2.0, 0.0, 0.0), p(0.0, 2.0, 2.0), p(0.0, 2.0, 2.0)];
    assert!(tri_tri_intersect(&s1, &s2));
    let s3 = [p(2.0, 0.0, 0.0), p(0.0, 2.0, 2.5), p(0.0, 2.0, 2.5)];
    assert!(!tri_tri_intersect(&s1, &s3));
    let collinear = [p(3.0, 3.0, 3.0), p(2.0, 2.0, 2.0), p(2.5, 2.5, 2.5)];
    assert!(tri_tri_intersect(&s1, &collinear));
    assert!(!tri_tri_intersect(&s1, &[p(3.0, 3.0, 3.0), p(2.5, 2.5, 2.5), p(2.0 + 1e-15, 2.0 + 1e-15, 2.0 + 1e-15)]));
    assert!(tri_tri_intersect(&[p(1.0, 1.0, 1.0); 3], &s1));
    assert!(segment_triangle_intersect(&p(1.0, 0.0, 5.0), &p(1.0, 0.0, -5.0), &t));
    assert!(!segment_triangle_intersect(&p(1.0, 1e-17, 5.0), &p(1.0, 1e-17, -5.0), &t));
    // -0.0 and 0.0 are the same coordinate.
    assert!(tri_tri_intersect(&[p(-0.0, 0.5, 0.0); 3], &[p(0.0, 0.0, 0.0), p(0.0, 1.0, 0.0), p(0.0, 1.0, 0.0)]));
}

#[test]
fn self_intersections_equal_brute_force() {
    let mut rng = Rng::new(5);
    // A triangle soup with shared vertices: 60 points, 150 faces.
    let p: Vec<Pt3> =
        (0..60).map(|_| Pt3::new(rng.range(0.0, 4.0), rng.range(0.0, 4.0), rng.range(0.0, 4.0))).collect();
    let faces: Vec<[u32; 3]> = (0..150)
        .filter_map(|_| {
            let f = [rng.below(60) as u32, rng.below(60) as u32, rng.below(60) as u32];
            (f[0] != f[1] && f[1] != f[2] && f[0] != f[2]).then_some(f)
        })
        .collect();
    let mut brute = Vec::new();
    for i in 0..faces.len() {
        for j in i + 1..faces.len() {
            if faces[i].iter().any(|v| faces[j].contains(v)) {
                continue;
            }
            let ti = faces[i].map(|v| p[v as usize]);
            let tj = faces[j].map(|v| p[v as usize]);
            if tri_tri_intersect(&ti, &tj) {
                brute.push((i as u32, j as u32));
            }
        }
    }
    assert!(brute.len() > 10, "soup should self-intersect");
    assert_eq!(self_intersecting_pairs(&faces, &p), brute);
    assert_eq!(count_self_intersections(&faces, &p), brute.len());
    // A clean flat strip has none (neighbours share vertices, others are apart).
    let strip_p: Vec<[f32; 3]> = (0..20).map(|i| [(i / 2) as f32, (i % 2) as f32, 0.0]).collect();
    let strip_f: Vec<[u32; 3]> =
        (0..18).map(|i| if i % 2 == 0 { [i, i + 1, i + 2] } else { [i + 1, i, i + 2] }).collect();
    assert_eq!(count_self_intersections(&strip_f, &strip_p), 0);
}

mod props {
    use super::*;
    use proptest::prelude::*;

    fn tri() -> impl Strategy<Value = [I3; 3]> {
        proptest::array::uniform3(proptest::array::uniform3(-3i128..=3))
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(2000))]

        #[test]
        fn matches_sat_and_is_symmetric(a in tri(), b in tri()) {
            prop_assume!(!degenerate(&a) && !degenerate(&b));
            let (fa, fb) = (to_f64(&a, 0.5, 0.0), to_f64(&b, 0.5, 0.0));
            let r = tri_tri_intersect(&fa, &fb);
            prop_assert_eq!(r, sat_intersect(&a, &b));
            prop_assert_eq!(r, tri_tri_intersect(&fb, &fa));
            prop_assert_eq!(r, tri_tri_intersect(&[fa[2], fa[1], fa[0]], &fb));
        }
    }
}

//! Closest-point functions against brute-force sampling.

use geom_core::math::Pt3;
use geom_core::query::{closest_point_segment, closest_point_triangle, closest_points_segments};
use geom_core::rng::Rng;

fn rand_pt(rng: &mut Rng, r: f64) -> Pt3 {
    Pt3::new(rng.range(-r, r), rng.range(-r, r), rng.range(-r, r))
}

/// Slack for comparing a computed minimum with sampled candidates: rounding of distances of
/// O(1) magnitude (a few ulps).
const TOL: f64 = 1e-12;

#[test]
fn triangle_closest_point_beats_every_sample() {
    let mut rng = Rng::new(1);
    let n = 60; // samples per edge of the barycentric grid
    for case in 0..300 {
        let mut t = [rand_pt(&mut rng, 1.0), rand_pt(&mut rng, 1.0), rand_pt(&mut rng, 1.0)];
        if case % 10 == 0 {
            t[2] = t[0] + (t[1] - t[0]) * 0.3; // degenerate (collinear)
        }
        let p = rand_pt(&mut rng, 2.0);
        let (q, b) = closest_point_triangle(&p, &t);
        // q is on the triangle: valid barycentrics reproducing it.
        assert!(b.iter().all(|&x| (-1e-15..=1.0 + 1e-15).contains(&x)), "{b:?}");
        assert!((b[0] + b[1] + b[2] - 1.0).abs() < 1e-14);
        let r = t[0].coords * b[0] + t[1].coords * b[1] + t[2].coords * b[2];
        assert!((r - q.coords).norm() < 1e-14, "bary does not reproduce the point");
        // No sample of the triangle is closer.
        let d = (p - q).norm();
        for i in 0..=n {
            for j in 0..=n - i {
                let (u, v) = (i as f64 / n as f64, j as f64 / n as f64);
                let s = t[0] + (t[1] - t[0]) * u + (t[2] - t[0]) * v;
                assert!(d <= (p - s).norm() + TOL, "case {case}: sample closer than the answer");
            }
        }
    }
}

#[test]
fn segment_closest_point_beats_every_sample() {
    let mut rng = Rng::new(2);
    for _ in 0..500 {
        let (a, b, p) = (rand_pt(&mut rng, 1.0), rand_pt(&mut rng, 1.0), rand_pt(&mut rng, 2.0));
        let (t, q) = closest_point_segment(&p, &a, &b);
        assert!((0.0..=1.0).contains(&t));
        assert!((a + (b - a) * t - q).norm() < 1e-15);
        let d = (p - q).norm();
        for i in 0..=1000 {
            let s = a + (b - a) * (i as f64 / 1000.0);
            assert!(d <= (p - s).norm() + TOL);
        }
    }
}

#[test]
fn segment_pairs_beat_every_sample_including_parallel_ones() {
    let mut rng = Rng::new(3);
    let n = 200;
    for case in 0..300 {
        let (p0, p1) = (rand_pt(&mut rng, 1.0), rand_pt(&mut rng, 1.0));
        let (q0, q1) = match case % 4 {
            // Exactly parallel, overlapping in projection.
            0 => {
                let off = rand_pt(&mut rng, 0.5).coords;
                (p0 + off + (p1 - p0) * 0.25, p1 + off + (p1 - p0) * 0.5)
            }
            // Zero-length second segment.
            1 => {
                let q = rand_pt(&mut rng, 1.0);
                (q, q)
            }
            _ => (rand_pt(&mut rng, 1.0), rand_pt(&mut rng, 1.0)),
        };
        let (s, t, c1, c2) = closest_points_segments(&p0, &p1, &q0, &q1);
        assert!((0.0..=1.0).contains(&s) && (0.0..=1.0).contains(&t));
        assert!((p0 + (p1 - p0) * s - c1).norm() < 1e-14);
        assert!((q0 + (q1 - q0) * t - c2).norm() < 1e-14);
        let d = (c1 - c2).norm();
        for i in 0..=n {
            let x = p0 + (p1 - p0) * (i as f64 / n as f64);
            for j in 0..=n {
                let y = q0 + (q1 - q0) * (j as f64 / n as f64);
                assert!(d <= (x - y).norm() + TOL, "case {case}");
            }
        }
    }
}

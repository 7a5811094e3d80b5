//! Skinning quality metrics (spec §2.4, §7): enclosed volume, joint / ring radius ratios,
//! distance to the posed bones, fold fraction of a deformation map, influence histograms, and
//! the vertex error against a reference deformation.
//!
//! Every extremum propagates NaN (`geom_core::stats::nan_min` / `nan_max`): a deformation that
//! produced a NaN vertex reports NaN, never the extremum of the remaining vertices.

use geom_core::math::{AsPt3, Pt3, Vec3};
use geom_core::query::closest_point_segment;
use geom_core::stats::{nan_max, nan_min};

/// Signed volume enclosed by a closed, outward-oriented triangle mesh (divergence theorem,
/// accumulated in `f64`; positive for outward faces): `geom_core::mesh::signed_volume`, which
/// takes the bounding-box centre as reference point (better conditioned than the origin).
pub fn signed_volume<P: AsPt3>(pos: &[P], tris: &[[u32; 3]]) -> f64 {
    geom_core::mesh::signed_volume(tris, pos)
}

/// Joint radius ratio: over the rest vertices within `sqrt(radius² + band²)` of the rest joint
/// (the ring(s) nearest the joint on a tube of that radius), the smallest deformed distance to
/// the posed joint, divided by `radius`. LBS at a bend β gives ≈ cos(β/2) (spec §3.2). Returns
/// NaN when no vertex qualifies.
pub fn joint_radius_ratio<P: AsPt3, Q: AsPt3>(
    pos: &[P],
    rest: &[Q],
    joint_posed: Pt3,
    joint_rest: Pt3,
    radius: f64,
    band: f64,
) -> f64 {
    let lim = (radius * radius + band * band).sqrt() * (1.0 + 1e-9);
    let mut best = f64::INFINITY;
    for (p, r) in pos.iter().zip(rest) {
        let r = r.pt3();
        let d0 = (r - joint_rest).norm();
        if d0 <= lim && d0 >= 0.5 * radius {
            best = nan_min(best, (p.pt3() - joint_posed).norm());
        }
    }
    if best.is_finite() {
        best / radius
    } else {
        f64::NAN
    }
}

/// Ring radius ratio about a fixed axis: over rest vertices whose axial coordinate
/// `(x − origin)·axis` lies in `[lo, hi]` and that are at least `radius/2` from the axis, the
/// smallest deformed distance to the axis line divided by `radius` (twist tests, spec §7.2 b).
pub fn ring_radius_ratio<P: AsPt3, Q: AsPt3>(
    pos: &[P],
    rest: &[Q],
    origin: Pt3,
    axis: Vec3,
    lo: f64,
    hi: f64,
    radius: f64,
) -> f64 {
    let a = axis.normalize();
    let mut best = f64::INFINITY;
    for (p, r) in pos.iter().zip(rest) {
        let q = r.pt3() - origin;
        let t = q.dot(&a);
        if t < lo || t > hi || (q - a * t).norm() < 0.5 * radius {
            continue;
        }
        let d = p.pt3() - origin;
        best = nan_min(best, (d - a * d.dot(&a)).norm());
    }
    if best.is_finite() {
        best / radius
    } else {
        f64::NAN
    }
}

/// Number of intersecting triangle pairs that share no vertex (spec §2.4; geom-core's AABB tree
/// broad phase and exact triangle–triangle test). Pairs sharing a vertex are adjacent by
/// construction and skipped.
pub fn self_intersections<P: AsPt3>(pos: &[P], tris: &[[u32; 3]]) -> usize {
    geom_core::query::count_self_intersections(tris, pos)
}

/// Minimum and maximum over `pos` of the distance to the nearest posed bone segment (m); NaN
/// when a position is NaN.
pub fn distance_to_bones<P: AsPt3>(pos: &[P], bones: &[(Pt3, Pt3)]) -> (f64, f64) {
    let mut lo = f64::INFINITY;
    let mut hi: f64 = 0.0;
    for p in pos {
        let p = p.pt3();
        let d = bones.iter().map(|(a, b)| (closest_point_segment(&p, a, b).1 - p).norm()).fold(f64::INFINITY, nan_min);
        lo = nan_min(lo, d);
        hi = nan_max(hi, d);
    }
    (lo, hi)
}

/// Largest and root-mean-square distance (m) between corresponding points of `a` and `b` (a
/// deformation against its reference); NaN if any distance is NaN, `(0, 0)` for empty input.
pub fn max_rms_error(a: &[Pt3], b: &[Pt3]) -> (f64, f64) {
    let mut mx: f64 = 0.0;
    let mut s = 0.0;
    for (x, y) in a.iter().zip(b) {
        let d = (x - y).norm();
        mx = nan_max(mx, d);
        s += d * d;
    }
    (mx, (s / a.len().max(1) as f64).sqrt())
}

/// `f32` positions (the skinners' output) as `f64` points.
pub fn to_f64(p: &[[f32; 3]]) -> Vec<Pt3> {
    p.iter().map(|x| Pt3::new(x[0] as f64, x[1] as f64, x[2] as f64)).collect()
}

/// Histogram of sparse weight-row sizes, the last bin holding every row of `cap` or more entries
/// (`h[k]` = rows with `k` influences).
pub fn rows_histogram(rows: &[Vec<(u16, f32)>], cap: usize) -> Vec<usize> {
    let mut h = vec![0usize; cap + 1];
    for r in rows {
        h[r.len().min(cap)] += 1;
    }
    h
}

/// Fraction of `samples` where the deformation `map` folds: `det J ≤ 0`, J by central
/// differences with step `h` (spec §7.4 c). NaN determinants count as folds.
pub fn fold_fraction(map: &(dyn Fn(Pt3) -> Pt3 + Sync), samples: &[Pt3], h: f64) -> f64 {
    use rayon::prelude::*;
    if samples.is_empty() {
        return 0.0;
    }
    let folds: usize = samples
        .par_iter()
        .map(|x| {
            let col = |e: Vec3| (map(x + e * h) - map(x - e * h)) / (2.0 * h);
            let j = geom_core::math::Mat3::from_columns(&[col(Vec3::x()), col(Vec3::y()), col(Vec3::z())]);
            let d = j.determinant();
            usize::from(d.is_nan() || d <= 0.0)
        })
        .sum();
    folds as f64 / samples.len() as f64
}

/// Histogram of row sizes of a compressed-row structure (`h[k]` = rows with `k` entries).
pub fn influences_histogram(offsets: &[u32]) -> Vec<usize> {
    let mut h = Vec::new();
    for w in offsets.windows(2) {
        let k = (w[1] - w[0]) as usize;
        if h.len() <= k {
            h.resize(k + 1, 0);
        }
        h[k] += 1;
    }
    h
}

/// Mean of a histogram (`Σ k·h[k] / Σ h[k]`).
pub fn histogram_mean(h: &[usize]) -> f64 {
    let n: usize = h.iter().sum();
    if n == 0 {
        return 0.0;
    }
    h.iter().enumerate().map(|(k, &c)| k * c).sum::<usize>() as f64 / n as f64
}

#[cfg(test)]
mod tests {
    use super::*;

    fn unit_cube() -> (Vec<Pt3>, Vec<[u32; 3]>) {
        let p: Vec<Pt3> =
            (0..8).map(|i| Pt3::new((i & 1) as f64, ((i >> 1) & 1) as f64, ((i >> 2) & 1) as f64)).collect();
        // Outward quads (CCW seen from outside), split into triangles.
        let quads = [[0, 2, 3, 1], [4, 5, 7, 6], [0, 1, 5, 4], [2, 6, 7, 3], [0, 4, 6, 2], [1, 3, 7, 5]];
        let t = quads.iter().flat_map(|q| [[q[0], q[1], q[2]], [q[0], q[2], q[3]]]).collect();
        (p, t)
    }

    #[test]
    fn cube_volume_is_one() {
        // Spec 7.1 d.
        let (p, t) = unit_cube();
        assert!((signed_volume(&p, &t) - 1.0).abs() < 1e-12);
        let shifted: Vec<Pt3> = p.iter().map(|x| x + Vec3::new(3.0, -2.0, 7.0)).collect();
        assert!((signed_volume(&shifted, &t) - 1.0).abs() < 1e-12);
    }

    #[test]
    fn self_intersections_of_closed_and_overlapping_meshes() {
        // Spec 7.1 d: 0 on an icosphere, > 0 on two overlapping boxes merged into one mesh.
        use geom_core::procedural::{box_surface, icosphere, Diagonals};
        let ico = icosphere(1.0, 3).unwrap();
        assert_eq!(self_intersections(&ico.positions, &ico.faces), 0);
        let b1 =
            box_surface(Pt3::new(0.0, 0.0, 0.0), Pt3::new(1.0, 1.0, 1.0), [2, 2, 2], Diagonals::Alternating).unwrap();
        let b2 =
            box_surface(Pt3::new(0.5, 0.5, 0.5), Pt3::new(1.5, 1.5, 1.5), [2, 2, 2], Diagonals::Alternating).unwrap();
        let mut p = b1.positions.clone();
        let off = p.len() as u32;
        p.extend_from_slice(&b2.positions);
        let mut f = b1.faces.clone();
        f.extend(b2.faces.iter().map(|t| [t[0] + off, t[1] + off, t[2] + off]));
        assert!(self_intersections(&p, &f) > 0);
        // Each box alone is clean.
        assert_eq!(self_intersections(&b1.positions, &b1.faces), 0);
    }

    #[test]
    fn distances_and_histograms() {
        let bones = [(Pt3::new(0.0, 0.0, 0.0), Pt3::new(1.0, 0.0, 0.0))];
        let (lo, hi) = distance_to_bones(&[Pt3::new(0.5, 0.2, 0.0), Pt3::new(2.0, 0.0, 0.0)], &bones);
        assert!((lo - 0.2).abs() < 1e-15 && (hi - 1.0).abs() < 1e-15);
        assert_eq!(influences_histogram(&[0, 1, 3, 4]), vec![0, 2, 1]);
        assert!((histogram_mean(&[0, 2, 1]) - 4.0 / 3.0).abs() < 1e-15);
    }

    #[test]
    fn fold_fraction_of_identity_and_reflection() {
        let s: Vec<Pt3> = (0..10).map(|i| Pt3::new(i as f64, 0.0, 0.0)).collect();
        assert_eq!(fold_fraction(&|x| x, &s, 1e-5), 0.0);
        assert_eq!(fold_fraction(&|x: Pt3| Pt3::new(-x.x, x.y, x.z), &s, 1e-5), 1.0);
    }
}

//! Approximate medial surface sampling and sphere packing (rigging spec §3.2, §3.3).
//!
//! The medial surface is where the distance field loses C¹ continuity; inside a leaf the
//! interpolant is smooth, so only leaf faces are sampled: on a τ-spaced grid over the three faces
//! of each leaf that touch its lower corner, a point is medial when two of the 8 unit gradients
//! at `p + ε(±1, ±1, ±1)` make an angle ≥ `medial_angle` and the point is deeper than
//! `medial_min_depth · τ` (paper: 120°, 2τ).

use geom_core::math::{Pt3, Vec3};

use crate::df::DistanceField;

/// A sphere inside the character: centre and radius (normalized units).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sphere {
    /// Centre.
    pub c: Pt3,
    /// Radius (depth of the centre).
    pub r: f64,
}

/// Minimum pairwise dot product of the unit gradients at the 8 points `p + e(±1, ±1, ±1)`.
fn min_gradient_dot(df: &DistanceField, p: &Pt3, e: f64) -> f64 {
    let g: [Vec3; 8] = std::array::from_fn(|k| {
        let o = Vec3::new(
            if k & 1 == 0 { -e } else { e },
            if k & 2 == 0 { -e } else { e },
            if k & 4 == 0 { -e } else { e },
        );
        df.grad(&(p + o)).try_normalize(1e-300).unwrap_or_else(Vec3::zeros)
    });
    let mut m = f64::INFINITY;
    for i in 0..8 {
        for j in i + 1..8 {
            m = m.min(g[i].dot(&g[j]));
        }
    }
    m
}

/// Medial samples sorted by radius, largest first (ties by position, so the order is
/// deterministic). `angle_deg` is the medial angle, `min_depth` in units of τ.
pub fn sample_medial(df: &DistanceField, angle_deg: f64, min_depth: f64) -> Vec<Sphere> {
    let tau = df.tau();
    let cos_a = angle_deg.to_radians().cos();
    let eps = 1e-3 * tau;
    let mut out = Vec::new();
    df.for_each_leaf(|o, h, v| {
        // Leaves whose corners are all shallower than the depth filter cannot hold samples
        // (the interpolant on their faces is bounded by the corner values up to τ).
        if v.iter().all(|&x| x > -min_depth * tau + tau) {
            return;
        }
        // Quick reject: gradients around the cell (in the neighbouring leaves) all agree.
        let c = o + Vec3::repeat(h * 0.5);
        if min_gradient_dot(df, &c, h * 0.5 + 1e-9) > 0.0 {
            return;
        }
        let n = ((h / tau).round() as usize).max(1);
        let step = h / n as f64;
        for face in 0..3 {
            let (a1, a2) = ((face + 1) % 3, (face + 2) % 3);
            for i in 0..n {
                for j in 0..n {
                    let mut p = o;
                    p[a1] += i as f64 * step;
                    p[a2] += j as f64 * step;
                    let depth = -df.eval(&p);
                    if depth <= min_depth * tau {
                        continue;
                    }
                    if min_gradient_dot(df, &p, eps) <= cos_a {
                        out.push(Sphere { c: p, r: depth });
                    }
                }
            }
        }
    });
    out.sort_by(|a, b| {
        b.r.total_cmp(&a.r).then(a.c.x.total_cmp(&b.c.x)).then(a.c.y.total_cmp(&b.c.y)).then(a.c.z.total_cmp(&b.c.z))
    });
    out.dedup_by(|a, b| a.c == b.c);
    out
}

/// Greedy packing (spec §3.3): walk the samples (sorted by radius, descending) and accept a
/// sample unless it lies inside an accepted sphere; stop after `max_spheres`. A uniform hash grid
/// of cell size `r_max` over the accepted centres keeps it near-linear.
pub fn pack_spheres(samples: &[Sphere], max_spheres: usize) -> Vec<Sphere> {
    let mut acc: Vec<Sphere> = Vec::new();
    let Some(first) = samples.first() else { return acc };
    let cell = first.r.max(1e-12);
    let mut grid: std::collections::HashMap<[i64; 3], Vec<u32>> = std::collections::HashMap::new();
    let key = |p: &Pt3| [p.x, p.y, p.z].map(|x| (x / cell).floor() as i64);
    for s in samples {
        if acc.len() >= max_spheres {
            break;
        }
        let k = key(&s.c);
        let mut inside = false;
        'search: for dx in -1..=1 {
            for dy in -1..=1 {
                for dz in -1..=1 {
                    if let Some(list) = grid.get(&[k[0] + dx, k[1] + dy, k[2] + dz]) {
                        for &i in list {
                            let a = &acc[i as usize];
                            if (s.c - a.c).norm() < a.r {
                                inside = true;
                                break 'search;
                            }
                        }
                    }
                }
            }
        }
        if !inside {
            grid.entry(k).or_default().push(acc.len() as u32);
            acc.push(*s);
        }
    }
    acc
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn packing_invariants() {
        let mut rng = geom_core::rng::Rng::new(3);
        let mut s: Vec<Sphere> = (0..2000)
            .map(|_| Sphere { c: Pt3::new(rng.f64(), rng.f64(), rng.f64()), r: rng.range(0.01, 0.08) })
            .collect();
        s.sort_by(|a, b| b.r.total_cmp(&a.r));
        let p = pack_spheres(&s, 300);
        assert!(p.len() <= 300);
        for w in p.windows(2) {
            assert!(w[0].r >= w[1].r);
        }
        for (i, a) in p.iter().enumerate() {
            for b in &p[..i] {
                assert!((a.c - b.c).norm() >= b.r, "accepted centre inside an earlier sphere");
            }
        }
        // Every rejected sample (before the cap was reached) is inside an accepted sphere.
        let last = s.iter().position(|x| x.c == p[p.len() - 1].c).expect("accepted sample is a sample");
        for x in &s[..last] {
            if !p.iter().any(|a| a.c == x.c) {
                assert!(p.iter().any(|a| (x.c - a.c).norm() < a.r));
            }
        }
    }
}

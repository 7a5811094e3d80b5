//! Additive continuous collision detection (Li, Kaufman, Jiang 2021, "Codimensional Incremental
//! Potential Contact", Algorithm 1): a conservative time of impact for a pair of primitives
//! moving linearly, from distance evaluations only.
//!
//! With the common translation removed, no point of the pair moves faster than l_p (the largest
//! displacement of the first primitive's points plus that of the second's), so the gap
//! g = d − ξ cannot close by more than l_p·Δt over a time Δt. Advancing by Δt = 0.9·g/l_p is
//! therefore safe; the search stops when the gap has fallen below s·g₀ (the pair may come that
//! close but no closer in this step) or when t passes t_max. The returned time is always
//! conservative: at every t' ≤ t the gap stays ≥ s·g₀ > 0.

use geom_core::math::{Pt3, Vec3};

/// Most iterations before giving up with the time reached so far (conservative): sliding
/// contacts (tangential motion much larger than the gap) need many small advances.
const MAX_ITERS: usize = 10_000;

/// The first time t ∈ [0, t_max] at which the gap of the pair may drop below
/// max(`s`·g₀, `floor`) (g₀ its value at t = 0), or `None` when it stays above over [0, t_max].
/// `x`: the pair's points at t = 0, `p`: their displacements over t ∈ [0, 1], `split`: how many
/// of them belong to the first primitive, `dist2`: the squared distance of the primitives,
/// `xi`: the thickness subtracted from the distance (m), `s ∈ (0, 1)`: the fraction of the gap
/// that must remain, `floor` (m): an absolute gap no motion may go below — a pair already at
/// or below it may only move apart (it gets t = 0 if its gap starts to shrink), so a conflict
/// that keeps pushing (a hard constraint into an obstacle) cannot drive a gap to zero.
#[allow(clippy::too_many_arguments)]
pub fn time_of_impact<const K: usize>(
    x: &[Pt3; K],
    p: &[Vec3; K],
    split: usize,
    dist2: impl Fn(&[Pt3; K]) -> f64,
    xi: f64,
    s: f64,
    floor: f64,
    t_max: f64,
) -> Option<f64> {
    let mean: Vec3 = p.iter().sum::<Vec3>() / K as f64;
    let rel: [Vec3; K] = std::array::from_fn(|k| p[k] - mean);
    let lp = rel[..split].iter().map(|v| v.norm()).fold(0.0, f64::max)
        + rel[split..].iter().map(|v| v.norm()).fold(0.0, f64::max);
    let d0 = dist2(x).sqrt();
    let g0 = d0 - xi;
    if !(g0 > 0.0) {
        return Some(0.0);
    }
    if lp == 0.0 {
        return None;
    }
    if g0 <= floor {
        // Only separation is allowed: the gap after a tiny part of the motion tells.
        let tiny = 1e-6 * t_max;
        let y: [Pt3; K] = std::array::from_fn(|k| x[k] + tiny * rel[k]);
        return if dist2(&y).sqrt() - xi < g0 { Some(0.0) } else { None };
    }
    let target = (s * g0).max(floor);
    let mut t = 0.0;
    let mut tl = (g0 - target) / lp;
    let mut y = *x;
    for _ in 0..MAX_ITERS {
        for k in 0..K {
            y[k] = x[k] + (t + tl) * rel[k];
        }
        let g = dist2(&y).sqrt() - xi;
        if t > 0.0 && g < target {
            return Some(t);
        }
        if !(g > 0.0) && t == 0.0 {
            // The first (1 − s)·g₀/l_p advance is provably safe; reaching a non-positive gap
            // there means rounding: stop at 0.
            return Some(0.0);
        }
        t += tl;
        if t >= t_max {
            return None;
        }
        tl = 0.9 * g / lp;
    }
    Some(t)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pp(x: &[Pt3; 2]) -> f64 {
        (x[0] - x[1]).norm_squared()
    }

    #[test]
    fn head_on_points_stop_short_of_contact() {
        // Two points 1 m apart closing at 2 m per unit time: contact at t = 0.5.
        let x = [Pt3::new(0.0, 0.0, 0.0), Pt3::new(1.0, 0.0, 0.0)];
        let p = [Vec3::new(1.0, 0.0, 0.0), Vec3::new(-1.0, 0.0, 0.0)];
        let t = time_of_impact(&x, &p, 1, pp, 0.0, 0.1, 0.0, 1.0).expect("they meet");
        // The gap at t is ≥ 0.1 and the search stops once it is below 0.1·(1/0.9)-ish.
        let gap = 1.0 - 2.0 * t;
        assert!((0.1 - 1e-12..0.2).contains(&gap), "t = {t}, gap = {gap}");
        // With thickness 0.5 the gap is 0.5 and closes at t = 0.25.
        let t = time_of_impact(&x, &p, 1, pp, 0.5, 0.1, 0.0, 1.0).expect("they meet");
        assert!(1.0 - 2.0 * t - 0.5 >= 0.05 - 1e-12 && t < 0.25);
    }

    #[test]
    fn the_floor_holds_a_pushed_pair_and_lets_it_separate() {
        let x = [Pt3::new(0.0, 0.0, 0.0), Pt3::new(1.0, 0.0, 0.0)];
        let closing = [Vec3::new(0.45, 0.0, 0.0), Vec3::new(-0.45, 0.0, 0.0)];
        // Gap 1, floor 0.5: may close to 0.5 at most (t ≤ 0.5/0.9).
        let t = time_of_impact(&x, &closing, 1, pp, 0.0, 0.1, 0.5, 1.0).expect("stopped by the floor");
        assert!(1.0 - 0.9 * t >= 0.5 - 1e-12 && t > 0.3, "t = {t}");
        // At the floor: no closing at all, separating is free.
        assert_eq!(time_of_impact(&x, &closing, 1, pp, 0.0, 0.1, 1.0, 1.0), Some(0.0));
        let opening = [Vec3::new(-0.45, 0.0, 0.0), Vec3::new(0.45, 0.0, 0.0)];
        assert_eq!(time_of_impact(&x, &opening, 1, pp, 0.0, 0.1, 1.0, 1.0), None);
    }

    #[test]
    fn separating_parallel_and_common_motion_never_hit() {
        let x = [Pt3::new(0.0, 0.0, 0.0), Pt3::new(1.0, 0.0, 0.0)];
        let away = [Vec3::new(-1.0, 0.0, 0.0), Vec3::new(1.0, 0.0, 0.0)];
        assert_eq!(time_of_impact(&x, &away, 1, pp, 0.0, 0.1, 0.0, 1.0), None);
        let common = [Vec3::new(5.0, 3.0, 0.0), Vec3::new(5.0, 3.0, 0.0)];
        assert_eq!(time_of_impact(&x, &common, 1, pp, 0.0, 0.1, 0.0, 1.0), None);
        // Sliding past at constant distance 1: no hit, bounded work.
        let slide = [Vec3::new(0.0, 0.0, 10.0), Vec3::zeros()];
        assert_eq!(time_of_impact(&x, &slide, 1, pp, 0.0, 0.1, 0.0, 1.0), None);
    }

    #[test]
    fn conservative_on_random_point_triangle_motions() {
        use geom_core::rng::Rng;
        let mut r = Rng::new(3);
        let d2 = |y: &[Pt3; 4]| {
            let (c, _) = geom_core::query::closest_point_triangle(&y[0], &[y[1], y[2], y[3]]);
            (y[0] - c).norm_squared()
        };
        for _ in 0..500 {
            let rp = |r: &mut Rng| Pt3::new(r.range(-1.0, 1.0), r.range(-1.0, 1.0), r.range(-1.0, 1.0));
            let rv = |r: &mut Rng| Vec3::new(r.range(-2.0, 2.0), r.range(-2.0, 2.0), r.range(-2.0, 2.0));
            let x = [rp(&mut r), rp(&mut r), rp(&mut r), rp(&mut r)];
            let p = [rv(&mut r), rv(&mut r), rv(&mut r), rv(&mut r)];
            let g0 = d2(&x).sqrt();
            let t = time_of_impact(&x, &p, 1, d2, 0.0, 0.1, 0.0, 1.0).unwrap_or(1.0);
            // Sample the motion up to t: the gap never falls below 0.1·g₀.
            for k in 0..=200 {
                let tau = t * k as f64 / 200.0;
                let y: [Pt3; 4] = std::array::from_fn(|i| x[i] + tau * p[i]);
                assert!(d2(&y).sqrt() >= 0.1 * g0 * (1.0 - 1e-9), "gap fell below the floor at {tau} < {t}");
            }
        }
    }
}

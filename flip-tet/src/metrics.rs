//! Probes and CSV rows (spec §6): surge-front position, residual column height, surface height
//! from a vertical root search of φ, zero-crossing period, and the per-step `metrics.csv` row.

use geom_core::math::Pt3;

use crate::particles::Particles;
use crate::sim::{FlipTetSim, StepStats};

/// Martin & Moyce (1952), Phil. Trans. R. Soc. A 244, Fig./Table for `a = 2¼ in`, `n² = 2`
/// (spec §6 S2): dimensionless surge front `Z = x_front / a` at `T = t √(2g/a)`.
pub const MARTIN_MOYCE_FRONT: [(f64, f64); 15] = [
    (0.41, 1.11),
    (0.84, 1.22),
    (1.19, 1.44),
    (1.43, 1.67),
    (1.63, 1.89),
    (1.83, 2.11),
    (1.98, 2.33),
    (2.20, 2.56),
    (2.32, 2.78),
    (2.51, 3.00),
    (2.65, 3.22),
    (2.83, 3.44),
    (2.98, 3.67),
    (3.11, 3.89),
    (3.33, 4.11),
];

/// Martin & Moyce (1952) residual column height `H = h / (2a)` at `τ = t √(g/a)` (spec §6 S2).
pub const MARTIN_MOYCE_HEIGHT: [(f64, f64); 17] = [
    (0.56, 0.94),
    (0.77, 0.89),
    (0.93, 0.83),
    (1.08, 0.78),
    (1.28, 0.72),
    (1.46, 0.67),
    (1.66, 0.61),
    (1.84, 0.56),
    (2.00, 0.50),
    (2.21, 0.44),
    (2.45, 0.39),
    (2.70, 0.33),
    (3.06, 0.28),
    (3.44, 0.22),
    (4.20, 0.17),
    (5.25, 0.11),
    (7.40, 0.06),
];

/// Front position `max_p (x_p + r_p)` along x over non-ballistic particles, measured from `wall`
/// (m); 0 without particles.
pub fn front_position(parts: &Particles, wall: f64) -> f64 {
    (0..parts.len()).filter(|&i| !parts.is_ballistic(i)).map(|i| parts.x[i].x + parts.r[i] - wall).fold(0.0, f64::max)
}

/// Residual column height `max_{x_p − wall < width} (y_p + r_p) − floor` (m).
pub fn column_height(p: &Particles, wall: f64, width: f64, floor: f64) -> f64 {
    (0..p.len())
        .filter(|&i| !p.is_ballistic(i) && p.x[i].x - wall < width)
        .map(|i| p.x[i].y + p.r[i] - floor)
        .fold(0.0, f64::max)
}

/// Surface height at `(x, z)`: the highest `y` where the linear interpolant of the node level set
/// changes sign from negative (below) to non-negative (above), by a vertical scan with step
/// `h_min / 8` and bisection (spec §6 S3 probe). `None` if the column holds no liquid.
pub fn surface_height(sim: &FlipTetSim, x: f64, z: f64) -> Option<f64> {
    let (lo, hi) = (sim.scene().domain.min[1], sim.scene().domain.max[1]);
    let dy = sim.spec().h_min() / 8.0;
    let phi_at = |y: f64| -> f64 {
        let p = Pt3::new(x, y, z);
        match sim.mesh().locate(sim.octree(), &p) {
            Some((t, l)) => {
                let tv = sim.mesh().tets[t as usize];
                (0..4).map(|a| l[a] * sim.phi()[tv[a] as usize]).sum()
            }
            None => f64::INFINITY,
        }
    };
    let mut y = hi - 1e-9;
    let mut prev = phi_at(y);
    while y > lo {
        let y2 = (y - dy).max(lo + 1e-9);
        let v = phi_at(y2);
        if v < 0.0 && prev >= 0.0 {
            let (mut a, mut b) = (y2, y);
            for _ in 0..50 {
                let m = 0.5 * (a + b);
                if phi_at(m) < 0.0 {
                    a = m;
                } else {
                    b = m;
                }
            }
            return Some(0.5 * (a + b));
        }
        if y2 <= lo + 1e-9 {
            break;
        }
        prev = v;
        y = y2;
    }
    None
}

/// Period from linearly interpolated crossings of `s(t) − mean` after `t_skip` (s): the mean
/// spacing of successive up-crossings and of successive down-crossings (averaged when both exist;
/// same-direction spacing is insensitive to a bias of the mean). `None` without two crossings of
/// one direction (then twice the spacing of mixed crossings; `None` with fewer than two).
pub fn zero_crossing_period(series: &[(f64, f64)], t_skip: f64) -> Option<f64> {
    let pts: Vec<(f64, f64)> = series.iter().copied().filter(|p| p.0 >= t_skip).collect();
    if pts.len() < 3 {
        return None;
    }
    let mean = pts.iter().map(|p| p.1).sum::<f64>() / pts.len() as f64;
    let (mut up, mut down) = (Vec::new(), Vec::new());
    for w in pts.windows(2) {
        let (a, b) = (w[0].1 - mean, w[1].1 - mean);
        if (a < 0.0) != (b < 0.0) && a != b {
            let t = w[0].0 + (w[1].0 - w[0].0) * a / (a - b);
            if a < 0.0 {
                up.push(t);
            } else {
                down.push(t);
            }
        }
    }
    let per = |c: &[f64]| (c.len() >= 2).then(|| (c[c.len() - 1] - c[0]) / (c.len() - 1) as f64);
    match (per(&up), per(&down)) {
        (Some(a), Some(b)) => Some(0.5 * (a + b)),
        (None, None) => {
            // Only one crossing of each direction: twice the spacing of mixed crossings.
            let mut all: Vec<f64> = up.iter().chain(&down).copied().collect();
            all.sort_by(f64::total_cmp);
            (all.len() >= 2).then(|| 2.0 * (all[all.len() - 1] - all[0]) / (all.len() - 1) as f64)
        }
        (a, b) => a.or(b),
    }
}

/// Damping ratio ζ of a decaying oscillation `s(t)` from the log decrement of its half-cycle
/// amplitudes after `t_skip` (s) (spec §6 S3, §9 "PIC fraction"): the mean of `s` over `t ≥ t_skip`
/// is removed, the largest `|s − mean|` between successive crossings of the mean gives one
/// amplitude `A_k` per half cycle (the partial half cycles before the first and after the last
/// crossing are dropped), and a least-squares line through `ln A_k` against `k` gives the
/// half-cycle decrement `δ/2`; `ζ = δ / √(4π² + δ²)` with `δ` the full-cycle decrement. Positive
/// for a decaying signal, negative for a growing one; `None` with fewer than three amplitudes.
pub fn damping_ratio(series: &[(f64, f64)], t_skip: f64) -> Option<f64> {
    let pts: Vec<(f64, f64)> = series.iter().copied().filter(|p| p.0 >= t_skip).collect();
    if pts.len() < 3 {
        return None;
    }
    let mean = pts.iter().map(|p| p.1).sum::<f64>() / pts.len() as f64;
    let mut amps: Vec<f64> = Vec::new();
    let mut current: Option<f64> = None;
    for w in pts.windows(2) {
        let (a, b) = (w[0].1 - mean, w[1].1 - mean);
        if let Some(m) = current.as_mut() {
            *m = m.max(a.abs());
        }
        if (a < 0.0) != (b < 0.0) {
            if let Some(m) = current {
                amps.push(m);
            }
            current = Some(b.abs());
        }
    }
    if amps.len() < 3 || amps.iter().any(|&a| a <= 0.0) {
        return None;
    }
    let n = amps.len() as f64;
    let (sx, sy) = (0..amps.len()).fold((0.0, 0.0), |(sx, sy), k| (sx + k as f64, sy + amps[k].ln()));
    let (mx, my) = (sx / n, sy / n);
    let (sxy, sxx) = (0..amps.len()).fold((0.0, 0.0), |(sxy, sxx), k| {
        let dx = k as f64 - mx;
        (sxy + dx * (amps[k].ln() - my), sxx + dx * dx)
    });
    let delta = -2.0 * sxy / sxx;
    Some(delta / (4.0 * std::f64::consts::PI.powi(2) + delta * delta).sqrt())
}

/// Linear interpolation in a sorted `(x, y)` table (clamped at the ends).
pub fn interp(table: &[(f64, f64)], x: f64) -> f64 {
    if table.is_empty() {
        return f64::NAN;
    }
    if x <= table[0].0 {
        return table[0].1;
    }
    for w in table.windows(2) {
        if x <= w[1].0 {
            let s = (x - w[0].0) / (w[1].0 - w[0].0);
            return w[0].1 + s * (w[1].1 - w[0].1);
        }
    }
    table[table.len() - 1].1
}

/// Column names of [`csv_row`].
pub const CSV_HEADER: [&str; 29] = [
    "step",
    "t",
    "dt",
    "remeshed",
    "n_particles",
    "n_ballistic",
    "n_split",
    "n_merge",
    "n_deleted",
    "n_nodes",
    "n_tets",
    "n_dofs",
    "n_ghost_tets",
    "n_k_reduced",
    "solver_iters",
    "solver_rel_residual",
    "vol_particles",
    "vol_levelset",
    "kinetic_energy",
    "potential_energy",
    "max_speed",
    "cfl_substeps",
    "budget_hit",
    "t_remesh",
    "t_transfer",
    "t_solve",
    "t_advect",
    "t_surface",
    "t_total",
];

/// One `metrics.csv` row for a step (numbers in full precision, same order as [`CSV_HEADER`]).
pub fn csv_row(s: &StepStats) -> Vec<f64> {
    let st = s.timings.stages();
    vec![
        s.step as f64,
        s.t,
        s.dt,
        f64::from(u8::from(s.remeshed)),
        s.n_particles as f64,
        s.n_ballistic as f64,
        s.n_split as f64,
        s.n_merge as f64,
        s.n_deleted as f64,
        s.n_nodes as f64,
        s.n_tets as f64,
        s.n_dofs as f64,
        s.n_ghost_tets as f64,
        s.n_k_reduced as f64,
        s.solver.iters as f64,
        s.solver.rel_residual,
        s.vol_particles,
        s.vol_levelset,
        s.kinetic_energy,
        s.potential_energy,
        s.max_speed,
        f64::from(s.cfl_substeps),
        f64::from(u8::from(s.budget_hit)),
        st[0],
        st[1],
        st[2],
        st[3],
        st[4],
        s.timings.total(),
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn period_of_a_cosine() {
        let s: Vec<(f64, f64)> =
            (0..2000).map(|i| i as f64 * 0.002).map(|t| (t, 0.3 + 0.02 * (5.0 * t).cos())).collect();
        let p = zero_crossing_period(&s, 0.1).unwrap();
        assert!((p - 2.0 * std::f64::consts::PI / 5.0).abs() < 1e-3);
        assert!((interp(&MARTIN_MOYCE_FRONT, 0.41) - 1.11).abs() < 1e-15);
        assert_eq!(csv_row(&StepStats::default()).len(), CSV_HEADER.len());
    }

    /// An exactly damped cosine `e^{−ζωt} cos(ω_d t)` (ζ = 0.05, ω = 5 rad/s, sampled every 2 ms)
    /// gives back ζ to 2e−3 (the sampled extrema sit up to half a sample off the true peaks); an
    /// undamped one gives |ζ| ≤ 1e−3; a signal with fewer than three half cycles gives `None`.
    #[test]
    fn damping_ratio_of_a_damped_cosine() {
        let (zeta, w) = (0.05f64, 5.0f64);
        let wd = w * (1.0 - zeta * zeta).sqrt();
        let s: Vec<(f64, f64)> = (0..4000)
            .map(|i| i as f64 * 0.002)
            .map(|t| (t, 0.3 + 0.02 * (-zeta * w * t).exp() * (wd * t).cos()))
            .collect();
        let z = damping_ratio(&s, 0.0).unwrap();
        assert!((z - zeta).abs() < 2e-3, "{z}");
        let u: Vec<(f64, f64)> = (0..4000).map(|i| i as f64 * 0.002).map(|t| (t, 0.3 + 0.02 * (w * t).cos())).collect();
        assert!(damping_ratio(&u, 0.0).unwrap().abs() < 1e-3);
        assert!(damping_ratio(&u[..300], 0.0).is_none());
    }
}

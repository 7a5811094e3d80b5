//! Every figure a flip-tet scene reports (spec §6): probes (surge-front position, residual
//! column height, surface height from a vertical root search of φ), signal analysis
//! (zero-crossing period, damping ratio), run statistics (relative drifts, particle-count
//! figures, the per-step `metrics.csv` row) and the comparisons with reference data.
//!
//! Maxima and drifts are NaN-safe: a NaN anywhere makes the figure NaN.

use geom_core::experiment::Report;
use geom_core::math::Pt3;
use geom_core::stats;

use crate::particles::Particles;
use crate::sim::{FlipTetSim, StepStats};

/// Front position `max_p (x_p + r_p)` along x over non-ballistic particles, measured from `wall`
/// (m); 0 without particles.
pub fn front_position(parts: &Particles, wall: f64) -> f64 {
    (0..parts.len())
        .filter(|&i| !parts.is_ballistic(i))
        .map(|i| parts.x[i].x + parts.r[i] - wall)
        .fold(0.0, stats::nan_max)
}

/// Residual column height `max_{x_p − wall < width} (y_p + r_p) − floor` (m).
pub fn column_height(p: &Particles, wall: f64, width: f64, floor: f64) -> f64 {
    (0..p.len())
        .filter(|&i| !p.is_ballistic(i) && p.x[i].x - wall < width)
        .map(|i| p.x[i].y + p.r[i] - floor)
        .fold(0.0, stats::nan_max)
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
    let pts: Vec<(f64, f64)> = amps.iter().enumerate().map(|(k, a)| (k as f64, a.ln())).collect();
    let (_, slope, _) = stats::linear_fit(&pts);
    let delta = -2.0 * slope;
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

/// Largest relative deviation `max_k |f(s_k) − f(s_0)| / |f(s_0)|` of a per-step quantity from
/// its first value (0 for no steps; NaN if any value is NaN).
pub fn rel_drift(stats: &[StepStats], f: impl Fn(&StepStats) -> f64) -> f64 {
    let Some(first) = stats.first() else { return 0.0 };
    let v0 = f(first);
    stats.iter().map(|x| (f(x) - v0).abs()).fold(0.0, stats::nan_max) / v0.abs().max(1e-300)
}

/// Largest particle speed over the steps (m/s; 0 for no steps, NaN if any is NaN).
pub fn max_speed(stats: &[StepStats]) -> f64 {
    stats.iter().map(|x| x.max_speed).fold(0.0, stats::nan_max)
}

/// Relative errors `(Z_sim(T) − Z_ref)/Z_ref` of a simulated series `(T, Z)` (sorted by `T`)
/// against the reference points `(T, Z_ref)` with `T − shift` inside the simulated range, the
/// simulation read at `T − shift` (a positive `shift` delays the simulation), and their RMS
/// (NaN without a compared point).
pub fn series_rel_errors(sim: &[(f64, f64)], reference: &[(f64, f64)], shift: f64) -> (Vec<f64>, f64) {
    let t_end = sim.last().map_or(0.0, |x| x.0);
    let errs: Vec<f64> =
        reference.iter().filter(|x| x.0 - shift <= t_end).map(|&(t, z)| (interp(sim, t - shift) - z) / z).collect();
    let rms = if errs.is_empty() { f64::NAN } else { stats::rms(&errs) };
    (errs, rms)
}

/// Relative front errors `(Z_sim − Z_exp)/Z_exp` at the tabulated reference times covered by the
/// simulated series `(T, Z)`, and their RMS (spec §6 S2, no time shift).
pub fn front_errors(front: &[(f64, f64)], reference: &[(f64, f64)]) -> (Vec<f64>, f64) {
    let t_end = front.last().map_or(0.0, |x| x.0);
    let errs: Vec<f64> = reference.iter().filter(|x| x.0 <= t_end).map(|&(t, z)| (interp(front, t) - z) / z).collect();
    let rms = (errs.iter().map(|e| e * e).sum::<f64>() / errs.len().max(1) as f64).sqrt();
    (errs, rms)
}

/// The time shift `δ ∈ [0, max]` (step `step`) minimising the RMS of `Z_sim(T − δ)` against the
/// reference, and that RMS (see [`fit_time_shift`]).
pub fn best_time_shift(sim: &[(f64, f64)], reference: &[(f64, f64)], max: f64, step: f64) -> (f64, f64) {
    fit_time_shift(sim, reference, 0.0, max, step)
}

/// One fitted time origin: the shift `δ ∈ [lo, hi]` (searched on the grid `lo + k · step`)
/// minimising the RMS relative error of `Z_sim(T − δ)` against the reference points `(T, Z_ref)`
/// with `T` inside the simulated range, and that RMS. A positive `δ` means the simulation leads
/// (it is delayed by `δ` to match). The simulated series is read by linear interpolation,
/// clamped at its ends. Ties keep the smaller shift; `(NaN, NaN)` without a compared point or
/// with NaN errors only.
pub fn fit_time_shift(sim: &[(f64, f64)], reference: &[(f64, f64)], lo: f64, hi: f64, step: f64) -> (f64, f64) {
    let n = ((hi - lo) / step).round() as usize;
    let t_end = sim.last().map_or(0.0, |f| f.0);
    let pts: Vec<(f64, f64)> = reference.iter().copied().filter(|x| x.0 <= t_end).collect();
    if pts.is_empty() {
        return (f64::NAN, f64::NAN);
    }
    let mut best = (f64::NAN, f64::INFINITY);
    for k in 0..=n {
        let d = lo + step * k as f64;
        let e: Vec<f64> = pts.iter().map(|&(t, z)| (interp(sim, t - d) - z) / z).collect();
        let rms = (e.iter().map(|v| v * v).sum::<f64>() / e.len() as f64).sqrt();
        if rms < best.1 {
            best = (d, rms);
        }
    }
    if best.1.is_infinite() {
        (f64::NAN, f64::NAN)
    } else {
        best
    }
}

/// Largest `|H_sim(τ) − H_ref(τ)|` over the reference points with `τ ≤ tau_max` (and inside the
/// simulated range); 0 without a point, NaN if a difference is NaN.
pub fn height_max_abs_err(sim: &[(f64, f64)], reference: &[(f64, f64)], tau_max: f64) -> f64 {
    let tau_end = sim.last().map_or(0.0, |x| x.0);
    reference
        .iter()
        .filter(|x| x.0 <= tau_end.min(tau_max))
        .map(|&(tau, h)| (interp(sim, tau) - h).abs())
        .fold(0.0, stats::nan_max)
}

/// Pearson correlation of two equally long samples (NaN when either has no spread).
pub fn pearson(xs: &[f64], ys: &[f64]) -> f64 {
    let n = xs.len().max(1) as f64;
    let (mx, my) = (xs.iter().sum::<f64>() / n, ys.iter().sum::<f64>() / n);
    let cov: f64 = xs.iter().zip(ys).map(|(a, b)| (a - mx) * (b - my)).sum();
    let (vx, vy) = (xs.iter().map(|a| (a - mx).powi(2)).sum::<f64>(), ys.iter().map(|b| (b - my).powi(2)).sum::<f64>());
    if vx > 0.0 && vy > 0.0 {
        cov / (vx * vy).sqrt()
    } else {
        f64::NAN
    }
}

/// The figures every simulation scene reports about its run (issue 5): `wall_s`, `steps`,
/// `particles_avg`, `us_per_particle_step`, the five stage times `time_{remesh,transfer,solve,
/// advect,surface}_s`, the phases inside them `phase_*_s` and the build `profile`.
pub fn run_figures(r: &mut Report, stats: &[StepStats], wall: f64) {
    let steps = stats.len().max(1) as f64;
    let psteps: f64 = stats.iter().map(|x| x.n_particles as f64).sum();
    r.timing("wall_s", wall);
    r.count("steps", stats.len() as u64);
    r.num("particles_avg", psteps / steps);
    r.timing("us_per_particle_step", 1e6 * wall / psteps.max(1.0));
    let mut st = [0.0; 5];
    for x in stats {
        for (a, b) in st.iter_mut().zip(x.timings.stages()) {
            *a += b;
        }
    }
    for (k, v) in ["remesh", "transfer", "solve", "advect", "surface"].iter().zip(st) {
        r.timing(&format!("time_{k}_s"), v);
    }
    let phase = |f: fn(&crate::sim::PhaseTimings) -> f64| stats.iter().map(|x| f(&x.timings)).sum::<f64>();
    r.timing("phase_p2g_s", phase(|t| t.p2g));
    r.timing("phase_extrapolate_s", phase(|t| t.extrapolate));
    r.timing("phase_g2p_s", phase(|t| t.g2p));
    r.timing("phase_assemble_s", phase(|t| t.assemble));
    r.timing("phase_linear_solve_s", phase(|t| t.solve));
    r.timing("phase_advect_s", phase(|t| t.advect));
    r.timing("phase_correction_s", phase(|t| t.correction));
    r.timing("phase_ballistic_s", phase(|t| t.ballistic));
    r.text("profile", profile());
}

/// `"debug"` or `"release"`: the build profile the figures were measured with.
pub fn profile() -> &'static str {
    if cfg!(debug_assertions) {
        "debug"
    } else {
        "release"
    }
}

/// Particle volume (m³, `Σ 8 r³`) below height `y`.
pub fn volume_below(parts: &Particles, y: f64) -> f64 {
    (0..parts.len()).filter(|&i| parts.x[i].y < y).map(|i| parts.volume(i)).sum()
}

/// Liquid volume of the scene's initial shapes (outside the obstacles) estimated by sampling the
/// centres of an `n × n × n` grid over the domain (m³).
pub fn sampled_liquid_volume(scene: &crate::scene::Scene, n: usize) -> f64 {
    let (mn, mx) = (scene.min(), scene.max());
    let d = (mx - mn) / n as f64;
    let mut c = 0usize;
    for i in 0..n {
        for j in 0..n {
            for k in 0..n {
                let x = mn
                    + geom_core::math::Vec3::new(
                        (i as f64 + 0.5) * d.x,
                        (j as f64 + 0.5) * d.y,
                        (k as f64 + 0.5) * d.z,
                    );
                if scene.liquid_sdf(&x) < 0.0 && scene.solid_sdf(&x) > 0.0 {
                    c += 1;
                }
            }
        }
    }
    c as f64 * d.x * d.y * d.z
}

/// Top of the liquid body: the largest `y + r` over the non-ballistic particles (m; NaN without
/// one).
pub fn liquid_top(p: &Particles) -> f64 {
    (0..p.len()).filter(|&i| !p.is_ballistic(i)).map(|i| p.x[i].y + p.r[i]).fold(f64::NAN, |a, b| {
        if a.is_nan() {
            b
        } else {
            stats::nan_max(a, b)
        }
    })
}

/// The rest state of the particles' liquid in the scene's box (spec §6 S10): the particle volume
/// `V = Σ (2r)³` spread flat over the domain floor `A` (obstacles ignored) has the surface height
/// `h = y_floor + V / A` and the potential energy `ρ g V (y_floor + (h − y_floor) / 2)` (J, the
/// convention of `StepStats::potential_energy`). Returns `(energy J, h m)`.
pub fn rest_potential_energy(scene: &crate::scene::Scene, p: &Particles) -> (f64, f64) {
    let v = p.total_volume();
    let area = (scene.domain.max[0] - scene.domain.min[0]) * (scene.domain.max[2] - scene.domain.min[2]);
    let floor = scene.domain.min[1];
    let depth = v / area;
    let g = -scene.gravity[1];
    (crate::sim::RHO * g * v * (floor + 0.5 * depth), floor + depth)
}

/// Splash height above the rest surface `h_rest` (m) from the liquid-top series `(t, top)`: the
/// largest top after the time the top was lowest (the falling liquid has merged with the pool),
/// minus `h_rest`. NaN for an empty series or NaN tops.
pub fn splash_height(tops: &[(f64, f64)], h_rest: f64) -> f64 {
    if tops.is_empty() || tops.iter().any(|x| x.1.is_nan()) {
        return f64::NAN;
    }
    let k = (0..tops.len()).fold(0, |b, i| if tops[i].1 < tops[b].1 { i } else { b });
    tops[k..].iter().map(|x| x.1).fold(f64::NEG_INFINITY, f64::max) - h_rest
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
        assert!((interp(&crate::reference::MARTIN_MOYCE_FRONT, 0.41) - 1.11).abs() < 1e-15);
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

//! Mouse-like paths (spec §3.13 "Mouse paths"): a Catmull–Rom spline through 6–10 random
//! waypoints in a 10 m × 10 m area, traversed with a smooth random speed profile, sampled at the
//! given rate, plus hand jitter (σ 5 mm in a 5–8 Hz band).

use geom_core::rng::Rng;
use std::f64::consts::TAU;

fn catmull(p0: [f64; 2], p1: [f64; 2], p2: [f64; 2], p3: [f64; 2], t: f64) -> [f64; 2] {
    let t2 = t * t;
    let t3 = t2 * t;
    let f = |a: f64, b: f64, c: f64, d: f64| {
        0.5 * (2.0 * b + (-a + c) * t + (2.0 * a - 5.0 * b + 4.0 * c - d) * t2 + (-a + 3.0 * b - 3.0 * c + d) * t3)
    };
    [f(p0[0], p1[0], p2[0], p3[0]), f(p0[1], p1[1], p2[1], p3[1])]
}

/// A performed path of `secs` seconds at `rate_hz` (x, z in metres), speeds within `speed`
/// (m/s). When the spline is shorter than the distance to travel, the walker stops at its end.
pub fn mouse_path(seed: u64, secs: f64, rate_hz: f64, speed: (f64, f64)) -> Vec<[f64; 2]> {
    let mut rng = Rng::new(seed);
    let nw = 6 + rng.below(5);
    let mut wp: Vec<[f64; 2]> = Vec::with_capacity(nw);
    while wp.len() < nw {
        let c = [rng.range(-5.0, 5.0), rng.range(-5.0, 5.0)];
        // Waypoints at least 2.5 m apart so the path has room for a few steps between them.
        if wp.last().is_none_or(|p: &[f64; 2]| (p[0] - c[0]).hypot(p[1] - c[1]) >= 2.5) {
            wp.push(c);
        }
    }
    // Dense polyline and its arc length.
    let mut dense = Vec::new();
    for i in 0..nw - 1 {
        let p0 = wp[i.saturating_sub(1)];
        let p3 = wp[(i + 2).min(nw - 1)];
        for j in 0..200 {
            dense.push(catmull(p0, wp[i], wp[i + 1], p3, j as f64 / 200.0));
        }
    }
    dense.push(wp[nw - 1]);
    let mut arc = vec![0.0];
    for w in dense.windows(2) {
        arc.push(arc[arc.len() - 1] + (w[1][0] - w[0][0]).hypot(w[1][1] - w[0][1]));
    }
    let total = arc[arc.len() - 1];
    let (lo, hi) = speed;
    // Smooth speed: mean + two slow sinusoids, mapped into [lo, hi].
    let (f1, f2) = (rng.range(0.03, 0.08), rng.range(0.08, 0.2));
    let (ph1, ph2) = (rng.range(0.0, TAU), rng.range(0.0, TAU));
    // Jitter: three sinusoids in 5–8 Hz, total RMS 5 mm per axis.
    let jit: Vec<(f64, f64, f64, f64)> = (0..3)
        .map(|_| (rng.range(5.0, 8.0), rng.range(0.0, TAU), rng.range(0.0, TAU), 0.005 * (2.0f64 / 3.0).sqrt()))
        .collect();
    let n = (secs * rate_hz).round().max(2.0) as usize;
    let mut s = 0.0;
    let mut out = Vec::with_capacity(n);
    let mut k = 0usize;
    for i in 0..n {
        let t = i as f64 / rate_hz;
        while k + 1 < arc.len() - 1 && arc[k + 1] < s {
            k += 1;
        }
        let seg = (arc[k + 1] - arc[k]).max(1e-12);
        let u = ((s - arc[k]) / seg).clamp(0.0, 1.0);
        let mut p =
            [dense[k][0] + (dense[k + 1][0] - dense[k][0]) * u, dense[k][1] + (dense[k + 1][1] - dense[k][1]) * u];
        for &(f, px, pz, a) in &jit {
            p[0] += a * (TAU * f * t + px).sin();
            p[1] += a * (TAU * f * t + pz).sin();
        }
        out.push(p);
        let v = 0.5 * (lo + hi) + 0.5 * (hi - lo) * 0.5 * ((TAU * f1 * t + ph1).sin() + (TAU * f2 * t + ph2).sin());
        s = (s + v / rate_hz).min(total);
    }
    out
}

/// A straight stroke along +Z at constant `speed` (m/s): the "too fast" input of PC-3.
pub fn straight_stroke(secs: f64, rate_hz: f64, speed: f64) -> Vec<[f64; 2]> {
    let n = (secs * rate_hz).round().max(2.0) as usize;
    (0..n).map(|i| [0.0, speed * i as f64 / rate_hz]).collect()
}

//! Nets with exact solutions and random nets, for the correctness tests (spec §7.1) and the
//! `scaling` scene.
//!
//! - [`cable`]: `n` free nodes in a chain between two fixed ends, uniform `q`, transverse load
//!   `p` per node. The discrete solution is the parabola `y_i = (p / 2q) · i · (n + 1 − i)`,
//!   exact at the nodes (spec 7.1 b).
//! - [`membrane`]: the unit square with `N × N` free nodes, spacing `h = 1/(N+1)`, border fixed
//!   at 0, nodal loads `p = h² f(x, y)` with `f = 2π² q sin(πx) sin(πy)`: the net is the
//!   5-point finite-difference Poisson problem, so the nodal solution converges to
//!   `u = sin(πx) sin(πy)` with max error `O(h²)` (spec 7.1 c).
//! - [`random_net`]: a random connected net with random positive force densities (spec 7.1 d,
//!   7.2 e, 7.4 a).

use crate::net::{Bar, BarNet};
use geom_core::math::{Pt3, Vec3};
use geom_core::rng::Rng;
use std::f64::consts::PI;

/// A net with node positions (fixed nodes at their place, free nodes at an initial guess),
/// loads on every node (ignored on fixed nodes) and, when known, the exact free-node solution.
#[derive(Clone, Debug)]
pub struct NetCase {
    /// The net.
    pub net: BarNet,
    /// Positions of every node.
    pub positions: Vec<Pt3>,
    /// Loads on every node.
    pub loads: Vec<Vec3>,
    /// Exact free-node positions, in ascending node order.
    pub exact: Option<Vec<Pt3>>,
}

impl NetCase {
    /// Free-node loads and fixed-node positions in the solver's order (ascending node index).
    pub fn split(&self) -> (Vec<Vec3>, Vec<Pt3>) {
        let loads = (0..self.net.n_nodes).filter(|&v| !self.net.fixed[v]).map(|v| self.loads[v]).collect();
        let fixed = (0..self.net.n_nodes).filter(|&v| self.net.fixed[v]).map(|v| self.positions[v]).collect();
        (loads, fixed)
    }
}

/// The loaded cable of spec 7.1 b: nodes `0..=n+1` at `x = i` (unit spacing), ends fixed at the
/// origin line, load `(0, p, 0)` on every free node, force density `q`.
pub fn cable(n: usize, q: f64, p: f64) -> NetCase {
    let nn = n + 2;
    let bars = (0..nn - 1).map(|i| Bar { a: i as u32, b: i as u32 + 1, q, group: None }).collect();
    let mut fixed = vec![false; nn];
    fixed[0] = true;
    fixed[nn - 1] = true;
    let positions = (0..nn).map(|i| Pt3::new(i as f64, 0.0, 0.0)).collect();
    let mut loads = vec![Vec3::new(0.0, p, 0.0); nn];
    loads[0] = Vec3::zeros();
    loads[nn - 1] = Vec3::zeros();
    let exact = (1..=n).map(|i| Pt3::new(i as f64, p / (2.0 * q) * (i as f64) * ((n + 1 - i) as f64), 0.0)).collect();
    NetCase { net: BarNet { n_nodes: nn, bars, fixed }, positions, loads, exact: Some(exact) }
}

/// A square grid net of `(N+2)²` nodes on the unit square (row-major, node `(i, j)` at
/// `(j h, i h, 0)`, `h = 1/(N+1)`), border fixed, 4-neighbour bars with force density `q`, no
/// loads.
pub fn grid_net(n: usize, q: f64) -> NetCase {
    let s = n + 2;
    let h = 1.0 / (n as f64 + 1.0);
    let id = |i: usize, j: usize| (i * s + j) as u32;
    let mut bars = Vec::with_capacity(2 * s * (s - 1));
    for i in 0..s {
        for j in 0..s {
            if j + 1 < s && i > 0 && i + 1 < s {
                bars.push(Bar { a: id(i, j), b: id(i, j + 1), q, group: None });
            }
            if i + 1 < s && j > 0 && j + 1 < s {
                bars.push(Bar { a: id(i, j), b: id(i + 1, j), q, group: None });
            }
        }
    }
    let fixed = (0..s * s).map(|k| (k / s) == 0 || (k / s) == s - 1 || k % s == 0 || k % s == s - 1).collect();
    let positions = (0..s * s).map(|k| Pt3::new((k % s) as f64 * h, (k / s) as f64 * h, 0.0)).collect();
    NetCase { net: BarNet { n_nodes: s * s, bars, fixed }, positions, loads: vec![Vec3::zeros(); s * s], exact: None }
}

/// The membrane of spec 7.1 c: [`grid_net`] with loads `p = h² · 2π² q sin(πx) sin(πy)` along
/// z; `exact` holds the continuum solution `u = sin(πx) sin(πy)` sampled at the free nodes
/// (the discrete solution differs by `O(h²)`).
pub fn membrane(n: usize, q: f64) -> NetCase {
    let mut c = grid_net(n, q);
    let h = 1.0 / (n as f64 + 1.0);
    let u = |p: &Pt3| (PI * p.x).sin() * (PI * p.y).sin();
    for (v, p) in c.positions.iter().enumerate() {
        if !c.net.fixed[v] {
            c.loads[v] = Vec3::new(0.0, 0.0, h * h * 2.0 * PI * PI * q * u(p));
        }
    }
    let exact = (0..c.net.n_nodes).filter(|&v| !c.net.fixed[v]).map(|v| {
        let p = c.positions[v];
        Pt3::new(p.x, p.y, u(&p))
    });
    c.exact = Some(exact.collect());
    c
}

/// A uniform-load membrane (`p = (0, 0, h²)` per free node), the `scaling` scene's system.
pub fn membrane_uniform(n: usize, q: f64) -> NetCase {
    let mut c = grid_net(n, q);
    let h = 1.0 / (n as f64 + 1.0);
    for v in 0..c.net.n_nodes {
        if !c.net.fixed[v] {
            c.loads[v] = Vec3::new(0.0, 0.0, h * h);
        }
    }
    c
}

/// A random connected 3-D net: `n_nodes` random positions in the unit cube, a random spanning
/// tree plus `extra` random bars (no self-loops, possibly duplicates), force densities
/// log-uniform in `[q_min, q_max]`, a fraction `fixed_frac` of the nodes fixed (at least one),
/// random loads of unit scale.
pub fn random_net(rng: &mut Rng, n_nodes: usize, extra: usize, fixed_frac: f64, q_min: f64, q_max: f64) -> NetCase {
    let n = n_nodes.max(2);
    let positions: Vec<Pt3> = (0..n).map(|_| Pt3::new(rng.f64(), rng.f64(), rng.f64())).collect();
    let mut bars = Vec::new();
    let lq = (q_min.ln(), q_max.ln());
    let q = |rng: &mut Rng| if lq.0 == lq.1 { q_min } else { rng.range(lq.0, lq.1).exp() };
    for v in 1..n {
        let u = rng.below(v);
        bars.push(Bar { a: u as u32, b: v as u32, q: q(rng), group: None });
    }
    for _ in 0..extra {
        let a = rng.below(n);
        let mut b = rng.below(n);
        if b == a {
            b = (a + 1) % n;
        }
        bars.push(Bar { a: a as u32, b: b as u32, q: q(rng), group: None });
    }
    let mut fixed: Vec<bool> = (0..n).map(|_| rng.chance(fixed_frac)).collect();
    if !fixed.iter().any(|&f| f) {
        fixed[rng.below(n)] = true;
    }
    let loads = (0..n).map(|_| Vec3::new(rng.range(-1.0, 1.0), rng.range(-1.0, 1.0), rng.range(-1.0, 1.0))).collect();
    NetCase { net: BarNet { n_nodes: n, bars, fixed }, positions, loads, exact: None }
}

/// Max normwise-relative nodal error `max_i ‖x_i − x*_i‖ / max_i ‖x*_i − x*_i,ref‖`, where the
/// reference is the unloaded straight line (cable) — here simply `max |Δ| / max |x*|` over the
/// coordinates given by `coord` (1 = y for the cable, 2 = z for the membrane).
pub fn max_rel_err(x: &[Pt3], exact: &[Pt3], coord: usize) -> f64 {
    let scale = exact.iter().map(|p| p[coord].abs()).fold(0.0, f64::max);
    let err = x.iter().zip(exact).map(|(a, b)| (a - b).norm()).fold(0.0, f64::max);
    if scale > 0.0 {
        err / scale
    } else {
        err
    }
}

/// Max absolute nodal error in coordinate `coord`.
pub fn max_abs_err(x: &[Pt3], exact: &[Pt3], coord: usize) -> f64 {
    x.iter().zip(exact).map(|(a, b)| (a[coord] - b[coord]).abs()).fold(0.0, f64::max)
}

//! Taubin λ|μ smoothing (Taubin 1995, "A signal processing approach to fair surface design"):
//! alternating a shrinking Laplacian step (λ > 0) and an inflating one (μ < −λ) smooths without
//! the shrinkage of plain Laplacian smoothing. TR uses (λ, μ) = (0.5, −0.53).

use serde::{Deserialize, Serialize};

use super::operators::cotan_stiffness;
use super::Topology;
use crate::math::{Pt3, Vec3};

/// Neighbour weights of the umbrella operator used by [`taubin_smooth`].
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum SmoothWeight {
    /// Every one-ring neighbour weighs 1 (also moves vertices tangentially toward regularity).
    #[default]
    Uniform,
    /// Cotan weights `−L_ij / L_ii`, recomputed from the current positions before each step
    /// (mostly normal motion; falls back to uniform at a vertex whose `L_ii ≤ 0`).
    Cotan,
}

/// Taubin smoothing in place: `iters` passes, each a step `x_i += λ Δx_i` followed by
/// `x_i += μ Δx_i`, with the normalised umbrella `Δx_i = Σ_j w_ij (x_j − x_i) / Σ_j w_ij` over the
/// one-ring, evaluated for all vertices before any moves (Jacobi, order-independent).
/// Vertices with `fixed[i] == true` (and isolated vertices) never move. Boundary vertices move
/// like any other (their one-ring is open); fix them to keep an open mesh's outline.
///
/// Panics if `p.len() != t.n_vertices()` or `fixed` has the wrong length (caller bugs, not
/// input data).
pub fn taubin_smooth(
    t: &Topology,
    p: &mut [Pt3],
    iters: u32,
    lambda: f64,
    mu: f64,
    w: SmoothWeight,
    fixed: Option<&[bool]>,
) {
    assert_eq!(p.len(), t.n_vertices(), "taubin_smooth: positions do not match the topology");
    if let Some(f) = fixed {
        assert_eq!(f.len(), p.len(), "taubin_smooth: `fixed` does not have one flag per vertex");
    }
    let faces = match w {
        SmoothWeight::Cotan => t.face_list(),
        SmoothWeight::Uniform => Vec::new(),
    };
    let ring = t.vertex_neighbors();
    let mut delta = vec![Vec3::zeros(); p.len()];
    for _ in 0..iters {
        for factor in [lambda, mu] {
            let l = (w == SmoothWeight::Cotan).then(|| cotan_stiffness(&faces, p, None));
            for (i, d) in delta.iter_mut().enumerate() {
                let xi = p[i];
                let uniform = || {
                    let r = ring.row(i);
                    if r.is_empty() {
                        return Vec3::zeros();
                    }
                    r.iter().fold(Vec3::zeros(), |s, &j| s + (p[j as usize] - xi)) / r.len() as f64
                };
                *d = match &l {
                    None => uniform(),
                    Some(l) => {
                        let (c, v) = l.row(i);
                        let mut diag = 0.0;
                        let mut s = Vec3::zeros();
                        for (&j, &lij) in c.iter().zip(v) {
                            if j as usize == i {
                                diag = lij;
                            } else {
                                s -= lij * (p[j as usize] - xi);
                            }
                        }
                        if diag > 0.0 && diag.is_finite() {
                            s / diag
                        } else {
                            uniform()
                        }
                    }
                };
            }
            for (i, (x, d)) in p.iter_mut().zip(&delta).enumerate() {
                if !fixed.is_some_and(|f| f[i]) {
                    *x += factor * d;
                }
            }
        }
    }
}

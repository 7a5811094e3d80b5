//! Every figure the wrinkle scenes and the benchmark report (spec §6, §9): the W1 per-frame
//! figures (mean modulation factor, area residual, clipped triangles), the W2 popping index,
//! probe lattices, and relative errors against a reference. Maxima and minima propagate NaN
//! (`geom_core::stats::{nan_max, nan_min}`): a failed triangle reads NaN, never 0.
//!
//! ```
//! use wrinkles::metrics::{popping_index, relative_errors};
//! assert_eq!(popping_index(None, &[0.1, 0.2], 0.2), 0.0);
//! assert!((popping_index(Some(&[0.1, 0.2]), &[0.1, 0.1], 0.2) - 0.5).abs() < 1e-15);
//! assert!(relative_errors(&[1.0, 2.0], &[1.0, 4.0], 1e-300).iter().any(|e| *e == 0.5));
//! ```

use geom_core::math::{Pt3, Vec2};
use geom_core::stats::{nan_max, nan_min};

use crate::animator::{AreaCheck, WrinkleAnimator};
use crate::error::Result;
use crate::frames::RestMesh;

/// The W1 figures of one frame of a single-pattern animator.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct UniaxialFrame {
    /// Mean modulation factor h over the unclipped triangles (h_max when all are clipped).
    pub h_mean: f64,
    /// Largest |A − A*|/A* over the unclipped triangles that can reach their target (a
    /// stretched triangle with h = 0 cannot and is skipped).
    pub area_residual: f64,
    /// Triangles whose h reached h_max.
    pub clipped: usize,
    /// Smallest h over all triangles.
    pub h_min: f64,
}

/// Modulates the deformed positions `def` with `a` (pattern 0) and measures the frame.
pub fn uniaxial_frame(a: &mut WrinkleAnimator, def: &[Pt3]) -> Result<UniaxialFrame> {
    let fm = a.frame(def)?;
    let rep = a.area_report(def, &fm, AreaCheck::PerTriangle)?;
    let hm = a.h_max()[0];
    let (mut hs, mut res, mut n, mut clipped) = (0.0, 0.0f64, 0usize, 0usize);
    for (t, h) in fm.tri_h.iter().enumerate() {
        if *h >= hm {
            clipped += 1;
            continue;
        }
        hs += h;
        n += 1;
        if *h == 0.0 && rep.area[t] >= rep.target[t] {
            continue; // stretched: no wrinkle can restore the area (h = 0 is the answer)
        }
        res = nan_max(res, (rep.area[t] - rep.target[t]).abs() / rep.target[t]);
    }
    let h_mean = if n > 0 { hs / n as f64 } else { hm };
    let h_min = fm.tri_h.iter().copied().fold(f64::INFINITY, nan_min);
    Ok(UniaxialFrame { h_mean, area_residual: res, clipped, h_min })
}

/// The W2 popping index of a frame: the largest change of the displacement at the probes since
/// the previous frame, `max |d − d_prev| / dmax` (0 for the first frame or `dmax ≤ 0`).
pub fn popping_index(prev: Option<&[f64]>, d: &[f64], dmax: f64) -> f64 {
    match prev {
        Some(p) if dmax > 0.0 => p.iter().zip(d).map(|(a, b)| (a - b).abs()).fold(0.0, nan_max) / dmax,
        _ => 0.0,
    }
}

/// Probe points of every triangle: the barycentric lattice of `level` (`(level+1)(level+2)/2`
/// points per triangle), as `(triangle, barycentric)`.
pub fn probe_lattice(n_tris: usize, level: u32) -> Vec<(usize, [f64; 3])> {
    let l = level as f64;
    (0..n_tris)
        .flat_map(|t| {
            (0..=level).flat_map(move |j| {
                (0..=(level - j)).map(move |i| (t, [(level - i - j) as f64 / l, i as f64 / l, j as f64 / l]))
            })
        })
        .collect()
}

/// The triangle of `mesh` (rest XY) containing the rest point `p`, if any.
pub fn triangle_at(mesh: &RestMesh, p: Vec2) -> Option<usize> {
    mesh.faces.iter().position(|f| {
        let q = |k: usize| Vec2::new(mesh.positions[f[k] as usize].x, mesh.positions[f[k] as usize].y);
        let cr = |a: Vec2, b: Vec2, c: Vec2| (b - a).perp(&(c - a));
        let (a, b, c) = (q(0), q(1), q(2));
        let s = cr(a, b, c).signum();
        cr(a, b, p) * s >= 0.0 && cr(b, c, p) * s >= 0.0 && cr(c, a, p) * s >= 0.0
    })
}

/// `|x − r| / max(r, floor)` per pair: relative errors against a non-negative reference `r`
/// (coefficients, modulation factors), `floor` guarding zeros.
pub fn relative_errors(x: &[f64], r: &[f64], floor: f64) -> Vec<f64> {
    x.iter().zip(r).map(|(a, b)| (a - b).abs() / b.max(floor)).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lattice_and_popping() {
        let p = probe_lattice(2, 4);
        assert_eq!(p.len(), 30);
        assert!(p.iter().all(|(_, b)| (b[0] + b[1] + b[2] - 1.0).abs() < 1e-15));
        assert!(popping_index(Some(&[0.0, f64::NAN]), &[0.0, 0.0], 1.0).is_nan());
    }
}

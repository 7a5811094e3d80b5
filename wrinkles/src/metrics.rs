//! Every figure the wrinkle scenes and the benchmark report (spec §6, §9): the W1 per-frame
//! figures (mean modulation factor, area residual, clipped triangles), the W2 popping index,
//! probe lattices, relative errors against a reference, and the W3/W4 fold statistics on a
//! material grid (detail height against a Gaussian-smoothed surface, its RMS, dominant
//! orientation and wavelength estimate, spec §6 W4 item 3) and area ratios in a region of
//! interest (item 2). Maxima and minima propagate NaN
//! (`geom_core::stats::{nan_max, nan_min}`): a failed triangle reads NaN, never 0.
//!
//! ```
//! use wrinkles::metrics::{popping_index, relative_errors};
//! assert_eq!(popping_index(None, &[0.1, 0.2], 0.2), 0.0);
//! assert!((popping_index(Some(&[0.1, 0.2]), &[0.1, 0.1], 0.2) - 0.5).abs() < 1e-15);
//! assert!(relative_errors(&[1.0, 2.0], &[1.0, 4.0], 1e-300).iter().any(|e| *e == 0.5));
//! ```

use geom_core::math::{Pt2, Pt3, Vec2, Vec3};
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

/// A regular grid of material points `(u, v) = origin + (i, j)·dx`, `i < nu`, `j < nv`, index
/// `j·nu + i` (m).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MaterialGrid {
    /// First point (m).
    pub origin: Pt2,
    /// Spacing (m).
    pub dx: f64,
    /// Points along u.
    pub nu: usize,
    /// Points along v.
    pub nv: usize,
}

impl MaterialGrid {
    /// The grid of spacing `dx` from `lo` that covers the box `[lo, hi]` (its last points are
    /// the last multiples of `dx` inside the box).
    pub fn covering(lo: Pt2, hi: Pt2, dx: f64) -> Self {
        let n = |a: f64, b: f64| ((b - a) / dx + 1e-9).floor().max(0.0) as usize + 1;
        Self { origin: lo, dx, nu: n(lo.x, hi.x), nv: n(lo.y, hi.y) }
    }

    /// Point (i, j) (m).
    pub fn point(&self, i: usize, j: usize) -> Pt2 {
        Pt2::new(self.origin.x + i as f64 * self.dx, self.origin.y + j as f64 * self.dx)
    }

    /// Every point, index order.
    pub fn points(&self) -> Vec<Pt2> {
        (0..self.nv).flat_map(|j| (0..self.nu).map(move |i| (i, j))).map(|(i, j)| self.point(i, j)).collect()
    }
}

/// The surface of a regular grid mesh (vertex (i, j) = `q[j·nx + i]`, material spacing
/// `size/(n − 1)` from material (0, 0)) at material point `uv`, bilinear in each cell (m).
/// Points outside are clamped to the sheet.
pub fn sample_grid_surface(q: &[Pt3], nx: usize, ny: usize, size: (f64, f64), uv: Pt2) -> Pt3 {
    let fx = (uv.x / size.0 * (nx - 1) as f64).clamp(0.0, (nx - 1) as f64);
    let fy = (uv.y / size.1 * (ny - 1) as f64).clamp(0.0, (ny - 1) as f64);
    let (i, j) = ((fx.floor() as usize).min(nx - 2), (fy.floor() as usize).min(ny - 2));
    let (a, b) = (fx - i as f64, fy - j as f64);
    let p = |i: usize, j: usize| q[j * nx + i].coords;
    Pt3::from(
        p(i, j) * ((1.0 - a) * (1.0 - b))
            + p(i + 1, j) * (a * (1.0 - b))
            + p(i, j + 1) * ((1.0 - a) * b)
            + p(i + 1, j + 1) * (a * b),
    )
}

/// Gaussian smoothing of grid samples in material space: separable, kernel `exp(−r²/2σ²)`
/// truncated at 3σ, weights renormalised where the kernel leaves the grid.
pub fn gaussian_smooth(x: &[Pt3], g: &MaterialGrid, sigma: f64) -> Vec<Pt3> {
    let r = ((3.0 * sigma / g.dx).ceil() as isize).max(1);
    let w: Vec<f64> = (-r..=r).map(|k| (-0.5 * (k as f64 * g.dx / sigma).powi(2)).exp()).collect();
    let pass = |src: &[Vec3], along_u: bool| -> Vec<Vec3> {
        let mut out = vec![Vec3::zeros(); src.len()];
        for j in 0..g.nv {
            for i in 0..g.nu {
                let (mut s, mut ws) = (Vec3::zeros(), 0.0);
                for (k, wk) in (-r..=r).zip(&w) {
                    let (ii, jj) = if along_u { (i as isize + k, j as isize) } else { (i as isize, j as isize + k) };
                    if ii < 0 || jj < 0 || ii >= g.nu as isize || jj >= g.nv as isize {
                        continue;
                    }
                    s += src[jj as usize * g.nu + ii as usize] * *wk;
                    ws += wk;
                }
                out[j * g.nu + i] = s / ws;
            }
        }
        out
    };
    let v: Vec<Vec3> = x.iter().map(|p| p.coords).collect();
    pass(&pass(&v, true), false).into_iter().map(Pt3::from).collect()
}

/// The detail height of spec §6 W4 item 3: `d = (X − X_s)·n_s`, `X_s` the surface smoothed with
/// σ ([`gaussian_smooth`]), `n_s` its unit normal `∂_u X_s × ∂_v X_s` (central differences,
/// one-sided at the border) (m).
pub fn detail_height(x: &[Pt3], g: &MaterialGrid, sigma: f64) -> Vec<f64> {
    let xs = gaussian_smooth(x, g, sigma);
    let at = |i: usize, j: usize| xs[j * g.nu + i];
    (0..g.nv)
        .flat_map(|j| (0..g.nu).map(move |i| (i, j)))
        .map(|(i, j)| {
            let du = at((i + 1).min(g.nu - 1), j) - at(i.saturating_sub(1), j);
            let dv = at(i, (j + 1).min(g.nv - 1)) - at(i, j.saturating_sub(1));
            let n = du.cross(&dv).try_normalize(0.0).unwrap_or(Vec3::z());
            (x[j * g.nu + i] - at(i, j)).dot(&n)
        })
        .collect()
}

/// Fold statistics of a detail-height field over a region of interest.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FoldStats {
    /// RMS(d) (m).
    pub rms: f64,
    /// Dominant orientation: the principal eigenvector of the structure tensor Σ∇d∇dᵀ (the
    /// wave vector), degrees from the u axis in (−90, 90].
    pub orient_deg: f64,
    /// Wavelength estimate λ̂ = 2π·sqrt(Σd² / Σ|∇d|²) (m).
    pub lambda_hat: f64,
    /// Folds across the middle row of the region: half the sign changes of d.
    pub folds: f64,
}

/// [`FoldStats`] of `d` (one value per grid point) over the grid points inside the material box
/// `[lo, hi]`; gradients by central differences (points on the grid border are skipped).
pub fn fold_stats(d: &[f64], g: &MaterialGrid, lo: Pt2, hi: Pt2) -> FoldStats {
    let inside = |p: Pt2| p.x >= lo.x && p.x <= hi.x && p.y >= lo.y && p.y <= hi.y;
    let (mut s2, mut n, mut jxx, mut jxy, mut jyy) = (0.0, 0usize, 0.0, 0.0, 0.0);
    let (mut jmin, mut jmax) = (usize::MAX, 0usize);
    for j in 1..g.nv.saturating_sub(1) {
        for i in 1..g.nu.saturating_sub(1) {
            if !inside(g.point(i, j)) {
                continue;
            }
            jmin = jmin.min(j);
            jmax = jmax.max(j);
            let k = j * g.nu + i;
            let gx = (d[k + 1] - d[k - 1]) / (2.0 * g.dx);
            let gy = (d[k + g.nu] - d[k - g.nu]) / (2.0 * g.dx);
            s2 += d[k] * d[k];
            n += 1;
            jxx += gx * gx;
            jxy += gx * gy;
            jyy += gy * gy;
        }
    }
    if n == 0 {
        return FoldStats { rms: f64::NAN, orient_deg: f64::NAN, lambda_hat: f64::NAN, folds: f64::NAN };
    }
    let orient = (0.5 * (2.0 * jxy).atan2(jxx - jyy)).to_degrees();
    let orient_deg = if orient <= -90.0 { orient + 180.0 } else { orient };
    let jm = (jmin + jmax) / 2;
    let row: Vec<f64> =
        (1..g.nu - 1).filter(|&i| inside(g.point(i, jm))).map(|i| d[jm * g.nu + i]).filter(|v| *v != 0.0).collect();
    let changes = row.windows(2).filter(|w| (w[0] > 0.0) != (w[1] > 0.0)).count();
    FoldStats {
        rms: (s2 / n as f64).sqrt(),
        orient_deg,
        lambda_hat: 2.0 * std::f64::consts::PI * (s2 / (jxx + jyy)).sqrt(),
        folds: if row.iter().any(|v| v.is_nan()) { f64::NAN } else { changes as f64 / 2.0 },
    }
}

/// The angle between two orientations (degrees, modulo 180°): in [0, 90].
pub fn orientation_difference_deg(a: f64, b: f64) -> f64 {
    let d = (a - b).rem_euclid(180.0);
    d.min(180.0 - d)
}

/// Surface area over material area of the faces whose material (UV) centroid lies in
/// `[lo, hi]`: `Σ area(q) / Σ area(uv)` (NaN when no face is inside). `uv(f, k)` is corner `k`
/// of face `f` in material coordinates (m).
pub fn area_ratio_in(faces: &[[u32; 3]], q: &[Pt3], uv: impl Fn(usize, usize) -> Pt2, lo: Pt2, hi: Pt2) -> f64 {
    let (mut a, mut a0) = (0.0, 0.0);
    for (f, t) in faces.iter().enumerate() {
        let (u0, u1, u2) = (uv(f, 0), uv(f, 1), uv(f, 2));
        let c = Pt2::from((u0.coords + u1.coords + u2.coords) / 3.0);
        if c.x < lo.x || c.x > hi.x || c.y < lo.y || c.y > hi.y {
            continue;
        }
        let [p0, p1, p2] = t.map(|i| q[i as usize]);
        a += 0.5 * (p1 - p0).cross(&(p2 - p0)).norm();
        a0 += 0.5 * (u1 - u0).perp(&(u2 - u0)).abs();
    }
    if a0 > 0.0 {
        a / a0
    } else {
        f64::NAN
    }
}

/// The face of `mesh` whose UV triangle contains the material point `p`, with the barycentric
/// coordinates of `p` in it (the first such face; `None` outside the UV domain).
pub fn locate_uv(mesh: &RestMesh, p: Pt2) -> Option<(usize, [f64; 3])> {
    (0..mesh.faces.len()).find_map(|f| {
        let (a, b, c) = (mesh.uv(f, 0), mesh.uv(f, 1), mesh.uv(f, 2));
        let det = (b - a).perp(&(c - a));
        if det.abs() <= 0.0 {
            return None;
        }
        let l1 = (p - a).perp(&(c - a)) / det;
        let l2 = (b - a).perp(&(p - a)) / det;
        let l0 = 1.0 - l1 - l2;
        let eps = -1e-12;
        (l0 >= eps && l1 >= eps && l2 >= eps).then_some((f, [l0, l1, l2]))
    })
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

    /// A sinusoidal height field along u: λ̂ equals λ, the orientation is 0° (wave vector along
    /// u), the RMS is A/√2, and the middle row crosses zero twice per wavelength. λ̂ comes from
    /// finite-difference gradients, which overestimate λ by kh/sin(kh) (2.6 % at h = λ/16,
    /// measured 3.2 % with the one-sided edges); at h = λ/64 the bias is 0.16 %, so the 1 %
    /// tolerance tests the estimator, not its grid.
    #[test]
    fn fold_stats_of_a_sinusoid() {
        let lambda = 0.05;
        let g = MaterialGrid::covering(Pt2::new(0.0, 0.0), Pt2::new(0.5, 0.2), lambda / 64.0);
        let d: Vec<f64> =
            g.points().iter().map(|p| 0.01 * (2.0 * std::f64::consts::PI * p.x / lambda + 0.3).sin()).collect();
        let s = fold_stats(&d, &g, Pt2::new(0.0, 0.0), Pt2::new(0.5, 0.2));
        assert!((s.lambda_hat - lambda).abs() < 0.01 * lambda, "{s:?}");
        assert!(s.orient_deg.abs() < 1e-9, "{s:?}");
        assert!((s.rms - 0.01 / 2f64.sqrt()).abs() < 2e-4, "{s:?}");
        assert!((s.folds - 10.0).abs() <= 0.5, "{s:?}");
        assert!((orientation_difference_deg(89.0, -89.0) - 2.0).abs() < 1e-12);
    }

    /// The detail height of a flat sheet carrying a small sinusoid is the sinusoid (the smoothing
    /// removes it from X_s); the area ratio of a sheet stretched by 2 along u is 2.
    #[test]
    fn detail_height_and_area_ratio() {
        let lambda = 0.04;
        let g = MaterialGrid::covering(Pt2::new(0.0, 0.0), Pt2::new(0.4, 0.4), lambda / 10.0);
        let amp = |x: f64| 0.002 * (2.0 * std::f64::consts::PI * x / lambda).sin();
        let x: Vec<Pt3> = g.points().iter().map(|p| Pt3::new(p.x, p.y, amp(p.x))).collect();
        let d = detail_height(&x, &g, lambda);
        let k = (g.nv / 2) * g.nu + g.nu / 2;
        assert!((d[k] - amp(g.points()[k].x)).abs() < 2e-4, "{} vs {}", d[k], amp(g.points()[k].x));
        let faces = [[0u32, 1, 2]];
        let uv = [Pt2::new(0.0, 0.0), Pt2::new(1.0, 0.0), Pt2::new(0.0, 1.0)];
        let q = [Pt3::new(0.0, 0.0, 0.0), Pt3::new(2.0, 0.0, 0.0), Pt3::new(0.0, 1.0, 0.0)];
        let r = area_ratio_in(&faces, &q, |_, k| uv[k], Pt2::new(0.0, 0.0), Pt2::new(1.0, 1.0));
        assert!((r - 2.0).abs() < 1e-15);
        assert!(area_ratio_in(&faces, &q, |_, k| uv[k], Pt2::new(5.0, 5.0), Pt2::new(6.0, 6.0)).is_nan());
    }
}

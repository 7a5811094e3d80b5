//! Metrics of spec §3.8 (computed outside the timed step): low-pass filter, coarse-scale
//! deviation D_c, detail amplitude a_d, detail wavelength λ_eff, bending energy and tug index
//! (Fig. 3/4), non-rigidity and seam–joint alignment (Fig. 7).

use geom_core::linalg::{Csr, Ordering, SparseLlt};
use geom_core::math::{Mat3, Pt3, Vec3};
use geom_core::mesh::TriMesh;
use shells::ShellSim;

use crate::error::Result;
use crate::guide::GuideAnimation;

/// The low-pass filter L_τ = (M_L + τK)⁻¹ M_L on a rest mesh (M_L lumped areas, K the PSD
/// cotangent Laplacian), factorised once.
pub struct LowPass {
    /// Lumped (barycentric) vertex areas a_i (m²).
    pub areas: Vec<f64>,
    /// Cotangent stiffness K.
    pub k: Csr,
    /// τ (m²).
    pub tau: f64,
    llt: SparseLlt,
}

impl LowPass {
    /// Builds L_τ with τ = (ℓ_c/π)², ℓ_c = sqrt(A_total/K) for `k_regions` test functions (spec
    /// §3.8), or the given τ.
    pub fn new(rest: &TriMesh, tau: f64) -> Result<Self> {
        let areas = geom_core::mesh::mass_barycentric(&rest.faces, &rest.positions);
        let k = geom_core::mesh::cotan_stiffness(&rest.faces, &rest.positions, Some(1e3));
        let a = Csr::diag(&areas).add(&k, 1.0, tau);
        let csc = a.to_csc_lower();
        let mut llt = SparseLlt::analyze(&csc, Ordering::Amd)?;
        llt.factor(&csc)?;
        Ok(Self { areas, k, tau, llt })
    }

    /// τ = (ℓ_c/π)² with ℓ_c = sqrt(A_total / K).
    pub fn tau_for(rest: &TriMesh, k_regions: usize) -> f64 {
        let a: f64 = geom_core::mesh::face_areas(&rest.faces, &rest.positions).iter().sum();
        let lc = (a / k_regions.max(1) as f64).sqrt();
        (lc / std::f64::consts::PI).powi(2)
    }

    /// L_τ d.
    pub fn apply(&self, d: &[Vec3]) -> Result<Vec<Vec3>> {
        let mut out = vec![Vec3::zeros(); d.len()];
        for c in 0..3 {
            let mut x: Vec<f64> = d.iter().zip(&self.areas).map(|(v, a)| a * v[c]).collect();
            self.llt.solve_in_place(&mut x)?;
            out.iter_mut().zip(&x).for_each(|(o, v)| o[c] = *v);
        }
        Ok(out)
    }

    /// Area-weighted RMS norm sqrt(Σ a_i‖x_i‖² / Σ a_i).
    pub fn rms(&self, x: &[Vec3]) -> f64 {
        let tot: f64 = self.areas.iter().sum();
        (x.iter().zip(&self.areas).map(|(v, a)| a * v.norm_squared()).sum::<f64>() / tot).sqrt()
    }

    /// Coarse-scale deviation D_c = rms(L_τ d) / L (dimensionless), d = q − q̄_f.
    pub fn coarse_deviation(&self, d: &[Vec3], scale: f64) -> Result<f64> {
        Ok(self.rms(&self.apply(d)?) / scale)
    }

    /// Detail amplitude a_d = rms(d − L_τ d) (m).
    pub fn detail_amplitude(&self, d: &[Vec3]) -> Result<f64> {
        let lo = self.apply(d)?;
        let h: Vec<Vec3> = d.iter().zip(&lo).map(|(a, b)| a - b).collect();
        Ok(self.rms(&h))
    }

    /// Detail wavelength λ_eff = 2π sqrt(hᵀM_L h / hᵀK h) (m) of a field h (for a sinusoid of
    /// wavelength λ on a flat mesh this returns λ). Infinite for h in the kernel of K.
    pub fn wavelength(&self, h: &[Vec3]) -> f64 {
        let mut num = 0.0;
        let mut den = 0.0;
        for c in 0..3 {
            let x: Vec<f64> = h.iter().map(|v| v[c]).collect();
            let mut kx = vec![0.0; x.len()];
            self.k.mul_vec(&x, &mut kx);
            num += x.iter().zip(&self.areas).map(|(v, a)| a * v * v).sum::<f64>();
            den += x.iter().zip(&kx).map(|(a, b)| a * b).sum::<f64>();
        }
        if den <= 0.0 {
            f64::INFINITY
        } else {
            std::f64::consts::TAU * (num / den).sqrt()
        }
    }
}

impl LowPass {
    /// Area-weighted RMS norm over the vertices with `mask[i]`:
    /// sqrt(Σ_{i∈S} a_i‖x_i‖² / Σ_{i∈S} a_i) (NaN for an empty subset).
    pub fn rms_subset(&self, x: &[Vec3], mask: &[bool]) -> f64 {
        let (mut num, mut tot) = (0.0, 0.0);
        for ((v, a), &m) in x.iter().zip(&self.areas).zip(mask) {
            if m {
                num += a * v.norm_squared();
                tot += a;
            }
        }
        if tot > 0.0 {
            (num / tot).sqrt()
        } else {
            f64::NAN
        }
    }

    /// Detail wavelength of a field h restricted to the vertices with `mask[i]` (m):
    /// λ = 2π sqrt(Σ_{i∈S} a_i‖h_i‖² / Σ_{ij∈E(S)} w_ij‖h_i − h_j‖²), the quotient of
    /// [`LowPass::wavelength`] with both sums over the subset (the edge form of hᵀKh keeps only
    /// the edges with both ends in S, so no jump is created at the subset's border). Equals
    /// [`LowPass::wavelength`] for the full mask; infinite when the subset's h is constant.
    pub fn wavelength_subset(&self, h: &[Vec3], mask: &[bool]) -> f64 {
        let mut num = 0.0;
        for ((v, a), &m) in h.iter().zip(&self.areas).zip(mask) {
            if m {
                num += a * v.norm_squared();
            }
        }
        let mut den = 0.0;
        for i in 0..self.k.nrows {
            if !mask[i] {
                continue;
            }
            let (cols, vals) = self.k.row(i);
            for (&j, &kij) in cols.iter().zip(vals) {
                let j = j as usize;
                if j > i && mask[j] {
                    den += -kij * (h[i] - h[j]).norm_squared();
                }
            }
        }
        if den <= 0.0 {
            f64::INFINITY
        } else {
            std::f64::consts::TAU * (num / den).sqrt()
        }
    }
}

/// A vertex mask of length `n` with `true` at `vertices`.
pub fn vertex_mask(n: usize, vertices: &[u32]) -> Vec<bool> {
    let mut m = vec![false; n];
    for &v in vertices {
        if let Some(x) = m.get_mut(v as usize) {
            *x = true;
        }
    }
    m
}

/// d = q − q̄_f with q̄_f = P q̄ (or q̄ itself for identical meshes).
pub fn guide_on_tracked(prolongation: Option<&Csr>, guide_q: &[Pt3]) -> Vec<Pt3> {
    match prolongation {
        None => guide_q.to_vec(),
        Some(p) => {
            let mut out = vec![Pt3::origin(); p.nrows];
            for c in 0..3 {
                let x: Vec<f64> = guide_q.iter().map(|v| v[c]).collect();
                let mut y = vec![0.0; p.nrows];
                p.mul_vec(&x, &mut y);
                out.iter_mut().zip(&y).for_each(|(o, v)| o[c] = *v);
            }
            out
        }
    }
}

/// Per-hinge bending energy k ω Δθ² of configuration q (J), shells' hinge model.
pub fn hinge_energies(sim: &ShellSim, q: &[Pt3]) -> Vec<f64> {
    sim.mesh().hinges.iter().map(|h| shells::kernels::bending::bending_energy(h, &h.v.map(|i| q[i as usize]))).collect()
}

/// Tug index (Fig. 3/4): share of the bending energy on hinges whose edge lies in the closed
/// one-ring of an anchor vertex, divided by the share of rest area of the anchors' incident
/// triangles. ≈ 1 for smooth tracking, ≫ 1 when anchors tug. 1 when the energy is zero.
pub fn tug_index(sim: &ShellSim, q: &[Pt3], anchors: &[u32]) -> f64 {
    let mesh = sim.mesh();
    let n = mesh.n_vertices();
    let mut near = vec![false; n];
    let mut anchor = vec![false; n];
    anchors.iter().for_each(|&a| anchor[a as usize] = true);
    let mut area_near = 0.0;
    let mut area_tot = 0.0;
    for t in &mesh.tris {
        let x = t.map(|v| mesh.rest[v as usize]);
        let a = 0.5 * (x[1] - x[0]).cross(&(x[2] - x[0])).norm();
        area_tot += a;
        if t.iter().any(|&v| anchor[v as usize]) {
            area_near += a;
            t.iter().for_each(|&v| near[v as usize] = true);
        }
    }
    let e = hinge_energies(sim, q);
    let tot: f64 = e.iter().sum();
    if tot <= 0.0 || area_near <= 0.0 {
        return 1.0;
    }
    let en: f64 = mesh
        .hinges
        .iter()
        .zip(&e)
        .filter(|(h, _)| near[h.v[0] as usize] && near[h.v[1] as usize])
        .map(|(_, e)| e)
        .sum();
    (en / tot) / (area_near / area_tot)
}

/// RMS residual of the best rigid fit (Kabsch) of `rest` onto `cur` (same length).
pub fn rigid_fit_rms(rest: &[Pt3], cur: &[Pt3]) -> f64 {
    let n = rest.len() as f64;
    if rest.is_empty() {
        return 0.0;
    }
    let ca = rest.iter().fold(Vec3::zeros(), |s, p| s + p.coords) / n;
    let cb = cur.iter().fold(Vec3::zeros(), |s, p| s + p.coords) / n;
    let mut h = Mat3::zeros();
    for (a, b) in rest.iter().zip(cur) {
        h += (a.coords - ca) * (b.coords - cb).transpose();
    }
    let svd = h.svd(true, true);
    let (u, vt) = (svd.u.expect("requested"), svd.v_t.expect("requested"));
    let mut d = Mat3::identity();
    if (vt.transpose() * u.transpose()).determinant() < 0.0 {
        d[(2, 2)] = -1.0;
    }
    let r = vt.transpose() * d * u.transpose();
    (rest.iter().zip(cur).map(|(a, b)| (r * (a.coords - ca) - (b.coords - cb)).norm_squared()).sum::<f64>() / n).sqrt()
}

/// Non-rigidity (Fig. 7): for each region, the max over `times` of the rigid-fit RMS residual of
/// its guide vertices (frame vs rest) divided by the region's rest diameter (bounding-box
/// diagonal); averaged over regions.
pub fn non_rigidity(guide: &GuideAnimation, vertex_labels: &[u32], k: usize, times: &[f64]) -> f64 {
    let mut members: Vec<Vec<usize>> = vec![Vec::new(); k];
    for (v, &l) in vertex_labels.iter().enumerate() {
        if l != geom_core::NONE {
            members[l as usize].push(v);
        }
    }
    let rest = &guide.rest.positions;
    let mut worst = vec![0.0f64; k];
    let mut buf = vec![Pt3::origin(); rest.len()];
    for &t in times {
        guide.sample(t, &mut buf);
        for (r, m) in members.iter().enumerate() {
            let a: Vec<Pt3> = m.iter().map(|&v| rest[v]).collect();
            let b: Vec<Pt3> = m.iter().map(|&v| buf[v]).collect();
            let diam = geom_core::mesh::bbox_of(&a).map_or(0.0, |(lo, hi)| (hi - lo).norm());
            if diam > 0.0 {
                worst[r] = worst[r].max(rigid_fit_rms(&a, &b) / diam);
            }
        }
    }
    let used = members.iter().filter(|m| !m.is_empty()).count().max(1);
    worst.iter().sum::<f64>() / used as f64
}

/// Seam–joint alignment (Fig. 7): fraction of seam edges (endpoints in different regions) whose
/// endpoints both have max skinning weight < 0.8, divided by the same fraction over all edges.
pub fn seam_joint_alignment(mesh: &TriMesh, vertex_labels: &[u32], max_weight: &[f64]) -> f64 {
    let edges = mesh.topology().edges();
    let joint = |e: &[u32; 2]| max_weight[e[0] as usize] < 0.8 && max_weight[e[1] as usize] < 0.8;
    let all = edges.iter().filter(|e| joint(e)).count() as f64 / edges.len().max(1) as f64;
    let seams: Vec<&[u32; 2]> =
        edges.iter().filter(|e| vertex_labels[e[0] as usize] != vertex_labels[e[1] as usize]).collect();
    if seams.is_empty() || all == 0.0 {
        return 0.0;
    }
    let s = seams.iter().filter(|e| joint(e)).count() as f64 / seams.len() as f64;
    s / all
}

// ---------------------------------------------------------------------------------------------
// figures of the scenes (computed from per-step and per-frame series)

/// Overhead of tracking (%) = 100·(Σ tracked step time / Σ untracked step time − 1) (Bergou et
/// al. 2007 §5.5 "overhead"); NaN without an untracked run.
pub fn overhead_pct(t_tracked: f64, t_untracked: f64) -> f64 {
    if t_untracked > 0.0 {
        100.0 * (t_tracked / t_untracked - 1.0)
    } else {
        f64::NAN
    }
}

/// Overhead (%) from the median tracked and untracked step times (robust to load bursts of a
/// shared machine); `step_times` = (tracked, untracked) wall time per step (s).
pub fn overhead_pct_median(step_times: &[(f64, f64)]) -> f64 {
    let t: Vec<f64> = step_times.iter().map(|x| x.0).collect();
    let u: Vec<f64> = step_times.iter().map(|x| x.1).collect();
    100.0 * (geom_core::stats::median(&t) / geom_core::stats::median(&u) - 1.0)
}

/// The tracked step's linear-solve cost relative to the untracked one (issue 20): the median
/// over steps of the tracked step's constrained solve time `t_kkt` (assembly of the KKT values,
/// numeric factorisation and solve, summed over the step's Newton iterations) over the median of
/// the untracked step's numeric factorisation + solve of A (`t_factor + t_solve`, also summed
/// over its iterations). Dimensionless; NaN when either sample is empty.
pub fn kkt_over_untracked_factor(t_kkt: &[f64], t_factor_solve_untracked: &[f64]) -> f64 {
    geom_core::stats::median(t_kkt) / geom_core::stats::median(t_factor_solve_untracked)
}

/// Largest value of `v` over the frames with time t ∈ [a, b] (`times` aligned with `v`); NaN
/// when no frame falls in the window or a value there is NaN.
pub fn window_max(times: &[f64], v: &[f64], a: f64, b: f64) -> f64 {
    let sel: Vec<f64> = times.iter().zip(v).filter(|(t, _)| **t >= a && **t <= b).map(|(_, e)| *e).collect();
    geom_core::stats::max(&sel)
}

/// Mean of `v` over the frames with a − 1e-9 ≤ t ≤ b + 1e-9; NaN when none.
pub fn window_mean(times: &[f64], v: &[f64], a: f64, b: f64) -> f64 {
    let sel: Vec<f64> =
        times.iter().zip(v).filter(|(x, _)| **x >= a - 1e-9 && **x <= b + 1e-9).map(|(_, y)| *y).collect();
    geom_core::stats::mean(&sel)
}

/// Value of `v` at the first frame within `tol` s of `t`, NaN when none.
pub fn value_at(times: &[f64], v: &[f64], t: f64, tol: f64) -> f64 {
    times.iter().zip(v).find(|(x, _)| (**x - t).abs() < tol).map_or(f64::NAN, |(_, y)| *y)
}

/// Centroid (unweighted mean of the vertices) (m).
pub fn centroid(q: &[Pt3]) -> Pt3 {
    Pt3::from(q.iter().fold(Vec3::zeros(), |a, p| a + p.coords) / q.len() as f64)
}

/// Mean vertex speed (m/s).
pub fn mean_speed(v: &[Vec3]) -> f64 {
    v.iter().map(|x| x.norm()).sum::<f64>() / v.len() as f64
}

/// Distance (m) of a point from the flag's branch axis (the line x = 2.0, y = 1.2 m along z).
pub fn branch_distance(c: &Pt3) -> f64 {
    ((c.x - 2.0).powi(2) + (c.y - 1.2).powi(2)).sqrt()
}

/// Stuck on the branch (§5.1): the last centroid within 0.3 m of the branch axis and mean speed
/// < 0.05 m/s over the last 0.5 s (`centroids`, `speeds` per frame at `fps`).
pub fn stuck_on_branch(centroids: &[Pt3], speeds: &[f64], fps: f64) -> bool {
    let n = (0.5 * fps).round() as usize;
    let (Some(c), true) = (centroids.last(), speeds.len() >= n) else { return false };
    let mean_v = speeds[speeds.len() - n..].iter().sum::<f64>() / n as f64;
    branch_distance(c) < 0.3 && mean_v < 0.05
}

/// Largest displacement (m) of any guide vertex between `t0` and the frames (at `fps`) up to
/// `t1` (the guide's kinetic energy after `t0` is zero iff this is zero).
pub fn guide_motion_after(guide: &GuideAnimation, t0: f64, t1: f64, fps: f64) -> f64 {
    let mut a = vec![Pt3::origin(); guide.n_vertices()];
    let mut b = a.clone();
    guide.sample(t0, &mut a);
    let mut worst = 0.0f64;
    let mut t = t0;
    while t <= t1 + 1e-9 {
        guide.sample(t, &mut b);
        worst = a.iter().zip(&b).map(|(x, y)| (x - y).norm()).fold(worst, geom_core::stats::nan_max);
        t += 1.0 / fps;
    }
    worst
}

/// Coefficient of variation (std / mean) of the region areas of a triangle labelling (Fig. 7's
/// evenness of the regions).
pub fn region_area_cv(mesh: &TriMesh, tri_labels: &[u32], regions: usize) -> f64 {
    let areas = geom_core::mesh::face_areas(&mesh.faces, &mesh.positions);
    let mut ra = vec![0.0; regions];
    for (f, &l) in tri_labels.iter().enumerate() {
        ra[l as usize] += areas[f];
    }
    let n = ra.len() as f64;
    let mean = geom_core::stats::mean(&ra);
    (ra.iter().map(|a| (a - mean).powi(2)).sum::<f64>() / n).sqrt() / mean
}

#[cfg(test)]
mod tests {
    use super::*;
    use geom_core::procedural::{grid, GridSpec};

    /// λ_eff of a sinusoid of wavelength λ on a fine flat grid returns λ (2 % for the
    /// discretisation at 20 samples per wavelength).
    #[test]
    fn wavelength_of_sinusoid() {
        let m = grid(&GridSpec { quads: [80, 8], size: [2.0, 0.2], ..GridSpec::default() }).expect("grid");
        let lp = LowPass::new(&m, 0.0).expect("lowpass");
        let lambda = 0.5;
        let h: Vec<Vec3> =
            m.positions.iter().map(|p| Vec3::new(0.0, 0.0, (std::f64::consts::TAU * p.x / lambda).sin())).collect();
        let w = lp.wavelength(&h);
        assert!((w - lambda).abs() < 0.02 * lambda, "λ_eff = {w}");
    }

    /// The subset forms: full mask = the whole-mesh figures (1e-12); on a grid whose left half
    /// carries a sinusoid of wavelength 0.25 m and whose right half one of 1 m, each half's
    /// wavelength is its own (5 %).
    #[test]
    fn subset_wavelength_and_rms() {
        let m = grid(&GridSpec { quads: [160, 8], size: [4.0, 0.2], ..GridSpec::default() }).expect("grid");
        let lp = LowPass::new(&m, 0.0).expect("lowpass");
        let wave =
            |x: f64| if x < 0.0 { (std::f64::consts::TAU * x / 0.25).sin() } else { (std::f64::consts::TAU * x).sin() };
        let h: Vec<Vec3> = m.positions.iter().map(|p| Vec3::new(0.0, 0.0, wave(p.x))).collect();
        let all = vec![true; h.len()];
        assert!((lp.wavelength_subset(&h, &all) - lp.wavelength(&h)).abs() < 1e-12 * lp.wavelength(&h));
        assert!((lp.rms_subset(&h, &all) - lp.rms(&h)).abs() < 1e-12);
        let left: Vec<u32> = (0..h.len() as u32).filter(|&v| m.positions[v as usize].x < -0.01).collect();
        let right: Vec<u32> = (0..h.len() as u32).filter(|&v| m.positions[v as usize].x > 0.01).collect();
        let (wl, wr) = (
            lp.wavelength_subset(&h, &vertex_mask(h.len(), &left)),
            lp.wavelength_subset(&h, &vertex_mask(h.len(), &right)),
        );
        assert!((wl - 0.25).abs() < 0.05 * 0.25, "left λ = {wl}");
        assert!((wr - 1.0).abs() < 0.05, "right λ = {wr}");
        assert!(lp.rms_subset(&h, &vec![false; h.len()]).is_nan());
    }

    /// Kabsch: a rigid motion has zero residual (1e-12).
    #[test]
    fn rigid_fit_zero_for_rigid_motion() {
        let a: Vec<Pt3> = (0..10).map(|i| Pt3::new(i as f64, (i * i) as f64 * 0.1, (i as f64).sin())).collect();
        let r = geom_core::math::UnitQuat::from_scaled_axis(Vec3::new(0.3, -1.0, 0.4));
        let b: Vec<Pt3> = a.iter().map(|p| Pt3::from(r * p.coords + Vec3::new(1.0, 2.0, 3.0))).collect();
        assert!(rigid_fit_rms(&a, &b) < 1e-12);
    }
}

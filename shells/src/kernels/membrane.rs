//! Constant-strain-triangle membrane with the St. Venant–Kirchhoff law, its orthotropic (Voigt)
//! generalisation and the compression-softened variant (shells.md §3.3, §3.4).
//!
//! Per triangle (i, j, k): shape-function gradients b_a (rest frame, precomputed in [`TriRest`]),
//! deformation gradient F = Σ_a q_a b_aᵀ (3×2), Green strain G = ½(FᵀF − I₂),
//! ε = (G₁₁, G₂₂, 2G₁₂), energy E_T = Ā ψ(G).
//!
//! * Voigt law ψ = ½εᵀℂε: S = ℂε, ∂E/∂q_a = Ā F S b_a,
//!   ∂²E/∂q_a∂q_b = Ā[(b_aᵀ S b_b) I₃ + D_aᵀ ℂ D_b] with D_a the rows
//!   (b_a1 f₁ᵀ, b_a2 f₂ᵀ, b_a1 f₂ᵀ + b_a2 f₁ᵀ). Isotropic StVK is
//!   ℂ = [[2μ+λ, λ, 0], [λ, 2μ+λ, 0], [0, 0, μ]] with μ = Yt/(2(1+ν)), λ = Ytν/(1−ν²).
//! * Softened law (isotropic, factor s on compressive principal strains): the principal-frame
//!   formulas of §3.3 with the divided difference δ.
//!
//! The first Hessian term (geometric stiffness) is indefinite under compression; the modes of
//! [`HessianMode`] decide what is done about it.

use super::psd::{project_psd, psd_part2, sym_eig2, HessianMode};
use geom_core::math::{Mat2, Mat3, Pt3, Vec2, Vec3};
use nalgebra::{Matrix3x2, SMatrix, SVector};
use serde::{Deserialize, Serialize};

/// 9×9 matrix over a triangle's three vertices.
pub type Mat9 = SMatrix<f64, 9, 9>;
/// 9-vector over a triangle's three vertices.
pub type Vec9 = SVector<f64, 9>;

/// Rest data of one triangle: area Ā (m²) and the shape-function gradients b_a (1/m) in the
/// triangle's rest frame (first axis = warp direction for orthotropic laws, first edge
/// otherwise).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct TriRest {
    /// Rest area Ā (m²).
    pub area: f64,
    /// Shape-function gradients b_i, b_j, b_k (sum to zero).
    pub grads: [Vec2; 3],
}

impl TriRest {
    /// Rest data of the triangle `x` with the frame's first axis along `axis` projected into the
    /// triangle plane (`None`: along the first edge). Returns `None` when the triangle is
    /// degenerate or the projected axis is shorter than 1e-6 (axis parallel to the normal).
    pub fn new(x: &[Pt3; 3], axis: Option<Vec3>) -> Option<Self> {
        let e1 = x[1] - x[0];
        let e2 = x[2] - x[0];
        let n = e1.cross(&e2);
        let area = 0.5 * n.norm();
        if !(area > 0.0) {
            return None;
        }
        let nh = n / (2.0 * area);
        let t = match axis {
            None => e1.normalize(),
            Some(a) => {
                let a = a.normalize();
                let p = a - nh * nh.dot(&a);
                if !(p.norm() >= 1e-6) {
                    return None;
                }
                p.normalize()
            }
        };
        let s = nh.cross(&t);
        let d = Mat2::new(e1.dot(&t), e2.dot(&t), e1.dot(&s), e2.dot(&s));
        let b = d.try_inverse()?;
        let bj = Vec2::new(b[(0, 0)], b[(0, 1)]);
        let bk = Vec2::new(b[(1, 0)], b[(1, 1)]);
        Some(Self { area, grads: [-bj - bk, bj, bk] })
    }
}

/// A membrane law resolved to the numbers the kernel needs (N/m).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub enum Membrane {
    /// ψ = ½εᵀℂε with a constant symmetric PSD ℂ (isotropic StVK or orthotropic).
    Voigt {
        /// The 3×3 Voigt stiffness (N/m), rows/cols (G₁₁, G₂₂, 2G₁₂).
        c: Mat3,
    },
    /// Compression-softened isotropic StVK: ψ = μΣc(gᵢ)gᵢ² + ½λc(tr G)(tr G)², c(x) = 1 for
    /// x ≥ 0 and `s` otherwise.
    Softened {
        /// Surface Lamé μ_s (N/m).
        mu: f64,
        /// Surface Lamé λ_s (N/m).
        lambda: f64,
        /// Compression factor s ∈ (0, 1].
        s: f64,
    },
}

impl Membrane {
    /// Surface Lamé parameters (μ_s, λ_s) of plane-stress StVK from Yt (N/m) and ν.
    pub fn lame(young_thickness: f64, poisson: f64) -> (f64, f64) {
        (young_thickness / (2.0 * (1.0 + poisson)), young_thickness * poisson / (1.0 - poisson * poisson))
    }

    /// Isotropic StVK as a Voigt law.
    pub fn isotropic(young_thickness: f64, poisson: f64) -> Self {
        let (mu, la) = Self::lame(young_thickness, poisson);
        Membrane::Voigt { c: Mat3::new(2.0 * mu + la, la, 0.0, la, 2.0 * mu + la, 0.0, 0.0, 0.0, mu) }
    }

    /// Orthotropic Voigt law ψ = ½k_uG₁₁² + ½k_vG₂₂² + 2k_shear G₁₂² + k_couple G₁₁G₂₂.
    pub fn orthotropic(k_u: f64, k_v: f64, k_shear: f64, k_couple: f64) -> Self {
        Membrane::Voigt { c: Mat3::new(k_u, k_couple, 0.0, k_couple, k_v, 0.0, 0.0, 0.0, k_shear) }
    }
}

/// Everything one membrane evaluation produces.
#[derive(Clone, Debug)]
pub struct MembraneOut {
    /// Energy Ā ψ (J).
    pub energy: f64,
    /// Gradient ∂E/∂q (N), blocks i, j, k.
    pub grad: Vec9,
    /// Hessian in the requested mode (N/m).
    pub hess: Mat9,
    /// β_stretch·H_stretch + β_shear·H_shear with the Gauss–Newton (material) parts (§3.5), when
    /// asked for.
    pub damp: Option<Mat9>,
    /// True when the deformed triangle has collapsed to zero area (|f₁ × f₂| = 0); the energy
    /// stays finite (StVK), the flag only feeds the step statistics (§8).
    pub collapsed: bool,
}

/// Membrane element: energy, gradient and Hessian of one triangle (§3.3) in `mode`.
pub fn membrane_element(t: &TriRest, m: &Membrane, x: &[Pt3; 3], mode: HessianMode) -> (f64, Vec9, Mat9) {
    let o = membrane_eval(t, m, x, mode, None);
    (o.energy, o.grad, o.hess)
}

/// Energy only (cheap; used by line search and energy reports).
pub fn membrane_energy(t: &TriRest, m: &Membrane, x: &[Pt3; 3]) -> f64 {
    let f = deformation_gradient(t, x);
    let g = green(&f);
    t.area * psi(m, &g)
}

fn deformation_gradient(t: &TriRest, x: &[Pt3; 3]) -> Matrix3x2<f64> {
    let mut f = Matrix3x2::zeros();
    for a in 0..3 {
        f += x[a].coords * t.grads[a].transpose();
    }
    f
}

fn green(f: &Matrix3x2<f64>) -> Mat2 {
    (f.transpose() * f - Mat2::identity()) * 0.5
}

fn soft(c: f64, s: f64) -> f64 {
    if c >= 0.0 {
        1.0
    } else {
        s
    }
}

fn psi(m: &Membrane, g: &Mat2) -> f64 {
    match m {
        Membrane::Voigt { c } => {
            let e = Vec3::new(g[(0, 0)], g[(1, 1)], 2.0 * g[(0, 1)]);
            0.5 * e.dot(&(c * e))
        }
        Membrane::Softened { mu, lambda, s } => {
            let (l, _) = sym_eig2(g);
            let tr = g[(0, 0)] + g[(1, 1)];
            mu * (soft(l.x, *s) * l.x * l.x + soft(l.y, *s) * l.y * l.y) + 0.5 * lambda * soft(tr, *s) * tr * tr
        }
    }
}

/// Full evaluation; `damp = Some((β_stretch, β_shear))` also returns the damping matrix.
pub fn membrane_eval(
    t: &TriRest,
    m: &Membrane,
    x: &[Pt3; 3],
    mode: HessianMode,
    damp: Option<(f64, f64)>,
) -> MembraneOut {
    let f = deformation_gradient(t, x);
    let g = green(&f);
    let f1: Vec3 = f.column(0).into_owned();
    let f2: Vec3 = f.column(1).into_owned();
    let b = &t.grads;
    let area = t.area;
    // Stress S and, per vertex, the three "strain-direction" vectors whose outer products make
    // the material Hessian: Voigt uses D_a rows; softened uses α_a, β_a, σ_a.
    let mut hmat = Mat9::zeros();
    let mut hdamp = damp.map(|_| Mat9::zeros());
    let (energy, s) = match m {
        Membrane::Voigt { c } => {
            let e = Vec3::new(g[(0, 0)], g[(1, 1)], 2.0 * g[(0, 1)]);
            let sv = c * e;
            let s = Mat2::new(sv.x, sv.z, sv.z, sv.y);
            // Rows r0, r1, r2 of D_a. With ℂ = stretch block (rows/cols 1–2) + shear entry c₂₂ +
            // couplings c₀₂, c₁₂: D_aᵀℂD_b = r0_a u_bᵀ + r1_a w_bᵀ + r2_a z_bᵀ + couplings, where
            // u_b = c₀₀r0_b + c₀₁r1_b, w_b = c₁₀r0_b + c₁₁r1_b, z_b = c₂₂r2_b. Only blocks a ≤ b
            // are formed (the matrix is symmetric); the damping blocks reuse the same parts.
            let rows: [[Vec3; 3]; 3] = std::array::from_fn(|a| {
                let (b1, b2) = (b[a].x, b[a].y);
                [b1 * f1, b2 * f2, b1 * f2 + b2 * f1]
            });
            let coupled = c[(0, 2)] != 0.0 || c[(1, 2)] != 0.0;
            let uwz: [[Vec3; 3]; 3] = std::array::from_fn(|a| {
                let [r0, r1, r2] = rows[a];
                [c[(0, 0)] * r0 + c[(0, 1)] * r1, c[(1, 0)] * r0 + c[(1, 1)] * r1, c[(2, 2)] * r2]
            });
            for a in 0..3 {
                for bb in a..3 {
                    let [r0, r1, r2] = rows[a];
                    let [u, w, z] = uwz[bb];
                    let st = area * (r0 * u.transpose() + r1 * w.transpose());
                    let sh = area * (r2 * z.transpose());
                    let mut blk = st + sh;
                    if coupled {
                        let [q0, q1, q2] = rows[bb];
                        blk += area
                            * (c[(0, 2)] * (r0 * q2.transpose() + r2 * q0.transpose())
                                + c[(1, 2)] * (r1 * q2.transpose() + r2 * q1.transpose()));
                    }
                    hmat.fixed_view_mut::<3, 3>(3 * a, 3 * bb).copy_from(&blk);
                    if bb != a {
                        hmat.fixed_view_mut::<3, 3>(3 * bb, 3 * a).copy_from(&blk.transpose());
                    }
                    if let (Some(hd), Some((bs, bsh))) = (hdamp.as_mut(), damp) {
                        let dblk = bs * st + bsh * sh;
                        hd.fixed_view_mut::<3, 3>(3 * a, 3 * bb).copy_from(&dblk);
                        if bb != a {
                            hd.fixed_view_mut::<3, 3>(3 * bb, 3 * a).copy_from(&dblk.transpose());
                        }
                    }
                }
            }
            (area * 0.5 * e.dot(&sv), s)
        }
        &Membrane::Softened { mu, lambda, s: sf } => {
            let (l, ev) = sym_eig2(&g);
            let (g1, g2) = (l.x, l.y);
            let (e1, e2): (Vec2, Vec2) = (ev.column(0).into_owned(), ev.column(1).into_owned());
            let tr = g1 + g2;
            let (c1, c2, ct) = (soft(g1, sf), soft(g2, sf), soft(tr, sf));
            let s = 2.0 * mu * (c1 * g1 * e1 * e1.transpose() + c2 * g2 * e2 * e2.transpose())
                + lambda * ct * tr * Mat2::identity();
            let delta = if (g1 - g2).abs() < 1e-12 { 2.0 * c1 } else { 2.0 * (c1 * g1 - c2 * g2) / (g1 - g2) };
            let fe1 = f * e1;
            let fe2 = f * e2;
            let al: [Vec3; 3] = std::array::from_fn(|a| e1.dot(&b[a]) * fe1);
            let be: [Vec3; 3] = std::array::from_fn(|a| e2.dot(&b[a]) * fe2);
            let si: [Vec3; 3] = std::array::from_fn(|a| 0.5 * (e1.dot(&b[a]) * fe2 + e2.dot(&b[a]) * fe1));
            for a in 0..3 {
                for bb in 0..3 {
                    let stretch = mu * (2.0 * c1 * al[a] * al[bb].transpose() + 2.0 * c2 * be[a] * be[bb].transpose())
                        + lambda * ct * (al[a] + be[a]) * (al[bb] + be[bb]).transpose();
                    let shear = mu * 2.0 * delta * si[a] * si[bb].transpose();
                    hmat.fixed_view_mut::<3, 3>(3 * a, 3 * bb).copy_from(&(area * (stretch + shear)));
                    if let (Some(hd), Some((bs, bsh))) = (hdamp.as_mut(), damp) {
                        hd.fixed_view_mut::<3, 3>(3 * a, 3 * bb).copy_from(&(area * (bs * stretch + bsh * shear)));
                    }
                }
            }
            let e = mu * (c1 * g1 * g1 + c2 * g2 * g2) + 0.5 * lambda * ct * tr * tr;
            (area * e, s)
        }
    };
    let mut grad = Vec9::zeros();
    let fs = f * s;
    for a in 0..3 {
        grad.fixed_rows_mut::<3>(3 * a).copy_from(&(area * fs * b[a]));
    }
    let s_geo = match mode {
        HessianMode::ProjectedCheap => psd_part2(&s),
        _ => s,
    };
    let mut hess = hmat;
    for a in 0..3 {
        for bb in 0..3 {
            let k = area * b[a].dot(&(s_geo * b[bb]));
            for r in 0..3 {
                hess[(3 * a + r, 3 * bb + r)] += k;
            }
        }
    }
    hess = (hess + hess.transpose()) * 0.5;
    if mode == HessianMode::ProjectedEigen {
        hess = project_psd(&hess);
    }
    let collapsed = f1.cross(&f2).norm_squared() == 0.0;
    MembraneOut { energy, grad, hess, damp: hdamp, collapsed }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kernels::testutil::TestRng;
    use nalgebra::SymmetricEigen;

    fn rest_tri(r: &mut TestRng) -> [Pt3; 3] {
        [
            Pt3::new(0.0, 0.0, 0.0),
            Pt3::new(r.range(0.8, 1.2), r.range(-0.2, 0.2), 0.0),
            Pt3::new(r.range(0.0, 0.8), r.range(0.6, 1.2), 0.0),
        ]
    }

    fn deform(x: &[Pt3; 3], r: &mut TestRng, amp: f64) -> [Pt3; 3] {
        x.map(|p| p + Vec3::new(r.range(-amp, amp), r.range(-amp, amp), r.range(-amp, amp)))
    }

    fn laws() -> Vec<Membrane> {
        vec![
            Membrane::isotropic(1000.0, 0.3),
            Membrane::orthotropic(2000.0, 500.0, 100.0, 300.0),
            Membrane::Softened { mu: 400.0, lambda: 200.0, s: 0.1 },
            Membrane::Softened { mu: 400.0, lambda: 0.0, s: 0.5 },
        ]
    }

    fn fd_check(t: &TriRest, m: &Membrane, x: &[Pt3; 3]) {
        let (_, g, h) = membrane_element(t, m, x, HessianMode::Full);
        let eps = 1e-6;
        let mut gfd = Vec9::zeros();
        let mut hfd = Mat9::zeros();
        for j in 0..9 {
            let (mut xp, mut xm) = (*x, *x);
            xp[j / 3][j % 3] += eps;
            xm[j / 3][j % 3] -= eps;
            gfd[j] = (membrane_energy(t, m, &xp) - membrane_energy(t, m, &xm)) / (2.0 * eps);
            let gp = membrane_element(t, m, &xp, HessianMode::Full).1;
            let gm = membrane_element(t, m, &xm, HessianMode::Full).1;
            hfd.set_column(j, &((gp - gm) / (2.0 * eps)));
        }
        // Central differences on O(1) geometry: error ~1e-10 relative; 1e-6 is the spec bound.
        assert!((g - gfd).amax() < 1e-6 * gfd.amax().max(1e-3), "grad {m:?} {}", (g - gfd).amax());
        assert!((h - hfd).amax() < 1e-6 * hfd.amax(), "hess {m:?} {}", (h - hfd).amax() / hfd.amax());
    }

    /// §7 tests 4 and 21: gradients and Hessians (Full mode) of every law vs finite differences,
    /// including configurations with principal strains of both signs.
    #[test]
    fn membrane_fd() {
        let mut r = TestRng::new(11);
        for law in laws() {
            for amp in [0.05, 0.2, 0.4] {
                for _ in 0..20 {
                    let x0 = rest_tri(&mut r);
                    let t = TriRest::new(&x0, None).unwrap();
                    let x = deform(&x0, &mut r, amp);
                    fd_check(&t, &law, &x);
                }
            }
            // Uniform compression (both principal strains negative) and stretch (both positive).
            let x0 = rest_tri(&mut r);
            let t = TriRest::new(&x0, None).unwrap();
            for s in [0.8, 1.3] {
                let x = x0.map(|p| Pt3::from(p.coords * s) + Vec3::new(0.01, -0.02, 0.003));
                let mut xr = x;
                xr[2].z += 0.05; // break exact equality of the principal strains
                fd_check(&t, &law, &xr);
            }
        }
    }

    /// §7 test 8: analytic energies of uniaxial and equibiaxial stretches, and the uniaxial gradient.
    #[test]
    fn membrane_analytic() {
        let (yt, nu) = (1000.0, 0.3);
        let (mu, la) = Membrane::lame(yt, nu);
        let m = Membrane::isotropic(yt, nu);
        let x0 = [Pt3::new(0.0, 0.0, 0.0), Pt3::new(1.0, 0.0, 0.0), Pt3::new(0.3, 0.9, 0.0)];
        let t = TriRest::new(&x0, None).unwrap();
        for s in [0.5, 0.9, 1.1, 2.0] {
            let g = 0.5 * (s * s - 1.0);
            let xu = x0.map(|p| Pt3::new(s * p.x, p.y, p.z));
            let (e, grad, _) = membrane_element(&t, &m, &xu, HessianMode::Full);
            let want = t.area * (mu + 0.5 * la) * g * g;
            assert!((e - want).abs() <= 1e-12 * want, "uniaxial {s}");
            let f = Matrix3x2::new(s, 0.0, 0.0, 1.0, 0.0, 0.0);
            let sm = Mat2::new(2.0 * mu * g + la * g, 0.0, 0.0, la * g);
            for a in 0..3 {
                let ga = t.area * f * sm * t.grads[a];
                assert!((grad.fixed_rows::<3>(3 * a) - ga).amax() <= 1e-12 * ga.amax().max(1e-300) + 1e-12);
            }
            let xb = x0.map(|p| Pt3::from(p.coords * s));
            let eb = membrane_energy(&t, &m, &xb);
            let wantb = 2.0 * t.area * (mu + la) * g * g;
            assert!((eb - wantb).abs() <= 1e-12 * wantb, "biaxial {s}");
        }
    }

    /// §7 test 21: isotropic ℂ through the orthotropic constructor and softening with s = 1 equal
    /// the isotropic kernel; a uniaxial pull along the warp axis stores ½k_u g² per area.
    #[test]
    fn law_equivalences() {
        let (yt, nu) = (1500.0, 0.25);
        let (mu, la) = Membrane::lame(yt, nu);
        let iso = Membrane::isotropic(yt, nu);
        let ortho = Membrane::orthotropic(2.0 * mu + la, 2.0 * mu + la, mu, la);
        let soft1 = Membrane::Softened { mu, lambda: la, s: 1.0 };
        let mut r = TestRng::new(5);
        for _ in 0..20 {
            let x0 = rest_tri(&mut r);
            let t = TriRest::new(&x0, None).unwrap();
            let x = deform(&x0, &mut r, 0.3);
            let (ea, ga, ha) = membrane_element(&t, &iso, &x, HessianMode::Full);
            let (eb, gb, hb) = membrane_element(&t, &ortho, &x, HessianMode::Full);
            assert!((ea - eb).abs() <= 1e-14 * ea.abs() && (ga - gb).amax() <= 1e-14 * ga.amax());
            assert!((ha - hb).amax() <= 1e-14 * ha.amax());
            let (ec, gc, hc) = membrane_element(&t, &soft1, &x, HessianMode::Full);
            assert!((ea - ec).abs() <= 1e-12 * ea.abs(), "{ea} {ec}");
            assert!((ga - gc).amax() <= 1e-12 * ga.amax());
            assert!((ha - hc).amax() <= 1e-12 * ha.amax());
        }
        // Warp axis along (1, 1, 0)/√2: pull by s along it.
        let ku = 3000.0;
        let m = Membrane::orthotropic(ku, 100.0, 50.0, 10.0);
        let x0 = [Pt3::new(0.0, 0.0, 0.0), Pt3::new(1.0, 0.2, 0.0), Pt3::new(0.1, 1.0, 0.0)];
        let w = Vec3::new(1.0, 1.0, 0.0).normalize();
        let t = TriRest::new(&x0, Some(w)).unwrap();
        let s = 1.2;
        let x = x0.map(|p| p + (s - 1.0) * w * p.coords.dot(&w));
        let g = 0.5 * (s * s - 1.0);
        let e = membrane_energy(&t, &m, &x);
        assert!((e - t.area * 0.5 * ku * g * g).abs() < 1e-12 * e);
        assert!(TriRest::new(&x0, Some(Vec3::z())).is_none());
    }

    /// §7 test 7 (membrane half): projected matrices are PSD; at rest nothing changes.
    #[test]
    fn membrane_psd_projection() {
        let mut r = TestRng::new(7);
        for law in laws() {
            for i in 0..250 {
                let x0 = rest_tri(&mut r);
                let t = TriRest::new(&x0, None).unwrap();
                let amp = [0.1, 0.3, 0.6][i % 3];
                let x = deform(&x0, &mut r, amp);
                for mode in [HessianMode::ProjectedCheap, HessianMode::ProjectedEigen] {
                    let (_, _, h) = membrane_element(&t, &law, &x, mode);
                    let ev = SymmetricEigen::new(h).eigenvalues;
                    assert!(ev.min() >= -1e-10 * h.amax(), "{mode:?} {law:?} {}", ev.min() / h.amax());
                }
            }
            let x0 = rest_tri(&mut r);
            let t = TriRest::new(&x0, None).unwrap();
            let (_, g, hf) = membrane_element(&t, &law, &x0, HessianMode::Full);
            assert!(g.amax() <= 1e-12 * law_scale(&law));
            for mode in [HessianMode::ProjectedCheap, HessianMode::ProjectedEigen] {
                let (e, _, h) = membrane_element(&t, &law, &x0, mode);
                assert!(e.abs() <= 1e-12 * law_scale(&law));
                assert!((h - hf).amax() <= 1e-12 * hf.amax());
            }
        }
    }

    fn law_scale(m: &Membrane) -> f64 {
        match m {
            Membrane::Voigt { c } => c.amax(),
            Membrane::Softened { mu, lambda, .. } => mu.max(*lambda),
        }
    }
}

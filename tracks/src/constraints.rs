//! The Petrov–Galerkin mass matrix and the constraint matrices C̄, C of eq. 5–8 (spec §3.2), the
//! constraint g(q) = C̄ q̄ − C q (eq. 2) and the free-DOF rank check.

use geom_core::linalg::{Csr, Triplets};
use geom_core::math::{Pt3, Vec3};
use geom_core::mesh::TriMesh;

use crate::error::{Result, TrackError};
use crate::testfn::{TestFunctions, TestKind};

/// Consistent P1 (Petrov–Galerkin) mass matrix 𝓜 of a mesh from its rest areas (spec §3.2):
/// per triangle (A/12)[[2,1,1],[1,2,1],[1,1,2]]. geom-core's `mass_p1` computes exactly this.
pub fn pg_mass_matrix(rest: &TriMesh) -> Csr {
    geom_core::mesh::mass_p1(&rest.faces, &rest.positions)
}

/// Linear averaged constraints g_i(q, t) = Σ_j C̄_ij q̄_j(t) − Σ_l C_il q_l (eq. 2, per coordinate),
/// rows normalised by eq. 8 and scaled to unit average (each row of C̄ and C sums to one).
#[derive(Clone, Debug, PartialEq)]
pub struct TrackingConstraints {
    /// C̄ (K × n̄).
    pub c_bar: Csr,
    /// C (K × n).
    pub c: Csr,
    /// Weak or pointwise.
    pub kind: TestKind,
}

fn row_sums(m: &Csr) -> Vec<f64> {
    (0..m.nrows).map(|i| m.row(i).1.iter().sum()).collect()
}

impl TrackingConstraints {
    /// C̄ = S̄𝓜̄, C = S𝓜 (weak) or C̄ = S̄, C = S (pointwise); eq. 8: C_i ← C_i·(ΣC̄_i)/(ΣC_i); then
    /// both rows divided by ΣC̄_i (unit average).
    ///
    /// Errors: shape mismatches (`TopologyMismatch`), a row with |ΣC̄_i| < 1e-12·A_total or
    /// |ΣC_i| = 0 (`ZeroIntegral(i)`).
    pub fn build(guide_rest: &TriMesh, tracked_rest: &TriMesh, tf: &TestFunctions) -> Result<Self> {
        let (nb, n) = (guide_rest.n_vertices(), tracked_rest.n_vertices());
        if tf.s_bar.ncols != nb {
            return Err(TrackError::TopologyMismatch {
                what: "S̄ columns vs guide vertices",
                expected: nb,
                got: tf.s_bar.ncols,
            });
        }
        if tf.s.ncols != n {
            return Err(TrackError::TopologyMismatch {
                what: "S columns vs tracked vertices",
                expected: n,
                got: tf.s.ncols,
            });
        }
        if tf.s.nrows != tf.s_bar.nrows {
            return Err(TrackError::TopologyMismatch {
                what: "test function count",
                expected: tf.s_bar.nrows,
                got: tf.s.nrows,
            });
        }
        let (mut c_bar, mut c, scale) = match tf.kind {
            TestKind::Weak => {
                let mb = pg_mass_matrix(guide_rest);
                let area: f64 = mb.val.iter().sum();
                (tf.s_bar.matmul(&mb), tf.s.matmul(&pg_mass_matrix(tracked_rest)), area)
            }
            TestKind::Pointwise => (tf.s_bar.clone(), tf.s.clone(), 1.0),
        };
        let sb = row_sums(&c_bar);
        let s = row_sums(&c);
        for i in 0..sb.len() {
            if !(sb[i].abs() >= 1e-12 * scale) || s[i] == 0.0 || !s[i].is_finite() {
                return Err(TrackError::ZeroIntegral(i));
            }
        }
        // Eq. 8 followed by the unit-average scaling: C_i ← C_i / ΣC_i, C̄_i ← C̄_i / ΣC̄_i.
        c.scale_rows(&s.iter().map(|x| 1.0 / x).collect::<Vec<_>>());
        c_bar.scale_rows(&sb.iter().map(|x| 1.0 / x).collect::<Vec<_>>());
        Ok(Self { c_bar, c, kind: tf.kind })
    }

    /// Number of vector constraints K.
    pub fn len(&self) -> usize {
        self.c.nrows
    }

    /// True for K = 0.
    pub fn is_empty(&self) -> bool {
        self.c.nrows == 0
    }

    /// g_i = (C̄ q̄)_i − (C q)_i (m), one 3-vector per constraint into `out` (length K).
    pub fn residual(&self, guide_q: &[Pt3], q: &[Pt3], out: &mut [Vec3]) {
        for (i, o) in out.iter_mut().enumerate() {
            let (cb, vb) = self.c_bar.row(i);
            let (cc, vc) = self.c.row(i);
            let mut g = Vec3::zeros();
            for (&j, &w) in cb.iter().zip(vb) {
                g += w * guide_q[j as usize].coords;
            }
            for (&l, &w) in cc.iter().zip(vc) {
                g -= w * q[l as usize].coords;
            }
            *o = g;
        }
    }

    /// max_i ‖g_i‖ (m).
    pub fn max_residual(&self, guide_q: &[Pt3], q: &[Pt3]) -> f64 {
        let mut g = vec![Vec3::zeros(); self.len()];
        self.residual(guide_q, q, &mut g);
        g.iter().map(|x| x.norm()).fold(0.0, f64::max)
    }

    /// Keeps only the listed rows (in order).
    pub fn select_rows(&self, rows: &[usize]) -> Self {
        let pick = |m: &Csr| {
            let mut t = Triplets::new(rows.len(), m.ncols);
            for (k, &i) in rows.iter().enumerate() {
                let (c, v) = m.row(i);
                for (&j, &w) in c.iter().zip(v) {
                    t.push(k as u32, j, w);
                }
            }
            Csr::from_triplets(&t)
        };
        Self { c_bar: pick(&self.c_bar), c: pick(&self.c), kind: self.kind }
    }

    /// Rows whose support has no free vertex (`free[l]` false for every column).
    pub fn pinned_only_rows(&self, free: &[bool]) -> Vec<usize> {
        (0..self.len()).filter(|&i| !self.c.row(i).0.iter().any(|&l| free[l as usize])).collect()
    }

    /// G = C_f diag(w) C_fᵀ (K × K, dense, row-major) over the columns with `w[l] > 0`
    /// (w = 1/m on free vertices, 0 on pinned ones).
    pub fn gram(&self, w: &[f64]) -> Vec<f64> {
        let k = self.len();
        let mut g = vec![0.0; k * k];
        let ct = self.c.transpose();
        for (l, &wl) in w.iter().enumerate() {
            if wl <= 0.0 {
                continue;
            }
            let (rows, vals) = ct.row(l);
            for (a, (&i, &ci)) in rows.iter().zip(vals).enumerate() {
                for (&j, &cj) in rows[a..].iter().zip(&vals[a..]) {
                    let v = ci * cj * wl;
                    g[i as usize * k + j as usize] += v;
                    if i != j {
                        g[j as usize * k + i as usize] += v;
                    }
                }
            }
        }
        g
    }

    /// Full-row-rank check of C_f (spec §3.2): incremental Cholesky of G = C_f W C_fᵀ; a pivot
    /// below 1e-10·G_ii marks row i dependent on earlier rows. Returns the dense factor
    /// (row-major lower L, G = LLᵀ) on success, `RankDeficient(rows)` listing every dependent row
    /// together with the earlier rows it depends on.
    pub fn check_rank(&self, w: &[f64]) -> Result<GramFactor> {
        let k = self.len();
        let g = self.gram(w);
        let mut l = vec![0.0; k * k];
        let mut bad: Vec<usize> = Vec::new();
        let mut ok = vec![true; k];
        for i in 0..k {
            for j in 0..=i {
                if !ok[j] {
                    continue;
                }
                let mut s = g[i * k + j];
                for p in 0..j {
                    s -= l[i * k + p] * l[j * k + p];
                }
                if i == j {
                    if !(s > 1e-10 * g[i * k + i]) || g[i * k + i] <= 0.0 {
                        ok[i] = false;
                        bad.push(i);
                        // Earlier rows it depends on: nonzero coefficients of G_II⁻¹ G_I,i.
                        let idx: Vec<usize> = (0..i).filter(|&p| ok[p]).collect();
                        let mut y: Vec<f64> = idx.iter().map(|&p| l[i * k + p]).collect();
                        // Back substitution with the factor of the independent rows.
                        for a in (0..idx.len()).rev() {
                            y[a] /= l[idx[a] * k + idx[a]];
                            for b in 0..a {
                                y[b] -= l[idx[a] * k + idx[b]] * y[a];
                            }
                        }
                        let ymax = y.iter().fold(0.0f64, |m, v| m.max(v.abs()));
                        for (a, &p) in idx.iter().enumerate() {
                            if y[a].abs() > 1e-8 * ymax.max(1e-300) {
                                bad.push(p);
                            }
                        }
                        for p in 0..k {
                            l[i * k + p] = 0.0;
                        }
                    } else {
                        l[i * k + i] = s.sqrt();
                    }
                } else {
                    l[i * k + j] = s / l[j * k + j];
                }
            }
        }
        if !bad.is_empty() {
            bad.sort_unstable();
            bad.dedup();
            return Err(TrackError::RankDeficient(bad));
        }
        Ok(GramFactor { k, l })
    }
}

/// Dense Cholesky factor of G = C_f W C_fᵀ (row-major lower triangle), for the initial projection
/// (§3.5) and the optional reprojection after collisions (§3.7).
#[derive(Clone, Debug, PartialEq)]
pub struct GramFactor {
    k: usize,
    l: Vec<f64>,
}

impl GramFactor {
    /// Solves G x = b in place (b length K).
    pub fn solve(&self, b: &mut [f64]) {
        let (k, l) = (self.k, &self.l);
        for i in 0..k {
            let mut s = b[i];
            for p in 0..i {
                s -= l[i * k + p] * b[p];
            }
            b[i] = s / l[i * k + i];
        }
        for i in (0..k).rev() {
            let mut s = b[i];
            for p in i + 1..k {
                s -= l[p * k + i] * b[p];
            }
            b[i] = s / l[i * k + i];
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::guide::{GuideAnimation, TimeInterp};
    use crate::testfn::{build_test_functions, RegionSel, TestFunctionSpec};
    use geom_core::math::{Mat3, UnitQuat};
    use geom_core::mesh::subdivide_linear;
    use geom_core::procedural::{box_surface, grid, Diagonals, GridSpec};
    use geom_core::rng::Rng;

    fn tri() -> TriMesh {
        TriMesh::new(vec![Pt3::new(0.0, 0.0, 0.0), Pt3::new(2.0, 0.0, 0.0), Pt3::new(0.3, 1.5, 0.4)], vec![[0, 1, 2]])
            .expect("valid triangle")
    }

    /// §7.1: single triangle 𝓜 = (A/12)[[2,1,1],[1,2,1],[1,1,2]] to 1e-15 relative.
    #[test]
    fn pg_mass_triangle() {
        let m = tri();
        let p = &m.positions;
        let a = 0.5 * (p[1] - p[0]).cross(&(p[2] - p[0])).norm();
        let mm = pg_mass_matrix(&m);
        for i in 0..3 {
            for j in 0..3 {
                let e = a / 12.0 * if i == j { 2.0 } else { 1.0 };
                assert!((mm.get(i, j) - e).abs() <= 1e-15 * e);
            }
        }
    }

    /// §7.2: symmetric, row sums A_j/3, total area, 1ᵀ𝓜x = ∫x, xᵀ𝓜x = ∫x² (exact per-triangle
    /// quadrature: ∫x² = A/6 (Σx_i² + Σ_{i<j} x_i x_j)), 1e-12 relative.
    #[test]
    fn pg_mass_properties() {
        let mut m = grid(&GridSpec { quads: [5, 4], ..GridSpec::default() }).expect("grid");
        let mut rng = Rng::new(3);
        for p in m.positions.iter_mut() {
            p.z = rng.range(-0.2, 0.2);
            p.x += rng.range(-0.02, 0.02);
        }
        let mm = pg_mass_matrix(&m);
        assert!(mm.is_symmetric(0.0));
        let areas = geom_core::mesh::face_areas(&m.faces, &m.positions);
        let total: f64 = areas.iter().sum();
        let mut aj = vec![0.0; m.n_vertices()];
        let (mut ix, mut ix2) = (0.0, 0.0);
        for (f, a) in m.faces.iter().zip(&areas) {
            let x = f.map(|v| m.positions[v as usize].x);
            for &v in f {
                aj[v as usize] += a;
            }
            ix += a * (x[0] + x[1] + x[2]) / 3.0;
            ix2 += a / 6.0 * (x[0] * x[0] + x[1] * x[1] + x[2] * x[2] + x[0] * x[1] + x[1] * x[2] + x[0] * x[2]);
        }
        let rs = row_sums(&mm);
        for (r, a) in rs.iter().zip(&aj) {
            assert!((r - a / 3.0).abs() <= 1e-12 * a);
        }
        assert!((mm.val.iter().sum::<f64>() - total).abs() <= 1e-12 * total);
        let x: Vec<f64> = m.positions.iter().map(|p| p.x).collect();
        let mut mx = vec![0.0; x.len()];
        mm.mul_vec(&x, &mut mx);
        assert!((mx.iter().sum::<f64>() - ix).abs() <= 1e-12 * ix.abs().max(1e-3));
        let xmx: f64 = x.iter().zip(&mx).map(|(a, b)| a * b).sum();
        assert!((xmx - ix2).abs() <= 1e-12 * ix2);
    }

    fn norm_fro(m: &Csr) -> f64 {
        m.val.iter().map(|v| v * v).sum::<f64>().sqrt()
    }

    fn static_guide(rest: &TriMesh) -> GuideAnimation {
        GuideAnimation::from_frames(rest.clone(), vec![rest.positions.clone()], 30.0, TimeInterp::CatmullRom)
            .expect("valid")
    }

    /// §7.3: for box (1–4 levels) and flag (3): ‖Pᵀ𝓜P − 𝓜̄‖ ≤ 1e-12‖𝓜̄‖, ‖CP − C̄‖ ≤ 1e-12 and
    /// g(Pq̄) = 0 for random q̄ (1e-12·scale).
    #[test]
    fn galerkin_subdivision() {
        let cube = box_surface(Pt3::new(-0.5, 0.0, -0.5), Pt3::new(0.5, 1.0, 0.5), [1, 1, 1], Diagonals::Alternating)
            .expect("box");
        let flag = grid(&GridSpec { quads: [6, 4], size: [1.2, 0.8], ..GridSpec::default() }).expect("grid");
        for (coarse, levels) in [(&cube, 1), (&cube, 2), (&cube, 4), (&flag, 3)] {
            let (fine, p) = subdivide_linear(coarse, levels);
            let mb = pg_mass_matrix(coarse);
            let mf = pg_mass_matrix(&fine);
            let ptmp = p.transpose().matmul(&mf).matmul(&p);
            let diff = ptmp.add(&mb, 1.0, -1.0);
            assert!(norm_fro(&diff) <= 1e-12 * norm_fro(&mb), "PᵀMP = M̄ at level {levels}");
            let g = static_guide(coarse);
            let tf = build_test_functions(&TestFunctionSpec::SubdivisionBasis, &g, &fine, Some(&p)).expect("tf");
            let c = TrackingConstraints::build(coarse, &fine, &tf).expect("constraints");
            let cp = c.c.matmul(&p).add(&c.c_bar, 1.0, -1.0);
            assert!(cp.max_abs() <= 1e-12);
            let mut rng = Rng::new(levels as u64);
            let qb: Vec<Pt3> = (0..coarse.n_vertices())
                .map(|_| Pt3::new(rng.range(-1.0, 1.0), rng.range(-1.0, 1.0), rng.range(-1.0, 1.0)))
                .collect();
            let mut q = vec![Pt3::origin(); fine.n_vertices()];
            for d in 0..3 {
                let x: Vec<f64> = qb.iter().map(|p| p[d]).collect();
                let mut y = vec![0.0; q.len()];
                p.mul_vec(&x, &mut y);
                q.iter_mut().zip(&y).for_each(|(a, b)| a[d] = *b);
            }
            assert!(c.max_residual(&qb, &q) <= 1e-12);
        }
    }

    /// §7.4: after eq. 8 the rows of C and C̄ have equal sums (1e-14); rigid motions commute with
    /// g: g(Rq̄ + t, Rq + t) = R g(q̄, q) (1e-12), also for rest shapes of different area.
    #[test]
    fn normalisation_invariance() {
        let guide = grid(&GridSpec { quads: [6, 4], size: [1.2, 0.8], ..GridSpec::default() }).expect("grid");
        let (mut fine, p) = subdivide_linear(&guide, 2);
        // Crinkle the tracked rest shape: a different area than the guide's.
        let mut rng = Rng::new(9);
        for q in fine.positions.iter_mut() {
            q.z += rng.range(-0.02, 0.02);
        }
        let g = static_guide(&guide);
        for spec in [
            TestFunctionSpec::SubdivisionBasis,
            TestFunctionSpec::Painted {
                guide: vec![RegionSel::RestBox { min: (-1.0, -1.0, -1.0), max: (0.0, 0.0, 1.0) }],
                tracked: vec![RegionSel::RestBox { min: (-1.0, -1.0, -1.0), max: (0.0, 0.0, 1.0) }],
            },
        ] {
            let tf = build_test_functions(&spec, &g, &fine, Some(&p)).expect("tf");
            let c = TrackingConstraints::build(&guide, &fine, &tf).expect("constraints");
            for (a, b) in row_sums(&c.c).iter().zip(row_sums(&c.c_bar)) {
                assert!((a - b).abs() <= 1e-14);
            }
            let qb: Vec<Pt3> = guide.positions.iter().map(|x| x + Vec3::new(0.0, 0.1 * x.x * x.x, 0.0)).collect();
            let q: Vec<Pt3> = fine.positions.iter().map(|x| x + Vec3::new(0.05 * x.y, 0.0, 0.0)).collect();
            let mut g0 = vec![Vec3::zeros(); c.len()];
            c.residual(&qb, &q, &mut g0);
            for s in 0..5 {
                let r = UnitQuat::from_scaled_axis(Vec3::new(rng.range(-2.0, 2.0), rng.range(-2.0, 2.0), s as f64));
                let t = Vec3::new(rng.range(-5.0, 5.0), rng.range(-5.0, 5.0), rng.range(-5.0, 5.0));
                let rm: Mat3 = r.to_rotation_matrix().into_inner();
                let tr = |v: &[Pt3]| -> Vec<Pt3> { v.iter().map(|x| Pt3::from(rm * x.coords + t)).collect() };
                let mut g1 = vec![Vec3::zeros(); c.len()];
                c.residual(&tr(&qb), &tr(&q), &mut g1);
                for (a, b) in g1.iter().zip(&g0) {
                    assert!((a - rm * b).norm() <= 1e-12);
                }
            }
        }
    }

    /// §7.6: for painted quadrants the tracked constant equals ∫φ̄_i / ∫(tracked hat sum) before
    /// the unit-average scaling, i.e. C_il/C̄-row-sum = (S𝓜)_il / Σ_l (S𝓜)_il (1e-12).
    #[test]
    fn painted_constant() {
        let guide = grid(&GridSpec { quads: [6, 4], size: [1.2, 0.8], ..GridSpec::default() }).expect("grid");
        let (fine, p) = subdivide_linear(&guide, 3);
        let g = static_guide(&guide);
        let q = |u: (f64, f64), v: (f64, f64)| RegionSel::Uv { u, v };
        let regions = vec![
            q((0.0, 0.6), (0.0, 0.4)),
            q((0.6 + 1e-9, 1.2), (0.0, 0.4)),
            q((0.0, 0.6), (0.4 + 1e-9, 0.8)),
            q((0.6 + 1e-9, 1.2), (0.4 + 1e-9, 0.8)),
        ];
        let spec = TestFunctionSpec::Painted { guide: regions.clone(), tracked: regions };
        let tf = build_test_functions(&spec, &g, &fine, Some(&p)).expect("tf");
        let c = TrackingConstraints::build(&guide, &fine, &tf).expect("constraints");
        let mf = pg_mass_matrix(&fine);
        let mb = pg_mass_matrix(&guide);
        let sm = tf.s.matmul(&mf);
        let sbm = tf.s_bar.matmul(&mb);
        for i in 0..4 {
            let ib: f64 = sbm.row(i).1.iter().sum();
            let it: f64 = sm.row(i).1.iter().sum();
            // Tracked constant c_i = ∫φ̄_i / ∫(hat sum of the region); the normalised row is
            // c_i (S𝓜)_i / ∫φ̄_i = (S𝓜)_i / it.
            let ci = ib / it;
            for (&l, &w) in c.c.row(i).0.iter().zip(c.c.row(i).1) {
                assert!((w * ib - ci * sm.get(i, l as usize)).abs() <= 1e-12 * ib);
            }
        }
    }

    /// §7.15 (first part): a duplicated region is reported with both rows.
    #[test]
    fn duplicated_region_is_rank_deficient() {
        let guide = grid(&GridSpec { quads: [4, 4], ..GridSpec::default() }).expect("grid");
        let g = static_guide(&guide);
        let r = RegionSel::RestBox { min: (-1.0, -1.0, -1.0), max: (0.0, 1.0, 1.0) };
        let r2 = RegionSel::RestBox { min: (0.01, -1.0, -1.0), max: (1.0, 1.0, 1.0) };
        let spec = TestFunctionSpec::Painted {
            guide: vec![r.clone(), r2.clone(), r.clone()],
            tracked: vec![r.clone(), r2, r],
        };
        let tf = build_test_functions(&spec, &g, &guide, None).expect("tf");
        let c = TrackingConstraints::build(&guide, &guide, &tf).expect("build");
        let w = vec![1.0; guide.n_vertices()];
        match c.check_rank(&w) {
            Err(TrackError::RankDeficient(rows)) => assert_eq!(rows, vec![0, 2]),
            other => panic!("expected RankDeficient, got {other:?}"),
        }
    }
}

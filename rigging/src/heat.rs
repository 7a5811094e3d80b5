//! Skin attachment by bone heat (rigging spec §3.11, paper §4): each bone is a heat source;
//! solve (L + M H) w_i = M H p_i on the surface for every bone, with L the cotangent stiffness
//! (PSD), M the mixed-Voronoi lumped mass, H_jj = k_j c / d_j² for the k_j nearest *visible*
//! bones of vertex j (p_ij = 1/k_j for those; d_j is the distance to the nearest visible bone,
//! ties within 1e-4 relative, as in the public Pinocchio release — a vertex whose nearest bone
//! is hidden takes heat from the nearest bone it can see). One sparse Cholesky factorisation
//! (`geom_core::linalg::SparseLlt`), one multi-RHS back-substitution for all bones.
//! Visibility: the segment from the bone point to the vertex must not cross the surface
//! (`geom_core::collide::MeshQuery::ray_cast`) and (cone test) must leave the vertex within 60°
//! of its normal.
//!
//! Summing the systems gives (L + MH) Σ_i w_i = MH·1, so Σ_i w_i = 1 exactly (up to the solve):
//! partition of unity holds before post-processing.

use geom_core::anim::skin::SkinWeights;
use geom_core::collide::MeshQuery;
use geom_core::linalg::{Csr, Ordering, SparseLlt};
use geom_core::math::{Pt3, Vec3};
use geom_core::mesh::{cotan_stiffness, mass_voronoi, vertex_normals, NormalWeight, TriMesh};
use geom_core::query::closest_point_segment;

use crate::error::{Result, RigError};
use crate::options::RigOptions;

/// Diagnostics of a bone-heat solve.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct HeatReport {
    /// Smallest raw weight (before clamping).
    pub min_raw: f64,
    /// Raw weights below −1e-6.
    pub negative_count: usize,
    /// max_j |Σ_i w_ij − 1| before post-processing.
    pub partition_err_raw: f64,
    /// max over bones of ‖(L + MH) w_i − MH p_i‖ / ‖MH p_i‖.
    pub residual_max: f64,
    /// Vertices with no visible bone (heat by diffusion only).
    pub invisible_vertices: usize,
    /// Vertices that got the nearest-bone fallback (a component with no visible bone).
    pub fallback_vertices: usize,
    /// Largest weight mass removed by pruning.
    pub pruned_mass_max: f64,
}

/// Bone-heat weights for `mesh` (normalized coordinates) and bones given as segments
/// `[a, b]`. Returns per-vertex sparse weights (joint index = bone index), the raw dense weights
/// (n × bones, column-major) and diagnostics.
pub fn bone_heat(mesh: &TriMesh, bones: &[[Pt3; 2]], o: &RigOptions) -> Result<(SkinWeights, HeatReport)> {
    let (w, rep) = bone_heat_raw(mesh, bones, o)?;
    let n = mesh.n_vertices();
    let nb = bones.len();
    let mut rows = Vec::with_capacity(n);
    let mut pruned_max: f64 = 0.0;
    for j in 0..n {
        let mut row: Vec<(u16, f64)> = (0..nb)
            .map(|b| (b as u16, w[b * n + j].clamp(0.0, 1.0)))
            .filter(|&(_, x)| x >= o.weight_prune && x > 0.0)
            .collect();
        let total: f64 = (0..nb).map(|b| w[b * n + j].clamp(0.0, 1.0)).sum();
        row.sort_by(|a, b| b.1.total_cmp(&a.1).then(a.0.cmp(&b.0)));
        if o.max_influences > 0 {
            row.truncate(o.max_influences);
        }
        if row.is_empty() {
            // All weights clamped away: attach to the bone with the largest raw weight.
            let b = (0..nb).max_by(|&a, &c| w[a * n + j].total_cmp(&w[c * n + j])).expect("at least one bone");
            row.push((b as u16, 1.0));
        }
        let kept: f64 = row.iter().map(|r| r.1).sum();
        pruned_max = pruned_max.max(total - kept);
        rows.push(row.into_iter().map(|(b, x)| (b, (x / kept) as f32)).collect::<Vec<_>>());
    }
    let sw = SkinWeights::from_rows(&rows)?;
    Ok((sw, HeatReport { pruned_mass_max: pruned_max, ..rep }))
}

/// The raw solve: weights `w[b * n + j]` for bone b at vertex j, before any clamping.
pub fn bone_heat_raw(mesh: &TriMesh, bones: &[[Pt3; 2]], o: &RigOptions) -> Result<(Vec<f64>, HeatReport)> {
    let n = mesh.n_vertices();
    let nb = bones.len();
    if nb == 0 {
        return Err(RigError::InvalidParameter("bone heat needs at least one bone".into()));
    }
    let pos = &mesh.positions;
    let q = if o.visibility_test { Some(MeshQuery::new(mesh)?) } else { None };
    let normals = vertex_normals(&mesh.faces, pos, NormalWeight::Area);
    let mut hdiag = vec![0.0; n];
    let mut pcols = vec![0.0; n * nb];
    let mut rep = HeatReport::default();
    let mut dist = vec![0.0; nb];
    let mut closest = vec![Pt3::origin(); nb];
    let visible = |x: &Pt3, c: &Pt3, nrm: &Vec3| -> bool {
        let d = x - c;
        let len = d.norm();
        if len <= 1e-12 {
            return true;
        }
        if let Some(cc) = o.cone_cos {
            if d.dot(nrm) / len < cc {
                return false;
            }
        }
        match &q {
            Some(q) => {
                let max_t = 1.0 - o.vis_margin / len;
                max_t <= 0.0 || q.ray_cast(c, &d, max_t).is_none()
            }
            None => true,
        }
    };
    let mut near_only = vec![(0usize, 0.0f64); n];
    for j in 0..n {
        let x = pos[j];
        for (b, s) in bones.iter().enumerate() {
            let (_, c) = closest_point_segment(&x, &s[0], &s[1]);
            dist[b] = (x - c).norm();
            closest[b] = c;
        }
        let dmin = dist.iter().copied().fold(f64::INFINITY, f64::min);
        let best = (0..nb).find(|&b| dist[b] == dmin).expect("at least one bone");
        near_only[j] = (best, dmin);
        // The nearest *visible* bone (and visible ties within 1e-4 relative): bones are tried in
        // order of distance, so usually one or two visibility tests suffice.
        let mut order: Vec<usize> = (0..nb).collect();
        order.sort_by(|&a, &b| dist[a].total_cmp(&dist[b]).then(a.cmp(&b)));
        let mut vis: Vec<usize> = Vec::new();
        let mut dvis = f64::INFINITY;
        for &b in &order {
            if dist[b] > dvis * (1.0 + 1e-4) {
                break;
            }
            if visible(&x, &closest[b], &normals[j]) {
                if vis.is_empty() {
                    dvis = dist[b];
                }
                vis.push(b);
            }
        }
        if vis.is_empty() {
            rep.invisible_vertices += 1;
            continue;
        }
        let k = vis.len() as f64;
        hdiag[j] = k * o.heat_c / dvis.max(o.d_floor).powi(2);
        for &b in &vis {
            pcols[b * n + j] = 1.0 / k;
        }
    }
    // Components with no heat source: nearest bone ignoring visibility (spec §8).
    let (nc, comp) = mesh.topology().face_components();
    let mut vcomp = vec![0u32; n];
    for (f, t) in mesh.faces.iter().enumerate() {
        for &v in t {
            vcomp[v as usize] = comp[f];
        }
    }
    for c in 0..nc as u32 {
        if !(0..n).any(|j| vcomp[j] == c && hdiag[j] > 0.0) {
            for j in (0..n).filter(|&j| vcomp[j] == c) {
                let (b, d) = near_only[j];
                hdiag[j] = o.heat_c / d.max(o.d_floor).powi(2);
                pcols[b * n + j] = 1.0;
                rep.fallback_vertices += 1;
            }
        }
    }
    let l = cotan_stiffness(&mesh.faces, pos, None);
    let m = mass_voronoi(&mesh.faces, pos);
    if l.val.iter().any(|x| !x.is_finite()) || m.iter().any(|x| !x.is_finite()) || hdiag.iter().any(|x| !x.is_finite())
    {
        return Err(RigError::NonFinite("bone heat operators"));
    }
    let mh: Vec<f64> = (0..n).map(|j| m[j] * hdiag[j]).collect();
    let a = l.add(&Csr::diag(&mh), 1.0, 1.0);
    let mut llt = SparseLlt::analyze(&a.to_csc_lower(), Ordering::Amd)?;
    llt.factor(&a.to_csc_lower()).map_err(|e| RigError::SolverFailed(e.to_string()))?;
    let mut x = geom_core::faer::Mat::<f64>::zeros(n, nb);
    for b in 0..nb {
        for j in 0..n {
            x[(j, b)] = mh[j] * pcols[b * n + j];
        }
    }
    llt.solve_many_in_place(&mut x)?;
    let mut w = vec![0.0; n * nb];
    let mut ax = vec![0.0; n];
    for b in 0..nb {
        let col: Vec<f64> = (0..n).map(|j| x[(j, b)]).collect();
        a.mul_vec(&col, &mut ax);
        let mut num = 0.0;
        let mut den = 0.0;
        for j in 0..n {
            let rhs = mh[j] * pcols[b * n + j];
            num += (ax[j] - rhs).powi(2);
            den += rhs * rhs;
        }
        if den > 0.0 {
            rep.residual_max = rep.residual_max.max((num / den).sqrt());
        }
        w[b * n..(b + 1) * n].copy_from_slice(&col);
    }
    rep.min_raw = w.iter().copied().fold(f64::INFINITY, f64::min);
    rep.negative_count = w.iter().filter(|&&x| x < -1e-6).count();
    rep.partition_err_raw =
        (0..n).map(|j| ((0..nb).map(|b| w[b * n + j]).sum::<f64>() - 1.0).abs()).fold(0.0, f64::max);
    if w.iter().any(|x| !x.is_finite()) {
        return Err(RigError::NonFinite("bone heat weights"));
    }
    Ok((w, rep))
}

#[cfg(test)]
mod tests {
    use super::*;
    use geom_core::iso::{polygonize, sdf, PolygonizeOptions};
    use geom_core::spatial::Aabb;

    fn cylinder(r: f64) -> TriMesh {
        let a = Pt3::new(0.1, 0.5, 0.5);
        let b = Pt3::new(0.9, 0.5, 0.5);
        let f = |p: &Pt3| sdf::capsule(p, &a, &b, r);
        let o = PolygonizeOptions { bounds: Aabb::new(Pt3::new(0.0, 0.3, 0.3), Pt3::new(1.0, 0.7, 0.7)), h: r / 5.0 };
        polygonize(&f, &o).expect("capsule meshes")
    }

    #[test]
    fn partition_of_unity_residual_and_single_bone() {
        let m = cylinder(0.06);
        let bones =
            [[Pt3::new(0.1, 0.5, 0.5), Pt3::new(0.5, 0.5, 0.5)], [Pt3::new(0.5, 0.5, 0.5), Pt3::new(0.9, 0.5, 0.5)]];
        let o = RigOptions::default();
        let (w, rep) = bone_heat_raw(&m, &bones, &o).expect("solves");
        assert!(rep.partition_err_raw <= 1e-8, "{}", rep.partition_err_raw);
        assert!(rep.residual_max <= 1e-10, "{}", rep.residual_max);
        assert!(rep.min_raw >= -1e-2);
        let (sw, _) = bone_heat(&m, &bones, &o).expect("solves");
        for v in 0..sw.len() {
            let (_, ws) = sw.row(v);
            assert!((ws.iter().map(|&x| x as f64).sum::<f64>() - 1.0).abs() <= 1e-6);
            assert!(ws.iter().all(|&x| x >= 0.0));
        }
        // Far left vertices belong to bone 0, far right to bone 1.
        let n = m.n_vertices();
        for j in 0..n {
            if m.positions[j].x < 0.25 {
                assert!(w[j] > 0.99, "left vertex weight {}", w[j]);
            }
        }
        let one = [[Pt3::new(0.1, 0.5, 0.5), Pt3::new(0.9, 0.5, 0.5)]];
        let (sw, _) = bone_heat(&m, &one, &o).expect("solves");
        assert!(sw.w.iter().all(|&x| x == 1.0));
    }

    /// Transition width ∝ distance to the surface (spec §7.4 g): the child-weight 0.1 → 0.9
    /// axial span doubles with the radius.
    #[test]
    fn transition_width_scales_with_radius() {
        let width = |r: f64| {
            let m = cylinder(r);
            let bones = [
                [Pt3::new(0.1, 0.5, 0.5), Pt3::new(0.5, 0.5, 0.5)],
                [Pt3::new(0.5, 0.5, 0.5), Pt3::new(0.9, 0.5, 0.5)],
            ];
            let (w, _) = bone_heat_raw(&m, &bones, &RigOptions::default()).expect("solves");
            let n = m.n_vertices();
            // Surface vertices away from the caps, sorted by x: first x with w1 ≥ 0.1 and ≥ 0.9.
            let mut pts: Vec<(f64, f64)> = (0..n)
                .filter(|&j| m.positions[j].x > 0.2 && m.positions[j].x < 0.8)
                .map(|j| (m.positions[j].x, w[n + j]))
                .collect();
            pts.sort_by(|a, b| a.0.total_cmp(&b.0));
            let x10 = pts.iter().find(|p| p.1 >= 0.1).expect("crosses 0.1").0;
            let x90 = pts.iter().find(|p| p.1 >= 0.9).expect("crosses 0.9").0;
            x90 - x10
        };
        let ratio = width(0.08) / width(0.04);
        assert!((ratio - 2.0).abs() <= 0.3, "ratio {ratio}");
    }
}

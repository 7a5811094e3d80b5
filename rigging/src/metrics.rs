//! The figures the rigging experiments report, as library calls: weight sanity of a rig
//! (partition of unity, non-negativity, rigid motion; spec §7.4 d, e, l), the width of the
//! weight transition across a joint (spec §7.4 g, paper Fig. 8), and how much arm weight torso
//! vertices carry (bone heat against nearest-bone weights; spec §6.7).
//!
//! Embedding correctness against ground truth is [`crate::eval::score`] (spec §7.5).
//!
//! Every maximum here propagates NaN (`geom_core::stats`): a NaN weight or position makes the
//! figure NaN, never 0.

use geom_core::anim::skin::{lbs, skinning_transforms, SkinWeights};
use geom_core::math::{Iso3, Pt3, UnitQuat};
use geom_core::query::closest_point_segment;
use geom_core::stats;

use crate::error::Result;
use crate::rig::Rig;
use crate::template::SkeletonTemplate;

/// Weight sanity of one rig.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WeightChecks {
    /// Largest |Σ_j w_vj − 1| over the vertices (spec §7.4 d: ≤ 1e-6 after post-processing).
    pub sum_max_err: f64,
    /// Smallest stored weight (spec §7.4 e: ≥ 0 after clamping).
    pub min_weight: f64,
    /// Stored weights below zero (count).
    pub negative: usize,
    /// Largest vertex error under one rigid transform of every skinning joint, divided by the
    /// character's height (spec §7.4 l: ≤ 1e-6).
    pub rigid_err_rel: f64,
}

/// The rigid transform of the rigid-motion check: translation (0.3, −0.2, 0.7), rotation with
/// Euler angles (0.4, −0.9, 0.25) rad.
pub fn rigid_test_transform() -> Iso3 {
    Iso3::from_parts(nalgebra::Translation3::new(0.3, -0.2, 0.7), UnitQuat::from_euler_angles(0.4, -0.9, 0.25))
}

/// Largest |Σ w − 1| over rows, the smallest weight, the number of negative weights and the
/// rigid-motion error over the height: posing every skinning joint with the same rigid transform
/// must move the mesh rigidly.
pub fn weight_checks(rig: &Rig) -> Result<WeightChecks> {
    let w = &rig.weights;
    let mut sum_err: f64 = 0.0;
    for v in 0..w.len() {
        let (_, ws) = w.row(v);
        sum_err = stats::nan_max(sum_err, (ws.iter().map(|&x| x as f64).sum::<f64>() - 1.0).abs());
    }
    let all: Vec<f64> = w.w.iter().map(|&x| x as f64).collect();
    let sk = rig.skin_skeleton()?;
    let t = rigid_test_transform();
    let posed: Vec<Iso3> = sk.rest_world.iter().map(|r| t * r).collect();
    let tr = skinning_transforms(&sk, &posed);
    let mut out = vec![Pt3::origin(); rig.mesh.n_vertices()];
    lbs(&rig.mesh.positions, w, &tr, &mut out);
    let h = rig.mesh.aabb().size().y;
    let errs: Vec<f64> = rig.mesh.positions.iter().zip(&out).map(|(x, y)| (t * x - y).norm()).collect();
    Ok(WeightChecks {
        sum_max_err: sum_err,
        min_weight: stats::min(&all),
        negative: negative_weights(w),
        rigid_err_rel: stats::max(&errs) / h,
    })
}

/// Number of stored weights below zero.
pub fn negative_weights(w: &SkinWeights) -> usize {
    w.w.iter().filter(|&&x| x < 0.0).count()
}

/// Axial width of a weight transition (spec §7.4 g): from `(x, w)` samples of the child-bone
/// weight along an axis, the distance from the first sample (in increasing `x`) whose weight
/// reaches `lo` to the first that reaches `hi`. `None` when either level is never reached.
pub fn transition_width(samples: &[(f64, f64)], lo: f64, hi: f64) -> Option<f64> {
    let mut pts = samples.to_vec();
    pts.sort_by(|x, y| x.0.total_cmp(&y.0));
    let a = pts.iter().find(|p| p.1 >= lo)?.0;
    let b = pts.iter().find(|p| p.1 >= hi)?.0;
    Some(b - a)
}

/// Arm weight on torso vertices (spec §6.7): for every vertex whose nearest ground-truth bone is
/// a spine bone (`back`, `hips`), its total bone-heat weight on arm bones (bones ending at an
/// elbow or a hand) and its nearest-bone ("proximity") weight on them (1 if the nearest embedded
/// bone is an arm bone, else 0).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TorsoArmWeights {
    /// Torso vertices (count).
    pub torso_vertices: usize,
    /// Torso vertices with more than half their bone-heat weight on arm bones.
    pub heat_over_half: usize,
    /// Torso vertices whose nearest embedded bone is an arm bone.
    pub proximity_over_half: usize,
    /// Per torso vertex: (vertex, bone-heat arm weight, proximity arm weight).
    pub rows: Vec<(usize, f64, f64)>,
}

/// [`TorsoArmWeights`] of a human rig: `positions` and `weights` of the rigged mesh (skinning
/// joint `b + 1` = bone `b`, as in [`Rig::weights`]), `truth` and `joints` in template order.
pub fn torso_arm_weights(
    sk: &SkeletonTemplate,
    positions: &[Pt3],
    weights: &SkinWeights,
    truth: &[Pt3],
    joints: &[Pt3],
) -> TorsoArmWeights {
    let bones = sk.bones();
    let gt: Vec<[Pt3; 2]> = bones.iter().map(|&(a, b)| [truth[a], truth[b]]).collect();
    let emb: Vec<[Pt3; 2]> = bones.iter().map(|&(a, b)| [joints[a], joints[b]]).collect();
    let is_arm = |b: usize| {
        let name = &sk.joints[bones[b].1].name;
        name.contains("elbow") || name.contains("hand")
    };
    let is_spine = |b: usize| matches!(sk.joints[bones[b].1].name.as_str(), "back" | "hips");
    let nearest = |segs: &[[Pt3; 2]], x: &Pt3| {
        (0..segs.len())
            .map(|b| (b, (closest_point_segment(x, &segs[b][0], &segs[b][1]).1 - x).norm()))
            .min_by(|a, c| a.1.total_cmp(&c.1))
            .map(|(b, _)| b)
    };
    let mut out = TorsoArmWeights::default();
    for (v, x) in positions.iter().enumerate() {
        if !nearest(&gt, x).is_some_and(is_spine) {
            continue;
        }
        out.torso_vertices += 1;
        let (js, ws) = weights.row(v);
        let heat_arm: f64 =
            js.iter().zip(ws).filter(|(j, _)| **j > 0 && is_arm(**j as usize - 1)).map(|(_, &w)| w as f64).sum();
        let prox_arm = if nearest(&emb, x).is_some_and(is_arm) { 1.0 } else { 0.0 };
        out.heat_over_half += (heat_arm > 0.5) as usize;
        out.proximity_over_half += (prox_arm > 0.5) as usize;
        out.rows.push((v, heat_arm, prox_arm));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn transition_width_finds_both_levels_or_none() {
        let s = [(0.3, 0.5), (0.1, 0.0), (0.2, 0.1), (0.4, 0.95)];
        assert!((transition_width(&s, 0.1, 0.9).unwrap() - 0.2).abs() < 1e-15);
        assert_eq!(transition_width(&s[..3], 0.1, 0.9), None);
        assert_eq!(transition_width(&[], 0.1, 0.9), None);
    }
}

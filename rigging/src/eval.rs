//! Scoring an embedding against ground truth (rigging spec §7.5, reconstructed and automated).
//!
//! Correct iff (1) every embedded joint is inside the mesh, (2) every reduced joint is within
//! 0.06·H of its ground-truth joint, (3) every embedded leaf joint's nearest ground-truth bone
//! belongs to the right limb, (4) degree-2 joints are within 0.10·H. H = character height.

use geom_core::collide::MeshQuery;
use geom_core::math::Pt3;
use geom_core::query::closest_point_segment;

use crate::template::SkeletonTemplate;

/// The score of one embedding.
#[derive(Clone, Debug, PartialEq)]
pub struct EmbeddingScore {
    /// All four criteria hold.
    pub ok: bool,
    /// Why not (empty when ok).
    pub reason: String,
    /// Mean joint error / H over all joints.
    pub mean_err_rel: f64,
    /// Largest joint error / H.
    pub max_err_rel: f64,
    /// Reduced joint with the largest error (template index).
    pub worst_reduced: usize,
}

/// Limb label of a template joint: the name of the child of the root whose subtree holds it,
/// with the hips/back chain split by the children of the first joint of degree > 2 below.
fn limb(sk: &SkeletonTemplate, mut j: usize) -> usize {
    // Walk up until the parent has degree > 2 (a branching joint) or is the root.
    let deg = |k: usize| sk.joints.iter().filter(|x| x.parent == Some(k)).count() + usize::from(k != 0);
    while let Some(p) = sk.joints[j].parent {
        if deg(p) > 2 || p == 0 {
            return j;
        }
        j = p;
    }
    j
}

/// Scores `joints` (template order, same coordinates as `truth` and `mesh`) against `truth`.
pub fn score(sk: &SkeletonTemplate, joints: &[Pt3], truth: &[Pt3], mesh: &MeshQuery) -> EmbeddingScore {
    let b = mesh.bbox();
    let h = b.max.y - b.min.y;
    let rs = sk.reduced();
    let errs: Vec<f64> = joints.iter().zip(truth).map(|(a, t)| (a - t).norm() / h).collect();
    let mean = errs.iter().sum::<f64>() / errs.len().max(1) as f64;
    let max = errs.iter().copied().fold(0.0, f64::max);
    let mut reason = String::new();
    for (j, q) in joints.iter().enumerate() {
        if mesh.signed_distance(q) >= 0.0 && reason.is_empty() {
            reason = format!("joint {} outside the mesh", sk.joints[j].name);
        }
    }
    let mut worst = rs.full_index[0];
    for &f in &rs.full_index {
        if errs[f] > errs[worst] {
            worst = f;
        }
        if errs[f] > 0.06 && reason.is_empty() {
            reason = format!("reduced joint {} off by {:.3} H", sk.joints[f].name, errs[f]);
        }
    }
    let bones = sk.bones();
    for i in 1..rs.len() {
        let f = rs.full_index[i];
        if sk.joints.iter().any(|x| x.parent == Some(f)) {
            continue; // not a leaf
        }
        let nearest = bones
            .iter()
            .min_by(|a, c| {
                let da = closest_point_segment(&joints[f], &truth[a.0], &truth[a.1]).1 - joints[f];
                let dc = closest_point_segment(&joints[f], &truth[c.0], &truth[c.1]).1 - joints[f];
                da.norm().total_cmp(&dc.norm())
            })
            .expect("at least one bone");
        if limb(sk, nearest.1) != limb(sk, f) && reason.is_empty() {
            reason = format!("leaf {} lies on limb of {}", sk.joints[f].name, sk.joints[nearest.1].name);
        }
    }
    for (j, e) in errs.iter().enumerate() {
        if !rs.full_index.contains(&j) && *e > 0.10 && reason.is_empty() {
            reason = format!("joint {} off by {:.3} H", sk.joints[j].name, e);
        }
    }
    EmbeddingScore { ok: reason.is_empty(), reason, mean_err_rel: mean, max_err_rel: max, worst_reduced: worst }
}

//! Curves from the joint skeleton (spec §3.4.1): one curve at a linear joint, three at a fork,
//! two at a cross (most opposite bones paired), greedy most-opposite pairing beyond; roots pair
//! their children the same way; leaves own no curve.

use geom_core::anim::skin::SkinSkeleton;
use geom_core::math::Vec3;

use super::types::{BoneEnd, CurveSkeleton, JointCurve, JointCurveDefaults, TopologyRules};

/// Unit direction from joint `j` to joint `far` in the rest pose (zero for a zero-length bone:
/// skipped in direction computations, spec §8).
fn rest_dir(sk: &SkinSkeleton, j: usize, far: usize) -> Vec3 {
    let d = sk.rest_world[far].translation.vector - sk.rest_world[j].translation.vector;
    let n = d.norm();
    if n > 1e-12 {
        d / n
    } else {
        Vec3::zeros()
    }
}

/// Pairs bones `0..u.len()` by the rules of §3.4.1 from their unit directions (away from J).
pub(crate) fn pair_bones(u: &[Vec3]) -> Vec<(usize, usize)> {
    let n = u.len();
    let opp = |a: usize, b: usize| -u[a].dot(&u[b]);
    match n {
        0 | 1 => Vec::new(),
        2 => vec![(0, 1)],
        3 => vec![(0, 1), (0, 2), (1, 2)],
        4 => {
            let cands = [[(0, 1), (2, 3)], [(0, 2), (1, 3)], [(0, 3), (1, 2)]];
            let mut best = cands[0];
            let mut best_v = f64::NEG_INFINITY;
            for c in cands {
                let v = opp(c[0].0, c[0].1) + opp(c[1].0, c[1].1);
                if v > best_v + 1e-12 {
                    best_v = v;
                    best = c;
                }
            }
            best.to_vec()
        }
        _ => {
            // Greedy most-opposite pairing; an unpaired bone gets a curve to its most opposite
            // partner (reconstructed generalisation).
            let mut all: Vec<(f64, usize, usize)> =
                (0..n).flat_map(|a| (a + 1..n).map(move |b| (a, b))).map(|(a, b)| (opp(a, b), a, b)).collect();
            all.sort_by(|x, y| y.0.total_cmp(&x.0).then((x.1, x.2).cmp(&(y.1, y.2))));
            let mut used = vec![false; n];
            let mut pairs = Vec::new();
            for &(_, a, b) in &all {
                if !used[a] && !used[b] {
                    used[a] = true;
                    used[b] = true;
                    pairs.push((a, b));
                }
            }
            let unpaired: Vec<usize> = (0..n).filter(|&a| !used[a]).collect();
            for a in unpaired {
                let partner =
                    (0..n).filter(|&b| b != a).max_by(|&x, &y| opp(a, x).total_cmp(&opp(a, y)).then(y.cmp(&x)));
                if let Some(b) = partner {
                    pairs.push((a.min(b), a.max(b)));
                }
            }
            pairs
        }
    }
}

/// Builds the curve skeleton of `sk` (spec §3.4.1). Bones at joint `J` are listed incoming bone
/// first (from the parent), then the outgoing bones in child order; each pair `(a, c)` becomes a
/// curve from the far end of `a` through `J` to the far end of `c`. Spans are `defaults.span`,
/// or 1.0 where the far end is a leaf or a root.
pub fn build_curve_skeleton(sk: &SkinSkeleton, rules: &TopologyRules, defaults: &JointCurveDefaults) -> CurveSkeleton {
    let children = sk.children();
    let mut curves = Vec::new();
    for j in 0..sk.len() {
        if rules.exclude_joints.contains(&j) {
            continue;
        }
        let mut bones: Vec<BoneEnd> = Vec::new();
        if let Some(p) = sk.parent[j] {
            bones.push(BoneEnd { far: p, owner: p });
        }
        for &c in &children[j] {
            bones.push(BoneEnd { far: c, owner: j });
        }
        let u: Vec<Vec3> = bones.iter().map(|b| rest_dir(sk, j, b.far)).collect();
        for (a, c) in pair_bones(&u) {
            let (ba, bc) = (bones[a], bones[c]);
            if rules.skip_rigid && ba.owner == bc.owner {
                continue;
            }
            let span = |b: &BoneEnd| {
                if children[b.far].is_empty() || sk.parent[b.far].is_none() {
                    1.0
                } else {
                    defaults.span
                }
            };
            curves.push(JointCurve {
                joint: j,
                bone_in: ba,
                bone_out: bc,
                span_in: span(&ba),
                span_out: span(&bc),
                bone_cp: defaults.bone_cp.clone(),
                shape: defaults.shape,
                twist: defaults.twist.clone(),
                centre: defaults.centre,
            });
        }
    }
    CurveSkeleton { curves }
}

#[cfg(test)]
mod tests {
    use super::*;
    use geom_core::math::Pt3;

    #[test]
    fn cross_pairs_most_opposite_bones() {
        // spine (down), head (up), left clavicle (+x), right clavicle (−x).
        let u = [
            Vec3::new(0.0, -1.0, 0.0),
            Vec3::new(0.0, 1.0, 0.0),
            Vec3::new(1.0, 0.1, 0.0).normalize(),
            Vec3::new(-1.0, 0.1, 0.0).normalize(),
        ];
        let p = pair_bones(&u);
        assert_eq!(p, vec![(0, 1), (2, 3)]);
    }

    #[test]
    fn counts_per_joint_kind() {
        // A fork: root r, hip h, two legs (two children of h), plus a spine child of h.
        let names: Vec<String> = (0..6).map(|i| format!("j{i}")).collect();
        let pos = [
            Pt3::new(0.0, 1.0, 0.0),
            Pt3::new(0.0, 0.9, 0.0),
            Pt3::new(0.2, 0.5, 0.0),
            Pt3::new(-0.2, 0.5, 0.0),
            Pt3::new(0.2, 0.0, 0.0),
            Pt3::new(-0.2, 0.0, 0.0),
        ];
        let parent = vec![None, Some(0), Some(1), Some(1), Some(2), Some(3)];
        let sk = SkinSkeleton::from_positions(names, parent, &pos).unwrap();
        let cs = build_curve_skeleton(&sk, &TopologyRules::default(), &JointCurveDefaults::default());
        let per_joint = |j| cs.curves.iter().filter(|c| c.joint == j).count();
        assert_eq!(per_joint(0), 0, "root with one child");
        assert_eq!(per_joint(1), 3, "fork");
        assert_eq!(per_joint(2), 1, "linear");
        assert_eq!(per_joint(4), 0, "leaf");
        // The bone to the root and the bones to leaves are fully covered.
        let c = cs.curves.iter().find(|c| c.joint == 2).unwrap();
        assert_eq!((c.span_in, c.span_out), (0.5, 1.0));
        let f = cs.curves.iter().find(|c| c.joint == 1).unwrap();
        assert_eq!(f.span_in, 1.0);
    }
}

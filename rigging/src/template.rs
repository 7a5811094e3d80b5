//! Skeleton templates (rigging spec §3.5): the generic joint trees that are embedded, with the
//! joint attributes used by the discrete penalty (symmetry, foot, fat), and their reduced form
//! (degree-2 chains merged into bone chains).
//!
//! Named `SkeletonTemplate` (GEOM-CORE.md §5.5) to keep `geom_core::anim::Skeleton` as the one
//! animation skeleton; a rig converts through [`crate::Rig::anim_skeleton`].
//! Units: "skeleton units" (about [−1, 1] in y, origin near the pelvis); +Y up, facing +Z, the
//! character's left is +X.

use std::path::Path;

use geom_core::anim::JointRole;
use geom_core::math::Pt3;
use serde::{Deserialize, Serialize};

use crate::error::{Result, RigError};

/// One joint of a template.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TemplateJoint {
    /// Unique name.
    pub name: String,
    /// Rest position in skeleton units.
    pub rest: [f64; 3],
    /// Parent index (smaller than this joint's index); `None` for the root (joint 0 only).
    #[serde(default)]
    pub parent: Option<usize>,
    /// Mirror partner (marked on the higher index of the pair).
    #[serde(default)]
    pub symmetric_to: Option<usize>,
    /// Should lie near the bottom of the character.
    #[serde(default)]
    pub foot: bool,
    /// Only large medial spheres are candidates (torso, head).
    #[serde(default)]
    pub fat: bool,
    /// Semantic role for retargeting motion onto the rig (`geom_core::anim::JointRole`); `None`
    /// = guessed from the name.
    #[serde(default)]
    pub role: Option<JointRole>,
}

/// A generic skeleton to embed.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SkeletonTemplate {
    /// Joints in topological order (joint 0 is the root).
    pub joints: Vec<TemplateJoint>,
}

/// The reduced skeleton (spec §3.5): the root and every joint of degree ≠ 2, reordered so that
/// high-degree joints come first (tight lower bounds), symmetric partners adjacent.
#[derive(Clone, Debug, PartialEq)]
pub struct ReducedSkeleton {
    /// Reduced joint → full joint.
    pub full_index: Vec<usize>,
    /// Reduced parent `p_R(i) < i` (`None` for the root, reduced index 0).
    pub parent: Vec<Option<usize>>,
    /// Full joints from the reduced parent (excluded) to joint i (included).
    pub chain: Vec<Vec<usize>>,
    /// Given chain length in skeleton units (multiply by the skeleton scale).
    pub chain_len: Vec<f64>,
    /// Per bone of the chain, its share of `chain_len` (sums to 1; equal shares for a
    /// zero-length chain).
    pub chain_frac: Vec<Vec<f64>>,
    /// Reduced mirror partner (on both joints of a pair).
    pub symmetric_to: Vec<Option<usize>>,
    /// Foot attribute.
    pub foot: Vec<bool>,
    /// Fat attribute.
    pub fat: Vec<bool>,
    /// Rest positions of the reduced joints (skeleton units).
    pub rest: Vec<Pt3>,
}

impl ReducedSkeleton {
    /// Number of reduced joints.
    pub fn len(&self) -> usize {
        self.full_index.len()
    }

    /// Whether there are no joints.
    pub fn is_empty(&self) -> bool {
        self.full_index.is_empty()
    }

    /// Children of reduced joint `i`.
    pub fn children(&self, i: usize) -> Vec<usize> {
        (0..self.len()).filter(|&k| self.parent[k] == Some(i)).collect()
    }

    /// Whether reduced joint `i` is a leaf (degree 1 in the tree).
    pub fn is_leaf(&self, i: usize) -> bool {
        i != 0 && self.children(i).is_empty()
    }

    /// Lowest common ancestor of reduced joints `a` and `b`.
    pub fn lca(&self, a: usize, b: usize) -> usize {
        let anc = |mut x: usize| {
            let mut v = vec![x];
            while let Some(p) = self.parent[x] {
                v.push(p);
                x = p;
            }
            v
        };
        let aa = anc(a);
        let bb = anc(b);
        // Both chains end at the root, so a common ancestor exists.
        *aa.iter().find(|x| bb.contains(x)).expect("reduced joints share the root")
    }
}

fn j(name: &str, rest: [f64; 3], parent: Option<usize>) -> TemplateJoint {
    TemplateJoint { name: name.into(), rest, parent, symmetric_to: None, foot: false, fat: false, role: None }
}

fn with_role(mut t: TemplateJoint, r: JointRole) -> TemplateJoint {
    t.role = Some(r);
    t
}

impl SkeletonTemplate {
    /// Adds the mirror image (x → −x) of joints `range`, named with `l_` → `r_` (or `lX` → `rX`),
    /// parents mapped inside the range, `symmetric_to` set on the new joints.
    fn mirror(&mut self, range: std::ops::Range<usize>) {
        let base = self.joints.len();
        for i in range.clone() {
            let s = &self.joints[i];
            let name = if let Some(rest) = s.name.strip_prefix('l') {
                format!("r{rest}")
            } else {
                format!("{}_mirror", s.name)
            };
            let parent = s.parent.map(|p| if range.contains(&p) { base + p - range.start } else { p });
            let mut m = TemplateJoint { name, rest: [-s.rest[0], s.rest[1], s.rest[2]], parent, ..s.clone() };
            m.symmetric_to = Some(i);
            m.role = s.role.map(JointRole::mirror);
            self.joints.push(m);
        }
    }

    /// The built-in human (spec §3.5 table): 18 joints, 7 reduced; arms about 45° down. Roles
    /// for retargeting: shoulders = `Neck` (the base of the neck, where the collar bones start),
    /// back = `Spine`, hips = `Root`, head = `Head`, thigh/knee/ankle/foot = `Hip`/`Knee`/`Ankle`/
    /// `Toe`, shoulder/elbow/hand = `Shoulder`/`Elbow`/`Hand`.
    pub fn human() -> Self {
        use JointRole::*;
        let mut s = SkeletonTemplate {
            joints: vec![
                TemplateJoint { fat: true, ..with_role(j("shoulders", [0.0, 0.5, 0.0], None), Neck) },
                with_role(j("back", [0.0, 0.17, 0.0], Some(0)), Spine),
                TemplateJoint { fat: true, ..with_role(j("hips", [0.0, -0.05, 0.0], Some(1)), Root) },
                TemplateJoint { fat: true, ..with_role(j("head", [0.0, 0.75, 0.0], Some(0)), Head) },
                with_role(j("l_thigh", [0.1, -0.05, 0.0], Some(2)), LeftHip),
                with_role(j("l_knee", [0.13, -0.42, 0.02], Some(4)), LeftKnee),
                with_role(j("l_ankle", [0.14, -0.82, 0.0], Some(5)), LeftAnkle),
                TemplateJoint { foot: true, ..with_role(j("l_foot", [0.14, -0.84, 0.12], Some(6)), LeftToe) },
            ],
        };
        s.mirror(4..8);
        s.joints.push(with_role(j("l_shoulder", [0.19, 0.5, 0.0], Some(0)), LeftShoulder));
        s.joints.push(with_role(j("l_elbow", [0.4, 0.26, 0.06], Some(12)), LeftElbow));
        s.joints.push(with_role(j("l_hand", [0.6, 0.02, 0.12], Some(13)), LeftHand));
        s.mirror(12..15);
        s
    }

    /// The built-in quadruped: body along z (head at +z), shoulders as root, spine to the hips,
    /// neck and head, four legs of thigh/knee/foot and a tail (18 joints, 8 reduced). Joint names
    /// match `geom_core::procedural::character::QUADRUPED_JOINTS`.
    pub fn quadruped() -> Self {
        let mut s = SkeletonTemplate {
            joints: vec![
                TemplateJoint { fat: true, ..j("shoulders", [0.0, 0.0, 0.5], None) },
                j("back", [0.0, 0.02, 0.0], Some(0)),
                TemplateJoint { fat: true, ..j("hips", [0.0, 0.0, -0.5], Some(1)) },
                j("neck", [0.0, 0.3, 0.7], Some(0)),
                TemplateJoint { fat: true, ..j("head", [0.0, 0.45, 0.9], Some(3)) },
                j("lf_thigh", [0.15, -0.07, 0.5], Some(0)),
                j("lf_knee", [0.15, -0.45, 0.55], Some(5)),
                TemplateJoint { foot: true, ..j("lf_foot", [0.15, -0.85, 0.53], Some(6)) },
            ],
        };
        s.mirror(5..8);
        s.joints.push(j("lh_thigh", [0.15, -0.07, -0.5], Some(2)));
        s.joints.push(j("lh_knee", [0.15, -0.45, -0.57], Some(11)));
        s.joints.push(TemplateJoint { foot: true, ..j("lh_foot", [0.15, -0.85, -0.47], Some(12)) });
        s.mirror(11..14);
        s.joints.push(j("tail", [0.0, 0.08, -1.1], Some(2)));
        s
    }

    /// A centaur: a quadruped body whose shoulders carry a human torso, head and arms.
    pub fn centaur() -> Self {
        let mut s = SkeletonTemplate {
            joints: vec![
                TemplateJoint { fat: true, ..j("withers", [0.0, 0.0, 0.5], None) },
                j("back", [0.0, 0.02, 0.0], Some(0)),
                TemplateJoint { fat: true, ..j("hips", [0.0, 0.0, -0.5], Some(1)) },
                j("waist", [0.0, 0.35, 0.6], Some(0)),
                TemplateJoint { fat: true, ..j("chest", [0.0, 0.7, 0.6], Some(3)) },
                TemplateJoint { fat: true, ..j("head", [0.0, 0.95, 0.6], Some(4)) },
                j("l_shoulder", [0.19, 0.7, 0.6], Some(4)),
                j("l_elbow", [0.4, 0.46, 0.66], Some(6)),
                j("l_hand", [0.6, 0.22, 0.72], Some(7)),
            ],
        };
        s.mirror(6..9);
        let front = s.joints.len();
        s.joints.push(j("lf_thigh", [0.15, -0.07, 0.5], Some(0)));
        s.joints.push(j("lf_knee", [0.15, -0.45, 0.55], Some(front)));
        s.joints.push(TemplateJoint { foot: true, ..j("lf_foot", [0.15, -0.85, 0.53], Some(front + 1)) });
        s.mirror(front..front + 3);
        let hind = s.joints.len();
        s.joints.push(j("lh_thigh", [0.15, -0.07, -0.5], Some(2)));
        s.joints.push(j("lh_knee", [0.15, -0.45, -0.57], Some(hind)));
        s.joints.push(TemplateJoint { foot: true, ..j("lh_foot", [0.15, -0.85, -0.47], Some(hind + 1)) });
        s.mirror(hind..hind + 3);
        s
    }

    /// Reads a template from a RON file (the fields of [`SkeletonTemplate`]) and validates it.
    pub fn from_ron_file(path: &Path) -> Result<Self> {
        let text = std::fs::read_to_string(path)
            .map_err(|e| RigError::File { path: path.display().to_string(), msg: e.to_string() })?;
        let s: SkeletonTemplate = ron::from_str(&text)
            .map_err(|e| RigError::File { path: path.display().to_string(), msg: e.to_string() })?;
        s.validate()?;
        Ok(s)
    }

    /// Checks the tree: non-empty, joint 0 the only root, parents before children, unique
    /// names, finite positions, symmetry partners in range and not self.
    pub fn validate(&self) -> Result<()> {
        if self.joints.is_empty() {
            return Err(RigError::InvalidSkeleton("no joints".into()));
        }
        let mut names = std::collections::HashSet::new();
        for (i, jt) in self.joints.iter().enumerate() {
            if !names.insert(jt.name.as_str()) {
                return Err(RigError::InvalidSkeleton(format!("duplicate joint name '{}'", jt.name)));
            }
            if !jt.rest.iter().all(|c| c.is_finite()) {
                return Err(RigError::InvalidSkeleton(format!("joint '{}' has a non-finite position", jt.name)));
            }
            match (i, jt.parent) {
                (0, None) => {}
                (0, Some(_)) => return Err(RigError::InvalidSkeleton("joint 0 must be the root".into())),
                (_, None) => return Err(RigError::InvalidSkeleton(format!("joint '{}' has no parent", jt.name))),
                (_, Some(p)) if p >= i => {
                    return Err(RigError::InvalidSkeleton(format!(
                        "joint '{}' (index {i}) has parent {p}: parents must come first",
                        jt.name
                    )))
                }
                _ => {}
            }
            if let Some(s) = jt.symmetric_to {
                if s >= self.joints.len() || s == i {
                    return Err(RigError::InvalidSkeleton(format!("joint '{}': bad symmetric_to {s}", jt.name)));
                }
            }
        }
        Ok(())
    }

    /// Number of joints.
    pub fn len(&self) -> usize {
        self.joints.len()
    }

    /// Whether the template has no joints.
    pub fn is_empty(&self) -> bool {
        self.joints.is_empty()
    }

    /// Rest positions as points.
    pub fn rest(&self) -> Vec<Pt3> {
        self.joints.iter().map(|j| Pt3::from(j.rest)).collect()
    }

    /// Parents.
    pub fn parents(&self) -> Vec<Option<usize>> {
        self.joints.iter().map(|j| j.parent).collect()
    }

    /// An animation skeleton with this template's joints at `joints` (template order): names,
    /// parents, offsets from the positions, the template's roles (overriding guesses from names).
    pub fn anim_skeleton(&self, joints: &[Pt3]) -> Result<geom_core::anim::Skeleton> {
        let names: Vec<String> = self.joints.iter().map(|j| j.name.clone()).collect();
        let mut s = geom_core::anim::Skeleton::from_joint_positions(&names, &self.parents(), joints)?;
        for (i, j) in self.joints.iter().enumerate() {
            if let Some(r) = j.role {
                s.roles.retain(|_, v| *v as usize != i);
                s.roles.insert(r, i as u16);
            }
        }
        Ok(s)
    }

    /// Index of the joint called `name`.
    pub fn find(&self, name: &str) -> Option<usize> {
        self.joints.iter().position(|j| j.name == name)
    }

    /// Bones `(parent joint, joint)`, one per non-root joint, in joint order (`s − 1` bones; bone
    /// `b` ends at joint `b + 1`).
    pub fn bones(&self) -> Vec<(usize, usize)> {
        self.joints.iter().enumerate().filter_map(|(i, j)| j.parent.map(|p| (p, i))).collect()
    }

    fn degree(&self) -> Vec<usize> {
        let mut d = vec![0usize; self.len()];
        for (p, c) in self.bones() {
            d[p] += 1;
            d[c] += 1;
        }
        d
    }

    /// The reduced skeleton (spec §3.5). Order: root, then joints of reduced degree > 2
    /// (breadth first), then the others breadth first with symmetric partners adjacent; always
    /// `p_R(i) < i`.
    pub fn reduced(&self) -> ReducedSkeleton {
        let deg = self.degree();
        let n = self.len();
        let kept: Vec<bool> = (0..n).map(|i| i == 0 || deg[i] != 2).collect();
        let rest = self.rest();
        // Nearest kept ancestor and chains.
        let mut kparent = vec![None; n];
        let mut chain: Vec<Vec<usize>> = vec![Vec::new(); n];
        for i in 1..n {
            if !kept[i] {
                continue;
            }
            let mut c = vec![i];
            let mut x = self.joints[i].parent.expect("validated: non-root joints have parents");
            while !kept[x] {
                c.push(x);
                x = self.joints[x].parent.expect("validated: non-root joints have parents");
            }
            c.reverse();
            kparent[i] = Some(x);
            chain[i] = c;
        }
        // Reduced degree.
        let mut rdeg = vec![0usize; n];
        for i in 1..n {
            if let Some(p) = kparent[i] {
                rdeg[i] += 1;
                rdeg[p] += 1;
            }
        }
        // Order: BFS from the root; high degree first within the constraint p before child.
        let mut order = vec![0usize];
        let mut placed = vec![false; n];
        placed[0] = true;
        for pass in 0..2 {
            loop {
                let mut added = false;
                for i in 1..n {
                    if !kept[i] || placed[i] || !placed[kparent[i].expect("kept non-root")] {
                        continue;
                    }
                    if pass == 0 && rdeg[i] <= 2 {
                        continue;
                    }
                    placed[i] = true;
                    order.push(i);
                    // Keep the mirror partner adjacent if it can be placed now.
                    let partner = (0..n).find(|&k| {
                        kept[k]
                            && !placed[k]
                            && (self.joints[k].symmetric_to == Some(i) || self.joints[i].symmetric_to == Some(k))
                    });
                    if let Some(k) = partner {
                        if placed[kparent[k].expect("kept non-root")] && (pass == 1 || rdeg[k] > 2) {
                            placed[k] = true;
                            order.push(k);
                        }
                    }
                    added = true;
                }
                if !added {
                    break;
                }
            }
        }
        let mut to_r = vec![usize::MAX; n];
        for (r, &f) in order.iter().enumerate() {
            to_r[f] = r;
        }
        let parent: Vec<Option<usize>> = order.iter().map(|&f| kparent[f].map(|p| to_r[p])).collect();
        let chains: Vec<Vec<usize>> = order.iter().map(|&f| chain[f].clone()).collect();
        let mut chain_len = Vec::new();
        let mut chain_frac = Vec::new();
        for (r, c) in chains.iter().enumerate() {
            if r == 0 {
                chain_len.push(0.0);
                chain_frac.push(Vec::new());
                continue;
            }
            let lens: Vec<f64> = c
                .iter()
                .map(|&f| (rest[f] - rest[self.joints[f].parent.expect("chain joints have parents")]).norm())
                .collect();
            let total: f64 = lens.iter().sum();
            chain_len.push(total);
            chain_frac.push(if total > 0.0 {
                lens.iter().map(|l| l / total).collect()
            } else {
                vec![1.0 / lens.len() as f64; lens.len()]
            });
        }
        let symmetric_to = order
            .iter()
            .map(|&f| {
                let s =
                    self.joints[f].symmetric_to.or_else(|| self.joints.iter().position(|k| k.symmetric_to == Some(f)));
                s.and_then(|s| if kept[s] { Some(to_r[s]) } else { None })
            })
            .collect();
        ReducedSkeleton {
            full_index: order.clone(),
            parent,
            chain: chains,
            chain_len,
            chain_frac,
            symmetric_to,
            foot: order.iter().map(|&f| self.joints[f].foot).collect(),
            fat: order.iter().map(|&f| self.joints[f].fat).collect(),
            rest: order.iter().map(|&f| rest[f]).collect(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn human_and_quadruped_reduce_as_in_the_paper() {
        let h = SkeletonTemplate::human();
        h.validate().expect("valid");
        assert_eq!(h.len(), 18);
        let r = h.reduced();
        assert_eq!(r.len(), 7);
        for i in 1..r.len() {
            assert!(r.parent[i].expect("non-root") < i);
            assert!((r.chain_frac[i].iter().sum::<f64>() - 1.0).abs() < 1e-12);
        }
        // Root, hips (degree 3) first; partners adjacent.
        assert_eq!(h.joints[r.full_index[1]].name, "hips");
        for i in 0..r.len() {
            if let Some(s) = r.symmetric_to[i] {
                assert_eq!((i as i64 - s as i64).abs(), 1, "partners adjacent");
            }
        }
        let names: Vec<&str> = h.joints.iter().map(|j| j.name.as_str()).collect();
        assert_eq!(names, geom_core::procedural::character::HUMANOID_JOINTS.to_vec());
        let q = SkeletonTemplate::quadruped();
        q.validate().expect("valid");
        assert_eq!(q.reduced().len(), 8);
        let c = SkeletonTemplate::centaur();
        c.validate().expect("valid");
        assert!(c.reduced().len() >= 9);
    }

    #[test]
    fn ron_round_trip_and_validation_errors() {
        let h = SkeletonTemplate::human();
        let text = ron::to_string(&h).expect("serialises");
        let dir = std::env::temp_dir().join(format!("rig_tpl_{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("temp dir");
        let p = dir.join("h.ron");
        std::fs::write(&p, &text).expect("write");
        assert_eq!(SkeletonTemplate::from_ron_file(&p).expect("reads"), h);
        let mut bad = h.clone();
        bad.joints[3].parent = Some(7);
        assert!(matches!(bad.validate(), Err(RigError::InvalidSkeleton(_))));
        std::fs::write(&p, "(joints: [(name: \"a\", rest: (0, 0, 0), bogus: 1)])").expect("write");
        assert!(matches!(SkeletonTemplate::from_ron_file(&p), Err(RigError::File { .. })));
    }
}

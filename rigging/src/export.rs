//! Outputs of a rig: the embedded skeleton as an OBJ of joints and bone lines, the weights per
//! joint, and `rig.json` ([`RigFile`]): joints and per-vertex weights in the input's axes and
//! units, with the mesh they refer to.

use std::fmt::Write as _;

use geom_core::anim::skin::SkinWeights;
use geom_core::anim::JointRole;
use geom_core::math::Pt3;
use geom_core::stats;
use serde::{Deserialize, Serialize};

use crate::character::CharacterRig;
use crate::error::{Result, RigError};
use crate::orient::{Axis, Orientation};
use crate::rig::Rig;
use crate::template::SkeletonTemplate;

/// The embedded skeleton as OBJ text: one vertex per joint (commented with its name), one `l`
/// line element per bone (spec §6: skeletons are written as line elements).
pub fn skeleton_obj(sk: &SkeletonTemplate, joints: &[Pt3]) -> String {
    let mut s = String::from("# embedded skeleton: one vertex per joint, one line per bone\n");
    for (j, p) in joints.iter().enumerate() {
        let _ = writeln!(s, "v {} {} {} # {}", p.x, p.y, p.z, sk.joints[j].name);
    }
    for (p, c) in sk.bones() {
        let _ = writeln!(s, "l {} {}", p + 1, c + 1);
    }
    s
}

/// The weights of a rig per template joint instead of per bone: a bone's weight goes to the joint
/// it starts at (the joint whose rotation moves it), the usual meaning of a joint weight in
/// animation packages. Rows follow the rig's (prepared) mesh.
pub fn joint_weights(rig: &Rig) -> Result<SkinWeights> {
    let bones = rig.template.bones();
    let rows: Vec<Vec<(u16, f32)>> = (0..rig.weights.len())
        .map(|v| {
            let (js, ws) = rig.weights.row(v);
            let mut row: Vec<(u16, f32)> = Vec::with_capacity(js.len());
            for (&j, &w) in js.iter().zip(ws) {
                // Skinning joint j ≥ 1 is bone j − 1; the synthetic root (0) carries no weight.
                let Some(&(p, _)) = (j as usize).checked_sub(1).and_then(|b| bones.get(b)) else { continue };
                match row.iter_mut().find(|(k, _)| *k as usize == p) {
                    Some(e) => e.1 += w,
                    None => row.push((p as u16, w)),
                }
            }
            row.sort_by_key(|e| e.0);
            row
        })
        .collect();
    Ok(SkinWeights::from_rows(&rows)?)
}

/// One joint of a [`RigFile`].
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RigFileJoint {
    /// Template joint name.
    pub name: String,
    /// Parent joint index (`null` for the root).
    pub parent: Option<usize>,
    /// Position in the input mesh's axes and units.
    pub position: [f64; 3],
    /// Retargeting role (`geom_core::anim::JointRole` name, e.g. `LeftKnee`), if any.
    #[serde(default)]
    pub role: Option<JointRole>,
}

/// The mesh a [`RigFile`]'s weights refer to: the input vertices in file order and its
/// triangles.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct RigFileMesh {
    /// Vertex positions (input axes and units).
    pub positions: Vec<[f64; 3]>,
    /// Triangles (polygons of the file fan-triangulated).
    pub triangles: Vec<[u32; 3]>,
}

/// `rig.json`, written by `cargo xtask rig` and read by `cargo xtask retarget` (format documented
/// in the crate README).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RigFile {
    /// Format tag, [`RIG_FILE_FORMAT`].
    pub format: String,
    /// The input axis that is up (`+x`, `-y`, …).
    pub up: String,
    /// The input axis the character faces.
    pub front: String,
    /// Standing height: the mesh's extent along `up` (input units).
    pub height: f64,
    /// Whether the discrete embedding is the proven optimum (false when the search budget was
    /// hit).
    pub certified_optimal: bool,
    /// Joints in template order (parents first).
    pub joints: Vec<RigFileJoint>,
    /// Per vertex of `mesh`: `[joint, weight]` pairs, weights summing to 1 (an empty row for a
    /// vertex that was not rigged, e.g. of a dropped component).
    pub weights: Vec<Vec<(usize, f32)>>,
    /// The mesh the weights refer to.
    pub mesh: RigFileMesh,
}

/// Format tag of [`RigFile`].
pub const RIG_FILE_FORMAT: &str = "rigging rig.json 1";

impl RigFile {
    /// The file of a character rig on the input mesh `positions`/`faces` (the soup given to
    /// [`crate::character::rig_character`]).
    pub fn new(r: &CharacterRig, positions: &[Pt3], faces: &[[u32; 3]]) -> Result<RigFile> {
        let jw = joint_weights(&r.rig)?;
        let map = &r.rig.diagnostics.prep.vertex_map;
        let weights = (0..positions.len())
            .map(|v| match map.get(v).copied().filter(|&p| (p as usize) < jw.len()) {
                Some(p) => {
                    let (js, ws) = jw.row(p as usize);
                    js.iter().zip(ws).map(|(&j, &w)| (j as usize, w)).collect()
                }
                None => Vec::new(),
            })
            .collect();
        let up = r.orientation.up.vector();
        let hs: Vec<f64> = positions.iter().map(|p| p.coords.dot(&up)).collect();
        Ok(RigFile {
            format: RIG_FILE_FORMAT.into(),
            up: r.orientation.up.name().into(),
            front: r.orientation.front.name().into(),
            height: stats::max(&hs) - stats::min(&hs),
            certified_optimal: r.rig.discrete.certified_optimal,
            joints: r
                .rig
                .template
                .joints
                .iter()
                .zip(&r.joints)
                .map(|(j, p)| RigFileJoint {
                    name: j.name.clone(),
                    parent: j.parent,
                    position: [p.x, p.y, p.z],
                    role: j.role,
                })
                .collect(),
            weights,
            mesh: RigFileMesh {
                positions: positions.iter().map(|p| [p.x, p.y, p.z]).collect(),
                triangles: faces.to_vec(),
            },
        })
    }

    /// Checks the file: format tag, axes, joints (parents first, finite positions), weights (one
    /// row per mesh vertex, joints in range, finite non-negative weights), triangles in range.
    /// Errors name the field.
    pub fn validate(&self) -> Result<Orientation> {
        let bad = |m: String| Err(RigError::InvalidParameter(m));
        if self.format != RIG_FILE_FORMAT {
            return bad(format!("format '{}' (expected '{RIG_FILE_FORMAT}')", self.format));
        }
        let o = Orientation::new(self.up.parse::<Axis>()?, self.front.parse::<Axis>()?)?;
        if self.joints.is_empty() {
            return bad("joints: empty".into());
        }
        for (i, j) in self.joints.iter().enumerate() {
            if j.parent.is_some_and(|p| p >= i) || (i > 0 && j.parent.is_none()) || (i == 0 && j.parent.is_some()) {
                return bad(format!("joints[{i}] ('{}'): parent {:?} must be an earlier joint", j.name, j.parent));
            }
            if !j.position.iter().all(|c| c.is_finite()) {
                return bad(format!("joints[{i}] ('{}'): non-finite position", j.name));
            }
        }
        let n = self.mesh.positions.len();
        if self.weights.len() != n {
            return bad(format!("weights: {} rows for {n} mesh vertices", self.weights.len()));
        }
        for (v, row) in self.weights.iter().enumerate() {
            if let Some((j, w)) = row.iter().find(|(j, w)| *j >= self.joints.len() || !(w.is_finite() && *w >= 0.0)) {
                return bad(format!("weights[{v}]: joint {j} weight {w}"));
            }
        }
        if let Some((f, t)) = self.mesh.triangles.iter().enumerate().find(|(_, t)| t.iter().any(|&v| v as usize >= n)) {
            return bad(format!("mesh.triangles[{f}] = {t:?} indexes past {n} vertices"));
        }
        if !(self.height > 0.0 && self.height.is_finite()) {
            return bad(format!("height {} must be positive", self.height));
        }
        Ok(o)
    }
}

impl RigFile {
    /// The rig as an animation skeleton in the template's frame (+Y up, facing +Z; input
    /// coordinates turned by `o`, scaled by `scale`, e.g. metres per input unit), with the file's
    /// roles (names guess the others).
    pub fn anim_skeleton(&self, o: &Orientation, scale: f64) -> Result<geom_core::anim::Skeleton> {
        let names: Vec<String> = self.joints.iter().map(|j| j.name.clone()).collect();
        let parents: Vec<Option<usize>> = self.joints.iter().map(|j| j.parent).collect();
        let pos: Vec<Pt3> = self.joints.iter().map(|j| o.point_to_canonical(&Pt3::from(j.position)) * scale).collect();
        let mut s = geom_core::anim::Skeleton::from_joint_positions(&names, &parents, &pos)?;
        s.name = "rig".into();
        for (i, j) in self.joints.iter().enumerate() {
            if let Some(r) = j.role {
                s.roles.retain(|_, v| *v as usize != i);
                s.roles.insert(r, i as u16);
            }
        }
        Ok(s)
    }

    /// The mesh in the template's frame, scaled like [`Self::anim_skeleton`].
    pub fn mesh_positions(&self, o: &Orientation, scale: f64) -> Vec<Pt3> {
        self.mesh.positions.iter().map(|p| o.point_to_canonical(&Pt3::from(*p)) * scale).collect()
    }

    /// The weights as skinning weights over the joints (a vertex without weights follows the
    /// root).
    pub fn skin_weights(&self) -> Result<SkinWeights> {
        let rows: Vec<Vec<(u16, f32)>> = self
            .weights
            .iter()
            .map(|r| if r.is_empty() { vec![(0, 1.0)] } else { r.iter().map(|&(j, w)| (j as u16, w)).collect() })
            .collect();
        Ok(SkinWeights::from_rows(&rows)?)
    }
}

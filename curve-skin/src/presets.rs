//! The paper's and the spec's canonical setups: the reference cylinder arm of spec §7, its
//! smoothstep ramp weights for LBS / DQS, the capsule humanoid with inverse-distance weights
//! (spec §6.3), the arm poses of the elbow-bend and candy-wrapper scenes (spec §6.1–6.2), and
//! the three skinners every comparison uses with their default options.
//!
//! ```
//! use curve_skin::presets;
//! let (mesh, sk) = presets::reference_arm(20, 12).unwrap();
//! assert_eq!(sk.len(), 3);
//! let lbs = presets::ramp_weights4(&mesh.positions, 1.0);
//! assert_eq!(lbs.len(), mesh.positions.len());
//! ```

use geom_core::math::{Pt3, UnitQuat, Vec3};
use serde::{Deserialize, Serialize};

use crate::curve::{build_curve_skeleton, CurveShape, JointCurveDefaults, TopologyRules};
use crate::error::Result;
use crate::poses::{axis_deg, SkinPose};
use crate::procedural::{cylinder_arm, humanoid, inverse_distance_weights, ramp_weights, Ramp, SkinMesh};
use crate::{CurveOptions, CurveSkeleton, CurveSkin, Dqs, Lbs, PackedWeights, SkinSkeleton, Skinner};

/// Limb radius R of the reference arm (m, spec §7).
pub const ARM_RADIUS: f64 = 0.15;
/// Bone length of the reference arm (m): the arm spans x ∈ [−1, 1] with the elbow at 0.
pub const ARM_BONE_LEN: f64 = 1.0;
/// Exponent of the humanoid's inverse-distance weights (spec §6.3, "own simple weights").
pub const HUMANOID_WEIGHT_POWER: f64 = 4.0;
/// Weight threshold of the humanoid's inverse-distance weights (spec §6.3: 0.01).
pub const HUMANOID_WEIGHT_THRESHOLD: f32 = 0.01;

/// The reference arm `cylinder_arm(R = 0.15, bone_len = 1.0, rings, segments)` (spec §7: 400 ×
/// 96; the quick runs use 100 × 32).
pub fn reference_arm(rings: usize, segments: usize) -> Result<(SkinMesh, SkinSkeleton)> {
    cylinder_arm(ARM_RADIUS, ARM_BONE_LEN, rings, segments)
}

/// Two-bone smoothstep ramp weights of half-width `half_width` (m) about the elbow (x = 0),
/// padded to four influences (the `K = 4` LBS / DQS of the comparisons).
pub fn ramp_weights4<P: geom_core::math::AsPt3>(rest: &[P], half_width: f64) -> PackedWeights<4> {
    widen(&ramp_weights(rest, 0.0, half_width, Ramp::SmoothStep))
}

/// Pads two-influence weights to `K ≥ 2` influences with zero weights on bone 0.
pub fn widen<const K: usize>(w: &PackedWeights<2>) -> PackedWeights<K> {
    PackedWeights {
        bone: w.bone.iter().map(|b| std::array::from_fn(|k| if k < 2 { b[k] } else { 0 })).collect(),
        w: w.w.iter().map(|x| std::array::from_fn(|k| if k < 2 { x[k] } else { 0.0 })).collect(),
    }
}

/// How the arm is posed: bent about z through the elbow or twisted about the forearm axis x.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum ArmMotion {
    /// Bend about z (collapsing elbow, spec §6.1).
    Bend,
    /// Twist about x (candy wrapper, spec §6.2).
    Twist,
}

impl ArmMotion {
    /// The forearm's world rotation at `deg` degrees.
    pub fn rotation(self, deg: f64) -> UnitQuat {
        match self {
            ArmMotion::Bend => axis_deg(Vec3::z(), deg),
            ArmMotion::Twist => axis_deg(Vec3::x(), deg),
        }
    }
}

/// The arm pose whose forearm (joint 1) is rotated by `g` in world axes.
pub fn arm_pose(sk: &SkinSkeleton, g: UnitQuat) -> SkinPose {
    let mut pose = SkinPose::rest(sk);
    pose.set_world(sk, 1, g);
    pose
}

/// The curve skeleton of `sk` with default topology rules and every joint curve of `shape`.
pub fn curve_skeleton(sk: &SkinSkeleton, shape: CurveShape) -> CurveSkeleton {
    build_curve_skeleton(sk, &TopologyRules::default(), &JointCurveDefaults { shape, ..Default::default() })
}

/// The capsule humanoid of spec §6.3 with its inverse-distance weights, bound once for every
/// method.
#[derive(Clone, Debug)]
pub struct Character {
    /// The mesh (f64 rest positions, triangles).
    pub mesh: SkinMesh,
    /// The skeleton (22 joints).
    pub sk: SkinSkeleton,
    /// Rest positions as `f32` (the skinners' bulk format).
    pub rest32: Vec<[f32; 3]>,
    /// Rest vertex normals as `f32`.
    pub normals32: Vec<[f32; 3]>,
    /// The weights packed to four influences.
    pub w4: PackedWeights<4>,
    /// The sparse weight rows (all influences above the threshold).
    pub rows: Vec<Vec<(u16, f32)>>,
}

/// The capsule humanoid at resolution `res` (1.0 ≈ 50k vertices) with inverse-distance weights
/// (power [`HUMANOID_WEIGHT_POWER`]) above `threshold`.
pub fn capsule_character(res: f64, threshold: f32) -> Result<Character> {
    let h = humanoid(res)?;
    let rows = inverse_distance_weights(&h.mesh.positions, &h.skeleton, HUMANOID_WEIGHT_POWER, threshold);
    let (w4, _) = PackedWeights::<4>::from_sparse(&rows)?;
    let rest32 = h.mesh.positions_f32();
    let normals32 = h.mesh.vertex_normals().iter().map(|v| [v.x as f32, v.y as f32, v.z as f32]).collect();
    Ok(Character { mesh: h.mesh, sk: h.skeleton, rest32, normals32, w4, rows })
}

/// A named skinner.
pub type NamedSkinner = (&'static str, Box<dyn Skinner>);

/// The three methods on a character, `lbs`, `dqs` (K = 4) and `curve` (default options,
/// circular arcs), with rest normals when `normals` is set.
pub fn character_skinners(c: &Character, normals: bool) -> Result<Vec<NamedSkinner>> {
    let n = if normals { Some(c.normals32.clone()) } else { None };
    let cskel = curve_skeleton(&c.sk, CurveShape::CircularArc);
    Ok(vec![
        ("lbs", Box::new(Lbs::new(c.rest32.clone(), n.clone(), c.w4.clone())?) as Box<dyn Skinner>),
        ("dqs", Box::new(Dqs::new(c.rest32.clone(), n, c.w4.clone())?)),
        (
            "curve",
            Box::new(CurveSkin::new(
                &c.sk,
                cskel,
                &c.mesh.positions,
                if normals { Some(&c.normals32) } else { None },
                CurveOptions::default(),
            )?),
        ),
    ])
}

/// The point `(x / bone_len, y / R, z / R)` of the reference arm in metres.
pub fn arm_point(p: (f64, f64, f64), radius: f64, bone_len: f64) -> Pt3 {
    Pt3::new(p.0 * bone_len, p.1 * radius, p.2 * radius)
}

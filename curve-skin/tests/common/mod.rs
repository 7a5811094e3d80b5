//! Shared set-up of the integration tests: the reference cylinder arm of spec §7 and helpers.
#![allow(dead_code)]

use curve_skin::curve::{
    build_curve_skeleton, CurveFrame, FrameHistory, JointCurveDefaults, TopologyRules, TwistChoice, VolumeComp,
};
use curve_skin::poses::{axis_deg, SkinPose};
use curve_skin::procedural::{cylinder_arm, ramp_weights, Ramp, SkinMesh};
use curve_skin::{CurveOptions, CurveSkin, PackedWeights, SkinSkeleton};
use geom_core::math::{Iso3, Pt3, Vec3};

/// Limb radius of the reference arm (m).
pub const R: f64 = 0.15;

pub struct Arm {
    pub mesh: SkinMesh,
    pub sk: SkinSkeleton,
    /// Side (ring) vertices: everything except the two fan-cap centres.
    pub side: Vec<bool>,
}

pub fn arm(rings: usize, segments: usize) -> Arm {
    let (mesh, sk) = cylinder_arm(R, 1.0, rings, segments).unwrap();
    let n = mesh.positions.len();
    let side = (0..n).map(|i| i < n - 2).collect();
    Arm { mesh, sk, side }
}

/// The reference arm `cylinder_arm(0.15, 1.0, 400, 96)`.
pub fn reference_arm() -> Arm {
    arm(400, 96)
}

pub fn ramp4(mesh: &SkinMesh, h: f64) -> PackedWeights<4> {
    let w2 = ramp_weights(&mesh.positions, 0.0, h, Ramp::SmoothStep);
    PackedWeights {
        bone: w2.bone.iter().map(|b| [b[0], b[1], 0, 0]).collect(),
        w: w2.w.iter().map(|w| [w[0], w[1], 0.0, 0.0]).collect(),
    }
}

/// Posed frames for a bend `bend_deg` about z and a twist `twist_deg` about the forearm axis.
pub fn arm_pose(sk: &SkinSkeleton, bend_deg: f64, twist_deg: f64) -> (Vec<Iso3>, SkinPose) {
    let mut p = SkinPose::rest(sk);
    p.set_world(sk, 1, axis_deg(Vec3::z(), bend_deg) * axis_deg(Vec3::x(), twist_deg));
    (p.globals(sk), p)
}

/// Curve `i` of `cur` in the posed frames (principal twist, fresh history, no compensation).
pub fn posed_curve(cur: &CurveSkin, i: usize, posed: &[Iso3]) -> CurveFrame {
    CurveFrame::new(
        &cur.skeleton.curves[i],
        &cur.rigs()[i],
        posed,
        &FrameHistory::default(),
        TwistChoice::Principal,
        VolumeComp::Off,
    )
    .0
}

pub fn curve_skin(a: &Arm, opts: CurveOptions) -> CurveSkin {
    let cs = build_curve_skeleton(&a.sk, &TopologyRules::default(), &JointCurveDefaults::default());
    CurveSkin::new(&a.sk, cs, &a.mesh.positions, None, opts).unwrap()
}

pub fn to_f64(p: &[[f32; 3]]) -> Vec<Pt3> {
    p.iter().map(|x| Pt3::new(x[0] as f64, x[1] as f64, x[2] as f64)).collect()
}

/// The posed bone segments of the arm.
pub fn bones(posed: &[Iso3]) -> Vec<(Pt3, Pt3)> {
    let j: Vec<Pt3> = posed.iter().map(|f| Pt3::from(f.translation.vector)).collect();
    vec![(j[0], j[1]), (j[1], j[2])]
}

pub fn side_only(p: &[Pt3], side: &[bool]) -> Vec<Pt3> {
    p.iter().zip(side).filter(|(_, &s)| s).map(|(x, _)| *x).collect()
}

/// Max over vertices of |a − b| / scale.
pub fn max_diff(a: &[Pt3], b: &[Pt3]) -> f64 {
    a.iter().zip(b).map(|(x, y)| (x - y).norm()).fold(0.0, f64::max)
}

/// Distance between two unit quaternions as rotations (up to sign), in quaternion coordinates —
/// precise near zero (unlike `angle_to`, which goes through `acos`).
pub fn qdist(a: &geom_core::math::UnitQuat, b: &geom_core::math::UnitQuat) -> f64 {
    (a.coords - b.coords).norm().min((a.coords + b.coords).norm())
}

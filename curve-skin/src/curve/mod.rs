//! Curve-skeleton skinning (Yang, Somasekharan and Zhang 2006; spec §3.4): curves over the joint
//! skeleton ([`topology`]), their posed geometry and frames ([`frame`]), the binding
//! ([`bind`](mod@bind)) and the skinner with its lookup tables ([`skin`]).

pub mod bind;
pub mod frame;
pub mod skin;
pub mod topology;
pub mod types;

pub use bind::{bind, BindStats, CurveBinding};
pub use frame::{swing_twist, unwrap_near, CurveFrame, CurveRig, FrameHistory, TwistChoice};
pub use skin::{CurveDiagnostics, CurveSkin};
pub use topology::build_curve_skeleton;
pub use types::{
    BoneCp, BoneEnd, CentreMode, CurveOptions, CurveShape, CurveSkeleton, JointCurve, JointCurveDefaults,
    TopologyRules, TwistDistribution, VolumeComp,
};

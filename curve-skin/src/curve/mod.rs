//! Curve-skeleton skinning (Yang, Somasekharan and Zhang 2006; spec §3.4): curves over the joint
//! skeleton ([`topology`]), their posed geometry and frames ([`frame`], with the B-spline shape in
//! [`bspline`]), the binding ([`bind`](mod@bind)), the skinner with its lookup tables ([`skin`])
//! and muscle action lines ([`muscle`]).

pub mod bind;
pub mod bspline;
pub mod frame;
pub mod muscle;
pub mod skin;
pub mod topology;
pub mod types;

pub use bind::{bind, BindStats, CurveBinding};
pub use bspline::QuadBSpline;
pub use frame::{swing_twist, unwrap_near, CurveFrame, CurveRig, FrameHistory, TwistChoice};
pub use muscle::{polyline_length, ActionLine, MuscleBulge};
pub use skin::{CurveDiagnostics, CurveSkin};
pub use topology::build_curve_skeleton;
pub use types::{
    BoneCp, BoneEnd, CentreMode, CurveOptions, CurveShape, CurveSkeleton, JointCurve, JointCurveDefaults,
    TopologyRules, TwistDistribution, VolumeComp,
};

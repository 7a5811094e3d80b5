//! Skeletal animation (GEOM-CORE.md §3.12, motion-graph.md §2.1–2.2): joint hierarchies with
//! semantic roles ([`Skeleton`]), poses and forward kinematics, motion clips ([`Motion`]:
//! resampling, slicing, time stretch, torso frames), BVH reading and writing ([`bvh`]),
//! analytic two-bone IK ([`ik`]), the procedural motion synthesiser ([`synth`]) and motion
//! metrics ([`metrics`]: foot skate, splice discontinuities, stick figures).
//!
//! Conventions: metres, seconds, radians (degrees only in BVH text); right-handed, +Y up; a
//! character's rest pose faces +Z with its left on +X.

pub mod bvh;
pub mod ik;
pub mod metrics;
pub mod motion;
pub mod retarget;
pub mod skeleton;
pub mod skin;
pub mod synth;

pub use motion::{ContactParams, FrameLabels, Motion};
pub use skeleton::{Channel, Joint, JointRole, Pose, Skeleton};

//! # curve-skin
//!
//! Curve-skeleton skinning (Xiaosong Yang, Arun Somasekharan, Jian J. Zhang, *Curve skeleton
//! skinning for human and creature characters*, CAVW 17(3–4), 2006) beside the two baselines a
//! user compares it with: linear blend skinning ([`lbs`]) and dual-quaternion skinning ([`dqs`],
//! Kavan et al. 2007/2008). All three take the same skinning transforms `T_b = W_b·B_b⁻¹` of a
//! `geom_core::anim::skin::SkinSkeleton`, so they can be compared pose by pose (spec §3.1).
//!
//! Bulk per-vertex data is `f32` (structure of arrays); per-bone / per-curve data is `f64`,
//! converted once per frame. Each method also has an `f64` reference path used by the tests.
//!
//! Modules: [`weights`] (packed K-influence weights), [`skinner`] (the common trait and parallel
//! driver), [`lbs`], [`dq`] + [`dqs`], [`curve`] (curve skeleton, frames, binding, tables),
//! [`metrics`], [`procedural`] (cylinder arm, capsule humanoid), [`poses`] (test poses, walk
//! cycle), [`gltf`] (glTF 2.0 export of a skinned mesh), [`presets`] (the reference arm, the
//! capsule character and the standard skinners), [`reference`] (closed forms), [`experiments`]
//! (the reproduction scenes of spec §6 as library calls).

pub mod curve;
pub mod dq;
pub mod dqs;
pub mod error;
pub mod experiments;
pub mod gltf;
pub mod lbs;
pub mod metrics;
pub mod poses;
pub mod presets;
pub mod procedural;
pub mod reference;
pub mod skinner;
pub mod weights;

pub use curve::{CurveOptions, CurveSkeleton, CurveSkin};
pub use dqs::{Antipodal, Dqs};
pub use error::{Error, Result, SkinError};
pub use geom_core::anim::skin::{forward_kinematics_local, skinning_transforms, SkinSkeleton, SkinWeights};
pub use lbs::Lbs;
pub use skinner::{deform_par, DeformOutput, Skinner};
pub use weights::PackedWeights;

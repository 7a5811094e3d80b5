//! # wrinkles
//!
//! Animated wrinkles on coarse cloth by per-triangle area conservation (S. Hadap, E. Bangerter,
//! P. Volino, N. Magnenat-Thalmann, *Animating Wrinkles on Clothes*, IEEE Visualization 1999).
//!
//! Pipeline: [`pattern`] (height field → wrinkle function) → [`precompute`] (rest frames and
//! the four wrinkling coefficients per triangle and pattern by adaptive [`quadrature`]) → per
//! frame [`WrinkleAnimator::frame`] (deformation measures, [`modulation`] factors, [`blend`]
//! weights, [`smoothing`]) → output surfaces ([`displaced`] mesh, bump normals, area report).
//!
//! Reproduction: [`presets`] (sheets, patterns, prescribed deformations), [`metrics`] (every
//! figure of the scenes), [`reference`] (the 1-D buckled strip) and [`experiments`] (the scenes of
//! spec §6 as library calls).
//!
//! Conventions: SI units (m); rest local frame per triangle with edge 0 as x axis (spec §3.3);
//! equation numbers refer to the spec's reconstructed §3 (the paper's own equations are not in
//! the seed).

pub mod animator;
pub mod blend;
pub mod coeffs;
pub mod displaced;
pub mod error;
pub mod experiments;
pub mod frames;
pub mod metrics;
pub mod modulation;
pub mod pattern;
pub mod presets;
pub mod quadrature;
pub mod reference;
pub mod smoothing;

pub use animator::{
    AreaCheck, AreaReport, FrameDiagnostics, FrameModulation, HMax, MapTransform, ModulationOptions, WrinkleAnimator,
};
pub use blend::BlendOptions;
pub use coeffs::{precompute, CoeffStatus, GradientSamples, PrecomputeOptions, TriCoeffs, WrinkleRig};
pub use error::{Error, Result, WrinkleError};
pub use frames::{Deformation, RestFrame, RestMesh};
pub use modulation::{ModulationMode, StrainMeasure};
pub use pattern::{
    Normalization, Offset, PatternOptions, PatternSource, Procedural, SplineKind, UvTransform, Wrap, WrinklePattern,
};
pub use smoothing::{Smoothing, VertexWeights};

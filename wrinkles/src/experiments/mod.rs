//! The reproduction experiments of spec §6, one module each: `run(&Params, Size, &mut dyn
//! Recorder) -> Result<Report>`, where `Params` is the scene file's `params` block.
//!
//! - [`uniaxial`]: W1, the analytic area check under prescribed deformations (`uniaxial`).
//! - [`four_stage`]: W2, the paper's four-stage demonstration (`four-stage`).
//! - [`precompute_cost`]: W5, precomputation time against triangle count (`precompute-cost`).
//! - [`realtime_small`]: W6, frames per second on a small sheet (`realtime-small`).
//! - `vs_fine` (feature `shells`): W4, coarse `shells` cloth + wrinkles against fine `shells`
//!   cloth (`vs-fine`); `sleeve` (feature `shells`): W3 on a `shells` sleeve (`sleeve`);
//!   `cloth` builds and steps those simulations.

pub mod four_stage;
pub mod precompute_cost;
pub mod realtime_small;
pub mod uniaxial;

#[cfg(feature = "shells")]
pub mod cloth;
#[cfg(feature = "shells")]
pub mod sleeve;
#[cfg(feature = "shells")]
pub mod vs_fine;

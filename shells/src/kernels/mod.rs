//! Stand-alone element kernels (pure functions, unit-tested, used by the assembly and benches):
//! hinge angle derivatives, bending, membrane, PSD projection and the plastic update.

pub mod bending;
pub mod hinge;
pub mod membrane;
pub mod plastic;
pub mod psd;
#[cfg(test)]
pub(crate) mod testutil;

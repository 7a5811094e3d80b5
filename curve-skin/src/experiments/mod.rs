//! The reproduction experiments of spec §6, one module each: `run(&Params, Size, &mut dyn
//! Recorder) -> Result<Report>`, where `Params` is the scene file's `params` block.
//!
//! - [`arm`]: the reference arm bent (`elbow-bend`) or twisted (`candy-wrapper`).
//! - [`humanoid`]: the capsule humanoid in the test poses (`humanoid-poses`).
//! - [`walk`]: the humanoid playing the procedural walk, with a glTF export (`walk`).
//! - [`perf`]: time per frame against vertex count and threads (`perf`).

use std::time::Instant;

use crate::{DeformOutput, Skinner};

pub mod arm;
pub mod humanoid;
pub mod perf;
pub mod walk;

/// Deforms every vertex with one skinner on the calling thread; returns the seconds it took.
pub fn timed_deform(s: &dyn Skinner, out: &mut [[f32; 3]]) -> f64 {
    let t = Instant::now();
    s.deform(DeformOutput { positions: out, normals: None });
    t.elapsed().as_secs_f64()
}

//! The reproduction experiments of spec §6, one module each: `run(&Params, Size, &mut dyn
//! Recorder) -> Result<Report>`, where `Params` is the scene file's `params` block.
//!
//! - [`arm_muscle`]: Figure 3 — biceps/triceps nets, elbow sweep, q variants (`arm-muscle`).
//! - [`elbow_volume`]: elbow-ring loads fitted per frame to keep the volume (`elbow-volume`).
//! - [`stiffness`]: the biceps group's q animated against constant q (`stiffness`).
//! - [`topology`]: a triangle/quad/pentagon patch with a hole (`topology`).
//! - [`scaling`]: analytic cable and membrane, grid membranes up to 512² (`scaling`).
//! - [`nonlinear_vs_fdm`]: elastic bars by Newton against the one-solve FDM (`nonlinear-vs-fdm`).

use geom_core::experiment::{BySize, Size};
use geom_core::graph::Ragged;
use geom_core::io::{obj, Faces, MeshOut, Positions};
use geom_core::math::Pt3;
use geom_core::record::Recorder;
use serde::Deserialize;

use crate::deformer::FrameTimings;
use crate::error::{BarNetError, Result};

pub mod arm_muscle;
pub mod elbow_volume;
pub mod nonlinear_vs_fdm;
pub mod scaling;
pub mod stiffness;
pub mod topology;

/// An elbow sweep: `frames` angles evenly from `from_deg` to `to_deg` (at least 2).
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Sweep {
    /// First elbow angle (degrees).
    pub from_deg: f64,
    /// Last elbow angle (degrees).
    pub to_deg: f64,
    /// Frames.
    pub frames: BySize<usize>,
}

impl Sweep {
    /// The elbow angles (rad).
    pub fn angles(&self, size: Size) -> Vec<f64> {
        let n = self.frames.get(size).max(2);
        (0..n)
            .map(|i| (self.from_deg + (self.to_deg - self.from_deg) * i as f64 / (n - 1) as f64).to_radians())
            .collect()
    }
}

/// `Err(Residual)` unless `r` is finite and at most `bound` (spec §7.3 e: every frame of every
/// scene is in equilibrium to 1e-12, `scaling` to 1e-10).
pub fn check_residual(what: &'static str, r: f64, bound: f64) -> Result<()> {
    if r.is_finite() && r <= bound {
        Ok(())
    } else {
        Err(BarNetError::Residual { what, residual: r, bound })
    }
}

/// The frame timings with the median total of `times` (sorted in place; `times` not empty).
pub fn median_timings(times: &mut [FrameTimings]) -> FrameTimings {
    times.sort_by(|x, y| x.total.total_cmp(&y.total));
    times[times.len() / 2]
}

/// Records frame `frame` of sequence `seq` as `seq/NNNN.obj` (polygon faces; f32 or f64
/// positions), unless the recorder discards outputs.
fn poly_frame(rec: &mut dyn Recorder, seq: &str, frame: usize, p: Positions, faces: &Ragged<u32>) -> Result<()> {
    if rec.keeps_outputs() {
        let m = MeshOut { positions: p, faces: Faces::Poly(faces), uv: None, normals: None };
        rec.file(&format!("{seq}/{frame:04}.obj"), obj::to_string(&m)?.as_bytes())?;
    }
    Ok(())
}

/// [`poly_frame`] of a fine mesh (f32 positions).
pub(crate) fn fine_frame(
    rec: &mut dyn Recorder,
    seq: &str,
    f: usize,
    p: &[[f32; 3]],
    faces: &Ragged<u32>,
) -> Result<()> {
    poly_frame(rec, seq, f, Positions::F32(p), faces)
}

/// [`poly_frame`] of a control mesh (f64 positions).
pub(crate) fn control_frame(rec: &mut dyn Recorder, seq: &str, f: usize, p: &[Pt3], faces: &Ragged<u32>) -> Result<()> {
    poly_frame(rec, seq, f, Positions::F64(p), faces)
}

/// `"dev"` or `"release"`: the build the timings come from.
pub fn profile() -> &'static str {
    if cfg!(debug_assertions) {
        "dev"
    } else {
        "release"
    }
}

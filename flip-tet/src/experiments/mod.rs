//! The experiments of spec §6 (S1–S10) and issue 26, each `run(&Params, Size, &mut dyn
//! Recorder) -> Result<Report>` with a serde `Params` (the scene file's `params` block, unknown
//! fields rejected). Every output goes to the recorder the moment it exists; the report holds
//! the figures of `summary.json` and the paper checks.
//!
//! ```no_run
//! use flip_tet::experiments::dam_break;
//! use geom_core::experiment::Size;
//! use geom_core::record::NullRecorder;
//! let report = dam_break::run(&flip_tet::presets::dam_break(), Size::Quick, &mut NullRecorder::default())?;
//! println!("front RMS error {}", report.get_f64("front_rms_rel_err"));
//! # Ok::<(), flip_tet::error::SimError>(())
//! ```

use geom_core::experiment::{BySize, Size};
use geom_core::record::{Recorder, Series};

use crate::error::Result;
use crate::scene::Scene;

pub mod adaptivity_payoff;
pub mod corridor_camera;
pub mod dam_break;
pub mod dam_break_gate;
mod driver;
pub mod drop_pool;
pub mod fvm_vs_nodal;
pub mod holes_plate;
pub mod inflow;
pub mod obstacle_force;
pub mod open_splash;
pub mod probes;
pub mod rest_pool;
mod snapshots;
pub mod standing_wave;
pub mod surface_mixed_radii;

pub use driver::{record_particles, simulate, simulate_frames, FrameLog, FrameOutput, RunOut, SimRun};
pub use snapshots::Snapshots;

/// `scene` with its finest (and optionally coarsest) resolution and duration for `size`.
pub fn sized_scene(
    scene: &Scene,
    finest: &BySize<u32>,
    coarsest: Option<&BySize<u32>>,
    duration: &BySize<f64>,
    size: Size,
) -> Scene {
    let mut s = scene.clone();
    s.resolution.finest = finest.get(size);
    if let Some(c) = coarsest {
        s.resolution.coarsest = c.get(size);
    }
    s.duration = duration.get(size);
    s
}

/// Hands one plot series to the recorder.
pub fn plot(
    rec: &mut dyn Recorder,
    plot: &str,
    label: &str,
    axes: (&str, &str),
    log: (bool, bool),
    points: Vec<(f64, f64)>,
) -> Result<()> {
    rec.series(&Series {
        plot: plot.to_string(),
        label: label.to_string(),
        axes: (axes.0.to_string(), axes.1.to_string()),
        log,
        points,
    })?;
    Ok(())
}

fn one() -> u64 {
    1
}

//! `shells/fold-stress` (shells.md §6 scene 4): a 1 m × 0.5 m silk strip falls edge-first onto a
//! 1 cm capsule, folds onto itself and piles on the ground (h = 1/60): the collision stress test.
//!
//! Figures: `max_intersections`, `nan_steps`, `steps`, the Bridson filter's counts
//! (`ccd_events`, `impact_zones`, `max_zone_size`, `frozen_vertices`, `proximity_pairs`; 0 under
//! IPC), `final_height_span_m` (pile height, m), and the timings `s_per_step`,
//! `collision_share`, `threads`. Frames `frames/NNNN.obj`, tables `steps_frames`,
//! `frames_frames`.
//!
//! ```no_run
//! use geom_core::experiment::Size;
//! use geom_core::record::NullRecorder;
//! #[derive(serde::Deserialize)]
//! struct File { params: shells::experiments::fold_stress::Params }
//! let f: File = ron::from_str(&std::fs::read_to_string("scenes/shells/fold-stress.ron").unwrap()).unwrap();
//! let r = shells::experiments::fold_stress::run(&f.params, Size::Quick, &mut NullRecorder::default()).unwrap();
//! println!("{:?}", r.get("max_intersections"));
//! ```

use geom_core::experiment::{Report, Size};
use geom_core::record::Recorder;

use super::drape::{plan, start};
use super::protocol;
use crate::error::{Error, Result};
use crate::metrics;

/// Parameters (the scene file's `params` block): the same as drape's.
pub type Params = super::drape::Params;

/// Runs the fold.
pub fn run(p: &Params, size: Size, rec: &mut dyn Recorder) -> Result<Report> {
    let shell = protocol::sized(&p.shell, p.resolution.as_ref(), p.duration.as_ref(), size);
    let (mut sim, mut sanity, passive) = start(&shell)?;
    super::contact::record_context(&sim, &shell, rec)?;
    let rs = protocol::run(&mut sim, &plan(&shell, p.frame_every, true, passive), &mut sanity, rec, |_, _| {})?;
    let mut r = Report::default();
    super::contact::sanity_figures(&mut r, "", &sanity, &rs);
    r.count("ccd_events", rs.totals.n_ccd as u64);
    r.count("impact_zones", rs.totals.n_impact_zones as u64);
    r.count("max_zone_size", rs.max_zone as u64);
    r.count("frozen_vertices", rs.totals.n_frozen as u64);
    r.count("proximity_pairs", rs.totals.n_proximity as u64);
    let wall: f64 = rs.step_wall.iter().sum();
    r.timing("collision_share", rs.totals.t_collision / wall.max(1e-300));
    r.timing("s_per_step", rs.s_per_step());
    r.num("final_height_span_m", metrics::height_span(&sim.state().q));
    r.timing("threads", rayon::current_num_threads() as f64);
    if let Some(e) = &rs.error {
        return Err(Error::RunFailed { scene: "fold-stress".into(), steps: rs.steps, message: e.clone() });
    }
    super::contact::checks(&mut r, "", 0.10, passive);
    Ok(r)
}

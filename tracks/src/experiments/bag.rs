//! `tracks/bag` (Bergou et al. 2007 §5.3, Fig. 9): the 88-vertex backflipping bag rig — whose
//! guide self-intersects at the crouch and the landing — tracked by the 1297-vertex vinyl bag
//! through 88 subdivision hats, beside the untracked bag. The tracked output must stay
//! intersection-free.
//!
//! Keys (besides the common ones): `tracked_intersections_max`, `guide_intersections_max`,
//! `guide_self_intersecting_frames`.
//!
//! ```no_run
//! use geom_core::experiment::Size;
//! use geom_core::record::NullRecorder;
//! let text = std::fs::read_to_string("scenes/tracks/bag.ron").unwrap();
//! #[derive(serde::Deserialize)]
//! struct File { params: tracks::experiments::bag::Params }
//! let f: File = ron::from_str(&text).unwrap();
//! let r = tracks::experiments::bag::run(&f.params, Size::Quick, &mut NullRecorder::default()).unwrap();
//! println!("{:?}", r.get("tracked_intersections_max"));
//! ```

use geom_core::experiment::{Report, Size, Target};
use geom_core::record::Recorder;

use super::protocol::{check_residual, check_sanity, run_standard, PairParams};
use crate::error::Result;
use crate::presets::bag_setup;

/// The bag's parameters (the RON `params` block).
pub type Params = PairParams;

/// Runs the bag tracked and untracked, counting self-intersections on every frame.
pub fn run(p: &Params, size: Size, rec: &mut dyn Recorder) -> Result<Report> {
    p.validate("tracks/bag")?;
    let setup = bag_setup(&p.shell(size))?;
    let (out, mut r) = run_standard(p, size, &setup, true, rec)?;
    r.count("tracked_intersections_max", out.isect_tracked.iter().copied().max().unwrap_or(0) as u64);
    r.count("guide_intersections_max", out.isect_guide.iter().copied().max().unwrap_or(0) as u64);
    r.count("guide_self_intersecting_frames", out.isect_guide.iter().filter(|&&x| x > 0).count() as u64);
    r.check(
        "tracked_intersections_max",
        Target::Equals(0.0),
        "Bergou et al. 2007 §5.3: the tracked bag stays intersection-free while its guide self-intersects",
    );
    check_residual(&mut r, "max_residual_pre");
    check_sanity(&mut r);
    Ok(r)
}

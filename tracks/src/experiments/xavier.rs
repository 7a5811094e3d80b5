//! `tracks/xavier` (Bergou et al. 2007 §5.4, Fig. 10): the 3038-vertex X-shaped character
//! stand-in (walk, headwind 4–7 s, electrocution with the CrinkleRest / RestoreRest rest-angle
//! events at 7 and 8.5 s) tracked through 200 animation-aware clustered regions plus 80 on the
//! feet, beside the untracked cloth.
//!
//! Keys (besides the common ones): `rest_event_updates`, `clustering_s`, `regions`,
//! `mesh_min_angle_deg`, `mesh_edge_ratio`.
//!
//! ```no_run
//! use geom_core::experiment::Size;
//! use geom_core::record::NullRecorder;
//! let text = std::fs::read_to_string("scenes/tracks/xavier.ron").unwrap();
//! #[derive(serde::Deserialize)]
//! struct File { params: tracks::experiments::xavier::Params }
//! let f: File = ron::from_str(&text).unwrap();
//! let r = tracks::experiments::xavier::run(&f.params, Size::Quick, &mut NullRecorder::default()).unwrap();
//! println!("{:?}", r.get("coarse_deviation_tracked"));
//! ```

use geom_core::experiment::{Report, Size, Target};
use geom_core::record::Recorder;

use super::protocol::{check_residual, check_sanity, run_standard, PairParams};
use crate::error::Result;
use crate::presets::{xavier_setup, xavier_tf, XAVIER_DURATION};
use crate::procedural::{xavier, xavier_guide};

/// Xavier's parameters (the RON `params` block).
pub type Params = PairParams;

/// Body and feet regions of Xavier's test functions (§5.4: 200 + 80 = 280 constraints).
pub const XAVIER_REGIONS: (usize, usize) = (200, 80);

/// Clusters Xavier's animation and runs it tracked and untracked.
pub fn run(p: &Params, size: Size, rec: &mut dyn Recorder) -> Result<Report> {
    p.validate("tracks/xavier")?;
    let x = xavier()?;
    let guide = xavier_guide(&x, XAVIER_DURATION)?;
    let (tf, clustering_s) = xavier_tf(&x, &guide, XAVIER_REGIONS.0, XAVIER_REGIONS.1)?;
    let k = tf.len();
    let setup = xavier_setup(&x, &guide, tf, &p.shell(size));
    let (out, mut r) = run_standard(p, size, &setup, false, rec)?;
    // Rest-angle updates of the CrinkleRest / RestoreRest blends (0 before 7 s).
    r.count("rest_event_updates", out.rest_updates as u64);
    r.timing("clustering_s", clustering_s);
    r.count("regions", k as u64);
    r.num("mesh_min_angle_deg", x.quality.0);
    r.num("mesh_edge_ratio", x.quality.1);
    r.check("clustering_s", Target::AtMost(60.0), "spec §6.4: clustering well under a minute (paper: < 5 min)");
    check_residual(&mut r, "max_residual_pre");
    check_sanity(&mut r);
    Ok(r)
}

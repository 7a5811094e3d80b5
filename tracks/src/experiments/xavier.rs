//! `tracks/xavier` (Bergou et al. 2007 §5.4, Fig. 10): the 3038-vertex X-shaped character
//! stand-in (walk, headwind 4–7 s, electrocution with the CrinkleRest / RestoreRest rest-angle
//! events at 7 and 8.5 s) tracked through 200 animation-aware clustered regions plus 80 on the
//! feet, beside the untracked cloth.
//!
//! Keys (besides the common ones): `rest_event_updates`, `clustering_s`, `regions`,
//! `mesh_min_angle_deg`, `mesh_edge_ratio`; Fig. 10 (spec §6.4): `feet_coarse_deviation_mean`,
//! `body_coarse_deviation_mean` (D_c restricted to the feet — the 80 finer regions — and to the
//! rest of the body, mean over frames), `feet_over_body_deviation` (their ratio; < 1: the finer
//! test functions echo the guide more closely), the same for the raw RMS ‖d‖
//! (`feet_over_body_rms_deviation`), `detail_amplitude_walk_m` (mean a_d over 0–4 s),
//! `detail_amplitude_headwind_m` (over 4–7 s) and `flutter_ratio` (headwind over walk, ≥ 2:
//! the cloth flutters in the headwind). The Fig. 10 checks are registered when the run covers
//! the headwind window (≥ 7 s, the default run).
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

use super::protocol::{check_residual, check_sanity, run_standard_with, PairParams};
use crate::error::Result;
use crate::metrics::window_mean;
use crate::presets::{xavier_feet, xavier_setup, xavier_tf, XAVIER_DURATION};
use crate::procedural::{xavier, xavier_guide};

/// Xavier's parameters (the RON `params` block).
pub type Params = PairParams;

/// Body and feet regions of Xavier's test functions (§5.4: 200 + 80 = 280 constraints).
pub const XAVIER_REGIONS: (usize, usize) = (200, 80);

/// The headwind window of the clip (s, spec §6.4): wind on from 4 s to 7 s.
pub const HEADWIND: (f64, f64) = (4.0, 7.0);

/// Clusters Xavier's animation and runs it tracked and untracked.
pub fn run(p: &Params, size: Size, rec: &mut dyn Recorder) -> Result<Report> {
    p.validate("tracks/xavier")?;
    let x = xavier()?;
    let guide = xavier_guide(&x, XAVIER_DURATION)?;
    let (tf, clustering_s) = xavier_tf(&x, &guide, XAVIER_REGIONS.0, XAVIER_REGIONS.1)?;
    let k = tf.len();
    let setup = xavier_setup(&x, &guide, tf, &p.shell(size));
    let feet = xavier_feet(&x);
    let is_foot = crate::metrics::vertex_mask(x.mesh.n_vertices(), &feet);
    let body: Vec<u32> = (0..x.mesh.n_vertices() as u32).filter(|&v| !is_foot[v as usize]).collect();
    let (out, mut r) = run_standard_with(p, size, &setup, false, vec![feet, body], rec)?;
    let mean = geom_core::stats::mean;
    let (feet_s, body_s) = (&out.subsets[0], &out.subsets[1]);
    r.num("feet_coarse_deviation_mean", mean(&feet_s.dc));
    r.num("body_coarse_deviation_mean", mean(&body_s.dc));
    r.num("feet_over_body_deviation", mean(&feet_s.dc) / mean(&body_s.dc));
    r.num("feet_over_body_rms_deviation", mean(&feet_s.rms) / mean(&body_s.rms));
    // Frames strictly after the wind switches on (half a frame past 4 s) up to 7 s.
    let t = out.t();
    let walk = window_mean(t, &out.ad_tracked, 0.0, HEADWIND.0);
    let wind = window_mean(t, &out.ad_tracked, HEADWIND.0 + 0.5 / setup.fps, HEADWIND.1);
    r.num("detail_amplitude_walk_m", walk);
    r.num("detail_amplitude_headwind_m", wind);
    r.num("flutter_ratio", wind / walk);
    // Rest-angle updates of the CrinkleRest / RestoreRest blends (0 before 7 s).
    r.count("rest_event_updates", out.rest_updates as u64);
    r.timing("clustering_s", clustering_s);
    r.count("regions", k as u64);
    r.num("mesh_min_angle_deg", x.quality.0);
    r.num("mesh_edge_ratio", x.quality.1);
    r.check("clustering_s", Target::AtMost(60.0), "spec §6.4: clustering well under a minute (paper: < 5 min)");
    if p.duration.get(size) >= HEADWIND.1 {
        let src = "Bergou et al. 2007 §5.4, Fig. 10 (spec §6.4): finer feet regions track closer; \
                   the cloth flutters in the headwind";
        r.check("feet_over_body_deviation", Target::Below(1.0), src);
        r.check("flutter_ratio", Target::AtLeast(2.0), src);
    }
    check_residual(&mut r, "max_residual_pre");
    check_sanity(&mut r);
    Ok(r)
}

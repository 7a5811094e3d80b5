//! `tracks/box` (Bergou et al. 2007 §5.2, Fig. 8): the 8-vertex twisting box guide (twist, hold,
//! untwist, abrupt stop at 4.5 s) tracked by the 1538-vertex rubber box through the 8 hats of
//! its subdivision basis (S̄ = I, S = Pᵀ), bottom face pinned, beside the untracked box.
//!
//! Keys (besides the common ones): `detail_amplitude_2_5s_m`, `detail_amplitude_4_4s_m` (NaN
//! when the run is shorter), `kinetic_energy_end_J`.
//!
//! ```no_run
//! use geom_core::experiment::Size;
//! use geom_core::record::NullRecorder;
//! let text = std::fs::read_to_string("scenes/tracks/box.ron").unwrap();
//! #[derive(serde::Deserialize)]
//! struct File { params: tracks::experiments::box_twist::Params }
//! let f: File = ron::from_str(&text).unwrap();
//! let r = tracks::experiments::box_twist::run(&f.params, Size::Quick, &mut NullRecorder::default()).unwrap();
//! assert!(r.get_f64("max_residual_pre") <= 1e-9);
//! ```

use geom_core::experiment::{Report, Size};
use geom_core::record::Recorder;

use super::protocol::{check_residual, run_standard, PairParams};
use crate::error::Result;
use crate::metrics::value_at;
use crate::presets::box_setup;

/// The box's parameters (the RON `params` block).
pub type Params = PairParams;

/// Runs the box tracked and untracked.
pub fn run(p: &Params, size: Size, rec: &mut dyn Recorder) -> Result<Report> {
    p.validate("tracks/box")?;
    let setup = box_setup(&p.shell(size))?;
    let (out, mut r) = run_standard(p, size, &setup, false, rec)?;
    // Detail at 2.5 s (twisted) and after the abrupt stop (tracked kinetic energy > 0).
    let tol = 0.5 / setup.fps;
    r.num("detail_amplitude_2_5s_m", value_at(out.t(), &out.ad_tracked, 2.5, tol));
    r.num("detail_amplitude_4_4s_m", value_at(out.t(), &out.ad_tracked, 4.4, tol));
    r.num("kinetic_energy_end_J", out.ke_tracked.last().copied().unwrap_or(f64::NAN));
    check_residual(&mut r, "max_residual_pre");
    Ok(r)
}

//! C6 `cloth-fit/validate` (Bhat et al. 2003 §6, Fig. 15; spec §6 C6): "We evaluated the
//! parameters obtained from optimization on longer sequences (150 frames) ... actuated by a
//! robot ... along a simple sinusoidal trajectory." Per fabric: the waving fit, then
//! val_ratio = E_val(p̂)/E_val(p*) on the held-out out-of-plane sinusoid, with truth-versus-fit
//! strips of the validation sequence.
//!
//! ```no_run
//! # fn demo(p: &cloth_fit::experiments::waving::Params) -> cloth_fit::Result<()> {
//! use cloth_fit::experiments::validate::run;
//! use geom_core::experiment::Size;
//! use geom_core::record::NullRecorder;
//! let report = run(p, Size::Quick, &mut NullRecorder::default())?;
//! println!("{:?}", report.get("val_ratio_max"));
//! # Ok(()) }
//! ```

use geom_core::experiment::{Report, Size, Target};
use geom_core::record::Recorder;
use geom_core::stats::max;

use super::waving::{run_all, tables};
use crate::error::{FitError, Result};

/// Scene parameters: the waving protocol's, with `validation_frames` > 0.
pub type Params = super::waving::Params;

/// Runs C6.
pub fn run(p: &Params, size: Size, rec: &mut dyn Recorder) -> Result<Report> {
    if p.validation_frames.get(size) == 0 {
        return Err(FitError::BadParameter("validate needs validation_frames > 0".into()));
    }
    rec.note(&format!("# C6 validation on the held-out robot sinusoid ({} frames)\n", p.validation_frames.get(size)))?;
    tables(rec)?;
    let mut r = Report::default();
    run_all(p, size, rec, &mut r)?;
    let v: Vec<f64> = p.fabrics.iter().map(|f| r.get_f64(&format!("val_ratio_{}", f.name()))).collect();
    r.num("val_ratio_max", max(&v));
    if size == Size::Full {
        r.check("val_ratio_max", Target::AtMost(1.25), "spec §5 / issue 24: validate --full, every fabric");
    }
    Ok(r)
}

//! `tracks/fig3-band` (Bergou et al. 2007 Fig. 3), as a shell ribbon: a 9 × 2-vertex guide
//! ribbon (1 m × 0.05 m) bends into a sine arc of 0.15 m over the first second (quasi-static),
//! then jolts sideways by 0.3 m within 0.1 s at t = 1.5 s; the 65 × 9 tracked ribbon follows its
//! 18 hats (averaged) or 18 anchors (pointwise). Interpolating constraints kink the ribbon.
//!
//! Keys: the common ones of the averaged run, `bend_energy_max_jolt_{averaged,pointwise}_J`,
//! `bend_energy_ratio_pointwise_over_averaged` (max E_bend for t ∈ [1.5, 3] s),
//! `bend_energy_max_quasistatic_*_J` (t ≤ 1.4 s), `tug_index_{pointwise,averaged}_jolt`,
//! `max_residual_pre_pointwise`.
//!
//! ```no_run
//! use geom_core::experiment::Size;
//! use geom_core::record::NullRecorder;
//! let text = std::fs::read_to_string("scenes/tracks/fig3-band.ron").unwrap();
//! #[derive(serde::Deserialize)]
//! struct File { params: tracks::experiments::fig3_band::Params }
//! let f: File = ron::from_str(&text).unwrap();
//! let r = tracks::experiments::fig3_band::run(&f.params, Size::Quick, &mut NullRecorder::default()).unwrap();
//! println!("{:?}", r.get("bend_energy_ratio_pointwise_over_averaged"));
//! ```

use std::sync::Arc;

use geom_core::experiment::{Report, Size};
use geom_core::math::{smoothstep, Pt3, Vec3};
use geom_core::mesh::subdivide_linear;
use geom_core::procedural::{grid, Diagonals, GridSpec, Plane};
use geom_core::record::Recorder;

use super::anchors::{averaged_vs_pointwise, AnchorParams, FPS};
use super::protocol::check_residual;
use crate::error::Result;
use crate::guide::GuideAnimation;
use crate::metrics::window_max;

/// The band's parameters (the RON `params` block).
pub type Params = AnchorParams;

/// The band guide: the 9 × 2 ribbon, its arc and its jolt (3 s).
pub fn band_guide() -> Result<GuideAnimation> {
    let m = grid(&GridSpec {
        quads: [8, 1],
        size: [1.0, 0.05],
        plane: Plane::XZ,
        diagonals: Diagonals::Alternating,
        center: Pt3::new(0.5, 0.0, 0.0),
    })?;
    let rest = m.positions.clone();
    GuideAnimation::procedural(
        m,
        Arc::new(move |t: f64| {
            let arc = smoothstep(0.0, 1.0, t);
            let jolt = smoothstep(1.5, 1.6, t);
            rest.iter()
                .map(|p| p + Vec3::new(0.0, 0.15 * arc * (std::f64::consts::PI * p.x).sin() + 0.3 * jolt, 0.0))
                .collect()
        }),
        3.0,
    )
}

/// Runs the averaged and the pointwise band.
pub fn run(p: &Params, size: Size, rec: &mut dyn Recorder) -> Result<Report> {
    let guide = band_guide()?;
    let (fine, pm) = subdivide_linear(&guide.rest, 3);
    let (avg, pw) = averaged_vs_pointwise(p, size, &guide, &guide, &fine, &pm, None, rec)?;
    let w = |o: &super::protocol::PairOut, a: f64, b: f64, v: &[f64]| window_max(&o.times, v, a, b);
    let mut r = Report::default();
    avg.report(&mut r);
    let (eb_a, eb_p) = (w(&avg, 1.5, 3.0, &avg.bend_tracked), w(&pw, 1.5, 3.0, &pw.bend_tracked));
    r.num("bend_energy_max_jolt_averaged_J", eb_a);
    r.num("bend_energy_max_jolt_pointwise_J", eb_p);
    r.num("bend_energy_ratio_pointwise_over_averaged", eb_p / eb_a);
    r.num("bend_energy_max_quasistatic_averaged_J", w(&avg, 0.0, 1.4, &avg.bend_tracked));
    r.num("bend_energy_max_quasistatic_pointwise_J", w(&pw, 0.0, 1.4, &pw.bend_tracked));
    r.num("tug_index_pointwise_jolt", w(&pw, 1.5, 3.0, &pw.tug_tracked));
    r.num("tug_index_averaged_jolt", w(&avg, 1.5, 3.0, &avg.tug_tracked));
    r.num("max_residual_pre_pointwise", pw.r_pre());
    r.num("duration_s", avg.frames as f64 / FPS);
    r.text("mode", size.name());
    check_residual(&mut r, "max_residual_pre");
    check_residual(&mut r, "max_residual_pre_pointwise");
    Ok(r)
}

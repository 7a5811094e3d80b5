//! `tracks/fig5-heterogeneous` (Bergou et al. 2007 Fig. 5; spec §6.7 heterogeneous variant):
//! spatially varying test functions. Xavier's walk + headwind clip tracked through an
//! animation-aware clustering that is fine on the upper half of the character (r = 256 regions
//! on the vertices above the rest mesh's mid-height) and coarse on the lower half (r = 16),
//! beside the untracked cloth. Finer test functions leave only finer detail to the simulation,
//! so the deviation from the guide has a shorter wavelength on the upper half.
//!
//! Keys (besides the common ones of [`PairOut::report`](super::protocol::PairOut::report)):
//! `wavelength_upper_m`, `wavelength_lower_m` (mean over frames of λ_eff of d = q − q̄
//! restricted to each half, [`LowPass::wavelength_subset`](crate::metrics::LowPass::wavelength_subset);
//! the raw field as in Fig. 6, spec §3.8), `wavelength_upper_over_lower` (< 1),
//! `deviation_upper`, `deviation_lower` (mean area-RMS ‖d‖ / L per half), `regions_upper`,
//! `regions_lower`, `clustering_s`.
//!
//! ```no_run
//! use geom_core::experiment::Size;
//! use geom_core::record::NullRecorder;
//! let text = std::fs::read_to_string("scenes/tracks/fig5-heterogeneous.ron").unwrap();
//! #[derive(serde::Deserialize)]
//! struct File { params: tracks::experiments::fig5_heterogeneous::Params }
//! let f: File = ron::from_str(&text).unwrap();
//! let r = tracks::experiments::fig5_heterogeneous::run(&f.params, Size::Quick, &mut NullRecorder::default()).unwrap();
//! println!("{:?}", r.get("wavelength_upper_over_lower"));
//! ```

use std::time::Instant;

use geom_core::experiment::{Report, Size, Target};
use geom_core::record::{Recorder, Series};
use serde::Deserialize;

use super::protocol::{bad, check_residual, check_sanity, run_standard_with, PairParams};
use crate::cluster::ClusterOptions;
use crate::error::Result;
use crate::presets::{xavier_setup, XAVIER_DURATION};
use crate::procedural::{xavier, xavier_guide, Xavier};
use crate::testfn::{build_test_functions, RegionSel, TestFunctionSpec, TestFunctions};

const SCENE: &str = "tracks/fig5-heterogeneous";

/// Parameters of `tracks/fig5-heterogeneous` (the RON `params` block).
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Params {
    /// Run settings, as in `tracks/xavier`.
    pub run: PairParams,
    /// Regions on the upper half (spec: 256).
    pub upper_regions: usize,
    /// Regions on the lower half (spec: 16).
    pub lower_regions: usize,
}

impl Params {
    /// Checks the run settings and region counts; the message names the field.
    pub fn validate(&self) -> Result<()> {
        self.run.validate(SCENE)?;
        if self.upper_regions == 0 || self.lower_regions == 0 {
            return Err(bad(
                SCENE,
                format!(
                    "upper_regions and lower_regions must be ≥ 1, got {} and {}",
                    self.upper_regions, self.lower_regions
                ),
            ));
        }
        Ok(())
    }
}

/// The vertices of Xavier's rest mesh above (`upper`) and at or below its mid-height.
pub fn halves(x: &Xavier) -> (Vec<u32>, Vec<u32>) {
    let ys = x.mesh.positions.iter().map(|p| p.y);
    let (lo, hi) = ys.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), y| (a.min(y), b.max(y)));
    let mid = 0.5 * (lo + hi);
    (0..x.mesh.n_vertices() as u32).partition(|&v| x.mesh.positions[v as usize].y > mid)
}

/// The heterogeneous test functions: `lower` animation-aware regions on the lower half (the
/// complement of the refined subset) and `upper` on the upper half (μ = 0.98, F = 32, seed 7);
/// returns them and the time taken (s).
pub fn heterogeneous_tf(
    x: &Xavier,
    guide: &crate::guide::GuideAnimation,
    upper_vertices: &[u32],
    upper: usize,
    lower: usize,
) -> Result<(TestFunctions, f64)> {
    let t0 = Instant::now();
    let base = ClusterOptions { regions: lower, mu: 0.98, frames: 32, seed: 7, ..ClusterOptions::default() };
    let spec = TestFunctionSpec::ClusteredWithRefinement {
        base,
        refine: vec![(RegionSel::Vertices(upper_vertices.to_vec()), upper)],
    };
    let tf = build_test_functions(&spec, guide, &x.mesh, None)?;
    Ok((tf, t0.elapsed().as_secs_f64()))
}

/// Clusters Xavier heterogeneously and runs it tracked and untracked.
pub fn run(p: &Params, size: Size, rec: &mut dyn Recorder) -> Result<Report> {
    p.validate()?;
    let x = xavier()?;
    let guide = xavier_guide(&x, XAVIER_DURATION)?;
    let (upper, lower) = halves(&x);
    let (tf, clustering_s) = heterogeneous_tf(&x, &guide, &upper, p.upper_regions, p.lower_regions)?;
    let setup = xavier_setup(&x, &guide, tf, &p.run.shell(size));
    let (out, mut r) = run_standard_with(&p.run, size, &setup, false, vec![upper, lower], rec)?;
    let mean = geom_core::stats::mean;
    let (up, low) = (&out.subsets[0], &out.subsets[1]);
    let (wu, wl) = (mean(&up.lambda_raw), mean(&low.lambda_raw));
    r.num("wavelength_upper_m", wu);
    r.num("wavelength_lower_m", wl);
    r.num("wavelength_upper_over_lower", wu / wl);
    r.num("deviation_upper", mean(&up.rms));
    r.num("deviation_lower", mean(&low.rms));
    r.count("regions_upper", p.upper_regions as u64);
    r.count("regions_lower", p.lower_regions as u64);
    r.timing("clustering_s", clustering_s);
    for (label, s) in [("upper half", up), ("lower half", low)] {
        rec.series(&Series {
            plot: "wavelength_halves".into(),
            label: label.into(),
            axes: ("t (s)".into(), "λ_eff of d (m)".into()),
            log: (false, false),
            points: out.t().iter().copied().zip(s.lambda_raw.iter().copied()).collect(),
        })?;
    }
    r.check(
        "wavelength_upper_over_lower",
        Target::Below(1.0),
        "Bergou et al. 2007 Fig. 5 (spec §6.7): finer test functions on the upper half, finer detail there",
    );
    check_residual(&mut r, "max_residual_pre");
    check_sanity(&mut r);
    Ok(r)
}

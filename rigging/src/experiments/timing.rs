//! `rigging/timing` (paper Table 1; spec §6.2): time per pipeline stage against the vertex count
//! of the test characters, beside the paper's totals.
//!
//! Outputs: table `timing` (seed, target and actual vertices, the eight stage times and the
//! total, s) and the log-log plot `timing` (one series per stage, plus the paper's Table 1).
//!
//! ```no_run
//! use geom_core::experiment::{BySize, Size};
//! use geom_core::record::NullRecorder;
//! use rigging::experiments::timing::{run, Params};
//! let p = Params { vertices: BySize::Same(vec![5000, 30000]), seeds: vec![1000], tau: 0.003 };
//! let r = run(&p, Size::Quick, &mut NullRecorder::default()).unwrap();
//! println!("{} s at 30k vertices", r.get_f64("s_30k"));
//! ```

use geom_core::experiment::{BySize, Report, Size, Target};
use geom_core::record::{Cell, Recorder, Series};
use geom_core::stats;
use serde::Deserialize;

use crate::characters::test_params;
use crate::error::Result;
use crate::presets::humanoid_character;
use crate::{autorig, RigOptions, SkeletonTemplate};

/// Parameters (the scene file's `params` block).
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Params {
    /// Target vertex counts.
    pub vertices: BySize<Vec<usize>>,
    /// Test-character seeds.
    pub seeds: Vec<u64>,
    /// Distance-field tolerance τ (normalized units).
    pub tau: f64,
}

/// The paper's Table 1 totals: (vertices, s) of models 3, 10 and 11.
pub const PAPER_TOTALS: [(f64, f64); 3] = [(19001.0, 12.6), (34339.0, 56.8), (56856.0, 77.1)];

/// Runs the experiment. Figures (all timing, s): `s_30k` (largest total over the seeds at the
/// 30 000-vertex target) and `s_30k_<stage>` (the last seed's stage times there), only when 30 000
/// is among the targets; `profile` (`dev` or `release`).
pub fn run(p: &Params, size: Size, rec: &mut dyn Recorder) -> Result<Report> {
    let counts = p.vertices.get(size);
    let o = RigOptions { tau: p.tau, ..Default::default() };
    let sk = SkeletonTemplate::human();
    let mut header = vec!["seed", "target", "vertices"];
    header.extend(super::TIMING_COLUMNS);
    rec.table("timing", &header)?;
    let names = ["distance_field", "medial", "graph", "discrete", "refine", "attach", "total"];
    let mut series: Vec<Vec<(f64, f64)>> = vec![Vec::new(); names.len()];
    let mut s30: Vec<f64> = Vec::new();
    let mut r = Report::default();
    let total = (p.seeds.len() * counts.len()) as u64;
    for (i, &seed) in p.seeds.iter().enumerate() {
        for (k, &nv) in counts.iter().enumerate() {
            rec.progress((i * counts.len() + k) as u64, total);
            let (mesh, _) = humanoid_character(&test_params(seed), nv)?;
            let rig = autorig(&mesh.positions, &mesh.faces, &sk, &[], &o)?;
            let t = rig.timings;
            let n = mesh.n_vertices();
            let mut cells: Vec<Cell> = vec![(seed as usize).into(), nv.into(), n.into()];
            cells.extend(super::timing_cells(&t));
            rec.row("timing", &cells)?;
            let vals = [t.distance_field, t.medial, t.graph, t.discrete, t.refine, t.attach, t.total()];
            for (k, v) in vals.iter().enumerate() {
                series[k].push((n as f64, v.max(1e-6)));
            }
            if nv == 30000 {
                s30.push(t.total());
                for (k, v) in vals.iter().enumerate() {
                    r.timing(&format!("s_30k_{}", names[k]), *v);
                }
            }
        }
    }
    rec.progress(total, total);
    let axes = ("vertices".to_string(), "seconds".to_string());
    for (k, pts) in series.into_iter().enumerate() {
        rec.series(&Series {
            plot: "timing".into(),
            label: names[k].into(),
            axes: axes.clone(),
            log: (true, true),
            points: pts,
        })?;
    }
    rec.series(&Series {
        plot: "timing".into(),
        label: "paper total (Table 1)".into(),
        axes,
        log: (true, true),
        points: PAPER_TOTALS.to_vec(),
    })?;
    if !s30.is_empty() {
        r.timing("s_30k", stats::max(&s30));
        r.check("s_30k", Target::AtMost(10.0), "spec §5: ≤ 10 s per 33k-vertex character (paper mean 31.3 s)");
    }
    r.text("profile", if cfg!(debug_assertions) { "dev" } else { "release" });
    Ok(r)
}

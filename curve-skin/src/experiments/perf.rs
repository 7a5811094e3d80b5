//! Time per frame against vertex count (spec §5, §6.5): the capsule humanoid subdivided to each
//! target vertex count, posed at one walk frame, deformed by LBS, DQS and curve skin with 1 and
//! 2 threads, positions only and with normals.
//!
//! Outputs: table `perf` (vertices, method, threads, normals, frame s, M vertices/s, prepare s)
//! and plot `time_vs_vertices`. Figures, at the first size ≥ `summary_at_least` vertices (all
//! timing): `<m>_mverts_per_s` (single thread, positions only), `<m>_mverts_per_s_normals`,
//! `<m>_mverts_per_s_<t>t`, `<m>_mverts_per_s_<t>t_normals`, `<m>_prepare_s`,
//! `curve_over_lbs_time_ratio`, `available_threads`; and `summary_vertices`, `profile`.
//!
//! ```no_run
//! use curve_skin::experiments::perf::{run, Params};
//! use geom_core::experiment::Size;
//! use geom_core::record::NullRecorder;
//! let p: Params =
//!     ron::from_str("(vertices: [10000], threads: [1, 2], min_time: 0.05, summary_at_least: 10000)").unwrap();
//! let report = run(&p, Size::Quick, &mut NullRecorder::default()).unwrap();
//! assert!(report.get_f64("curve_mverts_per_s") > 0.0);
//! ```

use std::collections::BTreeMap;
use std::time::Instant;

use geom_core::experiment::{BySize, Report, Size};
use geom_core::record::{Recorder, Series};
use serde::Deserialize;

use crate::error::{Result, SkinError};
use crate::poses::walk_pose;
use crate::presets::{capsule_character, character_skinners, HUMANOID_WEIGHT_THRESHOLD};
use crate::{deform_par, DeformOutput, Skinner};

/// The scene's `params` block.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Params {
    /// Target vertex counts.
    pub vertices: BySize<Vec<usize>>,
    /// Thread counts to time.
    pub threads: Vec<usize>,
    /// Minimum timing window per measurement (s).
    pub min_time: BySize<f64>,
    /// Vertex count (at least) whose figures are reported.
    pub summary_at_least: usize,
}

/// Mean seconds per full deform with `threads` threads (chunks of 4096 vertices), repeated for
/// at least `min_time` seconds and three times.
pub fn time_frames(
    s: &dyn Skinner,
    out: &mut [[f32; 3]],
    nrm: Option<&mut [[f32; 3]]>,
    threads: usize,
    min_time: f64,
) -> Result<f64> {
    let pool = match threads {
        1 => None,
        t => Some(
            rayon::ThreadPoolBuilder::new()
                .num_threads(t)
                .build()
                .map_err(|e| SkinError::Param(format!("a pool of {t} threads: {e}")))?,
        ),
    };
    let mut nrm = nrm;
    let mut run = |out: &mut [[f32; 3]]| {
        let o = DeformOutput { positions: out, normals: nrm.as_deref_mut() };
        match &pool {
            None => s.deform(o),
            Some(pool) => pool.install(|| deform_par(s, o, 4096)),
        }
    };
    run(out);
    let mut reps = 0usize;
    let t0 = Instant::now();
    while t0.elapsed().as_secs_f64() < min_time || reps < 3 {
        run(out);
        reps += 1;
    }
    Ok(t0.elapsed().as_secs_f64() / reps as f64)
}

/// Runs the sweep; see the module docs.
pub fn run(p: &Params, size: Size, rec: &mut dyn Recorder) -> Result<Report> {
    let (counts, min_time) = (p.vertices.get(size), p.min_time.get(size));
    if p.threads.contains(&0) {
        return Err(SkinError::Param("threads must be ≥ 1".into()));
    }
    rec.table("perf", &["vertices", "method", "threads", "normals", "frame_s", "mverts_per_s", "prepare_s"])?;
    let mut rep = Report::default();
    rep.text("profile", if cfg!(debug_assertions) { "debug" } else { "release" });
    // A count that depends on the machine: marked as timing (left out of reproducibility checks).
    rep.count("available_threads", std::thread::available_parallelism().map(|x| x.get()).unwrap_or(1) as u64);
    rep.timing.push("available_threads".into());
    let mut series: BTreeMap<String, Vec<(f64, f64)>> = BTreeMap::new();
    // The reported figures come from the first size ≥ summary_at_least (else the largest).
    let pick = counts.iter().position(|&c| c >= p.summary_at_least).unwrap_or(counts.len().saturating_sub(1));
    for (ci, &target) in counts.iter().enumerate() {
        rec.progress(ci as u64, counts.len() as u64);
        let at_summary = ci == pick;
        let c = capsule_character((target as f64 / 50_000.0).sqrt(), HUMANOID_WEIGHT_THRESHOLD)?;
        let n = c.rest32.len();
        let posed = walk_pose(&c.sk, 0.3).globals(&c.sk);
        let mut methods = character_skinners(&c, true)?;
        let mut out = vec![[0f32; 3]; n];
        let mut nrm = vec![[0f32; 3]; n];
        let mut frame1: BTreeMap<&str, f64> = BTreeMap::new();
        for (m, s) in methods.iter_mut() {
            let t0 = Instant::now();
            let reps = 20;
            for _ in 0..reps {
                s.prepare(&c.sk, &posed)?;
            }
            let tp = t0.elapsed().as_secs_f64() / reps as f64;
            for &th in &p.threads {
                for normals in [false, true] {
                    let nrm = if normals { Some(&mut nrm[..]) } else { None };
                    let dt = time_frames(s.as_ref(), &mut out, nrm, th, min_time)?;
                    let mv = n as f64 / dt / 1e6;
                    let yes = if normals { "yes" } else { "no" };
                    rec.row("perf", &[n.into(), (*m).into(), th.into(), yes.into(), dt.into(), mv.into(), tp.into()])?;
                    if !normals {
                        series.entry(format!("{m} {th}t")).or_default().push((n as f64, dt));
                    }
                    if th == 1 && !normals {
                        frame1.insert(*m, dt);
                    }
                    if at_summary {
                        let suffix = match (th, normals) {
                            (1, false) => String::new(),
                            (1, true) => "_normals".into(),
                            (t, false) => format!("_{t}t"),
                            (t, true) => format!("_{t}t_normals"),
                        };
                        rep.timing(&format!("{m}_mverts_per_s{suffix}"), mv);
                    }
                }
            }
            if at_summary {
                rep.timing(&format!("{m}_prepare_s"), tp);
            }
        }
        if at_summary {
            rep.count("summary_vertices", n as u64);
            if let (Some(cv), Some(lb)) = (frame1.get("curve"), frame1.get("lbs")) {
                rep.timing("curve_over_lbs_time_ratio", cv / lb);
            }
        }
    }
    for (label, points) in series {
        rec.series(&Series {
            plot: "time_vs_vertices".into(),
            label,
            axes: ("vertices".into(), "time per frame (s)".into()),
            log: (true, true),
            points,
        })?;
    }
    Ok(rep)
}

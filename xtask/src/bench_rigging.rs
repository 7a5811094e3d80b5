//! `cargo xtask bench rigging` (spec §9): the accuracy knobs — distance-field tolerance τ,
//! packing cap and refinement iterations — against embedding success, mean joint error and
//! time, on the held-out test characters. Writes `accuracy_vs_time.csv` and `pareto.png`.

use std::time::Instant;

use geom_core::collide::MeshQuery;
use rigging::characters::test_params;
use rigging::eval::score;
use rigging::presets::humanoid_character;
use rigging::{autorig, RigOptions, SkeletonTemplate};

use crate::error::Result;
use crate::out::{CsvWriter, Summary};
use crate::plot::{LinePlot, Series};
use crate::registry::BenchCtx;

/// The benchmark entry point.
pub fn run(ctx: &BenchCtx) -> Result<Summary> {
    let (seeds, nv, taus, caps, iters): (Vec<u64>, usize, Vec<f64>, Vec<usize>, Vec<usize>) = if ctx.quick {
        (vec![1000, 1006, 1012], 6000, vec![0.008, 0.004], vec![250, 1000], vec![0, 10])
    } else {
        ((1000..1016).collect(), 20000, vec![0.012, 0.006, 0.003], vec![250, 500, 1000, 2000], vec![0, 2, 5, 10, 20])
    };
    let sk = SkeletonTemplate::human();
    let chars: Vec<_> = seeds
        .iter()
        .map(|&s| {
            let (m, truth) = humanoid_character(&test_params(s), nv)?;
            let q = MeshQuery::new(&m)?;
            Ok((m, truth, q))
        })
        .collect::<Result<_>>()?;
    let mut csv = CsvWriter::create(
        &ctx.out_dir.join("accuracy_vs_time.csv"),
        &["knob", "value", "success_rate", "mean_err_rel", "mean_time_s", "mean_df_s", "mean_discrete_s"],
    )?;
    let base = RigOptions { tau: if ctx.quick { 0.004 } else { 0.003 }, ..Default::default() };
    let mut configs: Vec<(&str, f64, RigOptions)> = Vec::new();
    for &t in &taus {
        configs.push(("tau", t, RigOptions { tau: t, ..base.clone() }));
    }
    for &c in &caps {
        configs.push(("max_spheres", c as f64, RigOptions { max_spheres: c, ..base.clone() }));
    }
    for &i in &iters {
        configs.push(("refine_iters", i as f64, RigOptions { refine_iters: i, ..base.clone() }));
    }
    let mut pts: Vec<(String, Vec<(f64, f64)>)> = Vec::new();
    let mut s = Summary::new();
    for (knob, value, o) in &configs {
        let (mut ok, mut err, mut t, mut tdf, mut tdi) = (0usize, 0.0, 0.0, 0.0, 0.0);
        for (m, truth, q) in &chars {
            let t0 = Instant::now();
            match autorig(&m.positions, &m.faces, &sk, &[], o) {
                Ok(rig) => {
                    let sc = score(&sk, &rig.joints, &truth.rest, q);
                    ok += sc.ok as usize;
                    err += sc.mean_err_rel;
                    tdf += rig.timings.distance_field;
                    tdi += rig.timings.discrete;
                }
                Err(_) => err += 1.0,
            }
            t += t0.elapsed().as_secs_f64();
        }
        let n = chars.len() as f64;
        csv.row(&[
            (*knob).into(),
            (*value).into(),
            (ok as f64 / n).into(),
            (err / n).into(),
            (t / n).into(),
            (tdf / n).into(),
            (tdi / n).into(),
        ])?;
        match pts.iter_mut().find(|(k, _)| k == knob) {
            Some((_, v)) => v.push((t / n, err / n)),
            None => pts.push((knob.to_string(), vec![(t / n, err / n)])),
        }
        s.set(&format!("{knob}_{value}_success"), ok as f64 / n);
        s.set(&format!("{knob}_{value}_time_s"), t / n);
    }
    let mut plot = LinePlot::new("rigging: joint error vs time", "seconds per character", "mean joint error / height")
        .log(true, true);
    for (k, v) in pts {
        plot = plot.with(Series::new(k, v));
    }
    plot.write_png(&ctx.out_dir.join("pareto.png"))?;
    s.set_count("characters", chars.len() as u64);
    s.set_str("profile", if cfg!(debug_assertions) { "dev" } else { "release" });
    Ok(s)
}

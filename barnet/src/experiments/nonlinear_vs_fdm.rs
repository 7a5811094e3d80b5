//! What the linear method saves (spec §6.6, §9): on the arm's 12-free-node net, elastic bars
//! (a mass–spring-like truss, `s = k (l − L0)`) solved by Newton against the one-solve FDM whose
//! force densities `q = k (1 − L0/l)` match the pretensioned rest state, under biceps loads of
//! growing scale; plus Schek's nonlinear FDM (prescribed forces, fixed point) on a small
//! membrane, whose residual history shows linear convergence (spec §7.5 d).
//!
//! Outputs: tables `metrics` (per load scale), `newton_history`, `fixed_point_history`; plots
//! `shape_difference` and `time`. Figures: `shape_diff_rel_edge_at_scale1` (max position
//! difference ÷ mean edge at scale 1), `newton_iters_max`, `newton_converged_all`,
//! `fixed_point_iters`, `fixed_point_converged`, `fixed_point_contraction_max`,
//! `max_equilibrium_residual`, and the timings `time_ratio_newton_vs_fdm`, `fdm_factor_s`.
//!
//! ```no_run
//! use barnet::experiments::nonlinear_vs_fdm::{run, Params};
//! use geom_core::experiment::Size;
//! use geom_core::record::NullRecorder;
//! let p = Params { load_scales: vec![0.1, 1.0, 10.0], base_load: 0.002, k: 1.0, prestress: 0.9, reps: 1 };
//! let r = run(&p, Size::Quick, &mut NullRecorder::default()).unwrap();
//! assert_eq!(r.get_f64("newton_converged_all"), 1.0);
//! ```

use std::time::Instant;

use geom_core::experiment::{Report, Size, Target};
use geom_core::math::{Pt3, Vec3};
use geom_core::record::{Recorder, Series};
use geom_core::stats::{self, nan_max};
use serde::Deserialize;

use crate::analytic;
use crate::error::Result;
use crate::metrics::{contraction_ratios, history_ratios, max_distance};
use crate::nonlinear::{form_find_nonlinear, Elastic, NewtonOptions, NonlinearModel, NonlinearResult};
use crate::presets::arm_net;
use crate::solver::{FdmOptions, FdmSolver, SolveInfo};

use super::check_residual;

/// The scene's `params` block.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Params {
    /// Multiples of the base load.
    pub load_scales: Vec<f64>,
    /// Base load magnitude on the biceps middle nodes (force units).
    pub base_load: f64,
    /// Bar stiffness k (force per length).
    pub k: f64,
    /// Rest length as a fraction of the modelled length (pretension).
    pub prestress: f64,
    /// Timing repetitions of the FDM solve (the median is reported).
    pub reps: usize,
}

/// Schek's nonlinear FDM (prescribed bar forces s = 1) on a 5 × 5 membrane under a uniform
/// vertical load of 0.01 per free node: the fixed-point run of spec §7.5 a, d.
pub fn fixed_point_membrane() -> Result<NonlinearResult> {
    let mut c = analytic::grid_net(5, 1.0);
    for v in 0..c.net.n_nodes {
        if !c.net.fixed[v] {
            c.loads[v] = Vec3::new(0.0, 0.0, 0.01);
        }
    }
    let (ml, mf) = c.split();
    let (fr, _, _) = c.net.index_maps();
    let mx0: Vec<Pt3> = fr.iter().map(|&v| c.positions[v as usize]).collect();
    let model = NonlinearModel::PrescribedForces { s: vec![1.0; c.net.bars.len()] };
    form_find_nonlinear(&c.net, &model, &ml, &mf, &mx0, &NewtonOptions::default())
}

fn series(plot: &str, label: &str, y: &str, points: Vec<(f64, f64)>) -> Series {
    Series { plot: plot.into(), label: label.into(), axes: ("load scale".into(), y.into()), log: (true, true), points }
}

/// Runs the load sweep and the fixed-point study; see the module docs.
pub fn run(p: &Params, _size: Size, rec: &mut dyn Recorder) -> Result<Report> {
    let an = arm_net()?;
    let (net, xf, xs) = (&an.net, &an.free, &an.fixed);
    let edge = an.mean_edge();
    let k = vec![p.k; net.bars.len()];
    let l0: Vec<f64> = an.bar_len.iter().map(|l| p.prestress * l).collect();
    let zero = vec![Vec3::zeros(); xf.len()];
    let p0 = Elastic::new(net, &k, &l0, &zero, xs, xf).gradient(xf);
    let mut fnet = net.clone();
    for b in &mut fnet.bars {
        b.q = p.k * (1.0 - p.prestress);
    }
    let t0 = Instant::now();
    let fdm = FdmSolver::new(&fnet, &FdmOptions::default())?;
    let t_factor = t0.elapsed().as_secs_f64();
    let model = NonlinearModel::ElasticBars { k: k.clone(), rest_len: l0.clone() };
    rec.table(
        "metrics",
        &[
            "load_scale",
            "shape_diff_rel_edge",
            "fdm_s",
            "newton_s",
            "newton_iters",
            "newton_converged",
            "fdm_residual",
            "max_disp_rel_edge",
        ],
    )?;
    rec.table("newton_history", &["load_scale", "iter", "grad_norm"])?;
    // Every size runs the whole sweep: the 12-free-node net takes milliseconds.
    let (mut diff_pts, mut tf_pts, mut tn_pts) = (Vec::new(), Vec::new(), Vec::new());
    let (mut max_res, mut max_it, mut all_conv, mut ratio_at_1, mut diff_at_1): (f64, usize, bool, f64, f64) =
        (0.0, 0, true, f64::NAN, f64::NAN);
    for (li, &lam) in p.load_scales.iter().enumerate() {
        rec.progress(li as u64, p.load_scales.len() as u64);
        let loads: Vec<Vec3> = p0.iter().zip(&an.biceps_pattern).map(|(a, b)| a + b * (lam * p.base_load)).collect();
        let mut x = Vec::new();
        let mut tf = Vec::new();
        let mut info = SolveInfo::default();
        for _ in 0..p.reps.max(1) {
            let t = Instant::now();
            info = fdm.solve_into(&loads, xs, &mut x)?;
            tf.push(t.elapsed().as_secs_f64());
        }
        let t_fdm = stats::median(&tf);
        check_residual("nonlinear-vs-fdm", info.rel_residual, 1e-12)?;
        max_res = nan_max(max_res, info.rel_residual);
        let t = Instant::now();
        let r = form_find_nonlinear(net, &model, &loads, xs, xf, &NewtonOptions::default())?;
        let t_newton = t.elapsed().as_secs_f64();
        for (i, g) in r.history.iter().enumerate() {
            rec.row("newton_history", &[lam.into(), i.into(), (*g).into()])?;
        }
        let diff = max_distance(&x, &r.x) / edge;
        let disp = max_distance(&r.x, xf) / edge;
        max_it = max_it.max(r.iterations);
        all_conv &= r.converged;
        if (lam - 1.0).abs() < 1e-12 {
            ratio_at_1 = t_newton / t_fdm;
            diff_at_1 = diff;
        }
        diff_pts.push((lam, diff));
        tf_pts.push((lam, t_fdm));
        tn_pts.push((lam, t_newton));
        rec.row(
            "metrics",
            &[
                lam.into(),
                diff.into(),
                t_fdm.into(),
                t_newton.into(),
                r.iterations.into(),
                (r.converged as usize).into(),
                info.rel_residual.into(),
                disp.into(),
            ],
        )?;
    }
    let fp = fixed_point_membrane()?;
    rec.table("fixed_point_history", &["iter", "rel_change", "ratio"])?;
    for (i, (h, r)) in fp.history.iter().zip(history_ratios(&fp.history)).enumerate() {
        rec.row("fixed_point_history", &[i.into(), (*h).into(), r.into()])?;
    }
    let ratios = contraction_ratios(&fp.history);
    rec.series(&series("shape_difference", "difference", "max |x_FDM - x_Newton| / mean edge", diff_pts))?;
    rec.series(&series("time", "FDM (back-substitution)", "time (s)", tf_pts))?;
    rec.series(&series("time", "Newton (elastic bars)", "time (s)", tn_pts))?;
    let mut s = Report::default();
    s.num("max_equilibrium_residual", max_res);
    s.count("newton_iters_max", max_it as u64);
    s.count("newton_converged_all", all_conv as u64);
    s.timing("time_ratio_newton_vs_fdm", ratio_at_1);
    s.num("shape_diff_rel_edge_at_scale1", diff_at_1);
    s.timing("fdm_factor_s", t_factor);
    s.count("fixed_point_iters", fp.iterations as u64);
    s.count("fixed_point_converged", fp.converged as u64);
    if !ratios.is_empty() {
        s.num("fixed_point_contraction_max", stats::max(&ratios));
        s.check("fixed_point_contraction_max", Target::Below(1.0), "spec §7.5 d: contraction ratio < 1");
    }
    s.check("newton_converged_all", Target::Equals(1.0), "spec §7.5 b: Newton converges");
    s.check("fixed_point_converged", Target::Equals(1.0), "spec §7.5 a: the fixed point converges");
    s.check("max_equilibrium_residual", Target::AtMost(1e-12), "spec §7.3 e: every solve in equilibrium");
    Ok(s)
}

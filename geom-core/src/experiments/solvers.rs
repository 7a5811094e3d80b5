//! Accuracy against time of the sparse solvers (the `geom-core` benchmark).
//!
//! Systems: `A = L + M` with `L` the cotangent stiffness matrix and `M` the lumped barycentric
//! mass of a 1 m × 1 m sheet (`procedural::grid`) or a unit sphere (`procedural::icosphere`) —
//! a screened Poisson problem whose condition number grows like 1/h² (h the edge length), the
//! hard case for iterative solvers. Right-hand side `b = M g` with `g` uniform in [−1, 1] (a
//! fixed seed).
//!
//! Per system: full direct factorisation (AMD analysis + numeric Cholesky, `SparseLlt`),
//! numeric-only refactorisation with the cached analysis (what shells pays per step; also timed
//! with faer's Rayon parallelism to show the cost of the deterministic `Par::Seq` default),
//! solve, and IC(0)-preconditioned CG to relative residual 1e-6 and 1e-10 (IC(0) setup
//! included). Plus, per sheet, a saddle-point system `[A Cᵀ; C 0]` with ⌈1 %·n⌉ constraint rows
//! (a barycentric point constraint per row, on evenly spaced faces), solved by `SparseLdlt` with
//! dynamic regularisation and two refinement steps.
//!
//! Times are medians of up to `reps` runs, fewer when an operation takes seconds. Error: relative
//! residual `‖b − A x‖/‖b‖` for every method, and the PCG solution's relative distance to the
//! direct one.
//!
//! Outputs: table `solvers` (one row per system and method), plots `error_vs_time` and
//! `time_vs_n`, a note per system. Figures: `max_residual_direct` (largest direct-solve
//! residual; checked ≤ 1e-10), `kkt_residual` (largest refined saddle-point residual),
//! `largest_sheet_n`, `largest_sheet_pcg_ic0_<tol>_residual`, `largest_sheet_pcg_ic0_<tol>_iters`,
//! and the timings `refactor_speedup` (full ÷ numeric-only factorisation at the largest sheet),
//! `refactor_speedup_target_met` (≥ 1.2), `largest_sheet_full_factor_s`,
//! `largest_sheet_refactor_s`, `largest_sheet_refactor_rayon_s`, `largest_sheet_solve_s`,
//! `largest_sheet_pcg_ic0_<tol>_s`, `threads`, with `profile`.
//!
//! ```no_run
//! use geom_core::experiment::Size;
//! use geom_core::experiments::solvers::{run, Params};
//! use geom_core::record::NullRecorder;
//! let p = Params { sheet_quads: vec![15, 31], sphere_levels: vec![3], reps: 1 };
//! let r = run(&p, Size::Quick, &mut NullRecorder::default()).unwrap();
//! assert!(r.get_f64("max_residual_direct") <= 1e-10);
//! ```

use std::time::Instant;

use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};
use crate::experiment::{Report, Size, Target};
use crate::linalg::{
    pcg, rel_residual, CgOptions, Csc, Csr, Ic0, Ordering, Regularization, SparseLdlt, SparseLlt, Triplets,
};
use crate::mesh::{cotan_stiffness, mass_barycentric, TriMesh};
use crate::procedural::{grid, icosphere, GridSpec};
use crate::record::{Recorder, Series};
use crate::rng::Rng;
use crate::stats::{median, nan_max};

/// Required ratio of full to numeric-only factorisation time at the largest sheet (a timing
/// target: reported and flagged, never a failure).
pub const MIN_REFACTOR_SPEEDUP: f64 = 1.2;
/// Required largest relative residual of the direct solves.
pub const MAX_DIRECT_RESIDUAL: f64 = 1e-10;
/// PCG tolerances (relative residual).
pub const PCG_TOLS: [f64; 2] = [1e-6, 1e-10];
/// Fraction of constraint rows in the saddle-point systems.
const CONSTRAINT_FRACTION: f64 = 0.01;
/// Wall-time budget (s) per timed operation: repetitions stop early once it is spent.
const TIME_BUDGET_S: f64 = 2.0;

/// The systems measured.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Params {
    /// Sheet quads per side (`(q + 1)²` unknowns).
    pub sheet_quads: Vec<u32>,
    /// Icosphere levels (`10·4^l + 2` unknowns).
    pub sphere_levels: Vec<u32>,
    /// Timing repetitions (the median is reported).
    pub reps: usize,
}

impl Params {
    /// The benchmark's sweep: up to ~50k unknowns and 3 repetitions (`quick`), or ~200k and 5.
    pub fn bench(quick: bool) -> Params {
        if quick {
            Params { sheet_quads: vec![31, 63, 127, 223], sphere_levels: vec![4, 5, 6], reps: 3 }
        } else {
            Params { sheet_quads: vec![31, 63, 127, 223, 316, 446], sphere_levels: vec![4, 5, 6, 7], reps: 5 }
        }
    }
}

/// One test system: `A = L + M` and `b = M g` on a mesh.
pub struct System {
    /// `"sheet"` or `"sphere"`.
    pub kind: &'static str,
    /// Unknowns.
    pub n: usize,
    /// The matrix.
    pub a: Csr,
    /// The right-hand side.
    pub b: Vec<f64>,
    /// The mesh.
    pub mesh: TriMesh,
}

impl System {
    fn new(kind: &'static str, mesh: TriMesh, seed: u64) -> System {
        let l = cotan_stiffness(&mesh.faces, &mesh.positions, None);
        let m = mass_barycentric(&mesh.faces, &mesh.positions);
        let a = l.add(&Csr::diag(&m), 1.0, 1.0);
        let mut rng = Rng::new(seed);
        let b: Vec<f64> = m.iter().map(|mi| mi * rng.range(-1.0, 1.0)).collect();
        System { kind, n: a.nrows, a, b, mesh }
    }

    /// The unit sheet with `quads` quads per side.
    pub fn sheet(quads: u32) -> Result<System> {
        let mesh = grid(&GridSpec { quads: [quads, quads], ..GridSpec::default() })?;
        Ok(System::new("sheet", mesh, 0x5EE7 + quads as u64))
    }

    /// The unit icosphere of `level`.
    pub fn sphere(level: u32) -> Result<System> {
        Ok(System::new("sphere", icosphere(1.0, level)?, 0x5F4E + level as u64))
    }
}

/// Median wall time (s) of up to `reps` runs of `f` (at least one; fewer when the runs exceed
/// the time budget together); the last run's value is returned too.
fn time_median<T>(reps: usize, mut f: impl FnMut() -> Result<T>) -> Result<(f64, T)> {
    let mut times: Vec<f64> = Vec::with_capacity(reps);
    let mut last = None;
    while times.len() < reps.max(1) && (times.is_empty() || times.iter().sum::<f64>() < TIME_BUDGET_S) {
        let t0 = Instant::now();
        let v = f()?;
        times.push(t0.elapsed().as_secs_f64());
        last = Some(v);
    }
    // The loop body ran at least once, so `last` is set.
    Ok((median(&times), last.expect("at least one run")))
}

fn norm(v: &[f64]) -> f64 {
    v.iter().map(|x| x * x).sum::<f64>().sqrt()
}

/// Barycentric point constraints on `m` evenly spaced faces: row `r` is
/// `0.2 x_a + 0.3 x_b + 0.5 x_c` of face `r·F/m`.
pub fn constraints(mesh: &TriMesh, m: usize) -> Csr {
    let n = mesh.positions.len();
    let nf = mesh.faces.len();
    let mut t = Triplets::with_capacity(m, n, 3 * m);
    for r in 0..m {
        let f = mesh.faces[r * nf / m];
        for (&v, w) in f.iter().zip([0.2, 0.3, 0.5]) {
            t.push(r as u32, v, w);
        }
    }
    Csr::from_triplets(&t)
}

/// `[A Cᵀ; C 0]` (lower triangle, explicit zero diagonal on the multiplier block).
pub fn kkt_lower(a: &Csr, c: &Csr) -> Csc {
    let (n, m) = (a.nrows, c.nrows);
    let mut t = Triplets::with_capacity(n + m, n + m, a.nnz() + c.nnz() + m);
    for i in 0..n {
        let (cols, vals) = a.row(i);
        for (&j, &v) in cols.iter().zip(vals) {
            t.push(i as u32, j, v);
        }
    }
    for r in 0..m {
        let (cols, vals) = c.row(r);
        for (&j, &v) in cols.iter().zip(vals) {
            t.push((n + r) as u32, j, v);
        }
        t.push((n + r) as u32, (n + r) as u32, 0.0);
    }
    Csr::from_triplets(&t).to_csc_lower()
}

/// One measured method on one system (a row of the `solvers` table).
#[derive(Clone, Debug)]
pub struct MethodRow {
    /// `llt_full`, `llt_refactor`, `llt_refactor_par`, `pcg_ic0`, `ldlt_kkt_refine<k>`.
    pub method: String,
    /// PCG tolerance (0 for direct methods).
    pub tol: f64,
    /// Analysis / preconditioner setup (s).
    pub setup_s: f64,
    /// Numeric factorisation (s).
    pub factor_s: f64,
    /// Solve (s).
    pub solve_s: f64,
    /// Everything (s).
    pub total_s: f64,
    /// PCG iterations or refinement steps.
    pub iters: usize,
    /// `‖b − A x‖/‖b‖`.
    pub rel_residual: f64,
    /// PCG: relative distance to the direct solution.
    pub rel_error: f64,
    /// Non-zeros of the factor.
    pub nnz_l: usize,
}

impl MethodRow {
    fn direct(method: &str, setup_s: f64, factor_s: f64, solve_s: f64, rel_residual: f64, nnz_l: usize) -> Self {
        let total_s = setup_s + factor_s + solve_s;
        MethodRow {
            method: method.into(),
            tol: 0.0,
            setup_s,
            factor_s,
            solve_s,
            total_s,
            iters: 0,
            rel_residual,
            rel_error: 0.0,
            nnz_l,
        }
    }
}

/// Figures of one SPD system.
#[derive(Clone, Debug)]
pub struct SpdFigures {
    /// Full factorisation, numeric-only refactorisation, the same with Rayon, solve (s).
    pub full_s: f64,
    /// Numeric-only refactorisation (s).
    pub refactor_s: f64,
    /// Numeric-only refactorisation with faer's Rayon parallelism (s).
    pub refactor_par_s: f64,
    /// Solve (s).
    pub solve_s: f64,
    /// Direct solve residual.
    pub residual: f64,
    /// Per PCG tolerance: (total s, residual, iterations).
    pub pcg: Vec<(f64, f64, usize)>,
}

/// Measures the SPD solvers on `sys`, appending the table rows.
pub fn measure_spd(sys: &System, reps: usize, rows: &mut Vec<MethodRow>) -> Result<SpdFigures> {
    let csc = sys.a.to_csc_lower();
    let (analyze_s, _) = time_median(reps, || SparseLlt::analyze(&csc, Ordering::Amd))?;
    let (full_s, mut f) = time_median(reps, || {
        let mut f = SparseLlt::analyze(&csc, Ordering::Amd)?;
        f.factor(&csc)?;
        Ok(f)
    })?;
    let (refactor_s, _) = time_median(reps, || f.factor(&csc))?;
    let mut fp = SparseLlt::from_symbolic(&f.symbolic());
    fp.set_par(faer::Par::rayon(rayon::current_num_threads().max(1)));
    let (refactor_par_s, _) = time_median(reps, || fp.factor(&csc))?;
    f.factor(&csc)?;
    let (solve_s, x) = time_median(reps, || {
        let mut x = sys.b.clone();
        f.solve_in_place(&mut x)?;
        Ok(x)
    })?;
    let residual = rel_residual(&csc, &x, &sys.b);
    let nx = norm(&x);
    let nnz_l = f.nnz_l();
    rows.push(MethodRow::direct("llt_full", analyze_s, full_s - analyze_s, solve_s, residual, nnz_l));
    rows.push(MethodRow::direct("llt_refactor", 0.0, refactor_s, solve_s, residual, nnz_l));
    rows.push(MethodRow::direct("llt_refactor_par", 0.0, refactor_par_s, solve_s, residual, nnz_l));
    let mut pcg_fig = Vec::new();
    for tol in PCG_TOLS {
        let (setup_s, ic) = time_median(reps, || Ic0::new(&sys.a, None))?;
        let opts = CgOptions { tol, max_iters: 50_000, history: false };
        let (iter_s, (y, rep)) = time_median(reps, || {
            let mut y = vec![0.0; sys.n];
            let rep = pcg(&sys.a, &sys.b, &mut y, &ic, &opts)?;
            Ok((y, rep))
        })?;
        if !rep.converged {
            return Err(Error::NotConverged { iters: rep.iters, rel_residual: rep.rel_residual });
        }
        let err = norm(&y.iter().zip(&x).map(|(p, q)| p - q).collect::<Vec<_>>()) / nx;
        rows.push(MethodRow {
            method: "pcg_ic0".into(),
            tol,
            setup_s,
            factor_s: 0.0,
            solve_s: iter_s,
            total_s: setup_s + iter_s,
            iters: rep.iters,
            rel_residual: rep.rel_residual,
            rel_error: err,
            nnz_l: 0,
        });
        pcg_fig.push((setup_s + iter_s, rep.rel_residual, rep.iters));
    }
    Ok(SpdFigures { full_s, refactor_s, refactor_par_s, solve_s, residual, pcg: pcg_fig })
}

/// Measures the saddle-point system of a sheet; returns the refined residual.
pub fn measure_kkt(sys: &System, reps: usize, rows: &mut Vec<MethodRow>) -> Result<f64> {
    let m = ((CONSTRAINT_FRACTION * sys.n as f64).ceil() as usize).max(1);
    let k = kkt_lower(&sys.a, &constraints(&sys.mesh, m));
    let nk = sys.n + m;
    let mut b = sys.b.clone();
    // Constraint targets: small prescribed values (an arbitrary consistent right-hand side).
    let mut rng = Rng::new(0xC0_FFEE + sys.n as u64);
    b.extend((0..m).map(|_| rng.range(-0.01, 0.01)));
    let reg = Regularization::kkt(sys.n, m);
    let (analyze_s, _) = time_median(reps, || SparseLdlt::analyze(&k, Ordering::Amd))?;
    let mut f = SparseLdlt::analyze(&k, Ordering::Amd)?;
    let (factor_s, _) = time_median(reps, || f.factor(&k, &reg))?;
    let mut x = vec![0.0; nk];
    let (solve0_s, r0) = time_median(reps, || f.solve_refined(&k, &b, &mut x, 0))?;
    let (solve_s, r2) = time_median(reps, || f.solve_refined(&k, &b, &mut x, 2))?;
    for (steps, s, r) in [(0usize, solve0_s, r0), (2, solve_s, r2)] {
        let mut row = MethodRow::direct(&format!("ldlt_kkt_refine{steps}"), analyze_s, factor_s, s, r, f.nnz_l());
        row.iters = steps;
        rows.push(row);
    }
    Ok(r2)
}

fn push_point(v: &mut Vec<Series>, plot: &str, label: String, axes: (&str, &str), p: (f64, f64)) {
    match v.iter_mut().find(|s| s.plot == plot && s.label == label) {
        Some(s) => s.points.push(p),
        None => v.push(Series {
            plot: plot.into(),
            label,
            axes: (axes.0.into(), axes.1.into()),
            log: (true, true),
            points: vec![p],
        }),
    }
}

/// Measures every system; see the module docs.
pub fn run(p: &Params, _size: Size, rec: &mut dyn Recorder) -> Result<Report> {
    rec.table(
        "solvers",
        &[
            "mesh",
            "n",
            "nnz",
            "method",
            "tol",
            "setup_s",
            "factor_s",
            "solve_s",
            "total_s",
            "iters",
            "rel_residual",
            "rel_error",
            "nnz_l",
        ],
    )?;
    let (mut max_direct, mut max_kkt): (f64, f64) = (0.0, 0.0);
    let mut largest_sheet: Option<(usize, SpdFigures)> = None;
    let mut series: Vec<Series> = Vec::new();
    let systems: Vec<(&str, u32)> =
        p.sheet_quads.iter().map(|&q| ("sheet", q)).chain(p.sphere_levels.iter().map(|&l| ("sphere", l))).collect();
    for (si, &(kind, param)) in systems.iter().enumerate() {
        rec.progress(si as u64, systems.len() as u64);
        let sys = if kind == "sheet" { System::sheet(param)? } else { System::sphere(param)? };
        let mut rows = Vec::new();
        let meas = measure_spd(&sys, p.reps, &mut rows)?;
        if kind == "sheet" {
            max_kkt = nan_max(max_kkt, measure_kkt(&sys, p.reps, &mut rows)?);
        }
        max_direct = nan_max(max_direct, meas.residual);
        for r in &rows {
            rec.row(
                "solvers",
                &[
                    kind.into(),
                    sys.n.into(),
                    sys.a.nnz().into(),
                    r.method.clone().into(),
                    r.tol.into(),
                    r.setup_s.into(),
                    r.factor_s.into(),
                    r.solve_s.into(),
                    r.total_s.into(),
                    r.iters.into(),
                    r.rel_residual.into(),
                    r.rel_error.into(),
                    r.nnz_l.into(),
                ],
            )?;
            let label = if r.method == "pcg_ic0" {
                format!("{kind} IC(0)-PCG {:.0e}", r.tol)
            } else {
                format!("{kind} {}", r.method)
            };
            let res_axes = ("time (s)", "relative residual |b - Ax| / |b|");
            push_point(&mut series, "error_vs_time", label.clone(), res_axes, (r.total_s, r.rel_residual));
            push_point(&mut series, "time_vs_n", label, ("unknowns n", "time (s)"), (sys.n as f64, r.total_s));
        }
        rec.note(&format!(
            "{kind:6} n = {:6}: full {:.3} s, refactor {:.3} s (rayon {:.3} s), solve {:.4} s, residual {:.1e}; PCG {:?}",
            sys.n, meas.full_s, meas.refactor_s, meas.refactor_par_s, meas.solve_s, meas.residual, meas.pcg
        ))?;
        if kind == "sheet" && largest_sheet.as_ref().is_none_or(|(n, _)| sys.n > *n) {
            largest_sheet = Some((sys.n, meas));
        }
    }
    for s in &series {
        rec.series(s)?;
    }
    let (n_big, big) = largest_sheet.ok_or_else(|| Error::InvalidParameter("solvers: sheet_quads is empty".into()))?;
    let mut s = Report::default();
    let speedup = big.full_s / big.refactor_s;
    s.timing("refactor_speedup", speedup);
    s.num("max_residual_direct", max_direct);
    s.num("kkt_residual", max_kkt);
    s.count("largest_sheet_n", n_big as u64);
    s.timing("largest_sheet_full_factor_s", big.full_s);
    s.timing("largest_sheet_refactor_s", big.refactor_s);
    s.timing("largest_sheet_refactor_rayon_s", big.refactor_par_s);
    s.timing("largest_sheet_solve_s", big.solve_s);
    for (tol, (t, r, it)) in PCG_TOLS.iter().zip(&big.pcg) {
        let tag = format!("{tol:.0e}");
        s.timing(&format!("largest_sheet_pcg_ic0_{tag}_s"), *t);
        s.num(&format!("largest_sheet_pcg_ic0_{tag}_residual"), *r);
        s.count(&format!("largest_sheet_pcg_ic0_{tag}_iters"), *it as u64);
    }
    // Machine-dependent counts: marked as timing (left out of reproducibility checks).
    s.count("threads", rayon::current_num_threads() as u64);
    s.count("refactor_speedup_target_met", u64::from(speedup >= MIN_REFACTOR_SPEEDUP));
    s.timing.extend(["threads".to_string(), "refactor_speedup_target_met".to_string()]);
    s.text("profile", if cfg!(debug_assertions) { "dev" } else { "release" });
    s.check("max_residual_direct", Target::AtMost(MAX_DIRECT_RESIDUAL), "direct solves to 1e-10");
    s.check("refactor_speedup", Target::AtLeast(MIN_REFACTOR_SPEEDUP), "the cached analysis pays (timing)");
    Ok(s)
}

//! `cargo xtask bench geom-core`: accuracy versus time of the sparse solvers.
//!
//! Systems: `A = L + M` with `L` the cotangent stiffness matrix and `M` the lumped barycentric
//! mass of a 1 m × 1 m sheet (`procedural::grid`) or a unit sphere (`procedural::icosphere`) —
//! a screened Poisson problem whose condition number grows like 1/h² (h the edge length), the
//! hard case for iterative solvers. Sizes from ~1k to ~200k unknowns (quick: up to ~50k).
//! Right-hand side `b = M g` with `g` uniform in [−1, 1] (a fixed seed).
//!
//! Per system: full direct factorisation (AMD analysis + numeric Cholesky, `SparseLlt`),
//! numeric-only refactorisation with the cached analysis (what shells pays per step; also timed
//! with faer's Rayon parallelism to show the cost of the deterministic `Par::Seq` default),
//! solve, and IC(0)-preconditioned CG to relative residual 1e-6 and 1e-10 (IC(0) setup included).
//! Plus, per sheet, a saddle-point system `[A Cᵀ; C 0]` with ⌈1 %·n⌉ constraint rows (a
//! barycentric point constraint per row, on evenly spaced faces), solved by `SparseLdlt` with
//! dynamic regularisation and two refinement steps.
//!
//! Times are medians of up to 3 (quick) or 5 runs, fewer when an operation takes seconds
//! (release build recommended; other load on the machine shows up directly). Error: relative residual
//! `‖b − A x‖/‖b‖` for every method, and the PCG solution's relative distance to the direct one.
//!
//! Writes `solvers.csv`, `error_vs_time.png`, `time_vs_n.png` and the summary: `refactor_speedup`
//! (full / numeric-only factorisation at the largest sheet; must be ≥ 1.2),
//! `max_residual_direct` (largest direct-solve residual; must be ≤ 1e-10), `kkt_residual`
//! (largest refined saddle-point residual), and timings at the largest sheet. A violated
//! residual requirement is an error (the files and summary are still written); a speedup below its
//! target is reported and flagged (`refactor_speedup_target_met`), since timings on a shared
//! machine are noisy.

use std::time::Instant;

use geom_core::linalg::{
    pcg, rel_residual, CgOptions, Csc, Csr, Ic0, Ordering, Regularization, SparseLdlt, SparseLlt, Triplets,
};
use geom_core::mesh::{cotan_stiffness, mass_barycentric, TriMesh};
use geom_core::procedural::{grid, icosphere, GridSpec};
use geom_core::rng::Rng;

use crate::error::{Error, Result};
use crate::out::{Cell, CsvWriter, Summary};
use crate::plot::{LinePlot, Series};
use crate::registry::BenchCtx;

/// Required ratio of full to numeric-only factorisation time at the largest sheet.
const MIN_REFACTOR_SPEEDUP: f64 = 1.2;
/// Required largest relative residual of the direct solves.
const MAX_DIRECT_RESIDUAL: f64 = 1e-10;
/// PCG tolerances (relative residual).
const PCG_TOLS: [f64; 2] = [1e-6, 1e-10];
/// Fraction of constraint rows in the saddle-point systems.
const CONSTRAINT_FRACTION: f64 = 0.01;

/// One test system.
struct System {
    kind: &'static str,
    n: usize,
    a: Csr,
    b: Vec<f64>,
    mesh: TriMesh,
}

fn build(kind: &'static str, mesh: TriMesh, seed: u64) -> System {
    let l = cotan_stiffness(&mesh.faces, &mesh.positions, None);
    let m = mass_barycentric(&mesh.faces, &mesh.positions);
    let a = l.add(&Csr::diag(&m), 1.0, 1.0);
    let mut rng = Rng::new(seed);
    let b: Vec<f64> = m.iter().map(|mi| mi * rng.range(-1.0, 1.0)).collect();
    System { kind, n: a.nrows, a, b, mesh }
}

fn sheet(quads: u32) -> Result<System> {
    let mesh = grid(&GridSpec { quads: [quads, quads], ..GridSpec::default() })?;
    Ok(build("sheet", mesh, 0x5EE7 + quads as u64))
}

fn sphere(level: u32) -> Result<System> {
    Ok(build("sphere", icosphere(1.0, level)?, 0x5F4E + level as u64))
}

/// Wall-time budget (s) per timed operation: repetitions stop early once it is spent.
const TIME_BUDGET_S: f64 = 2.0;

/// Median wall time (s) of up to `reps` runs of `f` (at least one; fewer when the runs exceed
/// [`TIME_BUDGET_S`] together); the last run's value is returned too.
fn time_median<T>(reps: usize, mut f: impl FnMut() -> Result<T>) -> Result<(f64, T)> {
    let mut times: Vec<f64> = Vec::with_capacity(reps);
    let mut last = None;
    while times.len() < reps.max(1) && (times.is_empty() || times.iter().sum::<f64>() < TIME_BUDGET_S) {
        let t0 = Instant::now();
        let v = f()?;
        times.push(t0.elapsed().as_secs_f64());
        last = Some(v);
    }
    times.sort_by(f64::total_cmp);
    // The loop body ran at least once, so `last` is set.
    Ok((times[times.len() / 2], last.expect("at least one run")))
}

fn norm(v: &[f64]) -> f64 {
    v.iter().map(|x| x * x).sum::<f64>().sqrt()
}

/// Barycentric point constraints on `m` evenly spaced faces: row `r` is
/// `0.2 x_a + 0.3 x_b + 0.5 x_c` of face `r·F/m`.
fn constraints(mesh: &TriMesh, m: usize) -> Csr {
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
fn kkt_lower(a: &Csr, c: &Csr) -> Csc {
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

/// One CSV row.
struct Row {
    method: String,
    tol: f64,
    setup_s: f64,
    factor_s: f64,
    solve_s: f64,
    total_s: f64,
    iters: usize,
    rel_residual: f64,
    rel_error: f64,
    nnz_l: usize,
}

/// Figures of one SPD system kept for the summary.
struct Measured {
    full_s: f64,
    refactor_s: f64,
    refactor_par_s: f64,
    solve_s: f64,
    residual: f64,
    pcg: Vec<(f64, f64, usize)>,
}

fn core(e: geom_core::Error) -> Error {
    Error::Core(e)
}

fn measure_spd(sys: &System, reps: usize, rows: &mut Vec<Row>) -> Result<Measured> {
    let csc = sys.a.to_csc_lower();
    let (analyze_s, _) = time_median(reps, || SparseLlt::analyze(&csc, Ordering::Amd).map_err(core))?;
    let (full_s, mut f) = time_median(reps, || {
        let mut f = SparseLlt::analyze(&csc, Ordering::Amd).map_err(core)?;
        f.factor(&csc).map_err(core)?;
        Ok(f)
    })?;
    let (refactor_s, _) = time_median(reps, || f.factor(&csc).map_err(core))?;
    let mut fp = SparseLlt::from_symbolic(&f.symbolic());
    fp.set_par(geom_core::faer::Par::rayon(rayon::current_num_threads().max(1)));
    let (refactor_par_s, _) = time_median(reps, || fp.factor(&csc).map_err(core))?;
    f.factor(&csc).map_err(core)?;
    let (solve_s, x) = time_median(reps, || {
        let mut x = sys.b.clone();
        f.solve_in_place(&mut x).map_err(core)?;
        Ok(x)
    })?;
    let residual = rel_residual(&csc, &x, &sys.b);
    let nx = norm(&x);
    let nnz_l = f.nnz_l();
    rows.push(Row {
        method: "llt_full".into(),
        tol: 0.0,
        setup_s: analyze_s,
        factor_s: full_s - analyze_s,
        solve_s,
        total_s: full_s + solve_s,
        iters: 0,
        rel_residual: residual,
        rel_error: 0.0,
        nnz_l,
    });
    rows.push(Row {
        method: "llt_refactor".into(),
        tol: 0.0,
        setup_s: 0.0,
        factor_s: refactor_s,
        solve_s,
        total_s: refactor_s + solve_s,
        iters: 0,
        rel_residual: residual,
        rel_error: 0.0,
        nnz_l,
    });
    rows.push(Row {
        method: "llt_refactor_par".into(),
        tol: 0.0,
        setup_s: 0.0,
        factor_s: refactor_par_s,
        solve_s,
        total_s: refactor_par_s + solve_s,
        iters: 0,
        rel_residual: residual,
        rel_error: 0.0,
        nnz_l,
    });
    let mut pcg_fig = Vec::new();
    for tol in PCG_TOLS {
        let (setup_s, ic) = time_median(reps, || Ic0::new(&sys.a, None).map_err(core))?;
        let opts = CgOptions { tol, max_iters: 50_000, history: false };
        let (iter_s, (y, rep)) = time_median(reps, || {
            let mut y = vec![0.0; sys.n];
            let rep = pcg(&sys.a, &sys.b, &mut y, &ic, &opts).map_err(core)?;
            Ok((y, rep))
        })?;
        if !rep.converged {
            return Err(Error::Run(format!(
                "geom-core bench: IC(0)-PCG did not reach {tol:e} on the {} with n = {} ({} iterations, residual {:e})",
                sys.kind, sys.n, rep.iters, rep.rel_residual
            )));
        }
        let err = norm(&y.iter().zip(&x).map(|(p, q)| p - q).collect::<Vec<_>>()) / nx;
        rows.push(Row {
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
    Ok(Measured { full_s, refactor_s, refactor_par_s, solve_s, residual, pcg: pcg_fig })
}

/// Saddle-point system of a sheet: returns the refined residual.
fn measure_kkt(sys: &System, reps: usize, rows: &mut Vec<Row>) -> Result<f64> {
    let m = ((CONSTRAINT_FRACTION * sys.n as f64).ceil() as usize).max(1);
    let c = constraints(&sys.mesh, m);
    let k = kkt_lower(&sys.a, &c);
    let nk = sys.n + m;
    let mut b = sys.b.clone();
    // Constraint targets: small prescribed values (an arbitrary consistent right-hand side).
    let mut rng = Rng::new(0xC0_FFEE + sys.n as u64);
    b.extend((0..m).map(|_| rng.range(-0.01, 0.01)));
    let reg = Regularization::kkt(sys.n, m);
    let (analyze_s, _) = time_median(reps, || SparseLdlt::analyze(&k, Ordering::Amd).map_err(core))?;
    let mut f = SparseLdlt::analyze(&k, Ordering::Amd).map_err(core)?;
    let (factor_s, _) = time_median(reps, || f.factor(&k, &reg).map_err(core))?;
    let mut x = vec![0.0; nk];
    let (solve0_s, r0) = time_median(reps, || f.solve_refined(&k, &b, &mut x, 0).map_err(core))?;
    let (solve_s, r2) = time_median(reps, || f.solve_refined(&k, &b, &mut x, 2).map_err(core))?;
    for (steps, s, r) in [(0usize, solve0_s, r0), (2, solve_s, r2)] {
        rows.push(Row {
            method: format!("ldlt_kkt_refine{steps}"),
            tol: 0.0,
            setup_s: analyze_s,
            factor_s,
            solve_s: s,
            total_s: analyze_s + factor_s + s,
            iters: steps,
            rel_residual: r,
            rel_error: 0.0,
            nnz_l: f.nnz_l(),
        });
    }
    Ok(r2)
}

/// Appends `p` to the series called `label`, creating it on first use.
fn push_point(v: &mut Vec<Series>, label: String, p: (f64, f64)) {
    match v.iter_mut().find(|s| s.label == label) {
        Some(s) => s.points.push(p),
        None => v.push(Series::new(label, vec![p])),
    }
}

/// The benchmark entry point.
pub fn run(ctx: &BenchCtx) -> Result<Summary> {
    // Sheet quads per side → (q+1)² unknowns; icosphere level l → 10·4^l + 2 unknowns.
    let (sheet_quads, sphere_levels, reps): (Vec<u32>, Vec<u32>, usize) = if ctx.quick {
        (vec![31, 63, 127, 223], vec![4, 5, 6], 3)
    } else {
        (vec![31, 63, 127, 223, 316, 446], vec![4, 5, 6, 7], 5)
    };
    let mut csv = CsvWriter::create(
        &ctx.out_dir.join("solvers.csv"),
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
    let mut s = Summary::new();
    let mut max_direct: f64 = 0.0;
    let mut max_kkt: f64 = 0.0;
    let mut largest_sheet: Option<(usize, Measured)> = None;
    let mut series: Vec<Series> = Vec::new();
    let mut scaling: Vec<Series> = Vec::new();
    let systems = sheet_quads.iter().map(|&q| ("sheet", q)).chain(sphere_levels.iter().map(|&l| ("sphere", l)));
    for (kind, param) in systems {
        let sys = if kind == "sheet" { sheet(param)? } else { sphere(param)? };
        let mut rows = Vec::new();
        let meas = measure_spd(&sys, reps, &mut rows)?;
        if kind == "sheet" {
            max_kkt = max_kkt.max(measure_kkt(&sys, reps, &mut rows)?);
        }
        max_direct = max_direct.max(meas.residual);
        for r in &rows {
            csv.row(&[
                Cell::Text(kind.into()),
                Cell::from(sys.n),
                Cell::from(sys.a.nnz()),
                Cell::Text(r.method.clone()),
                Cell::Num(r.tol),
                Cell::Num(r.setup_s),
                Cell::Num(r.factor_s),
                Cell::Num(r.solve_s),
                Cell::Num(r.total_s),
                Cell::from(r.iters),
                Cell::Num(r.rel_residual),
                Cell::Num(r.rel_error),
                Cell::from(r.nnz_l),
            ])?;
            let label = if r.method == "pcg_ic0" {
                format!("{kind} IC(0)-PCG {:.0e}", r.tol)
            } else {
                format!("{kind} {}", r.method)
            };
            push_point(&mut series, label.clone(), (r.total_s, r.rel_residual));
            push_point(&mut scaling, label, (sys.n as f64, r.total_s));
        }
        println!(
            "  {kind:6} n = {:6}: full {:.3} s, refactor {:.3} s (rayon {:.3} s), solve {:.4} s, residual {:.1e}; PCG {:?}",
            sys.n, meas.full_s, meas.refactor_s, meas.refactor_par_s, meas.solve_s, meas.residual, meas.pcg
        );
        if kind == "sheet" && largest_sheet.as_ref().is_none_or(|(n, _)| sys.n > *n) {
            largest_sheet = Some((sys.n, meas));
        }
    }
    let mut err_plot =
        LinePlot::new("geom-core solvers: residual vs time", "time (s)", "relative residual |b - Ax| / |b|")
            .log(true, true);
    err_plot.series = series;
    err_plot.write_png(&ctx.out_dir.join("error_vs_time.png"))?;
    let mut n_plot = LinePlot::new("geom-core solvers: time vs size", "unknowns n", "time (s)").log(true, true);
    n_plot.series = scaling;
    n_plot.write_png(&ctx.out_dir.join("time_vs_n.png"))?;

    let (n_big, big) = largest_sheet.ok_or_else(|| Error::Run("geom-core bench: no sheet measured".into()))?;
    let speedup = big.full_s / big.refactor_s;
    s.set("refactor_speedup", speedup);
    s.set("max_residual_direct", max_direct);
    s.set("kkt_residual", max_kkt);
    s.set_count("largest_sheet_n", n_big as u64);
    s.set("largest_sheet_full_factor_s", big.full_s);
    s.set("largest_sheet_refactor_s", big.refactor_s);
    s.set("largest_sheet_refactor_rayon_s", big.refactor_par_s);
    s.set("largest_sheet_solve_s", big.solve_s);
    for (tol, (t, r, it)) in PCG_TOLS.iter().zip(&big.pcg) {
        let tag = format!("{tol:.0e}");
        s.set(&format!("largest_sheet_pcg_ic0_{tag}_s"), *t);
        s.set(&format!("largest_sheet_pcg_ic0_{tag}_residual"), *r);
        s.set_count(&format!("largest_sheet_pcg_ic0_{tag}_iters"), *it as u64);
    }
    s.set_count("threads", rayon::current_num_threads() as u64);
    s.set_str("profile", if cfg!(debug_assertions) { "dev" } else { "release" });

    // A timing ratio is a measurement, not an invariant: on a loaded machine it can miss its
    // target, so it is reported (and flagged), never turned into a failure. Residuals are invariants.
    s.set_count("refactor_speedup_target_met", u64::from(speedup >= MIN_REFACTOR_SPEEDUP));
    if speedup < MIN_REFACTOR_SPEEDUP {
        eprintln!("warning: refactor_speedup = {speedup:.3} < {MIN_REFACTOR_SPEEDUP} (timing noise or a real regression: rerun on an idle machine)");
    }
    let mut failures = Vec::new();
    if max_direct > MAX_DIRECT_RESIDUAL {
        failures.push(format!("max_residual_direct = {max_direct:e} > {MAX_DIRECT_RESIDUAL:e}"));
    }
    if !failures.is_empty() {
        s.write(&ctx.out_dir)?;
        return Err(Error::Run(format!("geom-core bench: {}", failures.join("; "))));
    }
    Ok(s)
}

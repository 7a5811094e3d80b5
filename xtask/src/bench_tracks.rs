//! `cargo xtask bench tracks` (spec §9): what accuracy costs in time, over library calls of
//! `tracks::experiments`.
//! 1. The Xavier clip with uniform animation-aware clusterings of 16, 64, 256 (and 1024) regions
//!    ([`partition_study`]): deviation and wavelength of the deviation field against the time
//!    per frame (`partitions.csv` and the four PNGs of the partition study).
//! 2. The exact KKT methods (constraint-last LDLᵀ, AMD-regularised LDLᵀ, bordered-LLᵀ Schur) at
//!    r = 0 (no constraint: the untracked path), 16, 64, 256 (and 1024) regions on the same clip:
//!    KKT solve time per step, stored factor entries and overhead against the multiplier rows 3K
//!    (`kkt_vs_regions.csv`, `overhead_vs_constraints.png`, `solve_ms_vs_constraints.png`).
//! 3. The tracked flag (spec §9 sweep 3): substeps × IPC Newton iteration caps ∈ {1, 3} against
//!    a fine-step reference (32 substeps, ≤ 10 Newton iterations, Newton tolerance 1e-4 m/s;
//!    quick: 16 substeps): mean vertex-RMS distance to the reference / L, D_c and a_d against
//!    milliseconds per frame (`flag_steps.csv`, `flag_error_vs_ms.png`).
//! 4. The box (collisions off): penalty stiffness k_p against the exact Lagrange multipliers —
//!    largest pre-collision residual / L against KKT milliseconds per step
//!    (`penalty_vs_lagrange.csv`, `penalty_vs_lagrange.png`).

use geom_core::experiment::Report;
use geom_core::math::Pt3;
use geom_core::record::{Cell, MemoryRecorder, Recorder, Series};
use shells::ContactMethod;
use tracks::experiments::fig6_partitions::{partition_keys, partition_study, record_partitions, PartitionRow, Solvers};
use tracks::experiments::flag::PREVIEW_DURATION;
use tracks::experiments::protocol::{run_pair, track_opts, PairOpts, PairOut};
use tracks::presets::{box_setup, flag_design, flag_setup, frames_for, FlagDesign, ShellOptions};
use tracks::KktMethod;

use crate::error::Result;
use crate::out::Summary;
use crate::record::FileRecorder;
use crate::registry::BenchCtx;

/// The contact model of every shell in the bench (the shells default).
const CONTACT: ContactMethod = ContactMethod::Ipc;

/// The fine shell of sweeps 1 and 2 (Xavier, no self-collision) and 3 (the box).
fn shell() -> ShellOptions {
    ShellOptions { substeps: 4, self_collision: false, contact: CONTACT }
}

/// Runs the four sweeps (quick: 16/64/256 regions, 3 frames; KKT methods 3 frames; flag 0.5 s; penalty
/// 0.2 s with k_p 1e3, 1e5, 1e7. Default: 16 … 1024 regions, 1 s; KKT methods 0.5 s; penalty
/// 0.2 s with k_p 1e3 … 1e8 — a penalty step costs ≈ 1 s on the box, the fill of ĈᵀĈ).
pub fn run(ctx: &BenchCtx) -> Result<Summary> {
    let (regions, duration): (&[usize], f64) =
        if ctx.quick { (&[16, 64, 256], 0.1) } else { (&[16, 64, 256, 1024], 1.0) };
    let mut rec = FileRecorder::new(&ctx.out_dir)?;
    let cl = KktMethod::ConstraintLastLdlt;
    let solvers = Solvers { kkt: cl, kkt_large: cl, large_from: usize::MAX, refine_steps: 0 };
    let rows = partition_study(regions, duration, &shell(), &solvers, &mut rec)?;
    record_partitions(&rows, &mut rec)?;
    let mut r = Report::default();
    partition_keys(&rows, &mut r);
    let untracked: Vec<f64> = rows.iter().map(|row| row.s_per_frame_untracked).collect();
    r.timing("s_per_frame_untracked", geom_core::stats::mean(&untracked));
    r.num("duration_s", duration);
    kkt_methods(ctx, &mut r, &mut rec)?;
    flag_steps(ctx, &mut r, &mut rec)?;
    penalty_vs_lagrange(ctx, &mut r, &mut rec)?;
    rec.finish()?;
    Ok(Summary::from_report(&r))
}

/// The exact methods compared in sweep 2, with their summary-key names.
fn exact_methods() -> [(&'static str, KktMethod); 3] {
    [
        ("constraint_last", KktMethod::ConstraintLastLdlt),
        ("amd_regularized", KktMethod::AmdRegularizedLdlt { delta: 1e-8 }),
        ("schur", KktMethod::Schur),
    ]
}

fn series(plot: &str, label: &str, axes: (&str, &str), log: (bool, bool), points: Vec<(f64, f64)>) -> Series {
    Series { plot: plot.into(), label: label.into(), axes: (axes.0.into(), axes.1.into()), log, points }
}

/// Sweep 2: KKT solve time, factor size and overhead per exact method and region count.
fn kkt_methods(ctx: &BenchCtx, r: &mut Report, rec: &mut FileRecorder) -> Result<()> {
    let (duration, regions): (f64, &[usize]) =
        if ctx.quick { (0.1, &[0, 16, 64, 256]) } else { (0.5, &[0, 16, 64, 256, 1024]) };
    let mut runs = FileRecorder::new(&ctx.out_dir.join("kkt_methods"))?;
    let mut all: Vec<(&str, Vec<PartitionRow>)> = Vec::new();
    for (name, m) in exact_methods() {
        let refine = u32::from(matches!(m, KktMethod::AmdRegularizedLdlt { .. }));
        let solvers = Solvers { kkt: m, kkt_large: m, large_from: usize::MAX, refine_steps: refine };
        let rows = partition_study(regions, duration, &shell(), &solvers, &mut runs)?;
        for row in &rows {
            let n = row.regions;
            r.timing(&format!("kkt_ms_per_step_{name}_r{n}"), 1e3 * row.solve_s_per_step);
            r.timing(&format!("overhead_pct_{name}_r{n}"), row.overhead_pct);
            r.count(&format!("nnz_l_{name}_r{n}"), row.nnz_l as u64);
            r.num(&format!("max_residual_pre_{name}_r{n}"), row.r_pre);
        }
        all.push((name, rows));
    }
    let header =
        ["method", "regions", "multipliers", "kkt_ms_per_step", "s_per_frame", "overhead_pct", "nnz_l", "r_pre_over_L"];
    rec.table("kkt_vs_regions", &header)?;
    for (name, rows) in &all {
        for row in rows {
            rec.row(
                "kkt_vs_regions",
                &[
                    Cell::from(*name),
                    Cell::from(row.regions),
                    Cell::from(3 * row.k),
                    Cell::from(1e3 * row.solve_s_per_step),
                    Cell::from(row.s_per_frame),
                    Cell::from(row.overhead_pct),
                    Cell::from(row.nnz_l),
                    Cell::from(row.r_pre),
                ],
            )?;
        }
        let pts = |f: &dyn Fn(&PartitionRow) -> f64| rows.iter().map(|row| ((3 * row.k) as f64, f(row))).collect();
        let rows3k = ("multiplier rows 3K", "overhead (%)");
        rec.series(&series("overhead_vs_constraints", name, rows3k, (true, false), pts(&|x| x.overhead_pct)))?;
        let ms = ("multiplier rows 3K", "ms per step");
        rec.series(&series("solve_ms_vs_constraints", name, ms, (true, true), pts(&|x| 1e3 * x.solve_s_per_step)))?;
    }
    runs.finish()?;
    Ok(())
}

/// One tracked flag run of sweep 3 (`substeps` per frame, IPC Newton capped at `newton`
/// iterations, tolerance `tol` m/s); returns the run and its tracked positions per frame.
fn flag_run(d: &FlagDesign, duration: f64, substeps: u32, newton: u32, tol: f64) -> Result<(PairOut, Vec<Vec<Pt3>>)> {
    let setup = flag_setup(d, &ShellOptions { substeps, self_collision: true, contact: CONTACT })?.edited(Box::new(
        move |desc| {
            if let Some(c) = desc.effects.collision.as_mut() {
                c.max_newton_iters = newton;
                c.newton_tol = tol;
            }
        },
    ));
    let o = PairOpts {
        frames: frames_for(duration, setup.fps),
        obj_every: 1,
        untracked: false,
        track: track_opts(KktMethod::ConstraintLastLdlt, 0),
        intersections: false,
        anchors: None,
        tag: String::new(),
        subsets: Vec::new(),
    };
    let mut mem = MemoryRecorder::default();
    let out = run_pair(&setup, &o, &mut mem)?;
    let frames = mem.frames.remove("tracked").unwrap_or_default().into_iter().map(|f| f.2).collect();
    Ok((out, frames))
}

/// Sweep 3 (spec §9): the tracked flag at substeps × Newton iterations ∈ {1, 3} against a
/// fine-step reference: mean over frames of the vertex-RMS distance to the reference / L, the
/// mean D_c and a_d, and milliseconds of step time per frame.
fn flag_steps(ctx: &BenchCtx, r: &mut Report, rec: &mut FileRecorder) -> Result<()> {
    let (duration, subs, ref_sub): (f64, &[u32], u32) =
        if ctx.quick { (0.5, &[1, 4], 16) } else { (2.0, &[1, 2, 4, 8], 32) };
    let design = flag_design(PREVIEW_DURATION, CONTACT)?;
    let (ref_out, ref_q) = flag_run(&design, duration, ref_sub, 10, 1e-4)?;
    let mean = geom_core::stats::mean;
    let scale = ref_out.scale;
    let header = ["substeps", "newton_iters", "ms_per_frame", "error_rms_over_L", "dc_mean", "ad_mean_m", "r_pre"];
    rec.table("flag_steps", &header)?;
    let row = |rec: &mut FileRecorder, s: u32, n: u32, o: &PairOut, err: f64| {
        let cells = [s as f64, n as f64, 1e3 * o.s_per_frame_tracked(), err, mean(&o.dc_tracked), mean(&o.ad_tracked)];
        let mut c: Vec<Cell> = cells.iter().map(|&x| Cell::from(x)).collect();
        c.push(Cell::from(o.r_pre()));
        rec.row("flag_steps", &c)
    };
    row(rec, ref_sub, 10, &ref_out, 0.0)?;
    r.timing("flag_ms_per_frame_reference", 1e3 * ref_out.s_per_frame_tracked());
    r.num("flag_dc_mean_reference", mean(&ref_out.dc_tracked));
    r.num("flag_ad_mean_m_reference", mean(&ref_out.ad_tracked));
    let mut pts: Vec<(u32, Vec<(f64, f64)>)> = vec![(1, Vec::new()), (3, Vec::new())];
    for &s in subs {
        for (n, line) in pts.iter_mut() {
            let (o, q) = flag_run(&design, duration, s, *n, 1e-2)?;
            // Frames ≥ 1 of both runs (frame 0 is the shared initial state).
            let errs: Vec<f64> = q
                .iter()
                .zip(&ref_q)
                .skip(1)
                .map(|(a, b)| {
                    let ss: f64 = a.iter().zip(b).map(|(x, y)| (x - y).norm_squared()).sum();
                    (ss / a.len().max(1) as f64).sqrt() / scale
                })
                .collect();
            let err = mean(&errs);
            row(rec, s, *n, &o, err)?;
            let key = format!("s{s}_n{n}");
            r.num(&format!("flag_error_{key}"), err);
            r.timing(&format!("flag_ms_per_frame_{key}"), 1e3 * o.s_per_frame_tracked());
            r.num(&format!("flag_dc_mean_{key}"), mean(&o.dc_tracked));
            r.num(&format!("flag_ad_mean_m_{key}"), mean(&o.ad_tracked));
            r.num(&format!("flag_max_residual_pre_{key}"), o.r_pre());
            line.push((1e3 * o.s_per_frame_tracked(), err.max(1e-12)));
        }
    }
    for (n, line) in pts {
        let axes = ("ms per frame (tracked)", "RMS distance to the reference / L");
        rec.series(&series("flag_error_vs_ms", &format!("≤ {n} Newton iterations"), axes, (true, true), line))?;
    }
    Ok(())
}

/// Sweep 4: the box with penalty constraints (k_p) against the exact constraint-last LDLᵀ.
fn penalty_vs_lagrange(ctx: &BenchCtx, r: &mut Report, rec: &mut FileRecorder) -> Result<()> {
    let (duration, ks): (f64, &[f64]) =
        if ctx.quick { (0.2, &[1e3, 1e5, 1e7]) } else { (0.2, &[1e3, 1e4, 1e5, 1e6, 1e7, 1e8]) };
    let setup = box_setup(&shell())?;
    let mut runs = FileRecorder::new(&ctx.out_dir.join("penalty"))?;
    let mut methods: Vec<(String, KktMethod)> = vec![("lagrange".into(), KktMethod::ConstraintLastLdlt)];
    methods.extend(ks.iter().map(|&k| (format!("penalty_{k:e}"), KktMethod::Penalty { stiffness: k })));
    let header = ["method", "stiffness", "kkt_ms_per_step", "max_residual_pre_over_L", "s_per_frame"];
    rec.table("penalty_vs_lagrange", &header)?;
    let (mut lag, mut pen) = (Vec::new(), Vec::new());
    for (name, m) in methods {
        let o = PairOpts {
            frames: frames_for(duration, setup.fps),
            obj_every: 0,
            untracked: false,
            track: track_opts(m, 0),
            intersections: false,
            anchors: None,
            tag: format!("_{name}"),
            subsets: Vec::new(),
        };
        let out = run_pair(&setup, &o, &mut runs)?;
        let ms = 1e3 * out.solve_s_per_step();
        let res = out.r_pre();
        let k = if let KktMethod::Penalty { stiffness } = m { stiffness } else { f64::NAN };
        let cells = [Cell::from(name.as_str()), Cell::from(k), Cell::from(ms), Cell::from(res)];
        rec.row("penalty_vs_lagrange", &[&cells[..], &[Cell::from(out.s_per_frame_tracked())]].concat())?;
        r.timing(&format!("box_kkt_ms_per_step_{name}"), ms);
        r.num(&format!("box_max_residual_pre_{name}"), res);
        if k.is_nan() {
            lag.push((ms, res.max(1e-18)))
        } else {
            pen.push((ms, res.max(1e-18)))
        }
    }
    let axes = ("KKT ms per step", "max r_pre / L");
    rec.series(&series("penalty_vs_lagrange", "penalty k_p", axes, (true, true), pen))?;
    rec.series(&series("penalty_vs_lagrange", "Lagrange (constraint-last LDLᵀ)", axes, (true, true), lag))?;
    runs.finish()?;
    Ok(())
}

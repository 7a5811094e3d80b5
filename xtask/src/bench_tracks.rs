//! `cargo xtask bench tracks` (issue 4, spec §9): what accuracy costs in time.
//! 1. The Xavier clip (walk, from t = 0) with uniform animation-aware clusterings of 16, 64, 256
//!    and 1024 regions: deviation from the guide (area-weighted RMS ‖q − q̄‖ / L, mean over
//!    frames) and wavelength λ_eff of the deviation field against the time per frame, tracked and
//!    untracked in lockstep (`partitions.csv` and the four PNGs of the partition study).
//! 2. The exact KKT methods (constraint-last LDLᵀ, AMD-regularised LDLᵀ, bordered-LLᵀ Schur) at
//!    16, 64 and 256 regions on the same clip: KKT solve time per step, stored factor entries and
//!    overhead against the number of multiplier rows 3K (`kkt_vs_regions.csv`,
//!    `overhead_vs_constraints.png`, `solve_ms_vs_constraints.png`).
//! 3. The box (§6.2, collisions off): penalty stiffness k_p against the exact Lagrange
//!    multipliers — largest pre-collision constraint residual / L against KKT milliseconds per
//!    step (`penalty_vs_lagrange.csv`, `penalty_vs_lagrange.png`).

use crate::error::Result;
use crate::out::{Cell, CsvWriter, Summary};
use crate::plot::{LinePlot, Series};
use crate::registry::BenchCtx;
use crate::scenes::tracks::{
    box_setup, frames_for, partition_keys, partition_study, run_pair, track_opts, write_partition_outputs, PairOpts,
    PartitionRow,
};
use tracks::KktMethod;

/// Runs the three sweeps (quick: 16/64/256 regions, 3 frames; KKT methods 3 frames; penalty
/// 0.2 s with k_p 1e3, 1e5, 1e7. Default: 16 … 1024 regions, 1 s; KKT methods 0.5 s; penalty
/// 0.2 s with k_p 1e3 … 1e8 — a penalty step costs ≈ 1 s on the box, the fill of ĈᵀĈ).
pub fn run(ctx: &BenchCtx) -> Result<Summary> {
    let (regions, duration): (&[usize], f64) =
        if ctx.quick { (&[16, 64, 256], 0.1) } else { (&[16, 64, 256, 1024], 1.0) };
    let rows = partition_study(
        regions,
        duration,
        4,
        false,
        KktMethod::ConstraintLastLdlt,
        KktMethod::ConstraintLastLdlt,
        usize::MAX,
        0,
        &ctx.out_dir,
    )?;
    write_partition_outputs(&rows, &ctx.out_dir)?;
    let mut s = Summary::new();
    partition_keys(&rows, &mut s);
    s.set("s_per_frame_untracked", rows.iter().map(|r| r.s_per_frame_untracked).sum::<f64>() / rows.len() as f64);
    s.set("duration_s", duration);
    kkt_methods(ctx, &mut s)?;
    penalty_vs_lagrange(ctx, &mut s)?;
    Ok(s)
}

/// The exact methods compared in sweep 2, with their summary-key names.
fn exact_methods() -> [(&'static str, KktMethod); 3] {
    [
        ("constraint_last", KktMethod::ConstraintLastLdlt),
        ("amd_regularized", KktMethod::AmdRegularizedLdlt { delta: 1e-8 }),
        ("schur", KktMethod::Schur),
    ]
}

/// Sweep 2: KKT solve time, factor size and overhead per exact method and region count.
fn kkt_methods(ctx: &BenchCtx, s: &mut Summary) -> Result<()> {
    let duration = if ctx.quick { 0.1 } else { 0.5 };
    let regions = [16usize, 64, 256];
    let dir = ctx.out_dir.join("kkt_methods");
    crate::out::ensure_dir(&dir)?;
    let mut all: Vec<(&str, Vec<PartitionRow>)> = Vec::new();
    for (name, m) in exact_methods() {
        let refine = u32::from(matches!(m, KktMethod::AmdRegularizedLdlt { .. }));
        let rows = partition_study(&regions, duration, 4, false, m, m, usize::MAX, refine, &dir)?;
        for r in &rows {
            s.set(&format!("kkt_ms_per_step_{name}_r{}", r.regions), 1e3 * r.solve_s_per_step);
            s.set(&format!("overhead_pct_{name}_r{}", r.regions), r.overhead_pct);
            s.set_count(&format!("nnz_l_{name}_r{}", r.regions), r.nnz_l as u64);
            s.set(&format!("max_residual_pre_{name}_r{}", r.regions), r.r_pre);
        }
        all.push((name, rows));
    }
    let mut csv = CsvWriter::create(
        &ctx.out_dir.join("kkt_vs_regions.csv"),
        &[
            "method",
            "regions",
            "multipliers",
            "kkt_ms_per_step",
            "s_per_frame",
            "overhead_pct",
            "nnz_l",
            "r_pre_over_L",
        ],
    )?;
    let (mut over, mut ms) = (
        LinePlot::new("tracking overhead vs constraint rows (Xavier)", "multiplier rows 3K", "overhead (%)")
            .log(true, false),
        LinePlot::new("KKT solve time vs constraint rows (Xavier)", "multiplier rows 3K", "ms per step")
            .log(true, true),
    );
    for (name, rows) in &all {
        for r in rows {
            csv.row(&[
                Cell::Text(name.to_string()),
                Cell::Int(r.regions as i64),
                Cell::Int(3 * r.k as i64),
                Cell::Num(1e3 * r.solve_s_per_step),
                Cell::Num(r.s_per_frame),
                Cell::Num(r.overhead_pct),
                Cell::Int(r.nnz_l as i64),
                Cell::Num(r.r_pre),
            ])?;
        }
        over = over.with(Series::new(*name, rows.iter().map(|r| ((3 * r.k) as f64, r.overhead_pct)).collect()));
        ms = ms.with(Series::new(*name, rows.iter().map(|r| ((3 * r.k) as f64, 1e3 * r.solve_s_per_step)).collect()));
    }
    over.write_png(&ctx.out_dir.join("overhead_vs_constraints.png"))?;
    ms.write_png(&ctx.out_dir.join("solve_ms_vs_constraints.png"))?;
    Ok(())
}

/// Sweep 3: the box with penalty constraints (k_p) against the exact constraint-last LDLᵀ.
fn penalty_vs_lagrange(ctx: &BenchCtx, s: &mut Summary) -> Result<()> {
    let (duration, ks): (f64, &[f64]) =
        if ctx.quick { (0.2, &[1e3, 1e5, 1e7]) } else { (0.2, &[1e3, 1e4, 1e5, 1e6, 1e7, 1e8]) };
    let setup = box_setup(4, false)?;
    let dir = ctx.out_dir.join("penalty");
    let mut methods: Vec<(String, KktMethod)> = vec![("lagrange".into(), KktMethod::ConstraintLastLdlt)];
    methods.extend(ks.iter().map(|&k| (format!("penalty_{k:e}"), KktMethod::Penalty { stiffness: k })));
    let mut csv = CsvWriter::create(
        &ctx.out_dir.join("penalty_vs_lagrange.csv"),
        &["method", "stiffness", "kkt_ms_per_step", "max_residual_pre_over_L", "s_per_frame"],
    )?;
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
        };
        let out = run_pair(&setup, &o, &dir)?;
        let ms = 1e3 * out.t_kkt / out.steps.max(1) as f64;
        let r = out.max_r_pre / out.scale;
        let k = if let KktMethod::Penalty { stiffness } = m { stiffness } else { f64::NAN };
        csv.row(&[
            Cell::Text(name.clone()),
            Cell::Num(k),
            Cell::Num(ms),
            Cell::Num(r),
            Cell::Num(out.s_per_frame_tracked()),
        ])?;
        s.set(&format!("box_kkt_ms_per_step_{name}"), ms);
        s.set(&format!("box_max_residual_pre_{name}"), r);
        if k.is_nan() {
            lag.push((ms, r.max(1e-18)))
        } else {
            pen.push((ms, r.max(1e-18)))
        }
    }
    LinePlot::new("box: constraint residual vs solve time", "KKT ms per step", "max r_pre / L")
        .log(true, true)
        .with(Series::new("penalty k_p", pen))
        .with(Series::new("Lagrange (constraint-last LDLᵀ)", lag))
        .write_png(&ctx.out_dir.join("penalty_vs_lagrange.png"))?;
    Ok(())
}

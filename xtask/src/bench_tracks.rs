//! `cargo xtask bench tracks` (issue 4, spec §9): what accuracy costs in time. The Xavier clip
//! (walk, from t = 0) with uniform animation-aware clusterings of 16, 64, 256 and 1024 regions:
//! deviation from the guide (area-weighted RMS ‖q − q̄‖ / L, mean over frames) and wavelength
//! λ_eff of the deviation field against the time per frame, tracked and untracked in lockstep.
//! Writes `partitions.csv` and the four PNGs of the partition study.

use crate::error::Result;
use crate::out::Summary;
use crate::registry::BenchCtx;
use crate::scenes::tracks::{partition_study, write_partition_outputs};
use tracks::KktMethod;

/// Runs the sweep (quick: 16/64/256 regions, 3 frames; full: 16 … 1024, 1 s).
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
    for r in &rows {
        s.set(&format!("deviation_r{}", r.regions), r.deviation);
        s.set(&format!("wavelength_m_r{}", r.regions), r.wavelength);
        s.set(&format!("s_per_frame_r{}", r.regions), r.s_per_frame);
        s.set(&format!("overhead_pct_r{}", r.regions), r.overhead_pct);
        s.set(&format!("overhead_pct_median_step_r{}", r.regions), r.overhead_pct_median);
        s.set(&format!("max_residual_pre_r{}", r.regions), r.r_pre);
    }
    s.set("s_per_frame_untracked", rows.iter().map(|r| r.s_per_frame_untracked).sum::<f64>() / rows.len() as f64);
    s.set("duration_s", duration);
    Ok(s)
}

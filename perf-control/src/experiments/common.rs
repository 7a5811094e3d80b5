//! Outputs the perf-control experiments share: the chosen segments, the target points and the
//! top view of requested against achieved control.

use geom_core::record::{Cell, Recorder, Series};

use crate::db::MappingDb;
use crate::dp::Interpretation;
use crate::error::Result;
use crate::track::PointTrack;

/// Table `segments`: per chosen segment the instance, its label, start/end at the working and
/// the fine rate, the alignment (θ, tx, tz) and `D`, `C` of the fine chain.
pub fn record_segments(
    rec: &mut dyn Recorder,
    db: &MappingDb,
    coarse: &Interpretation,
    fine: &Interpretation,
) -> Result<()> {
    rec.table(
        "segments",
        &["i", "instance", "label", "start_work", "end_work", "start_fine", "end_fine", "theta", "tx", "tz", "D", "C"],
    )?;
    for (i, (c, f)) in coarse.segments.iter().zip(&fine.segments).enumerate() {
        let label = format!("{:?}", db.instances[c.instance as usize].label).replace(['{', '}', ' '], "");
        rec.row(
            "segments",
            &[
                Cell::Int(i as i64),
                Cell::Int(c.instance as i64),
                label.into(),
                Cell::Int(c.start),
                Cell::Int(c.end),
                Cell::Int(f.start),
                Cell::Int(f.end),
                f.m.yaw.into(),
                f.m.x.into(),
                f.m.z.into(),
                f.d.into(),
                f.c.into(),
            ],
        )?;
    }
    Ok(())
}

/// Table `target_points`: every output point per frame.
pub fn record_target_points(rec: &mut dyn Recorder, pts: &PointTrack) -> Result<()> {
    rec.table("target_points", &["frame", "point", "x", "y", "z"])?;
    if !rec.keeps_outputs() {
        return Ok(());
    }
    for f in 0..pts.len() {
        for (k, q) in pts.frame(f).iter().enumerate() {
            rec.row("target_points", &[Cell::Int(f as i64), Cell::Int(k as i64), q.x.into(), q.y.into(), q.z.into()])?;
        }
    }
    Ok(())
}

/// Midpoints `(x, z)` of the first two points of every frame.
pub fn midpoints(t: &PointTrack) -> Vec<(f64, f64)> {
    (0..t.len())
        .map(|f| (0.5 * (t.frame(f)[0].x + t.frame(f)[1].x), 0.5 * (t.frame(f)[0].z + t.frame(f)[1].z)))
        .collect()
}

/// Plot `topview`: requested against achieved control midpoints.
pub fn topview(rec: &mut dyn Recorder, requested: &PointTrack, achieved: &PointTrack) -> Result<()> {
    for (label, t) in [("requested", requested), ("achieved", achieved)] {
        rec.series(&Series {
            plot: "topview".into(),
            label: label.into(),
            axes: ("x (m)".into(), "z (m)".into()),
            log: (false, false),
            points: midpoints(t),
        })?;
    }
    Ok(())
}

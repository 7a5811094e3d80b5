//! C8 `cloth-fit/real-roundtrip` (spec §6 C8, §3.4): the real-footage path end to end. A
//! synthetic linen waving capture (mismatched truth with noise) is written to disk exactly as a
//! real one would be — 8-bit PNG frames, a background plate, `rig.ron` with camera and
//! projector as marker correspondences, `corners.csv` at 120 Hz — and read back through the DLT
//! calibration, the corner tracks and background-plate silhouettes. The preprocessed frames,
//! the objective at fixed parameter points and a fit are compared with the in-memory path.
//!
//! ```no_run
//! # fn demo(p: &cloth_fit::experiments::real_roundtrip::Params) -> cloth_fit::Result<()> {
//! use cloth_fit::experiments::real_roundtrip::run;
//! use geom_core::experiment::Size;
//! use geom_core::record::NullRecorder;
//! let report = run(p, Size::Quick, &mut NullRecorder::default())?;
//! println!("{:?}", report.get("objective_rel_diff_max"));
//! # Ok(()) }
//! ```

use std::path::{Path, PathBuf};

use geom_core::experiment::{BySize, Report, Size, Target};
use geom_core::image::{ImageF32, Mask};
use geom_core::record::{Cell, Recorder};
use geom_core::rng::Rng;
use geom_core::stats::max;
use serde::{Deserialize, Serialize};

use super::common::{space, truths, FitScale, SearchScale};
use crate::angle::AngleFrame;
use crate::error::{FitError, Result};
use crate::fit::{fit, DynamicInit, TrialPolicy};
use crate::footage::{load_capture, write_synthetic_capture};
use crate::forward::ShellsForward;
use crate::metrics::{error_of, param_errors};
use crate::morphology::{dilate, erode};
use crate::noise::degrade;
use crate::objective::{EvalSetup, Objective};
use crate::params::ParamId;
use crate::presets::{waving_trial, FabricPreset};
use crate::synthetic::Condition;

/// Scene parameters (the RON `params` block).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Params {
    /// The fabric (the spec: linen).
    pub fabric: FabricPreset,
    /// Frames of the waving capture.
    pub frames: BySize<usize>,
    /// Synthetic condition of the capture.
    pub condition: BySize<Condition>,
    /// Background-plate threshold (intensity units).
    pub silhouette_threshold: f64,
    /// Parameter points at which both objectives are compared.
    pub objective_points: BySize<usize>,
    /// Fit from disk (and the in-memory fit beside it when `fit_in_memory`).
    pub fit_from_disk: BySize<bool>,
    /// Also fit the in-memory target for comparison.
    pub fit_in_memory: BySize<bool>,
    /// Seed of the random dynamic start.
    pub dynamic_seed: u64,
    /// Fit-side scale.
    pub fit: FitScale,
    /// Search budgets.
    pub search: SearchScale,
}

/// Per-frame comparison of two angle frames: pixels whose validity, fold mask or angle differ,
/// and how many of them lie farther than `band` px from either silhouette's boundary.
pub fn frame_diff(a: &AngleFrame, b: &AngleFrame, band: u32) -> (usize, usize) {
    let boundary = |s: &Mask| {
        let (d, e) = (dilate(s, band), erode(s, band));
        Mask { width: s.width, height: s.height, data: d.data.iter().zip(&e.data).map(|(x, y)| *x && !*y).collect() }
    };
    let (ba, bb) = (boundary(&a.silhouette), boundary(&b.silhouette));
    let (mut diff, mut off) = (0, 0);
    for i in 0..a.theta.data.len() {
        let both = a.valid.data[i] && b.valid.data[i];
        let d = a.valid.data[i] != b.valid.data[i]
            || a.fold_mask.data[i] != b.fold_mask.data[i]
            || (both && (a.theta.data[i] - b.theta.data[i]).abs() > 1e-6);
        if d {
            diff += 1;
            if !(ba.data[i] || bb.data[i]) {
                off += 1;
            }
        }
    }
    (diff, off)
}

fn scratch_dir() -> PathBuf {
    let nanos = std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).map(|d| d.as_nanos()).unwrap_or(0);
    std::env::temp_dir().join(format!("cloth-fit-capture-{}-{nanos}", std::process::id()))
}

fn copy_into_recorder(rec: &mut dyn Recorder, root: &Path, dir: &Path) -> Result<()> {
    let rd = std::fs::read_dir(dir).map_err(|e| FitError::Io { path: dir.to_path_buf(), msg: e.to_string() })?;
    let mut entries: Vec<PathBuf> = rd.filter_map(|e| e.ok().map(|e| e.path())).collect();
    entries.sort();
    for p in entries {
        if p.is_dir() {
            copy_into_recorder(rec, root, &p)?;
        } else {
            let bytes = std::fs::read(&p).map_err(|e| FitError::Io { path: p.clone(), msg: e.to_string() })?;
            let rel = p.strip_prefix(root).unwrap_or(&p).display().to_string();
            rec.file(&format!("capture/{rel}"), &bytes)?;
        }
    }
    Ok(())
}

/// Runs C8.
pub fn run(p: &Params, size: Size, rec: &mut dyn Recorder) -> Result<Report> {
    let setup = p.fit.setup(size)?;
    let fwd = ShellsForward;
    let f = p.fabric;
    let truth = f.params();
    let cond = p.condition.get(size);
    let e = waving_trial(f, 0, p.frames.get(size).max(2));
    let tr = truths(&fwd, std::slice::from_ref(&e), truth, &setup, cond, p.fit.noise)?.remove(0);
    let (w, h) = (setup.rig.camera.width, setup.rig.camera.height);
    let plate = match cond {
        Condition::Mismatched => degrade(&ImageF32::new(w, h, setup.render.background as f32), &p.fit.noise, 1 << 20),
        Condition::Matched => ImageF32::new(w, h, setup.render.background as f32),
    };
    let dir = scratch_dir();
    let result = (|| -> Result<Report> {
        write_synthetic_capture(&dir, &tr.images, &plate, &setup.rig, &e, p.silhouette_threshold)?;
        if rec.keeps_outputs() {
            copy_into_recorder(rec, &dir, &dir)?;
        }
        let cap = load_capture(&dir, &e, &setup.angle)?;
        for wmsg in &cap.warnings {
            rec.note(&format!("warning: {wmsg}"))?;
        }
        let mut r = Report::default();
        rec.note(&format!(
            "# C8 real-footage round trip\n\n{} waving, {} frames, {}; DLT RMS camera {:.2e} px, projector {:.2e} px",
            f.name(),
            e.frames,
            cond.name(),
            cap.calib_rms_px.0,
            cap.calib_rms_px.1
        ))?;
        r.num("calib_rms_camera_px", cap.calib_rms_px.0);
        r.num("calib_rms_projector_px", cap.calib_rms_px.1);
        r.num("camera_matrix_rel_diff", (cap.rig.camera.p - setup.rig.camera.p).norm() / setup.rig.camera.p.norm());
        // 1. Preprocessed frames.
        rec.table("frames", &["frame", "diff_pixels", "diff_off_boundary", "silhouette_xor"])?;
        let (mut fr_frac, mut off_total) = (Vec::new(), 0usize);
        for (k, (a, b)) in tr.target.frames.iter().zip(&cap.target.frames).enumerate() {
            let (d, off) = frame_diff(a, b, 2);
            let xor = a.silhouette.data.iter().zip(&b.silhouette.data).filter(|(x, y)| x != y).count();
            rec.row("frames", &[Cell::from(k), Cell::from(d), Cell::from(off), Cell::from(xor)])?;
            fr_frac.push(d as f64 / (w as f64 * h as f64));
            off_total += off;
        }
        r.num("angle_frame_diff_frac_max", max(&fr_frac));
        r.count("angle_frame_diff_off_boundary", off_total as u64);
        r.check(
            "angle_frame_diff_frac_max",
            Target::AtMost(0.001),
            "spec §6 C8: angle frames identical except ≤ 0.1 % of pixels",
        );
        // 2. The objective at fixed points, disk path vs in-memory path.
        let sp = space(&ParamId::ALL, truth)?;
        let disk_setup = EvalSetup { rig: cap.rig.clone(), ..setup.clone() };
        let mem = Objective::new(std::slice::from_ref(&tr.target), &fwd, &sp, &setup)?;
        let disk = Objective::new(std::slice::from_ref(&cap.target), &fwd, &sp, &disk_setup)?;
        let x0 = sp.to_unit(&truth);
        let mut rng = Rng::new(5);
        let xs: Vec<Vec<f64>> = (0..p.objective_points.get(size).max(1))
            .map(|k| {
                if k == 0 {
                    x0.clone()
                } else {
                    x0.iter().map(|&u| (u + 0.1 * (2.0 * rng.f64() - 1.0)).clamp(0.0, 1.0)).collect()
                }
            })
            .collect();
        let (em, ed) = (mem.eval_batch(&xs), disk.eval_batch(&xs));
        rec.table("objective", &["point", "e_memory", "e_disk", "rel_diff"])?;
        let mut rel = Vec::new();
        for (k, (a, b)) in em.iter().zip(&ed).enumerate() {
            let d = (b.error - a.error).abs() / a.error.abs().max(1e-300);
            rec.row("objective", &[Cell::from(k), Cell::from(a.error), Cell::from(b.error), Cell::from(d)])?;
            rel.push(d);
        }
        rec.progress(1, 2);
        r.num("objective_rel_diff_max", max(&rel));
        r.check("objective_rel_diff_max", Target::AtMost(1e-3), "spec §6 C8: objective within 1e-3 relative");
        // 3. Fits.
        let opts = p.search.options(
            size,
            DynamicInit::Random { seed: p.dynamic_seed },
            TrialPolicy::PerTrialThenSelect,
            false,
        );
        if p.fit_from_disk.get(size) {
            let fr =
                fit(std::slice::from_ref(&cap.target), &fwd, &sp, &disk_setup, &opts, &mut |d, t| rec.progress(d, t))?;
            let errs = param_errors(&sp, &fr.params, &truth);
            r.num("bend_err_disk", error_of(&errs, ParamId::Bend));
            r.num("stretch_err_disk", error_of(&errs, ParamId::Stretch));
            r.count("simulations_disk", fr.simulations as u64);
            if p.fit_in_memory.get(size) {
                let fm =
                    fit(std::slice::from_ref(&tr.target), &fwd, &sp, &setup, &opts, &mut |d, t| rec.progress(d, t))?;
                let em = param_errors(&sp, &fm.params, &truth);
                r.num("bend_err_memory", error_of(&em, ParamId::Bend));
                r.num("stretch_err_memory", error_of(&em, ParamId::Stretch));
            }
        }
        Ok(r)
    })();
    let _ = std::fs::remove_dir_all(&dir);
    result
}

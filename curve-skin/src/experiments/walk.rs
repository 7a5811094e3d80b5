//! The capsule humanoid playing the procedural walk cycle (spec §6.4) with LBS, DQS and curve
//! skin: per-frame volume ratio and deform / prepare times, OBJ frames, and a glTF 2.0 export of
//! the LBS-skinned character with the walk animation.
//!
//! Outputs: table `metrics` (frame, time, method, volume ratio, deform and prepare seconds), plot
//! `volume_ratio`, files `obj/<method>_<frame>.obj` every `obj_every` frames and `walk.gltf`.
//! Figures: `<m>_min_volume_ratio`, `<m>_max_volume_ratio` (NaN if any frame's volume is NaN),
//! `<m>_mean_deform_s` (s, timing), `frames`, `vertices`, `gltf` (the file name).
//!
//! ```no_run
//! use curve_skin::experiments::walk::{run, Params};
//! use geom_core::experiment::Size;
//! use geom_core::record::NullRecorder;
//! let p: Params =
//!     ron::from_str("(resolution: 0.3, duration: 0.4, fps: 30.0, obj_every: 0, gltf: false)").unwrap();
//! let report = run(&p, Size::Quick, &mut NullRecorder::default()).unwrap();
//! assert_eq!(report.get_f64("frames"), 13.0);
//! ```

use std::time::Instant;

use geom_core::experiment::{BySize, Report, Size};
use geom_core::io::{obj, MeshOut};
use geom_core::record::{Recorder, Series};
use geom_core::stats;
use serde::Deserialize;

use crate::error::{Result, SkinError};
use crate::metrics::{signed_volume, to_f64};
use crate::poses::walk_pose;
use crate::presets::{capsule_character, character_skinners, HUMANOID_WEIGHT_THRESHOLD};

use super::timed_deform;

/// The scene's `params` block.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Params {
    /// Mesh resolution (1.0 ≈ 50k vertices).
    pub resolution: BySize<f64>,
    /// Clip duration (s).
    pub duration: BySize<f64>,
    /// Frame rate (Hz).
    pub fps: f64,
    /// Write an OBJ every this many frames (0 = never).
    pub obj_every: usize,
    /// Export `walk.gltf` (LBS weights + animation).
    pub gltf: bool,
}

/// Runs the walk; see the module docs.
pub fn run(p: &Params, size: Size, rec: &mut dyn Recorder) -> Result<Report> {
    if p.fps.is_nan() || p.fps <= 0.0 {
        return Err(SkinError::Param(format!("fps = {} must be positive", p.fps)));
    }
    let c = capsule_character(p.resolution.get(size), HUMANOID_WEIGHT_THRESHOLD)?;
    let n = c.rest32.len();
    let v0 = signed_volume(&c.mesh.positions, &c.mesh.tris);
    let mut methods = character_skinners(&c, false)?;
    let frames = (p.duration.get(size) * p.fps).round() as usize + 1;
    rec.table("metrics", &["frame", "time", "method", "volume_ratio", "deform_s", "prepare_s"])?;
    let mut out = vec![[0f32; 3]; n];
    let mut vols: Vec<Vec<f64>> = vec![Vec::with_capacity(frames); methods.len()];
    let mut deform_s = vec![0.0; methods.len()];
    let mut poses = Vec::with_capacity(frames);
    for f in 0..frames {
        rec.progress(f as u64, frames as u64);
        let t = f as f64 / p.fps;
        let pose = walk_pose(&c.sk, t);
        let posed = pose.globals(&c.sk);
        for (mi, (m, s)) in methods.iter_mut().enumerate() {
            let t0 = Instant::now();
            s.prepare(&c.sk, &posed)?;
            let tp = t0.elapsed().as_secs_f64();
            let td = timed_deform(s.as_ref(), &mut out);
            let vol = signed_volume(&to_f64(&out), &c.mesh.tris) / v0;
            rec.row("metrics", &[f.into(), t.into(), (*m).into(), vol.into(), td.into(), tp.into()])?;
            vols[mi].push(vol);
            deform_s[mi] += td;
            if p.obj_every > 0 && f % p.obj_every == 0 && rec.keeps_outputs() {
                let text = obj::to_string(&MeshOut::tri_f32(&out, &c.mesh.tris))?;
                rec.file(&format!("obj/{m}_{f:04}.obj"), text.as_bytes())?;
            }
        }
        poses.push(pose);
    }
    let mut rep = Report::default();
    rep.count("vertices", n as u64);
    rep.count("frames", frames as u64);
    for (mi, (m, _)) in methods.iter().enumerate() {
        rep.num(&format!("{m}_min_volume_ratio"), stats::min(&vols[mi]));
        rep.num(&format!("{m}_max_volume_ratio"), stats::max(&vols[mi]));
        rep.timing(&format!("{m}_mean_deform_s"), deform_s[mi] / frames as f64);
        rec.series(&Series {
            plot: "volume_ratio".into(),
            label: m.to_string(),
            axes: ("time (s)".into(), "V/V0".into()),
            log: (false, false),
            points: vols[mi].iter().enumerate().map(|(f, &v)| (f as f64 / p.fps, v)).collect(),
        })?;
    }
    if p.gltf {
        let times: Vec<f64> = (0..frames).map(|f| f as f64 / p.fps).collect();
        let doc = crate::gltf::to_gltf(&c.rest32, &c.normals32, &c.mesh.tris, &c.sk, &c.w4, Some((&times, &poses)))?;
        let text = serde_json::to_string(&doc).map_err(|e| SkinError::Param(format!("glTF serialisation: {e}")))?;
        rec.file("walk.gltf", text.as_bytes())?;
        rep.text("gltf", "walk.gltf");
    }
    Ok(rep)
}

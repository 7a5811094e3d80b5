//! The capsule humanoid in the test poses of spec §6.3 (elbows 90/135°, forearm twists 90/180°,
//! squat, shoulder raise): volume ratio and deform time per pose and method, and the influence
//! statistics behind the paper's "mostly one weight, never more than three" (curve skin) against
//! "three to five" (LBS with a 0.01 threshold).
//!
//! Outputs: tables `influences` (histogram) and `metrics` (pose, method, volume ratio, time),
//! OBJ files `obj/<pose>_<method>.obj` when `obj` is set, a note. Figures:
//! `<m>_volume_ratio_<pose>`, `<m>_time_s_<pose>` (s, timing), `curve_one_weight_fraction`,
//! `curve_mean_weights`, `curve_max_weights`, `lbs_mean_influences`, `curves`,
//! `curve_clamped_vertices`, `vertices`.
//!
//! ```no_run
//! use curve_skin::experiments::humanoid::{run, Params};
//! use geom_core::experiment::Size;
//! use geom_core::record::NullRecorder;
//! let p: Params = ron::from_str(
//!     r#"(resolution: 0.3, poses: ["elbows_90", "squat"], weight_threshold: 0.01, obj: false)"#,
//! )
//! .unwrap();
//! let report = run(&p, Size::Quick, &mut NullRecorder::default()).unwrap();
//! assert!(report.get_f64("curve_max_weights") <= 3.0);
//! ```

use geom_core::experiment::{BySize, Report, Size, Target};
use geom_core::io::{obj, MeshOut};
use geom_core::record::Recorder;
use serde::Deserialize;

use crate::curve::CurveShape;
use crate::error::{Result, SkinError};
use crate::metrics::{histogram_mean, influences_histogram, rows_histogram, signed_volume, to_f64};
use crate::poses::{humanoid_pose, HUMANOID_POSES};
use crate::presets::{capsule_character, character_skinners, curve_skeleton};
use crate::{CurveOptions, CurveSkin};

use super::timed_deform;

/// The scene's `params` block.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Params {
    /// Mesh resolution (1.0 ≈ 50k vertices).
    pub resolution: BySize<f64>,
    /// Pose names (see `curve_skin::poses::HUMANOID_POSES`).
    pub poses: Vec<String>,
    /// Weight threshold of the inverse-distance weights (and of the LBS influence statistics).
    pub weight_threshold: f32,
    /// Write OBJ files per pose and method.
    pub obj: bool,
}

/// Runs the poses; see the module docs.
pub fn run(p: &Params, size: Size, rec: &mut dyn Recorder) -> Result<Report> {
    let c = capsule_character(p.resolution.get(size), p.weight_threshold)?;
    let n = c.rest32.len();
    let v0 = signed_volume(&c.mesh.positions, &c.mesh.tris);
    let mut methods = character_skinners(&c, false)?;
    let mut rep = Report::default();
    rep.count("vertices", n as u64);
    // Influence statistics: curves per vertex against LBS weights above the threshold.
    let cskel = curve_skeleton(&c.sk, CurveShape::CircularArc);
    rep.count("curves", cskel.curves.len() as u64);
    let cur = CurveSkin::new(&c.sk, cskel, &c.mesh.positions, None, CurveOptions::default())?;
    let ch = influences_histogram(&cur.binding.offsets);
    let lbs_hist = rows_histogram(&c.rows, 8);
    rep.num("curve_one_weight_fraction", ch.get(1).copied().unwrap_or(0) as f64 / n as f64);
    rep.num("curve_mean_weights", histogram_mean(&ch));
    rep.count("curve_max_weights", (ch.len() - 1) as u64);
    rep.num("lbs_mean_influences", histogram_mean(&lbs_hist));
    rep.count("curve_clamped_vertices", cur.binding.stats.clamped as u64);
    rec.table("influences", &["k", "curve_vertices", "lbs_vertices"])?;
    for (k, &l) in lbs_hist.iter().enumerate() {
        rec.row("influences", &[k.into(), ch.get(k).copied().unwrap_or(0).into(), l.into()])?;
    }
    rec.table("metrics", &["pose", "method", "volume_ratio", "time_s"])?;
    let mut out = vec![[0f32; 3]; n];
    for (pi, name) in p.poses.iter().enumerate() {
        rec.progress(pi as u64, p.poses.len() as u64);
        let pose = humanoid_pose(&c.sk, name)
            .ok_or_else(|| SkinError::Param(format!("unknown pose '{name}' (known: {})", HUMANOID_POSES.join(", "))))?;
        let posed = pose.globals(&c.sk);
        for (m, s) in methods.iter_mut() {
            s.prepare(&c.sk, &posed)?;
            let t = timed_deform(s.as_ref(), &mut out);
            let vol = signed_volume(&to_f64(&out), &c.mesh.tris) / v0;
            rec.row("metrics", &[name.as_str().into(), (*m).into(), vol.into(), t.into()])?;
            rep.num(&format!("{m}_volume_ratio_{name}"), vol);
            rep.timing(&format!("{m}_time_s_{name}"), t);
            if p.obj && rec.keeps_outputs() {
                let text = obj::to_string(&MeshOut::tri_f32(&out, &c.mesh.tris))?;
                rec.file(&format!("obj/{name}_{m}.obj"), text.as_bytes())?;
            }
        }
    }
    rep.check("curve_one_weight_fraction", Target::AtLeast(0.6), "spec §6.3 (paper): mostly one curve per vertex");
    rep.check("curve_max_weights", Target::AtMost(3.0), "spec §6.3 (paper): never more than three curves");
    rep.check("lbs_mean_influences", Target::AtLeast(2.0), "spec §6.3 (paper): smooth LBS uses three to five");
    rec.note(&format!(
        "Capsule humanoid, {n} vertices, {} curves. Curve skin: {:.1} % of vertices with one curve, mean {:.2}, max {} (paper: mostly 1, never more than 3). LBS inverse-distance weights above {}: mean {:.2} influences (paper: 3–5 for smooth skinning).",
        rep.get_f64("curves"),
        100.0 * rep.get_f64("curve_one_weight_fraction"),
        rep.get_f64("curve_mean_weights"),
        rep.get_f64("curve_max_weights"),
        p.weight_threshold,
        rep.get_f64("lbs_mean_influences"),
    ))?;
    Ok(rep)
}

//! S2 (spec §6): the dam break of Martin & Moyce (1952), a column `a × 2a` released at `t = 0`;
//! the surge front `Z = x/a` against `T = t √(2g/a)` and the residual column height
//! `H = h/(2a)` against `τ = t √(g/a)`.
//!
//! ```no_run
//! use flip_tet::experiments::dam_break;
//! use geom_core::experiment::Size;
//! let r = dam_break::run(&flip_tet::presets::dam_break(), Size::Quick, &mut geom_core::record::NullRecorder::default())?;
//! println!("front RMS error {}", r.get_f64("front_rms_rel_err"));
//! # Ok::<(), flip_tet::error::SimError>(())
//! ```

use geom_core::experiment::{BySize, Report, Size, Target};
use geom_core::record::{Cell, Recorder};
use geom_core::stats;
use serde::{Deserialize, Serialize};

use super::{one, plot, simulate, sized_scene, FrameOutput, RunOut, SimRun};
use crate::error::{Result, SimError};
use crate::metrics::{
    best_time_shift, column_height, fit_time_shift, front_errors, front_position, height_max_abs_err, interp,
    rel_drift, run_figures,
};
use crate::reference::{KO_FRONT, MARTIN_MOYCE_FRONT, MARTIN_MOYCE_HEIGHT, MM_FRONT_A1125, MM_FRONT_A225};
use crate::scene::{Scene, Shape};

/// Parameters (the scene file's `params`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Params {
    /// The tank; its first liquid shape is the column `Box` at the wall `x = min`.
    pub scene: Scene,
    /// Finest resolution per size.
    pub finest: BySize<u32>,
    /// Duration per size (s).
    pub duration: BySize<f64>,
    /// Surface OBJ every this many frames (0 = never).
    #[serde(default = "one")]
    pub obj_every: u64,
    /// Particle PLY every this many frames (0 = never).
    #[serde(default)]
    pub ply_every: u64,
    /// High-resolution surface every this many frames (0 = never).
    #[serde(default)]
    pub hires_every: u64,
    /// Extra runs at these finest resolutions (besides the main one), per size: the resolution
    /// study of issue 26 (keys `*_finest_<n>`).
    #[serde(default)]
    pub resolution_study: Option<BySize<Vec<u32>>>,
}

/// Range and step of the fitted time shift `ΔT` (dimensionless time).
pub const SHIFT_SEARCH: (f64, f64, f64) = (-1.0, 1.0, 0.001);

/// One literature curve: `(key tag, label, (T, Z) points)`.
pub type FrontCurve = (&'static str, &'static str, &'static [(f64, f64)]);

/// The literature's surge-front curves the front is compared with.
pub const FRONT_DATA: [FrontCurve; 3] = [
    ("mm", "Martin & Moyce 1952, a = 2.25 in", &MM_FRONT_A225),
    ("mm_a1125", "Martin & Moyce 1952, a = 1.125 in", &MM_FRONT_A1125),
    ("ko", "Koshizuka & Oka 1996", &KO_FRONT),
];

/// The front against each curve of [`FRONT_DATA`]: raw RMS relative error (no shift) as
/// `front_rms_rel_err_<tag>`, the RMS after one fitted time-origin shift as
/// `front_rms_rel_err_<tag>_shifted` and that shift `front_shift_T_<tag>` (`ΔT = Δt √(2g/a)`,
/// positive when the simulation leads), each key followed by `suffix`.
pub fn literature_figures(r: &mut Report, front: &[(f64, f64)], suffix: &str) {
    for (tag, _, data) in FRONT_DATA {
        let (_, raw) = front_errors(front, data);
        let (lo, hi, step) = SHIFT_SEARCH;
        let (shift, rms) = fit_time_shift(front, data, lo, hi, step);
        r.num(&format!("front_rms_rel_err_{tag}{suffix}"), raw);
        r.num(&format!("front_rms_rel_err_{tag}_shifted{suffix}"), rms);
        r.num(&format!("front_shift_T_{tag}{suffix}"), shift);
    }
}

/// One dam-break run: the dimensionless front `(T, Z)` and column height `(τ, H)` after every
/// step, with the run itself.
pub struct DamRun {
    /// Column width `a` (m).
    pub a: f64,
    /// `(T = t √(2g/a), Z = x_front / a)`.
    pub front: Vec<(f64, f64)>,
    /// `(τ = t √(g/a), H = h / (2a))`.
    pub height: Vec<(f64, f64)>,
    /// The run.
    pub run: SimRun,
}

/// Column width `a`: the first liquid shape's `x` extent (it must be a `Box`).
pub fn column_width(scene: &Scene) -> Result<f64> {
    match scene.liquid.first() {
        Some(Shape::Box { min, max }) => Ok(max[0] - min[0]),
        _ => Err(SimError::InvalidScene("dam-break: the first liquid shape must be the column Box".into())),
    }
}

/// Runs a dam break, probing the front and the residual column after every step.
pub fn dam_run(scene: &Scene, rec: &mut dyn Recorder, out: RunOut) -> Result<DamRun> {
    let a = column_width(scene)?;
    let (wall, floor) = (scene.domain.min[0], scene.domain.min[1]);
    let g = -scene.gravity[1];
    let mut front: Vec<(f64, f64)> = Vec::new();
    let mut height: Vec<(f64, f64)> = Vec::new();
    let run = simulate(scene, rec, out, &mut |sim, st| {
        let parts = sim.particles();
        front.push((st.t * (2.0 * g / a).sqrt(), front_position(parts, wall) / a));
        height.push((st.t * (g / a).sqrt(), column_height(parts, wall, a / 8.0, floor) / (2.0 * a)));
        Ok(())
    })?;
    Ok(DamRun { a, front, height, run })
}

/// Runs S2 and reports the front and height figures against Martin & Moyce.
pub fn run(p: &Params, size: Size, rec: &mut dyn Recorder) -> Result<Report> {
    let scene = sized_scene(&p.scene, &p.finest, None, &p.duration, size);
    let frames = FrameOutput { obj: p.obj_every, ply: p.ply_every, hires: p.hires_every };
    let d = dam_run(&scene, rec, RunOut::full("", frames))?;
    let (front, height, stats) = (&d.front, &d.height, &d.run.stats);
    let (errs, rms) = front_errors(front, &MARTIN_MOYCE_FRONT);
    rec.table("front_vs_mm", &["T", "Z_exp", "Z_sim", "rel_err"])?;
    for (&(t, z), e) in MARTIN_MOYCE_FRONT.iter().zip(&errs) {
        rec.row("front_vs_mm", &[Cell::Num(t), Cell::Num(z), Cell::Num(z * (1.0 + e)), Cell::Num(*e)])?;
    }
    let herr = height_max_abs_err(height, &MARTIN_MOYCE_HEIGHT, 2.5);
    // Late slope dZ/dT by least squares over T ∈ [2.5, 3.33].
    let late: Vec<(f64, f64)> = front.iter().copied().filter(|x| x.0 >= 2.5 && x.0 <= 3.33).collect();
    let slope = if late.len() > 2 { stats::linear_fit(&late).1 } else { f64::NAN };
    // Diagnostic (the pass metric has no offset): the time shift minimising the RMS.
    let (shift, rms_shift) = best_time_shift(front, &MARTIN_MOYCE_FRONT, 0.6, 0.005);
    let mut s = Report::default();
    s.num("front_rms_rel_err", rms);
    s.num("diag_front_best_gate_delay_T", shift);
    s.num("diag_front_rms_rel_err_with_best_delay", rms_shift);
    s.num("front_max_rel_err", errs.iter().map(|e| e.abs()).fold(0.0, stats::nan_max));
    s.count("front_points_compared", errs.len() as u64);
    s.num("height_max_abs_err_tau_le_2_5", herr);
    s.num("late_slope_dZdT", slope);
    s.num("vol_particles_drift_rel", rel_drift(stats, |x| x.vol_particles));
    s.num("vol_levelset_drift_rel", rel_drift(stats, |x| x.vol_levelset));
    s.num("column_width_a_m", d.a);
    s.text("time_scaling", "T = t*sqrt(2g/a) (front), tau = t*sqrt(g/a) (height), a = column width");
    run_figures(&mut s, stats, d.run.wall);
    literature_figures(&mut s, front, "");
    s.check("height_max_abs_err_tau_le_2_5", Target::AtMost(0.08), "spec §6 S2: column height within 0.08");
    s.check(
        "front_rms_rel_err_mm_shifted",
        Target::AtMost(0.05),
        "issue 26: vs Martin & Moyce a = 2.25 in, one fitted time shift",
    );
    s.check("front_shift_T_mm", Target::Within(0.0, 0.4), "issue 26: the fitted shift is a late release, 0 ≤ ΔT ≤ 0.4");
    s.check(
        "front_rms_rel_err_ko_shifted",
        Target::AtMost(0.07),
        "issue 26: vs Koshizuka & Oka 1996, one fitted time shift",
    );
    s.check("front_shift_T_ko", Target::Within(0.0, 0.4), "issue 26: 0 ≤ ΔT ≤ 0.4");
    rec.table("front_vs_literature", &["source", "T", "Z_exp", "Z_sim_raw", "Z_sim_shifted", "shift_T"])?;
    for (tag, label, data) in FRONT_DATA {
        let shift = s.get_f64(&format!("front_shift_T_{tag}"));
        plot(rec, "front_vs_literature", label, fa_axes(), (false, false), data.to_vec())?;
        let t_end = front.last().map_or(0.0, |x| x.0);
        for &(t, z) in data.iter().filter(|x| x.0 <= t_end) {
            let cells = [
                Cell::Text(tag.into()),
                Cell::Num(t),
                Cell::Num(z),
                Cell::Num(interp(front, t)),
                Cell::Num(interp(front, t - shift)),
                Cell::Num(shift),
            ];
            rec.row("front_vs_literature", &cells)?;
        }
    }
    plot(rec, "front_vs_literature", "simulation", fa_axes(), (false, false), front.clone())?;
    if let Some(list) = &p.resolution_study {
        for n in list.get(size) {
            let mut sc = scene.clone();
            sc.resolution.finest = n;
            let dir = format!("finest_{n}/");
            let r = dam_run(
                &sc,
                rec,
                RunOut { dir: &dir, frames: FrameOutput::NONE, snapshots: false, metrics: true, probes: None },
            )?;
            let (_, raw) = front_errors(&r.front, &MARTIN_MOYCE_FRONT);
            s.num(&format!("front_rms_rel_err_finest_{n}"), raw);
            literature_figures(&mut s, &r.front, &format!("_finest_{n}"));
            s.timing(&format!("wall_s_finest_{n}"), r.run.wall);
            plot(rec, "front_resolution", &format!("finest {n}"), fa_axes(), (false, false), r.front)?;
        }
        plot(
            rec,
            "front_resolution",
            &format!("finest {}", scene.resolution.finest),
            fa_axes(),
            (false, false),
            front.clone(),
        )?;
        plot(
            rec,
            "front_resolution",
            "Martin & Moyce 1952, a = 2.25 in",
            fa_axes(),
            (false, false),
            MM_FRONT_A225.to_vec(),
        )?;
    }
    let fa = fa_axes();
    plot(rec, "front_vs_mm", "simulation", fa, (false, false), front.clone())?;
    plot(rec, "front_vs_mm", "Martin & Moyce 1952", fa, (false, false), MARTIN_MOYCE_FRONT.to_vec())?;
    let ha = ("tau = t sqrt(g/a)", "H = h/(2a)");
    plot(rec, "height_vs_mm", "simulation", ha, (false, false), height.clone())?;
    plot(rec, "height_vs_mm", "Martin & Moyce 1952", ha, (false, false), MARTIN_MOYCE_HEIGHT.to_vec())?;
    Ok(s)
}

fn fa_axes() -> (&'static str, &'static str) {
    ("T = t sqrt(2g/a)", "Z = x/a")
}

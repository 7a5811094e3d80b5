//! Issue 26 item 5: the Martin & Moyce dam break with the gate modelled as a moving obstacle —
//! a plate of thickness `gate_thickness` against the column's face `x = a`, spanning the tank's
//! width, lifted at the constant speed `gate_speed` from `t = 0` (a `Translate` path). Does
//! modelling the release close the gap with the experiments without a fitted time shift?
//!
//! The front is compared with the same curves as `flip-tet/dam-break` (Martin & Moyce 1952 both
//! columns, Koshizuka & Oka 1996), raw and with one fitted time shift; every key carries the
//! suffix `_gate` (`front_rms_rel_err_mm_gate`, `front_rms_rel_err_mm_shifted_gate`,
//! `front_shift_T_mm_gate`, …). The force of the liquid on the gate is written per frame to
//! `probes.csv`; at the first step it is checked against the hydrostatic `ρ g w (2a)² / 2`.
//!
//! ```no_run
//! use flip_tet::experiments::{dam_break_gate, dam_break};
//! use geom_core::experiment::Size;
//! let p = dam_break_gate::Params { dam: flip_tet::presets::dam_break(), gate_thickness: 0.01, gate_speed: 1.0 };
//! let r = dam_break_gate::run(&p, Size::Quick, &mut geom_core::record::NullRecorder::default())?;
//! println!("raw front RMS vs Martin & Moyce {}", r.get_f64("front_rms_rel_err_mm_gate"));
//! # Ok::<(), flip_tet::error::SimError>(())
//! ```

use geom_core::experiment::{Report, Size};
use geom_core::kinematic::KinematicPath;
use geom_core::math::Vec3;
use geom_core::record::{Cell, Recorder};
use serde::{Deserialize, Serialize};

use super::dam_break::{column_width, literature_figures, DamRun, FRONT_DATA};
use super::obstacle_force::sanity;
use super::probes::Probes;
use super::{plot, simulate, sized_scene, FrameOutput, RunOut};
use crate::error::{Result, SimError};
use crate::metrics::{column_height, front_errors, front_position, height_max_abs_err};
use crate::obstacle::MovingObstacle;
use crate::reference::{MARTIN_MOYCE_FRONT, MARTIN_MOYCE_HEIGHT};
use crate::scene::{Scene, Shape};
use crate::sim::RHO;

/// Parameters (the scene file's `params`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Params {
    /// The dam break (`flip-tet/dam-break`'s parameters; its resolution study is not run here).
    pub dam: super::dam_break::Params,
    /// Gate thickness along `x` (m).
    pub gate_thickness: f64,
    /// Lifting speed (m/s).
    pub gate_speed: f64,
}

/// The dam-break scene with the gate: a `Box` from just outside the column face `x = a` to
/// `a + thickness`, from the floor to twice the domain height, through both `z` walls, moving up
/// at `speed` from `t = 0`.
pub fn gate_scene(scene: &Scene, thickness: f64, speed: f64) -> Result<Scene> {
    if !(thickness.is_finite() && thickness > 0.0 && speed.is_finite()) {
        return Err(SimError::InvalidScene(
            "dam-break-gate: gate_thickness > 0 and a finite gate_speed required".into(),
        ));
    }
    let a = column_width(scene)?;
    let (lo, hi) = (scene.domain.min, scene.domain.max);
    let x0 = lo[0] + a;
    // The column's last particle centres lie `r` from the face: the gap keeps them outside
    // `sdf > r` when sampling.
    let gap = 1e-9 * a;
    let ext = hi[2] - lo[2];
    let gate = Shape::Box {
        min: [x0 + gap, lo[1], lo[2] - ext],
        max: [x0 + gap + thickness, lo[1] + 2.0 * (hi[1] - lo[1]), hi[2] + ext],
    };
    let mut sc = scene.clone();
    sc.moving_obstacles
        .push(MovingObstacle { shape: gate, path: KinematicPath::Translate { velocity: Vec3::new(0.0, speed, 0.0) } });
    Ok(sc)
}

/// Runs the gated dam break and reports the front against the literature.
pub fn run(p: &Params, size: Size, rec: &mut dyn Recorder) -> Result<Report> {
    let d = &p.dam;
    let base = sized_scene(&d.scene, &d.finest, None, &d.duration, size);
    let scene = gate_scene(&base, p.gate_thickness, p.gate_speed)?;
    let a = column_width(&scene)?;
    let (wall, floor) = (scene.domain.min[0], scene.domain.min[1]);
    let g = -scene.gravity[1];
    let (mut front, mut height, mut gate_fx) = (Vec::new(), Vec::new(), Vec::new());
    let probes = Probes { obstacle_forces: true, ..Default::default() };
    let frames = FrameOutput { obj: d.obj_every, ply: d.ply_every, hires: d.hires_every };
    let out = RunOut { probes: Some(&probes), ..RunOut::full("", frames) };
    let run = simulate(&scene, rec, out, &mut |sim, st| {
        let parts = sim.particles();
        front.push((st.t * (2.0 * g / a).sqrt(), front_position(parts, wall) / a));
        height.push((st.t * (g / a).sqrt(), column_height(parts, wall, a / 8.0, floor) / (2.0 * a)));
        if gate_fx.is_empty() || st.frame_end {
            gate_fx.push((st.t, sim.obstacle_force(0).0.x));
        }
        Ok(())
    })?;
    let dr = DamRun { a, front, height, run };
    let mut s = Report::default();
    let (_, rms) = front_errors(&dr.front, &MARTIN_MOYCE_FRONT);
    s.num("front_rms_rel_err_gate", rms);
    literature_figures(&mut s, &dr.front, "_gate");
    s.num("height_max_abs_err_tau_le_2_5_gate", height_max_abs_err(&dr.height, &MARTIN_MOYCE_HEIGHT, 2.5));
    s.num("gate_speed_m_s", p.gate_speed);
    s.num("gate_thickness_m", p.gate_thickness);
    // Time for the gate to clear the column height 2a, in T = t sqrt(2g/a).
    s.num("gate_clear_T", 2.0 * a / p.gate_speed * (2.0 * g / a).sqrt());
    let width = scene.domain.max[2] - scene.domain.min[2];
    let hydro = 0.5 * RHO * g * width * (2.0 * a) * (2.0 * a);
    let f0 = gate_fx.first().map_or(f64::NAN, |x| x.1);
    s.num("gate_force_x_first_step_N", f0);
    s.num("gate_hydrostatic_N", hydro);
    s.num("gate_force_rel_err_first_step", (f0 - hydro).abs() / hydro);
    sanity(&mut s, &dr.run.stats, "gate");
    crate::metrics::run_figures(&mut s, &dr.run.stats, dr.run.wall);
    let fa = ("T = t sqrt(2g/a)", "Z = x/a");
    for (_, label, data) in FRONT_DATA {
        plot(rec, "front_vs_literature", label, fa, (false, false), data.to_vec())?;
    }
    plot(rec, "front_vs_literature", "simulation, gate lifted", fa, (false, false), dr.front.clone())?;
    plot(
        rec,
        "gate_force",
        "F_x on the gate",
        ("t (s)", "F_x (N)"),
        (false, false),
        gate_fx.iter().map(|x| (x.0, x.1)).collect(),
    )?;
    rec.table("front_gate", &["T", "Z"])?;
    for &(t, z) in &dr.front {
        rec.row("front_gate", &[Cell::Num(t), Cell::Num(z)])?;
    }
    Ok(s)
}

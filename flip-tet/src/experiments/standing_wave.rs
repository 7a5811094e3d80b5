//! S3 (spec §6): the first sloshing mode of a tank, `η = H + A cos(π x / L)`, released from rest;
//! the period of `η` at the wall against linear theory, the damping ratio, and the variants the
//! scene switches on (first-order free surface, depth `H = 0.25` m, uniform mesh), each in its
//! own sub-folder.
//!
//! ```no_run
//! use flip_tet::experiments::standing_wave;
//! use geom_core::experiment::Size;
//! let r = standing_wave::run(&flip_tet::presets::standing_wave(), Size::Quick, &mut geom_core::record::NullRecorder::default())?;
//! println!("period error {}", r.get_f64("period_rel_err"));
//! # Ok::<(), flip_tet::error::SimError>(())
//! ```

use geom_core::experiment::{BySize, Report, Size, Target};
use geom_core::record::Recorder;
use serde::{Deserialize, Serialize};

use super::{one, plot, simulate, sized_scene, FrameOutput, RunOut};
use crate::error::{Result, SimError};
use crate::metrics::{damping_ratio, rel_drift, run_figures, surface_height, zero_crossing_period};
use crate::presets::{with_depth, SHALLOW_DEPTH};
use crate::reference::WaveTheory;
use crate::scene::Scene;
use crate::sim::StepStats;

/// Parameters (the scene file's `params`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Params {
    /// The tank (first liquid shape: a `CosineSurface`).
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
    /// The extra runs of spec §6 S3 (all off when absent).
    #[serde(default)]
    pub variants: Variants,
}

/// The `variants: (...)` block (all off by default).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Variants {
    /// The wave with `second_order: false`.
    pub first_order: bool,
    /// The same wave over a pool of depth `H = 0.25` m.
    pub shallow: bool,
    /// The wave on a uniform mesh at the same finest resolution.
    pub uniform: bool,
    /// Finest resolution of the variant runs; `None` = the scene's.
    pub finest: Option<BySize<u32>>,
}

/// What one standing-wave run measured.
pub struct WaveRun {
    /// The theory of the run's scene.
    pub th: WaveTheory,
    /// `(t, η)` at the probe column after every step.
    pub eta: Vec<(f64, f64)>,
    /// Probe `x` (m): `x0 + h_min/2`.
    pub xp: f64,
    /// Period from the zero crossings after half a theoretical period (s).
    pub period: Option<f64>,
    /// Damping ratio ζ (log decrement of the half-cycle extrema over the whole run).
    pub damping: Option<f64>,
    /// Per-step statistics.
    pub stats: Vec<StepStats>,
    /// Wall time (s).
    pub wall: f64,
}

impl WaveRun {
    /// `|T_sim − T_th| / T_th` (NaN without a period).
    pub fn period_rel_err(&self) -> f64 {
        self.period.map_or(f64::NAN, |p| (p - self.th.period).abs() / self.th.period)
    }

    /// The linear-theory `η` at the probe at the run's sample times.
    pub fn theory_series(&self) -> Vec<(f64, f64)> {
        self.eta.iter().map(|&(t, _)| (t, self.th.eta(self.xp, t))).collect()
    }
}

/// Runs a standing wave with the §6 S3 probe: `η(t)` at `x = x0 + h_min/2`, mid-`z`.
pub fn wave_run(scene: &Scene, rec: &mut dyn Recorder, out: RunOut) -> Result<WaveRun> {
    let th = WaveTheory::of(scene).ok_or_else(|| {
        SimError::InvalidScene("standing-wave: the first liquid shape must be a CosineSurface".into())
    })?;
    let zc = 0.5 * (scene.domain.min[2] + scene.domain.max[2]);
    let mut eta: Vec<(f64, f64)> = Vec::new();
    let mut xp = th.x0;
    let run = simulate(scene, rec, out, &mut |sim, st| {
        xp = th.x0 + sim.spec().h_min() / 2.0;
        if let Some(h) = surface_height(sim, xp, zc) {
            eta.push((st.t, h));
        }
        Ok(())
    })?;
    let period = zero_crossing_period(&eta, 0.5 * th.period);
    let damping = damping_ratio(&eta, 0.0);
    Ok(WaveRun { th, eta, xp, period, damping, stats: run.stats, wall: run.wall })
}

const PLOT: &str = "eta_vs_time";
const AXES: (&str, &str) = ("t (s)", "eta (m)");

/// Runs the graded second-order wave and the variants the parameters switch on.
pub fn run(p: &Params, size: Size, rec: &mut dyn Recorder) -> Result<Report> {
    let scene = sized_scene(&p.scene, &p.finest, None, &p.duration, size);
    let frames = FrameOutput { obj: p.obj_every, ply: p.ply_every, hires: p.hires_every };
    let r = wave_run(&scene, rec, RunOut::full("", frames))?;
    let mut s = Report::default();
    s.num("period_theory_s", r.th.period);
    s.num("period_sim_s", r.period.unwrap_or(f64::NAN));
    s.num("period_rel_err", r.period_rel_err());
    s.num("amplitude_initial_m", r.th.amp);
    s.num("damping_ratio", r.damping.unwrap_or(f64::NAN));
    s.num("volume_drift_rel", rel_drift(&r.stats, |x| x.vol_levelset));
    run_figures(&mut s, &r.stats, r.wall);
    s.check("period_rel_err", Target::AtMost(0.03), "spec §6 S3: period within 3 % of linear theory");
    plot(rec, PLOT, "simulation", AXES, (false, false), r.eta.clone())?;
    plot(rec, PLOT, "linear theory", AXES, (false, false), r.theory_series())?;
    variants(p, &scene, &r, size, rec, &mut s)?;
    Ok(s)
}

fn variants(
    p: &Params,
    scene: &Scene,
    main: &WaveRun,
    size: Size,
    rec: &mut dyn Recorder,
    s: &mut Report,
) -> Result<()> {
    let v = &p.variants;
    let every = FrameOutput::surface(p.obj_every);
    let finest = v.finest.as_ref().map_or(scene.resolution.finest, |f| f.get(size));
    let mut base = scene.clone();
    base.resolution.finest = finest;
    if v.first_order || v.shallow || v.uniform {
        s.count("variants_finest", u64::from(finest));
    }
    let own;
    let graded = if (v.first_order || v.uniform) && finest != scene.resolution.finest {
        own = wave_run(&base, rec, RunOut::full("graded/", every))?;
        s.num("variants_graded_period_rel_err", own.period_rel_err());
        s.num("variants_graded_damping_ratio", own.damping.unwrap_or(f64::NAN));
        s.timing("variants_graded_wall_s", own.wall);
        plot(rec, PLOT, &format!("graded second order, finest {finest}"), AXES, (false, false), own.eta.clone())?;
        s.text(
            "variants_size_note",
            "the S3 variants run at variants_finest (time budget); variants_graded_* is the graded second-order wave at that size",
        );
        &own
    } else {
        main
    };
    if v.first_order {
        let mut sc = base.clone();
        sc.pressure.second_order = false;
        let r = wave_run(&sc, rec, RunOut::full("first_order/", every))?;
        s.num("first_order_period_sim_s", r.period.unwrap_or(f64::NAN));
        s.num("first_order_period_rel_err", r.period_rel_err());
        s.num("first_order_damping_ratio", r.damping.unwrap_or(f64::NAN));
        s.num("first_order_volume_drift_rel", rel_drift(&r.stats, |x| x.vol_levelset));
        s.timing("first_order_wall_s", r.wall);
        plot(rec, PLOT, &format!("first-order BC, finest {finest}"), AXES, (false, false), r.eta)?;
    }
    if v.shallow {
        let sc = with_depth(&base, SHALLOW_DEPTH)?;
        let r = wave_run(&sc, rec, RunOut::full("h025/", every))?;
        s.num("h025_period_theory_s", r.th.period);
        s.num("h025_period_sim_s", r.period.unwrap_or(f64::NAN));
        s.num("h025_period_rel_err", r.period_rel_err());
        s.num("h025_damping_ratio", r.damping.unwrap_or(f64::NAN));
        s.timing("h025_wall_s", r.wall);
        plot(rec, "h025/eta_vs_time", "simulation", AXES, (false, false), r.eta.clone())?;
        plot(rec, "h025/eta_vs_time", "linear theory", AXES, (false, false), r.theory_series())?;
    }
    if v.uniform {
        let mut sc = base.clone();
        sc.resolution.coarsest = finest;
        let r = wave_run(&sc, rec, RunOut::full("uniform/", every))?;
        s.num("uniform_period_sim_s", r.period.unwrap_or(f64::NAN));
        s.num("uniform_period_rel_err", r.period_rel_err());
        s.num("uniform_damping_ratio", r.damping.unwrap_or(f64::NAN));
        s.timing("uniform_wall_s", r.wall);
        let diff = match (graded.period, r.period) {
            (Some(g), Some(u)) => (g - u).abs() / u,
            _ => f64::NAN,
        };
        s.num("graded_vs_uniform_period_rel_diff", diff);
        s.check(
            "graded_vs_uniform_period_rel_diff",
            Target::AtMost(0.01),
            "spec §6 S3: graded vs uniform period within 1 %",
        );
        plot(rec, PLOT, &format!("uniform mesh, finest {finest}"), AXES, (false, false), r.eta)?;
    }
    Ok(())
}

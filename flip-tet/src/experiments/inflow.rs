//! Inflow and outflow (issue 26 item 4): a disc emitter pours a jet into a shallow pool. The
//! delivered volume is measured independently of the emitter's bookkeeping — as the change of
//! the liquid volume of the node level set — and compared with `rate × emission time`
//! (`inflow_volume_rel_err`, issue 26: ≤ 0.02); the particle-volume balance
//! (`inflow_particle_volume_rel_err`) is reported beside it. A second run (`outflow/`) adds the
//! `outflow` regions: drained volume (`outflow_volume_m3`) and the particle-volume balance
//! `emitted − drained = Δ particle volume` (`outflow_particle_balance_rel_err`, relative to the
//! emitted volume).
//!
//! ```no_run
//! use flip_tet::experiments::inflow;
//! use geom_core::experiment::Size;
//! #[derive(serde::Deserialize)]
//! struct File { params: inflow::Params }
//! let text = std::fs::read_to_string("scenes/flip-tet/inflow.ron")?;
//! let opts = ron::Options::default().with_default_extension(ron::extensions::Extensions::IMPLICIT_SOME);
//! let p = opts.from_str::<File>(&text)?.params;
//! let r = inflow::run(&p, Size::Quick, &mut geom_core::record::NullRecorder::default())?;
//! println!("delivered volume error {}", r.get_f64("inflow_volume_rel_err"));
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

use geom_core::experiment::{BySize, Report, Size, Target};
use geom_core::record::Recorder;
use serde::{Deserialize, Serialize};

use super::{one, plot, simulate, sized_scene, FrameOutput, RunOut};
use crate::error::{Result, SimError};
use crate::metrics::{max_speed, run_figures};
use crate::scene::Scene;
use crate::sim::FlipTetSim;
use crate::surface::liquid_volume;

/// Parameters (the scene file's `params`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Params {
    /// The tank with its `emitters` and `outflow` regions.
    pub scene: Scene,
    /// Finest resolution per size.
    pub finest: BySize<u32>,
    /// Duration per size (s).
    pub duration: BySize<f64>,
    /// Surface OBJ every this many frames (0 = never).
    #[serde(default = "one")]
    pub obj_every: u64,
    /// Outflow regions of the second run (none: no second run).
    #[serde(default)]
    pub outflow: Vec<crate::scene::Shape>,
}

/// Runs the scene and compares the delivered volume with the emitters' rates.
pub fn run(p: &Params, size: Size, rec: &mut dyn Recorder) -> Result<Report> {
    let scene = sized_scene(&p.scene, &p.finest, None, &p.duration, size);
    if scene.emitters.is_empty() {
        return Err(SimError::InvalidScene("inflow: the scene needs at least one emitter".into()));
    }
    let expected: f64 = scene
        .emitters
        .iter()
        .map(|e| e.rate * (e.stop.unwrap_or(f64::INFINITY).min(scene.duration) - e.start).max(0.0))
        .sum();
    let sim0 = FlipTetSim::new(&scene)?;
    let (v_ls0, v_p0) = (liquid_volume(sim0.mesh(), sim0.phi()), sim0.particles().total_volume());
    drop(sim0);
    let mut series = Vec::new();
    let run = simulate(&scene, rec, RunOut::full("", FrameOutput::surface(p.obj_every)), &mut |sim, st| {
        if st.frame_end {
            series.push((st.t, st.vol_levelset - v_ls0, sim.emitted_volume()));
        }
        Ok(())
    })?;
    let sim = &run.sim;
    let last = run.stats.last().ok_or_else(|| SimError::InvalidScene("inflow: zero duration".into()))?;
    let drained = sim.outflow_volume;
    let delivered_ls = last.vol_levelset - v_ls0;
    let delivered_p = last.vol_particles - v_p0 + sim.deleted_volume;
    let mut s = Report::default();
    s.num("inflow_expected_volume_m3", expected);
    s.num("inflow_emitted_volume_m3", sim.emitted_volume());
    s.num("inflow_drained_volume_m3", drained);
    s.num("inflow_delivered_levelset_m3", delivered_ls);
    s.num("inflow_volume_rel_err", (delivered_ls - expected).abs() / expected);
    s.num("inflow_particle_volume_rel_err", (delivered_p - expected).abs() / expected);
    s.num("max_speed", max_speed(&run.stats));
    s.flag("finite", run.stats.iter().all(|x| x.vol_levelset.is_finite() && x.kinetic_energy.is_finite()));
    s.count("final_particles", last.n_particles as u64);
    run_figures(&mut s, &run.stats, run.wall);
    let axes = ("t (s)", "volume (m^3)");
    plot(rec, "volume", "level-set volume change", axes, (false, false), series.iter().map(|x| (x.0, x.1)).collect())?;
    plot(rec, "volume", "emitted", axes, (false, false), series.iter().map(|x| (x.0, x.2)).collect())?;
    if !p.outflow.is_empty() {
        let mut sc = scene.clone();
        sc.outflow = p.outflow.clone();
        let r = simulate(&sc, rec, RunOut::full("outflow/", FrameOutput::surface(p.obj_every)), &mut |_, _| Ok(()))?;
        let l = r.stats.last().ok_or_else(|| SimError::InvalidScene("inflow: zero duration".into()))?;
        let em = r.sim.emitted_volume();
        s.num("outflow_volume_m3", r.sim.outflow_volume);
        s.num("outflow_emitted_volume_m3", em);
        let bal = (l.vol_particles - v_p0) - (em - r.sim.deleted_volume);
        s.num("outflow_particle_balance_rel_err", bal.abs() / em);
        s.num("outflow_max_speed", max_speed(&r.stats));
    }
    s.check("inflow_volume_rel_err", Target::AtMost(0.02), "issue 26: delivered volume = rate x time within 2 %");
    Ok(s)
}

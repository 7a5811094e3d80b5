//! The run protocol every simulation experiment shares: step a scene to its duration, hand each
//! step's `metrics.csv` row, the surface frames, particle point sets, high-resolution surfaces and
//! rendered snapshots to the [`Recorder`] as they are computed, and call a probe after each step.

use std::time::Instant;

use geom_core::record::{Attribute, Cell, MeshFrame, PointFrame, Recorder};

use super::probes::Probes;
use super::snapshots::Snapshots;
use crate::error::Result;
use crate::metrics::{csv_row, CSV_HEADER};
use crate::particles::ParticleFlags;
use crate::scene::Scene;
use crate::sim::{FlipTetSim, StepStats};

/// Which frames of a run are written: the simulation surface as OBJ every `obj` frames, the
/// particles as PLY every `ply` frames, the high-resolution output surface (spec §3.11.6) every
/// `hires` frames (0 = never).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct FrameOutput {
    /// Simulation surface (`frames/NNNN.obj`) every this many frames.
    pub obj: u64,
    /// Particles (`particles/NNNN.ply`: `pscale` = radius (m), `vx`, `vy`, `vz` (m/s), `phi` (m))
    /// every this many frames.
    pub ply: u64,
    /// High-resolution output surface (`frames_hires/NNNN.obj`) every this many frames.
    pub hires: u64,
}

impl FrameOutput {
    /// Nothing written (benchmarks, comparison runs).
    pub const NONE: Self = Self { obj: 0, ply: 0, hires: 0 };

    /// Only the simulation surface, every `obj` frames.
    pub fn surface(obj: u64) -> Self {
        Self { obj, ..Self::NONE }
    }
}

/// Where one run's outputs go inside an experiment's outputs: `dir` is `""` for the main run or a
/// sub-folder with a trailing slash (`"s1b/"`); `snapshots` renders the four surface snapshots.
#[derive(Clone, Copy, Debug)]
pub struct RunOut<'a> {
    /// Prefix of every output name.
    pub dir: &'a str,
    /// Frames to write.
    pub frames: FrameOutput,
    /// Render `snapshots/frame_NNNN.png` and `surface_snapshots.png`.
    pub snapshots: bool,
    /// Write `metrics.csv`.
    pub metrics: bool,
    /// Probes sampled at every frame into `probes.csv` (none when `None` or empty).
    pub probes: Option<&'a Probes>,
}

impl<'a> RunOut<'a> {
    /// Everything of a scene run in `dir` (metrics, snapshots, the given frames).
    pub fn full(dir: &'a str, frames: FrameOutput) -> Self {
        Self { dir, frames, snapshots: true, metrics: true, probes: None }
    }

    /// Nothing at all (benchmarks).
    pub fn silent() -> Self {
        Self { dir: "", frames: FrameOutput::NONE, snapshots: false, metrics: false, probes: None }
    }
}

/// A finished run.
pub struct SimRun {
    /// Per-step statistics.
    pub stats: Vec<StepStats>,
    /// Wall time (s), snapshot rendering included.
    pub wall: f64,
    /// The simulator at the end.
    pub sim: FlipTetSim,
    /// Probe values per frame (frame 0 first): `(t, heights m, pressures Pa)`.
    pub probes: Vec<(f64, Vec<f64>, Vec<f64>)>,
}

impl SimRun {
    /// Mean particle count over the steps.
    pub fn particles_avg(&self) -> f64 {
        self.stats.iter().map(|x| x.n_particles as f64).sum::<f64>() / self.stats.len().max(1) as f64
    }
}

/// Hands the particles to the recorder as a point frame.
pub fn record_particles(rec: &mut dyn Recorder, sequence: &str, index: usize, sim: &FlipTetSim) -> Result<()> {
    let p = sim.particles();
    let comp = |a: usize| p.v.iter().map(|v| v[a]).collect::<Vec<f64>>();
    let (vx, vy, vz) = (comp(0), comp(1), comp(2));
    let attributes = [
        Attribute { name: "pscale", values: &p.r },
        Attribute { name: "vx", values: &vx },
        Attribute { name: "vy", values: &vy },
        Attribute { name: "vz", values: &vz },
        Attribute { name: "phi", values: &p.phi },
    ];
    rec.points(&PointFrame { sequence, index, time: sim.time(), positions: &p.x, attributes: &attributes })?;
    Ok(())
}

/// Runs `scene` to its duration (spec §3.1 steps), recording as `out` says and calling `probe`
/// after every step.
pub fn simulate(
    scene: &Scene,
    rec: &mut dyn Recorder,
    out: RunOut,
    probe: &mut dyn FnMut(&FlipTetSim, &StepStats) -> Result<()>,
) -> Result<SimRun> {
    let t0 = Instant::now();
    let mut sim = FlipTetSim::new(scene)?;
    let table = format!("{}metrics", out.dir);
    if out.metrics {
        rec.table(&table, &CSV_HEADER)?;
    }
    let mut snaps = if out.snapshots { Some(Snapshots::new(scene, out.dir)?) } else { None };
    let every = out.frames;
    let (seq_obj, seq_ply, seq_hi) =
        (format!("{}frames", out.dir), format!("{}particles", out.dir), format!("{}frames_hires", out.dir));
    let mut write_frame = |sim: &FlipTetSim, frame: u64, rec: &mut dyn Recorder| -> Result<()> {
        if every.obj > 0 && frame.is_multiple_of(every.obj) {
            if let Some(m) = sim.surface() {
                let index = (frame / every.obj) as usize;
                let f = MeshFrame {
                    sequence: &seq_obj,
                    index,
                    time: sim.time(),
                    positions: &m.positions,
                    faces: &m.faces,
                    attributes: &[],
                };
                rec.frame(&f)?;
            }
        }
        if every.ply > 0 && frame.is_multiple_of(every.ply) {
            record_particles(rec, &seq_ply, frame as usize, sim)?;
        }
        if every.hires > 0 && frame.is_multiple_of(every.hires) {
            let o = sim.output_surface()?;
            if o.mesh.n_faces() > 0 {
                let index = (frame / every.hires) as usize;
                let f = MeshFrame {
                    sequence: &seq_hi,
                    index,
                    time: sim.time(),
                    positions: &o.mesh.positions,
                    faces: &o.mesh.faces,
                    attributes: &[],
                };
                rec.frame(&f)?;
            }
        }
        if let Some(s) = snaps.as_mut() {
            s.frame(sim, frame, rec)?;
        }
        Ok(())
    };
    write_frame(&sim, 0, rec)?;
    let probes = out.probes.filter(|p| !p.is_empty());
    let probe_table = format!("{}probes", out.dir);
    let mut probe_values = Vec::new();
    if let Some(p) = probes {
        p.declare(rec, &probe_table, sim.obstacles().len())?;
        let (h, pr) = p.record(&sim, rec, &probe_table)?;
        probe_values.push((sim.time(), h, pr));
    }
    let mut all = Vec::new();
    let mut frame = 0u64;
    let total = (scene.duration * scene.fps).round().max(1.0) as u64;
    while sim.time() < scene.duration - 1e-9 {
        let st = sim.step()?;
        if out.metrics {
            rec.row(&table, &csv_row(&st).into_iter().map(Cell::Num).collect::<Vec<_>>())?;
        }
        probe(&sim, &st)?;
        if st.frame_end {
            frame += 1;
            write_frame(&sim, frame, rec)?;
            if let Some(p) = probes {
                let (h, pr) = p.record(&sim, rec, &probe_table)?;
                probe_values.push((sim.time(), h, pr));
            }
            rec.progress(frame, total);
        }
        all.push(st);
    }
    let wall = t0.elapsed().as_secs_f64();
    if let Some(s) = snaps {
        s.finish(rec)?;
    }
    Ok(SimRun { stats: all, wall, sim, probes: probe_values })
}

/// What a frame-by-frame run (S5, S6) records per frame: `(t, particles, ballistic, wall s of
/// the frame)`, besides totals.
#[derive(Clone, Debug, Default)]
pub struct FrameLog {
    /// Sum over steps of the particle count.
    pub particle_steps: f64,
    /// Steps taken.
    pub steps: u64,
    /// Wall time (s).
    pub wall_s: f64,
    /// Per frame: `(t, particles, ballistic, frame wall s)`.
    pub frames: Vec<(f64, usize, usize, f64)>,
    /// Particles at the start.
    pub initial_particles: usize,
    /// Largest particle count after any step.
    pub peak_particles: usize,
    /// Particles at the end.
    pub final_particles: usize,
    /// Finest cube edge (m).
    pub h_min: f64,
    /// Coarsest particle radius `h_root / 4` (m).
    pub r_max: f64,
    /// Initial particle volume `Σ (2r)³` (m³).
    pub initial_liquid_volume: f64,
}

/// Runs `scene` frame by frame (`advance_to` each frame time); `on_frame(sim, frame)` sees the
/// state after each frame (and frame 0 before the first step).
pub fn simulate_frames(scene: &Scene, mut on_frame: impl FnMut(&FlipTetSim, usize) -> Result<()>) -> Result<FrameLog> {
    let t0 = Instant::now();
    let mut sim = FlipTetSim::new(scene)?;
    let n0 = sim.particles().len();
    let vol0: f64 = (0..n0).map(|i| sim.particles().volume(i)).sum();
    let spec = *sim.spec();
    let mut log = FrameLog {
        initial_particles: n0,
        peak_particles: n0,
        final_particles: n0,
        h_min: spec.h_min(),
        r_max: spec.h_root / crate::sizing::C_H,
        initial_liquid_volume: vol0,
        ..Default::default()
    };
    let n_frames = (scene.duration * scene.fps).round().max(1.0) as usize;
    on_frame(&sim, 0)?;
    for f in 1..=n_frames {
        let tf = Instant::now();
        let stats = sim.advance_to(f as f64 / scene.fps)?;
        for s in &stats {
            log.particle_steps += s.n_particles as f64;
            log.steps += 1;
            log.peak_particles = log.peak_particles.max(s.n_particles);
        }
        let p = sim.particles();
        let nb = p.flags.iter().filter(|fl| fl.has(ParticleFlags::BALLISTIC)).count();
        log.frames.push((sim.time(), p.len(), nb, tf.elapsed().as_secs_f64()));
        log.final_particles = p.len();
        on_frame(&sim, f)?;
    }
    log.wall_s = t0.elapsed().as_secs_f64();
    Ok(log)
}

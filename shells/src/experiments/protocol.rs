//! The run protocol every `shells` experiment (and `tracks`' untracked twin) shares: step a
//! simulation frame by frame, record each frame the moment it exists, watch the physical-sanity
//! invariants after every step ([`Sanity`]), time every step, and sum the per-step statistics.
//! [`sized`] gives a scene's mesh resolution and duration at a run size.

use std::time::Instant;

use geom_core::experiment::{BySize, Size};
use geom_core::record::{Attribute, Cell, MeshFrame, Recorder};

use crate::error::Result;
use crate::integrator::StepStats;
use crate::metrics::Sanity;
use crate::scene::{MeshSpec, ShellScene};
use crate::sim::ShellSim;

/// The shell scene at a run size: `resolution` sets a grid's (nx, ny) vertices or a tube's
/// (around, along) (an OBJ mesh is kept), `duration` the simulated time (s); `None` keeps the
/// scene's value.
pub fn sized(
    shell: &ShellScene,
    resolution: Option<&BySize<(u32, u32)>>,
    duration: Option<&BySize<f64>>,
    size: Size,
) -> ShellScene {
    let mut s = shell.clone();
    if let Some(r) = resolution {
        let (a, b) = r.get(size);
        match &mut s.mesh {
            MeshSpec::Grid { nx, ny, .. } => (*nx, *ny) = (a, b),
            MeshSpec::Tube { around, along, .. } => (*around, *along) = (a, b),
            MeshSpec::Obj { .. } => {}
        }
    }
    if let Some(d) = duration {
        s.duration = d.get(size);
    }
    s
}

/// How to run.
#[derive(Clone, Debug)]
pub struct RunPlan {
    /// Output frames (frame 0, the initial state, is recorded too).
    pub frames: usize,
    /// Steps per frame.
    pub substeps: u32,
    /// Step size (s).
    pub h: f64,
    /// Record every n-th frame's mesh (0 = none).
    pub frame_every: usize,
    /// The frame sequence's name (`"frames"`, `"tracked"` …).
    pub sequence: String,
    /// Count self-intersections on every recorded frame (exact test; costs time).
    pub count_intersections: bool,
    /// Track the energy for `energy_gain_rel`.
    pub track_energy: bool,
    /// Write the per-step table `steps_<sequence>` and the per-frame table `frames_<sequence>`
    /// (t, energies, exact self-intersections of the frame when they are counted, else −1).
    pub tables: bool,
}

/// What a run measured.
#[derive(Clone, Debug, Default)]
pub struct RunStats {
    /// Steps taken.
    pub steps: u64,
    /// Wall time of every step (s).
    pub step_wall: Vec<f64>,
    /// Sum of the per-step statistics (times, counts; `contact.min_gap` is the minimum,
    /// `contact.kappa` the last, `lin_residual` the maximum).
    pub totals: StepStats,
    /// Largest exact self-intersection count over recorded frames.
    pub max_intersections: u64,
    /// Steps that failed (0 or 1: the run stops at the first failure).
    pub nan_steps: u64,
    /// The error that stopped the run, if any (frames recorded so far stay recorded).
    pub error: Option<String>,
    /// Largest impact zone of the Bridson filter (vertices).
    pub max_zone: u32,
    /// Largest number of active IPC contacts in a step.
    pub max_active_contacts: u32,
    /// Newton iterations per step.
    pub newton_iters: Vec<u32>,
}

impl RunStats {
    /// Adds one step's statistics.
    pub fn add(&mut self, st: &StepStats, wall: f64) {
        self.steps += 1;
        self.step_wall.push(wall);
        self.newton_iters.push(st.newton_iters);
        let t = &mut self.totals;
        t.t_assembly += st.t_assembly;
        t.t_factor += st.t_factor;
        t.t_solve += st.t_solve;
        t.t_collision += st.t_collision;
        t.n_proximity += st.n_proximity;
        t.n_ccd += st.n_ccd;
        t.n_impact_zones += st.n_impact_zones;
        t.n_frozen += st.n_frozen;
        t.plastic_events += st.plastic_events;
        t.newton_iters += st.newton_iters;
        t.line_search_halvings += st.line_search_halvings;
        t.lin_residual = geom_core::stats::nan_max(t.lin_residual, st.lin_residual);
        t.regularization_shift = t.regularization_shift.max(st.regularization_shift);
        let c = &mut t.contact;
        c.ccd_clamps += st.contact.ccd_clamps;
        c.line_search_failures += st.contact.line_search_failures;
        c.unconverged += st.contact.unconverged;
        c.contact_free_steps += st.contact.contact_free_steps;
        c.friction = c.friction.max(st.contact.friction);
        c.active = c.active.max(st.contact.active);
        c.min_gap = if self.steps == 1 { st.contact.min_gap } else { c.min_gap.min(st.contact.min_gap) };
        c.kappa = st.contact.kappa;
        self.max_zone = self.max_zone.max(st.max_zone_size);
        self.max_active_contacts = self.max_active_contacts.max(st.contact.active);
    }

    /// Adds the statistics of another run (of a scene made of several runs): step counts,
    /// times and counters summed, maxima kept, `contact.min_gap` the minimum, the first error
    /// kept.
    pub fn merge(&mut self, o: &RunStats) {
        self.steps += o.steps;
        self.step_wall.extend_from_slice(&o.step_wall);
        self.newton_iters.extend_from_slice(&o.newton_iters);
        self.max_intersections = self.max_intersections.max(o.max_intersections);
        self.nan_steps += o.nan_steps;
        if self.error.is_none() {
            self.error.clone_from(&o.error);
        }
        self.max_zone = self.max_zone.max(o.max_zone);
        self.max_active_contacts = self.max_active_contacts.max(o.max_active_contacts);
        let (t, u) = (&mut self.totals, &o.totals);
        t.t_assembly += u.t_assembly;
        t.t_factor += u.t_factor;
        t.t_solve += u.t_solve;
        t.t_collision += u.t_collision;
        t.n_proximity += u.n_proximity;
        t.n_ccd += u.n_ccd;
        t.n_impact_zones += u.n_impact_zones;
        t.n_frozen += u.n_frozen;
        t.plastic_events += u.plastic_events;
        t.newton_iters += u.newton_iters;
        t.line_search_halvings += u.line_search_halvings;
        t.lin_residual = geom_core::stats::nan_max(t.lin_residual, u.lin_residual);
        t.regularization_shift = t.regularization_shift.max(u.regularization_shift);
        let (c, d) = (&mut t.contact, &u.contact);
        c.ccd_clamps += d.ccd_clamps;
        c.line_search_failures += d.line_search_failures;
        c.unconverged += d.unconverged;
        c.friction = c.friction.max(d.friction);
        c.active = c.active.max(d.active);
        c.min_gap = c.min_gap.min(d.min_gap);
        c.kappa = d.kappa;
    }

    /// Mean wall time per step (s).
    pub fn s_per_step(&self) -> f64 {
        geom_core::stats::mean(&self.step_wall)
    }
}

/// Runs `plan` on `sim`, recording frames and tables into `rec` and observing every step in
/// `sanity`. `per_step` runs after every successful step (scene-specific probes). A failed step
/// ends the run with `error` set and `nan_steps = 1`; the frames recorded so far stay.
pub fn run(
    sim: &mut ShellSim,
    plan: &RunPlan,
    sanity: &mut Sanity,
    rec: &mut dyn Recorder,
    mut per_step: impl FnMut(&ShellSim, &StepStats),
) -> Result<RunStats> {
    let faces = sim.mesh().tris.clone();
    let mut rs =
        RunStats { totals: StepStats { contact: Default::default(), ..Default::default() }, ..Default::default() };
    rs.totals.contact.min_gap = f64::INFINITY;
    let seq = plan.sequence.as_str();
    let steps_table = format!("steps_{seq}");
    let frames_table = format!("frames_{seq}");
    if plan.tables {
        rec.table(
            &frames_table,
            &["frame", "t", "kinetic_J", "membrane_J", "bending_J", "gravity_J", "intersections"],
        )?;
        rec.table(
            &steps_table,
            &[
                "t",
                "wall_s",
                "newton_iters",
                "active_contacts",
                "min_gap_m",
                "assembly_s",
                "factor_s",
                "solve_s",
                "collision_s",
            ],
        )?;
    }
    let record = |sim: &ShellSim, f: usize, rec: &mut dyn Recorder, rs: &mut RunStats| -> Result<()> {
        let mut inter = -1i64;
        if plan.frame_every > 0 && f.is_multiple_of(plan.frame_every) {
            let strain = edge_strain_per_vertex(sim);
            let attrs = [Attribute { name: "strain", values: &strain }];
            rec.frame(&MeshFrame {
                sequence: seq,
                index: f / plan.frame_every,
                time: sim.state().t,
                positions: &sim.state().q,
                faces: &faces,
                attributes: &attrs,
            })?;
            if plan.count_intersections {
                let k = crate::collision::count_self_intersections(&sim.state().q, &faces) as u64;
                rs.max_intersections = rs.max_intersections.max(k);
                inter = k as i64;
            }
        }
        if plan.tables {
            let e = sim.energies();
            rec.row(
                &frames_table,
                &[
                    Cell::Int(f as i64),
                    Cell::from(sim.state().t),
                    Cell::from(e.kinetic),
                    Cell::from(e.membrane),
                    Cell::from(e.bending),
                    Cell::from(e.gravity),
                    Cell::Int(inter),
                ],
            )?;
        }
        Ok(())
    };
    record(sim, 0, rec, &mut rs)?;
    let total = (plan.frames as u64) * plan.substeps as u64;
    'outer: for f in 1..=plan.frames {
        for _ in 0..plan.substeps {
            let t0 = Instant::now();
            match sim.step(plan.h) {
                Ok(st) => {
                    let wall = t0.elapsed().as_secs_f64();
                    rs.add(&st, wall);
                    let e = plan.track_energy.then(|| sim.energies().total());
                    sanity.observe(&sim.state().q, sim.state().t, e);
                    if plan.tables {
                        rec.row(
                            &steps_table,
                            &[
                                Cell::from(sim.state().t),
                                Cell::from(wall),
                                Cell::from(st.newton_iters),
                                Cell::from(st.contact.active),
                                Cell::from(st.contact.min_gap),
                                Cell::from(st.t_assembly),
                                Cell::from(st.t_factor),
                                Cell::from(st.t_solve),
                                Cell::from(st.t_collision),
                            ],
                        )?;
                    }
                    per_step(sim, &st);
                    rec.progress(rs.steps, total);
                }
                Err(e) => {
                    rs.nan_steps += 1;
                    rs.error = Some(e.to_string());
                    break 'outer;
                }
            }
        }
        record(sim, f, rec, &mut rs)?;
    }
    Ok(rs)
}

/// Per vertex, the largest strain ℓ/ℓ̄ − 1 of its edges (the colour of previews).
pub fn edge_strain_per_vertex(sim: &ShellSim) -> Vec<f64> {
    let m = sim.mesh();
    let q = &sim.state().q;
    let mut out = vec![0.0f64; q.len()];
    for e in &m.edges {
        let (a, b) = (e[0] as usize, e[1] as usize);
        let s = (q[a] - q[b]).norm() / (m.rest[a] - m.rest[b]).norm() - 1.0;
        out[a] = out[a].max(s);
        out[b] = out[b].max(s);
    }
    out
}

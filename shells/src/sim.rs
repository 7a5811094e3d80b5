//! [`ShellSim`]: the simulator — state, one implicit step (shells.md §3.7), energies.

use crate::assembly::{Assembler, EvalInput};
use crate::collision::Collider;
use crate::contact::Ipc;
use crate::effects::ContactMethod;
use crate::effects::{BlockTriplets, Effects};
use crate::error::{Error, Result};
use crate::integrator::{DofMap, ImplicitSystem, IntegratorKind, IntegratorSettings, StepStats, VelocitySolve};
use crate::kernels::bending::bending_energy;
use crate::kernels::hinge::{hinge_angle, hinge_is_collapsed};
use crate::kernels::membrane::{membrane_energy, Membrane};
use crate::kernels::plastic::plastic_update_clamped;
use crate::material::Material;
use crate::mesh::ShellMesh;
use crate::wind::WindField;
use geom_core::linalg::{rel_residual, LltSymbolic, Ordering, SparseLlt};
use geom_core::math::{Mat3, Pt3, Vec3};
use geom_core::mesh::Uv;
use geom_core::NONE;
use rayon::prelude::*;
use std::time::Instant;

/// Positions and velocities at time t.
#[derive(Clone, Debug, PartialEq)]
pub struct ShellState {
    /// Time (s).
    pub t: f64,
    /// Positions (m).
    pub q: Vec<Pt3>,
    /// Velocities (m/s).
    pub v: Vec<Vec3>,
}

/// Path of a kinematic vertex: `f(t, vertex) -> position`.
pub type KinematicFn = Box<dyn Fn(f64, u32) -> Pt3 + Send + Sync>;

/// Prescribed vertices.
pub enum VertexConstraint {
    /// Fixed at their initial positions.
    Pinned(Vec<u32>),
    /// Scripted: position p(t, i) at every step end.
    Kinematic(Vec<u32>, KinematicFn),
}

/// Everything needed to build a simulation.
pub struct ShellSceneDesc {
    /// Rest positions (m).
    pub rest: Vec<Pt3>,
    /// Triangles (orientation repaired if needed).
    pub faces: Vec<[u32; 3]>,
    /// Rest UVs (only needed by `WarpSource::RestUv`).
    pub uv: Option<Uv>,
    /// Initial positions (default: the rest positions).
    pub initial: Option<Vec<Pt3>>,
    /// Initial velocities (default: zero).
    pub initial_velocity: Option<Vec<Vec3>>,
    /// Material.
    pub material: Material,
    /// Optional effects.
    pub effects: Effects,
    /// Pinned / kinematic vertices.
    pub constraints: Vec<VertexConstraint>,
    /// Integrator settings.
    pub integrator: IntegratorSettings,
    /// Start time (s).
    pub t0: f64,
}

/// Energies of a state (J).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct EnergyBreakdown {
    /// Membrane (stretch + shear).
    pub membrane: f64,
    /// Bending.
    pub bending: f64,
    /// Kinetic ½Σm|v|².
    pub kinetic: f64,
    /// Gravitational potential −Σ m g·q (0 without gravity).
    pub gravity: f64,
}

impl EnergyBreakdown {
    /// Sum of all parts.
    pub fn total(&self) -> f64 {
        self.membrane + self.bending + self.kinetic + self.gravity
    }
}

/// The thin-shell simulator.
pub struct ShellSim {
    mesh: ShellMesh,
    material: Material,
    law: Membrane,
    effects: Effects,
    wind: Option<WindField>,
    settings: IntegratorSettings,
    pins: Vec<(u32, Pt3)>,
    kinematic: Vec<(Vec<u32>, KinematicFn)>,
    state: ShellState,
    prev: Option<(ShellState, f64)>,
    asm: Assembler,
    llt: SparseLlt,
    k0: Vec<f64>,
    collider: Option<Collider>,
    ipc: Option<Ipc>,
    steps: u64,
    energy_ref: f64,
    symbolic_analyses: u32,
    inv_mass: Vec<f64>,
}

impl ShellSim {
    /// Builds the simulator; every input is validated before any work (§8).
    pub fn new(desc: ShellSceneDesc) -> Result<Self> {
        desc.effects.validate()?;
        check_settings(&desc.integrator)?;
        if !desc.t0.is_finite() {
            return Err(Error::NonFinite("start time"));
        }
        let mesh = ShellMesh::new(desc.rest, &desc.faces, desc.uv.as_ref(), &desc.material)?;
        let n = mesh.n_vertices();
        let q = match desc.initial {
            Some(q) => {
                if q.len() != n {
                    return Err(Error::BadParameter(format!("initial positions: {} given for {n} vertices", q.len())));
                }
                q
            }
            None => mesh.rest.clone(),
        };
        let v = match desc.initial_velocity {
            Some(v) => {
                if v.len() != n {
                    return Err(Error::BadParameter(format!("initial velocities: {} given for {n} vertices", v.len())));
                }
                v
            }
            None => vec![Vec3::zeros(); n],
        };
        if q.iter().any(|p| p.iter().any(|c| !c.is_finite())) {
            return Err(Error::NonFinite("initial positions"));
        }
        if v.iter().any(|p| p.iter().any(|c| !c.is_finite())) {
            return Err(Error::NonFinite("initial velocities"));
        }
        // Constraints.
        let mut kind = vec![0u8; n]; // 0 free, 1 pinned, 2 kinematic
        let mut pins = Vec::new();
        let mut kinematic = Vec::new();
        for c in desc.constraints {
            let (ids, k) = match &c {
                VertexConstraint::Pinned(ids) => (ids.clone(), 1),
                VertexConstraint::Kinematic(ids, _) => (ids.clone(), 2),
            };
            for &i in &ids {
                if i as usize >= n {
                    return Err(Error::BadParameter(format!("constraint names vertex {i} of {n}")));
                }
                if kind[i as usize] != 0 {
                    return Err(Error::BadParameter(format!("vertex {i} is constrained twice")));
                }
                kind[i as usize] = k;
            }
            match c {
                VertexConstraint::Pinned(ids) => pins.extend(ids.iter().map(|&i| (i, q[i as usize]))),
                VertexConstraint::Kinematic(ids, f) => kinematic.push((ids, f)),
            }
        }
        pins.sort_by_key(|p| p.0);
        let mut dofs = DofMap { free_index: vec![NONE; n], ..Default::default() };
        for i in 0..n {
            match kind[i] {
                0 => {
                    dofs.free_index[i] = dofs.free_vertices.len() as u32;
                    dofs.free_vertices.push(i as u32);
                }
                1 => dofs.pinned.push(i as u32),
                _ => dofs.kinematic.push(i as u32),
            }
        }
        let inv_mass =
            (0..n).map(|i| if kind[i] == 0 && mesh.mass[i] > 0.0 { 1.0 / mesh.mass[i] } else { 0.0 }).collect();
        let asm = Assembler::new(&mesh, dofs);
        let llt = SparseLlt::analyze(asm.matrix(), Ordering::Amd)?;
        let law = desc.material.membrane.resolve();
        let wind = desc.effects.wind.as_ref().map(WindField::new);
        let collider = desc
            .effects
            .collision
            .as_ref()
            .filter(|cs| cs.method == ContactMethod::Bridson)
            .map(|cs| Collider::new(&mesh, &desc.effects, cs, desc.material.membrane.stiffness_scale()));
        let ipc = desc
            .effects
            .collision
            .as_ref()
            .filter(|cs| cs.method == ContactMethod::Ipc)
            .map(|cs| Ipc::new(&mesh, &desc.effects, cs));
        let k0 = mesh.hinges.iter().map(|h| h.stiffness).collect();
        let mut sim = Self {
            mesh,
            law,
            wind,
            settings: desc.integrator,
            pins,
            kinematic,
            state: ShellState { t: desc.t0, q, v },
            prev: None,
            asm,
            llt,
            k0,
            collider,
            ipc,
            steps: 0,
            energy_ref: 0.0,
            symbolic_analyses: 1,
            inv_mass,
            material: desc.material,
            effects: desc.effects,
        };
        sim.energy_ref = sim.reference_energy();
        Ok(sim)
    }

    /// Energy scale for the divergence test: initial total energy magnitude plus
    /// M_tot(|g|L + L²/s²) (a body of the scene's size moving its own size per second).
    fn reference_energy(&self) -> f64 {
        let e = self.energies();
        let mtot: f64 = self.mesh.mass.iter().sum();
        let l = geom_core::mesh::bbox_of(&self.state.q).map(|(a, b)| (b - a).norm()).unwrap_or(0.0).max(1e-3);
        let g = self.effects.gravity.map(|g| g.norm()).unwrap_or(0.0);
        let wind = self.wind.as_ref().map(|w| w.wind.base.norm_squared() * 4.0).unwrap_or(0.0);
        e.membrane + e.bending + e.kinetic + e.gravity.abs() + mtot * (g * l + l * l + wind)
    }

    /// Current state.
    pub fn state(&self) -> &ShellState {
        &self.state
    }

    /// The simulation mesh (rest data, hinges, masses).
    pub fn mesh(&self) -> &ShellMesh {
        &self.mesh
    }

    /// The effects it was built with.
    pub fn effects(&self) -> &Effects {
        &self.effects
    }

    /// The material.
    pub fn material(&self) -> &Material {
        &self.material
    }

    /// Integrator settings (mutable: e.g. switching the Hessian mode between steps).
    pub fn settings_mut(&mut self) -> &mut IntegratorSettings {
        &mut self.settings
    }

    /// Replaces the state (validated); BDF2 restarts with a backward-Euler step and the
    /// divergence threshold is re-based on the new state's energy.
    pub fn set_state(&mut self, s: ShellState) -> Result<()> {
        let n = self.mesh.n_vertices();
        if s.q.len() != n || s.v.len() != n {
            return Err(Error::BadParameter(format!("state has {}/{} entries for {n} vertices", s.q.len(), s.v.len())));
        }
        if !s.t.is_finite() || s.q.iter().any(|p| p.iter().any(|c| !c.is_finite())) {
            return Err(Error::NonFinite("state positions"));
        }
        if s.v.iter().any(|p| p.iter().any(|c| !c.is_finite())) {
            return Err(Error::NonFinite("state velocities"));
        }
        self.state = s;
        self.prev = None;
        self.energy_ref = self.reference_energy();
        Ok(())
    }

    /// Rest angles θ̄ per hinge (after plasticity).
    pub fn rest_angles(&self) -> Vec<f64> {
        self.mesh.hinges.iter().map(|h| h.rest_theta).collect()
    }

    /// Per-hinge stiffness k_e (after hardening).
    pub fn hinge_stiffness(&self) -> Vec<f64> {
        self.mesh.hinges.iter().map(|h| h.stiffness).collect()
    }

    /// Scripted rest-shape events: replaces θ̄ (one per hinge, finite).
    pub fn set_rest_angles(&mut self, theta_bar: &[f64]) -> Result<()> {
        if theta_bar.len() != self.mesh.hinges.len() {
            return Err(Error::BadParameter(format!(
                "{} rest angles given for {} hinges",
                theta_bar.len(),
                self.mesh.hinges.len()
            )));
        }
        if theta_bar.iter().any(|t| !t.is_finite()) {
            return Err(Error::NonFinite("rest angles"));
        }
        for (h, &t) in self.mesh.hinges.iter_mut().zip(theta_bar) {
            h.rest_theta = crate::kernels::bending::wrap_angle(t);
        }
        Ok(())
    }

    /// Replaces the per-hinge stiffness k_e (finite, ≥ 0), e.g. to carry hardened creases over.
    pub fn set_hinge_stiffness(&mut self, k: &[f64]) -> Result<()> {
        if k.len() != self.mesh.hinges.len() {
            return Err(Error::BadParameter(format!(
                "{} stiffnesses given for {} hinges",
                k.len(),
                self.mesh.hinges.len()
            )));
        }
        if k.iter().any(|x| !x.is_finite() || *x < 0.0) {
            return Err(Error::BadParameter("hinge stiffness must be finite and ≥ 0".into()));
        }
        for (h, &x) in self.mesh.hinges.iter_mut().zip(k) {
            h.stiffness = x;
        }
        Ok(())
    }

    /// θ per hinge of any configuration (0 for collapsed hinges).
    pub fn hinge_angles(&self, q: &[Pt3]) -> Vec<f64> {
        self.mesh
            .hinges
            .iter()
            .map(|h| {
                let x = h.v.map(|v| q[v as usize]);
                if hinge_is_collapsed(&x) {
                    0.0
                } else {
                    hinge_angle(&x)
                }
            })
            .collect()
    }

    /// Free / pinned / kinematic map.
    pub fn free_dofs(&self) -> &DofMap {
        &self.asm.dofs
    }

    /// Fill-reducing (AMD) elimination order of the system matrix, `perm[new] = old`.
    pub fn fill_reducing_perm(&self) -> &[usize] {
        self.llt.perm()
    }

    /// The cached symbolic Cholesky analysis (shared with `tracks`).
    pub fn llt_symbolic(&self) -> LltSymbolic {
        self.llt.symbolic()
    }

    /// How many symbolic analyses were computed (1 when the pattern never changes; IPC contact
    /// adds one whenever its pairs grow the pattern, `ShellSim::grow_pattern`).
    pub fn symbolic_analyses(&self) -> u32 {
        self.symbolic_analyses
    }

    /// Records, from the next step on, the end-of-step velocities after every stage of the
    /// collision filter (diagnostics; [`ShellSim::collision_trace`]).
    pub fn trace_collision_stages(&mut self, on: bool) {
        if let Some(c) = self.collider.as_mut() {
            c.trace = on.then(Vec::new);
        }
    }

    /// The stages of the last step's collision filter: `(stage, velocities after it)`, in order
    /// (`solve` first). Positions after a stage are q_k + h·v (backward Euler).
    pub fn collision_trace(&self) -> &[(&'static str, Vec<Vec3>)] {
        self.collider.as_ref().and_then(|c| c.trace.as_deref()).unwrap_or(&[])
    }

    /// True when a collision pipeline (and its broad-phase structures) exists.
    pub fn has_collision_structures(&self) -> bool {
        self.collider.is_some() || self.ipc.is_some()
    }

    /// The contact model in use (`None` without collision effects).
    pub fn contact_method(&self) -> Option<ContactMethod> {
        if self.ipc.is_some() {
            Some(ContactMethod::Ipc)
        } else if self.collider.is_some() {
            Some(ContactMethod::Bridson)
        } else {
            None
        }
    }

    /// Adds a deforming-mesh obstacle (a skinned body; `contact::deforming`): from the next step
    /// on, the cloth collides with its moving triangles. Its obstacle index in contact reports
    /// follows the rigid obstacles of the effects.
    ///
    /// Errors: `BadParameter` without IPC contact (`effects.collision` with the IPC method), or
    /// when the cloth's current state lies inside the obstacle at the current time.
    pub fn add_deforming_obstacle(&mut self, d: crate::contact::deforming::DeformingMesh) -> Result<()> {
        let Some(ipc) = self.ipc.as_mut() else {
            return Err(Error::BadParameter(
                "deforming obstacles need IPC contact (effects.collision with method Ipc)".into(),
            ));
        };
        let depth = d.max_penetration(self.state.t, &self.state.q)?;
        if !(depth == 0.0) {
            return Err(Error::BadParameter(format!(
                "the cloth starts inside the deforming obstacle at t = {} s (depth {depth:.3e} m)",
                self.state.t
            )));
        }
        ipc.add_deforming(d);
        Ok(())
    }

    /// IPC's activation distance d̂ and current barrier stiffness κ (`None` without IPC).
    pub fn barrier_parameters(&self) -> Option<(f64, f64)> {
        self.ipc.as_ref().map(|i| (i.dhat, i.kappa))
    }

    /// Steps taken since construction.
    pub fn steps_taken(&self) -> u64 {
        self.steps
    }

    /// Total linear momentum Σ m_i v_i (kg·m/s).
    pub fn momentum(&self) -> Vec3 {
        self.state.v.iter().zip(&self.mesh.mass).map(|(v, m)| *m * v).sum()
    }

    /// Energies of the current state.
    pub fn energies(&self) -> EnergyBreakdown {
        self.energies_of(&self.state.q, &self.state.v)
    }

    /// Energies of any configuration.
    pub fn energies_of(&self, q: &[Pt3], v: &[Vec3]) -> EnergyBreakdown {
        let mesh = &self.mesh;
        let tri_e: Vec<f64> = mesh
            .tris
            .par_iter()
            .zip(&mesh.tri_rest)
            .map(|(t, tr)| membrane_energy(tr, &self.law, &t.map(|i| q[i as usize])))
            .collect();
        let hin_e: Vec<f64> = mesh.hinges.par_iter().map(|h| bending_energy(h, &h.v.map(|i| q[i as usize]))).collect();
        let kinetic = 0.5 * v.iter().zip(&mesh.mass).map(|(v, m)| m * v.norm_squared()).sum::<f64>();
        let gravity = match self.effects.gravity {
            Some(g) => -q.iter().zip(&mesh.mass).map(|(p, m)| m * g.dot(&p.coords)).sum::<f64>(),
            None => 0.0,
        };
        EnergyBreakdown { membrane: tri_e.iter().sum(), bending: hin_e.iter().sum(), kinetic, gravity }
    }

    /// One ordinary (untracked) step of size h (s): plasticity → assemble → LLᵀ solve →
    /// collisions → update (§3.7).
    pub fn step(&mut self, h: f64) -> Result<StepStats> {
        self.step_impl(h, None)
    }

    /// The same step with the (first) velocity solve delegated to `solver` (tracks).
    pub fn step_with(&mut self, h: f64, solver: &mut dyn VelocitySolve) -> Result<StepStats> {
        self.step_impl(h, Some(solver))
    }

    fn step_impl(&mut self, h: f64, mut solver: Option<&mut dyn VelocitySolve>) -> Result<StepStats> {
        if !h.is_finite() {
            return Err(Error::NonFinite("time step"));
        }
        if h <= 0.0 {
            return Err(Error::BadParameter(format!("time step must be > 0 s, got {h}")));
        }
        let mut st = StepStats::default();
        let n = self.mesh.n_vertices();
        let t_next = self.state.t + h;
        // 1. Plasticity at the start of the step.
        if let Some(p) = self.material.plasticity {
            let q = &self.state.q;
            for (i, hg) in self.mesh.hinges.iter_mut().enumerate() {
                let x = hg.v.map(|v| q[v as usize]);
                if hinge_is_collapsed(&x) {
                    continue;
                }
                let ev = plastic_update_clamped(hg, hinge_angle(&x), &p, self.k0[i]);
                st.plastic_events += ev.yielded as u32;
                st.stiffness_clamped += ev.clamped as u32;
            }
        }
        // 2. Integrator coefficients (BDF2 needs the previous state at the same step size). The
        //    Newton guess is v_k for both integrators: the extrapolated BDF2 guess 2v_k − v_{k−1}
        //    of the spec made the single linearised step unstable on stiff cloth at h = 1/60
        //    (README, decisions); a converged Newton solve does not depend on the guess.
        let bdf2 = self.settings.kind == IntegratorKind::Bdf2
            && self.prev.as_ref().is_some_and(|(_, hp)| (hp - h).abs() <= 1e-12 * h);
        let (qk, vk) = (&self.state.q, &self.state.v);
        let (q_base, h_eff, v_ref, mut v_cur): (Vec<Pt3>, f64, Vec<Vec3>, Vec<Vec3>) = if bdf2 {
            let (p, _) = self.prev.as_ref().expect("bdf2 checked that prev exists");
            (
                qk.iter().zip(&p.q).map(|(a, b)| Pt3::from((4.0 * a.coords - b.coords) / 3.0)).collect(),
                2.0 * h / 3.0,
                vk.iter().zip(&p.v).map(|(a, b)| (4.0 * a - b) / 3.0).collect(),
                vk.clone(),
            )
        } else {
            (qk.clone(), h, vk.clone(), vk.clone())
        };
        // Constrained vertices: prescribed end positions.
        let mut targets: Vec<(u32, Pt3)> = self.pins.clone();
        for (ids, f) in &self.kinematic {
            for &i in ids {
                let p = f(t_next, i);
                if p.iter().any(|c| !c.is_finite()) {
                    return Err(Error::NonFinite("kinematic vertex path"));
                }
                targets.push((i, p));
            }
        }
        for &(i, p) in &targets {
            let i = i as usize;
            v_cur[i] = if bdf2 || p != q_base[i] { (p - q_base[i]) / h_eff } else { Vec3::zeros() };
        }
        if self.ipc.is_some() {
            let mut ipc = self.ipc.take().expect("checked just above");
            let r =
                self.ipc_newton(&mut ipc, &q_base, h_eff, &v_ref, &mut v_cur, &mut targets, h, t_next, solver, &mut st);
            self.ipc = Some(ipc);
            r?;
            return self.finish_step(&q_base, h_eff, v_cur, &targets, h, st);
        }
        // 3–7. Newton iterations.
        let (alpha, bs, bsh, bb) = self.material.damping.coefficients();
        let nf = self.asm.dofs.n_free();
        let mut force = vec![Vec3::zeros(); n];
        let mut q_eval = vec![Pt3::origin(); n];
        let iters = self.settings.newton_iters.max(1);
        for it in 0..iters {
            let ta = Instant::now();
            for i in 0..n {
                q_eval[i] = q_base[i] + h_eff * v_cur[i];
            }
            self.custom_jacobians(t_next, &q_eval, &v_cur, h_eff)?;
            let inp = EvalInput {
                q: &q_eval,
                v: &v_cur,
                h_eff,
                mode: self.settings.hessian,
                law: &self.law,
                damping: (alpha, bs, bsh, bb),
                wind: self.wind.as_ref().map(|w| (w, t_next)),
                shift: 0.0,
            };
            let out = self.asm.assemble(&self.mesh, &inp, &mut force);
            st.skipped_hinges = out.skipped_hinges;
            st.collapsed_triangles = out.collapsed_triangles;
            self.add_external_forces(t_next, &q_eval, &v_cur, &mut force);
            let mut b = vec![0.0; 3 * nf];
            for (fidx, &vtx) in self.asm.dofs.free_vertices.iter().enumerate() {
                let i = vtx as usize;
                let m = self.mesh.mass[i];
                let r = -m * (v_cur[i] - v_ref[i]) + h_eff * (force[i] - alpha * m * v_cur[i]);
                b[3 * fidx..3 * fidx + 3].copy_from_slice(r.as_slice());
            }
            st.t_assembly += ta.elapsed().as_secs_f64();
            if nf == 0 {
                break;
            }
            let dv = match (it, solver.as_deref_mut()) {
                (0, Some(s)) => {
                    let ts = Instant::now();
                    let sys = ImplicitSystem {
                        a: self.asm.matrix(),
                        b: &b,
                        q_pred: &q_eval,
                        v0: &v_cur,
                        h_eff,
                        dofs: &self.asm.dofs,
                        h,
                        t_next,
                    };
                    let dv = s.solve(&sys)?;
                    if dv.len() != 3 * nf || dv.iter().any(|x| !x.is_finite()) {
                        return Err(Error::Diverged {
                            step: self.steps,
                            reason: "delegated solve returned a bad Δv".into(),
                        });
                    }
                    st.t_solve += ts.elapsed().as_secs_f64();
                    dv
                }
                _ => self.solve_system(&b, h_eff, alpha, &mut st)?,
            };
            st.lin_residual = rel_residual(self.asm.matrix(), &dv, &b);
            // Optional backtracking on the incremental potential (iterations > 1 only).
            let mut step = 1.0;
            if self.settings.line_search && iters > 1 {
                let phi = |sim: &Self, vv: &[Vec3]| sim.incremental_potential(&q_base, h_eff, &v_ref, vv, t_next);
                let phi0 = phi(self, &v_cur);
                let mut trial = v_cur.clone();
                for _ in 0..12 {
                    for (fidx, &vtx) in self.asm.dofs.free_vertices.iter().enumerate() {
                        let d = Vec3::new(dv[3 * fidx], dv[3 * fidx + 1], dv[3 * fidx + 2]);
                        trial[vtx as usize] = v_cur[vtx as usize] + step * d;
                    }
                    if phi(self, &trial) <= phi0 {
                        break;
                    }
                    step *= 0.5;
                    st.line_search_halvings += 1;
                }
            }
            for (fidx, &vtx) in self.asm.dofs.free_vertices.iter().enumerate() {
                v_cur[vtx as usize] += step * Vec3::new(dv[3 * fidx], dv[3 * fidx + 1], dv[3 * fidx + 2]);
            }
            st.newton_iters += 1;
        }
        // 8. Collisions on the straight motion q_k → q_k + h w.
        if let Some(col) = self.collider.as_mut() {
            let tc = Instant::now();
            let qk = &self.state.q;
            if bdf2 {
                let mut w: Vec<Vec3> = (0..n).map(|i| (q_base[i] + h_eff * v_cur[i] - qk[i]) / h).collect();
                col.filter(qk, &mut w, h, t_next, &self.inv_mass, &mut st);
                for i in 0..n {
                    if self.inv_mass[i] > 0.0 {
                        v_cur[i] = (qk[i] + h * w[i] - q_base[i]) / h_eff;
                    }
                }
            } else {
                col.filter(qk, &mut v_cur, h, t_next, &self.inv_mass, &mut st);
            }
            st.t_collision = tc.elapsed().as_secs_f64();
        }
        self.finish_step(&q_base, h_eff, v_cur, &targets, h, st)
    }

    /// Step 9, the end of a step: positions q_base + h_eff·v (prescribed vertices at their targets),
    /// the NaN and energy checks, and the state update.
    fn finish_step(
        &mut self,
        q_base: &[Pt3],
        h_eff: f64,
        v_cur: Vec<Vec3>,
        targets: &[(u32, Pt3)],
        h: f64,
        st: StepStats,
    ) -> Result<StepStats> {
        let n = q_base.len();
        let t_next = self.state.t + h;
        let mut q_new: Vec<Pt3> = (0..n).map(|i| q_base[i] + h_eff * v_cur[i]).collect();
        for &(i, p) in targets {
            q_new[i as usize] = p;
        }
        if q_new.iter().any(|p| p.iter().any(|c| !c.is_finite()))
            || v_cur.iter().any(|p| p.iter().any(|c| !c.is_finite()))
        {
            return Err(Error::Diverged { step: self.steps, reason: "non-finite positions or velocities".into() });
        }
        let e = self.energies_of(&q_new, &v_cur);
        let limit = self.settings.divergence_energy_factor * self.energy_ref;
        if !(e.membrane + e.bending + e.kinetic <= limit) {
            return Err(Error::Diverged {
                step: self.steps,
                reason: format!("energy {:.3e} J above {:.3e} J", e.membrane + e.bending + e.kinetic, limit),
            });
        }
        let old = std::mem::replace(&mut self.state, ShellState { t: t_next, q: q_new, v: v_cur });
        self.prev = Some((old, h));
        self.steps += 1;
        Ok(st)
    }

    /// The IPC Newton solve of one step (module `contact`): a collision-free start (prescribed
    /// vertices first, then the free vertices' inertial predictor, each as far as CCD allows),
    /// then Newton iterations on the incremental potential with barrier and lagged friction,
    /// each step clamped by CCD and backtracked until the potential decreases, until
    /// ‖Δv‖∞ ≤ `newton_tol`. Prescribed vertices a blocked motion holds back are left where CCD
    /// stopped them (their `targets` updated) and reported in `StepStats::contact`.
    #[allow(clippy::too_many_arguments)]
    fn ipc_newton(
        &mut self,
        ipc: &mut Ipc,
        q_base: &[Pt3],
        h_eff: f64,
        v_ref: &[Vec3],
        v_cur: &mut [Vec3],
        targets: &mut [(u32, Pt3)],
        h: f64,
        t_next: f64,
        mut solver: Option<&mut dyn VelocitySolve>,
        st: &mut StepStats,
    ) -> Result<()> {
        let n = self.mesh.n_vertices();
        // The start (moved by the carry of deforming obstacles, `contact::deforming`).
        let mut qk = self.state.q.clone();
        let tc = Instant::now();
        let fr = ipc.begin_step(&mut qk, t_next, h).map_err(|reason| Error::Diverged { step: self.steps, reason })?;
        // A delegated solve (tracks) that keeps the mesh's symbolic analysis works on the
        // fixed pattern: drop the contact couplings (their blocks are lumped, `Ipc::add`).
        let grow = solver.as_deref().is_none_or(|s| s.accepts_pattern_changes());
        if !grow && !self.asm.extra.is_empty() {
            self.set_pattern(Vec::new())?;
        }
        st.contact.friction = fr;
        // Collision-free start: (A) prescribed vertices toward their targets, (B) the free
        // vertices' predictor q_base + h_eff v_k, each clamped by CCD from a feasible state.
        let mut dx = vec![Vec3::zeros(); n];
        for &(i, p) in targets.iter() {
            dx[i as usize] = p - qk[i as usize];
        }
        let a_pin = if dx.iter().any(|d| *d != Vec3::zeros()) {
            ipc.sweep(&qk, Some(&dx));
            ipc.max_step(&qk, &dx)
        } else {
            1.0
        };
        let mut x: Vec<Pt3> = qk.iter().zip(&dx).map(|(p, d)| p + a_pin * d).collect();
        if a_pin < 1.0 {
            st.contact.ccd_clamps += 1;
            for t in targets.iter_mut() {
                t.1 = x[t.0 as usize];
            }
        }
        for &(i, p) in targets.iter() {
            v_cur[i as usize] = (p - q_base[i as usize]) / h_eff;
        }
        let free = self.asm.dofs.free_vertices.clone();
        let mut dx = vec![Vec3::zeros(); n];
        // The predictor includes gravity (v + h_eff g): a free fall converges in one iteration.
        let g = self.effects.gravity.unwrap_or_else(Vec3::zeros);
        for &vtx in &free {
            let i = vtx as usize;
            dx[i] = q_base[i] + h_eff * (v_cur[i] + h_eff * g) - x[i];
        }
        ipc.sweep(&x, Some(&dx));
        let a_pred = ipc.max_step(&x, &dx);
        for &vtx in &free {
            let i = vtx as usize;
            x[i] += a_pred * dx[i];
            v_cur[i] = (x[i] - q_base[i]) / h_eff;
        }
        st.t_collision += tc.elapsed().as_secs_f64();
        let (alpha, bs, bsh, bb) = self.material.damping.coefficients();
        let nf = self.asm.dofs.n_free();
        let mut force = vec![Vec3::zeros(); n];
        let mut converged = false;
        let dec_tol = 0.5 * ipc.newton_tol.powi(2) * free.iter().map(|&i| self.mesh.mass[i as usize]).sum::<f64>();
        // Φ of the current iterate, carried over from the accepted trial of the last iteration.
        let mut phi_cur: Option<f64> = None;
        for _ in 0..ipc.max_iters {
            let ta = Instant::now();
            for i in 0..n {
                x[i] = q_base[i] + h_eff * v_cur[i];
            }
            // Contact blocks first: the element pass below gathers them into the matrix.
            let tcc = Instant::now();
            let contacts = ipc.contacts(&x);
            if grow {
                self.grow_pattern(ipc, &x, &contacts, st)?;
            }
            self.custom_jacobians(t_next, &x, v_cur, h_eff)?;

            let mut cforce = vec![Vec3::zeros(); n];
            self.asm.contact_diag.iter_mut().for_each(|d| *d = Mat3::zeros());
            self.asm.contact_offdiag.clear();
            {
                let asm = &mut self.asm;
                let offsets = &asm.block_offset;
                let free_index = &asm.dofs.free_index;
                let (diag, offdiag) = (&mut asm.contact_diag, &mut asm.contact_offdiag);
                let min_gap = ipc.add(
                    &x,
                    &contacts,
                    &mut cforce,
                    h_eff * h_eff,
                    |i, j| offsets.contains_key(&(i, j)),
                    |i, j, m| {
                        let (fi, fj) = (free_index[i as usize], free_index[j as usize]);
                        if fi == NONE || fj == NONE {
                            return;
                        }

                        if i == j {
                            diag[fi as usize] += m;
                        } else if let Some(&off) = offsets.get(&(i, j)) {
                            offdiag.push((off, m));
                        }
                    },
                );
                st.contact.min_gap = min_gap;
            }
            st.contact.active = contacts.len() as u32;
            st.t_collision += tcc.elapsed().as_secs_f64();
            let inp = EvalInput {
                q: &x,
                v: v_cur,
                h_eff,
                mode: self.settings.hessian,
                law: &self.law,
                damping: (alpha, bs, bsh, bb),
                wind: self.wind.as_ref().map(|w| (w, t_next)),
                shift: 0.0,
            };
            let out = self.asm.assemble(&self.mesh, &inp, &mut force);
            st.skipped_hinges = out.skipped_hinges;
            st.collapsed_triangles = out.collapsed_triangles;
            self.add_external_forces(t_next, &x, v_cur, &mut force);
            let mut b = vec![0.0; 3 * nf];
            for (fidx, &vtx) in free.iter().enumerate() {
                let i = vtx as usize;
                let m = self.mesh.mass[i];
                let r = -m * (v_cur[i] - v_ref[i]) + h_eff * (force[i] + cforce[i] - alpha * m * v_cur[i]);
                b[3 * fidx..3 * fidx + 3].copy_from_slice(r.as_slice());
            }
            st.t_assembly += ta.elapsed().as_secs_f64();
            if nf == 0 {
                converged = true;
                break;
            }
            let dv = match solver.as_deref_mut() {
                Some(s) => {
                    let ts = Instant::now();
                    let sys = ImplicitSystem {
                        a: self.asm.matrix(),
                        b: &b,
                        q_pred: &x,
                        v0: v_cur,
                        h_eff,
                        dofs: &self.asm.dofs,
                        h,
                        t_next,
                    };
                    let dv = s.solve(&sys)?;
                    if dv.len() != 3 * nf || dv.iter().any(|x| !x.is_finite()) {
                        return Err(Error::Diverged {
                            step: self.steps,
                            reason: "delegated solve returned a bad Δv".into(),
                        });
                    }
                    st.t_solve += ts.elapsed().as_secs_f64();
                    dv
                }
                None => self.solve_system(&b, h_eff, alpha, st)?,
            };
            st.lin_residual = rel_residual(self.asm.matrix(), &dv, &b);
            st.newton_iters += 1;
            let dv_max = dv.iter().fold(0.0f64, |a, x| a.max(x.abs()));
            // Converged when the Newton direction is below the velocity tolerance everywhere
            // (‖Δv‖∞ = ‖Δx‖∞/h_eff ≤ newton_tol), or when the Newton decrement ½ΔvᵀAΔv
            // (= ½Δvᵀb for the simulator's own solve, where A Δv = b holds; the model's predicted
            // decrease of Φ, the standard stopping test of Newton's method, Boyd & Vandenberghe
            // §9.5) is below ½ Σ m_i newton_tol², the kinetic energy of the whole cloth moving
            // at the tolerance: the ∞-norm alone is held hostage by a single vertex drifting
            // along a nearly flat mode (a buckle of the twisted tube: 1–2 vertices, ‖Δv‖ ~ 0.1
            // m/s for 10+ iterations while Φ changes by 1e-6 J).
            //
            // A delegated solve may impose constraints C Δv = r (tracks): there AΔv = b − Cᵀμ,
            // and the decrement of the constrained step is ½ΔvᵀAΔv = ½(Δvᵀb − μᵀr), evaluated
            // with A directly; it measures the predicted decrease only on a feasible iterate,
            // so the test also asks the solver's constraint violation (m/s) to be within
            // `newton_tol`.
            let decrement = match solver.as_deref() {
                None => 0.5 * dv.iter().zip(&b).map(|(x, y)| x * y).sum::<f64>(),
                Some(s) if s.constraint_violation() <= ipc.newton_tol => {
                    let mut adv = vec![0.0; dv.len()];
                    geom_core::linalg::sym_mul_vec(self.asm.matrix(), &dv, &mut adv);
                    0.5 * dv.iter().zip(&adv).map(|(x, y)| x * y).sum::<f64>()
                }
                Some(_) => f64::INFINITY,
            };
            let small = dv_max <= ipc.newton_tol || decrement <= dec_tol;
            // CCD bound, then backtracking on Φ (barrier and friction included).
            let tl = Instant::now();
            let mut step_dx = vec![Vec3::zeros(); n];
            for (fidx, &vtx) in free.iter().enumerate() {
                step_dx[vtx as usize] = h_eff * Vec3::new(dv[3 * fidx], dv[3 * fidx + 1], dv[3 * fidx + 2]);
            }
            ipc.sweep(&x, Some(&step_dx));
            let mut a = ipc.max_step(&x, &step_dx);
            if a < 1.0 {
                st.contact.ccd_clamps += 1;
            }
            if a == 0.0 {
                // Blocked: a pair at the gap floor would close further (a conflict that keeps
                // pushing, e.g. a tracking constraint into an obstacle): contact wins.
                st.t_collision += tl.elapsed().as_secs_f64();
                break;
            }
            if small {
                // Converged: take the (CCD-safe) step without a line search.
                for (fidx, &vtx) in free.iter().enumerate() {
                    let i = vtx as usize;
                    v_cur[i] += a * Vec3::new(dv[3 * fidx], dv[3 * fidx + 1], dv[3 * fidx + 2]);
                }
                converged = true;
                st.t_collision += tl.elapsed().as_secs_f64();
                break;
            }
            let phi0 = match phi_cur {
                Some(p) => p,
                None => self.ipc_potential(ipc, q_base, h_eff, v_ref, v_cur, t_next, alpha),
            };
            // The line search's merit: Φ, plus the wind's work linearised at this iterate (drag
            // depends on v and has no potential; −h_eff (v − v_k)·F_w(x_k, v_k) makes the slope
            // along Δv the −bᵀΔv the system was solved with — without it every line search of a
            // cloth moving through air fails), plus the delegated solver's constraint penalty
            // ([`VelocitySolve::merit`]).
            let wind_slope = match self.wind.as_ref() {
                Some(w) => {
                    let fw = w.vertex_forces(&self.mesh.tris, &x, v_cur, t_next);
                    h_eff
                        * free
                            .iter()
                            .enumerate()
                            .map(|(fidx, &vtx)| {
                                fw[vtx as usize].dot(&Vec3::new(dv[3 * fidx], dv[3 * fidx + 1], dv[3 * fidx + 2]))
                            })
                            .sum::<f64>()
                }
                None => 0.0,
            };
            let mut merit = |vv: &[Vec3]| -> f64 {
                match solver.as_deref_mut() {
                    Some(s) => {
                        let q: Vec<Pt3> = q_base.iter().zip(vv).map(|(p, v)| p + h_eff * v).collect();
                        s.merit(&q)
                    }
                    None => 0.0,
                }
            };
            let m0 = phi0 + merit(v_cur);
            let mut trial = v_cur.to_vec();
            let mut accepted = false;
            let mut phi = phi0;
            let a_full = a == 1.0;
            for _ in 0..30 {
                for (fidx, &vtx) in free.iter().enumerate() {
                    let i = vtx as usize;
                    trial[i] = v_cur[i] + a * Vec3::new(dv[3 * fidx], dv[3 * fidx + 1], dv[3 * fidx + 2]);
                }
                phi = self.ipc_potential(ipc, q_base, h_eff, v_ref, &trial, t_next, alpha);
                if phi - a * wind_slope + merit(&trial) <= m0 {
                    accepted = true;
                    break;
                }
                a *= 0.5;
                st.line_search_halvings += 1;
            }
            v_cur.copy_from_slice(&trial);
            phi_cur = Some(phi);
            if !accepted {
                // No decrease found (the frozen damping, the lagged friction or a constraint
                // that conflicts with contact make Δv inexact for the merit): keep the smallest
                // CCD-safe step tried (2⁻³⁰ of it), counted, and stop — the iterate has not
                // moved, so the next iteration would solve the same system for the same Δv
                // and fail again (measured on the tracked bag: 15 of 20 iterations per step
                // repeated one failed line search).
                st.contact.line_search_failures += 1;
                st.t_collision += tl.elapsed().as_secs_f64();
                break;
            }
            // Away from contact, the seed's integrator: when no pair is within d̂ at this iterate
            // or at the step's end, no friction is lagged, and neither CCD nor the line search
            // shortened the step, barrier and friction are zero and the `newton_iters`
            // linearised steps of the contact-free integrator (one by default, seed §4.3) are
            // accepted as they are.
            if accepted
                && a_full
                && a == 1.0
                && contacts.is_empty()
                && st.contact.friction == 0
                && st.newton_iters >= self.settings.newton_iters
            {
                let xe: Vec<Pt3> = q_base.iter().zip(v_cur.iter()).map(|(p, v)| p + h_eff * v).collect();
                if ipc.contacts(&xe).is_empty() {
                    st.contact.contact_free_steps += 1;
                    converged = true;
                    st.t_collision += tl.elapsed().as_secs_f64();
                    break;
                }
            }
            if std::env::var_os("SHELLS_IPC_DEBUG").is_some() {
                let (kmax, _) =
                    dv.iter().enumerate().fold((0, 0.0f64), |m, (k, x)| if x.abs() > m.1 { (k, x.abs()) } else { m });
                let vmax = free[kmax / 3];
                let nc = contacts.iter().filter(|c| c.cloth_nodes().contains(&vmax)).count();
                let d3 = Vec3::new(dv[kmax / 3 * 3], dv[kmax / 3 * 3 + 1], dv[kmax / 3 * 3 + 2]);
                let n_big = dv.chunks(3).filter(|c| c.iter().any(|x| x.abs() > 0.5 * dv_max)).count();
                eprintln!(
                    "  iter {}: |dv| {dv_max:.3e} alpha {a:.3e} contacts {} phi0 {phi0:.6e} phi {phi:.6e} | vmax {vmax} y {:.4} dv {:?} in {nc} contacts, {n_big} verts > half",
                    st.newton_iters,
                    contacts.len(),
                    x[vmax as usize].y,
                    d3.as_slice(),
                );
            }
            st.t_collision += tl.elapsed().as_secs_f64();
            if small {
                converged = true;
                break;
            }
        }
        if !converged {
            st.contact.unconverged += 1;
        }
        // Statistics at the accepted end state; κ grows while gaps get too small.
        for i in 0..n {
            x[i] = q_base[i] + h_eff * v_cur[i];
        }
        let end = ipc.contacts(&x);
        st.contact.active = end.len() as u32;
        st.contact.min_gap = end.iter().map(|c| c.gap(&x).d).fold(f64::INFINITY, f64::min);
        ipc.adapt_kappa(st.contact.min_gap);
        st.contact.kappa = ipc.kappa;
        Ok(())
    }

    /// Adds to the system's pattern the coupling blocks of the contact pairs it lacks (two free
    /// cloth vertices of one contact stencil that share no triangle), so that the contact
    /// Hessian enters the matrix exactly instead of being lumped onto the diagonals: with
    /// lumped couplings two layers in contact see each other as fixed walls and Newton
    /// converges linearly on piled cloth. The pattern only grows (a superset kept across steps,
    /// so a pile's pairs cost few analyses, not one per iteration): a growth reserves the pairs
    /// of every candidate closer than 2d̂, and a handful of missing pairs (fewer than 1/16 of
    /// the kept ones) stays lumped until more are missing. The superset is rebuilt from the
    /// current pairs when it is more than four times what the contacts use.
    fn grow_pattern(
        &mut self,
        ipc: &Ipc,
        x: &[Pt3],
        contacts: &[crate::contact::set::Contact],
        st: &mut StepStats,
    ) -> Result<()> {
        let (need, used) = self.missing_pairs(contacts);
        if need.is_empty() || (16 * need.len() < self.asm.extra.len() && need.len() < 256) {
            return Ok(());
        }
        let te = Instant::now();
        let near = ipc.contacts_within(x, 2.0 * ipc.dhat);
        let (more, _) = self.missing_pairs(&near);
        let mut extra =
            if self.asm.extra.len() > 4 * (used + more.len()) { Vec::new() } else { self.asm.extra.clone() };
        extra.extend(need);
        extra.extend(more);
        self.set_pattern(extra)?;
        st.t_factor += te.elapsed().as_secs_f64();
        Ok(())
    }

    /// The free cloth-vertex pairs of the contacts' stencils that the pattern lacks, and how
    /// many stencil pairs use the pattern's contact-coupling blocks.
    fn missing_pairs(&self, contacts: &[crate::contact::set::Contact]) -> (Vec<(u32, u32)>, usize) {
        let fi = &self.asm.dofs.free_index;
        let mut need: Vec<(u32, u32)> = Vec::new();
        let mut used = 0usize;
        for c in contacts {
            let ids = c.cloth_nodes();
            for a in 0..4 {
                for b in a + 1..4 {
                    let (i, j) = (ids[a], ids[b]);
                    if i == NONE || j == NONE || i == j || fi[i as usize] == NONE || fi[j as usize] == NONE {
                        continue;
                    }
                    match self.asm.block_offset.get(&(i, j)) {
                        Some(&off) if off >= self.asm.off_extra() => used += 1,
                        Some(_) => {}
                        None => need.push((i.min(j), i.max(j))),
                    }
                }
            }
        }
        need.sort_unstable();
        need.dedup();
        (need, used)
    }

    /// Rebuilds the assembler with the mesh's pattern plus the coupling blocks of `extra` and
    /// re-analyses the Cholesky factorisation (counted in [`ShellSim::symbolic_analyses`]).
    fn set_pattern(&mut self, extra: Vec<(u32, u32)>) -> Result<()> {
        self.asm = Assembler::with_extra(&self.mesh, self.asm.dofs.clone(), extra);
        self.llt = SparseLlt::analyze(self.asm.matrix(), Ordering::Amd)?;
        self.symbolic_analyses += 1;
        Ok(())
    }

    /// Φ(v) of the IPC line search: the incremental potential of [`ShellSim::incremental_potential`]
    /// plus mass damping ½hα·Σm|v|² and contact (barrier + lagged friction) energy.
    #[allow(clippy::too_many_arguments)]
    fn ipc_potential(&self, ipc: &Ipc, q_base: &[Pt3], h: f64, v_ref: &[Vec3], v: &[Vec3], t: f64, alpha: f64) -> f64 {
        let q: Vec<Pt3> = q_base.iter().zip(v).map(|(p, vv)| p + h * vv).collect();
        let damp: f64 = if alpha > 0.0 {
            0.5 * h
                * alpha
                * v.iter()
                    .zip(&self.mesh.mass)
                    .zip(&self.inv_mass)
                    .filter(|(_, &im)| im > 0.0)
                    .map(|((v, m), _)| m * v.norm_squared())
                    .sum::<f64>()
        } else {
            0.0
        };
        self.incremental_potential(q_base, h, v_ref, v, t) + damp + ipc.energy(&q)
    }

    /// Redoes the end of the last (backward Euler) step with other end-of-step velocities:
    /// free vertices take `v_new` (m/s, one per vertex; pinned and kinematic vertices keep their
    /// prescribed velocity), the collision pass (§3.9: proximity, CCD, impact zones) runs again
    /// on the straight motion q_k → q_k + h·v from the step's start q_k, and the state becomes
    /// (q_k + h·v, v) at the same time t. Used by `tracks` to reproject its constraints after
    /// collisions (tracks spec §3.7 step 5) while collision-freedom keeps priority. Without
    /// collision effects only the velocities and positions are replaced.
    ///
    /// Errors: `BadParameter` before any step, after a `set_state`, for a BDF2 simulation (its
    /// end positions are not q_k + h·v), or when `v_new` has the wrong length; `NonFinite` for
    /// non-finite input; `Diverged` as in [`ShellSim::step`]. On error the state is unchanged.
    pub fn recollide(&mut self, v_new: &[Vec3]) -> Result<StepStats> {
        let n = self.mesh.n_vertices();
        if self.settings.kind == IntegratorKind::Bdf2 {
            return Err(Error::BadParameter("recollide supports backward Euler only".into()));
        }
        let Some((prev, h)) = self.prev.as_ref() else {
            return Err(Error::BadParameter("recollide needs a previous step".into()));
        };
        if v_new.len() != n {
            return Err(Error::BadParameter(format!("recollide: {} velocities for {n} vertices", v_new.len())));
        }
        if v_new.iter().any(|p| p.iter().any(|c| !c.is_finite())) {
            return Err(Error::NonFinite("recollide velocities"));
        }
        let (h, t_next) = (*h, self.state.t);
        let qk = &prev.q;
        let mut st = StepStats::default();
        let mut v: Vec<Vec3> =
            (0..n).map(|i| if self.inv_mass[i] > 0.0 { v_new[i] } else { self.state.v[i] }).collect();
        if let Some(ipc) = self.ipc.as_mut() {
            // IPC: from the (collision-free) end of the step toward q_k + h·v, as far as CCD
            // allows — contact keeps priority, and no gap closes below its CCD fraction.
            let tc = Instant::now();
            let x = &self.state.q;
            let dx: Vec<Vec3> =
                (0..n).map(|i| if self.inv_mass[i] > 0.0 { qk[i] + h * v[i] - x[i] } else { Vec3::zeros() }).collect();
            ipc.sweep(x, Some(&dx));
            let a = ipc.max_step(x, &dx);
            if a < 1.0 {
                st.contact.ccd_clamps += 1;
            }
            for i in 0..n {
                if self.inv_mass[i] > 0.0 {
                    v[i] = (x[i] + a * dx[i] - qk[i]) / h;
                }
            }
            st.t_collision = tc.elapsed().as_secs_f64();
        }
        if let Some(col) = self.collider.as_mut() {
            let tc = Instant::now();
            col.filter(qk, &mut v, h, t_next, &self.inv_mass, &mut st);
            st.t_collision = tc.elapsed().as_secs_f64();
        }
        let q_new: Vec<Pt3> =
            (0..n).map(|i| if self.inv_mass[i] > 0.0 { qk[i] + h * v[i] } else { self.state.q[i] }).collect();
        if q_new.iter().any(|p| p.iter().any(|c| !c.is_finite())) || v.iter().any(|p| p.iter().any(|c| !c.is_finite()))
        {
            return Err(Error::Diverged { step: self.steps, reason: "non-finite positions or velocities".into() });
        }
        let e = self.energies_of(&q_new, &v);
        let limit = self.settings.divergence_energy_factor * self.energy_ref;
        if !(e.membrane + e.bending + e.kinetic <= limit) {
            return Err(Error::Diverged {
                step: self.steps,
                reason: format!("energy {:.3e} J above {:.3e} J", e.membrane + e.bending + e.kinetic, limit),
            });
        }
        self.state.q = q_new;
        self.state.v = v;
        Ok(st)
    }

    /// Factor with diagonal-shift retries (§3.8) and solve.
    fn solve_system(&mut self, b: &[f64], h_eff: f64, alpha: f64, st: &mut StepStats) -> Result<Vec<f64>> {
        let tf = Instant::now();
        let mut tau = 0.0;
        let mut tries = 0;
        loop {
            match self.llt.factor(self.asm.matrix()) {
                Ok(()) => break,
                Err(geom_core::Error::NotPositiveDefinite { .. }) if tries < 5 => {
                    tau = if tau == 0.0 { 1e-8 } else { tau * 100.0 };
                    tries += 1;
                    self.asm.reshift(&self.mesh, h_eff, alpha, tau);
                }
                Err(geom_core::Error::NotPositiveDefinite { .. }) => return Err(Error::FactorizationFailed),
                Err(e) => return Err(Error::Core(e)),
            }
        }
        st.regularization_shift = tau;
        st.t_factor += tf.elapsed().as_secs_f64();
        let ts = Instant::now();
        let mut x = b.to_vec();
        self.llt.solve_in_place(&mut x).map_err(|_| Error::Diverged {
            step: self.steps,
            reason: "linear solve produced non-finite values".into(),
        })?;
        st.t_solve += ts.elapsed().as_secs_f64();
        Ok(x)
    }

    /// Φ(v) = ½(v − v_ref)ᵀM(v − v_ref) + E(q_base + h v) − h vᵀF_ext (damping, wind frozen).
    fn incremental_potential(&self, q_base: &[Pt3], h: f64, v_ref: &[Vec3], v: &[Vec3], t: f64) -> f64 {
        let q: Vec<Pt3> = q_base.iter().zip(v).map(|(p, vv)| p + h * vv).collect();
        let e = self.energies_of(&q, v);
        let mut fext = vec![Vec3::zeros(); v.len()];
        self.add_external_forces(t, &q, v, &mut fext);
        let mut phi = e.membrane + e.bending;
        for i in 0..v.len() {
            if self.inv_mass[i] > 0.0 {
                let d = v[i] - v_ref[i];
                phi += 0.5 * self.mesh.mass[i] * d.norm_squared() - h * v[i].dot(&fext[i]);
            }
        }
        phi
    }

    fn add_external_forces(&self, t: f64, q: &[Pt3], v: &[Vec3], f: &mut [Vec3]) {
        if let Some(g) = self.effects.gravity {
            for (fi, m) in f.iter_mut().zip(&self.mesh.mass) {
                *fi += *m * g;
            }
        }
        for c in &self.effects.custom {
            c.add_forces(t, q, v, f);
        }
    }

    /// Collects custom Jacobians into the diagonal blocks (−h J_v − h² J_x).
    fn custom_jacobians(&mut self, t: f64, q: &[Pt3], v: &[Vec3], h: f64) -> Result<()> {
        if self.effects.custom.is_empty() {
            return Ok(());
        }
        let (mut jx, mut jv) = (BlockTriplets::default(), BlockTriplets::default());
        for c in &self.effects.custom {
            c.add_jacobians(t, q, v, &mut jx, &mut jv);
        }
        for d in self.asm.custom_diag.iter_mut() {
            *d = Mat3::zeros();
        }
        self.asm.custom_offdiag.clear();
        let n = self.mesh.n_vertices();
        for (blocks, s) in [(&jx.blocks, -h * h), (&jv.blocks, -h)] {
            for &(i, j, m) in blocks {
                if i as usize >= n || j as usize >= n {
                    return Err(Error::BadParameter(format!(
                        "custom Jacobian block ({i}, {j}) names a missing vertex"
                    )));
                }
                let (fi, fj) = (self.asm.dofs.free_index[i as usize], self.asm.dofs.free_index[j as usize]);
                if fi == NONE || fj == NONE {
                    continue; // constrained rows/columns never enter the system
                }
                if i == j {
                    self.asm.custom_diag[fi as usize] += s * m;
                } else {
                    let off = self.asm.block_offset(i, j).ok_or_else(|| {
                        Error::BadParameter(format!(
                            "custom force Jacobian block ({i}, {j}): the vertices share no triangle (fixed pattern)"
                        ))
                    })?;
                    self.asm.custom_offdiag.push((off, s * m));
                }
            }
        }
        Ok(())
    }
}

fn check_settings(s: &IntegratorSettings) -> Result<()> {
    if !s.divergence_energy_factor.is_finite() || s.divergence_energy_factor <= 1.0 {
        return Err(Error::BadParameter(format!(
            "divergence_energy_factor must be finite and > 1, got {}",
            s.divergence_energy_factor
        )));
    }
    if s.newton_iters == 0 || s.newton_iters > 100 {
        return Err(Error::BadParameter(format!("newton_iters must be in 1..=100, got {}", s.newton_iters)));
    }
    Ok(())
}

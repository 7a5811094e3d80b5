//! [`Tracker`]: a `shells` simulation constrained to a guide (spec §3.5–§3.7): setup (rank check,
//! rows on pinned vertices, consistent initial state) and the tracked step with the residual
//! before and after the collision pass.

use std::time::Instant;

use geom_core::linalg::Csr;
use geom_core::math::{Pt3, Vec3};
use shells::{ShellSim, ShellState, StepStats};

use crate::constraints::{GramFactor, TrackingConstraints};
use crate::error::{Result, TrackError};
use crate::guide::GuideAnimation;
use crate::kkt::{KktMethod, TrackingSolver};
use crate::testfn::TestFunctions;

/// Tracking options (spec §4).
#[derive(Clone, Debug, PartialEq, serde::Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct TrackOptions {
    /// Saddle-point solver.
    pub kkt: KktMethod,
    /// Project the initial state onto the constraints and their time derivative (§3.5).
    pub project_initial_state: bool,
    /// Share c ∈ (0, 1] of the violation removed per step (1 = the seed).
    pub correction_fraction: f64,
    /// Iterative refinement steps after the LDLᵀ solve.
    pub refine_steps: u32,
    /// Also time an unused LLᵀ of A each step (solve-overhead attribution).
    pub shadow_timing: bool,
    /// Also solve every step's system with each of these methods (results unused, timed and
    /// compared with the main solve): measures the alternatives on identical matrices in one
    /// run (spec §3.6, issue 4). Costs their time; keep empty in overhead runs.
    pub compare: Vec<KktMethod>,
    /// After the collision pass, correct the velocities by the smallest mass-weighted change
    /// that removes the constraint residual, v ← v + W Ĉᵀ G⁻¹ g(q_{k+1}) / h, and rerun only the
    /// collision pass on it ([`ShellSim::recollide`]), so collision-freedom keeps priority
    /// (spec §3.7 step 5). Costs one collision pass per step when the residual is non-zero.
    pub reproject_after_collisions: bool,
}

impl Default for TrackOptions {
    fn default() -> Self {
        Self {
            kkt: KktMethod::ConstraintLastLdlt,
            project_initial_state: true,
            correction_fraction: 1.0,
            refine_steps: 1,
            shadow_timing: false,
            compare: Vec::new(),
            reproject_after_collisions: false,
        }
    }
}

/// Statistics of one tracked step.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TrackStepStats {
    /// The shell step's own statistics.
    pub shell: StepStats,
    /// Wall time of the whole step (s).
    pub t_step: f64,
    /// Constrained solve time (s).
    pub t_kkt: f64,
    /// Shadow LLᵀ time (s).
    pub t_shadow_llt: f64,
    /// max_i ‖g_i‖ before the collision pass (m).
    pub residual_pre_collision: f64,
    /// max_i ‖g_i‖ of the final state (m).
    pub residual_post_collision: f64,
    /// Largest per-vertex constraint force (N).
    pub max_constraint_force: f64,
    /// Relative residual of the KKT solve after refinement.
    pub kkt_refinement_residual: f64,
    /// Refinement steps the constrained solve took.
    pub kkt_refine_steps: u32,
    /// max_i ‖g_i‖ after the first collision pass (m), before the reprojection of
    /// [`TrackOptions::reproject_after_collisions`]; equals `residual_post_collision` without it.
    pub residual_post_first_pass: f64,
    /// The reprojection ran (option on and a non-zero post-collision residual).
    pub reprojected: bool,
    /// Guide held past its end at this step.
    pub guide_held: bool,
    /// Stored entries of the factor used by the constrained solve.
    pub nnz_l: usize,
    /// Per method of [`TrackOptions::compare`]: its solve of the same system.
    pub compare: Vec<crate::kkt::CompareStats>,
}

/// A tracked simulation.
pub struct Tracker {
    /// The fine simulation.
    pub sim: ShellSim,
    /// The guide.
    pub guide: GuideAnimation,
    /// Prolongation P (guide → tracked) when the meshes are subdivision-related.
    pub prolongation: Option<Csr>,
    /// The constrained solve (None when K = 0: untracked path, spec §8).
    pub solver: Option<TrackingSolver>,
    /// Rows of the input test functions dropped because their support is pinned and satisfied.
    pub dropped_rows: Vec<usize>,
    /// Setup warnings (dropped rows, …).
    pub warnings: Vec<String>,
    gram: Option<GramFactor>,
    /// Cᵀ of the enforced constraints (row l: the constraints touching vertex l), for the
    /// mass-weighted corrections; `None` when K = 0.
    ct: Option<Csr>,
    /// Inverse masses of free vertices, 0 for pinned/kinematic ones (the W of §3.5).
    w: Vec<f64>,
    reproject: bool,
    /// The guide's bounding-box diagonal L at t = 0 (m).
    scale: f64,
    gbuf: Vec<Pt3>,
}

impl Tracker {
    /// Builds constraints from `tf`, checks them against the simulation's free DOFs and
    /// optionally projects the initial state (§3.5).
    ///
    /// Errors: `BadParameter` for `newton_iters ≠ 1` without IPC contact (the delegated solve
    /// then replaces only the first Newton iteration of `shells`) or `correction_fraction ∉ (0, 1]`;
    /// `TopologyMismatch`, `ZeroIntegral`, `RankDeficient`, `InfeasibleConstraint` from setup.
    pub fn new(
        mut sim: ShellSim,
        guide: GuideAnimation,
        tf: TestFunctions,
        prolongation: Option<Csr>,
        opts: TrackOptions,
    ) -> Result<Self> {
        // With the Bridson filter only the first Newton solve is delegated; the IPC contact
        // model delegates every iteration's solve, so any iteration count works there.
        if sim.contact_method() != Some(shells::ContactMethod::Ipc) && sim.settings_mut().newton_iters != 1 {
            return Err(TrackError::BadParameter(format!(
                "tracking needs newton_iters = 1 (got {}) without IPC contact: only the first Newton solve is constrained",
                sim.settings_mut().newton_iters
            )));
        }
        if !(opts.correction_fraction > 0.0 && opts.correction_fraction <= 1.0) {
            return Err(TrackError::BadParameter(format!(
                "correction_fraction = {} must be in (0, 1]",
                opts.correction_fraction
            )));
        }
        let mut gbuf = vec![Pt3::origin(); guide.n_vertices()];
        let tracked_rest = geom_core::mesh::TriMesh::new(sim.mesh().rest.clone(), sim.mesh().tris.clone())?;
        let cons_all = TrackingConstraints::build(&guide.rest, &tracked_rest, &tf)?;
        let n = sim.mesh().n_vertices();
        let dofs = sim.free_dofs().clone();
        let free: Vec<bool> = (0..n).map(|v| dofs.free_index[v] != geom_core::NONE).collect();
        // Rows acting only on constrained vertices: drop if satisfied over the whole guide.
        let scale = guide.scale().max(1e-300);
        let pinned_rows = cons_all.pinned_only_rows(&free);
        let mut warnings = Vec::new();
        let q0 = sim.state().q.clone();
        for &i in &pinned_rows {
            let one = cons_all.select_rows(&[i]);
            let steps = (guide.duration() * 30.0).ceil() as usize;
            let mut worst = 0.0f64;
            for s in 0..=steps {
                guide.sample(s as f64 / 30.0, &mut gbuf);
                worst = worst.max(one.max_residual(&gbuf, &q0));
            }
            if worst > 1e-9 * scale {
                return Err(TrackError::InfeasibleConstraint(i));
            }
            warnings.push(format!("constraint {i} acts only on pinned vertices and is satisfied: dropped"));
        }
        let keep: Vec<usize> = (0..cons_all.len()).filter(|i| !pinned_rows.contains(i)).collect();
        let cons = cons_all.select_rows(&keep);
        let mass = sim.mesh().mass.clone();
        let w: Vec<f64> = (0..n).map(|v| if free[v] { 1.0 / mass[v] } else { 0.0 }).collect();
        let gram = if cons.is_empty() {
            None
        } else {
            Some(cons.check_rank(&w).map_err(|e| match e {
                TrackError::RankDeficient(rows) => TrackError::RankDeficient(rows.iter().map(|&r| keep[r]).collect()),
                other => other,
            })?)
        };
        let ct = (!cons.is_empty()).then(|| cons.c.transpose());
        let solver = if cons.is_empty() {
            None
        } else {
            Some(TrackingSolver::new(cons, guide.clone(), &opts, sim.fill_reducing_perm().to_vec(), sim.llt_symbolic()))
        };
        let reproject = opts.reproject_after_collisions;
        let mut tr = Self {
            sim,
            guide,
            prolongation,
            solver,
            dropped_rows: pinned_rows,
            warnings,
            gram,
            ct,
            w,
            reproject,
            scale,
            gbuf,
        };
        if opts.project_initial_state && tr.solver.is_some() {
            tr.project_initial_state()?;
        }
        Ok(tr)
    }

    /// The enforced constraints (None when K = 0).
    pub fn constraints(&self) -> Option<&TrackingConstraints> {
        self.solver.as_ref().map(|s| s.constraints())
    }

    /// Smallest mass-weighted correction of (q₀, v₀) with g₀ = 0 and ġ₀ = 0 (§3.5):
    /// q₀ += W C_fᵀ G⁻¹ g₀, v₀ += W C_fᵀ G⁻¹ (C̄ q̄̇(0) − C v₀).
    fn project_initial_state(&mut self) -> Result<()> {
        let Some(cons) = self.solver.as_ref().map(|s| s.constraints().clone()) else {
            return Ok(());
        };
        let st = self.sim.state().clone();
        let k = cons.len();
        self.guide.sample(st.t, &mut self.gbuf);
        let mut gq = vec![Vec3::zeros(); k];
        cons.residual(&self.gbuf, &st.q, &mut gq);
        let mut vb = vec![Vec3::zeros(); self.guide.n_vertices()];
        self.guide.sample_velocity(st.t, &mut vb);
        let vb_pt: Vec<Pt3> = vb.iter().map(|v| Pt3::from(*v)).collect();
        let v_pt: Vec<Pt3> = st.v.iter().map(|v| Pt3::from(*v)).collect();
        let mut gv = vec![Vec3::zeros(); k];
        cons.residual(&vb_pt, &v_pt, &mut gv);
        let dq = self.mass_weighted_correction(&gq);
        let dv = self.mass_weighted_correction(&gv);
        let q: Vec<Pt3> = st.q.iter().zip(&dq).map(|(p, d)| p + d).collect();
        let v: Vec<Vec3> = st.v.iter().zip(&dv).map(|(p, d)| p + d).collect();
        self.sim.set_state(ShellState { t: st.t, q, v })?;
        Ok(())
    }

    /// The smallest correction Δ in the mass metric with C Δ = g per coordinate:
    /// Δ = W Cᵀ G⁻¹ g, G = C W Cᵀ (the cached Gram factor), zero on pinned vertices.
    fn mass_weighted_correction(&self, g: &[Vec3]) -> Vec<Vec3> {
        let w = &self.w;
        let mut out = vec![Vec3::zeros(); w.len()];
        let (Some(gram), Some(ct)) = (self.gram.as_ref(), self.ct.as_ref()) else {
            return out;
        };
        for d in 0..3 {
            let mut y: Vec<f64> = g.iter().map(|x| x[d]).collect();
            gram.solve(&mut y);
            for (l, o) in out.iter_mut().enumerate() {
                if w[l] > 0.0 {
                    let (rows, vals) = ct.row(l);
                    o[d] = w[l] * rows.iter().zip(vals).map(|(&i, &c)| c * y[i as usize]).sum::<f64>();
                }
            }
        }
        out
    }

    /// §3.7 step 5: velocities corrected by W Ĉᵀ G⁻¹ g(q_{k+1}) / h, then the collision pass
    /// again from q_k ([`ShellSim::recollide`]). Returns the residual max_i ‖g_i‖ it started
    /// from (m) and whether it ran (not when every ‖g_i‖ ≤ 1e-12·L).
    fn reproject_after_collisions(&mut self, h: f64) -> Result<(f64, bool)> {
        let Some(solver) = self.solver.as_ref() else {
            return Ok((0.0, false));
        };
        let cons = solver.constraints();
        let st = self.sim.state();
        self.guide.sample(st.t, &mut self.gbuf);
        let mut g = vec![Vec3::zeros(); cons.len()];
        cons.residual(&self.gbuf, &st.q, &mut g);
        let first = g.iter().map(|x| x.norm()).fold(0.0, f64::max);
        // Already at solver precision (spec: r ≈ 1e-13·L): nothing to correct.
        if first <= 1e-12 * self.scale {
            return Ok((first, false));
        }
        let dq = self.mass_weighted_correction(&g);
        let v: Vec<Vec3> = self.sim.state().v.iter().zip(&dq).map(|(v, d)| v + d / h).collect();
        self.sim.recollide(&v)?;
        Ok((first, true))
    }

    /// Current constraint residual max_i ‖g_i(q, t)‖ (m); 0 when K = 0.
    pub fn residual_now(&mut self) -> f64 {
        match self.solver.as_ref() {
            Some(s) => {
                let st = self.sim.state();
                self.guide.sample(st.t, &mut self.gbuf);
                s.constraints().max_residual(&self.gbuf, &st.q)
            }
            None => 0.0,
        }
    }

    /// One tracked step of size h (s) (§3.7). With K = 0 this is exactly `ShellSim::step`.
    pub fn step(&mut self, h: f64) -> Result<TrackStepStats> {
        let t0 = Instant::now();
        let mut out = TrackStepStats::default();
        match self.solver.as_mut() {
            None => {
                out.shell = self.sim.step(h)?;
            }
            Some(s) => {
                s.begin_step();
                out.shell = self.sim.step_with(h, s)?;
                let l = &s.last;
                out.t_kkt = l.t_kkt;
                out.t_shadow_llt = l.t_shadow_llt;
                out.residual_pre_collision = l.residual_pre;
                out.max_constraint_force = l.max_constraint_force;
                out.kkt_refinement_residual = l.refinement_residual;
                out.kkt_refine_steps = l.refine_steps_done;
                out.guide_held = l.guide_held;
                out.nnz_l = l.nnz_l;
                out.compare = l.compare.clone();
            }
        }
        if self.reproject {
            (out.residual_post_first_pass, out.reprojected) = self.reproject_after_collisions(h)?;
        }
        out.t_step = t0.elapsed().as_secs_f64();
        out.residual_post_collision = self.residual_now();
        if !self.reproject {
            out.residual_post_first_pass = out.residual_post_collision;
        }
        Ok(out)
    }
}

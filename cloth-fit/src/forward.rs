//! The forward model: a calibration experiment simulated by `shells` (spec §3.2).
//!
//! Mapping of the paper's Baraff–Witkin parameters onto `shells` (spec §3.2, reconstructed):
//! the membrane is the orthotropic St. Venant–Kirchhoff law
//! ψ = ½k_stretch(E_uu² + E_vv²) + 2k_shear E_uv² (per unit rest area, warp along the rest grid's
//! u axis, no Poisson coupling), bending is Discrete Shells with k_B = B/6 (a cylinder of
//! curvature κ stores ½Bκ² per area, independent of the resolution), damping is per term
//! Rayleigh (β_stretch, β_shear, β_bend on the Gauss–Newton Hessians, = Baraff–Witkin condition
//! damping with k_d = β·k_s), mass is lumped from the measured areal density, gravity is
//! −9.81·world_up, and the paper's nonlinear drag is a [`DragForce`] hook.

use std::sync::Arc;

use geom_core::math::{smoothstep, Pt3, Vec3};
use geom_core::procedural::{grid, Diagonals, GridSpec, Plane};
use serde::{Deserialize, Serialize};
use shells::{
    Damping, Effects, IntegratorKind, IntegratorSettings, Material, MembraneLaw, ShellSceneDesc, ShellSim, ShellState,
    VertexConstraint, WarpSource,
};

use crate::drag::DragForce;
use crate::error::{FitError, Result, SimError};
use crate::params::FabricParams;
use crate::rig::Rig;
use crate::setup::Experiment;

/// Time integrator of the forward model (spec §3.2 "Integrator").
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum Integrator {
    /// Linearly implicit backward Euler (the paper's first choice, rejected for its numerical
    /// damping).
    #[default]
    BackwardEuler,
    /// Second-order BDF (much less numerical damping; used for synthetic truths).
    Bdf2,
}

/// Collision handling of the forward model.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum CollisionMode {
    /// No collisions (the swatches; the paper's skirt needs them, C9 is not built).
    #[default]
    Off,
}

/// Discretisation of the forward model (spec §2 `SimOptions`, §4.5).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SimOptions {
    /// Quads per side of the swatch grid.
    pub res: usize,
    /// Time step (s).
    pub dt: f64,
    /// Integrator.
    #[serde(default)]
    pub integrator: Integrator,
    /// Collisions.
    #[serde(default)]
    pub collisions: CollisionMode,
    /// Levels of midpoint subdivision + smoothing of the rendered mesh (ours; 0 = none).
    #[serde(default)]
    pub render_subdivision: u32,
    /// Add the drag's velocity Jacobian to the implicit system (default explicit drag).
    #[serde(default)]
    pub implicit_drag: bool,
}

impl SimOptions {
    /// Checks the values.
    pub fn validate(&self) -> Result<()> {
        if self.res < 1 || self.res > 256 {
            return Err(FitError::BadParameter(format!("model res must be in 1..=256, got {}", self.res)));
        }
        if !(self.dt > 0.0 && self.dt <= 0.1) {
            return Err(FitError::BadParameter(format!("model dt must be in (0, 0.1] s, got {}", self.dt)));
        }
        if self.render_subdivision > 3 {
            return Err(FitError::BadParameter(format!(
                "render_subdivision must be ≤ 3, got {}",
                self.render_subdivision
            )));
        }
        Ok(())
    }
}

/// Vertex positions of the rendered mesh at the frame times.
#[derive(Clone, Debug, PartialEq)]
pub struct SimTrajectory {
    /// Frame k at t_k = k/fps after the settle (positions of the rendered mesh, m).
    pub frames: Vec<Vec<Pt3>>,
    /// Frame times (s after the settle).
    pub times: Vec<f64>,
    /// False when the settle protocol hit its time limit (a warning, spec §3.2).
    pub settled: bool,
    /// Settling time used (s).
    pub settle_s: f64,
    /// Implicit steps taken in all.
    pub steps: usize,
}

/// A forward model of the calibration experiments (spec §2). `Sync`, so independent
/// evaluations run in parallel.
pub trait ForwardModel: Sync {
    /// Simulates experiment `e` with parameters `p`; positions at the frame times.
    fn simulate(
        &self,
        p: &FabricParams,
        e: &Experiment,
        rig: &Rig,
        opts: &SimOptions,
    ) -> Result<SimTrajectory, SimError>;
    /// Triangles of the rendered mesh.
    fn faces(&self, opts: &SimOptions) -> Vec<[u32; 3]>;
}

/// The swatch mesh in its local frame: rest (u, v) coordinates in metres, faces, and the two
/// top-corner vertices.
#[derive(Clone, Debug, PartialEq)]
pub struct SwatchMesh {
    /// (u, v) ∈ [0, w] × [0, h] per vertex; v = h is the top edge.
    pub uv: Vec<(f64, f64)>,
    /// Triangles (alternating diagonals).
    pub faces: Vec<[u32; 3]>,
    /// Vertices of the top-left (u = 0) and top-right (u = w) corners.
    pub corners: [u32; 2],
}

/// The `res × res` grid over `w × h` with alternating diagonals (geom-core's grid generator).
pub fn swatch_mesh(res: usize, w: f64, h: f64) -> SwatchMesh {
    let spec = GridSpec {
        quads: [res as u32; 2],
        size: [w, h],
        plane: Plane::XZ,
        diagonals: Diagonals::Alternating,
        ..Default::default()
    };
    let m = grid(&spec).expect("validated: res ≥ 1 and a positive finite size make a valid grid");
    let uv = m.positions.iter().map(|p| (p.x + 0.5 * w, p.z + 0.5 * h)).collect();
    let n = res as u32 + 1;
    SwatchMesh { uv, faces: m.faces.clone(), corners: [res as u32 * n, res as u32 * n + res as u32] }
}

/// Midpoint subdivision followed by one uniform Laplacian smoothing pass (λ = ½) of the new
/// interior vertices, `levels` times (ours: the "render_subdivision" of spec §3.2, reducing the
/// faceting of coarse fitting meshes). Precomputed once as fixed stencils.
#[derive(Clone, Debug)]
pub struct RenderRefine {
    faces: Vec<[u32; 3]>,
    /// Per fine vertex: (coarse index, weight) pairs.
    stencils: Vec<Vec<(u32, f64)>>,
}

impl RenderRefine {
    /// The refinement of `faces` over `n` vertices (`levels = 0`: identity).
    pub fn new(n: usize, faces: &[[u32; 3]], levels: u32) -> Self {
        let mut stencils: Vec<Vec<(u32, f64)>> = (0..n as u32).map(|i| vec![(i, 1.0)]).collect();
        let mut faces = faces.to_vec();
        for _ in 0..levels {
            let mut edges = std::collections::BTreeMap::new();
            let mut next = Vec::with_capacity(4 * faces.len());
            let mut boundary = std::collections::BTreeMap::<(u32, u32), u32>::new();
            for f in &faces {
                for k in 0..3 {
                    let (a, b) = (f[k], f[(k + 1) % 3]);
                    *boundary.entry((a.min(b), a.max(b))).or_insert(0) += 1;
                }
            }
            let mut mid = |a: u32, b: u32, st: &mut Vec<Vec<(u32, f64)>>| -> u32 {
                *edges.entry((a.min(b), a.max(b))).or_insert_with(|| {
                    let s = combine(&[(&st[a as usize], 0.5), (&st[b as usize], 0.5)]);
                    st.push(s);
                    (st.len() - 1) as u32
                })
            };
            for f in &faces {
                let [a, b, c] = *f;
                let (ab, bc, ca) = (mid(a, b, &mut stencils), mid(b, c, &mut stencils), mid(c, a, &mut stencils));
                next.extend([[a, ab, ca], [ab, b, bc], [ca, bc, c], [ab, bc, ca]]);
            }
            // Smoothing of interior midpoints toward the mean of their fine neighbours.
            let nv = stencils.len();
            let mut nbr: Vec<std::collections::BTreeSet<u32>> = vec![Default::default(); nv];
            for f in &next {
                for k in 0..3 {
                    nbr[f[k] as usize].insert(f[(k + 1) % 3]);
                    nbr[f[(k + 1) % 3] as usize].insert(f[k]);
                }
            }
            let interior_mid: Vec<u32> =
                edges.iter().filter(|(e, _)| boundary.get(e).copied().unwrap_or(0) == 2).map(|(_, &m)| m).collect();
            let old = stencils.clone();
            for m in interior_mid {
                let ns: Vec<u32> = nbr[m as usize].iter().copied().collect();
                let w = 0.5 / ns.len() as f64;
                let mut parts: Vec<(&Vec<(u32, f64)>, f64)> = vec![(&old[m as usize], 0.5)];
                parts.extend(ns.iter().map(|&j| (&old[j as usize], w)));
                stencils[m as usize] = combine(&parts);
            }
            faces = next;
        }
        Self { faces, stencils }
    }

    /// Refined faces.
    pub fn faces(&self) -> &[[u32; 3]] {
        &self.faces
    }

    /// Refined positions from coarse ones.
    pub fn apply(&self, q: &[Pt3]) -> Vec<Pt3> {
        self.stencils
            .iter()
            .map(|s| Pt3::from(s.iter().fold(Vec3::zeros(), |a, &(i, w)| a + w * q[i as usize].coords)))
            .collect()
    }
}

fn combine(parts: &[(&Vec<(u32, f64)>, f64)]) -> Vec<(u32, f64)> {
    let mut m = std::collections::BTreeMap::<u32, f64>::new();
    for (s, w) in parts {
        for &(i, x) in s.iter() {
            *m.entry(i).or_insert(0.0) += w * x;
        }
    }
    m.into_iter().collect()
}

/// The `shells` forward model (spec §2 `ShellsForward`).
#[derive(Clone, Copy, Debug, Default)]
pub struct ShellsForward;

/// The `shells` material of `p` for areal density `rho` with extra mass damping `alpha`.
pub fn material(p: &FabricParams, rho: f64, alpha: f64) -> Material {
    Material {
        density: rho,
        membrane: MembraneLaw::Orthotropic {
            k_stretch_u: p.stretch,
            k_stretch_v: p.stretch,
            k_shear: p.shear,
            k_couple: 0.0,
            warp: WarpSource::Direction(Vec3::x()),
        },
        bending: Material::k_b_from_modulus(p.bend),
        damping: Damping::PerTerm {
            alpha,
            beta_stretch: p.stretch_damp,
            beta_shear: p.shear_damp,
            beta_bend: p.bend_damp,
        },
        plasticity: None,
    }
}

fn kind_of(i: Integrator) -> IntegratorKind {
    match i {
        Integrator::BackwardEuler => IntegratorKind::BackwardEuler,
        Integrator::Bdf2 => IntegratorKind::Bdf2,
    }
}

fn sim_err(t: f64) -> impl Fn(shells::Error) -> SimError {
    move |e| match e {
        shells::Error::BadParameter(_) | shells::Error::NonFinite(_) => SimError::Setup(e.to_string()),
        other => SimError::Diverged { t, reason: other.to_string() },
    }
}

/// Records frames at times k/fps from a stepped simulation, interpolating linearly in time when
/// dt does not divide 1/fps.
struct FrameSampler {
    fps: f64,
    n: usize,
    frames: Vec<Vec<Pt3>>,
    times: Vec<f64>,
}

impl FrameSampler {
    fn next_time(&self) -> Option<f64> {
        (self.frames.len() < self.n).then(|| self.frames.len() as f64 / self.fps)
    }

    /// Offers the step (t0, q0) → (t1, q1); records every frame time in (t0, t1].
    fn offer(&mut self, t0: f64, q0: &[Pt3], t1: f64, q1: &[Pt3]) {
        while let Some(tf) = self.next_time() {
            if tf > t1 + 1e-9 * (t1 - t0) {
                break;
            }
            let s = if (t1 - tf).abs() <= 1e-9 * (t1 - t0) { 1.0 } else { ((tf - t0) / (t1 - t0)).clamp(0.0, 1.0) };
            let q = if s == 1.0 { q1.to_vec() } else { q0.iter().zip(q1).map(|(a, b)| a + s * (b - a)).collect() };
            self.frames.push(q);
            self.times.push(tf);
        }
    }
}

impl ShellsForward {
    /// Simulates and returns the *simulation* mesh positions (before render refinement).
    pub fn simulate_raw(
        &self,
        p: &FabricParams,
        e: &Experiment,
        rig: &Rig,
        opts: &SimOptions,
    ) -> Result<SimTrajectory, SimError> {
        let setup = |m: FitError| SimError::Setup(m.to_string());
        e.validate().map_err(setup)?;
        opts.validate().map_err(setup)?;
        p.validate().map_err(setup)?;
        let sw = e.swatch;
        let (mid, e_u, up) = e.swatch_frame(&rig.world_up).map_err(setup)?;
        let mesh = swatch_mesh(opts.res, sw.width, sw.height);
        let normal = e_u.cross(&up);
        // Toward the camera.
        let toward = match rig.camera.center() {
            Some(c) if (c - mid).dot(&normal) < 0.0 => -normal,
            _ => normal,
        };
        let place = |u: f64, v: f64| mid + (u - 0.5 * sw.width) * e_u + (v - sw.height) * up;
        let rest: Vec<Pt3> = mesh.uv.iter().map(|&(u, v)| place(u, v)).collect();
        let pi = std::f64::consts::PI;
        let initial: Vec<Pt3> = mesh
            .uv
            .iter()
            .zip(&rest)
            .map(|(&(u, v), x)| x + e.settle.bulge_m * (pi * u / sw.width).sin() * (pi * v / sw.height).sin() * toward)
            .collect();
        let faces = Arc::new(mesh.faces.clone());
        // The settle runs with a fixed damping and drag (see `SettleProtocol::damping`); the
        // fabric's own values take over for the recorded motion.
        let settle_p = FabricParams {
            stretch_damp: e.settle.damping,
            shear_damp: e.settle.damping,
            bend_damp: e.settle.damping,
            drag: crate::presets::drag_midpoint(),
            ..*p
        };
        let mut settle_drag = DragForce::new(settle_p.drag, faces.clone());
        settle_drag.implicit = opts.implicit_drag;
        let settle_drag = Arc::new(settle_drag);
        let mut drag = DragForce::new(p.drag, faces.clone());
        drag.implicit = opts.implicit_drag;
        let drag = Arc::new(drag);
        let integrator = IntegratorSettings { kind: kind_of(opts.integrator), ..Default::default() };
        let effects = Effects { gravity: Some(rig.gravity()), custom: vec![drag], ..Default::default() };
        let settle_effects = Effects { custom: vec![settle_drag], ..effects.clone() };
        let [c0, c1] = mesh.corners;
        let starts = [rest[c0 as usize], rest[c1 as usize]];
        let targets = e.corner_targets();
        let move_s = e.settle.move_s;
        let settle_path = move |t: f64, i: u32| -> Pt3 {
            let k = if i == c0 { 0 } else { 1 };
            let s = if move_s > 0.0 { smoothstep(0.0, move_s, t) } else { 1.0 };
            starts[k] + s * (targets[k] - starts[k])
        };
        let desc = ShellSceneDesc {
            rest: rest.clone(),
            faces: mesh.faces.clone(),
            uv: None,
            initial: Some(initial),
            initial_velocity: None,
            material: material(&settle_p, sw.areal_density, e.settle.alpha),
            effects: settle_effects,
            constraints: vec![VertexConstraint::Kinematic(vec![c0, c1], Box::new(settle_path))],
            integrator: integrator.clone(),
            t0: 0.0,
        };
        let mut sim = ShellSim::new(desc).map_err(sim_err(0.0))?;
        let dt = opts.dt;
        let bound = 10.0 * sw.width.max(sw.height);
        let check = |q: &[Pt3], t: f64| -> Result<(), SimError> {
            for (i, x) in q.iter().enumerate() {
                let d = (x - mid).norm();
                if !(d <= bound) {
                    return Err(SimError::Escaped { t, vertex: i, distance: d });
                }
            }
            Ok(())
        };
        let mass: f64 = sim.mesh().mass.iter().sum();
        let n_min = (e.settle.settle_s / dt).round() as usize;
        let n_max = (e.settle.max_s / dt).round().max(n_min as f64) as usize;
        let mut steps = 0usize;
        let mut settled = false;
        let qs = e.settle.quasi_static_steps;
        let at_rest = |sim: &mut ShellSim, t: f64| -> Result<(), SimError> {
            let st = sim.state().clone();
            let v = vec![Vec3::zeros(); st.v.len()];
            sim.set_state(ShellState { v, ..st }).map_err(sim_err(t))
        };
        if qs > 0 {
            // Quasi-static continuation: each step from rest, backward Euler.
            sim.settings_mut().kind = IntegratorKind::BackwardEuler;
            let h = e.settle.move_s.max(1e-3) / qs as f64;
            for _ in 0..qs {
                let t = sim.state().t + h;
                sim.step(h).map_err(sim_err(t))?;
                at_rest(&mut sim, t)?;
                steps += 1;
            }
            check(&sim.state().q, sim.state().t)?;
        }
        while qs == 0 && steps < n_max {
            let t = (steps + 1) as f64 * dt;
            sim.step(dt).map_err(sim_err(t))?;
            steps += 1;
            if steps.is_multiple_of(16) {
                check(&sim.state().q, t)?;
            }
            if steps >= n_min && sim.energies().kinetic / mass < e.settle.ke_per_mass {
                settled = true;
                break;
            }
        }
        // Quasi-static relaxation to the equilibrium (backward Euler, large steps), then rest.
        if qs > 0 {
            // From rest every step, until no vertex moves more than the tolerance.
            for _ in 0..e.settle.relax_steps {
                let q0 = sim.state().q.clone();
                let t = sim.state().t + e.settle.relax_dt;
                sim.step(e.settle.relax_dt).map_err(sim_err(t))?;
                at_rest(&mut sim, t)?;
                steps += 1;
                let moved: Vec<f64> = q0.iter().zip(&sim.state().q).map(|(a, b)| (a - b).norm()).collect();
                if geom_core::stats::max(&moved) <= e.settle.relax_tol_m {
                    settled = true;
                    break;
                }
            }
            sim.settings_mut().kind = kind_of(opts.integrator);
        } else if e.settle.relax_steps > 0 {
            let kind = sim.settings_mut().kind;
            sim.settings_mut().kind = IntegratorKind::BackwardEuler;
            for k in 0..e.settle.relax_steps {
                let t = steps as f64 * dt + (k + 1) as f64 * e.settle.relax_dt;
                sim.step(e.settle.relax_dt).map_err(sim_err(t))?;
            }
            sim.settings_mut().kind = kind;
            let t = sim.state().t;
            at_rest(&mut sim, t)?;
            steps += e.settle.relax_steps;
        }
        let settle_s = sim.state().t;
        check(&sim.state().q, settle_s)?;
        let mut sampler = FrameSampler { fps: rig.fps, n: e.frames, frames: Vec::new(), times: Vec::new() };
        sampler.frames.push(sim.state().q.clone());
        sampler.times.push(0.0);
        if !e.is_dynamic() {
            // Static: the scene does not move; every frame shows the equilibrium.
            while let Some(tf) = sampler.next_time() {
                sampler.frames.push(sim.state().q.clone());
                sampler.times.push(tf);
            }
        } else if e.frames > 1 {
            let st = sim.state().clone();
            let ee = e.clone();
            let path = move |t: f64, i: u32| -> Pt3 { ee.corner_at(if i == c0 { 0 } else { 1 }, t) };
            let desc = ShellSceneDesc {
                rest,
                faces: mesh.faces.clone(),
                uv: None,
                initial: Some(st.q.clone()),
                initial_velocity: Some(st.v.clone()),
                material: material(p, sw.areal_density, 0.0),
                effects,
                constraints: vec![VertexConstraint::Kinematic(vec![c0, c1], Box::new(path))],
                integrator,
                t0: 0.0,
            };
            let mut stepper = ShellSim::new(desc).map_err(sim_err(settle_s))?;
            let mut k = 0usize;
            while sampler.next_time().is_some() {
                let q0 = stepper.state().q.clone();
                let t0 = k as f64 * dt;
                stepper.step(dt).map_err(sim_err(settle_s + t0 + dt))?;
                k += 1;
                steps += 1;
                let t1 = k as f64 * dt;
                if k.is_multiple_of(16) {
                    check(&stepper.state().q, settle_s + t1)?;
                }
                sampler.offer(t0, &q0, t1, &stepper.state().q);
            }
            check(&stepper.state().q, settle_s + k as f64 * dt)?;
        }
        Ok(SimTrajectory { frames: sampler.frames, times: sampler.times, settled, settle_s, steps })
    }
}

impl ForwardModel for ShellsForward {
    fn simulate(
        &self,
        p: &FabricParams,
        e: &Experiment,
        rig: &Rig,
        opts: &SimOptions,
    ) -> Result<SimTrajectory, SimError> {
        let mut tr = self.simulate_raw(p, e, rig, opts)?;
        if opts.render_subdivision > 0 {
            let n = (opts.res + 1) * (opts.res + 1);
            let mesh = swatch_mesh(opts.res, e.swatch.width, e.swatch.height);
            let r = RenderRefine::new(n, &mesh.faces, opts.render_subdivision);
            for f in tr.frames.iter_mut() {
                *f = r.apply(f);
            }
        }
        Ok(tr)
    }

    fn faces(&self, opts: &SimOptions) -> Vec<[u32; 3]> {
        let mesh = swatch_mesh(opts.res, 1.0, 1.0);
        if opts.render_subdivision == 0 {
            return mesh.faces;
        }
        let n = (opts.res + 1) * (opts.res + 1);
        RenderRefine::new(n, &mesh.faces, opts.render_subdivision).faces().to_vec()
    }
}

//! Contact by Incremental Potential Contact (Li et al. 2020; its codimensional form for cloth,
//! Li, Kaufman, Jiang 2021): the default contact model of `shells`.
//!
//! Contact is part of the implicit step's potential instead of a velocity filter after it: every
//! pair of non-adjacent primitives closer than d̂ (self-contact) or within d̂ of an obstacle adds
//! the barrier κ·b(d) ([`barrier`]) to the incremental potential, and every pair in contact at
//! the step's start adds lagged friction ([`friction`]). The Newton iterations of the step take a
//! line search whose step is first clamped by continuous collision detection ([`accd`]) so that
//! no gap ever reaches zero: every iterate, hence every step, is intersection-free by
//! construction, and the potential decreases from iterate to iterate, so contact cannot add
//! energy. This replaces the velocity filter of Bridson et al. 2002 (still available as
//! [`crate::effects::ContactMethod::Bridson`]), whose rigid impact zones and obstacle pass
//! added energy and let vertices through obstacles (README, "Contact").
//!
//! The contact Hessian is the Gauss–Newton form κ b″(d) ∇d∇dᵀ (PSD, b is convex); friction's
//! is the majorizer μλ f₁(y)/y on the tangent plane ([`friction`]). With the simulator's own
//! solve the blocks enter the matrix exactly: contact pairs coupling vertices that share no
//! triangle grow the sparsity pattern (`ShellSim::grow_pattern`, re-analysing the Cholesky only
//! when it grows; a handful of new pairs stays lumped as below until more are missing). With a delegated solve (`tracks`, whose constrained factorisations are built
//! on the mesh's fixed pattern) such a block is replaced by ‖B‖-scaled blocks on both diagonals
//! ([`Ipc::add`]), which keeps the matrix an upper bound of the exact one (PSD), so every Newton
//! direction is still a descent direction.

pub mod accd;
pub mod barrier;
pub mod deforming;
pub mod distance;
pub(crate) mod friction;
pub(crate) mod obstacle;
pub(crate) mod set;

use geom_core::math::{Mat3, Pt3, Vec3};
use geom_core::NONE;
use rayon::prelude::*;

use crate::collision::broad::BroadPhase;
use crate::effects::{CollisionSettings, Effects, Obstacle};
use crate::mesh::ShellMesh;
use friction::FrictionContact;
use obstacle::Placed;
use set::{Contact, Node, Topo};

/// What one step's contact handling did.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ContactStats {
    /// Active contact pairs at the step's end.
    pub active: u32,
    /// Frozen friction contacts of the step.
    pub friction: u32,
    /// Smallest gap at the step's end (m; +∞ without contacts).
    pub min_gap: f64,
    /// Barrier stiffness κ used (N/m).
    pub kappa: f64,
    /// Times the CCD clamped a Newton step below 1.
    pub ccd_clamps: u32,
    /// Line searches that found no decrease of the potential and took the CCD-safe step anyway.
    pub line_search_failures: u32,
    /// Newton iterations that ended without reaching the tolerance.
    pub unconverged: u32,
    /// 1 when the step ended on the contact-free path (no pair within d̂, no friction, the full
    /// linearised step taken: the seed's integrator), else 0.
    pub contact_free_steps: u32,
}

/// The IPC contact model of one simulation.
pub(crate) struct Ipc {
    tris: Vec<[u32; 3]>,
    edges: Vec<[u32; 2]>,
    mean_edge: f64,
    obstacles: Vec<Obstacle>,
    obstacle_edges: Vec<Vec<[u32; 2]>>,
    /// Deforming-mesh obstacles with their edges (module [`deforming`]); placed after the rigid
    /// ones (obstacle index `obstacles.len() + k`).
    deforming: Vec<(deforming::DeformingMesh, Vec<[u32; 2]>)>,
    /// True while [`Ipc::max_step`] checks the carry motion of a step's start, in which the
    /// deforming obstacles move too (relative motion); false during the Newton iterations.
    relative: bool,
    placed: Vec<Placed>,
    /// Activation distance d̂ (m).
    pub dhat: f64,
    /// Barrier stiffness κ (N/m).
    pub kappa: f64,
    kappa_max: f64,
    eps_v: f64,
    mu_self: f64,
    self_collision: bool,
    /// Newton tolerance on ‖Δv‖∞ (m/s).
    pub newton_tol: f64,
    /// Newton iteration cap.
    pub max_iters: u32,
    bp: BroadPhase,
    /// Candidate pairs of the last [`Ipc::sweep`].
    cands: Option<Cands>,
    friction: Vec<FrictionContact>,
    x0: Vec<Pt3>,
    eps: f64,
}

/// Fraction of a pair's gap the CCD line search lets a step close at most.
const CCD_KEEP: f64 = 0.1;

/// The smallest gap any step may produce, as a fraction of d̂: the barrier's force there is
/// ~10³ times its force at d̂/2, and a conflict that keeps pushing (a tracking constraint into
/// an obstacle) stops at this gap instead of driving it to zero.
const GAP_FLOOR: f64 = 1e-3;

/// IPC's contact distance d̂ (m), the reach of the barrier: the scene's `thickness` when
/// positive, else a tenth of the mesh's mean rest edge length `mean_edge` (m) clamped to
/// [1 mm, 1 cm].
pub fn contact_distance(thickness: f64, mean_edge: f64) -> f64 {
    if thickness > 0.0 {
        thickness
    } else {
        (0.1 * mean_edge).clamp(1e-3, 1e-2)
    }
}

impl Ipc {
    pub(crate) fn new(mesh: &ShellMesh, effects: &Effects, cs: &CollisionSettings) -> Self {
        let mean_edge = mesh.mean_edge_length();
        let dhat = contact_distance(cs.thickness, mean_edge);
        let n = mesh.n_vertices().max(1);
        let m_avg = mesh.mass.iter().sum::<f64>() / n as f64;
        let g = effects.gravity.map(|g| g.norm()).unwrap_or(0.0).max(1.0);
        // A resting vertex is held at d ≈ d̂/2 by κ|b′(d̂/2)| ≈ 1.19 κ d̂ = m g: κ = 100 m̄ g / d̂
        // keeps resting gaps near d̂ (b′ grows fast below); κ doubles while gaps fall below
        // 1 % of d̂ (membrane forces pressing layers together, impacts).
        let kappa = cs.barrier_stiffness.unwrap_or(100.0 * m_avg * g / dhat);
        let obstacle_edges = effects
            .obstacles
            .iter()
            .map(|o| match &o.shape {
                crate::effects::ObstacleShape::Mesh { tris, .. } => obstacle::mesh_edges(tris),
                _ => Vec::new(),
            })
            .collect();
        Self {
            tris: mesh.tris.clone(),
            edges: mesh.edges.clone(),
            mean_edge,
            obstacles: effects.obstacles.clone(),
            obstacle_edges,
            deforming: Vec::new(),
            relative: false,
            placed: Vec::new(),
            dhat,
            kappa,
            kappa_max: kappa * 1e6,
            eps_v: cs.friction_eps_v,
            mu_self: cs.friction,
            self_collision: effects.self_collision,
            newton_tol: cs.newton_tol,
            max_iters: cs.max_newton_iters,
            bp: BroadPhase::default(),
            cands: None,
            friction: Vec::new(),
            x0: Vec::new(),
            eps: 0.0,
        }
    }

    /// Adds a deforming-mesh obstacle (module [`deforming`]); it is placed from the next step on.
    pub(crate) fn add_deforming(&mut self, d: deforming::DeformingMesh) {
        let e = obstacle::mesh_edges(d.tris());
        self.deforming.push((d, e));
    }

    /// Places the obstacles at the step's end t_next and freezes friction at the start `x0`
    /// (contacts active there, normal forces κ|b′(d)|). With deforming obstacles, `x0` is first
    /// moved by the carry of [`deforming`] (the Newton solve's start; friction's reference
    /// stays the unmoved start). Errors when an obstacle's new placement intersects the cloth
    /// at the step's start (an obstacle moving by more than the gap in one step): the step
    /// must be shortened.
    pub(crate) fn begin_step(&mut self, x0: &mut [Pt3], t_next: f64, h: f64) -> Result<u32, String> {
        self.bp.next_step();
        let t_prev = t_next - h;
        self.placed = self
            .obstacles
            .iter()
            .zip(&self.obstacle_edges)
            .map(|(o, e)| obstacle::place(o, &obstacle::pose(o, t_next), e))
            .collect();
        self.x0 = x0.to_vec();
        self.eps = self.eps_v * h;
        if !self.deforming.is_empty() {
            self.carry(x0, t_prev, t_next)?;
        }
        let x0: &[Pt3] = x0;
        self.sweep(x0, None);
        let contacts = self.contacts(x0);
        let mut bad = 0u32;
        let mut first_bad: Option<(&Contact, f64)> = None;
        let mut fr = Vec::new();
        for c in &contacts {
            let g = c.gap(x0);
            if !(g.d > 0.0) {
                bad += 1;
                first_bad.get_or_insert((c, g.d));
                continue;
            }
            let lambda = self.kappa * -barrier::first(g.d, self.dhat);
            let shift = |p: &Pt3| -> Vec3 {
                if c.obstacle == NONE {
                    return Vec3::zeros();
                }
                if c.obstacle as usize >= self.obstacles.len() {
                    return self.deforming_shift(c, p);
                }
                let o = &self.obstacles[c.obstacle as usize];
                match &o.motion {
                    None => Vec3::zeros(),
                    Some(m) => {
                        let a = m.transform(t_prev);
                        let b = m.transform(t_next);
                        // The material point now at p (end placement) was at b⁻¹p in the rest frame.
                        let rest = b.inverse_transform_point(p);
                        p - a * rest
                    }
                }
            };
            fr.extend(FrictionContact::new(c, x0, lambda, shift));
        }
        self.friction = fr;
        if let Some((c, d)) = first_bad {
            return Err(format!(
                "{bad} contact pair(s) have no gap at the step's start t = {t_prev} s; first: {} against {}, \
                 gap {d:.3e} m (the log barrier needs every gap > 0: start the cloth at least the collision \
                 thickness d̂ = {:.3e} m off obstacles and itself, or shorten the step if a moving obstacle \
                 entered the cloth)",
                c.key.0.describe(&self.edges),
                c.key.1.describe(&self.edges),
                self.dhat
            ));
        }
        Ok(self.friction.len() as u32)
    }

    /// The carry of a step's start (module [`deforming`]): places the deforming obstacles at
    /// t_next (trees over their motion from t_prev), moves `x` by the carry displacement and
    /// checks by CCD, the obstacles moving too, that the motion is intersection-free.
    fn carry(&mut self, x: &mut [Pt3], t_prev: f64, t_next: f64) -> Result<(), String> {
        let mut dx = vec![Vec3::zeros(); x.len()];
        for (k, (d, e)) in self.deforming.iter().enumerate() {
            let (p0, p1) = (d.positions(t_prev), d.positions(t_next));
            deforming::add_carry(d.tris(), &p0, &p1, x, self.dhat, &mut dx)
                .map_err(|err| format!("deforming obstacle {k}: {err}"))?;
            self.placed.push(Placed::Core(Box::new(obstacle::Core::moving(&p0, p1, e.clone(), d.tris().to_vec()))));
        }
        self.relative = true;
        self.sweep(x, Some(&dx));
        let alpha = self.max_step(x, &dx);
        self.relative = false;
        if alpha < 1.0 {
            return Err(format!(
                "a deforming obstacle moves into the cloth within the step to t = {t_next} s (the carried start \
                 allows {alpha:.3} of the motion): shorten the step"
            ));
        }
        for (p, d) in x.iter_mut().zip(&dx) {
            *p += d;
        }
        Ok(())
    }

    /// The displacement over the step of the deforming obstacle's point `p` of contact `c`
    /// (one of the vertices of its obstacle feature).
    fn deforming_shift(&self, c: &Contact, p: &Pt3) -> Vec3 {
        let Some(Placed::Core(core)) = self.placed.get(c.obstacle as usize) else { return Vec3::zeros() };
        for f in [c.key.0, c.key.1] {
            let ids: Vec<u32> = match f {
                set::Feat::OP(_, i) => vec![i],
                set::Feat::OE(_, i) => core.edges[i as usize].to_vec(),
                set::Feat::OT(_, i) => core.tris[i as usize].to_vec(),
                _ => continue,
            };
            return core.shift_of(&ids, p);
        }
        Vec3::zeros()
    }

    /// Coulomb friction μ of placed obstacle `o` (rigid ones first, then deforming ones).
    fn obstacle_friction(&self, o: usize) -> f64 {
        match self.obstacles.get(o) {
            Some(ob) => ob.friction,
            None => self.deforming[o - self.obstacles.len()].0.friction,
        }
    }

    /// Finds, with one broad phase, every pair that may come within d̂ anywhere on the straight
    /// motion x → x + dx (at x when `dx` is `None`): the candidates that [`Ipc::contacts`] and
    /// [`Ipc::max_step`] then test for any configuration on that segment. One sweep per Newton
    /// iteration serves the CCD bound, every line-search trial and the next iteration's contact
    /// set (the accepted iterate lies on the segment).
    pub(crate) fn sweep(&mut self, x: &[Pt3], dx: Option<&[Vec3]>) {
        let topo = Topo { tris: &self.tris, edges: &self.edges, mean_edge: self.mean_edge, mu_self: self.mu_self };
        let (mut vt, mut ee) = if self.self_collision {
            let (vb, eb, tb) = set::boxes(x, dx, &self.tris, &self.edges, 0.5 * self.dhat);
            set::self_candidates(&mut self.bp, &topo, &vb, &eb, &tb)
        } else {
            (Vec::new(), Vec::new())
        };
        // Keep only pairs that can come within d̂ on the segment: the distance at x minus the
        // most the pair can approach (the largest displacement of each side) — boxes of a flat
        // grid overlap far more pairs than are close (a diagonal's box covers its neighbours).
        let moved = |i: u32| dx.map_or(0.0, |d| d[i as usize].norm());
        let side = |ids: &[u32]| ids.iter().map(|&i| moved(i)).fold(0.0, f64::max);
        let dhat = self.dhat;
        let (tris, edges) = (&self.tris, &self.edges);
        vt = vt
            .into_par_iter()
            .with_min_len(1024)
            .filter(|&(v, t)| {
                let tri = tris[t as usize];
                let d = pt_d2(&[x[v as usize], x[tri[0] as usize], x[tri[1] as usize], x[tri[2] as usize]]).sqrt();
                d - moved(v) - side(&tri) < dhat
            })
            .collect();
        ee = ee
            .into_par_iter()
            .with_min_len(1024)
            .filter(|&(e, f)| {
                let (a, b) = (edges[e as usize], edges[f as usize]);
                let d = ee_d2(&[x[a[0] as usize], x[a[1] as usize], x[b[0] as usize], x[b[1] as usize]]).sqrt();
                d - side(&a) - side(&b) < dhat
            })
            .collect();
        let obs = if self.placed.iter().any(|p| matches!(p, Placed::Core(_))) {
            let (vb, eb, tb) = set::boxes(x, dx, &self.tris, &self.edges, self.dhat);
            self.placed
                .iter()
                .map(|p| match p {
                    Placed::Core(c) => set::core_candidates(&topo, c, &vb, &eb, &tb),
                    Placed::Half { .. } => set::CoreCands::default(),
                })
                .collect()
        } else {
            vec![set::CoreCands::default(); self.placed.len()]
        };
        self.cands = Some(Cands { vt, ee, obs });
    }

    /// The contact set at `x` (pairs closer than d̂), sorted by key, from the candidates of
    /// the last [`Ipc::sweep`] (whose segment must contain `x`).
    pub(crate) fn contacts(&self, x: &[Pt3]) -> Vec<Contact> {
        self.contacts_within(x, self.dhat)
    }

    /// The pairs of the last sweep's candidates closer than `dist` at `x` (the contact set for
    /// `dist` = d̂; a larger `dist` gives the pairs likely to become contacts soon, which
    /// `ShellSim::grow_pattern` reserves in the sparsity pattern).
    pub(crate) fn contacts_within(&self, x: &[Pt3], dist: f64) -> Vec<Contact> {
        let dhat = dist;
        let topo = Topo { tris: &self.tris, edges: &self.edges, mean_edge: self.mean_edge, mu_self: self.mu_self };
        let Some(c) = self.cands.as_ref() else { return Vec::new() };
        let mut all = if self.self_collision { set::self_contacts(&topo, x, &c.vt, &c.ee, dhat) } else { Vec::new() };
        for (o, (p, oc)) in self.placed.iter().zip(&c.obs).enumerate() {
            all.extend(set::obstacle_contacts(&topo, x, o as u32, p, oc, self.obstacle_friction(o), dhat));
        }
        set::dedup(all)
    }

    /// Barrier and friction energy at `x` (J): κΣb(d) + ΣD; +∞ if a gap is ≤ 0.
    pub(crate) fn energy(&self, x: &[Pt3]) -> f64 {
        let c = self.contacts(x);
        let (kappa, dhat) = (self.kappa, self.dhat);
        let b: f64 = c.iter().map(|c| kappa * barrier::value(c.gap(x).d, dhat)).sum();
        let f: f64 = self.friction.iter().map(|f| f.energy(x, &self.x0, self.eps)).sum();
        b + f
    }

    /// Adds the contact forces −∇(κΣb + ΣD) at `x` to `force` and the Hessian blocks times
    /// `scale` through `block(i, j, m)` (global vertex ids; i == j for diagonal blocks, both
    /// (i, j) and (j, i) for off-diagonal ones). Off-diagonal blocks of vertex pairs that
    /// `in_pattern` rejects are lumped onto the two diagonals in the same direction: for the
    /// rank-one barrier block B = g_a g_bᵀ, c²g_a g_aᵀ and g_b g_bᵀ/c² with c² = |g_b|/|g_a|
    /// (then [[c²g_a g_aᵀ, −B], [−Bᵀ, g_b g_bᵀ/c²]] = vvᵀ ⪰ 0); for a friction block w_a w_b S
    /// (S ⪰ 0), |w_a w_b| S on both. The lumped matrix is ⪰ the exact one and stiffer only along
    /// the contact's own directions (normal, resp. tangent plane). Returns the smallest gap (m).
    pub(crate) fn add(
        &self,
        x: &[Pt3],
        contacts: &[Contact],
        force: &mut [Vec3],
        scale: f64,
        in_pattern: impl Fn(u32, u32) -> bool,
        mut block: impl FnMut(u32, u32, Mat3),
    ) -> f64 {
        let (kappa, dhat) = (self.kappa, self.dhat);
        let evals: Vec<(f64, f64, f64, nalgebra::SVector<f64, 12>)> = contacts
            .par_iter()
            .with_min_len(256)
            .map(|c| {
                let g = c.gap(x);
                (g.d, kappa * barrier::first(g.d, dhat), kappa * barrier::second(g.d, dhat), g.grad)
            })
            .collect();
        let mut min_gap = f64::INFINITY;
        for (c, (d, db, ddb, g)) in contacts.iter().zip(&evals) {
            min_gap = min_gap.min(*d);
            let gv = |k: usize| Vec3::new(g[3 * k], g[3 * k + 1], g[3 * k + 2]);
            let slots: [u32; 4] = c.nodes.map(|n| if let Node::Cloth(i) = n { i } else { NONE });
            for (k, &i) in slots.iter().enumerate() {
                if i != NONE {
                    force[i as usize] -= *db * gv(k);
                }
            }
            // Gauss–Newton: κ b″(d) ∇d ∇dᵀ (PSD since b is convex on (0, d̂)).
            let w = scale * *ddb;
            for a in 0..4 {
                if slots[a] == NONE {
                    continue;
                }
                let ga = gv(a);
                block(slots[a], slots[a], w * ga * ga.transpose());
                for b in a + 1..4 {
                    if slots[b] == NONE {
                        continue;
                    }
                    let gb = gv(b);
                    if in_pattern(slots[a], slots[b]) {
                        let m = w * ga * gb.transpose();
                        block(slots[a], slots[b], m);
                        block(slots[b], slots[a], m.transpose());
                    } else {
                        let (na, nb) = (ga.norm(), gb.norm());
                        if na > 0.0 && nb > 0.0 {
                            block(slots[a], slots[a], (w * nb / na) * ga * ga.transpose());
                            block(slots[b], slots[b], (w * na / nb) * gb * gb.transpose());
                        }
                    }
                }
            }
        }
        for f in &self.friction {
            f.add(x, &self.x0, self.eps, force, &in_pattern, |i, j, m| block(i, j, m * scale));
        }
        min_gap
    }

    /// The largest α ∈ (0, 1] such that the straight motion x → x + α·dx keeps every gap above
    /// [`CCD_KEEP`] of its value (additive CCD over the candidates of the last
    /// [`Ipc::sweep`], which must have been of this very segment).
    pub(crate) fn max_step(&self, x: &[Pt3], dx: &[Vec3]) -> f64 {
        let Some(c) = self.cands.as_ref() else { return 1.0 };
        let (tris, edges) = (&self.tris, &self.edges);
        let floor = GAP_FLOOR * self.dhat;
        let a_vt =
            c.vt.par_iter()
                .with_min_len(512)
                .map(|&(v, t)| {
                    let tri = tris[t as usize];
                    let ids = [v, tri[0], tri[1], tri[2]];
                    toi4(&ids.map(|i| x[i as usize]), &ids.map(|i| dx[i as usize]), 1, pt_d2, 0.0, floor)
                })
                .reduce(|| 1.0, f64::min);
        let a_ee =
            c.ee.par_iter()
                .with_min_len(512)
                .map(|&(e, f)| {
                    let (a, b) = (edges[e as usize], edges[f as usize]);
                    let ids = [a[0], a[1], b[0], b[1]];
                    toi4(&ids.map(|i| x[i as usize]), &ids.map(|i| dx[i as usize]), 2, ee_d2, 0.0, floor)
                })
                .reduce(|| 1.0, f64::min);
        let mut alpha = a_vt.min(a_ee);
        for (p, oc) in self.placed.iter().zip(&c.obs) {
            alpha = alpha.min(obstacle_toi(p, oc, x, dx, tris, edges, floor, self.relative));
        }
        alpha
    }

    /// Doubles κ (up to 10⁶ times its start) when the smallest gap fell below 1 % of d̂;
    /// returns whether it did.
    pub(crate) fn adapt_kappa(&mut self, min_gap: f64) -> bool {
        if min_gap < 0.01 * self.dhat && self.kappa < self.kappa_max {
            self.kappa *= 2.0;
            return true;
        }
        false
    }
}

fn pt_d2(y: &[Pt3; 4]) -> f64 {
    let (c, _) = geom_core::query::closest_point_triangle(&y[0], &[y[1], y[2], y[3]]);
    (y[0] - c).norm_squared()
}

fn ee_d2(y: &[Pt3; 4]) -> f64 {
    let (_, _, a, b) = geom_core::query::closest_points_segments(&y[0], &y[1], &y[2], &y[3]);
    (a - b).norm_squared()
}

/// TOI of a 4-point pair as a step fraction (1 when no impact); `floor` the absolute gap floor.
fn toi4(x: &[Pt3; 4], dx: &[Vec3; 4], split: usize, d2: fn(&[Pt3; 4]) -> f64, xi: f64, floor: f64) -> f64 {
    accd::time_of_impact(x, dx, split, d2, xi, CCD_KEEP, floor, 1.0).unwrap_or(1.0)
}

/// Step bound from one placed obstacle (fixed during the step's Newton iterations; with
/// `relative`, a deforming mesh moves from its step-start to its end positions together with
/// the cloth: additive CCD of the relative motion).
#[allow(clippy::too_many_arguments)]
fn obstacle_toi(
    p: &Placed,
    c: &set::CoreCands,
    x: &[Pt3],
    dx: &[Vec3],
    tris: &[[u32; 3]],
    edges: &[[u32; 2]],
    floor: f64,
    relative: bool,
) -> f64 {
    match p {
        Placed::Half { normal, offset } => x
            .par_iter()
            .zip(dx)
            .with_min_len(1024)
            .map(|(q, d)| {
                let g0 = normal.dot(&q.coords) - offset;
                let rate = normal.dot(d);
                let target = (CCD_KEEP * g0).max(floor);
                if rate >= 0.0 {
                    1.0
                } else if g0 > target {
                    ((g0 - target) / -rate).min(1.0)
                } else {
                    0.0
                }
            })
            .reduce(|| 1.0, f64::min),
        Placed::Core(core) => {
            let z = Vec3::zeros();
            let moving = relative && !core.disp.is_empty();
            // The obstacle's points at the motion's start and their displacements.
            let pt =
                |i: u32| if moving { core.points[i as usize] - core.disp[i as usize] } else { core.points[i as usize] };
            let od = |i: u32| if moving { core.disp[i as usize] } else { z };
            let mut alpha: f64 = 1.0;
            for &(v, t) in &c.v_ot {
                let (v, ot) = (v as usize, core.tris[t as usize]);
                let y = [x[v], pt(ot[0]), pt(ot[1]), pt(ot[2])];
                alpha = alpha.min(toi4(&y, &[dx[v], od(ot[0]), od(ot[1]), od(ot[2])], 1, pt_d2, core.xi, floor));
            }
            for &(e, f) in &c.e_oe {
                let (a, ob) = (edges[e as usize], core.edges[f as usize]);
                let y = [x[a[0] as usize], x[a[1] as usize], pt(ob[0]), pt(ob[1])];
                let d = [dx[a[0] as usize], dx[a[1] as usize], od(ob[0]), od(ob[1])];
                alpha = alpha.min(toi4(&y, &d, 2, ee_d2, core.xi, floor));
            }
            for &(v, q) in &c.v_op {
                let v = v as usize;
                let pp = |y: &[Pt3; 2]| (y[0] - y[1]).norm_squared();
                let t = accd::time_of_impact(&[x[v], pt(q)], &[dx[v], od(q)], 1, pp, core.xi, CCD_KEEP, floor, 1.0);
                alpha = alpha.min(t.unwrap_or(1.0));
            }
            for &(t, q) in &c.t_op {
                let tri = tris[t as usize];
                let y = [pt(q), x[tri[0] as usize], x[tri[1] as usize], x[tri[2] as usize]];
                let d = [od(q), dx[tri[0] as usize], dx[tri[1] as usize], dx[tri[2] as usize]];
                alpha = alpha.min(toi4(&y, &d, 1, pt_d2, core.xi, floor));
            }
            alpha
        }
    }
}

/// Candidate pairs of one sweep.
struct Cands {
    vt: Vec<(u32, u32)>,
    ee: Vec<(u32, u32)>,
    obs: Vec<set::CoreCands>,
}

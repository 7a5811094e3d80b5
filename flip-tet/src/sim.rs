//! [`FlipTetSim`]: the adaptive FLIP time loop of spec §3.1 on the graded BCC mesh, with
//! CFL time-step control (§3.13), remeshing with split/merge (§3.2, §3.10), per-stage timings and
//! step statistics.

use std::time::Instant;

use geom_core::math::{Pt3, Vec3};
use geom_core::mesh::TriMesh;
use geom_core::rng::Rng;
use geom_core::NONE;
use rayon::prelude::*;

use crate::advect::{advect, g2p, AdvectMesh, TetField};
use crate::bcc::{tetrahedralize, TetMesh};
use crate::error::{Result, SimError};
use crate::inflow::EmitterState;
use crate::obstacle::Obstacles;
use crate::octree::{balance_2to1, build_octree, Octree, OctreeSpec, SizeDemand};
use crate::particles::{apply_obstacles, apply_walls, classify_ballistic, position_correction, Particles};
use crate::pressure::{add_solid_flux, apply_pressure, assemble_pressure, PressureSolver, SolveReport, W_MIN};
use crate::scene::{BoxFace, DtPolicy, Scene, Shape, TimeIntegration};
use crate::sizing::{Sizing, SizingContext, SurfaceCurvature, C_H};
use crate::split_merge::{split_merge, OldLevelSet};
use crate::surface::{level_set_on_nodes, level_set_on_nodes_sign_inside, liquid_volume, Walls};
use crate::transfer::{blend_weak, extrapolate, node_average, particles_to_tets, sample};

/// Liquid density used for the energies (kg/m³).
pub const RHO: f64 = 1000.0;

/// Seconds spent per phase of one step (spec §3.1 list).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PhaseTimings {
    /// Ballistic classification and neighbour tree.
    pub ballistic: f64,
    /// Level set on nodes (simulation surface).
    pub levelset: f64,
    /// Sizing, octree, tetrahedralisation, split/merge (remesh steps only).
    pub remesh: f64,
    /// P2G.
    pub p2g: f64,
    /// Extrapolations and nodal averages.
    pub extrapolate: f64,
    /// Pressure assembly.
    pub assemble: f64,
    /// Linear solve.
    pub solve: f64,
    /// Velocity update.
    pub apply: f64,
    /// G2P.
    pub g2p: f64,
    /// Advection, walls, obstacles.
    pub advect: f64,
    /// Position correction.
    pub correction: f64,
}

impl PhaseTimings {
    /// The issue's five stages: (remesh, transfer, solve, advect, surface) in seconds.
    pub fn stages(&self) -> [f64; 5] {
        [
            self.remesh,
            self.p2g + self.extrapolate + self.g2p,
            self.assemble + self.solve + self.apply,
            self.advect + self.correction + self.ballistic,
            self.levelset,
        ]
    }

    /// Total seconds.
    pub fn total(&self) -> f64 {
        self.stages().iter().sum()
    }
}

/// Statistics of one step (spec §2).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct StepStats {
    /// Step counter (0-based, before increment).
    pub step: u64,
    /// Time at the end of the step (s).
    pub t: f64,
    /// Step size (s).
    pub dt: f64,
    /// Whether the remesh stage ran in this step (every `remesh_interval` steps; the mesh itself
    /// is kept when it cannot change, see `remesh`).
    pub remeshed: bool,
    /// Whether the particle budget (`particles.max_particles`) stopped splitting at this step's
    /// remesh (spec §3.10; with `budget_is_error` the step returns an error instead).
    pub budget_hit: bool,
    /// Whether the step ended on a frame boundary.
    pub frame_end: bool,
    /// Particles.
    pub n_particles: usize,
    /// Ballistic particles.
    pub n_ballistic: usize,
    /// Splits at this step's remesh.
    pub n_split: usize,
    /// Merges at this step's remesh.
    pub n_merge: usize,
    /// Particles deleted at open faces.
    pub n_deleted: usize,
    /// Mesh nodes.
    pub n_nodes: usize,
    /// Mesh tets.
    pub n_tets: usize,
    /// Pressure DOFs.
    pub n_dofs: usize,
    /// Interface tets.
    pub n_ghost_tets: usize,
    /// Interface tets with `k_t < 1`.
    pub n_k_reduced: usize,
    /// Tets whose weakly covered P2G velocity was blended with the extrapolated one (spec §3.7,
    /// §8 H-COARSE-LANDING).
    pub n_weak_blend: usize,
    /// Solver report.
    pub solver: SolveReport,
    /// `Σ (2r)³` (m³).
    pub vol_particles: f64,
    /// Liquid volume of the node level set (m³).
    pub vol_levelset: f64,
    /// Kinetic energy (J, ρ = 1000).
    pub kinetic_energy: f64,
    /// Potential energy `Σ ρ V (−g·x)` (J).
    pub potential_energy: f64,
    /// Largest particle speed (m/s).
    pub max_speed: f64,
    /// Advection substeps beyond one (sum over particles).
    pub cfl_substeps: u32,
    /// Per-phase seconds.
    pub timings: PhaseTimings,
}

/// The simulator (spec §2).
pub struct FlipTetSim {
    scene: Scene,
    spec: OctreeSpec,
    sizing: Sizing,
    /// The obstacle-metric demands ([`Self::obstacle_demands`]): the obstacles are static and
    /// those metrics read only the solid SDF and the level sizes, so they are sampled once.
    obstacle_demands: Vec<SizeDemand>,
    /// Every obstacle (static, mesh, moving), placed at the current time.
    obstacles: Obstacles,
    /// The obstacles' union SDF at the mesh nodes (m; empty without obstacles).
    node_sdf: Vec<f64>,
    /// Inflow emitters (issue 26).
    emitters: Vec<EmitterState>,
    /// Volume of the particles deleted by the outflow regions (m³), also counted in
    /// `deleted_volume`.
    pub outflow_volume: f64,
    octree: Octree,
    mesh: TetMesh,
    h_tet: Vec<f64>,
    edges: geom_core::graph::Ragged<u32>,
    parts: Particles,
    phi: Vec<f64>,
    nodal_u: Vec<Vec3>,
    /// Post-projection tet velocities `u_new` of the last step (after extrapolation).
    tet_u: Vec<Vec3>,
    solver: PressureSolver,
    warm: Option<(Vec<u32>, Vec<f64>)>,
    /// Gauge pressure of the last projection at the mesh nodes (Pa; 0 at air and solid nodes):
    /// `p = ρ q / Δt_kick` from the solve's `q = Δt_kick p / ρ`.
    pressure: Vec<f64>,
    step: u64,
    time: f64,
    frame: u64,
    rng: Rng,
    open: [bool; 6],
    /// Largest initial liquid height above the domain floor (m), for `U_ref` of the turbulence metric.
    h_ref: f64,
    /// Volume of deleted particles (m³).
    pub deleted_volume: f64,
    /// Particle budget hit at the last remesh.
    pub budget_hit: bool,
    /// Length of the previous step (s; 0 before the first): the leapfrog kick spans
    /// `(prev_dt + Δt) / 2`.
    prev_dt: f64,
}

fn face_index(f: BoxFace) -> usize {
    match f {
        BoxFace::NegX => 0,
        BoxFace::PosX => 1,
        BoxFace::NegY => 2,
        BoxFace::PosY => 3,
        BoxFace::NegZ => 4,
        BoxFace::PosZ => 5,
    }
}

/// Samples every leaf inside the liquid with 2×2×2 particles of radius `h_leaf/4` at the sub-cube
/// centres (spec S1a), jittered by `jitter · 2r`, shifted by `lattice_offset · 2r` (spec S1b);
/// optional standing-wave column stretching.
fn sample_particles(scene: &Scene, obstacles: &Obstacles, oct: &Octree, rng: &mut Rng) -> Particles {
    let mut p = Particles::default();
    let jit = scene.particles.sampling_jitter;
    let off = Vec3::from(scene.particles.lattice_offset);
    for lf in &oct.leaves {
        let h = oct.spec.h(lf.level);
        let o = oct.spec.position(&lf.origin.0);
        let r = h / 4.0;
        for c in 0..8 {
            let mut x = o + Vec3::new(
                (0.5 + (c & 1) as f64) * h / 2.0,
                (0.5 + ((c >> 1) & 1) as f64) * h / 2.0,
                (0.5 + ((c >> 2) & 1) as f64) * h / 2.0,
            );
            if jit > 0.0 {
                x += Vec3::new(rng.range(-1.0, 1.0), rng.range(-1.0, 1.0), rng.range(-1.0, 1.0)) * (jit * r);
            }
            let d = scene.liquid_sdf(&x);
            // The shift (zero by default: `x + 0 = x` bitwise for every non-(−0) coordinate) moves
            // the kept particle; membership, velocity and φ_p are those of the unshifted point.
            let xs = x + off * (2.0 * r);
            if d < 0.0 && obstacles.sdf(&xs) > r {
                p.push(xs, scene.velocity_at(&x), r, scene.initial_phi(&x));
            }
        }
    }
    if scene.particles.column_top_on_surface {
        if let Some(Shape::CosineSurface { mean, amplitude, length, x0 }) = scene.liquid.first() {
            // Column = same (x, z); stretch each column evenly so that its top particle sits at
            // η(x) − r and its bottom particle stays where it is (spec S3 column sampling).
            let mut cols: std::collections::HashMap<(i64, i64), Vec<usize>> = std::collections::HashMap::new();
            let q = oct.spec.unit() * 1e-3;
            for i in 0..p.len() {
                let key = ((p.x[i].x / q).round() as i64, (p.x[i].z / q).round() as i64);
                cols.entry(key).or_default().push(i);
            }
            let mut keys: Vec<(i64, i64)> = cols.keys().copied().collect();
            keys.sort_unstable();
            for key in keys {
                let ids = &cols[&key];
                let (mut lo, mut hi) = (ids[0], ids[0]);
                for &i in ids {
                    if p.x[i].y < p.x[lo].y {
                        lo = i;
                    }
                    if p.x[i].y > p.x[hi].y {
                        hi = i;
                    }
                }
                let eta = mean + amplitude * (std::f64::consts::PI * (p.x[hi].x - x0) / length).cos();
                let (y0, y1) = (p.x[lo].y, p.x[hi].y);
                let target = eta - p.r[hi];
                for &i in ids {
                    if y1 > y0 {
                        p.x[i].y = y0 + (p.x[i].y - y0) * (target - y0) / (y1 - y0);
                    } else {
                        p.x[i].y = target;
                    }
                    p.phi[i] = p.x[i].y - eta;
                }
            }
        }
    }
    p
}

/// One-layer redistancing of the liquid side from the exact outside values (ours, see README
/// "Deviations"): for every liquid node `i` with an edge to a node `g` with `φ_g ≥ 0`,
/// `φ_i ← min(φ_i, max_g (φ_g − |x_i − x_g|))`.
///
/// Why: inside a union of hulls the minimum of the component distances only bounds the true
/// signed distance from above (it is too shallow, e.g. −0.52 r instead of −2 r one half cube
/// below a flat particle surface), while the 1-Lipschitz bound `φ_g − |x_i − x_g|` from the exact
/// outside values bounds it from below and is exact whenever a neighbour lies along the surface
/// normal (every flat horizontal surface on the BCC lattice). The ghost-fluid fractions
/// `s_g = φ_g / φ̃` of §3.5 need the liquid-side values, so without this the resting pool is not an
/// equilibrium.
pub fn redistance_first_layer(nodes: &[Pt3], edges: &geom_core::graph::Ragged<u32>, phi: &mut [f64]) {
    let upd: Vec<Option<f64>> = (0..phi.len())
        .into_par_iter()
        .map(|i| {
            if phi[i] >= 0.0 {
                return None;
            }
            let mut best = f64::NEG_INFINITY;
            for &g in edges.row(i) {
                let g = g as usize;
                if phi[g] >= 0.0 {
                    best = best.max(phi[g] - (nodes[i] - nodes[g]).norm());
                }
            }
            (best > f64::NEG_INFINITY && best < phi[i]).then_some(best)
        })
        .collect();
    for (i, u) in upd.into_iter().enumerate() {
        if let Some(v) = u {
            phi[i] = v;
        }
    }
}

/// Liquid-side redistancing of every liquid node below the first layer (ours, see README
/// "Deviations"): multi-source Dijkstra along mesh edges from the first-layer liquid nodes (those
/// with an edge to a node with `φ ≥ 0`), seeded with their `|φ|`; every other liquid node gets
/// `φ_i = −(shortest seed value + edge path length)`. Nodes with `φ ≥ 0` are untouched.
///
/// Why: the node level set inside the liquid is the union-of-balls value with interior radii
/// `r_temp = max(r, −k φ_p)`, and `φ_p` is read back from these node values every step. Inside the
/// union the value only bounds the depth from above, and the spec's redistancing (§3.11.3) only
/// replaces values `≤ −band`, which a 12 r band never reaches in shallow scenes: the stored depth
/// then shrinks by about `k` per step (measured in the standing wave: `φ_p / depth` fell from 0.56
/// to 0.03 in four steps), `r_temp` falls back to `r`, lattice nodes (at `√3 r` from their nearest
/// particles) become holes with `φ > 0` inside the liquid, and those spurious free surfaces let the
/// liquid fall into them (kinetic energy ×20 within five steps). The edge-path distance overestimates
/// the Euclidean depth by at most ≈ 24 % on the BCC lattice, so `k · 1.24 < 1` keeps the interior
/// spheres below the surface (spec §3.11.3 argument).
pub fn redistance_interior(nodes: &[Pt3], edges: &geom_core::graph::Ragged<u32>, phi: &mut [f64]) {
    use std::cmp::Reverse;
    use std::collections::BinaryHeap;
    let n = phi.len();
    let mut dist = vec![f64::INFINITY; n];
    let mut heap = BinaryHeap::new();
    for i in 0..n {
        if phi[i] < 0.0 && edges.row(i).iter().any(|&g| phi[g as usize] >= 0.0) {
            dist[i] = -phi[i];
            // Non-negative f64 bit patterns order like the values: a total, deterministic key.
            heap.push(Reverse((dist[i].to_bits(), i as u32)));
        }
    }
    while let Some(Reverse((bits, i))) = heap.pop() {
        let (d, i) = (f64::from_bits(bits), i as usize);
        if d > dist[i] {
            continue;
        }
        for &j in edges.row(i) {
            let j = j as usize;
            if phi[j] >= 0.0 {
                continue;
            }
            let nd = d + (nodes[i] - nodes[j]).norm();
            if nd < dist[j] {
                dist[j] = nd;
                heap.push(Reverse((nd.to_bits(), j as u32)));
            }
        }
    }
    for i in 0..n {
        if phi[i] < 0.0 && dist[i].is_finite() {
            phi[i] = -dist[i];
        }
    }
}

/// Smoothed gradient of the node level set at the nodes (ours, see README "Deviations"): the
/// volume-weighted mean of the per-tet P1 gradients `Σ_a φ_a ∇λ_a` over the tets incident to
/// each node.
///
/// Why: the position correction keeps only the tangential part of a near-surface particle's
/// displacement (spec §3.9), which needs a good surface normal. The raw P1 gradient of the
/// triplet-hull level set in the single tet holding the particle is noisy next to walls (measured
/// in the standing wave: normals tilted by up to 35° under a flat surface); with a tilted normal the
/// overlap relief between vertically compressed particles keeps a vertical part and lifts the
/// surface layer by ≈ 0.1 r per step, which pinned the wall crest (period error 6.7 % → 0.6 %
/// with the correction off). Averaging over the one-ring and interpolating is exact for linear φ
/// and removes the per-tet noise. At nodes on the closed walls of `wall_mask` (bit `2a + side` as in
/// `TetMesh::node_boundary`) the wall-normal component is removed: the level set mirrors the
/// particles there (spec §3.11.3), so `∂φ/∂n = 0` on the wall, and the one-sided average would
/// otherwise tilt the normal of the wall columns.
pub fn nodal_phi_gradient(mesh: &TetMesh, phi: &[f64], wall_mask: u8) -> Vec<Vec3> {
    (0..mesh.nodes.len())
        .into_par_iter()
        .map(|i| {
            crate::transfer::ring_average(mesh, i, wall_mask, |t| {
                let tv = mesh.tets[t];
                Some((0..4).fold(Vec3::zeros(), |acc, a| acc + mesh.grad_bary[t][a] * phi[tv[a] as usize]))
            })
            .unwrap_or_else(Vec3::zeros)
        })
        .collect()
}

impl FlipTetSim {
    /// Builds the simulator: validates the scene, finds the initial octree as a fixed point of
    /// "octree → lattice particles → particle demands → octree" (spec S1a), samples particles
    /// and builds the mesh.
    pub fn new(scene: &Scene) -> Result<Self> {
        scene.validate()?;
        let spec = OctreeSpec::new(scene.min(), scene.max(), scene.resolution.coarsest, scene.resolution.finest)?;
        let sizing = Sizing::from_params(&scene.sizing).map_err(|e| SimError::InvalidScene(e.to_string()))?;
        let mut rng = Rng::new(scene.seed);
        let mut open = [false; 6];
        for f in &scene.open_faces {
            open[face_index(*f)] = true;
        }
        let obstacles = Obstacles::new(scene)?;
        let obstacle_demands = {
            // The obstacle metrics are sampled once: from the static obstacles only.
            let mut ctx = SizingContext::new(spec.h_min(), spec.h_root);
            let solid = |x: &Pt3| obstacles.static_sdf(x);
            if !scene.obstacles.is_empty() {
                ctx.solid_sdf = Some(&solid);
            }
            Self::obstacle_demands(scene, &spec, &sizing, &ctx)
        };
        let mut octree = Octree::uniform(spec, 0);
        let mut parts = sample_particles(scene, &obstacles, &octree, &mut rng.clone());
        if spec.levels > 1 {
            for _ in 0..12 {
                // Curvature sizing needs a surface at t = 0: the analytic liquid SDF on the current mesh.
                let curv = if sizing.needs_surface() {
                    tetrahedralize(&octree).ok().and_then(|m| {
                        let phi: Vec<f64> = m.nodes.iter().map(|x| scene.liquid_sdf(x)).collect();
                        let tri = crate::surface::marching_tets(&m, &phi).ok()?;
                        if tri.faces.is_empty() {
                            return None;
                        }
                        let sm = crate::surface::smooth_surface(&tri, scene.surface.smoothing_iterations);
                        let k = crate::surface::vertex_curvature(&sm, 1.0 / (2.0 * spec.h_min() / C_H));
                        Some(SurfaceCurvature::new(&sm, k))
                    })
                } else {
                    None
                };
                let mut ctx = SizingContext::new(spec.h_min(), spec.h_root);
                ctx.surface = curv.as_ref();
                let solid = |x: &Pt3| obstacles.sdf(x);
                if !obstacles.is_empty() {
                    ctx.solid_sdf = Some(&solid);
                }
                let mut demands =
                    Self::demands_static(scene, &spec, &sizing, &parts, scene.flip.dt_max, Some(&ctx), None);
                demands.extend_from_slice(&obstacle_demands);
                demands.extend(Self::moving_obstacle_demands(&obstacles, scene, &spec));
                let mut next = build_octree(spec, &demands);
                if scene.extra_grading_layers > 0 {
                    balance_2to1(&mut next, scene.extra_grading_layers);
                }
                let same = next.leaves == octree.leaves;
                octree = next;
                parts = sample_particles(scene, &obstacles, &octree, &mut rng.clone());
                if same {
                    break;
                }
            }
        }
        let _ = rng.next_u64();
        let h_ref = parts.x.iter().zip(&parts.r).map(|(x, r)| x.y + r - scene.domain.min[1]).fold(0.0, f64::max);
        let mut sim = Self {
            scene: scene.clone(),
            spec,
            sizing,
            obstacle_demands,
            emitters: scene
                .emitters
                .iter()
                .enumerate()
                .map(|(k, e)| EmitterState::new(e, spec.h_min() / C_H, scene.seed ^ (k as u64 + 1)))
                .collect(),
            obstacles,
            node_sdf: Vec::new(),
            outflow_volume: 0.0,
            octree: octree.clone(),
            mesh: TetMesh::default(),
            h_tet: Vec::new(),
            edges: geom_core::graph::Ragged::new(),
            parts,
            phi: Vec::new(),
            nodal_u: Vec::new(),
            tet_u: Vec::new(),
            solver: PressureSolver::default(),
            warm: None,
            pressure: Vec::new(),
            step: 0,
            time: 0.0,
            frame: 0,
            rng,
            open,
            h_ref,
            deleted_volume: 0.0,
            budget_hit: false,
            prev_dt: 0.0,
        };
        sim.set_mesh(octree)?;
        sim.relocate();
        sim.phi = sim.level_set();
        Ok(sim)
    }

    fn set_mesh(&mut self, oct: Octree) -> Result<()> {
        let mut mesh = tetrahedralize(&oct)?;
        if !self.obstacles.is_empty() {
            self.node_sdf = self.obstacles.node_sdf(&mesh);
            mesh.solid_frac = Some(Obstacles::fluid_fractions_from(&mesh, &self.node_sdf));
        }
        self.h_tet = mesh.tet_level.iter().map(|&l| self.spec.h(l)).collect();
        self.nodal_u = vec![Vec3::zeros(); mesh.nodes.len()];
        self.tet_u = vec![Vec3::zeros(); mesh.tets.len()];
        self.pressure = vec![0.0; mesh.nodes.len()];
        // Same rows as `surface::node_edges` (tested in tests/mesh.rs), cached by the mesh.
        self.edges = mesh.node_nbrs.clone();
        self.mesh = mesh;
        self.octree = oct;
        Ok(())
    }

    /// One size demand per non-ballistic particle (spec §3.12); with `prev` (the octree being
    /// replaced) and `sizing.temporal_smoothing` each radius is limited to twice the radius of
    /// the particle's current leaf.
    fn demands_static(
        scene: &Scene,
        spec: &OctreeSpec,
        sizing: &Sizing,
        parts: &Particles,
        dt: f64,
        ctx_extra: Option<&SizingContext>,
        prev: Option<&Octree>,
    ) -> Vec<SizeDemand> {
        let base = SizingContext::new(spec.h_min(), spec.h_root);
        let ctx = ctx_extra.copied().unwrap_or(base);
        let (r_min, r_max) = (spec.h_min() / C_H, spec.h_root / C_H);
        let prev = prev.filter(|_| scene.sizing.temporal_smoothing);
        (0..parts.len())
            .into_par_iter()
            .filter(|&i| !parts.is_ballistic(i))
            .map(|i| {
                let mut s = sizing.radius_at_phi(&parts.x[i], Some(parts.phi[i]), &ctx);
                if let Some(o) = prev {
                    s = s.min(2.0 * o.leaf_h(o.leaf_at(&parts.x[i])) / C_H);
                }
                let s = s.clamp(r_min, r_max);
                let level = spec.level_for_size(C_H * s);
                let h = spec.h(level);
                let pad = (2.0 * h).max(f64::from(scene.flip.remesh_interval) * dt * parts.v[i].norm());
                SizeDemand { center: parts.x[i], pad, level }
            })
            .collect()
    }

    /// Obstacle-metric demands (spec §3.12: "obstacle metrics add demands sampled on a coarse
    /// grid of points"): the obstacle metrics ([`Sizing::obstacle_radius_at`], e.g. the solid
    /// curvature) evaluated at the centres of the finest cubes of the whole domain, so the mesh is
    /// graded around the obstacles (hole rims, S7) whether or not liquid is there yet. Each
    /// finite demand covers its sample cell: pad `2 h + (√3/2) h_min` for its level's edge `h`.
    /// Empty (no cost) unless an obstacle metric is on and the scene has obstacles.
    fn obstacle_demands(scene: &Scene, spec: &OctreeSpec, sizing: &Sizing, ctx: &SizingContext) -> Vec<SizeDemand> {
        if !sizing.has_obstacle_metric() || scene.obstacles.is_empty() || ctx.solid_sdf.is_none() {
            return Vec::new();
        }
        let (r_min, r_max) = (spec.h_min() / C_H, spec.h_root / C_H);
        let h_min = spec.h_min();
        let ext = scene.max() - scene.min();
        let n = [0, 1, 2].map(|a| (ext[a] / h_min).round().max(1.0) as usize);
        let cover = 0.5 * 3f64.sqrt() * h_min;
        (0..n[0] * n[1] * n[2])
            .into_par_iter()
            .filter_map(|k| {
                let (i, j, l) = (k % n[0], (k / n[0]) % n[1], k / (n[0] * n[1]));
                let x = scene.min() + Vec3::new(i as f64 + 0.5, j as f64 + 0.5, l as f64 + 0.5) * h_min;
                let r = sizing.obstacle_radius_at(&x, ctx);
                if !r.is_finite() {
                    return None;
                }
                let level = spec.level_for_size(C_H * r.clamp(r_min, r_max));
                (level > 0).then(|| SizeDemand { center: x, pad: 2.0 * spec.h(level) + cover, level })
            })
            .collect()
    }

    /// Finest-level demands along the surfaces of the moving obstacles (issue 26): every centre
    /// of a finest cube of the domain within `1.5 h_min` of a moving obstacle's surface asks
    /// for the finest level, so that a thin moving plate (a gate) is seen by the linear
    /// interpolant of its SDF wherever it is (in a coarse tet it vanishes and the liquid leaks
    /// through it). Sampled at every remesh from the obstacles' current placement; empty (no
    /// cost) without moving obstacles.
    fn moving_obstacle_demands(obstacles: &Obstacles, scene: &Scene, spec: &OctreeSpec) -> Vec<SizeDemand> {
        if !obstacles.any_moving() || spec.levels <= 1 {
            return Vec::new();
        }
        let h_min = spec.h_min();
        let ext = scene.max() - scene.min();
        let n = [0, 1, 2].map(|a| (ext[a] / h_min).round().max(1.0) as usize);
        let cover = 0.5 * 3f64.sqrt() * h_min;
        let level = spec.levels - 1;
        let moving: Vec<usize> = (0..obstacles.len()).filter(|&k| obstacles.is_moving(k)).collect();
        (0..n[0] * n[1] * n[2])
            .into_par_iter()
            .filter_map(|k| {
                let (i, j, l) = (k % n[0], (k / n[0]) % n[1], k / (n[0] * n[1]));
                let x = scene.min() + Vec3::new(i as f64 + 0.5, j as f64 + 0.5, l as f64 + 0.5) * h_min;
                let d = moving.iter().map(|&m| obstacles.sdf_of(m, &x).abs()).fold(f64::INFINITY, f64::min);
                (d <= 1.5 * h_min).then_some(SizeDemand { center: x, pad: 2.0 * h_min + cover, level })
            })
            .collect()
    }

    fn walls(&self) -> [bool; 6] {
        self.open.map(|o| !o)
    }

    fn level_set(&self) -> Vec<f64> {
        self.level_set_with(false)
    }

    /// The node level set; `exact_interior` evaluates every node (the reference the fast path is
    /// tested against).
    fn level_set_with(&self, exact_interior: bool) -> Vec<f64> {
        // Nodes inside the obstacles, and within the finest particle radius of their surface
        // (issue 26): the particles stop `r` short of an obstacle, so the particle level set puts
        // a free surface (φ ≈ 0) along a liquid–obstacle contact; those nodes take the mean φ of
        // their other neighbours instead, so the liquid sees a wall there, not a free surface.
        let r_min = self.spec.h_min() / C_H;
        let solid: Option<Vec<bool>> = self.mesh.solid_frac.as_ref().map(|w| {
            (0..self.mesh.nodes.len())
                .map(|i| {
                    self.node_sdf.get(i).is_some_and(|&d| d <= r_min)
                        || self.mesh.node_tets.row(i).iter().all(|&t| w[t as usize] < W_MIN)
                })
                .collect()
        });
        let walls = Walls {
            min: self.scene.min(),
            max: self.scene.max(),
            mirror: self.walls(),
            node_in_solid: solid.as_deref(),
        };
        // Deep liquid nodes only need their sign here: the two redistancing passes below
        // overwrite them (bitwise equal to `level_set_on_nodes`, test `fast_level_set_equals_exact_in_the_simulation`).
        let mut phi = if exact_interior {
            level_set_on_nodes(&self.mesh, &self.parts, &self.scene.surface, &walls)
        } else {
            level_set_on_nodes_sign_inside(&self.mesh, &self.parts, &self.scene.surface, &walls)
        };
        redistance_first_layer(&self.mesh.nodes, &self.edges, &mut phi);
        redistance_interior(&self.mesh.nodes, &self.edges, &mut phi);
        phi
    }

    /// Locates every particle (walking from its previous tet).
    fn relocate(&mut self) {
        let (mesh, oct) = (&self.mesh, &self.octree);
        self.parts.tet.par_iter_mut().zip(self.parts.x.par_iter()).for_each(|(t, x)| {
            *t = mesh.walk(oct, *t, x).map_or(NONE, |(tt, _)| tt);
        });
    }

    /// Stores each located particle's interpolated level set `φ_p` (0 for unlocated ones).
    fn store_particle_phi(&mut self) {
        let vals: Vec<f64> = (0..self.parts.len())
            .into_par_iter()
            .map(|i| {
                let t = self.parts.tet[i];
                if t == NONE {
                    0.0
                } else {
                    self.mesh.interpolate(t, &self.parts.x[i], &self.phi)
                }
            })
            .collect();
        self.parts.phi = vals;
    }

    fn choose_dt(&self) -> f64 {
        let f = &self.scene.flip;
        let mut dt = match f.dt_policy {
            DtPolicy::Fixed(dt) => dt,
            DtPolicy::Adaptive => {
                let m = (0..self.parts.len())
                    .into_par_iter()
                    .filter(|&i| !self.parts.is_ballistic(i) && self.parts.tet[i] != NONE)
                    .map(|i| self.h_tet[self.parts.tet[i] as usize] / (self.parts.v[i].norm() + 1e-12))
                    .reduce(|| f64::INFINITY, f64::min);
                (f.cfl * m).clamp(f.dt_min, f.dt_max)
            }
        };
        let next = (self.frame + 1) as f64 / self.scene.fps;
        if self.time + dt >= next - 1e-9 * dt || self.time + 1.5 * dt > next {
            let rem = next - self.time;
            dt = if self.time + dt >= next - 1e-9 * dt { rem } else { 0.5 * rem };
        }
        dt.max(1e-12)
    }

    /// Rebuilds the octree from the sizing demands, splits and merges particles against it and
    /// rebuilds the mesh, the particle locations and `φ`. A one-level spec (uniform mesh) has no
    /// octree to rebuild, and when the new octree has the same leaves and no particle was split
    /// or merged the mesh is kept: both used to rebuild an identical mesh (18 s per remesh at
    /// uniform 64). The particle locations and `φ` are redone either way, so that the results
    /// do not depend on the shortcut.
    fn remesh(&mut self, dt: f64) -> Result<(usize, usize)> {
        self.budget_hit = false;
        let (mut ns, mut nm) = (0, 0);
        if self.spec.levels > 1 {
            let oct = self.next_octree(dt);
            // Keep the old mesh's φ for the split/merge snap.
            if self.scene.particles.split_merge {
                (ns, nm) = self.split_merge(&oct)?;
            }
            if ns > 0 || nm > 0 || oct.leaves != self.octree.leaves {
                self.set_mesh(oct)?;
            }
        }
        // Locations from scratch (a particle on a shared face lands in the tet a rebuild gives)
        // and φ (its interior radii read the particle φ stored since step 2), kept mesh or not.
        self.relocate_from_scratch();
        self.phi = self.level_set();
        Ok((ns, nm))
    }

    /// The octree the sizing demands now (spec §3.12), balanced with the scene's extra layers.
    fn next_octree(&self, dt: f64) -> Octree {
        let needs_surface = self.sizing.needs_surface();
        let curv = if needs_surface {
            let tri = crate::surface::marching_tets(&self.mesh, &self.phi).ok();
            tri.map(|m| {
                let sm = crate::surface::smooth_surface(&m, self.scene.surface.smoothing_iterations);
                let k = crate::surface::vertex_curvature(&sm, 1.0 / (2.0 * self.spec.h_min() / C_H));
                SurfaceCurvature::new(&sm, k)
            })
        } else {
            None
        };
        let mesh = &self.mesh;
        let oct = &self.octree;
        let nodal = &self.nodal_u;
        let vort = |x: &Pt3| -> f64 {
            match mesh.locate(oct, x) {
                Some((t, _)) => {
                    let tv = mesh.tets[t as usize];
                    let g = &mesh.grad_bary[t as usize];
                    (0..4).fold(Vec3::zeros(), |acc, a| acc + g[a].cross(&nodal[tv[a] as usize])).norm()
                }
                None => 0.0,
            }
        };
        let obstacles = &self.obstacles;
        let solid = |x: &Pt3| obstacles.sdf(x);
        let mut ctx = SizingContext::new(self.spec.h_min(), self.spec.h_root);
        ctx.time = self.time;
        ctx.u_ref = (self.scene.g().norm() * self.h_ref.max(self.spec.h_min())).sqrt();
        ctx.surface = curv.as_ref();
        ctx.vorticity = Some(&vort);
        if !self.obstacles.is_empty() {
            ctx.solid_sdf = Some(&solid);
        }
        let mut demands = Self::demands_static(
            &self.scene,
            &self.spec,
            &self.sizing,
            &self.parts,
            dt,
            Some(&ctx),
            Some(&self.octree),
        );
        demands.extend_from_slice(&self.obstacle_demands);
        demands.extend(Self::moving_obstacle_demands(&self.obstacles, &self.scene, &self.spec));
        let mut oct = build_octree(self.spec, &demands);
        if self.scene.extra_grading_layers > 0 {
            balance_2to1(&mut oct, self.scene.extra_grading_layers);
        }
        oct
    }

    /// Locates every particle without its previous tet (after a mesh change).
    fn relocate_from_scratch(&mut self) {
        for t in self.parts.tet.iter_mut() {
            *t = NONE;
        }
        self.relocate();
    }

    /// Split and merge against the new octree's leaf sizes (spec §3.10, [`crate::split_merge`]),
    /// the surface snap reading the old mesh's `φ`.
    fn split_merge(&mut self, new_oct: &Octree) -> Result<(usize, usize)> {
        let old = OldLevelSet { mesh: &self.mesh, octree: &self.octree, phi: &self.phi };
        let pp = &self.scene.particles;
        match split_merge(&mut self.parts, new_oct, pp, &mut self.rng, &old) {
            Ok(c) => {
                self.budget_hit = c.budget_hit;
                Ok((c.split, c.merged))
            }
            Err(e) => {
                self.budget_hit = matches!(e, SimError::ParticleBudgetExceeded { .. });
                Err(e)
            }
        }
    }

    /// One adaptive time step (spec §3.1).
    pub fn step(&mut self) -> Result<StepStats> {
        let mut tm = PhaseTimings::default();
        let mut st = StepStats { step: self.step, ..Default::default() };
        let g = self.scene.g();
        // 1. Ballistic classification, Δt.
        let c = Instant::now();
        let tree = crate::surface::SphereTree::build(&self.parts.x, &vec![0.0; self.parts.len()]);
        st.n_ballistic = classify_ballistic(
            &mut self.parts,
            &tree,
            self.scene.particles.ballistic_factor,
            self.scene.particles.ballistic,
        );
        let dt = self.choose_dt();
        tm.ballistic = c.elapsed().as_secs_f64();
        // Moving obstacles: placed at the step's start, solid fractions rebuilt (issue 26).
        if self.obstacles.any_moving() {
            let c = Instant::now();
            self.obstacles.set_time(self.time);
            self.node_sdf = self.obstacles.node_sdf(&self.mesh);
            self.mesh.solid_frac = Some(Obstacles::fluid_fractions_from(&self.mesh, &self.node_sdf));
            tm.remesh += c.elapsed().as_secs_f64();
        }
        // 2. Level set on the nodes, stored at particles.
        let c = Instant::now();
        self.phi = self.level_set();
        self.store_particle_phi();
        tm.levelset = c.elapsed().as_secs_f64();
        // 3. Remesh.
        if self.step > 0 && self.step.is_multiple_of(u64::from(self.scene.flip.remesh_interval)) {
            let c = Instant::now();
            let (ns, nm) = self.remesh(dt)?;
            st.n_split = ns;
            st.n_merge = nm;
            st.remeshed = true;
            st.budget_hit = self.budget_hit;
            self.store_particle_phi();
            tm.remesh = c.elapsed().as_secs_f64();
        }
        let m = self.mesh.tets.len();
        // 4–5. P2G and extrapolation.
        let c = Instant::now();
        let p2g = particles_to_tets(&self.mesh, &self.h_tet, &self.parts, &self.scene.transfer);
        tm.p2g = c.elapsed().as_secs_f64();
        let c = Instant::now();
        let layers = self.scene.transfer.extrapolation_layers.unwrap_or(self.scene.flip.cfl.ceil() as u32 + 2);
        let mut u_old = p2g.u.clone();
        let mut valid = p2g.valid.clone();
        // Weak coverage first (its `u_ext` is one extrapolation pass from the well-covered tets),
        // so that the extrapolation below spreads the blended values (spec §3.7).
        st.n_weak_blend = blend_weak(&self.mesh, &p2g, &mut u_old, &self.scene.transfer);
        extrapolate(&self.mesh, &mut u_old, &mut valid, layers);
        // Tets below the coverage threshold that nothing reached by extrapolation keep their own
        // (weak) particle average instead of zero: a droplet cluster smaller than a cube has no
        // valid tet at all and would otherwise lose its momentum every step (spec §8 H-DROPLET-8).
        for t in 0..m {
            if !valid[t] && p2g.coverage[t] > 0.0 {
                u_old[t] = p2g.u[t];
            }
        }
        tm.extrapolate = c.elapsed().as_secs_f64();
        // 6. Forces.
        // Kick length: leapfrog velocities live at half steps (README "Deviations").
        let ti = self.scene.flip.time_integration;
        let dt_kick = match ti {
            TimeIntegration::Leapfrog => 0.5 * (self.prev_dt + dt),
            TimeIntegration::TimeCentred | TimeIntegration::EndOfStep => dt,
        };
        let mut u = u_old.iter().map(|v| v + g * dt_kick).collect::<Vec<_>>();
        // 7. Pressure projection.
        let c = Instant::now();
        // Open box faces are free surfaces for the pressure (p = 0 there), so liquid can leave.
        let phi_p: std::borrow::Cow<[f64]> = if self.open.iter().any(|&o| o) {
            let mut f = self.phi.clone();
            for (i, v) in f.iter_mut().enumerate() {
                let b = self.mesh.node_boundary[i];
                if (0..6).any(|k| self.open[k] && b & (1 << k) != 0) {
                    *v = v.max(0.0);
                }
            }
            std::borrow::Cow::Owned(f)
        } else {
            std::borrow::Cow::Borrowed(&self.phi)
        };
        let mut sys = assemble_pressure(&self.mesh, &phi_p, &u, self.spec.h_min(), &self.scene.pressure);
        if let Some(us) = self.obstacles.tet_velocities(&self.mesh) {
            add_solid_flux(&self.mesh, &mut sys, &us);
        }
        tm.assemble = c.elapsed().as_secs_f64();
        let c = Instant::now();
        let warm = self.warm.as_ref().map(|(nodes, q)| {
            let mut w = vec![0.0; sys.rhs.len()];
            let keymap: std::collections::HashMap<_, _> =
                nodes.iter().zip(q).map(|(&k, &v)| (k, v)).collect::<std::collections::HashMap<u32, f64>>();
            for (d, &node) in sys.node_of_dof.iter().enumerate() {
                if let Some(v) = keymap.get(&node) {
                    w[d] = *v;
                }
            }
            w
        });
        let (q, rep) =
            self.solver.solve(&sys, &self.scene.pressure, if st.remeshed { None } else { warm.as_deref() })?;
        tm.solve = c.elapsed().as_secs_f64();
        let c = Instant::now();
        if q.iter().any(|v| !v.is_finite()) {
            return Err(SimError::NonFinite { what: "pressure", step: self.step });
        }
        let updated = apply_pressure(&self.mesh, &sys, &q, &mut u);
        let mut pressure = vec![0.0; self.mesh.nodes.len()];
        for (d, &node) in sys.node_of_dof.iter().enumerate() {
            pressure[node as usize] = RHO * q[d] / dt_kick;
        }
        self.pressure = pressure;
        self.warm = Some((sys.node_of_dof.clone(), q));
        tm.apply = c.elapsed().as_secs_f64();
        st.n_dofs = sys.rhs.len();
        st.n_ghost_tets = sys.n_ghost_tets;
        st.n_k_reduced = sys.n_k_reduced;
        st.solver = rep;
        // Valid after the projection: updated tets and tets holding a non-ballistic particle centre.
        let c = Instant::now();
        let mut valid_new = updated;
        for i in 0..self.parts.len() {
            let t = self.parts.tet[i];
            if t != NONE && !self.parts.is_ballistic(i) {
                valid_new[t as usize] = true;
            }
        }
        let mut du: Vec<Vec3> = (0..m).map(|t| u[t] - u_old[t]).collect();
        let mut valid_du = valid_new.clone();
        extrapolate(&self.mesh, &mut u, &mut valid_new, layers);
        extrapolate(&self.mesh, &mut du, &mut valid_du, layers);
        let wall_mask = (0..6).filter(|&k| !self.open[k]).fold(0u8, |m, k| m | (1 << k));
        let nodal_new = node_average(&self.mesh, &u, wall_mask);
        let nodal_du = node_average(&self.mesh, &du, wall_mask);
        tm.extrapolate += c.elapsed().as_secs_f64();
        // 9. G2P.
        let c = Instant::now();
        let r_min = self.spec.h_min() / C_H;
        let new_field = TetField { tet: &u, nodal: &nodal_new };
        g2p(&self.mesh, &mut self.parts, new_field, TetField { tet: &du, nodal: &nodal_du }, r_min, &self.scene.flip);
        tm.g2p = c.elapsed().as_secs_f64();
        // 10. Advection (RK2 with substeps), ballistic free flight, walls, obstacles.
        let c = Instant::now();
        // Time-centred advection (ours, see README "Deviations"): the old field's nodal averages.
        let nodal_old = (ti == TimeIntegration::TimeCentred).then(|| node_average(&self.mesh, &u_old, wall_mask));
        let old_field = nodal_old.as_deref().map(|no| TetField { tet: &u_old, nodal: no });
        let grid = AdvectMesh { mesh: &self.mesh, octree: &self.octree, h_tet: &self.h_tet };
        let subs = advect(&grid, &mut self.parts, new_field, old_field, g * dt_kick, dt);
        st.cfl_substeps = subs.iter().sum();
        let keep = apply_walls(&mut self.parts, &self.scene.min(), &self.scene.max(), &self.open);
        let mut keep = keep;
        if !self.obstacles.is_empty() {
            // Pushed out of the obstacles where they are at the step's end, with their velocity.
            self.obstacles.set_time(self.time + dt);
            let ob = &self.obstacles;
            if ob.any_moving() {
                apply_obstacles(&mut self.parts, &|x: &Pt3| ob.sdf(x), Some(&|x: &Pt3| ob.sdf_velocity(x).1));
            } else {
                apply_obstacles(&mut self.parts, &|x: &Pt3| ob.sdf(x), None);
            }
        }
        if !self.scene.outflow.is_empty() {
            let sc = &self.scene;
            let out: Vec<bool> = self.parts.x.par_iter().map(|x| sc.outflow.iter().any(|s| s.sdf(x) < 0.0)).collect();
            for (i, o) in out.iter().enumerate() {
                if *o && keep[i] {
                    keep[i] = false;
                    self.outflow_volume += self.parts.volume(i);
                }
            }
        }
        let deleted = keep.iter().filter(|&&k| !k).count();
        if deleted > 0 {
            self.deleted_volume +=
                (0..self.parts.len()).filter(|&i| !keep[i]).map(|i| self.parts.volume(i)).sum::<f64>();
            self.parts.retain(&keep);
        }
        st.n_deleted = deleted;
        for e in &mut self.emitters {
            e.emit(self.time + dt, &mut self.parts);
        }
        self.relocate();
        tm.advect = c.elapsed().as_secs_f64();
        // 11. Position correction.
        let c = Instant::now();
        if self.scene.particles.position_correction && !self.parts.is_empty() {
            let band = self.scene.particles.surface_band_factor;
            // Surface normals from the smoothed (node-averaged, then interpolated) gradient of φ,
            // not the raw per-tet P1 gradient: see `nodal_phi_gradient`.
            let wall_mask = (0..6).filter(|&k| !self.open[k]).fold(0u8, |m, k| m | (1 << k));
            let gnode = nodal_phi_gradient(&self.mesh, &self.phi, wall_mask);
            let normals: Vec<Option<Vec3>> = (0..self.parts.len())
                .into_par_iter()
                .map(|i| {
                    let t = self.parts.tet[i];
                    if t == NONE || self.parts.phi[i] <= -band * self.parts.r[i] {
                        return None;
                    }
                    let l = self.mesh.barycentric(t, &self.parts.x[i]);
                    let tv = self.mesh.tets[t as usize];
                    let gr = (0..4).fold(Vec3::zeros(), |acc, a| acc + gnode[tv[a] as usize] * l[a].clamp(0.0, 1.0));
                    let n = gr.norm();
                    (n > 0.0).then(|| gr / n)
                })
                .collect();
            let tree = crate::surface::SphereTree::build(&self.parts.x, &self.parts.r);
            let closed = self.walls();
            let seed = self.scene.seed ^ self.step.wrapping_mul(0x9e37_79b9_7f4a_7c15);
            position_correction(
                &mut self.parts,
                &tree,
                &self.scene.min(),
                &self.scene.max(),
                &closed,
                &normals,
                self.scene.particles.correction_gamma,
                seed,
            );
            let _ = apply_walls(&mut self.parts, &self.scene.min(), &self.scene.max(), &[false; 6]);
            self.relocate();
        }
        tm.correction = c.elapsed().as_secs_f64();
        self.nodal_u = nodal_new;
        self.tet_u = u;
        // Statistics.
        self.time += dt;
        self.step += 1;
        self.prev_dt = dt;
        let next = (self.frame + 1) as f64 / self.scene.fps;
        if self.time >= next - 1e-9 * dt.max(1e-12) {
            self.frame += 1;
            st.frame_end = true;
        }
        if self.parts.x.iter().any(|x| !x.coords.iter().all(|c| c.is_finite()))
            || self.parts.v.iter().any(|v| !v.iter().all(|c| c.is_finite()))
        {
            return Err(SimError::NonFinite { what: "particles", step: st.step });
        }
        st.t = self.time;
        st.dt = dt;
        st.n_particles = self.parts.len();
        st.n_nodes = self.mesh.nodes.len();
        st.n_tets = self.mesh.tets.len();
        st.vol_particles = self.parts.total_volume();
        st.vol_levelset = liquid_volume(&self.mesh, &self.phi);
        let (ke, pe, vmax) = (0..self.parts.len()).fold((0.0, 0.0, 0.0f64), |(k, p, m), i| {
            let mass = RHO * self.parts.volume(i);
            let s = self.parts.v[i].norm();
            (k + 0.5 * mass * s * s, p - mass * g.dot(&self.parts.x[i].coords), m.max(s))
        });
        st.kinetic_energy = ke;
        st.potential_energy = pe;
        st.max_speed = vmax;
        st.timings = tm;
        Ok(st)
    }

    /// Steps until `time ≥ t` (frame times are landed on exactly).
    pub fn advance_to(&mut self, t: f64) -> Result<Vec<StepStats>> {
        let mut out = Vec::new();
        while self.time < t - 1e-9 {
            out.push(self.step()?);
        }
        Ok(out)
    }

    /// Simulation surface by marching tetrahedra on the node level set (spec §3.11.4); `None`
    /// when there is no liquid surface.
    pub fn surface(&self) -> Option<TriMesh> {
        crate::surface::marching_tets(&self.mesh, &self.phi).ok()
    }

    /// High-resolution output surface for rendering (spec §3.11.6, see
    /// [`crate::surface::output_surface`]): a separate tet mesh `surface.output_extra_levels`
    /// levels finer than the simulation's around the surface and the spray (ballistic particles
    /// included), the same hull level set with the same wall mirroring, marching tetrahedra and
    /// Taubin smoothing. Obstacles are not carved out (the surface may continue inside them,
    /// where a renderer hides it). Costly: scenes ask for it per frame (`hires_every`).
    pub fn output_surface(&self) -> Result<crate::surface::OutputSurface> {
        let walls = Walls { min: self.scene.min(), max: self.scene.max(), mirror: self.walls(), node_in_solid: None };
        crate::surface::output_surface(&self.spec, &self.parts, &self.scene.surface, &walls)
    }

    /// Grid velocity of the last step at `x` (m/s): the sub-tet interpolation (spec §3.7) of the
    /// post-projection tet velocities and their nodal averages; `None` outside the mesh or before
    /// the first step.
    pub fn grid_velocity(&self, x: &Pt3) -> Option<Vec3> {
        if self.tet_u.len() != self.mesh.tets.len() || self.nodal_u.len() != self.mesh.nodes.len() {
            return None;
        }
        let (t, l) = self.mesh.locate(&self.octree, x)?;
        Some(sample(&self.mesh, &self.tet_u, &self.nodal_u, t, &l))
    }

    /// The obstacles, placed at the current time.
    pub fn obstacles(&self) -> &Obstacles {
        &self.obstacles
    }

    /// Force (N) and torque (N·m, about the obstacle's moved centre) of the last projection's
    /// gauge pressure on obstacle `k` ([`Obstacles::pressure_force`]).
    pub fn obstacle_force(&self, k: usize) -> (Vec3, Vec3) {
        self.obstacles.pressure_force(k, &self.mesh, &self.pressure)
    }

    /// Volume emitted by the inflow emitters so far (m³).
    pub fn emitted_volume(&self) -> f64 {
        self.emitters.iter().map(EmitterState::emitted_volume).sum()
    }

    /// Gauge pressure of the last projection at the mesh nodes (Pa; 0 at air and solid nodes).
    pub fn node_pressure(&self) -> &[f64] {
        &self.pressure
    }

    /// Gauge pressure of the last projection at `x` (Pa): the P1 interpolant of the node
    /// pressures in the tet holding `x` (exact for hydrostatics `p = ρ g (H − y)` below the first
    /// node layer under the surface); `None` outside the mesh or before the first step.
    pub fn pressure_at(&self, x: &Pt3) -> Option<f64> {
        if self.pressure.len() != self.mesh.nodes.len() || self.step == 0 {
            return None;
        }
        let (t, l) = self.mesh.locate(&self.octree, x)?;
        let tv = self.mesh.tets[t as usize];
        Some((0..4).map(|a| l[a] * self.pressure[tv[a] as usize]).sum())
    }

    /// Particles.
    pub fn particles(&self) -> &Particles {
        &self.parts
    }
    /// Mutable particles (tests, stress cases).
    pub fn particles_mut(&mut self) -> &mut Particles {
        &mut self.parts
    }
    /// Tet mesh.
    pub fn mesh(&self) -> &TetMesh {
        &self.mesh
    }
    /// Octree.
    pub fn octree(&self) -> &Octree {
        &self.octree
    }
    /// Node level set of the last step (m).
    pub fn phi(&self) -> &[f64] {
        &self.phi
    }
    /// Simulated time (s).
    pub fn time(&self) -> f64 {
        self.time
    }
    /// Steps taken.
    pub fn steps(&self) -> u64 {
        self.step
    }
    /// The scene.
    pub fn scene(&self) -> &Scene {
        &self.scene
    }
    /// Octree resolution.
    pub fn spec(&self) -> &OctreeSpec {
        &self.spec
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::octree::{build_octree, OctreeSpec};

    /// Uniform BCC mesh of the unit cube with 8 finest cubes per axis, and a graded one (levels
    /// 2..8 refined around a point).
    fn meshes() -> Vec<TetMesh> {
        let sp = OctreeSpec::new(Pt3::origin(), Pt3::new(1.0, 1.0, 1.0), 8, 8).unwrap();
        let uni = tetrahedralize(&Octree::uniform(sp, 0)).unwrap();
        let sp = OctreeSpec::new(Pt3::origin(), Pt3::new(1.0, 1.0, 1.0), 2, 8).unwrap();
        let d = [SizeDemand { center: Pt3::new(0.4, 0.6, 0.5), pad: 0.15, level: 2 }];
        let graded = tetrahedralize(&build_octree(sp, &d)).unwrap();
        vec![uni, graded]
    }

    /// Flat surface `y = H` on a node plane of the uniform mesh, interior values replaced by a
    /// too-shallow stand-in (what the union of balls gives, `0.1 ×` depth): the first-layer bound
    /// plus the interior redistancing restore `φ = y − H` exactly at every liquid node (vertical
    /// edge paths are exact on the BCC lattice; the diagonal edges are longer than their vertical
    /// part). Air values are untouched.
    #[test]
    fn interior_redistancing_restores_flat_depth() {
        let m = &meshes()[0];
        let edges = m.node_nbrs.clone();
        let h = 0.5;
        let exact: Vec<f64> = m.nodes.iter().map(|x| x.y - h).collect();
        let mut phi: Vec<f64> = exact.iter().map(|&v| if v < 0.0 { 0.1 * v } else { v }).collect();
        redistance_first_layer(&m.nodes, &edges, &mut phi);
        redistance_interior(&m.nodes, &edges, &mut phi);
        for (i, (&p, &e)) in phi.iter().zip(&exact).enumerate() {
            if m.node_boundary[i] & 0b11_0011 == 0 {
                assert!((p - e).abs() <= 1e-12, "node {i}: {p} vs {e}");
            } else {
                // Face-centre nodes on the side walls have no vertical edge: their path runs
                // through a half-cube diagonal, at most h/2 (h = 1/8) longer than the depth.
                assert!(p <= e + 1e-12 && -p <= -e + 0.0625 + 1e-12, "wall node {i}: {p} vs {e}");
            }
        }
    }

    /// On the graded mesh with a tilted plane the redistanced depth is a path length: never
    /// shallower than the exact depth minus round-off and at most ≈ 24 % deeper (spec §3.11.3
    /// bound, plus one coarse edge of slack at the first layer), and signs never change.
    #[test]
    fn interior_redistancing_bounds_on_graded_mesh() {
        for m in &meshes() {
            let edges = m.node_nbrs.clone();
            let n = Vec3::new(0.3, 1.0, -0.2).normalize();
            let exact: Vec<f64> = m.nodes.iter().map(|x| n.dot(&(x.coords - Vec3::new(0.5, 0.55, 0.5)))).collect();
            let mut phi: Vec<f64> = exact.iter().map(|&v| if v < 0.0 { 0.05 * v } else { v }).collect();
            redistance_first_layer(&m.nodes, &edges, &mut phi);
            redistance_interior(&m.nodes, &edges, &mut phi);
            for (i, (&p, &e)) in phi.iter().zip(&exact).enumerate() {
                assert_eq!(p < 0.0, e < 0.0, "node {i}: sign changed");
                if e < 0.0 {
                    assert!(p <= e + 1e-12, "node {i}: {p} shallower than {e}");
                    assert!(-p <= 1.25 * -e + 0.25, "node {i}: {p} far deeper than {e}");
                }
            }
        }
    }

    /// Temporal sizing smoothing (spec §3.12, opt-in): with every particle in a finest leaf and
    /// a sizing that asks for the coarsest radius below the surface band, the demands fall at
    /// most one level below the finest (`S ≤ 2 S_prev`); without it the deep particles demand
    /// levels two or more below, and the off switch changes nothing else.
    #[test]
    fn temporal_smoothing_limits_coarsening_to_one_level() {
        let text = |on: bool| {
            format!(
                r#"(domain: (min: (0.0, 0.0, 0.0), max: (1.0, 1.0, 1.0)),
                resolution: (coarsest: 2, finest: 16), duration: 0.1, fps: 60.0,
                liquid: [Box(min: (0.0, 0.0, 0.0), max: (1.0, 0.5, 1.0))],
                sizing: (depth_floor: Some(2.0), surface_band: Some(2.0), temporal_smoothing: {on}))"#
            )
        };
        let levels = |on: bool| {
            let scene: Scene = ron::from_str(&text(on)).unwrap();
            let sim = FlipTetSim::new(&scene).unwrap();
            let fine = Octree::uniform(sim.spec, sim.spec.levels - 1);
            let d = FlipTetSim::demands_static(&scene, &sim.spec, &sim.sizing, &sim.parts, 0.01, None, Some(&fine));
            d.iter().map(|x| x.level).collect::<Vec<u8>>()
        };
        let finest = FlipTetSim::new(&ron::from_str::<Scene>(&text(false)).unwrap()).unwrap().spec.levels - 1;
        let (off, on) = (levels(false), levels(true));
        assert_eq!(off.len(), on.len());
        assert!(off.iter().any(|&l| l + 2 <= finest), "without smoothing some demand is ≥ 2 levels coarser");
        assert!(on.iter().all(|&l| l + 1 >= finest), "with smoothing every demand within one level");
        // Where the sizing asks for at most one level of coarsening, smoothing changes nothing.
        for (a, b) in off.iter().zip(&on) {
            if a + 1 >= finest {
                assert_eq!(a, b);
            }
        }
    }

    /// T-SPLIT-MERGE (spec §7): 100 split/merge passes against octrees refined around random
    /// points (levels 0–2 of a 3-level spec, so every pass both splits and merges somewhere)
    /// conserve `Σ r³` and `Σ r³ v` to 1e−12 relative (a few roundings per particle of sums of
    /// O(10³) terms), and two runs with the same seed give bitwise equal particles.
    #[test]
    fn split_merge_conserves_volume_and_momentum_and_is_deterministic() {
        let text = r#"(domain: (min: (0.0, 0.0, 0.0), max: (0.5, 0.5, 0.5)),
            resolution: (coarsest: 2, finest: 8), duration: 0.1, fps: 60.0, seed: 5,
            liquid: [Box(min: (0.0, 0.0, 0.0), max: (0.5, 0.25, 0.5))])"#;
        let run = || {
            let scene: Scene = ron::from_str(text).unwrap();
            let mut sim = FlipTetSim::new(&scene).unwrap();
            // Random velocities, so that Σ r³ v tests the momentum weights.
            let mut rng = geom_core::rng::Rng::new(17);
            for v in sim.parts.v.iter_mut() {
                *v = rng.unit_vec3() * rng.range(0.0, 2.0);
            }
            let sums = |p: &Particles| {
                let vol: f64 = p.r.iter().map(|r| r.powi(3)).sum();
                let mom = (0..p.len()).fold(Vec3::zeros(), |a, i| a + p.v[i] * p.r[i].powi(3));
                (vol, mom)
            };
            let (vol0, mom0) = sums(&sim.parts);
            let (mut n_split, mut n_merge) = (0, 0);
            for pass in 0..100 {
                let c = Pt3::new(rng.range(0.0, 0.5), rng.range(0.0, 0.25), rng.range(0.0, 0.5));
                let level = (pass % 3) as u8;
                let d = [SizeDemand { center: c, pad: rng.range(0.05, 0.2), level }];
                let oct = build_octree(sim.spec, &d);
                let (a, b) = sim.split_merge(&oct).unwrap();
                n_split += a;
                n_merge += b;
                let (vol, mom) = sums(&sim.parts);
                assert!((vol - vol0).abs() <= 1e-12 * vol0, "pass {pass}: Σ r³ {vol} vs {vol0}");
                assert!((mom - mom0).norm() <= 1e-12 * mom0.norm().max(vol0), "pass {pass}: Σ r³ v");
            }
            assert!(n_split > 0 && n_merge > 0, "splits {n_split}, merges {n_merge}");
            sim.parts
        };
        let (a, b) = (run(), run());
        assert_eq!(a.x, b.x);
        assert_eq!(a.v, b.v);
        assert_eq!(a.r, b.r);
    }

    /// The remesh shortcut (same leaves, no split or merge: keep the mesh, relocate the particles,
    /// recompute `φ`) is what a rebuild gives: rebuilding from an equal octree after some steps
    /// of a collapsing graded column reproduces the nodes, tets, particle tets and `φ` bitwise.
    #[test]
    fn rebuild_from_an_equal_octree_changes_nothing() {
        let text = r#"(domain: (min: (0.0, 0.0, 0.0), max: (0.5, 0.25, 0.125)),
            resolution: (coarsest: 4, finest: 16), duration: 0.1, fps: 60.0,
            liquid: [Box(min: (0.0, 0.0, 0.0), max: (0.125, 0.1875, 0.125))],
            sizing: (depth_floor: Some(0.25), surface_band: Some(3.0)),
            flip: (remesh_interval: 3))"#;
        let scene: Scene = ron::from_str(text).unwrap();
        let mut sim = FlipTetSim::new(&scene).unwrap();
        for _ in 0..4 {
            sim.step().unwrap();
        }
        assert!(sim.octree.level_histogram().iter().filter(|&&n| n > 0).count() > 1, "graded");
        // The shortcut.
        sim.relocate_from_scratch();
        sim.phi = sim.level_set();
        let (nodes, tets, ptet, phi) =
            (sim.mesh.nodes.clone(), sim.mesh.tets.clone(), sim.parts.tet.clone(), sim.phi.clone());
        // The rebuild.
        let same = sim.octree.clone();
        sim.set_mesh(same).unwrap();
        sim.relocate_from_scratch();
        sim.phi = sim.level_set();
        assert_eq!(nodes, sim.mesh.nodes);
        assert_eq!(tets, sim.mesh.tets);
        assert_eq!(ptet, sim.parts.tet);
        assert!(phi.iter().zip(&sim.phi).all(|(a, b)| a.to_bits() == b.to_bits()), "φ changed");
    }

    /// The simulator's level set with cheap stand-ins at deep liquid nodes equals the fully
    /// evaluated one bitwise after the redistancing passes, at every step of a collapsing column
    /// (remeshing, split/merge, splashing) and of a droplet plus pool with an isolated blob.
    #[test]
    fn fast_level_set_equals_exact_in_the_simulation() {
        let scenes = [
            r#"(domain: (min: (0.0, 0.0, 0.0), max: (0.5, 0.25, 0.125)),
                resolution: (coarsest: 4, finest: 16), duration: 0.1, fps: 60.0,
                liquid: [Box(min: (0.0, 0.0, 0.0), max: (0.125, 0.1875, 0.125))],
                sizing: (depth_floor: Some(0.25), surface_band: Some(3.0)),
                flip: (remesh_interval: 3))"#,
            r#"(domain: (min: (0.0, 0.0, 0.0), max: (0.5, 0.5, 0.5)),
                resolution: (coarsest: 4, finest: 16), duration: 0.1, fps: 60.0,
                liquid: [Box(min: (0.0, 0.0, 0.0), max: (0.5, 0.125, 0.5)),
                         Sphere(center: (0.25, 0.34, 0.25), radius: 0.08)],
                sizing: (depth_floor: Some(0.25), surface_band: Some(3.0)),
                flip: (remesh_interval: 2))"#,
        ];
        for text in scenes {
            let scene: Scene = ron::from_str(text).unwrap();
            let mut sim = FlipTetSim::new(&scene).unwrap();
            let mut stand_ins = 0;
            for _ in 0..8 {
                let exact = sim.level_set_with(true);
                let fast = sim.level_set_with(false);
                assert_eq!(exact.len(), fast.len());
                for (i, (a, b)) in exact.iter().zip(&fast).enumerate() {
                    assert_eq!(a.to_bits(), b.to_bits(), "node {i}: {a} vs {b}");
                }
                // The fast path did skip work: some nodes were deep (not first-layer) liquid.
                let nbrs = &sim.mesh.node_nbrs;
                stand_ins += (0..exact.len())
                    .filter(|&i| exact[i] < 0.0 && nbrs.row(i).iter().all(|&j| exact[j as usize] < 0.0))
                    .count();
                sim.step().unwrap();
            }
            assert!(stand_ins > 100, "{stand_ins}");
        }
    }

    /// The smoothed nodal gradient is exact for linear φ (on graded meshes too), and at closed
    /// wall nodes the wall-normal component is removed.
    #[test]
    fn nodal_gradient_exact_for_linear_phi() {
        for m in &meshes() {
            let g = Vec3::new(0.3, -1.2, 0.7);
            let phi: Vec<f64> = m.nodes.iter().map(|x| g.dot(&x.coords) + 0.1).collect();
            let open = nodal_phi_gradient(m, &phi, 0);
            for v in &open {
                assert!((v - g).norm() <= 1e-11, "{v:?}");
            }
            let walled = nodal_phi_gradient(m, &phi, 0x3f);
            for (i, v) in walled.iter().enumerate() {
                let b = m.node_boundary[i];
                for a in 0..3 {
                    let on_wall = b & (3 << (2 * a)) != 0;
                    let want = if on_wall { 0.0 } else { g[a] };
                    assert!((v[a] - want).abs() <= 1e-11, "node {i} axis {a}: {} vs {want}", v[a]);
                }
            }
        }
    }

    /// S1b lattice offset: with `lattice_offset = (0.1, 0.37, −0.2)` the seeding keeps the same
    /// lattice points as without it (same count, radii, velocities, `φ_p` bitwise) and moves each
    /// by exactly `offset · 2r`; the default (zero) offset gives the unshifted lattice; offsets
    /// outside (−1, 1) are rejected by `validate`.
    #[test]
    fn lattice_offset_translates_the_seeded_lattice() {
        let text = r#"(domain: (min: (0.0, 0.0, 0.0), max: (1.0, 0.5, 0.5)),
            resolution: (coarsest: 8, finest: 8), duration: 0.1,
            liquid: [Box(min: (0.0, 0.0, 0.0), max: (1.0, 0.25, 0.5))])"#;
        let base: Scene = ron::from_str(text).expect("test scene parses");
        let oct = Octree::uniform(OctreeSpec::new(base.min(), base.max(), 8, 8).unwrap(), 0);
        let a = sample_particles(&base, &Obstacles::default(), &oct, &mut Rng::new(1));
        // 8 × 2 × 4 cubes of h = 1/8 below y = 0.25, 8 particles each.
        assert_eq!(a.len(), 8 * 2 * 4 * 8);
        let top = a.x.iter().map(|x| x.y).fold(f64::MIN, f64::max);
        assert_eq!(top, 0.25 - 1.0 / 32.0);
        let mut shifted = base.clone();
        shifted.particles.lattice_offset = [0.1, 0.37, -0.2];
        shifted.validate().expect("offset inside (−1, 1) is valid");
        let b = sample_particles(&shifted, &Obstacles::default(), &oct, &mut Rng::new(1));
        assert_eq!(b.len(), a.len());
        let off = Vec3::new(0.1, 0.37, -0.2);
        for i in 0..a.len() {
            assert_eq!(b.x[i], a.x[i] + off * (2.0 * a.r[i]), "particle {i}");
            assert_eq!((b.r[i], b.phi[i], b.v[i]), (a.r[i], a.phi[i], a.v[i]));
        }
        shifted.particles.lattice_offset = [0.0, 1.5, 0.0];
        assert!(shifted.validate().is_err());
    }
}

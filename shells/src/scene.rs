//! Scene description (serde, RON) of a shell simulation: the `shell` block that the xtask scenes
//! of this crate use and that `tracks` embeds unchanged (shells.md §2 "scene file").

use crate::effects::{CollisionSettings, Effects, Obstacle, Wind};
use crate::error::{Error, Result};
use crate::integrator::{IntegratorKind, IntegratorSettings};
use crate::kernels::psd::HessianMode;
use crate::material::Material;
use crate::sim::{ShellSceneDesc, VertexConstraint};
use geom_core::math::{Pt3, UnitQuat, Vec3};
use geom_core::mesh::TriMesh;
use geom_core::procedural::{grid, Diagonals, GridSpec, Plane};
use geom_core::rng::Rng;
use serde::{Deserialize, Serialize};
use std::path::Path;

/// A shell scene (everything except output and scene-specific measurements).
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ShellScene {
    /// The mesh.
    pub mesh: MeshSpec,
    /// Rigid placement of the rest mesh.
    #[serde(default)]
    pub placement: Placement,
    /// Rest-shape perturbation (e.g. rough cellophane).
    #[serde(default)]
    pub rest_offsets: RestOffsets,
    /// Material.
    pub material: Material,
    /// Effects (each optional).
    #[serde(default)]
    pub effects: EffectsSpec,
    /// Pinned vertex sets (fixed at their rest positions).
    #[serde(default)]
    pub pins: Vec<PinSpec>,
    /// Kinematic vertex sets: each set follows a rigid path from its rest placement (twist,
    /// pull or carry the cloth); the sets must not overlap each other or `pins`.
    #[serde(default)]
    pub kinematic: Vec<KinematicPins>,
    /// Time stepping.
    #[serde(default)]
    pub integrator: SceneIntegrator,
    /// Uniform initial velocity (m/s).
    #[serde(default)]
    pub initial_velocity: Vec3,
    /// Simulated duration (s).
    pub duration: f64,
}

/// Where the mesh comes from.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub enum MeshSpec {
    /// A grid of `nx × ny` **vertices** (GEOM-CORE.md §5.1: quads = n − 1) of `size` metres in the
    /// XY plane, centred at the origin.
    Grid {
        /// Vertices along x.
        nx: u32,
        /// Vertices along y.
        ny: u32,
        /// Extent (m).
        size: (f64, f64),
        /// Quad split pattern.
        #[serde(default)]
        diagonals: Diagonals,
    },
    /// An OBJ file (relative paths resolve against the base directory given to `build`).
    Obj {
        /// Path.
        path: String,
    },
    /// An open cylinder along +y from the origin: `around` vertices per ring, `along` rings
    /// (quads split into triangles); radius and length in metres.
    Tube {
        /// Radius (m).
        radius: f64,
        /// Length (m).
        length: f64,
        /// Vertices per ring (≥ 3).
        around: u32,
        /// Rings (≥ 2).
        along: u32,
    },
}

/// A vertex set that follows a rigid path.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct KinematicPins {
    /// The vertices.
    pub set: PinSpec,
    /// Their rigid motion from the placed rest positions.
    pub path: geom_core::kinematic::KinematicPath,
}

/// Where a mesh obstacle's closed triangle mesh comes from.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub enum MeshSource {
    /// An axis-aligned box (m), triangulated with `segments` quads per side.
    Box {
        /// Minimum corner (m).
        min: Pt3,
        /// Maximum corner (m).
        max: Pt3,
        /// Quads per side along x, y, z.
        #[serde(default = "one3")]
        segments: (u32, u32, u32),
    },
    /// A closed OBJ, PLY or OFF mesh (relative paths resolve against the base directory).
    File {
        /// Path.
        path: String,
    },
}

fn one3() -> (u32, u32, u32) {
    (1, 1, 1)
}

/// A rigid obstacle given as a closed triangle mesh.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MeshObstacleSpec {
    /// The mesh.
    pub mesh: MeshSource,
    /// Cloth–obstacle Coulomb friction μ.
    #[serde(default = "half")]
    pub friction: f64,
    /// Rigid motion; `None` = static.
    #[serde(default)]
    pub motion: Option<geom_core::kinematic::KinematicPath>,
}

fn half() -> f64 {
    0.5
}

/// Rigid placement: rotate (degrees about x, then y, then z, fixed axes), then translate (m).
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Placement {
    /// Translation (m).
    #[serde(default)]
    pub translate: (f64, f64, f64),
    /// Rotation angles (degrees).
    #[serde(default)]
    pub rotate_deg: (f64, f64, f64),
}

/// Rest-shape perturbation.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
pub enum RestOffsets {
    /// None.
    #[default]
    None,
    /// Random offsets along the vertex normal, uniform in ±amplitude (m), seeded.
    NormalNoise {
        /// Amplitude (m).
        amplitude: f64,
        /// Seed.
        seed: u64,
    },
}

/// The effects block of a scene file.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct EffectsSpec {
    /// Gravity (m/s²).
    #[serde(default)]
    pub gravity: Option<Vec3>,
    /// Wind.
    #[serde(default)]
    pub wind: Option<Wind>,
    /// Cloth self-collision.
    #[serde(default)]
    pub self_collision: bool,
    /// Rigid obstacles.
    #[serde(default)]
    pub obstacles: Vec<Obstacle>,
    /// Rigid obstacles given as closed triangle meshes (a box, a file).
    #[serde(default)]
    pub mesh_obstacles: Vec<MeshObstacleSpec>,
    /// Collision settings (`None`: no collision code at all).
    #[serde(default)]
    pub collision: Option<CollisionSettings>,
}

/// A set of pinned vertices.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub enum PinSpec {
    /// Explicit vertex indices.
    Vertices(Vec<u32>),
    /// Grid only: the two corners of the last row (max v, the "top" before placement).
    TopCorners,
    /// Grid only: all four corners.
    Corners,
    /// Grid only: every vertex of the column u = 0 (the left side).
    LeftSide,
    /// Grid only: the first `n` columns from u = 0 (a clamp).
    LeftColumns(u32),
    /// Every vertex within `radius` (m) of `point` (placed coordinates).
    Near {
        /// Centre (m).
        point: Pt3,
        /// Radius (m).
        radius: f64,
    },
    /// Every vertex within `tol` (m) of the plane through `point` with normal `normal` (placed
    /// coordinates), e.g. one end ring of a tube.
    Plane {
        /// A point of the plane (m).
        point: Pt3,
        /// Its normal (normalised on use).
        normal: Vec3,
        /// Distance tolerance (m).
        tol: f64,
    },
}

/// Time-stepping block.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SceneIntegrator {
    /// Output frames per second.
    #[serde(default = "d_fps")]
    pub fps: f64,
    /// Steps per frame (h = 1/(fps·substeps)).
    #[serde(default = "d_sub")]
    pub substeps: u32,
    /// Integrator.
    #[serde(default)]
    pub kind: IntegratorKind,
    /// Newton iterations per step.
    #[serde(default = "d_one")]
    pub newton_iters: u32,
    /// Hessian mode.
    #[serde(default)]
    pub hessian: HessianMode,
    /// Line search.
    #[serde(default)]
    pub line_search: bool,
    /// Deterministic reductions.
    #[serde(default = "d_true")]
    pub deterministic: bool,
}

fn d_fps() -> f64 {
    30.0
}
fn d_sub() -> u32 {
    4
}
fn d_one() -> u32 {
    1
}
fn d_true() -> bool {
    true
}

impl Default for SceneIntegrator {
    fn default() -> Self {
        Self {
            fps: 30.0,
            substeps: 4,
            kind: IntegratorKind::BackwardEuler,
            newton_iters: 1,
            hessian: HessianMode::ProjectedCheap,
            line_search: false,
            deterministic: true,
        }
    }
}

impl SceneIntegrator {
    /// Step size h = 1/(fps·substeps) (s).
    pub fn h(&self) -> f64 {
        1.0 / (self.fps * self.substeps as f64)
    }

    /// Integrator settings.
    pub fn settings(&self) -> IntegratorSettings {
        IntegratorSettings {
            kind: self.kind,
            newton_iters: self.newton_iters,
            hessian: self.hessian,
            line_search: self.line_search,
            deterministic: self.deterministic,
            divergence_energy_factor: 1e6,
        }
    }
}

/// A built scene: the simulator description plus what runners need to know about the mesh.
pub struct BuiltScene {
    /// Simulator description.
    pub desc: ShellSceneDesc,
    /// Grid vertex counts (nx, ny) when the mesh is a grid.
    pub grid: Option<(u32, u32)>,
    /// The placed rest mesh.
    pub mesh: TriMesh,
}

impl ShellScene {
    /// Builds the mesh, placement, pins and effects. Validation errors name the field.
    pub fn build(&self, base_dir: &Path) -> Result<BuiltScene> {
        if !(self.duration >= 0.0) || !self.duration.is_finite() {
            return Err(Error::BadParameter(format!("duration must be finite and ≥ 0 s, got {}", self.duration)));
        }
        let it = &self.integrator;
        if !(it.fps > 0.0) || !it.fps.is_finite() || it.substeps == 0 {
            return Err(Error::BadParameter(format!(
                "fps must be > 0 and substeps ≥ 1, got {} and {}",
                it.fps, it.substeps
            )));
        }
        let (mesh, dims) = match &self.mesh {
            MeshSpec::Grid { nx, ny, size, diagonals } => {
                if *nx < 2 || *ny < 2 {
                    return Err(Error::BadParameter(format!("grid needs ≥ 2 vertices per side, got {nx}×{ny}")));
                }
                let g = grid(&GridSpec {
                    quads: [nx - 1, ny - 1],
                    size: [size.0, size.1],
                    plane: Plane::XY,
                    diagonals: *diagonals,
                    center: Pt3::origin(),
                })?;
                (g, Some((*nx, *ny)))
            }
            MeshSpec::Obj { path } => {
                let p = base_dir.join(path);
                (geom_core::io::obj::read_tri(&p)?, None)
            }
            MeshSpec::Tube { radius, length, around, along } => {
                if *along < 2 {
                    return Err(Error::BadParameter(format!("mesh.Tube.along: a tube needs ≥ 2 rings, got {along}")));
                }
                let t = geom_core::procedural::tube(&geom_core::procedural::TubeSpec {
                    radius: *radius,
                    length: *length,
                    around: *around,
                    along: along - 1,
                    start: Pt3::origin(),
                    axis: Vec3::y(),
                    caps: geom_core::procedural::Caps::Open,
                })
                .map_err(|e| Error::BadParameter(format!("mesh.Tube: {e}")))?;
                (t.triangulate_fan()?.0, None)
            }
        };
        let (rx, ry, rz) = self.placement.rotate_deg;
        let rot = UnitQuat::from_euler_angles(rx.to_radians(), ry.to_radians(), rz.to_radians());
        let tr = Vec3::new(self.placement.translate.0, self.placement.translate.1, self.placement.translate.2);
        let mut pos: Vec<Pt3> = mesh.positions.iter().map(|p| rot * p + tr).collect();
        if let RestOffsets::NormalNoise { amplitude, seed } = self.rest_offsets {
            let normals = vertex_normals(&pos, &mesh.faces);
            let mut rng = Rng::new(seed);
            for (p, n) in pos.iter_mut().zip(&normals) {
                *p += rng.range(-amplitude, amplitude) * n;
            }
        }
        let placed = mesh.with_positions(pos.clone())?;
        let n = pos.len() as u32;
        let mut pinned: Vec<u32> = Vec::new();
        for (k, p) in self.pins.iter().enumerate() {
            let ids = select(p, dims, &pos).map_err(|m| Error::BadParameter(format!("pins[{k}]: {m}")))?;
            // An empty set is a mistake (a wrong radius, an empty list), never an intent.
            if ids.is_empty() {
                return Err(Error::BadParameter(format!("pins[{k}] selects no vertex")));
            }
            if let Some(&bad) = ids.iter().find(|&&i| i >= n) {
                return Err(Error::BadParameter(format!("pins[{k}]: vertex {bad} out of range ({n} vertices)")));
            }
            pinned.extend(ids);
        }
        pinned.sort_unstable();
        pinned.dedup();
        let mut constraints =
            if pinned.is_empty() { Vec::new() } else { vec![VertexConstraint::Pinned(pinned.clone())] };
        let mut taken: std::collections::BTreeSet<u32> = pinned.iter().copied().collect();
        for (k, kp) in self.kinematic.iter().enumerate() {
            let field = format!("kinematic[{k}]");
            kp.path.validate().map_err(|e| Error::BadParameter(format!("{field}.path: {e}")))?;
            let mut ids = select(&kp.set, dims, &pos).map_err(|m| Error::BadParameter(format!("{field}.set: {m}")))?;
            ids.sort_unstable();
            ids.dedup();
            if ids.is_empty() {
                return Err(Error::BadParameter(format!("{field}.set selects no vertex")));
            }
            if let Some(&bad) = ids.iter().find(|&&i| i >= n) {
                return Err(Error::BadParameter(format!("{field}.set: vertex {bad} out of range ({n} vertices)")));
            }
            if let Some(&dup) = ids.iter().find(|i| taken.contains(i)) {
                return Err(Error::BadParameter(format!("{field}.set: vertex {dup} is already pinned or kinematic")));
            }
            taken.extend(&ids);
            let rest: std::collections::HashMap<u32, Pt3> = ids.iter().map(|&i| (i, pos[i as usize])).collect();
            let path = kp.path.clone();
            let f: crate::sim::KinematicFn = Box::new(move |t, i| path.point_at(t, &rest[&i]));
            constraints.push(VertexConstraint::Kinematic(ids, f));
        }
        let e = &self.effects;
        let mut obstacles = e.obstacles.clone();
        for (k, mo) in e.mesh_obstacles.iter().enumerate() {
            obstacles.push(
                mesh_obstacle(mo, base_dir)
                    .map_err(|m| Error::BadParameter(format!("effects.mesh_obstacles[{k}]: {m}")))?,
            );
        }
        let effects = Effects {
            gravity: e.gravity,
            wind: e.wind.clone(),
            obstacles,
            self_collision: e.self_collision,
            collision: e.collision.clone(),
            custom: Vec::new(),
        };
        let v0 = self.initial_velocity;
        let desc = ShellSceneDesc {
            rest: pos,
            faces: mesh.faces.clone(),
            uv: mesh.uv.clone(),
            initial: None,
            initial_velocity: (v0 != Vec3::zeros()).then(|| vec![v0; n as usize]),
            material: self.material.clone(),
            effects,
            constraints,
            integrator: self.integrator.settings(),
            t0: 0.0,
        };
        Ok(BuiltScene { desc, grid: dims, mesh: placed })
    }
}

/// The vertices of a pin set (`dims`: grid vertex counts for the grid-only sets).
fn select(p: &PinSpec, dims: Option<(u32, u32)>, pos: &[Pt3]) -> std::result::Result<Vec<u32>, String> {
    let n = pos.len() as u32;
    let need_grid = || "this pin set needs a Grid mesh".to_string();
    let mut out = Vec::new();
    match p {
        PinSpec::Vertices(v) => out.extend(v),
        PinSpec::TopCorners => {
            let (nx, ny) = dims.ok_or_else(need_grid)?;
            out.extend([(ny - 1) * nx, ny * nx - 1]);
        }
        PinSpec::Corners => {
            let (nx, ny) = dims.ok_or_else(need_grid)?;
            out.extend([0, nx - 1, (ny - 1) * nx, ny * nx - 1]);
        }
        PinSpec::LeftSide => {
            let (nx, ny) = dims.ok_or_else(need_grid)?;
            out.extend((0..ny).map(|j| j * nx));
        }
        PinSpec::LeftColumns(c) => {
            let (nx, ny) = dims.ok_or_else(need_grid)?;
            for j in 0..ny {
                out.extend((0..(*c).min(nx)).map(|i| j * nx + i));
            }
        }
        PinSpec::Near { point, radius } => {
            if !(radius.is_finite() && *radius >= 0.0) || point.iter().any(|c| !c.is_finite()) {
                return Err(format!("Near needs a finite point and radius ≥ 0, got {radius}"));
            }
            out.extend((0..n).filter(|&i| (pos[i as usize] - point).norm() <= *radius));
        }
        PinSpec::Plane { point, normal, tol } => {
            let nn = normal.try_normalize(0.0).ok_or("Plane needs a non-zero normal")?;
            if !(tol.is_finite() && *tol >= 0.0) || point.iter().any(|c| !c.is_finite()) {
                return Err(format!("Plane needs a finite point and tol ≥ 0, got {tol}"));
            }
            out.extend((0..n).filter(|&i| nn.dot(&(pos[i as usize] - point)).abs() <= *tol));
        }
    }
    Ok(out)
}

/// A mesh obstacle as an [`Obstacle`]: the mesh must be closed (it has an inside).
fn mesh_obstacle(mo: &MeshObstacleSpec, base_dir: &Path) -> std::result::Result<Obstacle, String> {
    let m = match &mo.mesh {
        MeshSource::Box { min, max, segments } => {
            geom_core::procedural::box_surface(*min, *max, [segments.0, segments.1, segments.2], Diagonals::Alternating)
                .map_err(|e| format!("mesh.Box: {e}"))?
        }
        MeshSource::File { path } => {
            let p = base_dir.join(path);
            let poly = geom_core::io::read_any(&p).map_err(|e| format!("mesh.File {}: {e}", p.display()))?;
            poly.triangulate_fan().map_err(|e| format!("mesh.File {}: {e}", p.display()))?.0
        }
    };
    if !m.topology().is_closed() {
        return Err(format!(
            "the obstacle mesh is not closed ({} boundary edges): it has no inside",
            m.topology().n_boundary_edges()
        ));
    }
    if let Some(path) = &mo.motion {
        path.validate().map_err(|e| format!("motion: {e}"))?;
    }
    Ok(Obstacle {
        shape: crate::effects::ObstacleShape::Mesh { verts: m.positions.clone(), tris: m.faces.clone() },
        friction: mo.friction,
        motion: mo.motion.clone(),
    })
}

/// Area-weighted unit vertex normals (zero for isolated vertices).
pub fn vertex_normals(p: &[Pt3], faces: &[[u32; 3]]) -> Vec<Vec3> {
    let mut n = vec![Vec3::zeros(); p.len()];
    for t in faces {
        let [a, b, c] = t.map(|i| p[i as usize]);
        let fnrm = (b - a).cross(&(c - a));
        for &i in t {
            n[i as usize] += fnrm;
        }
    }
    for v in n.iter_mut() {
        let l = v.norm();
        if l > 0.0 {
            *v /= l;
        }
    }
    n
}

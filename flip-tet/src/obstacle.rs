//! Obstacles at run time (issue 26 item 4): the scene's static analytic shapes, closed triangle
//! meshes (`Shape::Mesh`, through geom-core's [`MeshQuery`]) and obstacles moving on a rigid
//! [`KinematicPath`] (`Scene::moving_obstacles`), with their signed distance, their velocity
//! field, and the pressure force and torque the liquid exerts on each.
//!
//! A moving obstacle imposes its velocity on the liquid through the projection's right-hand
//! side (`Gᵀ (W u* + (V − W) u_solid)`, [`crate::pressure::add_solid_flux`]): the solid
//! fractions are rebuilt every step from the obstacles' placement at the step's start, and
//! particles are pushed out with the obstacle's velocity ([`crate::particles::apply_obstacles`]).
//!
//! ```
//! use flip_tet::obstacle::MovingObstacle;
//! // A gate 5 mm thick lifted at 1 m/s from t = 0.
//! let gate: MovingObstacle = ron::from_str(
//!     "(shape: Box(min: (0.05, -0.01, -0.01), max: (0.055, 0.2, 0.05)), path: Translate(velocity: (0, 1, 0)))",
//! ).unwrap();
//! assert!(!gate.path.is_static());
//! ```

use std::path::Path;
use std::sync::Arc;

use geom_core::collide::MeshQuery;
use geom_core::kinematic::KinematicPath;
use geom_core::math::{Iso3, Pt3, Vec3};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::bcc::TetMesh;
use crate::error::{Result, SimError};
use crate::scene::{Scene, Shape};

/// An obstacle moving on a rigid path (scene file `moving_obstacles: [(shape: …, path: …)]`):
/// a point `p₀` of `shape` (its rest placement) is at `path.transform(t) · p₀` at time `t`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MovingObstacle {
    /// The obstacle in its rest placement (an analytic shape or a closed `Mesh`).
    pub shape: Shape,
    /// Its rigid motion (geom-core's `KinematicPath`: `Translate`, `Rotate`, `After`, `Compose`,
    /// `Keyframes`).
    pub path: KinematicPath,
}

/// The signed distance of one obstacle in its rest placement.
#[derive(Clone, Debug)]
enum Geometry {
    Analytic(Shape),
    Mesh(Arc<MeshQuery>),
}

impl Geometry {
    fn sdf(&self, x: &Pt3) -> f64 {
        match self {
            Geometry::Analytic(s) => s.sdf(x),
            Geometry::Mesh(q) => q.signed_distance(x),
        }
    }
}

/// One obstacle: geometry, optional path, placement at the current time.
#[derive(Clone, Debug)]
struct Solid {
    geom: Geometry,
    path: Option<KinematicPath>,
    /// Placement at the current time and its inverse.
    pose: Iso3,
    inv: Iso3,
    /// Reference point of the torque in the rest placement (m): the shape's centre.
    center: Pt3,
}

/// The obstacles of a scene at one time: `obstacles` first (static), then `moving_obstacles`.
#[derive(Clone, Debug, Default)]
pub struct Obstacles {
    solids: Vec<Solid>,
    time: f64,
}

/// Reads a closed triangle mesh (OBJ, PLY, OFF, … by content) for a `Mesh` obstacle; the error
/// names `field` and the file.
pub fn load_mesh(path: &str, field: &str) -> Result<MeshQuery> {
    let bad = |m: String| SimError::InvalidScene(format!("{field}: mesh '{path}': {m}"));
    let poly = geom_core::io::read_any(Path::new(path)).map_err(|e| bad(format!("cannot read: {e}")))?;
    let (tri, _) = poly.triangulate_fan().map_err(|e| bad(format!("cannot triangulate: {e}")))?;
    MeshQuery::new(&tri).map_err(|e| match e {
        geom_core::Error::NotClosed { boundary_edges } => {
            bad(format!("not closed ({boundary_edges} boundary edges): an obstacle mesh must be watertight"))
        }
        e => bad(e.to_string()),
    })
}

/// Centre of a shape in its rest placement (m): box / sphere / cylinder centre, the mesh's
/// bounding-box centre, the base's centre for a CSG difference, the origin otherwise.
fn shape_center(s: &Shape, mesh: Option<&MeshQuery>) -> Pt3 {
    match (s, mesh) {
        (_, Some(q)) => {
            let b = q.bbox();
            Pt3::from((b.min.coords + b.max.coords) / 2.0)
        }
        (Shape::Box { min, max }, _) => {
            Pt3::new((min[0] + max[0]) / 2.0, (min[1] + max[1]) / 2.0, (min[2] + max[2]) / 2.0)
        }
        (Shape::Sphere { center, .. }, _) => Pt3::new(center[0], center[1], center[2]),
        (Shape::Cylinder { a, b, .. }, _) => Pt3::new((a[0] + b[0]) / 2.0, (a[1] + b[1]) / 2.0, (a[2] + b[2]) / 2.0),
        (Shape::Subtract { base, .. }, _) => shape_center(base, None),
        _ => Pt3::origin(),
    }
}

impl Obstacles {
    /// The obstacles of `scene` placed at `t = 0`, meshes read from their (resolved) paths.
    pub fn new(scene: &Scene) -> Result<Self> {
        let mut solids = Vec::new();
        let mut add = |shape: &Shape, path: Option<&KinematicPath>, field: String| -> Result<()> {
            let (geom, center) = match shape {
                Shape::Mesh { path: file } => {
                    let q = load_mesh(file, &field)?;
                    let c = shape_center(shape, Some(&q));
                    (Geometry::Mesh(Arc::new(q)), c)
                }
                s => (Geometry::Analytic(s.clone()), shape_center(s, None)),
            };
            let path = path.filter(|p| !p.is_static()).cloned();
            solids.push(Solid { geom, path, pose: Iso3::identity(), inv: Iso3::identity(), center });
            Ok(())
        };
        for (k, s) in scene.obstacles.iter().enumerate() {
            add(s, None, format!("obstacles[{k}]"))?;
        }
        for (k, m) in scene.moving_obstacles.iter().enumerate() {
            add(&m.shape, Some(&m.path), format!("moving_obstacles[{k}]"))?;
        }
        let mut o = Self { solids, time: f64::NAN };
        o.set_time(0.0);
        Ok(o)
    }

    /// Number of obstacles.
    pub fn len(&self) -> usize {
        self.solids.len()
    }

    /// Whether there is no obstacle.
    pub fn is_empty(&self) -> bool {
        self.solids.is_empty()
    }

    /// Whether any obstacle moves.
    pub fn any_moving(&self) -> bool {
        self.solids.iter().any(|s| s.path.is_some())
    }

    /// Whether obstacle `k` moves.
    pub fn is_moving(&self, k: usize) -> bool {
        self.solids[k].path.is_some()
    }

    /// Places every moving obstacle at time `t` (s).
    pub fn set_time(&mut self, t: f64) {
        if t == self.time {
            return;
        }
        self.time = t;
        for s in &mut self.solids {
            if let Some(p) = &s.path {
                s.pose = p.transform(t);
                s.inv = s.pose.inverse();
            }
        }
    }

    /// The time the obstacles are placed at (s).
    pub fn time(&self) -> f64 {
        self.time
    }

    /// Signed distance to obstacle `k` (m, negative inside; a rigid placement keeps distances).
    pub fn sdf_of(&self, k: usize, x: &Pt3) -> f64 {
        let s = &self.solids[k];
        if s.path.is_some() {
            s.geom.sdf(&(s.inv * x))
        } else {
            s.geom.sdf(x)
        }
    }

    /// Union signed distance (m; +∞ without obstacles).
    pub fn sdf(&self, x: &Pt3) -> f64 {
        (0..self.solids.len()).map(|k| self.sdf_of(k, x)).fold(f64::INFINITY, f64::min)
    }

    /// Union signed distance of the static obstacles only (+∞ without).
    pub fn static_sdf(&self, x: &Pt3) -> f64 {
        (0..self.solids.len()).filter(|&k| !self.is_moving(k)).map(|k| self.sdf_of(k, x)).fold(f64::INFINITY, f64::min)
    }

    /// The union signed distance and the velocity (m/s) of the nearest obstacle at `x` (zero
    /// for a static one; `(+∞, 0)` without obstacles).
    pub fn sdf_velocity(&self, x: &Pt3) -> (f64, Vec3) {
        let mut best = (f64::INFINITY, usize::MAX);
        for k in 0..self.solids.len() {
            let d = self.sdf_of(k, x);
            if d < best.0 {
                best = (d, k);
            }
        }
        if best.1 == usize::MAX {
            return (best.0, Vec3::zeros());
        }
        (best.0, self.velocity_of(best.1, x))
    }

    /// Velocity (m/s) at time [`Self::time`] of the material point of obstacle `k` now at `x`.
    pub fn velocity_of(&self, k: usize, x: &Pt3) -> Vec3 {
        let s = &self.solids[k];
        match &s.path {
            Some(p) => p.velocity_at(self.time, &(s.inv * x)),
            None => Vec3::zeros(),
        }
    }

    /// Current position of obstacle `k`'s reference point (its rest centre, moved), the torque's
    /// reference (m).
    pub fn center(&self, k: usize) -> Pt3 {
        let s = &self.solids[k];
        s.pose * s.center
    }

    /// Per-tet velocity of the nearest obstacle at the tet centroid (m/s), for the projection's
    /// solid flux; `None` when no obstacle moves.
    pub fn tet_velocities(&self, mesh: &TetMesh) -> Option<Vec<Vec3>> {
        if !self.any_moving() {
            return None;
        }
        Some((0..mesh.tets.len()).into_par_iter().map(|t| self.sdf_velocity(&mesh.centroid[t]).1).collect())
    }

    /// Fluid fraction `w_t` per tet (spec §3.3: the volume fraction outside the obstacles of the
    /// linear interpolant of the union SDF at the nodes).
    pub fn fluid_fractions(&self, mesh: &TetMesh) -> Vec<f64> {
        let sdf = self.node_sdf(mesh);
        Self::fluid_fractions_from(mesh, &sdf)
    }

    /// The union SDF at the mesh nodes (m).
    pub fn node_sdf(&self, mesh: &TetMesh) -> Vec<f64> {
        mesh.nodes.par_iter().map(|x| self.sdf(x)).collect()
    }

    /// [`Self::fluid_fractions`] from the node SDF values `sdf`.
    pub fn fluid_fractions_from(mesh: &TetMesh, sdf: &[f64]) -> Vec<f64> {
        (0..mesh.tets.len())
            .into_par_iter()
            .map(|t| {
                let tv = mesh.tets[t];
                let p = tv.map(|i| mesh.nodes[i as usize]);
                let v = tv.map(|i| -sdf[i as usize]);
                (crate::surface::tet_liquid_volume(&p, &v) / mesh.volume[t]).clamp(0.0, 1.0)
            })
            .collect()
    }

    /// Force (N) and torque (N·m, about [`Self::center`]) of the liquid's gauge pressure on
    /// obstacle `k`: `F = −∮ p n dA`, `τ = −∮ (x − c) × p n dA` over the zero set of the linear
    /// interpolant of its SDF in each tet it cuts (a triangle or a quad per tet, `n` the
    /// obstacle's outward normal), with the P1 node pressures `pressure` (Pa; 0 at air and solid
    /// nodes) interpolated along the cut edges; the moment of the linear pressure over each
    /// triangle is integrated exactly (`∫ x p dA = A/12 (Σ xᵢpᵢ + Σxᵢ Σpᵢ)`). Parts of the
    /// boundary inside another obstacle or in air contribute nothing (zero pressure); a face
    /// lying on a closed domain wall would pick up the pressure of the wall nodes, so scene
    /// obstacles that touch a wall extend through it.
    pub fn pressure_force(&self, k: usize, mesh: &TetMesh, pressure: &[f64]) -> (Vec3, Vec3) {
        let sdf: Vec<f64> = mesh.nodes.par_iter().map(|x| self.sdf_of(k, x)).collect();
        let c = self.center(k);
        let parts: Vec<(Vec3, Vec3)> = (0..mesh.tets.len())
            .into_par_iter()
            .filter_map(|t| {
                let tv = mesh.tets[t];
                let s = tv.map(|i| sdf[i as usize]);
                let inside = s.map(|v| v < 0.0);
                let n_in = inside.iter().filter(|&&b| b).count();
                if n_in == 0 || n_in == 4 {
                    return None;
                }
                // Crossing points on the edges from an inside to an outside node, in an order
                // that walks the quad's boundary for the 2–2 case.
                let cross = |a: usize, b: usize| -> (Pt3, f64) {
                    let f = s[a] / (s[a] - s[b]);
                    let (xa, xb) = (mesh.nodes[tv[a] as usize], mesh.nodes[tv[b] as usize]);
                    let (pa, pb) = (pressure[tv[a] as usize], pressure[tv[b] as usize]);
                    (xa + (xb - xa) * f, pa + (pb - pa) * f)
                };
                let ins: Vec<usize> = (0..4).filter(|&a| inside[a]).collect();
                let outs: Vec<usize> = (0..4).filter(|&a| !inside[a]).collect();
                let poly: Vec<(Pt3, f64)> = match (ins.len(), outs.len()) {
                    (1, 3) => outs.iter().map(|&b| cross(ins[0], b)).collect(),
                    (3, 1) => ins.iter().map(|&a| cross(a, outs[0])).collect(),
                    _ => vec![
                        cross(ins[0], outs[0]),
                        cross(ins[0], outs[1]),
                        cross(ins[1], outs[1]),
                        cross(ins[1], outs[0]),
                    ],
                };
                // Outward normal of the obstacle: along the P1 gradient of its SDF.
                let g = &mesh.grad_bary[t];
                let grad = (0..4).fold(Vec3::zeros(), |acc, a| acc + g[a] * s[a]);
                let (mut f, mut tq) = (Vec3::zeros(), Vec3::zeros());
                for j in 1..poly.len() - 1 {
                    let tri = [poly[0], poly[j], poly[j + 1]];
                    let mut area = (tri[1].0 - tri[0].0).cross(&(tri[2].0 - tri[0].0)) / 2.0;
                    if area.dot(&grad) < 0.0 {
                        area = -area;
                    }
                    let a = area.norm();
                    if a == 0.0 {
                        continue;
                    }
                    let n = area / a;
                    let sum_p: f64 = tri.iter().map(|q| q.1).sum();
                    let sum_x = tri.iter().fold(Vec3::zeros(), |acc, q| acc + (q.0 - c));
                    let sum_xp = tri.iter().fold(Vec3::zeros(), |acc, q| acc + (q.0 - c) * q.1);
                    // ∫ p dA and ∫ (x − c) p dA over the triangle (p linear).
                    let ip = a * sum_p / 3.0;
                    let ixp = (sum_xp + sum_x * sum_p) * (a / 12.0);
                    f -= n * ip;
                    tq -= ixp.cross(&n);
                }
                Some((f, tq))
            })
            .collect();
        parts.iter().fold((Vec3::zeros(), Vec3::zeros()), |(f, t), (a, b)| (f + a, t + b))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn moving_box_sdf_and_velocity_follow_the_path() {
        let mut sc = Scene::new(([0.0; 3], [1.0; 3]), (4, 4), vec![]);
        sc.moving_obstacles = vec![MovingObstacle {
            shape: Shape::Box { min: [0.4, 0.0, 0.0], max: [0.6, 0.2, 1.0] },
            path: KinematicPath::Translate { velocity: Vec3::new(0.0, 2.0, 0.0) },
        }];
        let mut o = Obstacles::new(&sc).unwrap();
        assert!(o.any_moving());
        let x = Pt3::new(0.5, 0.3, 0.5);
        assert!((o.sdf(&x) - 0.1).abs() < 1e-12);
        o.set_time(0.1);
        assert!((o.sdf(&x) + 0.1).abs() < 1e-12, "the box moved up by 0.2 m");
        let (_, v) = o.sdf_velocity(&x);
        assert!((v - Vec3::new(0.0, 2.0, 0.0)).norm() < 1e-6);
        assert!((o.center(0) - Pt3::new(0.5, 0.3, 0.5)).norm() < 1e-12);
    }

    #[test]
    fn unreadable_mesh_is_an_error_naming_the_field() {
        let mut sc = Scene::new(([0.0; 3], [1.0; 3]), (4, 4), vec![]);
        sc.obstacles = vec![Shape::Mesh { path: "/nonexistent/box.obj".into() }];
        let e = Obstacles::new(&sc).unwrap_err().to_string();
        assert!(e.contains("obstacles[0]") && e.contains("box.obj"), "{e}");
    }
}

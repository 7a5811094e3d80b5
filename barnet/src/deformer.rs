//! [`BarNetDeformer`]: the character coupling of spec §3.4–3.6 on the procedural arm.
//!
//! Per frame: (1) LBS of the control mesh; (2) animated stiffness, if any: new q per group,
//! numeric refactorisation and new shape-holding loads `P0 = D X0 + D_f X0_f`; (3) loads
//! `P_i(t) = R_i(t) (p0_local_i + Σ_c m_c(driver) · scale_c · dir_local_c,i)` with `R_i` the
//! quaternion blend of node i's bones (§3.5); (4) one equilibrium solve
//! `D x = P − D_f y_fixed` (back-substitution only when q is constant); (5) the fine mesh
//! `S · control` (subdivision) or the wrap evaluation.
//!
//! With no channels the rest pose reproduces the control mesh exactly and a rigid motion of
//! every bone moves the free nodes rigidly (spec 7.3 a, b), because `D·1 + D_f·1 = 0` and the
//! loads rotate with the nodes.

use crate::arm::{Arm, ArmSpec};
use crate::error::{BarNetError, Result};
use crate::net::BarNet;
use crate::skin::{Chain, SkinBinding};
use crate::solver::{FdmOptions, FdmSolver};
use crate::subdiv::{self, Scheme};
use crate::wrap::WrapBinding;
use geom_core::graph::Ragged;
use geom_core::linalg::Csr;
use geom_core::math::{Curve1D, Iso3, Pt3, Vec3};
use geom_core::mesh::PolyMesh;
use serde::{Deserialize, Serialize};
use std::time::Instant;

/// A set of control-mesh nodes: a name the arm defines ([`Arm::named`]) or explicit indices.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum NodeSet {
    /// A named set of the procedural arm.
    Named(String),
    /// Explicit node indices.
    List(Vec<u32>),
}

/// Load direction in node-local terms (spec §3.5).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum DirLocal {
    /// Away from the closest bone axis (rest pose).
    Radial,
    /// Along the closest bone, towards the centroid of the channel's nodes.
    AxialToMiddle,
    /// An explicit rest-pose vector (same for every node).
    Vector([f64; 3]),
}

/// What drives a channel.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum DriverSpec {
    /// A joint's flexion angle (rad).
    JointAngle {
        /// Joint name.
        joint: String,
    },
    /// Time (s).
    Time,
    /// The constant 1 (the curve's value at 1).
    Constant,
}

/// One load channel ("muscle" handle) as written in a scene (spec §2.3).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LoadSpec {
    /// Channel name.
    pub name: String,
    /// Free nodes receiving the load.
    pub nodes: NodeSet,
    /// Direction.
    pub dir_local: DirLocal,
    /// Driver.
    pub driver: DriverSpec,
    /// Keys `(driver value, magnitude)` of the monotone cubic curve.
    pub curve: Vec<(f64, f64)>,
    /// Load scale (force units; spec §4).
    pub scale: f64,
}

/// A bar group: bars with at least one end in `nodes` get group `id` (first match wins).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GroupSpec {
    /// Group id.
    pub id: u32,
    /// Nodes whose bars join the group.
    pub nodes: NodeSet,
}

/// Animated force density of a group (spec §3.6): `q = curve(driver)`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StiffnessSpec {
    /// Group id.
    pub group: u32,
    /// Driver.
    pub driver: DriverSpec,
    /// Keys `(driver value, q)`.
    pub curve: Vec<(f64, f64)>,
}

/// The fine surface (spec §2.2 `FineSurface`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum FineSpec {
    /// `fine = S · control`.
    Subdivision {
        /// Scheme.
        scheme: Scheme,
        /// Levels.
        levels: u32,
    },
    /// The Catmull–Clark surface of `levels` (rest pose) taken as an arbitrary polygon mesh and
    /// bound to the control triangles by [`WrapBinding`] with `k_tris` triangles per vertex.
    Wrap {
        /// Levels of the rest fine mesh.
        levels: u32,
        /// Triangles per fine vertex.
        k_tris: usize,
    },
}

/// Everything that defines an arm deformer (spec §2.3).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DeformerConfig {
    /// The procedural arm.
    pub arm: ArmSpec,
    /// Half width (m) of the smoothstep skinning ramp at each joint.
    pub ramp_half_width: f64,
    /// Free nodes.
    pub free: NodeSet,
    /// Uniform force density of every bar.
    pub q: f64,
    /// Bar groups.
    #[serde(default)]
    pub groups: Vec<GroupSpec>,
    /// Load channels.
    #[serde(default)]
    pub loads: Vec<LoadSpec>,
    /// Stiffness channels.
    #[serde(default)]
    pub stiffness: Vec<StiffnessSpec>,
    /// Fine surface.
    pub fine: FineSpec,
    /// Optional clamp of each free node's displacement from its LBS position (m).
    #[serde(default)]
    pub max_disp: Option<f64>,
}

/// A resolved driver.
#[derive(Clone, Debug, PartialEq)]
pub enum Driver {
    /// Joint index.
    JointAngle(usize),
    /// Time.
    Time,
    /// Constant 1.
    Constant,
}

/// Driver values of one frame.
#[derive(Clone, Debug, Default)]
pub struct Drivers {
    /// Per joint: flexion angle (rad).
    pub joint_angles: Vec<f64>,
    /// Time (s).
    pub time: f64,
}

impl Driver {
    fn value(&self, d: &Drivers) -> f64 {
        match self {
            Driver::JointAngle(j) => d.joint_angles.get(*j).copied().unwrap_or(0.0),
            Driver::Time => d.time,
            Driver::Constant => 1.0,
        }
    }
}

/// A resolved load channel (spec §2.2).
#[derive(Clone, Debug)]
pub struct LoadChannel {
    /// Name.
    pub name: String,
    /// Free nodes (control-mesh indices).
    pub nodes: Vec<u32>,
    /// Per node: rest-pose (local) direction, unit.
    pub dir_local: Vec<Vec3>,
    /// Driver.
    pub driver: Driver,
    /// Driver → magnitude.
    pub curve: Curve1D,
    /// Scale.
    pub scale: f64,
}

/// A resolved stiffness channel.
#[derive(Clone, Debug)]
pub struct StiffnessChannel {
    /// Group.
    pub group: u32,
    /// Driver.
    pub driver: Driver,
    /// Driver → q.
    pub curve: Curve1D,
}

/// The fine layer.
#[derive(Clone, Debug)]
pub enum FineSurface {
    /// Subdivision operator and the fine faces.
    Subdivision {
        /// Scheme.
        scheme: Scheme,
        /// Levels.
        levels: u32,
        /// `fine = S · control`.
        op: Csr,
        /// Fine faces.
        faces: Ragged<u32>,
    },
    /// Wrap binding and the fine faces.
    Wrap {
        /// Binding.
        binding: WrapBinding,
        /// Fine faces.
        faces: Ragged<u32>,
        /// Scratch positions (f64).
        scratch: Vec<Pt3>,
    },
}

impl FineSurface {
    /// Fine faces.
    pub fn faces(&self) -> &Ragged<u32> {
        match self {
            FineSurface::Subdivision { faces, .. } | FineSurface::Wrap { faces, .. } => faces,
        }
    }

    /// Evaluates the fine positions from control positions.
    pub fn eval(&mut self, control: &[Pt3], out: &mut Vec<[f32; 3]>) {
        match self {
            FineSurface::Subdivision { op, .. } => {
                out.resize(op.nrows, [0.0; 3]);
                subdiv::apply_f32(op, control, out, false);
            }
            FineSurface::Wrap { binding, scratch, .. } => {
                scratch.resize(binding.len(), Pt3::origin());
                binding.eval(control, scratch);
                out.clear();
                out.extend(scratch.iter().map(|p| [p.x as f32, p.y as f32, p.z as f32]));
            }
        }
    }
}

/// Per-stage times of one frame (s).
#[derive(Clone, Copy, Debug, Default)]
pub struct FrameTimings {
    /// Control-mesh LBS.
    pub lbs: f64,
    /// Stiffness update (refactorisation and new P0), 0 when q is constant.
    pub stiffness: f64,
    /// Node frames and loads.
    pub loads: f64,
    /// Right-hand side and equilibrium solve.
    pub solve: f64,
    /// Fine surface.
    pub fine: f64,
    /// Whole frame.
    pub total: f64,
}

/// One frame's output (spec §2.2).
#[derive(Clone, Debug, Default)]
pub struct FrameOutput {
    /// Control mesh (free nodes from the bar-net, the rest LBS).
    pub control: Vec<Pt3>,
    /// Control mesh by LBS alone.
    pub lbs: Vec<Pt3>,
    /// Fine mesh.
    pub fine: Vec<[f32; 3]>,
    /// Relative equilibrium residual of the solve.
    pub residual: f64,
    /// Whether D was refactorised this frame.
    pub refactored: bool,
    /// Stage times.
    pub timings: FrameTimings,
}

/// The bar-net deformer; see the module docs.
pub struct BarNetDeformer {
    /// The arm (control mesh, joints, named sets).
    pub arm: Arm,
    /// The skinning chain.
    pub chain: Chain,
    /// Control-mesh skin weights.
    pub weights: SkinBinding,
    /// The net (bars = control edges with a free end).
    pub net: BarNet,
    /// The equilibrium solver.
    pub solver: FdmSolver,
    /// Shape-holding loads in the nodes' local (rest) frames, free-node order.
    pub p0_local: Vec<Vec3>,
    /// Load channels.
    pub loads: Vec<LoadChannel>,
    /// Stiffness channels.
    pub stiffness: Vec<StiffnessChannel>,
    /// Fine surface.
    pub fine: FineSurface,
    /// Displacement clamp.
    pub max_disp: Option<f64>,
    rest_free: Vec<Pt3>,
    rest_fixed: Vec<Pt3>,
    base_q: Vec<f64>,
    current_group_q: Vec<(u32, f64)>,
    /// Per free node: (channel, direction).
    node_channels: Vec<Vec<(usize, Vec3)>>,
    channel_mag: Vec<f64>,
}

fn resolve_nodes(arm: &Arm, s: &NodeSet) -> Result<Vec<u32>> {
    match s {
        NodeSet::Named(n) => arm.named(n),
        NodeSet::List(v) => {
            let n = arm.mesh.positions.len();
            if let Some(&bad) = v.iter().find(|&&i| i as usize >= n) {
                return Err(BarNetError::NodeOutOfRange { bar: usize::MAX, node: bad, n_nodes: n });
            }
            Ok(v.clone())
        }
    }
}

fn resolve_driver(chain: &Chain, d: &DriverSpec) -> Result<Driver> {
    Ok(match d {
        DriverSpec::JointAngle { joint } => Driver::JointAngle(chain.joint(joint)?),
        DriverSpec::Time => Driver::Time,
        DriverSpec::Constant => Driver::Constant,
    })
}

impl BarNetDeformer {
    /// Builds the deformer from a configuration: arm, LBS weights, net, factorisation, P0,
    /// channels and the fine operator. Errors: bad names, channels on fixed nodes, invalid nets.
    pub fn new(cfg: &DeformerConfig) -> Result<Self> {
        let arm = Arm::new(&cfg.arm)?;
        let chain = Chain { names: arm.joint_names.clone(), joints: arm.joints.clone() };
        let weights = SkinBinding::ramp(&chain, &arm.mesh.positions, cfg.ramp_half_width)?;
        let nv = arm.mesh.positions.len();
        let free_list = resolve_nodes(&arm, &cfg.free)?;
        let mut free = vec![false; nv];
        for &v in &free_list {
            free[v as usize] = true;
        }
        if !cfg.q.is_finite() {
            return Err(BarNetError::NonFinite { what: "config q", index: 0 });
        }
        let mut net = BarNet::from_mesh_edges(&arm.mesh, &free, cfg.q)?;
        for g in &cfg.groups {
            let nodes = resolve_nodes(&arm, &g.nodes)?;
            let mut in_set = vec![false; nv];
            for v in nodes {
                in_set[v as usize] = true;
            }
            for b in net.bars.iter_mut().filter(|b| b.group.is_none()) {
                if in_set[b.a as usize] || in_set[b.b as usize] {
                    b.group = Some(g.id);
                }
            }
        }
        let solver = FdmSolver::new(&net, &FdmOptions::default())?;
        let rest_free: Vec<Pt3> = solver.free_nodes().iter().map(|&v| arm.mesh.positions[v as usize]).collect();
        let rest_fixed: Vec<Pt3> = solver.fixed_nodes().iter().map(|&v| arm.mesh.positions[v as usize]).collect();
        // Rest frames are the identity (skinning transforms are relative to the rest pose), so
        // the local shape-holding loads equal the rest-pose ones.
        let p0_local = solver.rest_loads(&rest_free, &rest_fixed)?;
        let mut loads = Vec::new();
        let mut node_channels = vec![Vec::new(); solver.free_nodes().len()];
        for (ci, l) in cfg.loads.iter().enumerate() {
            let nodes = resolve_nodes(&arm, &l.nodes)?;
            if !l.scale.is_finite() {
                return Err(BarNetError::NonFinite { what: "load channel scale", index: ci });
            }
            let centroid = nodes.iter().fold(Vec3::zeros(), |a, &v| a + arm.mesh.positions[v as usize].coords)
                / nodes.len().max(1) as f64;
            let mut dirs = Vec::with_capacity(nodes.len());
            for &v in &nodes {
                if !free[v as usize] {
                    return Err(BarNetError::InvalidParameter(format!(
                        "load channel '{}': node {v} is fixed (loads act on free nodes only)",
                        l.name
                    )));
                }
                let p = arm.mesh.positions[v as usize];
                let j = chain.closest_bone(&p);
                let (c, axis) = chain.closest_on_bone(j, &p);
                let d = match &l.dir_local {
                    DirLocal::Radial => (p - c).normalize(),
                    DirLocal::AxialToMiddle => {
                        let s = (centroid - p.coords).dot(&axis);
                        if s.abs() < 1e-12 {
                            Vec3::zeros()
                        } else {
                            axis * s.signum()
                        }
                    }
                    DirLocal::Vector(x) => Vec3::new(x[0], x[1], x[2]),
                };
                if !d.iter().all(|x| x.is_finite()) {
                    return Err(BarNetError::NonFinite { what: "load direction", index: v as usize });
                }
                dirs.push(d);
                node_channels[solver.node_index()[v as usize] as usize].push((ci, d));
            }
            loads.push(LoadChannel {
                name: l.name.clone(),
                nodes,
                dir_local: dirs,
                driver: resolve_driver(&chain, &l.driver)?,
                curve: Curve1D::new(&l.curve)?,
                scale: l.scale,
            });
        }
        let mut stiffness = Vec::new();
        for s in &cfg.stiffness {
            if !net.bars.iter().any(|b| b.group == Some(s.group)) {
                return Err(BarNetError::InvalidParameter(format!("stiffness channel: group {} has no bar", s.group)));
            }
            stiffness.push(StiffnessChannel {
                group: s.group,
                driver: resolve_driver(&chain, &s.driver)?,
                curve: Curve1D::new(&s.curve)?,
            });
        }
        let fine = match &cfg.fine {
            FineSpec::Subdivision { scheme, levels } => {
                let (m, op) = subdiv::subdivide(&arm.mesh, *scheme, *levels)?;
                FineSurface::Subdivision { scheme: *scheme, levels: *levels, op, faces: m.faces }
            }
            FineSpec::Wrap { levels, k_tris } => {
                let (m, _) = subdiv::catmull_clark(&arm.mesh, *levels)?;
                let binding = WrapBinding::bind(&arm.mesh, &m.positions, *k_tris)?;
                FineSurface::Wrap { binding, faces: m.faces, scratch: Vec::new() }
            }
        };
        let base_q = net.q();
        let n_channels = loads.len();
        Ok(Self {
            arm,
            chain,
            weights,
            net,
            solver,
            p0_local,
            loads,
            stiffness,
            fine,
            max_disp: cfg.max_disp,
            rest_free,
            rest_fixed,
            base_q,
            current_group_q: Vec::new(),
            node_channels,
            channel_mag: vec![0.0; n_channels],
        })
    }

    /// The rest control mesh.
    pub fn control_rest(&self) -> &PolyMesh {
        &self.arm.mesh
    }

    /// Skinning transforms of the arm chain for an elbow flexion of `elbow` rad (rotation about
    /// +Z, bending the forearm towards the +Y front) and a rigid root motion.
    pub fn arm_pose(&self, elbow: f64, root: &Iso3) -> Result<Vec<Iso3>> {
        let r = geom_core::math::UnitQuat::from_axis_angle(&Vec3::z_axis(), elbow);
        self.chain.pose(&[geom_core::math::UnitQuat::identity(), r], root)
    }

    /// Deforms one frame with channel magnitudes from their curves.
    pub fn deform(&mut self, posed: &[Iso3], d: &Drivers, out: &mut FrameOutput) -> Result<()> {
        self.deform_with(posed, d, None, out)
    }

    /// Deforms one frame; `magnitudes` (one per load channel) overrides the curves (used by the
    /// inverse design of §3.8).
    pub fn deform_with(
        &mut self,
        posed: &[Iso3],
        d: &Drivers,
        magnitudes: Option<&[f64]>,
        out: &mut FrameOutput,
    ) -> Result<()> {
        let t0 = Instant::now();
        crate::error::check_len("posed bone transforms", self.chain.n_bones(), posed.len())?;
        let rest = &self.arm.mesh.positions;
        out.lbs.resize(rest.len(), Pt3::origin());
        self.weights.lbs(rest, posed, &mut out.lbs);
        let t1 = Instant::now();
        // Stiffness channels.
        out.refactored = false;
        if !self.stiffness.is_empty() {
            let gq: Vec<(u32, f64)> =
                self.stiffness.iter().map(|s| (s.group, s.curve.eval(s.driver.value(d)))).collect();
            if gq != self.current_group_q {
                let q: Vec<f64> = self
                    .net
                    .bars
                    .iter()
                    .zip(&self.base_q)
                    .map(|(b, &q0)| b.group.and_then(|g| gq.iter().find(|x| x.0 == g)).map_or(q0, |x| x.1))
                    .collect();
                self.solver.update_q(&q)?;
                self.p0_local = self.solver.rest_loads(&self.rest_free, &self.rest_fixed)?;
                self.current_group_q = gq;
                out.refactored = true;
            }
        }
        let t2 = Instant::now();
        for (c, ch) in self.loads.iter().enumerate() {
            let m = match magnitudes {
                Some(m) => *m.get(c).ok_or(BarNetError::DimensionMismatch {
                    what: "channel magnitudes",
                    expected: self.loads.len(),
                    got: m.len(),
                })?,
                None => ch.curve.eval(ch.driver.value(d)),
            };
            self.channel_mag[c] = m * ch.scale;
        }
        let free = self.solver.free_nodes();
        let mut p = Vec::with_capacity(free.len());
        for (i, &v) in free.iter().enumerate() {
            let mut local = self.p0_local[i];
            for &(c, dir) in &self.node_channels[i] {
                local += dir * self.channel_mag[c];
            }
            p.push(self.weights.rotation(v as usize, posed) * local);
        }
        let fixed: Vec<Pt3> = self.solver.fixed_nodes().iter().map(|&v| out.lbs[v as usize]).collect();
        let t3 = Instant::now();
        let mut x = Vec::with_capacity(free.len());
        let info = self.solver.solve_into(&p, &fixed, &mut x)?;
        out.residual = info.rel_residual;
        out.control.clear();
        out.control.extend_from_slice(&out.lbs);
        for (i, &v) in free.iter().enumerate() {
            let mut xi = x[i];
            if let Some(md) = self.max_disp {
                let y = out.lbs[v as usize];
                let dv = xi - y;
                if dv.norm() > md {
                    xi = y + dv * (md / dv.norm());
                }
            }
            out.control[v as usize] = xi;
        }
        let t4 = Instant::now();
        self.fine.eval(&out.control, &mut out.fine);
        let t5 = Instant::now();
        out.timings = FrameTimings {
            lbs: (t1 - t0).as_secs_f64(),
            stiffness: (t2 - t1).as_secs_f64(),
            loads: (t3 - t2).as_secs_f64(),
            solve: (t4 - t3).as_secs_f64(),
            fine: (t5 - t4).as_secs_f64(),
            total: (t5 - t0).as_secs_f64(),
        };
        Ok(())
    }
}

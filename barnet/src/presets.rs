//! The paper's setups (Zhang, Yang and Zhao 2007, Figure 3; spec §6.1): the procedural arm with
//! the 12-free-node biceps/triceps bar-net, its biceps-bulge load channel, and the same net as a
//! bare [`BarNet`] with its rest state for the nonlinear comparison (spec §6.6, §7.5, §7.6).
//!
//! ```
//! use barnet::deformer::{BarNetDeformer, Drivers, FrameOutput};
//! use barnet::presets;
//! use geom_core::math::Iso3;
//! let mut cfg = presets::biceps_arm();
//! cfg.loads.push(presets::biceps_bulge());
//! let mut d = BarNetDeformer::new(&cfg).unwrap();
//! let pose = d.arm_pose(1.5, &Iso3::identity()).unwrap();
//! let mut out = FrameOutput::default();
//! d.deform(&pose, &Drivers { joint_angles: vec![0.0, 1.5, 0.0], time: 0.0 }, &mut out).unwrap();
//! assert!(out.residual <= 1e-12);
//! assert_eq!(out.fine.len(), 2848); // Catmull–Clark level 2: the paper's 2816 faces
//! ```

use geom_core::math::{Pt3, Vec3};

use crate::arm::{Arm, ArmSpec};
use crate::deformer::{DeformerConfig, DirLocal, DriverSpec, FineSpec, LoadSpec, NodeSet};
use crate::error::Result;
use crate::net::BarNet;
use crate::subdiv::Scheme;

/// Half width (m) of the smoothstep skinning ramp at each joint of the arm scenes.
pub const ARM_RAMP_HALF_WIDTH: f64 = 0.04;

/// The muscle example of Figure 3 without load channels: the default procedural arm (8 × 23
/// open tube), smoothstep ramps of half width [`ARM_RAMP_HALF_WIDTH`], the 12 free nodes
/// `biceps_triceps_12`, uniform q = 1, Catmull–Clark level 2 skin (2816 faces).
pub fn biceps_arm() -> DeformerConfig {
    DeformerConfig {
        arm: ArmSpec::default(),
        ramp_half_width: ARM_RAMP_HALF_WIDTH,
        free: NodeSet::Named("biceps_triceps_12".into()),
        q: 1.0,
        groups: vec![],
        loads: vec![],
        stiffness: vec![],
        fine: FineSpec::Subdivision { scheme: Scheme::CatmullClark, levels: 2 },
        max_disp: None,
    }
}

/// The biceps bulge channel: radial loads on the middle biceps ring driven by the elbow angle
/// (0 at rest, 0.6 at 90°, 1 at 137.5°; scale 0.02 force units).
pub fn biceps_bulge() -> LoadSpec {
    LoadSpec {
        name: "biceps_bulge".into(),
        nodes: NodeSet::Named("biceps_mid".into()),
        dir_local: DirLocal::Radial,
        driver: DriverSpec::JointAngle { joint: "elbow".into() },
        curve: vec![(0.0, 0.0), (1.57, 0.6), (2.4, 1.0)],
        scale: 0.02,
    }
}

/// The biceps/triceps net of [`biceps_arm`] as a bare bar-net at rest (q = 1), for the
/// nonlinear comparison.
#[derive(Clone, Debug)]
pub struct ArmNet {
    /// The net (edges of the arm's control mesh; the 12 muscle nodes free).
    pub net: BarNet,
    /// Rest positions of the free nodes (free-node order, m).
    pub free: Vec<Pt3>,
    /// Rest positions of the fixed nodes (fixed-node order, m).
    pub fixed: Vec<Pt3>,
    /// Rest length of every bar (m).
    pub bar_len: Vec<f64>,
    /// Unit radial directions on the middle biceps ring (free-node order; zero elsewhere): the
    /// biceps-bulge load pattern.
    pub biceps_pattern: Vec<Vec3>,
}

impl ArmNet {
    /// Mean bar length (m).
    pub fn mean_edge(&self) -> f64 {
        self.bar_len.iter().sum::<f64>() / self.bar_len.len() as f64
    }
}

/// The default arm's 12-free-node net (see [`ArmNet`]).
pub fn arm_net() -> Result<ArmNet> {
    let arm = Arm::new(&ArmSpec::default())?;
    let mut free = vec![false; arm.mesh.positions.len()];
    for v in arm.named("biceps_triceps_12")? {
        free[v as usize] = true;
    }
    let net = BarNet::from_mesh_edges(&arm.mesh, &free, 1.0)?;
    let (fr, fx, index) = net.index_maps();
    let pos = &arm.mesh.positions;
    let xf: Vec<Pt3> = fr.iter().map(|&v| pos[v as usize]).collect();
    let xs: Vec<Pt3> = fx.iter().map(|&v| pos[v as usize]).collect();
    let bar_len = net.bars.iter().map(|b| (pos[b.a as usize] - pos[b.b as usize]).norm()).collect();
    let mut pattern = vec![Vec3::zeros(); fr.len()];
    for v in arm.named("biceps_mid")? {
        let p = pos[v as usize];
        pattern[index[v as usize] as usize] = Vec3::new(0.0, p.y, p.z).normalize();
    }
    Ok(ArmNet { net, free: xf, fixed: xs, bar_len, biceps_pattern: pattern })
}

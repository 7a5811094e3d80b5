//! Bends the procedural arm with a biceps bar-net and prints bulge, residual and frame time.
//!
//! `cargo run -p barnet --example arm`

use barnet::deformer::{
    BarNetDeformer, DeformerConfig, DirLocal, DriverSpec, Drivers, FineSpec, FrameOutput, LoadSpec, NodeSet,
};
use barnet::subdiv::Scheme;
use geom_core::math::Iso3;

fn main() -> Result<(), barnet::BarNetError> {
    let cfg = DeformerConfig {
        arm: Default::default(),
        ramp_half_width: 0.04,
        free: NodeSet::Named("biceps_triceps_12".into()),
        q: 1.0,
        groups: vec![],
        loads: vec![LoadSpec {
            name: "biceps_bulge".into(),
            nodes: NodeSet::Named("biceps_mid".into()),
            dir_local: DirLocal::Radial,
            driver: DriverSpec::JointAngle { joint: "elbow".into() },
            curve: vec![(0.0, 0.0), (1.57, 0.6), (2.4, 1.0)],
            scale: 0.02,
        }],
        stiffness: vec![],
        fine: FineSpec::Subdivision { scheme: Scheme::CatmullClark, levels: 2 },
        max_disp: None,
    };
    let mut d = BarNetDeformer::new(&cfg)?;
    let mut out = FrameOutput::default();
    for deg in [0.0f64, 45.0, 90.0, 140.0] {
        let a = deg.to_radians();
        let pose = d.arm_pose(a, &Iso3::identity())?;
        d.deform(&pose, &Drivers { joint_angles: vec![0.0, a, 0.0], time: 0.0 }, &mut out)?;
        let bulge = out.control.iter().zip(&out.lbs).map(|(c, l)| (c - l).norm()).fold(0.0, f64::max);
        println!(
            "elbow {deg:5.1}°: max control offset from LBS {:.2} mm, residual {:.1e}, frame {:.1} µs, {} fine vertices",
            bulge * 1e3,
            out.residual,
            out.timings.total * 1e6,
            out.fine.len()
        );
    }
    Ok(())
}

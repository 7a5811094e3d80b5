//! Bends the procedural arm with a biceps bar-net and prints bulge, residual and frame time.
//!
//! `cargo run -p barnet --example arm`

use barnet::deformer::{BarNetDeformer, Drivers, FrameOutput};
use barnet::metrics::max_distance;
use barnet::presets::{biceps_arm, biceps_bulge};
use geom_core::math::Iso3;

fn main() -> Result<(), barnet::BarNetError> {
    let mut cfg = biceps_arm();
    cfg.loads.push(biceps_bulge());
    let mut d = BarNetDeformer::new(&cfg)?;
    let mut out = FrameOutput::default();
    for deg in [0.0f64, 45.0, 90.0, 140.0] {
        let a = deg.to_radians();
        let pose = d.arm_pose(a, &Iso3::identity())?;
        d.deform(&pose, &Drivers { joint_angles: vec![0.0, a, 0.0], time: 0.0 }, &mut out)?;
        let bulge = max_distance(&out.control, &out.lbs);
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

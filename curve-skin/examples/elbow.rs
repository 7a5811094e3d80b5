//! Bends the cylinder arm 90° with LBS, DQS and curve skinning and prints the joint radius ratio,
//! volume ratio and largest distance to the bones of each (the collapsing-elbow comparison).
//!
//! `cargo run -p curve-skin --example elbow`

use curve_skin::curve::{build_curve_skeleton, JointCurveDefaults, TopologyRules};
use curve_skin::metrics::{distance_to_bones, joint_radius_ratio, signed_volume};
use curve_skin::poses::{axis_deg, SkinPose};
use curve_skin::procedural::{cylinder_arm, ramp_weights, Ramp};
use curve_skin::{CurveOptions, CurveSkin, DeformOutput, Dqs, Lbs, PackedWeights, Skinner};
use geom_core::math::{Pt3, Vec3};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let r = 0.15;
    let (mesh, sk) = cylinder_arm(r, 1.0, 200, 48)?;
    let w2 = ramp_weights(&mesh.positions, 0.0, r, Ramp::SmoothStep);
    let w4 = PackedWeights::<4> {
        bone: w2.bone.iter().map(|b| [b[0], b[1], 0, 0]).collect(),
        w: w2.w.iter().map(|x| [x[0], x[1], 0.0, 0.0]).collect(),
    };
    let rest = mesh.positions_f32();
    let cs = build_curve_skeleton(&sk, &TopologyRules::default(), &JointCurveDefaults::default());
    let mut methods: Vec<(&str, Box<dyn Skinner>)> = vec![
        ("LBS", Box::new(Lbs::new(rest.clone(), None, w4.clone())?)),
        ("DQS", Box::new(Dqs::new(rest.clone(), None, w4)?)),
        ("curve", Box::new(CurveSkin::new(&sk, cs, &mesh.positions, None, CurveOptions::default())?)),
    ];
    let mut pose = SkinPose::rest(&sk);
    pose.set_world(&sk, 1, axis_deg(Vec3::z(), 90.0));
    let posed = pose.globals(&sk);
    let j: Vec<Pt3> = posed.iter().map(|f| Pt3::from(f.translation.vector)).collect();
    let v0 = signed_volume(&mesh.positions, &mesh.tris);
    let mut out = vec![[0f32; 3]; rest.len()];
    println!("method  joint radius ratio  volume ratio  max dist/R");
    for (name, s) in methods.iter_mut() {
        s.prepare(&sk, &posed)?;
        s.deform(DeformOutput { positions: &mut out, normals: None });
        let jr = joint_radius_ratio(&out, &mesh.positions, j[1], Pt3::origin(), r, 0.006);
        let v = signed_volume(&out, &mesh.tris) / v0;
        let side = &out[..out.len() - 2];
        let (_, hi) = distance_to_bones(side, &[(j[0], j[1]), (j[1], j[2])]);
        println!("{name:6}  {jr:18.4}  {v:12.4}  {:10.4}", hi / r);
    }
    Ok(())
}

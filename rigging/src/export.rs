//! Text outputs of a rig: the embedded skeleton as an OBJ of joints and bone lines.

use std::fmt::Write as _;

use geom_core::math::Pt3;

use crate::template::SkeletonTemplate;

/// The embedded skeleton as OBJ text: one vertex per joint (commented with its name), one `l`
/// line element per bone (spec §6: skeletons are written as line elements).
pub fn skeleton_obj(sk: &SkeletonTemplate, joints: &[Pt3]) -> String {
    let mut s = String::from("# embedded skeleton: one vertex per joint, one line per bone\n");
    for (j, p) in joints.iter().enumerate() {
        let _ = writeln!(s, "v {} {} {} # {}", p.x, p.y, p.z, sk.joints[j].name);
    }
    for (p, c) in sk.bones() {
        let _ = writeln!(s, "l {} {}", p + 1, c + 1);
    }
    s
}

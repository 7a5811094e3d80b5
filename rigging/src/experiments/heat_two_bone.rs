//! `rigging/heat-two-bone` (paper Fig. 8; spec §6.5, §7.4 d, f, g): bone-heat weights across the
//! single joint of a bent two-capsule arm, and the width of the weight transition on a straight
//! two-bone cylinder against its radius (it should scale with the distance from the joint to the
//! surface: doubling the radius doubles the width).
//!
//! Outputs: table `weights_lines` (forearm weight along the outer and inner side of the bend) and
//! the arm posed at 0, 45 and 90° of extra elbow bend (`posed_<deg>.obj`).
//!
//! ```no_run
//! use geom_core::experiment::{BySize, Size};
//! use geom_core::record::NullRecorder;
//! use rigging::experiments::heat_two_bone::{run, Params};
//! let p = Params { radius: 0.06, widths: (0.04, 0.08), h_rel: BySize::Same(0.25) };
//! let r = run(&p, Size::Quick, &mut NullRecorder::default()).unwrap();
//! println!("transition ratio {}", r.get_f64("transition_ratio"));
//! ```

use geom_core::anim::skin::lbs;
use geom_core::experiment::{BySize, Report, Size, Target};
use geom_core::io::{obj, MeshOut};
use geom_core::math::{Iso3, Pt3, UnitQuat, Vec3};
use geom_core::record::Recorder;
use serde::Deserialize;

use crate::error::{Result, RigError};
use crate::heat::{bone_heat, bone_heat_raw};
use crate::metrics::transition_width;
use crate::presets::{bent_arm_joints, straight_arm_joints, two_capsules};
use crate::RigOptions;

/// Parameters (the scene file's `params` block).
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Params {
    /// Radius (normalized units) of the bent arm.
    pub radius: f64,
    /// Cylinder radii of the transition-width check (small, large).
    pub widths: (f64, f64),
    /// Grid spacing of the polygonizer as a fraction of the radius.
    pub h_rel: BySize<f64>,
}

/// The 0.1 → 0.9 transition width of the child-bone weight along the straight two-bone cylinder
/// of radius `r` polygonized at spacing `h` (samples with 0.2 ≤ x < 0.8).
pub fn straight_transition_width(r: f64, h: f64) -> Result<f64> {
    let (a, b, c) = straight_arm_joints();
    let m = two_capsules(a, b, c, r, h)?;
    let (w, _) = bone_heat_raw(&m, &[[a, b], [b, c]], &RigOptions::default())?;
    let n = m.n_vertices();
    let samples: Vec<(f64, f64)> =
        (0..n).filter(|&j| (0.2..0.8).contains(&m.positions[j].x)).map(|j| (m.positions[j].x, w[n + j])).collect();
    transition_width(&samples, 0.1, 0.9).ok_or_else(|| {
        RigError::Degenerate(format!("no 0.1 → 0.9 transition of the child weight on the cylinder of radius {r}"))
    })
}

/// Runs the experiment. Figures: `transition_width_small`, `transition_width_large` (normalized
/// units), `transition_ratio` (large / small; expected 2), `radius_ratio`, `partition_err_raw`
/// (max |Σ w − 1| before post-processing), `min_raw_weight`, `residual_max` (relative residual
/// of the heat solves).
pub fn run(p: &Params, size: Size, rec: &mut dyn Recorder) -> Result<Report> {
    let hr = p.h_rel.get(size);
    let (a, b, c) = bent_arm_joints();
    let r = p.radius;
    let m = two_capsules(a, b, c, r, hr * r)?;
    let bones = [[a, b], [b, c]];
    let (w, rep) = bone_heat_raw(&m, &bones, &RigOptions::default())?;
    let n = m.n_vertices();
    rec.table("weights_lines", &["side", "arc", "x", "y", "w_forearm"])?;
    // Outer side: z ≈ 0.5 plane, outside the bend (x > 0.5 or y < 0.3); inner side: inside.
    for j in 0..n {
        let x = m.positions[j];
        if (x.z - 0.5).abs() > 0.25 * r {
            continue;
        }
        let outer = x.x > b.x + 0.5 * r || x.y < b.y - 0.5 * r;
        let side = if outer { "outer" } else { "inner" };
        let arc = if x.y <= b.y { x.x - b.x } else { x.y - b.y };
        rec.row("weights_lines", &[side.into(), arc.into(), x.x.into(), x.y.into(), w[n + j].into()])?;
    }
    // Posed at 0, 45, 90 degrees of extra elbow bend (about z through the elbow).
    let (sw, _) = bone_heat(&m, &bones, &RigOptions::default())?;
    for deg in [0.0f64, 45.0, 90.0] {
        let rot = Iso3::rotation_wrt_point(UnitQuat::from_axis_angle(&Vec3::z_axis(), deg.to_radians()), b);
        let t = [Iso3::identity(), rot];
        let mut out = vec![Pt3::origin(); n];
        lbs(&m.positions, &sw, &t, &mut out);
        if rec.keeps_outputs() {
            let text = obj::to_string(&MeshOut::tri(&out, &m.faces))?;
            rec.file(&format!("posed_{deg:.0}.obj"), text.as_bytes())?;
        }
    }
    // Both cylinders at the spacing of the smaller one, so only the radius changes.
    let w1 = straight_transition_width(p.widths.0, hr * p.widths.0)?;
    let w2 = straight_transition_width(p.widths.1, hr * p.widths.0)?;
    let mut s = Report::default();
    s.num("transition_width_small", w1)
        .num("transition_width_large", w2)
        .num("transition_ratio", w2 / w1)
        .num("radius_ratio", p.widths.1 / p.widths.0)
        .num("partition_err_raw", rep.partition_err_raw)
        .num("min_raw_weight", rep.min_raw)
        .num("residual_max", rep.residual_max);
    s.check("transition_ratio", Target::Within(1.8, 2.2), "spec §7.4 g: the width doubles with the radius (2 ± 0.2)")
        .check("partition_err_raw", Target::AtMost(1e-8), "spec §7.4 d: partition of unity before post-processing")
        .check("residual_max", Target::AtMost(1e-10), "spec §7.4 f: relative residual of the heat solves");
    Ok(s)
}

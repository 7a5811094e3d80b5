//! Spec §7.5 g, h on the capsule humanoid: at most 3 curves per vertex with weights summing to
//! 1, positional continuity across mesh edges for poses with joint angles ≤ 90°, mostly one
//! curve per vertex, and the LBS influence statistic.

use curve_skin::curve::{build_curve_skeleton, JointCurveDefaults, TopologyRules};
use curve_skin::metrics::{histogram_mean, influences_histogram};
use curve_skin::poses::{humanoid_pose, walk_pose};
use curve_skin::procedural::{humanoid, inverse_distance_weights};
use curve_skin::{CurveOptions, CurveSkin, Skinner};
use geom_core::math::Pt3;

#[test]
fn humanoid_curve_weights_and_continuity() {
    let h = humanoid(0.3).unwrap();
    let cs = build_curve_skeleton(&h.skeleton, &TopologyRules::default(), &JointCurveDefaults::default());
    let mut cur = CurveSkin::new(&h.skeleton, cs, &h.mesh.positions, None, CurveOptions::default()).unwrap();
    let b = &cur.binding;
    for v in 0..b.len() {
        let r = b.row(v);
        assert!((1..=3).contains(&r.len()), "vertex {v}: {} curves", r.len());
        let s: f64 = r.map(|e| b.w[e]).sum();
        assert!((s - 1.0).abs() < 1e-6);
    }
    // 7.5 h: ≥ 60 % of vertices with exactly one curve.
    let hist = influences_histogram(&b.offsets);
    let one = hist[1] as f64 / b.len() as f64;
    assert!(one >= 0.6, "one-curve fraction {one}");
    // LBS inverse-distance weights thresholded at 0.01: mean ≥ 2 influences.
    let rows = inverse_distance_weights(&h.mesh.positions, &h.skeleton, 4.0, 0.01);
    let mut lh = vec![0usize; 32];
    for r in &rows {
        lh[r.len()] += 1;
    }
    assert!(histogram_mean(&lh) >= 2.0, "{}", histogram_mean(&lh));

    // 7.5 g: |x'_a − x'_b| ≤ 3 |x_a − x_b| on every edge for poses with joint angles ≤ 90°.
    let mut poses =
        vec![humanoid_pose(&h.skeleton, "elbows_90").unwrap(), humanoid_pose(&h.skeleton, "twist_90").unwrap()];
    poses.extend((0..6).map(|i| walk_pose(&h.skeleton, 0.18 * i as f64)));
    let mut out = vec![Pt3::origin(); h.mesh.positions.len()];
    for (k, p) in poses.iter().enumerate() {
        cur.reset_history();
        cur.twist_hint = p.twist_hint.clone();
        cur.prepare(&h.skeleton, &p.globals(&h.skeleton)).unwrap();
        cur.deform_f64(&mut out);
        let mut worst: f64 = 0.0;
        for t in &h.mesh.tris {
            for e in 0..3 {
                let (a, c) = (t[e] as usize, t[(e + 1) % 3] as usize);
                let d0 = (h.mesh.positions[a] - h.mesh.positions[c]).norm();
                let d1 = (out[a] - out[c]).norm();
                worst = worst.max(d1 / d0);
            }
        }
        assert!(worst <= 3.0, "pose {k}: edge stretch {worst}");
    }
}

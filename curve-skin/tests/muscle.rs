//! Spec §3.4.8: muscle action lines are bound like skin vertices and deformed by the same curve
//! frames; the bulge thickens a shortened muscle and leaves the rest of the skin alone.

mod common;

use common::*;
use curve_skin::curve::{ActionLine, MuscleBulge};
use curve_skin::metrics::signed_volume;
use curve_skin::{CurveOptions, DeformOutput, Skinner};
use geom_core::math::Pt3;

#[test]
fn action_line_follows_the_skin_and_shortens_inside_the_bend() {
    let a = arm(100, 32);
    let mut cur = curve_skin(&a, CurveOptions::default());
    // Control points = skin vertices on the +y side (the inside of a positive bend about z).
    let on_side: Vec<usize> = (0..a.mesh.positions.len() - 2)
        .filter(|&v| {
            let p = a.mesh.positions[v];
            p.y > 0.149 && p.x > -0.7 && p.x < 0.5
        })
        .collect();
    assert!(on_side.len() > 10);
    let idx: Vec<usize> = on_side.iter().step_by(on_side.len() / 8).copied().collect();
    let inside = ActionLine::new(idx.iter().map(|&v| a.mesh.positions[v]).collect()).unwrap();
    let outside = ActionLine::new(inside.control_points.iter().map(|p| Pt3::new(p.x, -0.12, p.z)).collect()).unwrap();
    let mut prev = 1.0 + 1e-12;
    for bend in [0.0, 45.0, 90.0, 135.0] {
        let (posed, _) = arm_pose(&a.sk, bend, 0.0);
        cur.prepare(&a.sk, &posed).unwrap();
        let mut skin = vec![Pt3::origin(); a.mesh.positions.len()];
        cur.deform_f64(&mut skin);
        let mut line = Vec::new();
        inside.deform(&cur, &mut line);
        // Bound exactly like skin vertices: identical to the skin at the same rest points.
        for (k, &v) in idx.iter().enumerate() {
            assert!((line[k] - skin[v]).norm() < 1e-12, "{bend}: point {k}");
        }
        // Inside of the bend shortens monotonically; the outside line lengthens.
        let r_in = inside.length_ratio(&line);
        assert!(r_in < prev, "{bend}: {r_in} ≥ {prev}");
        prev = r_in;
        let mut out_line = Vec::new();
        outside.deform(&cur, &mut out_line);
        let r_out = outside.length_ratio(&out_line);
        if bend > 0.0 {
            assert!(r_in < 1.0 && r_out > 1.0, "{bend}: {r_in} {r_out}");
        } else {
            assert!((r_in - 1.0).abs() < 1e-12 && (r_out - 1.0).abs() < 1e-12);
        }
    }
}

#[test]
fn bulge_adds_volume_near_the_muscle_only() {
    let a = arm(100, 32);
    let mut cur = curve_skin(&a, CurveOptions::default());
    let line =
        ActionLine::new(vec![Pt3::new(-0.7, 0.1, 0.0), Pt3::new(-0.2, 0.11, 0.0), Pt3::new(0.3, 0.1, 0.0)]).unwrap();
    let bulge = MuscleBulge::new(&line, &a.mesh.positions, 0.04, 0.1).unwrap();
    assert!(!bulge.is_empty());
    let (posed, _) = arm_pose(&a.sk, 90.0, 0.0);
    cur.prepare(&a.sk, &posed).unwrap();
    let mut plain = vec![[0f32; 3]; a.mesh.positions.len()];
    cur.deform(DeformOutput { positions: &mut plain, normals: None });
    let mut lp = Vec::new();
    line.deform(&cur, &mut lp);
    let ratio = line.length_ratio(&lp);
    assert!(ratio < 0.95, "{ratio}");
    let mut bulged = plain.clone();
    bulge.apply(&lp, ratio, &mut bulged);
    let v0 = signed_volume(&plain, &a.mesh.tris);
    let v1 = signed_volume(&bulged, &a.mesh.tris);
    assert!(v1 > v0, "{v1} ≤ {v0}");
    // Vertices farther than `influence` from the rest line (e.g. the −y side) do not move.
    let mut moved = 0;
    for (v, p) in a.mesh.positions.iter().enumerate() {
        let near = p.y > 0.0 && p.x > -0.8 && p.x < 0.4;
        if bulged[v] != plain[v] {
            moved += 1;
            assert!(near, "vertex {v} at {p} moved");
        }
    }
    assert!(moved > 0 && moved <= bulge.len());
}

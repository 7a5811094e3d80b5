//! Rigging a user's mesh (issue 23): orientation found from the shape, any scale, non-manifold
//! vertices split, a bounded search on the long-necked quadruped, refusals that name the defect.

use geom_core::math::Pt3;
use rigging::character::{rig_character, CharacterOptions};
use rigging::characters::test_params;
use rigging::export::RigFile;
use rigging::orient::{Axis, Orientation};
use rigging::presets::{humanoid_character, long_necked_quadruped};
use rigging::{RigError, RigOptions, SkeletonTemplate};

fn options() -> CharacterOptions {
    CharacterOptions { rig: RigOptions { tau: 0.005, ..Default::default() }, ..Default::default() }
}

/// Joint distance over the height, after turning `b` (input axes of `ob`) back upright.
fn max_err(a: &[Pt3], b: &[Pt3], ob: &Orientation, h: f64) -> f64 {
    a.iter().zip(b).map(|(x, y)| (x - ob.point_to_canonical(y)).norm() / h).fold(0.0, f64::max)
}

#[test]
fn z_up_minus_z_and_plus_x_facing_copies_give_the_same_rig() {
    let (mesh, _) = humanoid_character(&test_params(1000), 3000).expect("character");
    let sk = SkeletonTemplate::human();
    let h = mesh.aabb().size().y;
    let upright = rig_character(&mesh.positions, &mesh.faces, &sk, &options()).expect("rigs upright");
    assert_eq!(upright.orientation, Orientation::default(), "{:?}", upright.detection);
    for o in [
        Orientation::new(Axis::PosZ, Axis::NegY).unwrap(),
        Orientation::new(Axis::PosY, Axis::NegZ).unwrap(),
        Orientation::new(Axis::PosY, Axis::PosX).unwrap(),
    ] {
        let turned: Vec<Pt3> = mesh.positions.iter().map(|p| o.point_from_canonical(p)).collect();
        let r = rig_character(&turned, &mesh.faces, &sk, &options()).expect("rigs turned");
        assert_eq!(r.orientation, o, "detected {} for {o}: {:?}", r.orientation, r.detection);
        let e = max_err(&upright.joints, &r.joints, &o, h);
        assert!(e <= 0.02, "{o}: joints off by {e} of the height");
        // Given axes skip the detection and give the same rig.
        let given = CharacterOptions { up: Some(o.up), front: Some(o.front), ..options() };
        let g = rig_character(&turned, &mesh.faces, &sk, &given).expect("rigs with given axes");
        assert!(g.detection.is_none());
        assert!(max_err(&upright.joints, &g.joints, &o, h) <= 0.02);
    }
}

#[test]
fn any_scale_rigs_the_same_way() {
    let (mesh, _) = humanoid_character(&test_params(1001), 3000).expect("character");
    let sk = SkeletonTemplate::human();
    let o = CharacterOptions { up: Some(Axis::PosY), front: Some(Axis::PosZ), ..options() };
    let a = rig_character(&mesh.positions, &mesh.faces, &sk, &o).expect("rigs at 1");
    let big: Vec<Pt3> = mesh.positions.iter().map(|p| Pt3::from(p.coords * 150.0)).collect();
    let b = rig_character(&big, &mesh.faces, &sk, &o).expect("rigs at 150");
    let h = mesh.aabb().size().y;
    for (x, y) in a.joints.iter().zip(&b.joints) {
        assert!((x - y / 150.0).norm() <= 1e-6 * h, "{x} vs {}", y / 150.0);
    }
    // Weights agree to f32 rounding of the rescaled solve.
    let (wa, wb) = (&a.rig.weights, &b.rig.weights);
    assert!(wa.offsets == wb.offsets && wa.joint == wb.joint, "same influences");
    let d = wa.w.iter().zip(&wb.w).map(|(x, y)| (x - y).abs()).fold(0.0f32, f32::max);
    assert!(d <= 1e-5, "weights differ by {d}");
}

#[test]
fn a_non_manifold_vertex_is_split_and_rigged() {
    let (mesh, _) = humanoid_character(&test_params(1002), 3000).expect("character");
    let sk = SkeletonTemplate::human();
    // Pinch the surface: vertex w (at least three rings from v) is merged into v.
    let v = 0u32;
    let ring = |set: &std::collections::BTreeSet<u32>| {
        let mut out = set.clone();
        for t in &mesh.faces {
            if t.iter().any(|x| set.contains(x)) {
                out.extend(t.iter().copied());
            }
        }
        out
    };
    let near = ring(&ring(&ring(&[v].into())));
    let w = (0..mesh.n_vertices() as u32)
        .filter(|x| !near.contains(x))
        .min_by(|a, b| {
            let d = |x: u32| (mesh.positions[x as usize] - mesh.positions[v as usize]).norm();
            d(*a).total_cmp(&d(*b))
        })
        .expect("a far vertex");
    let mut pos = mesh.positions.clone();
    pos[w as usize] = pos[v as usize];
    let faces: Vec<[u32; 3]> = mesh.faces.iter().map(|t| t.map(|x| if x == w { v } else { x })).collect();
    let o = CharacterOptions { up: Some(Axis::PosY), front: Some(Axis::PosZ), ..options() };
    let r = rig_character(&pos, &faces, &sk, &o).expect("a pinched vertex is repaired");
    assert_eq!(r.rig.diagnostics.prep.split_vertices, 1);
    let file = RigFile::new(&r, &pos, &faces).expect("rig file");
    file.validate().expect("valid rig file");
    for (k, row) in file.weights.iter().enumerate() {
        if k != w as usize {
            let s: f32 = row.iter().map(|x| x.1).sum();
            assert!((s - 1.0).abs() < 1e-5, "vertex {k}: {row:?}");
        }
    }
    // A hole cannot be repaired: refused, naming the defect.
    let e = rig_character(&pos, &faces[3..], &sk, &o).unwrap_err();
    assert!(matches!(e, RigError::NotClosed { .. }) && e.to_string().contains("not closed"), "{e}");
}

#[test]
fn long_necked_quadruped_returns_within_the_search_budget() {
    let (mesh, truth) = long_necked_quadruped(3, 0.5, 6000).expect("quadruped");
    let sk = SkeletonTemplate::quadruped();
    let o = CharacterOptions {
        up: Some(Axis::PosY),
        front: Some(Axis::PosZ),
        rig: RigOptions { tau: 0.004, ..Default::default() },
        ..Default::default()
    };
    let r = rig_character(&mesh.positions, &mesh.faces, &sk, &o).expect("rigs");
    let d = &r.rig.discrete;
    assert!(d.expanded <= o.rig.max_expansions, "{} expansions", d.expanded);
    // The embedded head is on the neck's side of the body, above the shoulders.
    let (head, sh) = (r.joints[4], truth.rest[0]);
    assert!(head.z > sh.z && head.y > sh.y, "head {head} shoulders {sh}");
}

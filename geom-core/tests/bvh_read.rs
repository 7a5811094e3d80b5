//! BVH reader/writer tests (motion-graph.md §7.1 tests 2–5, §8 hard cases): the CMU clips,
//! hand-computed forward kinematics, round trips, every `BvhError` with its line number.

use geom_core::anim::bvh::{self, BvhOptions, BvhUnits, BvhWriteOptions, FrameCount};
use geom_core::anim::{Channel, JointRole, Motion};
use geom_core::math::{euler_to_quat, Pt3, RotOrder, UnitQuat};
use geom_core::rng::Rng;
use geom_core::{BvhError, Error};
use std::path::PathBuf;

fn mocap(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../assets/mocap").join(name)
}

fn positions(m: &Motion, f: usize) -> Vec<Pt3> {
    let mut p = vec![Pt3::origin(); m.n_joints()];
    m.joint_positions(f, &mut p);
    p
}

/// Largest joint-position difference over all frames, joints matched by name (end sites, whose
/// names BVH does not store, by index).
fn max_position_diff(a: &Motion, b: &Motion) -> f64 {
    assert_eq!(a.len(), b.len());
    assert_eq!(a.n_joints(), b.n_joints());
    let map: Vec<usize> =
        a.skeleton
            .joints
            .iter()
            .enumerate()
            .map(|(i, j)| {
                if j.end_site {
                    i
                } else {
                    b.skeleton.find(&j.name).expect("joint missing after round trip") as usize
                }
            })
            .collect();
    let mut worst = 0.0f64;
    for f in 0..a.len() {
        let pa = positions(a, f);
        let pb = positions(b, f);
        for (i, &k) in map.iter().enumerate() {
            worst = worst.max((pa[i] - pb[k]).norm());
        }
    }
    worst
}

fn read_err(text: &str) -> BvhError {
    read_err_with(text, &BvhOptions::default())
}

fn read_err_with(text: &str, o: &BvhOptions) -> BvhError {
    match bvh::read(text, o) {
        Err(Error::Bvh(e)) => {
            assert!(!e.to_string().is_empty());
            e
        }
        Err(e) => panic!("expected a BvhError, got {e}"),
        Ok(_) => panic!("expected an error"),
    }
}

/// A small valid file: root with 6 channels, one joint, an end site; two frames (lines 19–20).
const SMALL: &str = "HIERARCHY
ROOT Hips
{
\tOFFSET 0 0 0
\tCHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation
\tJOINT Chest
\t{
\t\tOFFSET 0 10 0
\t\tCHANNELS 3 Zrotation Xrotation Yrotation
\t\tEnd Site
\t\t{
\t\t\tOFFSET 0 5 0
\t\t}
\t}
}
MOTION
Frames: 2
Frame Time: 0.04
1 2 3 0 0 0 0 0 0
1 2 3 90 0 0 0 90 0
";

// ---------------------------------------------------------------------------------------------
// CMU clips

fn check_cmu(file: &str, frames: usize) {
    let text = std::fs::read_to_string(mocap(file)).unwrap();
    let info = bvh::inspect(&text).unwrap();
    assert_eq!(info.declared_frames, frames);
    assert_eq!(info.rows_present, frames);
    assert!(!info.count_mismatch());
    assert_eq!(info.channels, 96);
    assert_eq!(info.joint_count(), 31);
    assert_eq!(info.end_site_count(), 7);
    assert_eq!(info.auto_units, BvhUnits::CmuAsf);
    assert!((info.frame_time - 1.0 / 120.0).abs() <= 1e-6);
    assert!(info.to_string().contains("LeftToeBase"));

    let m = bvh::read(&text, &BvhOptions::default()).unwrap();
    assert_eq!(m.len(), frames);
    assert_eq!(m.n_joints(), 38);
    assert!((m.frame_time - 1.0 / 120.0).abs() <= 1e-6);
    let s = &m.skeleton;
    // CMU hierarchy and roles (motion-graph.md §2.1 table).
    let name = |r: JointRole| s.role(r).map(|j| s.joints[j as usize].name.clone());
    assert_eq!(name(JointRole::Root).as_deref(), Some("Hips"));
    assert_eq!(name(JointRole::Spine).as_deref(), Some("LowerBack"));
    assert_eq!(name(JointRole::Chest).as_deref(), Some("Spine1"));
    assert_eq!(name(JointRole::LeftCollar).as_deref(), Some("LeftShoulder"));
    assert_eq!(name(JointRole::LeftShoulder).as_deref(), Some("LeftArm"));
    assert_eq!(name(JointRole::LeftAnkle).as_deref(), Some("LeftFoot"));
    assert_eq!(name(JointRole::RightToe).as_deref(), Some("RightToeBase"));
    assert_eq!(name(JointRole::HeadTop).as_deref(), Some("Head_End"));
    let lhip = s.find("LHipJoint").unwrap();
    assert_eq!(s.joints[s.find("LeftUpLeg").unwrap() as usize].parent, Some(lhip));
    assert!(s.joints.iter().all(|j| j.end_site || j.channels.len() == 3 || j.parent.is_none()));
    assert_eq!(s.joints[0].channels[3..], [Channel::Zrot, Channel::Yrot, Channel::Xrot]);
    // Leg length ≈ 16 units × 0.056444 ≈ 0.90 m.
    assert!((s.leg_length() - 0.90).abs() < 0.03, "{}", s.leg_length());
    // Rest pose: left hip at larger x than the right hip.
    let rest = s.rest_globals();
    let lx = rest[s.role(JointRole::LeftHip).unwrap() as usize].translation.x;
    let rx = rest[s.role(JointRole::RightHip).unwrap() as usize].translation.x;
    assert!(lx > rx);
    // 5th percentile of the lowest joint height over the clip within [−0.05, 0.10] m.
    let mut lowest: Vec<f64> =
        (0..m.len()).map(|f| positions(&m, f).iter().map(|p| p.y).fold(f64::INFINITY, f64::min)).collect();
    lowest.sort_by(f64::total_cmp);
    let p5 = lowest[lowest.len() * 5 / 100];
    assert!((-0.05..=0.10).contains(&p5), "p5 lowest = {p5}");
    // Hip height at frame 0 within [0.85, 1.10] m.
    let hip = positions(&m, 0)[0].y;
    assert!((0.85..=1.10).contains(&hip), "hip height {hip}");
    // Quaternions are hemisphere-continuous.
    let nj = m.n_joints();
    for f in 1..m.len() {
        for j in 0..nj {
            assert!(m.rot[f * nj + j].coords.dot(&m.rot[(f - 1) * nj + j].coords) >= 0.0);
        }
    }

    // Round trip read → write → read: joint positions equal to 1e-6 m on every frame.
    let text2 = bvh::write(&m, &BvhWriteOptions::default());
    let back = bvh::read(&text2, &BvhOptions::default()).unwrap();
    assert_eq!(back.len(), m.len());
    assert_eq!(back.skeleton.joints.len(), m.skeleton.joints.len());
    let err = max_position_diff(&m, &back);
    assert!(err <= 1e-6, "{file}: round trip error {err} m");
}

#[test]
fn cmu_01_01() {
    check_cmu("01_01.bvh", 2752);
}

#[test]
fn cmu_01_03() {
    check_cmu("01_03.bvh", 4511);
}

#[test]
fn cmu_round_trip_in_other_units_and_read_file() {
    let m = bvh::read_file(mocap("01_01.bvh"), &BvhOptions::default()).unwrap();
    let m = m.slice(0, 200);
    for units in [BvhUnits::CmuAsf, BvhUnits::Metres, BvhUnits::Inches] {
        let t = bvh::write(&m, &BvhWriteOptions { units, decimals: 6 });
        let back = bvh::read(&t, &BvhOptions { units, ..Default::default() }).unwrap();
        let err = max_position_diff(&m, &back);
        assert!(err <= 1e-6, "{units:?}: {err}");
    }
    assert!(matches!(bvh::read_file(mocap("missing.bvh"), &BvhOptions::default()), Err(Error::Io(_))));
}

// ---------------------------------------------------------------------------------------------
// Forward kinematics by hand (§7.1 test 2)

#[test]
fn three_joint_fk_with_90_degree_rotations() {
    // Root at (1,2,3) m, rotated 90° about z; chest offset (0,10,0) cm rotated 90° about x;
    // end site (0,5,0) cm.
    let m = bvh::read(SMALL, &BvhOptions { units: BvhUnits::Centimetres, ..Default::default() }).unwrap();
    assert_eq!(m.len(), 2);
    assert_eq!(m.n_joints(), 3);
    assert_eq!(m.skeleton.joints[2].name, "Chest_End");
    assert!(m.skeleton.joints[2].end_site);
    let p = positions(&m, 1);
    let root = Pt3::new(0.01, 0.02, 0.03);
    // Rz(90)·(0, 0.1, 0) = (−0.1, 0, 0).
    let chest = root + nalgebra::Vector3::new(-0.1, 0.0, 0.0);
    // Chest global = Rz(90)·Rx(90); applied to (0, 0.05, 0): Rx(90)·(0,.05,0) = (0,0,.05), Rz(90) keeps it.
    let end = chest + nalgebra::Vector3::new(0.0, 0.0, 0.05);
    for (got, want) in p.iter().zip([root, chest, end]) {
        assert!((got - want).norm() <= 1e-12, "{got} vs {want}");
    }
    // Frame 0: rest pose.
    let p0 = positions(&m, 0);
    assert!((p0[2] - Pt3::new(0.01, 0.17, 0.03)).norm() <= 1e-12);
}

// ---------------------------------------------------------------------------------------------
// Synthetic skeleton with every rotation order (§7.1 test 3)

fn mixed_order_bvh(frames: usize, seed: u64) -> String {
    let orders = [
        "Xrotation Yrotation Zrotation",
        "Xrotation Zrotation Yrotation",
        "Yrotation Xrotation Zrotation",
        "Yrotation Zrotation Xrotation",
        "Zrotation Xrotation Yrotation",
        "Zrotation Yrotation Xrotation",
    ];
    // Channel kinds of a row: 'p' position, 'r' rotation, 'm' middle rotation of a triple.
    let mut kinds = String::from("ppprmr");
    let mut t = String::from(
        "HIERARCHY\nROOT Root\n{\n  OFFSET 1 2 3\n  CHANNELS 6 Xposition Yposition Zposition Yrotation Xrotation Zrotation\n",
    );
    for (i, o) in orders.iter().enumerate() {
        t += &format!("  JOINT J{i}\n  {{\n    OFFSET {} {} {}\n", 0.3 + 0.1 * i as f64, -0.4, 0.25);
        if i == 2 {
            // Position channels on a non-root joint, mixed in with the rotations.
            t += &format!("    CHANNELS 6 Xposition {o} Zposition Yposition\n");
            kinds += "prmrpp";
        } else {
            t += &format!("    CHANNELS 3 {o}\n");
            kinds += "rmr";
        }
    }
    // Two rotation channels and a zero-channel joint.
    t += "  JOINT Two\n  {\n    OFFSET 0 0.7 0\n    CHANNELS 2 Zrotation Xrotation\n  JOINT None\n  {\n    OFFSET 0 0 0.4\n    CHANNELS 0\n    End Site\n    {\n      OFFSET 0.1 0.1 0.1\n    }\n  }\n  }\n";
    kinds += "rm";
    for _ in 0..6 {
        t += "  }\n";
    }
    t += "}\n";
    let mut rng = Rng::new(seed);
    t += &format!("MOTION\nFrames: {frames}\nFrame Time: 0.0333333\n");
    for f in 0..frames {
        let row: Vec<String> = kinds
            .chars()
            .map(|k| match k {
                'p' => format!("{:.5}", rng.range(-1.0, 1.0)),
                // Every 5th frame puts the middle angles at ±90° (gimbal lock).
                'm' if f % 5 == 4 => (if rng.f64() < 0.5 { "90" } else { "-90" }).to_string(),
                _ => format!("{:.4}", rng.range(-180.0, 180.0)),
            })
            .collect();
        t += &row.join(" ");
        t += "\n";
    }
    t
}

#[test]
fn mixed_orders_round_trip() {
    let text = mixed_order_bvh(40, 5);
    // The nesting above: J0..J5 chained, Two and None inside J5.
    let m = bvh::read(&text, &BvhOptions { units: BvhUnits::Metres, ..Default::default() }).unwrap();
    assert_eq!(m.len(), 40);
    assert!(m.extra_trans.is_some());
    let j2 = m.skeleton.find("J2").unwrap() as usize;
    assert_eq!(m.skeleton.joints[j2].channels.len(), 6);
    for units in [BvhUnits::Metres, BvhUnits::Centimetres] {
        let w = bvh::write(&m, &BvhWriteOptions { units, decimals: 6 });
        let back = bvh::read(&w, &BvhOptions { units, ..Default::default() }).unwrap();
        let err = max_position_diff(&m, &back);
        assert!(err <= 1e-6, "{units:?}: {err}");
        // The stored layout (channel orders) is preserved.
        for (a, b) in m.skeleton.joints.iter().zip(&back.skeleton.joints) {
            assert_eq!(a.channels, b.channels, "{}", a.name);
            assert_eq!(a.name, b.name);
        }
    }
    // Reading: the rotation equals the explicit product of the listed axes.
    let j4 = m.skeleton.find("J4").unwrap() as usize; // Zrotation Xrotation Yrotation
    let row: Vec<f64> = text
        .lines()
        .nth(text.lines().position(|l| l.starts_with("Frame Time")).unwrap() + 1)
        .unwrap()
        .split_whitespace()
        .map(|v| v.parse().unwrap())
        .collect();
    // Channel offset of J4: root 6 + J0 3 + J1 3 + J2 6 + J3 3 = 21.
    let a: Vec<f64> = row[21..24].iter().map(|d: &f64| d.to_radians()).collect();
    let want = euler_to_quat(RotOrder::ZXY, [a[0], a[1], a[2]]);
    assert!(m.frame_rot(0)[j4].angle_to(&want) < 1e-12);
}

#[test]
fn synthetic_humanoid_round_trip() {
    // A motion built in code on the standard humanoid (root offset 0.95 m), written and read back.
    let s = std::sync::Arc::new(geom_core::anim::Skeleton::standard_humanoid());
    let mut rng = Rng::new(8);
    let poses: Vec<_> = (0..30)
        .map(|_| {
            let mut p = s.rest_pose();
            p.root_pos += nalgebra::Vector3::new(rng.range(-1.0, 1.0), rng.range(-0.1, 0.1), rng.range(-1.0, 1.0));
            for (j, q) in p.rot.iter_mut().enumerate() {
                if !s.joints[j].end_site {
                    *q = UnitQuat::from_scaled_axis(rng.unit_vec3() * rng.range(0.0, 3.0));
                }
            }
            p
        })
        .collect();
    let m = Motion::from_poses(s, 1.0 / 30.0, &poses).unwrap();
    let w = bvh::write(&m, &BvhWriteOptions::default());
    let back = bvh::read(&w, &BvhOptions::default()).unwrap();
    assert!((back.skeleton.joints[0].offset - m.skeleton.joints[0].offset).norm() < 1e-15);
    assert!(max_position_diff(&m, &back) <= 1e-6);
    // End sites come back as `<parent>_End`, which still map to the tip roles.
    assert_eq!(back.skeleton.roles, m.skeleton.roles);
}

// ---------------------------------------------------------------------------------------------
// Units

#[test]
fn auto_units_pick_by_leg_length() {
    // Leg drop 92 units → centimetres; 0.92 → metres; 36 → inches; 16 → CMU.
    for (leg, want) in
        [(92.0, BvhUnits::Centimetres), (0.92, BvhUnits::Metres), (36.0, BvhUnits::Inches), (16.0, BvhUnits::CmuAsf)]
    {
        let text = format!(
            "HIERARCHY\nROOT Hips\n{{\nOFFSET 0 0 0\nCHANNELS 3 Zrotation Xrotation Yrotation\nJOINT LeftUpLeg\n{{\nOFFSET 0 {} 0\nCHANNELS 3 Zrotation Xrotation Yrotation\nJOINT LeftFoot\n{{\nOFFSET 0 {} 0\nCHANNELS 3 Zrotation Xrotation Yrotation\n}}\n}}\n}}\nMOTION\nFrames: 1\nFrame Time: 0.01\n0 0 0 0 0 0 0 0 0\n",
            -leg / 2.0,
            -leg / 2.0
        );
        assert_eq!(bvh::inspect(&text).unwrap().auto_units, want, "leg {leg}");
        let m = bvh::read(&text, &BvhOptions::default()).unwrap();
        assert!((m.skeleton.leg_length() - leg * want.scale().unwrap()).abs() < 1e-12);
    }
    let m = bvh::read(SMALL, &BvhOptions { units: BvhUnits::Scale(2.0), ..Default::default() }).unwrap();
    assert_eq!(m.skeleton.joints[1].offset.y, 20.0);
    assert!(matches!(
        bvh::read(SMALL, &BvhOptions { units: BvhUnits::Scale(-1.0), ..Default::default() }),
        Err(Error::InvalidParameter(_))
    ));
}

#[test]
fn options_from_ron() {
    let o: BvhOptions = ron::from_str("(units: Centimetres, frame_count: Lenient)").unwrap();
    assert_eq!(o, BvhOptions { units: BvhUnits::Centimetres, frame_count: FrameCount::Lenient, roles: None });
    let o: BvhOptions = ron::from_str("(units: Scale(0.5))").unwrap();
    assert_eq!(o.units, BvhUnits::Scale(0.5));
}

#[test]
fn role_override() {
    let mut roles = std::collections::BTreeMap::new();
    roles.insert(JointRole::Chest, "Chest".to_string());
    roles.insert(JointRole::Head, "Chest_End".to_string());
    let m = bvh::read(SMALL, &BvhOptions { roles: Some(roles.clone()), ..Default::default() }).unwrap();
    assert_eq!(m.skeleton.role(JointRole::Head), Some(2));
    assert_eq!(m.skeleton.role(JointRole::Chest), Some(1));
    roles.insert(JointRole::Neck, "Nope".to_string());
    let e = bvh::read(SMALL, &BvhOptions { roles: Some(roles), ..Default::default() });
    assert!(matches!(e, Err(Error::InvalidParameter(m)) if m.contains("Nope")));
}

// ---------------------------------------------------------------------------------------------
// Whitespace variants

#[test]
fn crlf_tabs_bom_and_blank_lines() {
    let base = bvh::read(SMALL, &BvhOptions::default()).unwrap();
    let crlf = format!("\u{feff}{}", SMALL.replace('\n', "\r\n\r\n").replace('\t', " \t  "));
    let m = bvh::read(&crlf, &BvhOptions::default()).unwrap();
    assert_eq!(m.rot, base.rot);
    assert_eq!(m.root_pos, base.root_pos);
    // Rows split over several lines and several rows on one line: a token stream.
    let joined = SMALL.replace("0 0 0 0 0 0\n1 2 3", "0 0 0 0 0 0 1 2 3").replace("90 0 0 0", "90 0\n0 0");
    let m = bvh::read(&joined, &BvhOptions::default()).unwrap();
    assert_eq!(m.rot, base.rot);
    // Channel names are case-insensitive.
    let m = bvh::read(&SMALL.replace("Zrotation", "ZROTATION"), &BvhOptions::default()).unwrap();
    assert_eq!(m.rot, base.rot);
}

// ---------------------------------------------------------------------------------------------
// Every BvhError variant, with its line number (§7.1 test 5)

#[test]
fn error_truncated() {
    let text = SMALL.replace("Frames: 2", "Frames: 3");
    assert_eq!(read_err(&text), BvhError::Truncated { line: 20, declared: 3, found: 2 });
    // A row cut in the middle.
    let cut = &SMALL[..SMALL.len() - 6];
    assert_eq!(read_err(cut), BvhError::Truncated { line: 20, declared: 2, found: 1 });
}

#[test]
fn error_unbalanced_braces() {
    // Missing the root's closing brace: MOTION arrives inside the hierarchy (line 15).
    let text = SMALL.replacen("}\nMOTION", "MOTION", 1);
    assert_eq!(read_err(&text), BvhError::UnbalancedBraces { line: 15 });
    // One closing brace too many (line 16).
    let text = SMALL.replacen("}\nMOTION", "}\n}\nMOTION", 1);
    assert_eq!(read_err(&text), BvhError::UnbalancedBraces { line: 16 });
    // Missing opening brace after a joint name (line 7 holds OFFSET instead).
    let text = SMALL.replacen("\t{\n\t\tOFFSET 0 10 0", "\t\tOFFSET 0 10 0", 1);
    assert_eq!(read_err(&text), BvhError::UnbalancedBraces { line: 7 });
    // End of file inside the hierarchy.
    assert_eq!(read_err(&SMALL[..SMALL.find("\t}\n}").unwrap()]), BvhError::UnbalancedBraces { line: 13 });
}

#[test]
fn error_bad_frame_time() {
    for (ft, text) in [("0", "0"), ("-0.1", "-0.1"), ("abc", "abc"), ("inf", "inf"), ("NaN", "NaN")] {
        let t = SMALL.replace("Frame Time: 0.04", &format!("Frame Time: {ft}"));
        assert_eq!(read_err(&t), BvhError::BadFrameTime { line: 18, text: text.into() });
    }
    let t = SMALL.replace("Frame Time: 0.04", "Frame Rate: 25");
    assert_eq!(read_err(&t), BvhError::BadFrameTime { line: 18, text: "Rate:".into() });
}

#[test]
fn error_bad_number() {
    let t = SMALL.replace("1 2 3 90 0 0", "1 2 3 nan 0 0");
    assert_eq!(read_err(&t), BvhError::BadNumber { line: 20, text: "nan".into() });
    let t = SMALL.replace("1 2 3 90 0 0", "1 2 3 inf 0 0");
    assert_eq!(read_err(&t), BvhError::BadNumber { line: 20, text: "inf".into() });
    let t = SMALL.replace("OFFSET 0 10 0", "OFFSET 0 1O 0");
    assert_eq!(read_err(&t), BvhError::BadNumber { line: 8, text: "1O".into() });
    let t = SMALL.replace("Frames: 2", "Frames: two");
    assert_eq!(read_err(&t), BvhError::BadNumber { line: 17, text: "two".into() });
}

#[test]
fn error_repeated_axis() {
    let t = SMALL.replace("CHANNELS 3 Zrotation Xrotation Yrotation", "CHANNELS 3 Xrotation Xrotation Zrotation");
    assert_eq!(read_err(&t), BvhError::RepeatedAxis { line: 9, joint: "Chest".into() });
}

#[test]
fn error_unknown_keyword() {
    let t = SMALL.replace("JOINT Chest", "JIONT Chest");
    assert_eq!(read_err(&t), BvhError::UnknownKeyword { line: 6, keyword: "JIONT".into() });
    let e = read_err(&SMALL.replace("HIERARCHY", "HIERARCHIE"));
    assert!(matches!(e, BvhError::UnknownKeyword { line: 1, .. }));
    // End Site without OFFSET (line 12 holds the closing brace).
    let t = SMALL.replace("\t\t\tOFFSET 0 5 0\n", "");
    let e = read_err(&t);
    assert!(
        matches!(&e, BvhError::UnknownKeyword { line: 12, keyword } if keyword.contains("End Site without OFFSET")),
        "{e:?}"
    );
    // Empty input.
    assert!(matches!(read_err(""), BvhError::UnknownKeyword { line: 1, .. }));
}

#[test]
fn error_duplicate_joint() {
    let t = SMALL.replace("JOINT Chest", "JOINT Hips");
    assert_eq!(read_err(&t), BvhError::DuplicateJoint { line: 6, name: "Hips".into() });
}

#[test]
fn error_channel_count() {
    // Fewer names than declared: 'End' (line 10) is not a channel.
    let t = SMALL.replace("CHANNELS 3 Zrotation Xrotation Yrotation", "CHANNELS 4 Zrotation Xrotation Yrotation");
    assert!(matches!(read_err(&t), BvhError::ChannelCount { line: 10, .. }));
    // More names than declared.
    let t = SMALL.replace("CHANNELS 3 Zrotation Xrotation Yrotation", "CHANNELS 2 Zrotation Xrotation Yrotation");
    assert!(matches!(read_err(&t), BvhError::ChannelCount { line: 9, .. }));
    // Unknown channel name and a non-numeric count.
    let t = SMALL.replace("CHANNELS 3 Zrotation Xrotation Yrotation", "CHANNELS 3 Zrotation Xrotation Wrotation");
    assert!(matches!(read_err(&t), BvhError::ChannelCount { line: 9, msg } if msg.contains("Wrotation")));
    let t = SMALL.replace("CHANNELS 3 Zrotation", "CHANNELS three Zrotation");
    assert!(matches!(read_err(&t), BvhError::ChannelCount { line: 9, .. }));
    // A repeated position channel.
    let t = SMALL.replace("Xposition Yposition Zposition", "Xposition Xposition Zposition");
    assert!(matches!(read_err(&t), BvhError::ChannelCount { line: 5, .. }));
}

#[test]
fn error_no_frames() {
    let t = SMALL.replace("Frames: 2", "Frames: 0");
    assert_eq!(read_err(&t), BvhError::NoFrames { line: 17 });
    // No MOTION section at all.
    let t = &SMALL[..SMALL.find("MOTION").unwrap()];
    assert_eq!(read_err(t), BvhError::NoFrames { line: 15 });
    // Lenient reading with no complete row.
    let t = SMALL.replace("1 2 3 0 0 0 0 0 0\n1 2 3 90 0 0 0 90 0\n", "1 2 3\n");
    let e = read_err_with(&t, &BvhOptions { frame_count: FrameCount::Lenient, ..Default::default() });
    assert_eq!(e, BvhError::NoFrames { line: 17 });
}

// ---------------------------------------------------------------------------------------------
// Hard cases (§8)

#[test]
fn zero_frames_is_an_error_but_inspect_reports_it() {
    let t = SMALL.replace("Frames: 2", "Frames: 0");
    assert!(bvh::read(&t, &BvhOptions::default()).is_err());
    let info = bvh::inspect(&t).unwrap();
    assert_eq!(info.declared_frames, 0);
    assert_eq!(info.rows_present, 2);
    assert!(info.count_mismatch());
    assert!(info.to_string().contains("MISMATCH"));
}

#[test]
fn single_frame() {
    let t = SMALL.replace("Frames: 2", "Frames: 1").replace("1 2 3 90 0 0 0 90 0\n", "");
    let m = bvh::read(&t, &BvhOptions::default()).unwrap();
    assert_eq!(m.len(), 1);
    assert_eq!(m.duration(), 0.0);
    assert_eq!(m.resample(0.01).unwrap().len(), 1);
    assert_eq!(m.time_stretch(4).len(), 4);
}

#[test]
fn joints_without_channels() {
    // CHANNELS 0, and no CHANNELS line at all.
    for chest in ["\t\tCHANNELS 0\n", ""] {
        let t = SMALL
            .replace("\t\tCHANNELS 3 Zrotation Xrotation Yrotation\n", chest)
            .replace("1 2 3 0 0 0 0 0 0\n", "1 2 3 0 0 0\n")
            .replace("1 2 3 90 0 0 0 90 0\n", "1 2 3 90 0 0\n");
        let metres = BvhOptions { units: BvhUnits::Metres, ..Default::default() };
        let m = bvh::read(&t, &metres).unwrap();
        assert!(m.skeleton.joints[1].channels.is_empty());
        let p = positions(&m, 1);
        // Root rotated 90° about z carries the chest (0,10,0) to (−10,0,0).
        assert!((p[1] - Pt3::new(1.0 - 10.0, 2.0, 3.0)).norm() < 1e-12, "{}", p[1]);
        let w = bvh::write(&m, &BvhWriteOptions { units: BvhUnits::Metres, decimals: 6 });
        assert!(w.contains("CHANNELS 0\n"));
        let back = bvh::read(&w, &metres).unwrap();
        assert!(max_position_diff(&m, &back) < 1e-6);
    }
    // A skeleton with no channels at all: frames are the rows (lines) after Frame Time.
    let t = "HIERARCHY\nROOT A\n{\nOFFSET 0 0 0\nEnd Site\n{\nOFFSET 0 1 0\n}\n}\nMOTION\nFrames: 3\nFrame Time: 0.1\n\n\n\n";
    let m = bvh::read(t, &BvhOptions::default()).unwrap();
    assert_eq!(m.len(), 3);
    let w = bvh::write(&m, &BvhWriteOptions::default());
    assert_eq!(bvh::read(&w, &BvhOptions::default()).unwrap().len(), 3);
    let huge = t.replace("Frames: 3", "Frames: 999999999999");
    assert!(matches!(read_err(&huge), BvhError::Truncated { found: 3, .. }));
}

#[test]
fn huge_declared_count_with_few_rows() {
    let t = SMALL.replace("Frames: 2", "Frames: 18446744073709551615");
    match read_err(&t) {
        BvhError::Truncated { declared, found, .. } => assert_eq!((declared, found), (usize::MAX, 2)),
        e => panic!("{e:?}"),
    }
    let m = bvh::read(&t, &BvhOptions { frame_count: FrameCount::Lenient, ..Default::default() }).unwrap();
    assert_eq!(m.len(), 2);
    let info = bvh::inspect(&t).unwrap();
    assert_eq!((info.declared_frames, info.rows_present), (usize::MAX, 2));
}

#[test]
fn extra_and_missing_rows() {
    // One extra row: strict keeps the declared count, lenient keeps all; the info reports it.
    let t = format!("{SMALL}5 5 5 0 0 0 0 0 0\n");
    let (m, info) = bvh::read_with_info(&t, &BvhOptions::default()).unwrap();
    assert_eq!(m.len(), 2);
    assert_eq!((info.declared_frames, info.rows_present), (2, 3));
    let m = bvh::read(&t, &BvhOptions { frame_count: FrameCount::Lenient, ..Default::default() }).unwrap();
    assert_eq!(m.len(), 3);
    // Strict mode does not even parse rows beyond the declared count.
    let junk = format!("{SMALL}garbage\n");
    assert_eq!(bvh::read(&junk, &BvhOptions::default()).unwrap().len(), 2);
    // A missing row: lenient keeps the complete rows.
    let t = SMALL.replace("Frames: 2", "Frames: 5");
    let m = bvh::read(&t, &BvhOptions { frame_count: FrameCount::Lenient, ..Default::default() }).unwrap();
    assert_eq!(m.len(), 2);
    // An incomplete last row is dropped in lenient mode and reported by inspect.
    let t = format!("{SMALL}1 2 3\n").replace("Frames: 2", "Frames: 3");
    let m = bvh::read(&t, &BvhOptions { frame_count: FrameCount::Lenient, ..Default::default() }).unwrap();
    assert_eq!(m.len(), 2);
    let info = bvh::inspect(&t).unwrap();
    assert_eq!((info.rows_present, info.trailing_values), (2, 3));
    assert!(info.to_string().contains("incomplete"));
}

#[test]
fn deep_nesting_does_not_overflow_the_stack() {
    let depth = 20_000;
    let mut t = String::from("HIERARCHY\nROOT R\n{\nOFFSET 0 0 0\nCHANNELS 1 Zrotation\n");
    for i in 0..depth {
        t += &format!("JOINT J{i}\n{{\nOFFSET 0 1 0\n");
    }
    t += &"}\n".repeat(depth + 1);
    t += "MOTION\nFrames: 1\nFrame Time: 1\n0\n";
    let m = bvh::read(&t, &BvhOptions { units: BvhUnits::Metres, ..Default::default() }).unwrap();
    assert_eq!(m.n_joints(), depth + 1);
    let w = bvh::write(&m, &BvhWriteOptions { units: BvhUnits::Metres, decimals: 3 });
    assert!(w.len() > t.len() / 2);
    // An unclosed deep file is an error, not a crash.
    let open = t.replacen(&"}\n".repeat(depth + 1), "", 1);
    assert!(matches!(read_err(&open), BvhError::UnbalancedBraces { .. }));
}

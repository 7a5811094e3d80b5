//! Fuzz-style property tests of the BVH reader (motion-graph.md §7.1 test 5): random bytes,
//! truncated and mutated valid files never panic, and every error has a message with a line.

use geom_core::anim::bvh::{self, BvhOptions, FrameCount};
use geom_core::Error;
use proptest::prelude::*;

/// A small valid file exercising every construct: two rotation orders, position channels on a
/// non-root joint, a zero-channel joint, end sites.
const VALID: &str = "HIERARCHY
ROOT Hips
{
\tOFFSET 0 0 0
\tCHANNELS 6 Xposition Yposition Zposition Zrotation Yrotation Xrotation
\tJOINT Spine
\t{
\t\tOFFSET 0 10 0
\t\tCHANNELS 6 Xposition Yposition Zposition Xrotation Zrotation Yrotation
\t\tJOINT Head
\t\t{
\t\t\tOFFSET 0 12 1
\t\t\tCHANNELS 0
\t\t\tEnd Site
\t\t\t{
\t\t\t\tOFFSET 0 5 0
\t\t\t}
\t\t}
\t}
\tJOINT LeftUpLeg
\t{
\t\tOFFSET 3 -2 0
\t\tCHANNELS 2 Zrotation Xrotation
\t\tEnd Site
\t\t{
\t\t\tOFFSET 0 -40 0
\t\t}
\t}
}
MOTION
Frames: 3
Frame Time: 0.0333333
0 90 0 0 0 0 0 0 0 10 20 30 5 5
1 91 0 10 0 0 0 0 0 -10 20 30 5 -5
2 92 0 90 45 90 0.5 0 0 10 90 30 -90 5
";

/// Reads with every option combination; checks the invariants of each outcome.
fn check(text: &str) {
    if let Err(e) = bvh::inspect(text) {
        assert!(!e.to_string().is_empty());
    }
    for frame_count in [FrameCount::Strict, FrameCount::Lenient] {
        match bvh::read(text, &BvhOptions { frame_count, ..Default::default() }) {
            Ok(m) => {
                assert!(!m.is_empty());
                assert_eq!(m.rot.len(), m.len() * m.n_joints());
                // Forward kinematics is finite.
                let mut p = vec![geom_core::math::Pt3::origin(); m.n_joints()];
                m.joint_positions(m.len() - 1, &mut p);
                assert!(p.iter().all(|q| q.iter().all(|c| c.is_finite())));
            }
            Err(Error::Bvh(e)) => {
                let msg = e.to_string();
                assert!(msg.starts_with("line "), "{msg}");
            }
            Err(e) => assert!(!e.to_string().is_empty()),
        }
    }
}

#[test]
fn valid_file_reads() {
    let m = bvh::read(VALID, &BvhOptions::default()).unwrap();
    assert_eq!(m.len(), 3);
    assert_eq!(m.n_joints(), 6);
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 200, .. ProptestConfig::default() })]

    #[test]
    fn random_bytes_never_panic(bytes in proptest::collection::vec(any::<u8>(), 0..600)) {
        check(&String::from_utf8_lossy(&bytes));
    }

    #[test]
    fn random_tokens_never_panic(toks in proptest::collection::vec(
        prop_oneof![
            Just("HIERARCHY"), Just("ROOT"), Just("JOINT"), Just("End"), Just("Site"), Just("{"), Just("}"),
            Just("OFFSET"), Just("CHANNELS"), Just("3"), Just("0"), Just("-1.5"), Just("nan"), Just("Xrotation"),
            Just("Yposition"), Just("MOTION"), Just("Frames:"), Just("Frame"), Just("Time:"), Just("\n"), Just("A"),
        ], 0..80)) {
        check(&toks.join(" "));
    }

    #[test]
    fn truncated_valid_file_never_panics(cut in 0usize..VALID.len()) {
        check(&VALID[..cut]);
    }

    #[test]
    fn mutated_valid_file_never_panics(
        edits in proptest::collection::vec((0usize..VALID.len(), any::<u8>(), 0u8..3), 1..6)
    ) {
        let mut bytes = VALID.as_bytes().to_vec();
        for (pos, b, kind) in edits {
            let pos = pos.min(bytes.len());
            match kind {
                0 if pos < bytes.len() => bytes[pos] = b,
                1 => bytes.insert(pos, b),
                _ if pos < bytes.len() => { bytes.remove(pos); }
                _ => {}
            }
        }
        check(&String::from_utf8_lossy(&bytes));
    }

    #[test]
    fn mutated_tokens_never_panic(idx in 0usize..200, repl in prop_oneof![
        Just("{"), Just("}"), Just("1e400"), Just("-0"), Just("CHANNELS"), Just("JOINT"), Just("999999999999999"),
        Just("Zrotation"), Just(""), Just("End Site"), Just("Frames:"), Just("0.0"),
    ]) {
        let toks: Vec<&str> = VALID.split_whitespace().collect();
        let i = idx % toks.len();
        let mut out: Vec<&str> = toks.clone();
        out[i] = repl;
        check(&out.join("\n"));
    }
}

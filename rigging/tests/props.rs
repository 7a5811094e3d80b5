//! Property tests: sphere-packing invariants (spec §7.2 b); the template RON reader returns a
//! valid template or a typed error naming the file on arbitrary and on truncated input.

use geom_core::math::Pt3;
use proptest::prelude::*;
use rigging::medial::{pack_spheres, Sphere};
use rigging::RigError;

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    #[test]
    fn packing_never_accepts_a_centre_inside_an_earlier_sphere(
        raw in prop::collection::vec((0.0f64..1.0, 0.0f64..1.0, 0.0f64..1.0, 0.001f64..0.1), 1..200),
        cap in 1usize..100,
    ) {
        let mut s: Vec<Sphere> = raw.iter().map(|&(x, y, z, r)| Sphere { c: Pt3::new(x, y, z), r }).collect();
        s.sort_by(|a, b| b.r.total_cmp(&a.r));
        let p = pack_spheres(&s, cap);
        prop_assert!(p.len() <= cap);
        for (i, a) in p.iter().enumerate() {
            for b in &p[..i] {
                prop_assert!((a.c - b.c).norm() >= b.r);
                prop_assert!(b.r >= a.r);
            }
        }
    }

    #[test]
    fn template_reader_returns_errors_not_panics(text in ".{0,200}") {
        let dir = std::env::temp_dir().join(format!("rig_prop_{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("temp dir");
        let p = dir.join("t.ron");
        std::fs::write(&p, &text).expect("write");
        match rigging::SkeletonTemplate::from_ron_file(&p) {
            // Whatever parses is a valid tree.
            Ok(s) => prop_assert!(s.validate().is_ok()),
            // Parse errors name the file; tree errors say what is wrong.
            Err(RigError::File { path, msg }) => {
                prop_assert_eq!(path, p.display().to_string());
                prop_assert!(!msg.is_empty());
            }
            Err(RigError::InvalidSkeleton(msg)) => prop_assert!(!msg.is_empty()),
            Err(e) => prop_assert!(false, "unexpected error kind: {e}"),
        }
    }

    /// A valid template file cut short anywhere is refused with an error naming the file; the
    /// whole file reads back equal to the template.
    #[test]
    fn truncated_template_files_are_refused_naming_the_file(cut in 0.0f64..1.0) {
        let h = rigging::SkeletonTemplate::human();
        let text = ron::to_string(&h).expect("serialises");
        let dir = std::env::temp_dir().join(format!("rig_prop_cut_{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("temp dir");
        let p = dir.join("t.ron");
        std::fs::write(&p, &text).expect("write");
        prop_assert_eq!(rigging::SkeletonTemplate::from_ron_file(&p).expect("whole file reads"), h);
        // Cut strictly inside the text (the last character closes the outer struct).
        let k = ((cut * (text.len() - 1) as f64) as usize).min(text.len() - 1);
        let k = (0..=k).rev().find(|&i| text.is_char_boundary(i)).expect("0 is a boundary");
        std::fs::write(&p, &text[..k]).expect("write");
        match rigging::SkeletonTemplate::from_ron_file(&p) {
            Err(RigError::File { path, .. }) => prop_assert_eq!(path, p.display().to_string()),
            other => prop_assert!(false, "cut at {k} of {}: {other:?}", text.len()),
        }
    }
}

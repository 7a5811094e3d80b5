//! Property tests: sphere-packing invariants (spec §7.2 b) and the template RON reader never
//! panics on arbitrary input.

use geom_core::math::Pt3;
use proptest::prelude::*;
use rigging::medial::{pack_spheres, Sphere};

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
        let _ = rigging::SkeletonTemplate::from_ron_file(&p);
    }
}

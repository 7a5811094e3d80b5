//! The PNG pattern path end to end: a 16-bit grayscale sinusoid written with geom-core, read back
//! through `PatternSource::Png`, blurred, spline-fitted, and used for coefficients that agree with
//! the analytic sinusoid.

mod common;

use common::*;
use geom_core::image::{write_png_gray16, ImageF32};
use wrinkles::*;

#[test]
fn png_pattern_matches_procedural() {
    let n = 256u32;
    let periods = 8.0;
    let mut img = ImageF32::new(n, n, 0.0);
    for y in 0..n {
        for x in 0..n {
            let s = (x as f64 + 0.5) / n as f64;
            img.set(x, y, (0.5 + 0.4 * (std::f64::consts::TAU * periods * s).sin()) as f32);
        }
    }
    let path = std::env::temp_dir().join(format!("wrinkles_png_pattern_{}.png", std::process::id()));
    write_png_gray16(&path, &img, 65535.0).unwrap();
    let l = 0.1;
    let o = PatternOptions {
        normalization: Normalization::TargetRestSlope(0.8),
        blur_texels: 0.0,
        uv_transform: UvTransform { scale: [1.0 / l, 1.0 / l], ..Default::default() },
        ..Default::default()
    };
    let png = WrinklePattern::new(&PatternSource::Png { path: path.clone() }, o);
    let _ = std::fs::remove_file(&path);
    let png = png.unwrap();
    let mesh = two_triangle_square(l);
    let pre = PrecomputeOptions { tolerance: 1e-4, ..Default::default() };
    let a = precompute(&mesh, &[png], &pre).unwrap();
    let b = precompute(&mesh, &[sinusoid(l / periods, 0.0, 0.8)], &pre).unwrap();
    // The B-spline smooths a 32-texel-per-period sinusoid by (sinc-like) factor ≈ 1 − (2π/32)²/6
    // ≈ 0.6 % in amplitude; TargetRestSlope renormalises it, so the coefficients agree to about
    // the slope estimate's sampling error (≈ 1 %) — 3 % is a safe bound that still fails for a
    // wrong chain rule (a transposed or unscaled J changes C1/C3 by O(1)).
    for t in 0..2 {
        let (ca, cb) = (a.coeff(t, 0), b.coeff(t, 0));
        for (x, y) in [(ca.k[(0, 0)], cb.k[(0, 0)]), (ca.k[(1, 1)], cb.k[(1, 1)]), (ca.c4, cb.c4)] {
            assert!((x - y).abs() <= 0.03 * y.abs(), "{x} vs {y}");
        }
        assert_eq!(ca.status, CoeffStatus::Ok);
    }
    // Missing file: a clear error naming the path.
    let e = WrinklePattern::new(&PatternSource::Png { path: path.clone() }, PatternOptions::default()).unwrap_err();
    assert!(e.to_string().contains("wrinkles_png_pattern"), "{e}");
}

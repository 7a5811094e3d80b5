//! Issue 26's probes and metrics: a pressure probe in a resting pool reads `ρ g depth`, a height
//! probe the surface; the fitted time shift recovers a known shift; the rest-state energy and
//! the splash height of simple series.

use flip_tet::experiments::probes::Probes;
use flip_tet::metrics::{fit_time_shift, rest_potential_energy, splash_height};
use flip_tet::particles::Particles;
use flip_tet::scene::{Scene, Shape};
use flip_tet::sim::FlipTetSim;
use geom_core::math::{Pt3, Vec3};

/// A uniform pool `1 × 0.5 × 0.25` m filled to 0.25 m at finest 8, stepped 4 times: the pressure
/// probes one cube and more below the surface read hydrostatics to 1e−9 relative (P1 exact for a
/// linear field), the height probe the surface to 1e−9 m.
#[test]
fn pressure_probe_reads_hydrostatics_in_a_resting_pool() {
    let mut scene =
        Scene::new(([0.0; 3], [1.0, 0.5, 0.25]), (8, 8), vec![Shape::Box { min: [0.0; 3], max: [1.0, 0.25, 0.25] }]);
    scene.pressure.solver = flip_tet::error::SolverKind::DirectCholesky;
    scene.flip.dt_max = 1.0 / 120.0;
    let mut sim = FlipTetSim::new(&scene).unwrap();
    assert!(sim.pressure_at(&Pt3::new(0.5, 0.1, 0.125)).is_none(), "no pressure before the first step");
    for _ in 0..4 {
        sim.step().unwrap();
    }
    let probes = Probes {
        heights: vec![(0.5, 0.125)],
        pressures: vec![[0.5, 0.1, 0.125], [0.3, 0.05, 0.1]],
        ..Default::default()
    };
    let (h, p) = probes.sample(&sim);
    assert!((h[0] - 0.25).abs() <= 1e-9, "{h:?}");
    for (q, v) in probes.pressures.iter().zip(&p) {
        let want = 1000.0 * 9.81 * (0.25 - q[1]);
        assert!(((v - want) / want).abs() <= 1e-9, "{v} vs {want}");
    }
}

/// `fit_time_shift` finds the shift of a reference that is the simulated curve delayed by 0.3.
#[test]
fn fitted_time_shift_recovers_a_delay() {
    let sim: Vec<(f64, f64)> = (0..=350).map(|k| 0.01 * k as f64).map(|t| (t, 1.0 + 0.2 * t * t)).collect();
    let reference: Vec<(f64, f64)> =
        [0.8, 1.5, 2.2, 3.0].iter().map(|&t| (t, 1.0 + 0.2 * (t - 0.3f64).powi(2))).collect();
    let (d, rms) = fit_time_shift(&sim, &reference, -1.0, 1.0, 0.001);
    assert!((d - 0.3).abs() < 1.5e-3, "{d}");
    assert!(rms < 1e-4, "{rms}");
    assert!(fit_time_shift(&[], &reference, 0.0, 1.0, 0.1).0.is_nan());
}

/// Rest state of 8 particles of radius 0.05 (volume 8 · 0.1³) in a 1 × 1 m floor: depth 8e−3 m,
/// energy ρ g V h/2; the splash height is the highest top after the lowest one.
#[test]
fn rest_energy_and_splash_height() {
    let scene = Scene::new(([0.0; 3], [1.0, 1.0, 1.0]), (4, 4), vec![]);
    let mut p = Particles::default();
    for i in 0..8 {
        p.push(Pt3::new(0.1 * i as f64, 0.5, 0.5), Vec3::zeros(), 0.05, -0.05);
    }
    let (e, h) = rest_potential_energy(&scene, &p);
    assert!((h - 8e-3).abs() < 1e-15);
    assert!((e - 1000.0 * 9.81 * 8e-3 * 4e-3).abs() < 1e-12);
    let tops = [(0.0, 0.8), (0.1, 0.5), (0.2, 0.3), (0.3, 0.45), (0.4, 0.4)];
    assert!((splash_height(&tops, 0.25) - 0.2).abs() < 1e-15);
    assert!(splash_height(&[(0.0, f64::NAN)], 0.25).is_nan());
}

//! Accuracy regressions of the time loop (fta, session 5): time-centred advection integrates a
//! freely falling cluster exactly, and the standing wave stays a small-amplitude wave (the
//! interior level-set decay used to open holes inside the liquid and multiply its kinetic energy
//! by ~50; the raw per-tet normals used to pin the wall crest).

use flip_tet::scene::{DtPolicy, Scene};
use flip_tet::sim::FlipTetSim;
use geom_core::math::{Pt3, Vec3};

/// Eight particles in one coarse cube away from the walls, no liquid node (as H-DROPLET-8):
/// mean drop after `n` fixed steps.
fn cluster_drop(time_centred: bool, n: usize) -> (f64, f64) {
    let text = r#"(
        domain: (min: (0.0, 0.0, 0.0), max: (1.0, 1.0, 1.0)),
        resolution: (coarsest: 4, finest: 4),
        duration: 0.2, fps: 50.0,
        liquid: [],
    )"#;
    let mut s: Scene = ron::from_str(text).unwrap();
    s.flip.dt_policy = DtPolicy::Fixed(0.005);
    s.flip.time_centred_advection = time_centred;
    s.particles.position_correction = false;
    let mut sim = FlipTetSim::new(&s).unwrap();
    for c in 0..8 {
        let o = Vec3::new((c & 1) as f64, ((c >> 1) & 1) as f64, ((c >> 2) & 1) as f64) * 0.02;
        sim.particles_mut().push(Pt3::new(0.54, 0.64, 0.54) + o, Vec3::zeros(), 0.01, 0.0);
    }
    let y0: f64 = sim.particles().x.iter().map(|x| x.y).sum::<f64>() / 8.0;
    for _ in 0..n {
        sim.step().unwrap();
    }
    let y1: f64 = sim.particles().x.iter().map(|x| x.y).sum::<f64>() / 8.0;
    (y0 - y1, sim.time())
}

/// Constant acceleration: the linear-in-time field gives the exact parabola `g t² / 2`
/// (tolerance 2 %: the grid field of eight particles in one cube comes from the weak-coverage
/// blend with extrapolated values and lags the particle velocity by ≈ 1 %, as in H-DROPLET-8),
/// while the end-of-step field overshoots by `Δt / t` (10 % after 10 steps).
#[test]
fn time_centred_advection_is_exact_for_free_fall() {
    let (d, t) = cluster_drop(true, 10);
    let exact = 0.5 * 9.81 * t * t;
    assert!((d - exact).abs() <= 0.02 * exact, "time-centred drop {d} vs {exact}");
    let (d_end, _) = cluster_drop(false, 10);
    assert!(d_end > 1.05 * exact, "end-of-step drop {d_end} should lead {exact} by ~Δt/t");
}

fn wave(finest: u32) -> Scene {
    let text = format!(
        r#"(
        domain: (min: (0.0, 0.0, 0.0), max: (1.0, 0.75, 0.125)),
        resolution: (coarsest: 8, finest: {finest}),
        fps: 60.0, duration: 1.0,
        liquid: [CosineSurface(mean: 0.5, amplitude: 0.02, length: 1.0, x0: 0.0)],
        sizing: (depth_floor: Some(0.25), surface_band: Some(3.0)),
        particles: (column_top_on_surface: true),
        flip: (dt_max: 0.008333333333333333),
    )"#
    );
    ron::from_str(&text).unwrap()
}

/// S3 over the first half period at finest 16: the kinetic energy stays below twice the
/// linear-theory wave energy `ρ g A² L W / 4` (it reached 50× with the decaying interior level
/// set), and the wall crest follows `η = H + A cos(πx/L) cos(ωt)` within `0.3 A` (measured
/// 0.21 A; with the raw per-tet normals the position correction pinned it near `H`, 0.65 A off
/// at `t = 0.5` s).
#[test]
fn standing_wave_first_half_period_follows_linear_theory() {
    let scene = wave(16);
    let mut sim = FlipTetSim::new(&scene).unwrap();
    let (a, g) = (0.02, 9.81);
    let e_wave = 1000.0 * g * a * a * 1.0 * 0.125 / 4.0;
    let k = std::f64::consts::PI;
    let omega = (g * k * (k * 0.5f64).tanh()).sqrt();
    let xp = 1.0 / 32.0;
    let mut worst: f64 = 0.0;
    while sim.time() < 0.6 {
        let st = sim.step().unwrap();
        assert!(st.kinetic_energy <= 2.0 * e_wave, "t {}: KE {} J vs wave energy {e_wave} J", st.t, st.kinetic_energy);
        let eta = flip_tet::metrics::surface_height(&sim, xp, 0.0625).expect("liquid under the probe");
        let theory = 0.5 + a * (k * xp).cos() * (omega * st.t).cos();
        worst = worst.max((eta - theory).abs());
    }
    assert!(worst <= 0.3 * a, "wall crest off linear theory by {worst} m");
}

//! Building blocks of the accuracy-versus-time benchmark (shells.md §9; `cargo xtask bench
//! shells`): a scene run for a fixed simulated time with its cost per frame, the fine reference
//! configuration, and one point of the sweep (substeps × Newton iterations × Hessian mode). The
//! error is [`metrics::rms_distance_rel`](crate::metrics::rms_distance_rel).
//!
//! ```
//! use shells::experiments::accuracy::{configured, reference, simulate};
//! use shells::scene::{MeshSpec, ShellScene};
//! use shells::HessianMode;
//! let shell: ShellScene = ron::from_str(
//!     "(mesh: Grid(nx: 5, ny: 5, size: (1.0, 1.0)), material: (density: 0.15,
//!       membrane: Isotropic(young_thickness: 2000.0, poisson: 0.3), bending: 5e-6),
//!       effects: (gravity: Some((0.0, -9.81, 0.0))), pins: [TopCorners], duration: 1.0)",
//! ).unwrap();
//! let fine = simulate(&reference(&shell, 4), 0.1).unwrap();
//! let run = simulate(&configured(&shell, 1, 1, HessianMode::ProjectedCheap), 0.1).unwrap();
//! let err = shells::metrics::rms_distance_rel(&run.q, &fine.q, &fine.mass);
//! assert!(err > 0.0 && err < 0.05, "{err}");
//! ```

use std::time::Instant;

use geom_core::math::Pt3;

use crate::error::Result;
use crate::kernels::psd::HessianMode;
use crate::scene::ShellScene;
use crate::sim::ShellSim;

/// The end of a timed run.
#[derive(Clone, Debug)]
pub struct TimedRun {
    /// Final positions (m).
    pub q: Vec<Pt3>,
    /// Lumped vertex masses (kg).
    pub mass: Vec<f64>,
    /// Wall time per output frame (ms).
    pub ms_per_frame: f64,
    /// Steps whose factorisation needed a diagonal shift.
    pub regularizations: u32,
}

/// Simulates `shell` for `duration` seconds (round(duration·fps) frames of its substeps).
pub fn simulate(shell: &ShellScene, duration: f64) -> Result<TimedRun> {
    let b = shell.build(std::path::Path::new("."))?;
    let mut sim = ShellSim::new(b.desc)?;
    let h = shell.integrator.h();
    let frames = (duration * shell.integrator.fps).round() as usize;
    let mut regularizations = 0;
    let t0 = Instant::now();
    for _ in 0..frames * shell.integrator.substeps as usize {
        let st = sim.step(h)?;
        regularizations += (st.regularization_shift > 0.0) as u32;
    }
    let ms_per_frame = 1e3 * t0.elapsed().as_secs_f64() / frames.max(1) as f64;
    Ok(TimedRun { q: sim.state().q.clone(), mass: sim.mesh().mass.clone(), ms_per_frame, regularizations })
}

/// The fine reference of a scene: `factor`× its substeps, 20 Newton iterations with line
/// search, ProjectedEigen (shells.md §9: h_ref = h/16 in the full sweep).
pub fn reference(shell: &ShellScene, factor: u32) -> ShellScene {
    let mut r = shell.clone();
    r.integrator.substeps = shell.integrator.substeps * factor;
    r.integrator.newton_iters = 20;
    r.integrator.line_search = true;
    r.integrator.hessian = HessianMode::ProjectedEigen;
    r
}

/// One point of the sweep: the scene with `substeps`, `newton_iters` and `hessian`.
pub fn configured(shell: &ShellScene, substeps: u32, newton_iters: u32, hessian: HessianMode) -> ShellScene {
    let mut c = shell.clone();
    c.integrator.substeps = substeps;
    c.integrator.newton_iters = newton_iters;
    c.integrator.hessian = hessian;
    c
}

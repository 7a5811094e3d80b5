//! [`CapturedSystem`]: an owned copy of one step's implicit system, taken through the
//! [`VelocitySolve`] hook of `shells` — for benchmarks and studies that solve the very same
//! system with several methods (`benches/tracking.rs`, `examples/kkt_orderings.rs`).

use geom_core::linalg::Csc;
use geom_core::math::{Pt3, Vec3};
use shells::{DofMap, ImplicitSystem, ShellSim, VelocitySolve};

/// An owned copy of an [`ImplicitSystem`] (the solver interface only borrows it).
#[derive(Clone, Debug)]
pub struct CapturedSystem {
    /// System matrix A (free DOFs, lower triangle).
    pub a: Csc,
    /// Right-hand side b.
    pub b: Vec<f64>,
    /// Predicted positions q⁰ (m).
    pub q_pred: Vec<Pt3>,
    /// Velocities at the step start (m/s).
    pub v0: Vec<Vec3>,
    /// Effective step h_eff (s).
    pub h_eff: f64,
    /// Free-DOF map.
    pub dofs: DofMap,
    /// Step h (s).
    pub h: f64,
    /// Time at the end of the step (s).
    pub t_next: f64,
}

impl CapturedSystem {
    /// The borrowed view the solvers take.
    pub fn system(&self) -> ImplicitSystem<'_> {
        ImplicitSystem {
            a: &self.a,
            b: &self.b,
            q_pred: &self.q_pred,
            v0: &self.v0,
            h_eff: self.h_eff,
            dofs: &self.dofs,
            h: self.h,
            t_next: self.t_next,
        }
    }

    /// Runs one step of `sim` of size `h` (s), capturing its system; the step itself is
    /// answered with Δv = 0 (a valid, if unphysical, velocity), so only the capture is meaningful.
    pub fn capture_step(sim: &mut ShellSim, h: f64) -> shells::Result<Self> {
        let mut cap = Capture(None);
        sim.step_with(h, &mut cap)?;
        cap.0.ok_or_else(|| shells::Error::BadParameter("the step did not call its velocity solver".into()))
    }
}

/// Records the system it is asked to solve and answers Δv = 0.
struct Capture(Option<CapturedSystem>);

impl VelocitySolve for Capture {
    fn solve(&mut self, sys: &ImplicitSystem) -> shells::Result<Vec<f64>> {
        self.0 = Some(CapturedSystem {
            a: sys.a.clone(),
            b: sys.b.to_vec(),
            q_pred: sys.q_pred.to_vec(),
            v0: sys.v0.to_vec(),
            h_eff: sys.h_eff,
            dofs: sys.dofs.clone(),
            h: sys.h,
            t_next: sys.t_next,
        });
        Ok(vec![0.0; sys.b.len()])
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use geom_core::linalg::{Ordering, SparseLlt};
    use geom_core::procedural::{grid, GridSpec, Plane};
    use shells::{Effects, IntegratorSettings, Material, ShellSceneDesc, VertexConstraint};

    fn sheet() -> ShellSim {
        let m =
            grid(&GridSpec { quads: [4, 3], size: [0.4, 0.3], plane: Plane::XZ, ..GridSpec::default() }).expect("grid");
        ShellSim::new(ShellSceneDesc {
            rest: m.positions.clone(),
            faces: m.faces.clone(),
            uv: None,
            initial: None,
            initial_velocity: None,
            material: Material::cotton(),
            effects: Effects { gravity: Some(Vec3::new(0.0, -9.81, 0.0)), ..Effects::default() },
            constraints: vec![VertexConstraint::Pinned(vec![0, 4])],
            integrator: IntegratorSettings::default(),
            t0: 0.0,
        })
        .expect("valid sheet")
    }

    /// The captured system is the step's own: solving it gives the velocities of an identical
    /// simulation stepped normally (no collisions, one Newton step: v = v₀ + Δv), to 1e-12.
    #[test]
    fn captured_system_is_the_step_system() {
        let (mut a, mut b) = (sheet(), sheet());
        let h = 1.0 / 60.0;
        a.step(h).expect("step");
        b.step(h).expect("step");
        let cap = CapturedSystem::capture_step(&mut a, h).expect("capture");
        b.step(h).expect("step");
        let sys = cap.system();
        assert_eq!(sys.a.nrows(), 3 * sys.dofs.free_vertices.len());
        let mut llt = SparseLlt::analyze(sys.a, Ordering::Amd).expect("analysis");
        llt.factor(sys.a).expect("SPD");
        let mut dv = sys.b.to_vec();
        llt.solve_in_place(&mut dv).expect("solve");
        let scale = b.state().v.iter().map(|v| v.norm()).fold(0.0, f64::max);
        for (f, &v) in sys.dofs.free_vertices.iter().enumerate() {
            let want = b.state().v[v as usize];
            let got = sys.v0[v as usize] + Vec3::new(dv[3 * f], dv[3 * f + 1], dv[3 * f + 2]);
            assert!((got - want).norm() <= 1e-12 * scale, "vertex {v}: {got:?} vs {want:?}");
        }
    }
}

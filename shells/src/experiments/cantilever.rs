//! `shells/cantilever`: a 1 m equilateral strip ([`presets::equilateral_strip`]) clamped at one
//! end, ν = 0, solved quasi-statically (h = 10³ s, damped relaxation), at several edge lengths ℓ.
//!
//! * End moment M = 2πEI/L ([`reference::circle_moment`]) with the plate rigidity EI = 6k_B·w
//!   ([`reference::plate_rigidity`]; stiff membrane, Searle parameter w²κ/t ≫ 1: cylindrical
//!   bending) as a conservative follower moment ([`EndMoment`]) on each row's last segment: the
//!   strip must close a circle; figure `moment_circle_gap_rel` = tip–root distance / free length
//!   at the finest ℓ.
//! * A small tip load ([`TipLoad`], δ/L = 1 %, soft membrane: a free anticlastic beam) against
//!   δ = PL³/(3EI) ([`reference::tip_deflection`]) with EI = c·k_B·w, c measured from the lattice's
//!   own cylinder and sphere energies (`calib::strip_rigidity_factor`, ≈ 16/3 on equilateral
//!   meshes): `small_load_tip_rel_err`; with c = 6: `small_load_tip_rel_err_plate_rigidity`.
//!
//! Also `finest_ell_m`, and the sanity figures of every relaxation step of both runs at every ℓ
//! (`max_edge_strain`, `max_edge_compression`, `max_obstacle_penetration_m` = 0,
//! `max_intersections` on each run's final state, `nan_steps`, `steps`, timing `s_per_step`); table `cantilever`, plot `cantilever` (gap against ℓ), the bent strip of
//! each ℓ as frame 0 of the sequence `moment_ell<ℓ>`.
//!
//! ```no_run
//! use geom_core::experiment::{BySize, Size};
//! use geom_core::record::NullRecorder;
//! use shells::experiments::cantilever::{run, Params};
//! let p = Params {
//!     length: 1.0,
//!     width: 0.1,
//!     ells: BySize::Same(vec![0.05]),
//!     bending: 1e-3,
//!     young_thickness_moment: 1e6,
//!     young_thickness_small: 1e4,
//!     moment_load_steps: 60,
//!     newton_iters: 6,
//!     hold_steps: BySize::Same(120),
//!     relaxation_keep: 0.8,
//!     small_deflection: 0.01,
//! };
//! let r = run(&p, Size::Quick, &mut NullRecorder::default()).unwrap();
//! println!("{:?}", r.get("small_load_tip_rel_err"));
//! ```

use std::sync::Arc;

use geom_core::experiment::{BySize, Report, Size, Target};
use geom_core::math::{Pt3, Vec3};
use geom_core::record::{Cell, MeshFrame, Recorder, Series};
use geom_core::stats::nan_max;
use serde::Deserialize;

use crate::calib;
use crate::effects::{Effects, ExternalForce};
use crate::error::{Error, Result};
use crate::integrator::IntegratorSettings;
use crate::kernels::psd::HessianMode;
use crate::loads::{EndMoment, TipLoad};
use crate::material::{Damping, Material, MembraneLaw};
use crate::metrics::Sanity;
use crate::presets;
use crate::reference;
use crate::sim::{ShellSceneDesc, ShellSim, VertexConstraint};

/// Parameters (the scene file's `params` block).
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Params {
    /// Strip length (m).
    pub length: f64,
    /// Strip width (m); the row count is the nearest odd number of lattice rows.
    pub width: f64,
    /// Equilateral edge lengths per run size (m); the last is the finest, each in
    /// (0, length/8].
    pub ells: BySize<Vec<f64>>,
    /// Hinge stiffness k_B (J).
    pub bending: f64,
    /// Membrane Yt (N/m) of the end-moment run: large, so that the strip bends cylindrically
    /// (Searle parameter w²κ/t ≫ 1 with t = √(72 k_B/Yt)): plate rigidity EI = 6 k_B w.
    pub young_thickness_moment: f64,
    /// Membrane Yt (N/m) of the small-load run: w²κ/t ≪ 1, a free (anticlastic) beam.
    pub young_thickness_small: f64,
    /// Load steps for the end moment.
    pub moment_load_steps: u32,
    /// Newton iterations per load step.
    pub newton_iters: u32,
    /// Relaxation steps at full moment, per run size.
    pub hold_steps: BySize<u32>,
    /// Fraction of the velocity kept between relaxation steps, in [0, 1).
    pub relaxation_keep: f64,
    /// Small tip load, as the beam-theory deflection over L.
    pub small_deflection: f64,
}

/// The strip's material: areal density 0.01 kg/m², isotropic membrane Yt with ν = 0, hinge
/// stiffness k_B, no damping.
fn strip_material(bending: f64, yt: f64) -> Material {
    Material {
        density: 0.01,
        membrane: MembraneLaw::Isotropic { young_thickness: yt, poisson: 0.0, compression_softening: None },
        bending,
        damping: Damping::None,
        plasticity: None,
    }
}

fn strip_sim(
    p: &Params,
    yt: f64,
    pos: &[Pt3],
    faces: &[[u32; 3]],
    pins: Vec<u32>,
    custom: Arc<dyn ExternalForce>,
) -> Result<ShellSim> {
    let mut effects = Effects::default();
    effects.custom.push(custom);
    ShellSim::new(ShellSceneDesc {
        rest: pos.to_vec(),
        faces: faces.to_vec(),
        uv: None,
        initial: None,
        initial_velocity: None,
        material: strip_material(p.bending, yt),
        effects,
        constraints: vec![VertexConstraint::Pinned(pins)],
        integrator: IntegratorSettings {
            newton_iters: p.newton_iters,
            hessian: HessianMode::ProjectedEigen,
            ..Default::default()
        },
        t0: 0.0,
    })
}

/// Dynamic relaxation toward the static equilibrium: one step with h ≫ the inertial time scale
/// (a few Newton iterations on the static problem started from the extrapolated increment
/// q_k + h v_k), then the velocity is scaled by `keep` ∈ [0, 1) so the extrapolation
/// accelerates the slow rotation modes without oscillating.
pub fn quasi_static_step(sim: &mut ShellSim, h: f64, keep: f64) -> Result<()> {
    sim.step(h)?;
    let mut st = sim.state().clone();
    st.v.iter_mut().for_each(|v| *v *= keep);
    sim.set_state(st)
}

/// The sanity figures of the quasi-static runs: every relaxation step observed by a
/// [`Sanity`] of its strip, exact self-intersections counted on each run's final state.
#[derive(Default)]
struct Watch {
    strain: f64,
    compression: f64,
    intersections: u64,
    steps: u64,
    wall: Vec<f64>,
}

impl Watch {
    fn step(&mut self, sim: &mut ShellSim, sanity: &mut Sanity, h: f64, keep: f64) -> Result<()> {
        let t0 = std::time::Instant::now();
        quasi_static_step(sim, h, keep)?;
        self.wall.push(t0.elapsed().as_secs_f64());
        self.steps += 1;
        sanity.observe(&sim.state().q, sim.state().t, None);
        Ok(())
    }

    fn frame(&mut self, sim: &ShellSim, faces: &[[u32; 3]]) {
        let k = crate::collision::count_self_intersections(&sim.state().q, faces) as u64;
        self.intersections = self.intersections.max(k);
    }

    fn absorb(&mut self, s: &Sanity) {
        self.strain = nan_max(self.strain, s.max_edge_strain);
        self.compression = nan_max(self.compression, s.max_edge_compression);
    }

    /// `max_edge_strain`, `max_edge_compression`, `max_obstacle_penetration_m` (0: no
    /// obstacle), `max_intersections`, `nan_steps` (0: a failed step is the scene's error),
    /// `steps` and the timing `s_per_step`.
    fn figures(&self, r: &mut Report) {
        r.num("max_edge_strain", self.strain).num("max_edge_compression", self.compression);
        r.num("max_obstacle_penetration_m", 0.0);
        r.count("max_intersections", self.intersections).count("nan_steps", 0).count("steps", self.steps);
        r.timing("s_per_step", geom_core::stats::mean(&self.wall));
    }
}

/// Runs the end-moment and small-load tests at every ℓ of the size.
pub fn run(p: &Params, size: Size, rec: &mut dyn Recorder) -> Result<Report> {
    let ells = p.ells.get(size);
    if ells.is_empty() || ells.iter().any(|&l| !(l > 0.0) || l > p.length / 8.0) || !(p.width > 0.0) {
        return Err(Error::BadParameter("ells must be in (0, length/8] and width > 0".into()));
    }
    if !(0.0..1.0).contains(&p.relaxation_keep) {
        return Err(Error::BadParameter(format!("relaxation_keep must be in [0, 1), got {}", p.relaxation_keep)));
    }
    rec.table(
        "cantilever",
        &[
            "ell_m",
            "vertices",
            "rigidity_factor",
            "moment_circle_gap_rel",
            "tip_deflection_m",
            "beam_theory_m",
            "small_load_tip_rel_err",
            "plate_rigidity_tip_rel_err",
        ],
    )?;
    let h = 1e3; // quasi-static: inertia negligible against h²K
    let mut last = (f64::NAN, f64::NAN, f64::NAN);
    let mut rows_md = String::new();
    let mut conv = Vec::new();
    let mut watch = Watch::default();
    for &ell in &ells {
        let dy = ell * 3f64.sqrt() / 2.0;
        let rows = (2.0 * (p.width / (2.0 * dy)).round()).max(2.0) as u32 + 1;
        let (pos, faces, rv) = presets::equilateral_strip(p.length, ell, rows);
        let width = pos.iter().map(|q| q.y).fold(0.0, nan_max);
        // Effective rigidity of this discretisation (its own cylinder/sphere calibration).
        let (pp, pf) = calib::equilateral_patch(0.5, ell, false);
        let factor = calib::strip_rigidity_factor(&pp, &pf, 2.5, 1.5 * ell)?;
        let ei = reference::strip_rigidity(factor, p.bending, width);
        let ei_plate = reference::plate_rigidity(p.bending, width);
        let lfree = p.length - ell;
        let pins: Vec<u32> = (0..pos.len() as u32).filter(|&i| pos[i as usize].x <= ell * 1.001).collect();
        let nr = rv.len();
        let wts: Vec<f64> = (0..nr).map(|j| if j == 0 || j == nr - 1 { 0.5 } else { 1.0 } / (nr - 1) as f64).collect();
        let mid = &rv[nr / 2];
        let root = *mid.iter().rfind(|&&i| pins.contains(&i)).ok_or_else(|| {
            Error::BadParameter(format!("cantilever: ℓ = {ell} leaves the clamp without a vertex in the middle row"))
        })?;
        let tip = *mid.last().ok_or_else(|| Error::BadParameter("cantilever: empty middle row".into()))?;
        // Pure end moment M = 2πEI/L (plate rigidity: cylindrical regime) ramped over load steps.
        let em =
            Arc::new(EndMoment::new(rv.iter().zip(&wts).map(|(r, &w)| (r[r.len() - 1], r[r.len() - 2], w)).collect()));
        let mut sim = strip_sim(p, p.young_thickness_moment, &pos, &faces, pins.clone(), em.clone())?;
        let mtot = reference::circle_moment(ei_plate, lfree);
        let n_load = p.moment_load_steps.max(1);
        let mut sanity = Sanity::new(&sim.mesh().rest, &sim.mesh().edges, Vec::new(), None);
        for k in 1..=n_load + p.hold_steps.get(size) {
            em.set_moment(mtot * (k.min(n_load) as f64 / n_load as f64));
            watch.step(&mut sim, &mut sanity, h, p.relaxation_keep)?;
        }
        watch.frame(&sim, &faces);
        let gap = (sim.state().q[tip as usize] - sim.state().q[root as usize]).norm() / lfree;
        rec.frame(&MeshFrame {
            sequence: &format!("moment_ell{ell}"),
            index: 0,
            time: sim.state().t,
            positions: &sim.state().q,
            faces: &faces,
            attributes: &[],
        })?;
        // Small tip load P: δ = P L³ / (3 EI).
        let delta_want = p.small_deflection * lfree;
        let pload = reference::tip_load_for_deflection(delta_want, lfree, ei);
        let loads: Vec<(u32, Vec3)> =
            rv.iter().zip(&wts).map(|(r, &w)| (r[r.len() - 1], Vec3::new(0.0, 0.0, -pload * w))).collect();
        let mut sim = strip_sim(p, p.young_thickness_small, &pos, &faces, pins, Arc::new(TipLoad(loads)))?;
        for _ in 0..10 {
            watch.step(&mut sim, &mut sanity, h, p.relaxation_keep)?;
        }
        watch.frame(&sim, &faces);
        watch.absorb(&sanity);
        let d = -rv.iter().zip(&wts).map(|(r, &w)| sim.state().q[r[r.len() - 1] as usize].z * w).sum::<f64>();
        let rel = (d - delta_want).abs() / delta_want;
        let plate = (d * factor / 6.0 - delta_want).abs() / delta_want;
        rec.row(
            "cantilever",
            &[
                Cell::Num(ell),
                Cell::Int(pos.len() as i64),
                Cell::Num(factor),
                Cell::Num(gap),
                Cell::Num(d),
                Cell::Num(delta_want),
                Cell::Num(rel),
                Cell::Num(plate),
            ],
        )?;
        rows_md += &format!(
            "| {ell} | {} | {factor:.4} | {gap:.4} | {d:.5e} | {delta_want:.5e} | {rel:.4} | {plate:.4} |\n",
            pos.len()
        );
        conv.push((ell, gap.max(1e-12)));
        last = (gap, rel, plate);
    }
    rec.series(&Series {
        plot: "cantilever".into(),
        label: "gap".into(),
        axes: ("edge length ℓ (m)".into(), "end-point gap / L under 2πEI/L".into()),
        log: (true, true),
        points: conv,
    })?;
    rec.note(&format!(
        "### shells/cantilever\n\nEquilateral strip {} m × {} m clamped at one end, ν = 0. End moment 2πEI/L with \
         the plate rigidity EI = 6k_B·w (stiff membrane, Searle parameter ≫ 1: cylindrical bending) must close a \
         circle. Small tip load vs δ = PL³/(3EI) with the free-strip rigidity EI = c·k_B·w, c measured from the \
         same lattice's cylinder and sphere energies (a free strip relaxes anticlastically: c = 16/3 for \
         Discrete Shells on equilateral meshes; the last column shows the error if 6 is used).\n\n\
         | ℓ (m) | vertices | c | gap/L | δ (m) | theory (m) | rel. err | with c = 6 |\n\
         |---|---|---|---|---|---|---|---|\n{rows_md}",
        p.length, p.width
    ))?;
    let mut r = Report::default();
    r.num("moment_circle_gap_rel", last.0)
        .num("small_load_tip_rel_err", last.1)
        .num("small_load_tip_rel_err_plate_rigidity", last.2)
        .num("finest_ell_m", *ells.last().unwrap_or(&f64::NAN));
    watch.figures(&mut r);
    let src = "shells README (Euler–Bernoulli cantilever at the finest ℓ)";
    r.check("moment_circle_gap_rel", Target::AtMost(0.02), src);
    r.check("small_load_tip_rel_err", Target::AtMost(0.05), src);
    Ok(r)
}

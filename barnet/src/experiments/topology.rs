//! Arbitrary connectivity (spec §6.4): a triangle/quad/pentagon control patch with a hole,
//! rigidly rotated back and forth, with random radial loads at random free nodes.
//!
//! Outputs: table `metrics` (frame, residual, max displacement from the rigid motion, solve
//! time), plot `displacement`, control frames `frames/NNNN.obj` every `obj_every` frames.
//! Figures: `max_equilibrium_residual`, `rest_reproduction_err_m` (m), `n_vertices`, `n_free`,
//! `faces_tri`, `faces_quad`, `faces_pent`, `boundary_loops`, `solver_path`, and the timings
//! `s_per_frame`, `s_factorization` (s).
//!
//! ```no_run
//! use barnet::experiments::topology::{run, Params};
//! use geom_core::experiment::{BySize, Size};
//! use geom_core::record::NullRecorder;
//! let p = Params {
//!     rings: 12,
//!     around: 24,
//!     q: 1.0,
//!     n_loaded: 12,
//!     load_scale: 0.01,
//!     rotate_amp: 0.4,
//!     frames: BySize::Same(5),
//!     seed: 9,
//!     obj_every: 10,
//! };
//! let r = run(&p, Size::Quick, &mut NullRecorder::default()).unwrap();
//! assert!(r.get_f64("rest_reproduction_err_m") < 1e-12);
//! ```

use std::time::Instant;

use geom_core::experiment::{BySize, Report, Size, Target};
use geom_core::math::{Iso3, Pt3, Vec3};
use geom_core::record::{Recorder, Series};
use geom_core::rng::Rng;
use geom_core::stats::{self, nan_max};
use serde::Deserialize;

use crate::error::Result;
use crate::net::BarNet;
use crate::patch;
use crate::solver::{FdmOptions, FdmSolver};
use crate::topo::PolyTopo;

use super::{check_residual, control_frame};

/// The scene's `params` block.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Params {
    /// Rings of the patch.
    pub rings: usize,
    /// Vertices around the outer ring.
    pub around: usize,
    /// Uniform force density.
    pub q: f64,
    /// Free nodes receiving a random load.
    pub n_loaded: usize,
    /// Load amplitude (force units).
    pub load_scale: f64,
    /// Rigid rotation amplitude of the whole patch (rad).
    pub rotate_amp: f64,
    /// Frames (at least 2).
    pub frames: BySize<usize>,
    /// Seed of the load placement.
    pub seed: u64,
    /// Frame stride of the OBJ output.
    pub obj_every: usize,
}

/// Runs the animation; see the module docs.
pub fn run(p: &Params, size: Size, rec: &mut dyn Recorder) -> Result<Report> {
    let n = p.frames.get(size).max(2);
    let pt = patch::mixed_patch(p.rings, p.around);
    let free: Vec<bool> = pt.boundary.iter().map(|b| !b).collect();
    let net = BarNet::from_mesh_edges(&pt.mesh, &free, p.q)?;
    let t0 = Instant::now();
    let solver = FdmSolver::new(&net, &FdmOptions::default())?;
    let t_factor = t0.elapsed().as_secs_f64();
    let fr = solver.free_nodes().to_vec();
    let fx = solver.fixed_nodes().to_vec();
    let rest = &pt.mesh.positions;
    let rest_free: Vec<Pt3> = fr.iter().map(|&v| rest[v as usize]).collect();
    let rest_fixed: Vec<Pt3> = fx.iter().map(|&v| rest[v as usize]).collect();
    let p0 = solver.rest_loads(&rest_free, &rest_fixed)?;
    let mut rng = Rng::new(p.seed);
    let mut loaded: Vec<(usize, Vec3, f64)> = Vec::new();
    for _ in 0..p.n_loaded.min(fr.len()) {
        let i = rng.below(fr.len());
        let normal = rest_free[i].coords.normalize();
        loaded.push((i, normal, rng.range(0.5, 1.5)));
    }
    rec.table("metrics", &["frame", "t", "residual", "max_disp_m", "t_solve_s"])?;
    let (mut max_res, mut times, mut rest_err): (f64, Vec<f64>, f64) = (0.0, Vec::new(), 0.0);
    let mut ctrl = rest.clone();
    let mut rpts = Vec::new();
    for f in 0..n {
        rec.progress(f as u64, n as u64);
        let t = f as f64 / (n - 1) as f64;
        let ang = p.rotate_amp * (std::f64::consts::TAU * t).sin();
        let g = Iso3::rotation(Vec3::new(0.3, 1.0, 0.2).normalize() * ang);
        let amp = p.load_scale * (std::f64::consts::PI * t).sin().powi(2);
        let mut loads: Vec<Vec3> = p0.iter().map(|v| g.rotation * v).collect();
        for &(i, nrm, w) in &loaded {
            loads[i] += g.rotation * nrm * (amp * w);
        }
        let fixed: Vec<Pt3> = rest_fixed.iter().map(|x| g * x).collect();
        let ts = Instant::now();
        let mut x = Vec::new();
        let info = solver.solve_into(&loads, &fixed, &mut x)?;
        let dt = ts.elapsed().as_secs_f64();
        check_residual("topology", info.rel_residual, 1e-12)?;
        max_res = nan_max(max_res, info.rel_residual);
        times.push(dt);
        let mut md: f64 = 0.0;
        for (i, &v) in fr.iter().enumerate() {
            ctrl[v as usize] = x[i];
            md = nan_max(md, (x[i] - g * rest_free[i]).norm());
        }
        for (k, &v) in fx.iter().enumerate() {
            ctrl[v as usize] = fixed[k];
        }
        if f == 0 {
            rest_err = md;
        }
        rpts.push((t, md * 1000.0));
        rec.row("metrics", &[f.into(), t.into(), info.rel_residual.into(), md.into(), dt.into()])?;
        if f % p.obj_every.max(1) == 0 || f + 1 == n {
            control_frame(rec, "frames", f, &ctrl, &pt.mesh.faces)?;
        }
    }
    rec.series(&Series {
        plot: "displacement".into(),
        label: "bar-net".into(),
        axes: ("t".into(), "max displacement from rigid (mm)".into()),
        log: (false, false),
        points: rpts,
    })?;
    let h = patch::face_histogram(&pt.mesh);
    let topo = PolyTopo::new(&pt.mesh)?;
    let mut s = Report::default();
    s.num("max_equilibrium_residual", max_res);
    s.timing("s_per_frame", stats::mean(&times));
    s.timing("s_factorization", t_factor);
    s.num("rest_reproduction_err_m", rest_err);
    s.count("n_vertices", rest.len() as u64);
    s.count("n_free", fr.len() as u64);
    s.count("faces_tri", h[0] as u64);
    s.count("faces_quad", h[1] as u64);
    s.count("faces_pent", h[2] as u64);
    s.count("boundary_loops", topo.boundary_loops(&pt.mesh).len() as u64);
    s.text("solver_path", &format!("{:?}", solver.path()));
    s.check("max_equilibrium_residual", Target::AtMost(1e-12), "spec §7.3 e: every frame in equilibrium");
    s.check("rest_reproduction_err_m", Target::AtMost(1e-12), "spec §7.3 a: rest shape reproduced");
    s.check("boundary_loops", Target::Equals(2.0), "spec §6.4: a patch with a hole");
    Ok(s)
}

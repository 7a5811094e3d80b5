//! Linear subdivision and the cotangent Laplacian, level by level: the prolongation matrix
//! reproduces the fine positions, subdivision keeps the area (every coarse triangle's plane),
//! the Galerkin identity `Pᵀ M_fine P = M_coarse` holds for the consistent P1 mass, and the
//! cotangent stiffness is symmetric with zero row sums.
//!
//! Outputs: table `levels` (per mesh and level), plot `subdivide_time`. Figures:
//! `prolongation_max_abs_err` (m), `area_max_rel_err`, `galerkin_mass_max_rel_err`,
//! `laplacian_rowsum_max_rel`, `laplacian_asymmetry_max_rel` (all NaN-propagating maxima),
//! `levels`, `<name>_fine_vertices`, `<name>_euler_characteristic`, and the timing
//! `<name>_subdivide_s`.
//!
//! ```
//! use geom_core::experiment::{BySize, Size};
//! use geom_core::experiments::subdivision::{run, Params};
//! use geom_core::experiments::MeshSource;
//! use geom_core::record::NullRecorder;
//! let p = Params {
//!     levels: BySize::Same(2),
//!     meshes: vec![("ico".into(), MeshSource::Icosphere { radius: 1.0, level: 0 })],
//!     root: Default::default(),
//! };
//! let r = run(&p, Size::Quick, &mut NullRecorder::default()).unwrap();
//! assert_eq!(r.get_f64("prolongation_max_abs_err"), 0.0);
//! assert_eq!(r.get_f64("ico_euler_characteristic"), 2.0);
//! ```

use std::path::PathBuf;
use std::time::Instant;

use serde::{Deserialize, Serialize};

use crate::error::Result;
use crate::experiment::{BySize, Report, Size, Target};
use crate::linalg::Csr;
use crate::mesh::{cotan_stiffness, face_areas, mass_p1, subdivide_linear, TriMesh};
use crate::record::{Cell, Recorder, Series};
use crate::stats::nan_max;

use super::MeshSource;

/// The scene's `params` block.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Params {
    /// Subdivision levels (0 ..= levels are measured).
    pub levels: BySize<u32>,
    /// The coarse meshes.
    pub meshes: Vec<(String, MeshSource)>,
    /// Folder relative mesh files are read from (not part of the scene file: the caller sets it).
    #[serde(skip)]
    pub root: PathBuf,
}

/// Largest |P x_coarse − x_fine| over the three coordinates (m).
pub fn prolongation_error(coarse: &TriMesh, fine: &TriMesh, p: &Csr) -> f64 {
    let mut err = 0.0f64;
    for d in 0..3 {
        let xc: Vec<f64> = coarse.positions.iter().map(|q| q[d]).collect();
        let mut xf = vec![0.0; fine.positions.len()];
        p.mul_vec(&xc, &mut xf);
        for (a, q) in xf.iter().zip(&fine.positions) {
            err = nan_max(err, (a - q[d]).abs());
        }
    }
    err
}

/// Largest entry of `|Pᵀ M_fine P − M_coarse|` over both patterns, relative to the largest entry
/// of `M_coarse`.
pub fn galerkin_error(m_coarse: &Csr, m_fine: &Csr, p: &Csr) -> f64 {
    let galerkin = p.transpose().matmul(m_fine).matmul(p);
    let mut err = 0.0f64;
    let scale = m_coarse.val.iter().fold(0.0f64, |a, v| nan_max(a, v.abs()));
    for i in 0..m_coarse.nrows {
        for m in [&galerkin, m_coarse] {
            let (cols, _) = m.row(i);
            for &j in cols {
                err = nan_max(err, (galerkin.get(i, j as usize) - m_coarse.get(i, j as usize)).abs());
            }
        }
    }
    err / scale.max(f64::MIN_POSITIVE)
}

/// Largest |row sum| and largest |L_ij − L_ji| of a stiffness matrix, relative to its largest
/// diagonal entry.
pub fn laplacian_identities(l: &Csr) -> (f64, f64) {
    let diag_max = (0..l.nrows).map(|i| l.get(i, i).abs()).fold(0.0f64, nan_max).max(f64::MIN_POSITIVE);
    let (mut rowsum, mut asym) = (0.0f64, 0.0f64);
    for i in 0..l.nrows {
        let (cols, vals) = l.row(i);
        rowsum = nan_max(rowsum, vals.iter().sum::<f64>().abs() / diag_max);
        for (&j, &v) in cols.iter().zip(vals) {
            asym = nan_max(asym, (v - l.get(j as usize, i)).abs() / diag_max);
        }
    }
    (rowsum, asym)
}

/// Measures every mesh at every level; see the module docs.
pub fn run(p: &Params, size: Size, rec: &mut dyn Recorder) -> Result<Report> {
    let levels = p.levels.get(size);
    let mut s = Report::default();
    rec.table(
        "levels",
        &[
            "mesh",
            "level",
            "vertices",
            "faces",
            "euler",
            "prolongation_err",
            "area_rel_err",
            "galerkin_mass_err",
            "laplacian_rowsum_max",
            "laplacian_asym_max",
            "subdivide_s",
            "cotan_s",
        ],
    )?;
    let (mut worst_p, mut worst_area, mut worst_galerkin, mut worst_rowsum, mut worst_asym) =
        (0.0f64, 0.0f64, 0.0f64, 0.0f64, 0.0f64);
    for (mi, (name, src)) in p.meshes.iter().enumerate() {
        rec.progress(mi as u64, p.meshes.len() as u64);
        let coarse = src.build(&p.root)?;
        let area0: f64 = face_areas(&coarse.faces, &coarse.positions).iter().sum();
        let m_coarse = mass_p1(&coarse.faces, &coarse.positions);
        let mut pts = Vec::new();
        for level in 0..=levels {
            let t0 = Instant::now();
            let (fine, pmat) = subdivide_linear(&coarse, level);
            let t_sub = t0.elapsed().as_secs_f64();
            let perr = prolongation_error(&coarse, &fine, &pmat);
            // Area of the fine mesh (linear subdivision keeps every coarse triangle's plane).
            let area: f64 = face_areas(&fine.faces, &fine.positions).iter().sum();
            let area_err = (area - area0).abs() / area0.max(f64::MIN_POSITIVE);
            let gerr = galerkin_error(&m_coarse, &mass_p1(&fine.faces, &fine.positions), &pmat);
            let t1 = Instant::now();
            let l = cotan_stiffness(&fine.faces, &fine.positions, None);
            let t_cot = t1.elapsed().as_secs_f64();
            let (rowsum, asym) = laplacian_identities(&l);
            let topo = fine.topology();
            let euler = topo.n_vertices() as i64 - topo.n_edges() as i64 + topo.n_faces() as i64;
            rec.row(
                "levels",
                &[
                    name.as_str().into(),
                    level.into(),
                    fine.positions.len().into(),
                    fine.faces.len().into(),
                    Cell::Int(euler),
                    perr.into(),
                    area_err.into(),
                    gerr.into(),
                    rowsum.into(),
                    asym.into(),
                    t_sub.into(),
                    t_cot.into(),
                ],
            )?;
            pts.push((fine.faces.len() as f64, t_sub.max(1e-7)));
            worst_p = nan_max(worst_p, perr);
            worst_area = nan_max(worst_area, area_err);
            worst_galerkin = nan_max(worst_galerkin, gerr);
            worst_rowsum = nan_max(worst_rowsum, rowsum);
            worst_asym = nan_max(worst_asym, asym);
            if level == levels {
                s.count(&format!("{name}_fine_vertices"), fine.positions.len() as u64);
                s.count(&format!("{name}_euler_characteristic"), euler.max(0) as u64);
                s.timing(&format!("{name}_subdivide_s"), t_sub);
            }
        }
        rec.series(&Series {
            plot: "subdivide_time".into(),
            label: name.clone(),
            axes: ("faces".into(), "time (s)".into()),
            log: (true, true),
            points: pts,
        })?;
    }
    s.num("prolongation_max_abs_err", worst_p);
    s.num("area_max_rel_err", worst_area);
    s.num("galerkin_mass_max_rel_err", worst_galerkin);
    s.num("laplacian_rowsum_max_rel", worst_rowsum);
    s.num("laplacian_asymmetry_max_rel", worst_asym);
    s.count("levels", levels as u64);
    s.check("prolongation_max_abs_err", Target::Equals(0.0), "linear subdivision: P reproduces the fine mesh");
    s.check("galerkin_mass_max_rel_err", Target::AtMost(1e-12), "Pᵀ M_fine P = M_coarse (P1 mass)");
    s.check("laplacian_rowsum_max_rel", Target::AtMost(1e-12), "cotangent stiffness: constants in the kernel");
    s.check("laplacian_asymmetry_max_rel", Target::AtMost(1e-12), "cotangent stiffness is symmetric");
    Ok(s)
}

//! The procedural arm of the paper's Figure 3 (spec §6.1): an open quad tube (8 around × 23
//! rings = 184 vertices, 176 quads) along +X around a shoulder–elbow–wrist chain, with the
//! named node sets of the muscle and elbow examples (spec §12.5, decision: centre lines of the
//! biceps and triceps).
//!
//! Conventions: ring `r` sits at `x = r · L / along` (`L = upper_len + fore_len`), vertex
//! `(r, k) = r · around + k` at angle `θ_k = 2π (k + ½) / around` measured from +Y towards +Z:
//! `(x, R cos θ_k, R sin θ_k)`. +Y is the front (the biceps side, towards which the elbow
//! flexes), −Y the back (triceps). Faces `[v(r,k), v(r,k+1), v(r+1,k+1), v(r+1,k)]`.
//!
//! The tube is `geom_core::procedural::tube` (vertex numbering `r · around + k`) with the
//! vertices offset by half a step ([`open_tube`]).

use crate::error::{BarNetError, Result};
use geom_core::math::{Pt3, Vec3};
use geom_core::mesh::PolyMesh;
use geom_core::procedural::{tube, Caps, TubeSpec};
use serde::{Deserialize, Serialize};

/// An open quad tube along +X from the origin: `around` vertices per ring, `along` quad rows,
/// radius `radius`, length `length` (m). Topology and numbering are those of
/// `geom_core::procedural::tube` (open); the vertices are the odd columns of the tube with
/// `2·around` vertices per ring, i.e. at `θ_k = 2π (2k + 1) / (2·around)` — exactly (bit for bit)
/// the half-step angles `2π (k + ½) / around` of the module docs. No UVs. Errors: those of `tube`
/// (non-positive radius or length, `around` < 3, `along` < 1).
pub fn open_tube(around: u32, along: u32, radius: f64, length: f64) -> Result<PolyMesh> {
    let spec = TubeSpec { radius, length, around, along, start: Pt3::origin(), axis: Vec3::x(), caps: Caps::Open };
    let mut m = tube(&spec)?;
    let fine = tube(&TubeSpec { around: 2 * around, ..spec })?;
    for (i, p) in m.positions.iter_mut().enumerate() {
        *p = fine.positions[2 * i + 1];
    }
    m.uv = None;
    Ok(m)
}

/// Parameters of the procedural arm (spec §2.3 `ProceduralArm`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ArmSpec {
    /// Vertices per ring (≥ 4, even).
    pub around: u32,
    /// Quad rows along the arm.
    pub along: u32,
    /// Tube radius (m).
    pub radius: f64,
    /// Shoulder–elbow length (m).
    pub upper_len: f64,
    /// Elbow–wrist length (m).
    pub fore_len: f64,
}

impl Default for ArmSpec {
    fn default() -> Self {
        Self { around: 8, along: 22, radius: 0.045, upper_len: 0.30, fore_len: 0.27 }
    }
}

/// The arm control mesh, its joint positions and named node sets.
#[derive(Clone, Debug)]
pub struct Arm {
    /// The parameters.
    pub spec: ArmSpec,
    /// The control mesh (rest pose).
    pub mesh: PolyMesh,
    /// Joint names, `["shoulder", "elbow", "wrist"]`.
    pub joint_names: Vec<String>,
    /// Rest joint positions (m).
    pub joints: Vec<Pt3>,
}

impl Arm {
    /// Builds the arm. Errors: `around` odd or < 4, `along` < 4, non-positive lengths.
    pub fn new(spec: &ArmSpec) -> Result<Self> {
        if spec.around < 4 || !spec.around.is_multiple_of(2) || spec.along < 4 {
            return Err(BarNetError::InvalidParameter(format!(
                "arm: around = {} must be even and ≥ 4, along = {} ≥ 4",
                spec.around, spec.along
            )));
        }
        if [spec.radius, spec.upper_len, spec.fore_len].iter().any(|v| v.is_nan() || *v <= 0.0) {
            return Err(BarNetError::InvalidParameter("arm: radius and lengths must be positive".into()));
        }
        let len = spec.upper_len + spec.fore_len;
        Ok(Self {
            spec: spec.clone(),
            mesh: open_tube(spec.around, spec.along, spec.radius, len)?,
            joint_names: vec!["shoulder".into(), "elbow".into(), "wrist".into()],
            joints: vec![Pt3::origin(), Pt3::new(spec.upper_len, 0.0, 0.0), Pt3::new(len, 0.0, 0.0)],
        })
    }

    /// Ring spacing (m).
    pub fn dx(&self) -> f64 {
        (self.spec.upper_len + self.spec.fore_len) / self.spec.along as f64
    }

    /// Vertex `(ring r, column k)`.
    pub fn vertex(&self, r: usize, k: usize) -> u32 {
        (r * self.spec.around as usize + k % self.spec.around as usize) as u32
    }

    /// Ring nearest to the middle of the upper arm.
    pub fn upper_mid_ring(&self) -> usize {
        (0.5 * self.spec.upper_len / self.dx()).round() as usize
    }

    /// Ring nearest to the elbow (ring 12 of 0–22 for the default arm).
    pub fn elbow_ring(&self) -> usize {
        (self.spec.upper_len / self.dx()).round() as usize
    }

    /// The two front (+Y, biceps) columns and the two back (−Y, triceps) columns.
    pub fn muscle_columns(&self) -> ([usize; 2], [usize; 2]) {
        let a = self.spec.around as usize;
        ([a - 1, 0], [a / 2 - 1, a / 2])
    }

    /// A named node set (spec §12.5):
    /// - `biceps_triceps_12`: the 12 free nodes of the muscle example — biceps (2 front columns
    ///   × 3 rings around the middle of the upper arm) and triceps (the same at the back);
    /// - `biceps_mid`, `triceps_mid`: the middle ring of each muscle (2 nodes each);
    /// - `biceps_ends`, `triceps_ends`: the two end rings of each muscle (4 nodes each);
    /// - `elbow_ring`: the ring nearest the elbow (8 nodes); `elbow_24`: it and its two
    ///   neighbouring rings (24 nodes).
    ///
    /// Errors: unknown name (the message lists the known ones).
    pub fn named(&self, name: &str) -> Result<Vec<u32>> {
        let m = self.upper_mid_ring();
        let e = self.elbow_ring();
        let (front, back) = self.muscle_columns();
        let a = self.spec.around as usize;
        let set = |rings: &[usize], cols: &[usize]| -> Vec<u32> {
            let mut v: Vec<u32> =
                rings.iter().flat_map(|&r| cols.iter().map(move |&k| (r, k))).map(|(r, k)| self.vertex(r, k)).collect();
            v.sort_unstable();
            v
        };
        let all: Vec<usize> = (0..a).collect();
        let both: Vec<usize> = front.iter().chain(back.iter()).copied().collect();
        Ok(match name {
            "biceps_triceps_12" => set(&[m - 1, m, m + 1], &both),
            "biceps_mid" => set(&[m], &front),
            "triceps_mid" => set(&[m], &back),
            "biceps_ends" => set(&[m - 1, m + 1], &front),
            "triceps_ends" => set(&[m - 1, m + 1], &back),
            "biceps" => set(&[m - 1, m, m + 1], &front),
            "triceps" => set(&[m - 1, m, m + 1], &back),
            "elbow_ring" => set(&[e], &all),
            "elbow_24" => set(&[e - 1, e, e + 1], &all),
            _ => {
                return Err(BarNetError::InvalidParameter(format!(
                    "unknown arm node set '{name}'; known: biceps_triceps_12, biceps, triceps, biceps_mid, \
                     triceps_mid, biceps_ends, triceps_ends, elbow_ring, elbow_24"
                )))
            }
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn open_tube_is_the_half_step_layout_exactly() {
        // Bit-for-bit (x, R cos θ_k, R sin θ_k) with θ_k = 2π(k + ½)/around, x = L·r/along.
        let (n, m, r, l) = (8u32, 22u32, 0.045, 0.57);
        let t = open_tube(n, m, r, l).unwrap();
        for ring in 0..=m as usize {
            for k in 0..n as usize {
                let th = std::f64::consts::TAU * (k as f64 + 0.5) / n as f64;
                let x = l * ring as f64 / m as f64;
                assert_eq!(t.positions[ring * n as usize + k], Pt3::new(x, r * th.cos(), r * th.sin()));
            }
        }
        assert_eq!(t.faces.row(0), &[0, 1, n + 1, n]);
        assert!(t.uv.is_none());
    }

    #[test]
    fn default_arm_matches_the_paper_layout() {
        let arm = Arm::new(&ArmSpec::default()).unwrap();
        assert_eq!(arm.mesh.positions.len(), 184);
        assert_eq!(arm.mesh.faces.len(), 176);
        assert_eq!(arm.elbow_ring(), 12);
        assert_eq!(arm.named("biceps_triceps_12").unwrap().len(), 12);
        assert_eq!(arm.named("elbow_24").unwrap().len(), 24);
        let mid = arm.named("biceps_mid").unwrap();
        // The biceps middle nodes face +Y.
        for v in mid {
            assert!(arm.mesh.positions[v as usize].y > 0.04);
        }
        assert!(arm.named("deltoid").is_err());
    }
}

//! Rest mesh, per-triangle local rest frames and deformation measures (spec §3.3).
//!
//! Rest frame of triangle t: `e1 = (P1−P0)/|P1−P0|`, `n = unit((P1−P0)×(P2−P0))`, `e2 = n×e1`;
//! local corners `x0 = (0,0)`, `x1 = (L,0)`, `x2 = (u,v)` with `v > 0`; `Dm = [x1 x2]`.
//! Per frame: `Ds = [p1−p0, p2−p0]`, `F = Ds·Dm⁻¹` (3×2), `C = FᵀF`, `E = ½(C − I)`.

use geom_core::math::{Mat2, Pt2, Pt3, Vec2, Vec3};
use geom_core::mesh::{TriMesh, Uv};
use nalgebra::Matrix3x2;

use crate::error::{Result, WrinkleError};

/// Rest triangles whose area is below this times the mean rest area are `DegenerateRest`
/// (spec §3.7, §4).
pub const DEGENERATE_REL_AREA: f64 = 1e-10;

/// A UV map with `|det J| ≤ this·‖J‖_F²` is singular (`DegenerateUv`): the UV triangle is a
/// sliver whose pattern is effectively one-dimensional noise.
pub const DEGENERATE_UV_REL: f64 = 1e-10;

/// The rest mesh: positions (m), faces, UVs. Unlike `geom_core::TriMesh`, zero-area faces are
/// accepted (they become `DegenerateRest`, spec §8) and no manifoldness is required.
#[derive(Clone, Debug)]
pub struct RestMesh {
    /// Rest positions (m).
    pub positions: Vec<Pt3>,
    /// Triangles (counter-clockwise seen from the front).
    pub faces: Vec<[u32; 3]>,
    /// Texture coordinates (per vertex or per corner).
    pub uvs: Uv,
}

impl RestMesh {
    /// Validates and builds a rest mesh.
    ///
    /// Errors: [`WrinkleError::NonFinitePosition`], [`WrinkleError::BadFace`] (index out of range or
    /// repeated), [`WrinkleError::InvalidOption`] when the UV array length does not match.
    pub fn new(positions: Vec<Pt3>, faces: Vec<[u32; 3]>, uvs: Uv) -> Result<Self> {
        if let Some(v) = positions.iter().position(|p| !p.coords.iter().all(|c| c.is_finite())) {
            return Err(WrinkleError::NonFinitePosition { vertex: v });
        }
        let n = positions.len();
        for (f, t) in faces.iter().enumerate() {
            for k in 0..3 {
                if t[k] as usize >= n || t[k] == t[(k + 1) % 3] {
                    return Err(WrinkleError::BadFace { face: f, index: t[k], n_vertices: n });
                }
            }
        }
        let ok = match &uvs {
            Uv::PerVertex(u) => u.len() == n && u.iter().all(|p| p.x.is_finite() && p.y.is_finite()),
            Uv::PerCorner(u) => {
                u.len() == faces.len() && u.iter().flatten().all(|p| p.x.is_finite() && p.y.is_finite())
            }
        };
        if !ok {
            return Err(WrinkleError::InvalidOption(
                "UVs: wrong length (per vertex or per face corner expected) or non-finite value".into(),
            ));
        }
        Ok(Self { positions, faces, uvs })
    }

    /// From a geom-core mesh with UVs ([`WrinkleError::MissingUv`] without).
    pub fn from_trimesh(m: &TriMesh) -> Result<Self> {
        let uv = m.uv.clone().ok_or(WrinkleError::MissingUv)?;
        Self::new(m.positions.clone(), m.faces.clone(), uv)
    }

    /// UV of corner `k` of face `f`.
    pub fn uv(&self, f: usize, k: usize) -> Pt2 {
        self.uvs.corner(f, &self.faces[f], k)
    }
}

/// Per-triangle rest data (computed once).
#[derive(Clone, Debug)]
pub struct RestFrame {
    /// Local axis e1 (unit), e2 (unit), normal n (unit), all zero for a degenerate triangle.
    pub e1: Vec3,
    /// Local axis e2 = n × e1.
    pub e2: Vec3,
    /// Rest unit normal.
    pub n: Vec3,
    /// `Dm = [x1 x2]` = `[[L, u], [0, v]]` (m).
    pub dm: Mat2,
    /// `Dm⁻¹` (zero for a degenerate triangle).
    pub dm_inv: Mat2,
    /// Flat rest area A_T = ½Lv (m²).
    pub area: f64,
    /// UV Jacobian: `uv(x) = uv0 + J·x` (x local, m).
    pub j: Mat2,
    /// Gradients of the barycentric coordinates in local coordinates (1/m).
    pub grad_bary: [Vec2; 3],
    /// The rest triangle is degenerate (area below [`DEGENERATE_REL_AREA`]·mean).
    pub degenerate: bool,
    /// The UV map is singular.
    pub degenerate_uv: bool,
}

/// Builds the rest frames of all triangles.
pub fn rest_frames(mesh: &RestMesh) -> Vec<RestFrame> {
    let raw: Vec<f64> = mesh
        .faces
        .iter()
        .map(|t| {
            let p = |k: usize| mesh.positions[t[k] as usize];
            0.5 * (p(1) - p(0)).cross(&(p(2) - p(0))).norm()
        })
        .collect();
    let mean = if raw.is_empty() { 0.0 } else { raw.iter().sum::<f64>() / raw.len() as f64 };
    mesh.faces
        .iter()
        .enumerate()
        .map(|(f, t)| {
            let p = |k: usize| mesh.positions[t[k] as usize];
            let (d1, d2) = (p(1) - p(0), p(2) - p(0));
            let len = d1.norm();
            let nn = d1.cross(&d2);
            let degenerate = raw[f].is_nan() || raw[f] <= DEGENERATE_REL_AREA * mean || len == 0.0;
            if degenerate {
                return RestFrame {
                    e1: Vec3::zeros(),
                    e2: Vec3::zeros(),
                    n: Vec3::zeros(),
                    dm: Mat2::zeros(),
                    dm_inv: Mat2::zeros(),
                    area: raw[f],
                    j: Mat2::zeros(),
                    grad_bary: [Vec2::zeros(); 3],
                    degenerate: true,
                    degenerate_uv: false,
                };
            }
            let e1 = d1 / len;
            let n = nn / nn.norm();
            let e2 = n.cross(&e1);
            let dm = Mat2::new(len, d2.dot(&e1), 0.0, d2.dot(&e2));
            let dm_inv = Mat2::new(1.0 / dm[(0, 0)], -dm[(0, 1)] / (dm[(0, 0)] * dm[(1, 1)]), 0.0, 1.0 / dm[(1, 1)]);
            let (uv0, uv1, uv2) = (mesh.uv(f, 0), mesh.uv(f, 1), mesh.uv(f, 2));
            let duv = Mat2::from_columns(&[uv1 - uv0, uv2 - uv0]);
            let j = duv * dm_inv;
            let degenerate_uv =
                j.determinant().abs() <= DEGENERATE_UV_REL * j.norm_squared() || !j.iter().all(|v| v.is_finite());
            // λ1 = row 0 of Dm⁻¹·x, λ2 = row 1, λ0 = 1 − λ1 − λ2.
            let g1 = Vec2::new(dm_inv[(0, 0)], dm_inv[(0, 1)]);
            let g2 = Vec2::new(dm_inv[(1, 0)], dm_inv[(1, 1)]);
            RestFrame {
                e1,
                e2,
                n,
                dm,
                dm_inv,
                area: 0.5 * dm[(0, 0)] * dm[(1, 1)],
                j,
                grad_bary: [-(g1 + g2), g1, g2],
                degenerate: false,
                degenerate_uv,
            }
        })
        .collect()
}

/// Deformation of one triangle at one frame.
#[derive(Clone, Copy, Debug)]
pub struct Deformation {
    /// Deformation gradient `F = Ds·Dm⁻¹` (3×2).
    pub f: Matrix3x2<f64>,
    /// Right Cauchy–Green tensor `C = FᵀF`.
    pub c: Mat2,
    /// Unnormalised deformed normal `(p1−p0)×(p2−p0)`.
    pub area_vector: Vec3,
}

impl Deformation {
    /// From rest frame and deformed corner positions.
    pub fn new(rf: &RestFrame, p: [&Pt3; 3]) -> Self {
        let (d1, d2) = (p[1] - p[0], p[2] - p[0]);
        let ds = Matrix3x2::from_columns(&[d1, d2]);
        let f = ds * rf.dm_inv;
        Self { f, c: f.transpose() * f, area_vector: d1.cross(&d2) }
    }

    /// A pure in-plane deformation with gradient `f2` (2×2) in the rest frame (tests, prescribed
    /// drivers): `F = [f2; 0]`.
    pub fn from_f2(f2: &Mat2) -> Self {
        let f = Matrix3x2::new(f2[(0, 0)], f2[(0, 1)], f2[(1, 0)], f2[(1, 1)], 0.0, 0.0);
        let c = f2.transpose() * f2;
        Self { f, c, area_vector: Vec3::new(0.0, 0.0, f2.determinant()) }
    }

    /// Green strain `E = ½(C − I)`.
    pub fn green(&self) -> Mat2 {
        0.5 * (self.c - Mat2::identity())
    }

    /// The paper's upper-triangular parameters (a, b, d) with edge 0 as the x axis (spec §3.3,
    /// reconstructed): `a = √C11`, `b = C12/a`, `d = √det C / a`; zero when a = 0.
    pub fn paper_abd(&self) -> (f64, f64, f64) {
        let a = self.c[(0, 0)].max(0.0).sqrt();
        if a == 0.0 {
            return (0.0, 0.0, 0.0);
        }
        let det = self.c.determinant().max(0.0);
        (a, self.c[(0, 1)] / a, det.sqrt() / a)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frame_reproduces_rest_and_f_is_rigid_invariant() {
        let pos = vec![Pt3::new(0.1, 0.2, 0.3), Pt3::new(0.5, 0.1, 0.4), Pt3::new(0.2, 0.6, 0.0)];
        let uv = Uv::PerVertex(vec![Pt2::new(0.0, 0.0), Pt2::new(1.0, 0.0), Pt2::new(0.0, 1.0)]);
        let m = RestMesh::new(pos.clone(), vec![[0, 1, 2]], uv).unwrap();
        let rf = &rest_frames(&m)[0];
        let d = Deformation::new(rf, [&pos[0], &pos[1], &pos[2]]);
        assert!((d.c - Mat2::identity()).norm() < 1e-14);
        // UV map reproduces the corners.
        let x2 = Vec2::new(rf.dm[(0, 1)], rf.dm[(1, 1)]);
        assert!((rf.j * x2 - Vec2::new(0.0, 1.0)).norm() < 1e-14);
        // Barycentric gradients: ∇λ1·x1 = 1, ∇λ2·x2 = 1.
        assert!((rf.grad_bary[1].dot(&Vec2::new(rf.dm[(0, 0)], 0.0)) - 1.0).abs() < 1e-14);
        assert!((rf.grad_bary[2].dot(&x2) - 1.0).abs() < 1e-14);
    }
}

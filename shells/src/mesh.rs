//! [`ShellMesh`]: the immutable simulation mesh with its rest quantities (shells.md §3.1):
//! consistently oriented triangles, per-triangle rest data, one hinge per interior edge and
//! lumped masses.

use crate::error::{Error, Result};
use crate::kernels::bending::Hinge;
use crate::kernels::hinge::{hinge_angle, hinge_is_collapsed};
use crate::kernels::membrane::TriRest;
use crate::material::{Material, MembraneLaw, WarpSource};
use geom_core::math::{Pt2, Pt3, Vec3};
use geom_core::mesh::{TriMesh, Uv};
use std::collections::HashMap;

/// Relative area below which a rest triangle is rejected: area < `DEGENERATE_REL`·L², L the
/// bounding-box diagonal (§8).
pub const DEGENERATE_REL: f64 = 1e-12;

/// The simulation mesh (topology fixed for the lifetime of a simulation).
#[derive(Clone, Debug)]
pub struct ShellMesh {
    /// Undeformed (rest) positions X_i (m).
    pub rest: Vec<Pt3>,
    /// Consistently oriented triangles.
    pub tris: Vec<[u32; 3]>,
    /// One hinge per interior edge (rest angle, weight, stiffness).
    pub hinges: Vec<Hinge>,
    /// Per-triangle rest data (area, shape-function gradients in the law's rest frame).
    pub tri_rest: Vec<TriRest>,
    /// Unique undirected edges `[a, b]`, a < b (for edge–edge collision tests).
    pub edges: Vec<[u32; 2]>,
    /// Lumped masses m_i = ρ_s Σ_{T∋i} Ā_T/3 (kg).
    pub mass: Vec<f64>,
    /// Number of sliver rest triangles (min angle < 1°), allowed but reported (§8).
    pub n_slivers: usize,
}

impl ShellMesh {
    /// Builds the simulation mesh from rest positions and faces. Orientation is repaired
    /// automatically when the surface is orientable (§8).
    ///
    /// Errors: [`Error::NonFinite`] for NaN/∞ positions, [`Error::BadParameter`] for out-of-range
    /// indices, [`Error::DegenerateTriangle`] (area < 1e-12·L²), [`Error::NonManifoldEdge`] for an
    /// edge with more than two faces or a non-orientable surface, and material errors.
    /// `uv` (per-corner rest UVs) is needed for `WarpSource::RestUv`.
    pub fn new(rest: Vec<Pt3>, faces: &[[u32; 3]], uv: Option<&Uv>, material: &Material) -> Result<Self> {
        material.validate()?;
        if rest.iter().any(|p| p.iter().any(|c| !c.is_finite())) {
            return Err(Error::NonFinite("rest positions"));
        }
        let n = rest.len();
        for (f, t) in faces.iter().enumerate() {
            if t.iter().any(|&v| v as usize >= n) || t[0] == t[1] || t[1] == t[2] || t[0] == t[2] {
                return Err(Error::BadParameter(format!("face {f} has an invalid or repeated vertex index: {t:?}")));
            }
        }
        let l2 = geom_core::mesh::bbox_of(&rest).map(|(lo, hi)| (hi - lo).norm_squared()).unwrap_or(0.0);
        for (f, t) in faces.iter().enumerate() {
            let x = t.map(|v| rest[v as usize]);
            let area = 0.5 * (x[1] - x[0]).cross(&(x[2] - x[0])).norm();
            if !(area >= DEGENERATE_REL * l2) || area == 0.0 {
                return Err(Error::DegenerateTriangle(f as u32));
            }
        }
        let (tris, flipped) = orient(n, faces)?;
        let mesh = TriMesh::new(rest.clone(), tris.clone()).map_err(|e| match e {
            geom_core::Error::DegenerateFace { face } => Error::DegenerateTriangle(face),
            geom_core::Error::NonManifoldEdge { a, b, .. } => Error::NonManifoldEdge(a, b),
            other => Error::Core(other),
        })?;
        let law = &material.membrane;
        let mut tri_rest = Vec::with_capacity(tris.len());
        let mut n_slivers = 0;
        for (f, t) in tris.iter().enumerate() {
            let x = t.map(|v| rest[v as usize]);
            if min_angle(&x) < 1f64.to_radians() {
                n_slivers += 1;
            }
            let axis = match law {
                MembraneLaw::Isotropic { .. } => None,
                MembraneLaw::Orthotropic { warp: WarpSource::Direction(d), .. } => Some(*d),
                MembraneLaw::Orthotropic { warp: WarpSource::RestUv, .. } => {
                    let uv = uv.ok_or_else(|| Error::BadParameter("warp: RestUv needs rest UVs on the mesh".into()))?;
                    let mut corner: [Pt2; 3] = std::array::from_fn(|k| uv.corner(f, &faces[f], k));
                    if flipped[f] {
                        corner.swap(1, 2);
                    }
                    Some(
                        uv_u_direction(&x, &corner)
                            .ok_or_else(|| Error::BadParameter(format!("warp: degenerate UV triangle at face {f}")))?,
                    )
                }
            };
            let tr = TriRest::new(&x, axis).ok_or_else(|| {
                if axis.is_some() {
                    Error::BadParameter(format!("warp direction parallel to the normal of triangle {f}"))
                } else {
                    Error::DegenerateTriangle(f as u32)
                }
            })?;
            tri_rest.push(tr);
        }
        let topo = mesh.topology();
        let mut hinges = Vec::new();
        for hv in topo.hinges() {
            let x = hv.map(|v| rest[v as usize]);
            let a1 = 0.5 * (x[1] - x[0]).cross(&(x[2] - x[0])).norm();
            let a2 = 0.5 * (x[0] - x[1]).cross(&(x[3] - x[1])).norm();
            let el = (x[1] - x[0]).norm();
            let area_sum = a1 + a2;
            let rest_theta = if hinge_is_collapsed(&x) { 0.0 } else { hinge_angle(&x) };
            hinges.push(Hinge {
                v: hv,
                rest_theta,
                weight: 3.0 * el * el / area_sum,
                stiffness: material.bending,
                edge_len: el,
                area_sum,
            });
        }
        let edges = topo.edges().to_vec();
        let mut mass = vec![0.0; n];
        for (t, tr) in tris.iter().zip(&tri_rest) {
            for &v in t {
                mass[v as usize] += material.density * tr.area / 3.0;
            }
        }
        Ok(Self { rest, tris, hinges, tri_rest, edges, mass, n_slivers })
    }

    /// Builds from a geom-core mesh (its positions are the rest shape, its UVs the rest UVs).
    pub fn from_trimesh(m: &TriMesh, material: &Material) -> Result<Self> {
        Self::new(m.positions.clone(), &m.faces, m.uv.as_ref(), material)
    }

    /// Number of vertices.
    pub fn n_vertices(&self) -> usize {
        self.rest.len()
    }

    /// Mean rest edge length (m); 0 for a mesh without edges.
    pub fn mean_edge_length(&self) -> f64 {
        if self.edges.is_empty() {
            return 0.0;
        }
        self.edges.iter().map(|e| (self.rest[e[1] as usize] - self.rest[e[0] as usize]).norm()).sum::<f64>()
            / self.edges.len() as f64
    }
}

fn min_angle(x: &[Pt3; 3]) -> f64 {
    let mut m = f64::INFINITY;
    for k in 0..3 {
        let a = x[(k + 1) % 3] - x[k];
        let b = x[(k + 2) % 3] - x[k];
        m = m.min(a.angle(&b));
    }
    m
}

/// 3-D direction of increasing u over a triangle with corner UVs (the warp direction).
fn uv_u_direction(x: &[Pt3; 3], uv: &[Pt2; 3]) -> Option<Vec3> {
    let (d1, d2) = (uv[1] - uv[0], uv[2] - uv[0]);
    let det = d1.x * d2.y - d1.y * d2.x;
    if det.abs() < 1e-300 {
        return None;
    }
    // Position as a function of (u, v): ∂x/∂u = (e1 d2.y − e2 d1.y)/det.
    let e1 = x[1] - x[0];
    let e2 = x[2] - x[0];
    let du = (e1 * d2.y - e2 * d1.y) / det;
    (du.norm() > 0.0).then_some(du)
}

/// Orients faces consistently per connected component (breadth-first flips). Returns the
/// oriented faces and which were flipped. Errors: an edge with more than two faces, or a
/// non-orientable component (Möbius-like), both as [`Error::NonManifoldEdge`].
fn orient(n: usize, faces: &[[u32; 3]]) -> Result<(Vec<[u32; 3]>, Vec<bool>)> {
    let mut edge_faces: HashMap<(u32, u32), Vec<u32>> = HashMap::with_capacity(faces.len() * 2);
    for (f, t) in faces.iter().enumerate() {
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            edge_faces.entry((a.min(b), a.max(b))).or_default().push(f as u32);
        }
    }
    // Deterministic error reporting: smallest offending edge.
    let mut bad: Vec<(u32, u32)> = edge_faces.iter().filter(|(_, v)| v.len() > 2).map(|(k, _)| *k).collect();
    bad.sort_unstable();
    if let Some(&(a, b)) = bad.first() {
        return Err(Error::NonManifoldEdge(a, b));
    }
    let _ = n;
    let mut out = faces.to_vec();
    let mut flipped = vec![false; faces.len()];
    let mut seen = vec![false; faces.len()];
    let has_dir = |t: &[u32; 3], a: u32, b: u32| (0..3).any(|k| t[k] == a && t[(k + 1) % 3] == b);
    for start in 0..faces.len() {
        if seen[start] {
            continue;
        }
        seen[start] = true;
        let mut queue = std::collections::VecDeque::from([start]);
        while let Some(f) = queue.pop_front() {
            let t = out[f];
            for k in 0..3 {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                for &g in &edge_faces[&(a.min(b), a.max(b))] {
                    let g = g as usize;
                    if g == f {
                        continue;
                    }
                    // A consistent neighbour holds b→a.
                    if !seen[g] {
                        seen[g] = true;
                        if has_dir(&out[g], a, b) {
                            out[g].swap(1, 2);
                            flipped[g] = true;
                        }
                        queue.push_back(g);
                    } else if has_dir(&out[g], a, b) {
                        return Err(Error::NonManifoldEdge(a.min(b), a.max(b)));
                    }
                }
            }
        }
    }
    Ok((out, flipped))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn square() -> (Vec<Pt3>, Vec<[u32; 3]>) {
        let p =
            vec![Pt3::new(0.0, 0.0, 0.0), Pt3::new(1.0, 0.0, 0.0), Pt3::new(1.0, 1.0, 0.0), Pt3::new(0.0, 1.0, 0.0)];
        (p, vec![[0, 1, 2], [0, 2, 3]])
    }

    #[test]
    fn builds_hinges_and_masses() {
        let (p, f) = square();
        let m = ShellMesh::new(p, &f, None, &Material::cotton()).unwrap();
        assert_eq!(m.hinges.len(), 1);
        let h = m.hinges[0];
        assert_eq!(h.rest_theta, 0.0);
        assert!((h.weight - 3.0 * 2.0 / 1.0).abs() < 1e-14);
        let total: f64 = m.mass.iter().sum();
        assert!((total - 0.15).abs() < 1e-15);
    }

    #[test]
    fn repairs_orientation_and_rejects_bad_input() {
        let (p, _) = square();
        let m = ShellMesh::new(p.clone(), &[[0, 1, 2], [0, 3, 2]], None, &Material::cotton()).unwrap();
        assert_eq!(m.hinges.len(), 1);
        let mut q = p.clone();
        q[3] = Pt3::new(2.0, 0.0, 0.0);
        assert!(matches!(
            ShellMesh::new(q, &[[0, 1, 3]], None, &Material::cotton()),
            Err(Error::DegenerateTriangle(0))
        ));
        let mut p5 = p.clone();
        p5.push(Pt3::new(0.5, 0.5, 1.0));
        let fan = [[0, 2, 1], [0, 2, 3], [0, 2, 4]];
        assert!(matches!(ShellMesh::new(p5, &fan, None, &Material::cotton()), Err(Error::NonManifoldEdge(0, 2))));
        let mut nan = p.clone();
        nan[0].x = f64::NAN;
        assert!(matches!(ShellMesh::new(nan, &[[0, 1, 2]], None, &Material::cotton()), Err(Error::NonFinite(_))));
        let mut neg = Material::cotton();
        neg.density = -1.0;
        assert!(matches!(ShellMesh::new(p, &[[0, 1, 2]], None, &neg), Err(Error::BadParameter(_))));
    }
}

//! [`WrapBinding`]: an arbitrary fine polygon mesh bound to the control mesh's triangles (spec
//! §3.4.4 `Wrap`, decision §12.4: a documented surface-oriented wrap in the spirit of Singh and
//! Kokkevis 2000, since the commercial wrap deformer is unpublished).
//!
//! Binding (rest pose): each fine vertex is bound to its `k` closest control triangles (n-gons
//! fan-triangulated): per triangle the barycentric coordinates of the foot point and the offset
//! from it expressed in the triangle's orthonormal frame (`e₁` = first edge direction, `n` =
//! unit normal, `e₂ = n × e₁`), blended with normalised inverse-distance weights
//! (`k = 1` by default, `k = 4` smooths kinks at triangle borders). Evaluation: rebuild the
//! frames and evaluate — the rest pose is reproduced exactly (to rounding) and a rigid motion
//! of the control mesh moves the fine mesh rigidly (spec 7.3 d). A triangle whose area drops
//! below 1e-14 (a fold) keeps its previous frame (spec §8).

use crate::error::{BarNetError, Result};
use geom_core::math::{Mat3, Pt3, Vec3};
use geom_core::mesh::PolyMesh;
/// Closest point on a triangle and its barycentric coordinates (Ericson §5.1.5), from
/// geom-core; re-exported under its former path.
pub use geom_core::query::closest_point_triangle;

/// One fine vertex's binding to one control triangle.
#[derive(Clone, Copy, Debug)]
struct Bind {
    tri: u32,
    bary: [f64; 3],
    offset: Vec3,
    weight: f64,
}

/// Fine mesh bound to a control mesh; see the module docs.
#[derive(Clone, Debug)]
pub struct WrapBinding {
    tris: Vec<[u32; 3]>,
    /// Per fine vertex, `k` bindings (flattened, `k` per vertex).
    binds: Vec<Bind>,
    k: usize,
    frames: Vec<Mat3>,
}

/// Orthonormal frame `[e₁ e₂ n]` (columns) of a triangle, `None` when its area is < 1e-14.
fn tri_frame(a: &Pt3, b: &Pt3, c: &Pt3) -> Option<Mat3> {
    let e = b - a;
    let n = e.cross(&(c - a));
    if 0.5 * n.norm() < 1e-14 || e.norm() == 0.0 {
        return None;
    }
    let e1 = e.normalize();
    let n = n.normalize();
    let e2 = n.cross(&e1);
    Some(Mat3::from_columns(&[e1, e2, n]))
}

impl WrapBinding {
    /// Binds `fine` (rest positions) to `control` (rest pose), `k_tris` triangles per vertex.
    /// Errors: `k_tris` = 0, a control mesh without non-degenerate triangles.
    pub fn bind(control: &PolyMesh, fine: &[Pt3], k_tris: usize) -> Result<Self> {
        if k_tris == 0 {
            return Err(BarNetError::InvalidParameter("wrap k_tris must be ≥ 1".into()));
        }
        let p = &control.positions;
        let mut tris = Vec::new();
        for row in control.faces.rows() {
            for i in 1..row.len().saturating_sub(1) {
                tris.push([row[0], row[i], row[i + 1]]);
            }
        }
        let mut frames = Vec::with_capacity(tris.len());
        let mut good = Vec::with_capacity(tris.len());
        for t in &tris {
            match tri_frame(&p[t[0] as usize], &p[t[1] as usize], &p[t[2] as usize]) {
                Some(f) => {
                    frames.push(f);
                    good.push(true);
                }
                None => {
                    frames.push(Mat3::identity());
                    good.push(false);
                }
            }
        }
        let k = k_tris.min(good.iter().filter(|&&g| g).count());
        if k == 0 {
            return Err(BarNetError::InvalidParameter("wrap: control mesh has no non-degenerate triangle".into()));
        }
        let mut binds = Vec::with_capacity(fine.len() * k);
        let mut cand: Vec<(f64, u32, Pt3, [f64; 3])> = Vec::with_capacity(tris.len());
        for x in fine {
            cand.clear();
            for (ti, t) in tris.iter().enumerate() {
                if !good[ti] {
                    continue;
                }
                let tp = [p[t[0] as usize], p[t[1] as usize], p[t[2] as usize]];
                let (foot, bary) = closest_point_triangle(x, &tp);
                cand.push(((x - foot).norm(), ti as u32, foot, bary));
            }
            // Ties broken by triangle index: deterministic.
            cand.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
            let chosen = &cand[..k];
            let eps = 1e-9;
            let wsum: f64 = chosen.iter().map(|c| 1.0 / (c.0 + eps)).sum();
            for c in chosen {
                let f = frames[c.1 as usize];
                binds.push(Bind {
                    tri: c.1,
                    bary: c.3,
                    offset: f.transpose() * (x - c.2),
                    weight: 1.0 / (c.0 + eps) / wsum,
                });
            }
        }
        Ok(Self { tris, binds, k, frames })
    }

    /// Number of bound fine vertices.
    pub fn len(&self) -> usize {
        self.binds.len() / self.k
    }

    /// True when no fine vertex is bound.
    pub fn is_empty(&self) -> bool {
        self.binds.is_empty()
    }

    /// Evaluates the fine positions for deformed control positions `p` (f64 accumulation).
    pub fn eval(&mut self, p: &[Pt3], out: &mut [Pt3]) {
        for (ti, t) in self.tris.iter().enumerate() {
            if let Some(f) = tri_frame(&p[t[0] as usize], &p[t[1] as usize], &p[t[2] as usize]) {
                self.frames[ti] = f;
            }
        }
        for (v, o) in out.iter_mut().enumerate().take(self.len()) {
            let mut acc = Vec3::zeros();
            for b in &self.binds[v * self.k..(v + 1) * self.k] {
                let t = self.tris[b.tri as usize];
                let foot = p[t[0] as usize].coords * b.bary[0]
                    + p[t[1] as usize].coords * b.bary[1]
                    + p[t[2] as usize].coords * b.bary[2];
                acc += (foot + self.frames[b.tri as usize] * b.offset) * b.weight;
            }
            *o = Pt3::from(acc);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use geom_core::math::Iso3;

    /// Spec 7.3 d: rest fine mesh reproduced exactly; rigid motion ⇒ rigid (1e-12).
    #[test]
    fn wrap_reproduces_rest_and_is_rigid() {
        let control = crate::arm::open_tube(8, 22, 0.045, 0.57).unwrap();
        let fine = crate::arm::open_tube(13, 31, 0.05, 0.57).unwrap().positions;
        for k in [1, 4] {
            let mut w = WrapBinding::bind(&control, &fine, k).unwrap();
            let mut out = vec![Pt3::origin(); fine.len()];
            w.eval(&control.positions, &mut out);
            let e = out.iter().zip(&fine).map(|(a, b)| (a - b).norm()).fold(0.0, f64::max);
            assert!(e < 1e-12, "k = {k}: rest error {e}");
            let g = Iso3::new(Vec3::new(0.3, -1.0, 2.0), Vec3::new(0.7, -0.5, 1.1));
            let moved: Vec<Pt3> = control.positions.iter().map(|p| g * p).collect();
            w.eval(&moved, &mut out);
            let e = out.iter().zip(&fine).map(|(a, b)| (a - g * b).norm()).fold(0.0, f64::max);
            assert!(e < 1e-12, "k = {k}: rigid error {e}");
        }
    }

    #[test]
    fn closest_point_regions() {
        let t = [Pt3::new(0.0, 0.0, 0.0), Pt3::new(1.0, 0.0, 0.0), Pt3::new(0.0, 1.0, 0.0)];
        let (p, b) = closest_point_triangle(&Pt3::new(0.25, 0.25, 1.0), &t);
        assert!((p - Pt3::new(0.25, 0.25, 0.0)).norm() < 1e-15);
        assert!((b[0] - 0.5).abs() < 1e-15);
        let (p, _) = closest_point_triangle(&Pt3::new(-1.0, -1.0, 0.0), &t);
        assert_eq!(p, t[0]);
        let (p, b) = closest_point_triangle(&Pt3::new(1.0, 1.0, 0.0), &t);
        assert!((p - Pt3::new(0.5, 0.5, 0.0)).norm() < 1e-15 && b[0].abs() < 1e-15);
    }
}

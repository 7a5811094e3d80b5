//! Deforming-mesh obstacles (issue 23 item 5): a closed triangle mesh whose vertices move per
//! frame — a skinned body — as IPC contact geometry.
//!
//! Over a step [t − h, t] the obstacle's vertices move linearly from their positions P⁰ at
//! t − h to P¹ at t ([`DeformingMesh::positions`] interpolates the frames linearly). The step
//! is made of two intersection-free motions:
//!
//! 1. **Carry.** The obstacle moves P⁰ → P¹ while every cloth vertex within reach is carried
//!    by the displacement of its closest obstacle point (weight 1 within d̂ + D of the surface,
//!    fading linearly to 0 at d̂ + 2D, D the largest obstacle displacement of the step): the
//!    start of the Newton solve. Additive CCD ([`super::accd`]) checks this motion with the
//!    obstacle's displacement on the obstacle's side of each pair (relative motion); a pair
//!    that would close within the step errors (the step must be shortened) instead of letting
//!    the body through the cloth.
//! 2. **Newton.** The obstacle stays at P¹; barrier distances are to the end-of-step triangles
//!    and the Newton iterates are CCD-clamped against them, exactly as for a rigid obstacle
//!    placed at its end pose.
//!
//! Lagged friction uses the cloth's motion relative to the obstacle's surface point: the
//! frozen shift c_o δ of [`super::friction`] is the barycentric blend of the obstacle
//! vertices' displacements P¹ − P⁰.
//!
//! Opt-in through [`crate::ShellSim::add_deforming_obstacle`]: a simulation without one runs
//! none of this code.

use geom_core::collide::MeshQuery;
use geom_core::math::{Pt3, Vec3};
use geom_core::mesh::TriMesh;
use rayon::prelude::*;

use crate::error::{Error, Result};

/// A closed triangle mesh whose vertices follow sampled frames.
#[derive(Clone, Debug)]
pub struct DeformingMesh {
    tris: Vec<[u32; 3]>,
    frames: Vec<Vec<Pt3>>,
    t0: f64,
    fps: f64,
    /// Cloth–obstacle Coulomb friction μ.
    pub friction: f64,
}

impl DeformingMesh {
    /// A deforming obstacle with vertex positions `frames[k]` (m) at times t0 + k/fps (s);
    /// held at the first frame before t0 and at the last after the end.
    ///
    /// Errors: no frame, frames of different sizes, a non-finite position, an out-of-range
    /// index, a mesh that is not closed (it has no inside), fps ≤ 0, friction < 0.
    pub fn new(tris: Vec<[u32; 3]>, frames: Vec<Vec<Pt3>>, t0: f64, fps: f64, friction: f64) -> Result<Self> {
        let bad = |s: String| Err(Error::BadParameter(format!("deforming obstacle: {s}")));
        let Some(first) = frames.first() else { return bad("no frame".into()) };
        let n = first.len();
        if let Some((k, f)) = frames.iter().enumerate().find(|(_, f)| f.len() != n) {
            return bad(format!("frame {k} has {} vertices, frame 0 has {n}", f.len()));
        }
        if frames.iter().flatten().any(|p| p.iter().any(|c| !c.is_finite())) {
            return Err(Error::NonFinite("deforming obstacle positions"));
        }
        if !(fps > 0.0) || !fps.is_finite() || !t0.is_finite() {
            return bad(format!("frame rate must be finite and > 0 and t0 finite, got {fps} fps, t0 {t0}"));
        }
        if !(friction >= 0.0) || !friction.is_finite() {
            return bad(format!("friction must be finite and ≥ 0, got {friction}"));
        }
        let m = TriMesh::new(first.clone(), tris.clone())
            .map_err(|e| Error::BadParameter(format!("deforming obstacle: {e}")))?;
        if m.faces.is_empty() || !m.topology().is_closed() {
            return bad(format!(
                "the mesh is not closed ({} boundary edges, {} faces): it has no inside",
                m.topology().n_boundary_edges(),
                m.faces.len()
            ));
        }
        Ok(Self { tris, frames, t0, fps, friction })
    }

    /// Triangles (outward faces).
    pub fn tris(&self) -> &[[u32; 3]] {
        &self.tris
    }

    /// Number of vertices.
    pub fn n_vertices(&self) -> usize {
        self.frames[0].len()
    }

    /// Vertex positions at time `t` (s): linear between frames, clamped at both ends.
    pub fn positions(&self, t: f64) -> Vec<Pt3> {
        let last = self.frames.len() - 1;
        let s = ((t - self.t0) * self.fps).clamp(0.0, last as f64);
        let k = (s.floor() as usize).min(last);
        let w = s - k as f64;
        if k == last || w == 0.0 {
            return self.frames[k].clone();
        }
        self.frames[k].iter().zip(&self.frames[k + 1]).map(|(a, b)| a + w * (b - a)).collect()
    }

    /// The deepest penetration (m) of points `q` into the obstacle at time `t`: the largest
    /// −signed distance, 0 when every point is outside; NaN if a point is NaN.
    pub fn max_penetration(&self, t: f64, q: &[Pt3]) -> Result<f64> {
        let mq = self.query(t)?;
        let d: Vec<f64> = q
            .par_iter()
            .with_min_len(256)
            .map(|p| if p.iter().any(|c| c.is_nan()) { f64::NAN } else { (-mq.signed_distance(p)).max(0.0) })
            .collect();
        Ok(d.iter().fold(0.0, |m, &x| geom_core::stats::nan_max(m, x)))
    }

    /// The closest-point query structure of the obstacle at time `t`.
    pub fn query(&self, t: f64) -> Result<MeshQuery> {
        let m = TriMesh::new(self.positions(t), self.tris.clone())?;
        Ok(MeshQuery::new(&m)?)
    }
}

/// The carry displacement of the cloth vertices `x` (m) for an obstacle moving `p0` → `p1`
/// over a step, with activation distance `dhat` (m): each vertex within d̂ + 2D of the surface
/// at `p0` (D the largest obstacle displacement) gets the displacement of its closest surface
/// point, weighted 1 up to d̂ + D and fading linearly to 0 at d̂ + 2D; added to `out`.
pub(crate) fn add_carry(
    tris: &[[u32; 3]],
    p0: &[Pt3],
    p1: &[Pt3],
    x: &[Pt3],
    dhat: f64,
    out: &mut [Vec3],
) -> Result<()> {
    let disp: Vec<Vec3> = p0.iter().zip(p1).map(|(a, b)| b - a).collect();
    let dmax = disp.iter().map(|d| d.norm()).fold(0.0, f64::max);
    if !(dmax > 0.0) {
        return Ok(());
    }
    let mq = MeshQuery::new(&TriMesh::new(p0.to_vec(), tris.to_vec())?)?;
    let (r_in, r_out) = (dhat + dmax, dhat + 2.0 * dmax);
    let lo = p0.iter().fold(Vec3::repeat(f64::INFINITY), |m, p| m.inf(&p.coords));
    let hi = p0.iter().fold(Vec3::repeat(f64::NEG_INFINITY), |m, p| m.sup(&p.coords));
    let carry: Vec<Vec3> = x
        .par_iter()
        .with_min_len(256)
        .map(|q| {
            if (0..3).any(|k| q[k] < lo[k] - r_out || q[k] > hi[k] + r_out) {
                return Vec3::zeros();
            }
            let c = mq.closest(q);
            if c.distance >= r_out {
                return Vec3::zeros();
            }
            let w = ((r_out - c.distance) / (r_out - r_in)).min(1.0);
            let t = tris[c.face as usize];
            w * (0..3).map(|k| c.bary[k] * disp[t[k] as usize]).sum::<Vec3>()
        })
        .collect();
    for (o, c) in out.iter_mut().zip(carry) {
        *o += c;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::super::obstacle::{mesh_edges, Core, Placed};
    use super::super::set::{self, CoreCands, Topo};
    use super::*;
    use geom_core::procedural::{box_surface, Diagonals};

    /// A triangle in the plane y = `y0` moving to y = `y1` over the step.
    fn rising(y0: f64, y1: f64) -> Placed {
        let at = |y: f64| vec![Pt3::new(-1.0, y, -1.0), Pt3::new(2.0, y, -1.0), Pt3::new(-1.0, y, 2.0)];
        Placed::Core(Box::new(Core::moving(&at(y0), at(y1), mesh_edges(&[[0, 1, 2]]), vec![[0, 1, 2]])))
    }

    #[test]
    fn ccd_against_a_moving_triangle_uses_the_relative_motion() {
        let p = rising(0.0, 2.0);
        let c = CoreCands { v_ot: vec![(0, 0)], ..Default::default() };
        let x = [Pt3::new(0.2, 1.0, 0.2)];
        let toi = |dx: Vec3, relative: bool| super::super::obstacle_toi(&p, &c, &x, &[dx], &[], &[], 1e-9, relative);
        // Gap 1 m closing at 2 m per step; the CCD stops at 10 % of the gap: t* = 0.45.
        let a = toi(Vec3::zeros(), true);
        assert!(a <= 0.45 && a > 0.44, "{a}");
        // Falling at 1 m per step toward it: closing at 3, t* = 0.3.
        let a = toi(Vec3::new(0.0, -1.0, 0.0), true);
        assert!(a <= 0.3 && a > 0.29, "{a}");
        // Carried with it: no relative motion, no bound.
        assert_eq!(toi(Vec3::new(0.0, 2.0, 0.0), true), 1.0);
        // The Newton phase: the triangle fixed at its end (y = 2), the still point 1 m below.
        assert_eq!(toi(Vec3::zeros(), false), 1.0);
    }

    #[test]
    fn barrier_distances_are_to_the_end_of_step_triangle() {
        let p = rising(0.0, 0.5);
        let c = CoreCands { v_ot: vec![(0, 0)], ..Default::default() };
        let topo = Topo { tris: &[], edges: &[], mean_edge: 1.0, mu_self: 0.0 };
        let x = [Pt3::new(0.2, 0.51, 0.2)];
        let cs = set::obstacle_contacts(&topo, &x, 0, &p, &c, 0.3, 0.05);
        assert_eq!(cs.len(), 1);
        assert!((cs[0].gap(&x).d - 0.01).abs() < 1e-12, "{}", cs[0].gap(&x).d);
        // 0.51 m above the start triangle: no contact there is considered.
        assert!(set::obstacle_contacts(&topo, &[Pt3::new(0.2, 0.6, 0.2)], 0, &p, &c, 0.3, 0.05).is_empty());
    }

    #[test]
    fn the_carry_moves_near_vertices_with_the_surface_and_leaves_far_ones() {
        let b = box_surface(Pt3::new(-0.5, -1.0, -0.5), Pt3::new(0.5, 0.0, 0.5), [2, 2, 2], Diagonals::Alternating)
            .unwrap();
        let p1: Vec<Pt3> = b.positions.iter().map(|p| p + Vec3::new(0.0, 0.05, 0.0)).collect();
        let x = [Pt3::new(0.1, 0.01, 0.1), Pt3::new(0.1, 0.08, 0.1), Pt3::new(0.1, 1.0, 0.1)];
        let mut out = vec![Vec3::zeros(); 3];
        add_carry(&b.faces, &b.positions, &p1, &x, 0.01, &mut out).unwrap();
        // Within d̂ + D = 0.06: carried fully; at 0.08 (between 0.06 and 0.11): 60 %; far: still.
        assert!((out[0] - Vec3::new(0.0, 0.05, 0.0)).norm() < 1e-12, "{:?}", out[0]);
        assert!((out[1] - Vec3::new(0.0, 0.03, 0.0)).norm() < 1e-12, "{:?}", out[1]);
        assert_eq!(out[2], Vec3::zeros());
    }

    #[test]
    fn frames_interpolate_linearly_and_hold_at_the_ends() {
        let b = box_surface(Pt3::new(-0.5, -1.0, -0.5), Pt3::new(0.5, 0.0, 0.5), [1, 1, 1], Diagonals::Alternating)
            .unwrap();
        let up: Vec<Pt3> = b.positions.iter().map(|p| p + Vec3::new(0.0, 1.0, 0.0)).collect();
        let d = DeformingMesh::new(b.faces.clone(), vec![b.positions.clone(), up], 1.0, 10.0, 0.2).unwrap();
        assert!((d.positions(1.05)[0].y - (b.positions[0].y + 0.5)).abs() < 1e-12);
        assert_eq!(d.positions(0.0)[0], b.positions[0]);
        assert_eq!(d.positions(9.0)[0].y, b.positions[0].y + 1.0);
        assert_eq!(d.max_penetration(0.0, &[Pt3::new(0.0, -0.25, 0.0)]).unwrap(), 0.25);
        assert!(d.max_penetration(0.0, &[Pt3::new(f64::NAN, 0.0, 0.0)]).unwrap().is_nan());
    }
}

//! Squared distances between contact primitives with their exact gradients and Hessians, and the
//! classification of a point–triangle or edge–edge pair by its closest features (Li et al. 2020,
//! "Incremental Potential Contact", §4 and supplement: the distance of a pair is the distance of
//! its closest features, so a point–triangle pair is a point–point, point–edge or point–plane
//! distance depending on where the closest point falls).
//!
//! Every function returns D = d² (m²), ∇D and ∇²D over the stacked coordinates of the points it
//! takes, in argument order. Point–plane and line–line share one form, D = s²/w with
//! s = u·(a×b) (a triple product) and w = |a×b|²; point–line is D = |u×a|²/|a|². The
//! derivatives are written in the difference vectors (u, a, b) and mapped to the points by the
//! constant linear map between them. Finite-difference tests below check each.

use geom_core::math::{Mat3, Pt3, Vec3};
use nalgebra::{SMatrix, SVector};

/// A squared distance with gradient and Hessian over `N` coordinates.
#[derive(Clone, Debug)]
pub struct Sq<const N: usize> {
    /// D = d² (m²).
    pub d2: f64,
    /// ∇D.
    pub grad: SVector<f64, N>,
    /// ∇²D (symmetric).
    pub hess: SMatrix<f64, N, N>,
}

fn skew(v: &Vec3) -> Mat3 {
    v.cross_matrix()
}

fn put3<const N: usize>(g: &mut SVector<f64, N>, k: usize, v: &Vec3) {
    g.fixed_rows_mut::<3>(3 * k).copy_from(v);
}

fn put33<const N: usize>(h: &mut SMatrix<f64, N, N>, r: usize, c: usize, m: &Mat3) {
    h.fixed_view_mut::<3, 3>(3 * r, 3 * c).copy_from(m);
    if r != c {
        h.fixed_view_mut::<3, 3>(3 * c, 3 * r).copy_from(&m.transpose());
    }
}

/// D = s²/w from (s, ∇s, ∇²s) and (w, ∇w, ∇²w) (quotient and product rules).
fn quotient_sq<const N: usize>(
    s: f64,
    gs: &SVector<f64, N>,
    hs: &SMatrix<f64, N, N>,
    w: f64,
    gw: &SVector<f64, N>,
    hw: &SMatrix<f64, N, N>,
) -> Sq<N> {
    let d2 = s * s / w;
    let grad = gs * (2.0 * s / w) - gw * (s * s / (w * w));
    let cross = gs * gw.transpose();
    let hess = gs * gs.transpose() * (2.0 / w) + hs * (2.0 * s / w)
        - (cross + cross.transpose()) * (2.0 * s / (w * w))
        - hw * (s * s / (w * w))
        + gw * gw.transpose() * (2.0 * s * s / (w * w * w));
    Sq { d2, grad, hess }
}

/// D = (u·(a×b))²/|a×b|² in the 9 coordinates (u, a, b).
fn triple_sq(u: &Vec3, a: &Vec3, b: &Vec3) -> Sq<9> {
    let n = a.cross(b);
    let s = u.dot(&n);
    let w = n.norm_squared();
    let mut gs = SVector::<f64, 9>::zeros();
    put3(&mut gs, 0, &n);
    put3(&mut gs, 1, &b.cross(u));
    put3(&mut gs, 2, &u.cross(a));
    let mut hs = SMatrix::<f64, 9, 9>::zeros();
    put33(&mut hs, 0, 1, &(-skew(b)));
    put33(&mut hs, 0, 2, &skew(a));
    put33(&mut hs, 1, 2, &(-skew(u)));
    let mut gw = SVector::<f64, 9>::zeros();
    put3(&mut gw, 1, &(2.0 * b.cross(&n)));
    put3(&mut gw, 2, &(2.0 * n.cross(a)));
    let (sa, sb) = (skew(a), skew(b));
    let mut hw = SMatrix::<f64, 9, 9>::zeros();
    put33(&mut hw, 1, 1, &(-2.0 * sb * sb));
    put33(&mut hw, 2, 2, &(-2.0 * sa * sa));
    put33(&mut hw, 1, 2, &(2.0 * sb * sa - 2.0 * skew(&n)));
    quotient_sq(s, &gs, &hs, w, &gw, &hw)
}

/// Maps derivatives in difference coordinates (rows of L: each a combination of points) to the
/// points: ∇ₓ = Lᵀ∇, ∇²ₓ = Lᵀ∇²L.
fn lift<const M: usize, const N: usize>(q: &Sq<M>, l: &SMatrix<f64, M, N>) -> Sq<N> {
    Sq { d2: q.d2, grad: l.transpose() * q.grad, hess: l.transpose() * q.hess * l }
}

/// The 3-blocked linear map L (rows: difference vectors, columns: points) from the coefficient
/// table `c[row][point]`.
fn blocks<const M: usize, const N: usize>(c: &[&[f64]]) -> SMatrix<f64, M, N> {
    let mut l = SMatrix::<f64, M, N>::zeros();
    for (r, row) in c.iter().enumerate() {
        for (p, &x) in row.iter().enumerate() {
            if x != 0.0 {
                l.fixed_view_mut::<3, 3>(3 * r, 3 * p).copy_from(&(Mat3::identity() * x));
            }
        }
    }
    l
}

/// Point–point: D = |p − q|², over (p, q).
pub fn point_point(p: &Pt3, q: &Pt3) -> Sq<6> {
    let u = p - q;
    let mut grad = SVector::<f64, 6>::zeros();
    put3(&mut grad, 0, &(2.0 * u));
    put3(&mut grad, 1, &(-2.0 * u));
    let mut hess = SMatrix::<f64, 6, 6>::zeros();
    let i2 = Mat3::identity() * 2.0;
    put33(&mut hess, 0, 0, &i2);
    put33(&mut hess, 1, 1, &i2);
    put33(&mut hess, 0, 1, &(-i2));
    Sq { d2: u.norm_squared(), grad, hess }
}

/// D = f/w from (f, ∇f, ∇²f) and (w, ∇w, ∇²w).
fn quotient<const N: usize>(
    f: f64,
    gf: &SVector<f64, N>,
    hf: &SMatrix<f64, N, N>,
    w: f64,
    gw: &SVector<f64, N>,
    hw: &SMatrix<f64, N, N>,
) -> Sq<N> {
    let cross = gf * gw.transpose();
    Sq {
        d2: f / w,
        grad: gf / w - gw * (f / (w * w)),
        hess: hf / w - (cross + cross.transpose()) / (w * w) - hw * (f / (w * w))
            + gw * gw.transpose() * (2.0 * f / (w * w * w)),
    }
}

/// Point–line (the infinite line through e0, e1): D = |u × a|²/|a|², u = p − e0, a = e1 − e0,
/// over (p, e0, e1) — the cross-product form, exact to rounding even for a point close to the
/// line far from e0 (the projection form |u|² − (u·a)²/|a|² cancels there). Requires e0 ≠ e1.
pub fn point_line(p: &Pt3, e0: &Pt3, e1: &Pt3) -> Sq<9> {
    let u = p - e0;
    let a = e1 - e0;
    let c = u.cross(&a);
    let mut gf = SVector::<f64, 6>::zeros();
    put3(&mut gf, 0, &(2.0 * a.cross(&c)));
    put3(&mut gf, 1, &(2.0 * c.cross(&u)));
    let (sa, su) = (skew(&a), skew(&u));
    let mut hf = SMatrix::<f64, 6, 6>::zeros();
    put33(&mut hf, 0, 0, &(-2.0 * sa * sa));
    put33(&mut hf, 1, 1, &(-2.0 * su * su));
    put33(&mut hf, 0, 1, &(2.0 * sa * su - 2.0 * skew(&c)));
    let mut gw = SVector::<f64, 6>::zeros();
    put3(&mut gw, 1, &(2.0 * a));
    let mut hw = SMatrix::<f64, 6, 6>::zeros();
    put33(&mut hw, 1, 1, &(Mat3::identity() * 2.0));
    let q = quotient(c.norm_squared(), &gf, &hf, a.norm_squared(), &gw, &hw);
    lift(&q, &blocks::<6, 9>(&[&[1.0, -1.0, 0.0], &[0.0, -1.0, 1.0]]))
}

/// Point–plane (the plane through t0, t1, t2): over (p, t0, t1, t2). Requires a non-degenerate
/// triangle.
pub fn point_plane(p: &Pt3, t0: &Pt3, t1: &Pt3, t2: &Pt3) -> Sq<12> {
    let q = triple_sq(&(p - t0), &(t1 - t0), &(t2 - t0));
    lift(&q, &blocks::<9, 12>(&[&[1.0, -1.0, 0.0, 0.0], &[0.0, -1.0, 1.0, 0.0], &[0.0, -1.0, 0.0, 1.0]]))
}

/// Line–line (the infinite lines through a0–a1 and b0–b1): over (a0, a1, b0, b1). Requires
/// non-parallel lines.
pub fn line_line(a0: &Pt3, a1: &Pt3, b0: &Pt3, b1: &Pt3) -> Sq<12> {
    let q = triple_sq(&(a0 - b0), &(a1 - a0), &(b1 - b0));
    lift(&q, &blocks::<9, 12>(&[&[1.0, 0.0, -1.0, 0.0], &[-1.0, 1.0, 0.0, 0.0], &[0.0, 0.0, -1.0, 1.0]]))
}

/// Squared distance and gradient only (the Gauss–Newton contact Hessian needs no ∇²D): the
/// same forms as the functions above, without the Hessian's cost.
pub mod grad {
    use super::*;

    /// Point–point: (D, ∇D) over (p, q).
    pub fn point_point(p: &Pt3, q: &Pt3) -> (f64, [Vec3; 4]) {
        let u = p - q;
        (u.norm_squared(), [2.0 * u, -2.0 * u, Vec3::zeros(), Vec3::zeros()])
    }

    /// Point–line (cross-product form): (D, ∇D) over (p, e0, e1).
    pub fn point_line(p: &Pt3, e0: &Pt3, e1: &Pt3) -> (f64, [Vec3; 4]) {
        let (u, a) = (p - e0, e1 - e0);
        let c = u.cross(&a);
        let (f, w) = (c.norm_squared(), a.norm_squared());
        let gu = 2.0 * a.cross(&c) / w;
        let ga = 2.0 * c.cross(&u) / w - (2.0 * f / (w * w)) * a;
        (f / w, [gu, -gu - ga, ga, Vec3::zeros()])
    }

    /// (D, ∇_u, ∇_a, ∇_b) of D = (u·(a×b))²/|a×b|².
    fn triple(u: &Vec3, a: &Vec3, b: &Vec3) -> (f64, Vec3, Vec3, Vec3) {
        let n = a.cross(b);
        let (s, w) = (u.dot(&n), n.norm_squared());
        let (k1, k2) = (2.0 * s / w, s * s / (w * w));
        (s * s / w, k1 * n, k1 * b.cross(u) - k2 * 2.0 * b.cross(&n), k1 * u.cross(a) - k2 * 2.0 * n.cross(a))
    }

    /// Point–plane: (D, ∇D) over (p, t0, t1, t2).
    pub fn point_plane(p: &Pt3, t0: &Pt3, t1: &Pt3, t2: &Pt3) -> (f64, [Vec3; 4]) {
        let (d, gu, ga, gb) = triple(&(p - t0), &(t1 - t0), &(t2 - t0));
        (d, [gu, -gu - ga - gb, ga, gb])
    }

    /// Line–line: (D, ∇D) over (a0, a1, b0, b1).
    pub fn line_line(a0: &Pt3, a1: &Pt3, b0: &Pt3, b1: &Pt3) -> (f64, [Vec3; 4]) {
        let (d, gu, ga, gb) = triple(&(a0 - b0), &(a1 - a0), &(b1 - b0));
        (d, [gu - ga, ga, -gu - gb, gb])
    }
}

/// Which features of a point–triangle pair are closest.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum PtKind {
    /// The point and triangle vertex k.
    Vertex(u8),
    /// The point and triangle edge (k, k+1 mod 3).
    Edge(u8),
    /// The point and the triangle's interior (point–plane).
    Face,
}

/// Classifies a point–triangle pair by its closest features (barycentric regions of the
/// closest point on the triangle).
pub fn point_triangle_kind(p: &Pt3, t: &[Pt3; 3]) -> PtKind {
    let (_, w) = geom_core::query::closest_point_triangle(p, t);
    let zero: Vec<usize> = (0..3).filter(|&k| w[k] <= 0.0).collect();
    match zero.len() {
        0 => PtKind::Face,
        1 => {
            // Opposite vertex k has weight 0: the point lies on edge (k+1, k+2).
            PtKind::Edge(((zero[0] + 1) % 3) as u8)
        }
        _ => PtKind::Vertex((0..3).find(|&k| w[k] > 0.0).unwrap_or(0) as u8),
    }
}

/// Which features of an edge–edge pair are closest.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum EeKind {
    /// Endpoint i of edge a and endpoint j of edge b.
    Points(u8, u8),
    /// Endpoint i of edge a and the interior of edge b.
    PointA(u8),
    /// Endpoint j of edge b and the interior of edge a.
    PointB(u8),
    /// The interiors (line–line).
    Lines,
}

/// Classifies an edge–edge pair by its closest features; nearly parallel edges (|a×b|² below
/// 1e-20·|a|²|b|², where the line–line distance loses precision) are classified by their
/// closest endpoint pair instead.
pub fn edge_edge_kind(a0: &Pt3, a1: &Pt3, b0: &Pt3, b1: &Pt3) -> EeKind {
    let (s, t, _, _) = geom_core::query::closest_points_segments(a0, a1, b0, b1);
    let (a, b) = (a1 - a0, b1 - b0);
    let parallel = a.cross(&b).norm_squared() <= 1e-20 * a.norm_squared() * b.norm_squared();
    let end = |x: f64| x <= 0.0 || x >= 1.0;
    if parallel || (end(s) && end(t)) {
        if parallel {
            // Closest endpoint against the other segment.
            let cands = [
                (geom_core::query::closest_point_segment(a0, b0, b1).1 - a0).norm_squared(),
                (geom_core::query::closest_point_segment(a1, b0, b1).1 - a1).norm_squared(),
                (geom_core::query::closest_point_segment(b0, a0, a1).1 - b0).norm_squared(),
                (geom_core::query::closest_point_segment(b1, a0, a1).1 - b1).norm_squared(),
            ];
            let k = (0..4).min_by(|&i, &j| cands[i].total_cmp(&cands[j])).unwrap_or(0);
            let (pt, seg) = match k {
                0 => (a0, (b0, b1)),
                1 => (a1, (b0, b1)),
                2 => (b0, (a0, a1)),
                _ => (b1, (a0, a1)),
            };
            let (w, _) = geom_core::query::closest_point_segment(pt, seg.0, seg.1);
            return match (k, end(w)) {
                (0 | 1, false) => EeKind::PointA(k as u8),
                (2 | 3, false) => EeKind::PointB((k - 2) as u8),
                (0 | 1, true) => EeKind::Points(k as u8, (w >= 1.0) as u8),
                _ => EeKind::Points((w >= 1.0) as u8, (k - 2) as u8),
            };
        }
        return EeKind::Points((s >= 1.0) as u8, (t >= 1.0) as u8);
    }
    if end(s) {
        EeKind::PointA((s >= 1.0) as u8)
    } else if end(t) {
        EeKind::PointB((t >= 1.0) as u8)
    } else {
        EeKind::Lines
    }
}

/// Embeds a smaller derivative set into 12 coordinates: `slots[k]` is the 12-stencil point that
/// point k of `q` is.
pub fn embed<const M: usize>(q: &Sq<M>, slots: &[usize]) -> Sq<12> {
    let mut grad = SVector::<f64, 12>::zeros();
    let mut hess = SMatrix::<f64, 12, 12>::zeros();
    for (a, &sa) in slots.iter().enumerate() {
        grad.fixed_rows_mut::<3>(3 * sa).copy_from(&q.grad.fixed_rows::<3>(3 * a));
        for (b, &sb) in slots.iter().enumerate() {
            hess.fixed_view_mut::<3, 3>(3 * sa, 3 * sb).copy_from(&q.hess.fixed_view::<3, 3>(3 * a, 3 * b));
        }
    }
    Sq { d2: q.d2, grad, hess }
}

/// Point–triangle squared distance over (p, t0, t1, t2) for the given closest-feature kind.
pub fn point_triangle(p: &Pt3, t: &[Pt3; 3], kind: PtKind) -> Sq<12> {
    match kind {
        PtKind::Face => point_plane(p, &t[0], &t[1], &t[2]),
        PtKind::Vertex(k) => embed(&point_point(p, &t[k as usize]), &[0, 1 + k as usize]),
        PtKind::Edge(k) => {
            let (i, j) = (k as usize, (k as usize + 1) % 3);
            embed(&point_line(p, &t[i], &t[j]), &[0, 1 + i, 1 + j])
        }
    }
}

/// Edge–edge squared distance over (a0, a1, b0, b1) for the given closest-feature kind.
pub fn edge_edge(a: [&Pt3; 2], b: [&Pt3; 2], kind: EeKind) -> Sq<12> {
    match kind {
        EeKind::Lines => line_line(a[0], a[1], b[0], b[1]),
        EeKind::Points(i, j) => embed(&point_point(a[i as usize], b[j as usize]), &[i as usize, 2 + j as usize]),
        EeKind::PointA(i) => embed(&point_line(a[i as usize], b[0], b[1]), &[i as usize, 2, 3]),
        EeKind::PointB(j) => embed(&point_line(b[j as usize], a[0], a[1]), &[2 + j as usize, 0, 1]),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use geom_core::rng::Rng;

    fn rand_pt(r: &mut Rng) -> Pt3 {
        Pt3::new(r.range(-1.0, 1.0), r.range(-1.0, 1.0), r.range(-1.0, 1.0))
    }

    /// Central differences of D and of ∇D against ∇D and ∇²D; tolerance relative to the
    /// magnitudes (step 1e-6: truncation O(1e-12), rounding O(1e-10) relative).
    fn fd_check<const N: usize>(f: impl Fn(&SVector<f64, N>) -> Sq<N>, x: SVector<f64, N>) {
        let e = 1e-6;
        let q = f(&x);
        let scale_g = q.grad.amax().max(1e-3);
        let scale_h = q.hess.amax().max(1e-3);
        for k in 0..N {
            let mut xp = x;
            let mut xm = x;
            xp[k] += e;
            xm[k] -= e;
            let (p, m) = (f(&xp), f(&xm));
            let g = (p.d2 - m.d2) / (2.0 * e);
            assert!((g - q.grad[k]).abs() <= 1e-6 * scale_g, "grad {k}: fd {g} vs {}", q.grad[k]);
            let hcol = (p.grad - m.grad) / (2.0 * e);
            for r in 0..N {
                assert!(
                    (hcol[r] - q.hess[(r, k)]).abs() <= 1e-5 * scale_h,
                    "hess ({r},{k}): fd {} vs {}",
                    hcol[r],
                    q.hess[(r, k)]
                );
            }
        }
        assert!((q.hess - q.hess.transpose()).amax() <= 1e-12 * scale_h, "Hessian symmetric");
    }

    fn pts<const N: usize>(x: &SVector<f64, N>) -> Vec<Pt3> {
        (0..N / 3).map(|k| Pt3::new(x[3 * k], x[3 * k + 1], x[3 * k + 2])).collect()
    }

    fn stack<const N: usize>(p: &[Pt3]) -> SVector<f64, N> {
        SVector::<f64, N>::from_iterator(p.iter().flat_map(|q| [q.x, q.y, q.z]))
    }

    #[test]
    fn derivatives_match_finite_differences() {
        let mut r = Rng::new(7);
        for _ in 0..20 {
            let p: Vec<Pt3> = (0..4).map(|_| rand_pt(&mut r)).collect();
            fd_check::<6>(
                |x| {
                    let q = pts(x);
                    point_point(&q[0], &q[1])
                },
                stack(&p[..2]),
            );
            fd_check::<9>(
                |x| {
                    let q = pts(x);
                    point_line(&q[0], &q[1], &q[2])
                },
                stack(&p[..3]),
            );
            fd_check::<12>(
                |x| {
                    let q = pts(x);
                    point_plane(&q[0], &q[1], &q[2], &q[3])
                },
                stack(&p),
            );
            fd_check::<12>(
                |x| {
                    let q = pts(x);
                    line_line(&q[0], &q[1], &q[2], &q[3])
                },
                stack(&p),
            );
        }
    }

    #[test]
    fn values_match_closest_point_queries() {
        let mut r = Rng::new(11);
        for _ in 0..2000 {
            let p = rand_pt(&mut r);
            let t = [rand_pt(&mut r), rand_pt(&mut r), rand_pt(&mut r)];
            let k = point_triangle_kind(&p, &t);
            let d2 = point_triangle(&p, &t, k).d2;
            let (c, _) = geom_core::query::closest_point_triangle(&p, &t);
            let truth = (p - c).norm_squared();
            assert!((d2 - truth).abs() <= 1e-9 * truth.max(1e-6), "{k:?}: {d2} vs {truth}");
            let e = [rand_pt(&mut r), rand_pt(&mut r), rand_pt(&mut r), rand_pt(&mut r)];
            let k = edge_edge_kind(&e[0], &e[1], &e[2], &e[3]);
            let d2 = edge_edge([&e[0], &e[1]], [&e[2], &e[3]], k).d2;
            let (_, _, pa, pb) = geom_core::query::closest_points_segments(&e[0], &e[1], &e[2], &e[3]);
            let truth = (pa - pb).norm_squared();
            assert!((d2 - truth).abs() <= 1e-9 * truth.max(1e-6), "{k:?}: {d2} vs {truth}");
        }
    }

    #[test]
    fn gradient_only_forms_equal_the_full_ones() {
        let mut r = Rng::new(5);
        for _ in 0..50 {
            let p: Vec<Pt3> = (0..4).map(|_| rand_pt(&mut r)).collect();
            let pairs: [(Sq<12>, (f64, [Vec3; 4])); 4] = [
                (embed(&point_point(&p[0], &p[1]), &[0, 1]), grad::point_point(&p[0], &p[1])),
                (embed(&point_line(&p[0], &p[1], &p[2]), &[0, 1, 2]), grad::point_line(&p[0], &p[1], &p[2])),
                (point_plane(&p[0], &p[1], &p[2], &p[3]), grad::point_plane(&p[0], &p[1], &p[2], &p[3])),
                (line_line(&p[0], &p[1], &p[2], &p[3]), grad::line_line(&p[0], &p[1], &p[2], &p[3])),
            ];
            for (full, (d, g)) in pairs {
                assert!((full.d2 - d).abs() <= 1e-12 * d.max(1e-6));
                for k in 0..4 {
                    let fk = Vec3::new(full.grad[3 * k], full.grad[3 * k + 1], full.grad[3 * k + 2]);
                    assert!((fk - g[k]).norm() <= 1e-9 * full.grad.amax().max(1e-6));
                }
            }
        }
    }

    #[test]
    fn parallel_edges_use_endpoint_distances() {
        let e = [Pt3::new(0.0, 0.0, 0.0), Pt3::new(1.0, 0.0, 0.0), Pt3::new(0.5, 0.1, 0.0), Pt3::new(2.0, 0.1, 0.0)];
        let k = edge_edge_kind(&e[0], &e[1], &e[2], &e[3]);
        let q = edge_edge([&e[0], &e[1]], [&e[2], &e[3]], k);
        assert!((q.d2 - 0.01).abs() < 1e-15, "{k:?} {}", q.d2);
        assert!(q.grad.iter().all(|x| x.is_finite()));
    }
}

//! Continuous refinement of the embedding (rigging spec §3.10, paper §3.3): minimise
//! g(q) = α_A g_A + Σ_bones (α_S g_S + α_L g_L + α_O g_O) over all joint positions by gradient
//! descent with a step-doubling line search; one outer iteration = two line searches along −∇g
//! followed by one per bone along −∇g restricted to the bone's two endpoints.
//!
//! Gradients are central differences (h = 1e-6) of the terms touching each joint only (g is a
//! sum of per-bone terms, so ∂g/∂q_j involves the bones incident to j and their mirror pairs).
//! Departure from the spec (which suggests forward-mode dual numbers): g is piecewise smooth
//! (min/max/clamps, leaf-wise trilinear field), the line search only needs a descent direction,
//! and monotonicity is guaranteed by exact comparisons of g whatever the direction.

use geom_core::math::{Pt3, Vec3};
use geom_core::spatial::KdTree;

use crate::df::DistanceField;
use crate::options::RigOptions;
use crate::template::SkeletonTemplate;

/// The refinement objective with its data.
pub struct Objective<'a> {
    df: &'a DistanceField,
    medial: KdTree,
    /// Bones (parent, child) of the template.
    bones: Vec<(usize, usize)>,
    /// Given (scaled) bone vectors.
    given: Vec<Vec3>,
    /// Mirror bone pairs (indices into `bones`).
    pairs: Vec<(usize, usize)>,
    alpha: [f64; 4],
    tau: f64,
    /// Hint balls (joint, centre, radius): a joint leaving its ball makes g infinite, so the
    /// line search never accepts such a step (hints hold after refinement too).
    constraints: Vec<(usize, Pt3, f64)>,
}

impl<'a> Objective<'a> {
    /// Builds the objective over the medial sample points `medial`.
    pub fn new(df: &'a DistanceField, medial: &[Pt3], sk: &SkeletonTemplate, o: &RigOptions) -> Self {
        let bones = sk.bones();
        let rest = sk.rest();
        let given = bones.iter().map(|&(p, c)| (rest[c] - rest[p]) * o.skeleton_scale).collect();
        let mut pairs = Vec::new();
        for (b, &(_, c)) in bones.iter().enumerate() {
            if let Some(s) = sk.joints[c].symmetric_to {
                if let Some(bs) = bones.iter().position(|&(_, c2)| c2 == s) {
                    pairs.push((bs.min(b), bs.max(b)));
                }
            }
        }
        pairs.sort_unstable();
        pairs.dedup();
        Objective {
            df,
            medial: KdTree::build(medial),
            bones,
            given,
            pairs,
            alpha: o.refine_alpha,
            tau: df.tau(),
            constraints: Vec::new(),
        }
    }

    /// Adds hint balls `(joint, centre, radius)` (normalized coordinates).
    pub fn with_constraints(mut self, c: Vec<(usize, Pt3, f64)>) -> Self {
        self.constraints = c;
        self
    }

    /// Per-bone term α_S g_S + α_L g_L + α_O g_O of bone `b` with embedded end points.
    fn bone(&self, b: usize, qp: &Pt3, qc: &Pt3) -> f64 {
        let gv = self.given[b];
        let e = qc - qp;
        // g_S: stay inside and near the medial surface.
        let mut gs = 0.0;
        if !self.medial.is_empty() {
            for k in 0..10 {
                let x = qc + (qp - qc) * (k as f64 / 10.0);
                let m = self.medial.nearest(&x).map_or(0.0, |(_, d)| d);
                let s = -self.df.eval(&x);
                let pen = m.min(0.001 + (0.05 - s).max(0.0)).powi(2);
                if pen > self.tau * self.tau {
                    gs += pen;
                }
            }
            gs /= 10.0;
        }
        // g_L: too short.
        let gn = gv.norm();
        let lp = (e.dot(&gv)).max(-10.0) / gn.max(1e-12);
        let gl = ((1e-4 + gn * gn) / (1e-4 + lp * lp)).max(0.5);
        // g_O: orientation.
        let go = match (e.try_normalize(1e-12), gv.try_normalize(1e-12)) {
            (Some(eu), Some(gu)) => {
                let th = eu.dot(&gu).clamp(-1.0, 1.0).acos();
                let v = (0.3 + th / 2.0).powi(3);
                if e.dot(&gv) < 0.0 {
                    10.0 * v
                } else {
                    v
                }
            }
            _ => 0.3f64.powi(3),
        };
        self.alpha[0] * gs + self.alpha[1] * gl + self.alpha[2] * go
    }

    fn asym(&self, q: &[Pt3], (a, b): (usize, usize)) -> f64 {
        let len2 = |k: usize| (q[self.bones[k].1] - q[self.bones[k].0]).norm_squared();
        let (l, l2) = (len2(a), len2(b));
        self.alpha[3] * 1.05f64.max(l / (1e-3 + l2)).max(l2 / (1e-3 + l))
    }

    /// g(q).
    pub fn eval(&self, q: &[Pt3]) -> f64 {
        if self.constraints.iter().any(|(j, c, r)| (q[*j] - c).norm() > *r) {
            return f64::INFINITY;
        }
        let mut s = 0.0;
        for (b, &(p, c)) in self.bones.iter().enumerate() {
            s += self.bone(b, &q[p], &q[c]);
        }
        for &pr in &self.pairs {
            s += self.asym(q, pr);
        }
        s
    }

    /// The part of g that depends on joint j.
    fn local(&self, q: &[Pt3], j: usize) -> f64 {
        let mut s = 0.0;
        for (b, &(p, c)) in self.bones.iter().enumerate() {
            if p == j || c == j {
                s += self.bone(b, &q[p], &q[c]);
            }
        }
        for &pr in &self.pairs {
            let touches = |k: usize| self.bones[k].0 == j || self.bones[k].1 == j;
            if touches(pr.0) || touches(pr.1) {
                s += self.asym(q, pr);
            }
        }
        s
    }

    /// ∇g by central differences of the joint-local terms (h = 1e-6).
    pub fn gradient(&self, q: &[Pt3]) -> Vec<Vec3> {
        self.gradient_at(q, &(0..q.len()).collect::<Vec<_>>())
    }

    /// ∇g restricted to the joints `js` (zero elsewhere).
    pub fn gradient_at(&self, q: &[Pt3], js: &[usize]) -> Vec<Vec3> {
        let h = 1e-6;
        let mut x = q.to_vec();
        (0..q.len())
            .map(|j| {
                if !js.contains(&j) {
                    return Vec3::zeros();
                }
                let mut gj = Vec3::zeros();
                for a in 0..3 {
                    let orig = x[j][a];
                    x[j][a] = orig + h;
                    let fp = self.local(&x, j);
                    x[j][a] = orig - h;
                    let fm = self.local(&x, j);
                    x[j][a] = orig;
                    gj[a] = (fp - fm) / (2.0 * h);
                }
                gj
            })
            .collect()
    }
}

/// Step-doubling line search from `q` along `d` (paper §3.3): start with
/// h₀ = 5·10⁻⁴ / sqrt(10⁻³ + Σ|d|²), keep stepping and doubling while g decreases, keep the last
/// improving point. Never increases g. Returns the new value.
pub fn line_search(obj: &Objective, q: &mut [Pt3], d: &[Vec3], g0: f64) -> f64 {
    let norm2: f64 = d.iter().map(|v| v.norm_squared()).sum();
    if norm2 == 0.0 || !norm2.is_finite() {
        return g0;
    }
    let mut h = 5e-4 / (1e-3 + norm2).sqrt();
    let mut best = g0;
    let mut cur = q.to_vec();
    for _ in 0..60 {
        let trial: Vec<Pt3> = cur.iter().zip(d).map(|(p, v)| p + v * h).collect();
        let gt = obj.eval(&trial);
        if gt < best {
            best = gt;
            cur = trial;
            h *= 2.0;
        } else {
            break;
        }
    }
    q.copy_from_slice(&cur);
    best
}

/// Refines `init` (normalized coordinates, full skeleton) for `o.refine_iters` outer
/// iterations; returns the refined joints and the objective history (one value per line
/// search, non-increasing).
pub fn refine(obj: &Objective, init: &[Pt3], iters: usize) -> (Vec<Pt3>, Vec<f64>) {
    let mut q = init.to_vec();
    let mut g = obj.eval(&q);
    let mut hist = vec![g];
    for _ in 0..iters {
        for _ in 0..2 {
            let d: Vec<Vec3> = obj.gradient(&q).into_iter().map(|v| -v).collect();
            g = line_search(obj, &mut q, &d, g);
            hist.push(g);
        }
        for &(p, c) in &obj.bones.clone() {
            let d: Vec<Vec3> = obj.gradient_at(&q, &[p, c]).into_iter().map(|v| -v).collect();
            g = line_search(obj, &mut q, &d, g);
            hist.push(g);
        }
    }
    (q, hist)
}

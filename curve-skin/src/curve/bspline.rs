//! The plain quadratic B-spline curve shape (spec §3.4.2, `QuadraticBSpline`; the paper's
//! B-spline with a Joint_CP and two Bone_CPs) in closed form.
//!
//! Control points `P₀ = J + L·u_a`, `P₁ = J`, `P₂ = J + L·u_c` with unit `u_a`, `u_c` and bend
//! angle β between `t₁ = −u_a` and `u_c`. The curve (a quadratic Bézier, i.e. the uniform
//! quadratic B-spline with clamped ends) is `B(t) = J + L·((1−t)²u_a + t²u_c)`, `t ∈ [0, 1]`,
//! so `B(0) = P₀`, `B(1) = P₂` (end interpolation) and `B′(t) = 2L((1−t)t₁ + t·u_c)`, tangent
//! to both bones at the ends (C¹ with the straight bone parts).
//!
//! Everything here is in units of `L` and in the bend plane (`e₁ = t₁`, `e₂ = b × t₁`, where
//! `u_c = cos β·e₁ + sin β·e₂`). With `c = cos(β/2)`, `s = sin(β/2)`:
//! * speed `|B′|/(2L) = sqrt(c² + 4s²(t−½)²)`, minimal (`c`) at the joint;
//! * arc length (closed form) `ℓ(t) = (F(2s(t−½)) − F(−s))/s`, `F(y) = ½(y·sqrt(c²+y²) + c²·asinh(y/c))`,
//!   total `ℓ(1) = 1 + (c²/s)·asinh(s/c)` (2 when straight, 1 when folded back);
//! * tangent angle `ψ(t) = atan2(t·sin β, 1 − t + t·cos β)` (0 at `P₀`, β/2 at the joint, β at `P₂`);
//! * curvature `κ(t) = sin β / (4L·speed³)`, largest at the joint: `κ_max = s/(L c²)`.
//!
//! Fold-free rule (reconstructed like the circular arc's, spec §3.4.3): with the centre on the
//! skeleton and the skeleton zone `[s_J − L, s_J + L]` mapped onto the curve by normalised arc
//! length, the swing rate is `ψ′(s) = κ(u)·ℓ(1)/2` and the Jacobian `cos α − ψ′·ℓ_N` is smallest at
//! the joint (α = β/2, κ largest), so the skin is fold-free iff `L ≥ d·g(β)` with
//! `g(β) = (tan(β/2)/cos(β/2) + asinh(tan(β/2)))/(2cos(β/2))` — about 1.46× the arc's
//! `β/(2cos(β/2))` at 90°: the curvature concentrates at the middle (spec). With the centre on the
//! curve the rule is the paper's `1/κ_max ≥ d`, i.e. `L ≥ d·tan(β/2)/cos(β/2)`.

use geom_core::math::{Pt3, Vec3};

/// Below this `sin(β/2)` the arc length uses its series (the closed form divides by `s`).
const SMALL_S: f64 = 1e-6;

/// The bend-angle-dependent shape of the quadratic B-spline, in units of `L`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct QuadBSpline {
    /// Bend angle β ∈ [0, π] (rad).
    pub beta: f64,
    c: f64,
    s: f64,
    sinb: f64,
    cosb: f64,
    f0: f64,
    total: f64,
}

impl QuadBSpline {
    /// The shape for bend angle β (clamped to `[0, π]`).
    pub fn new(beta: f64) -> QuadBSpline {
        let beta = beta.clamp(0.0, std::f64::consts::PI);
        let (s, c) = (0.5 * beta).sin_cos();
        let c = c.max(0.0);
        let mut q = QuadBSpline { beta, c, s, sinb: beta.sin(), cosb: beta.cos(), f0: 0.0, total: 0.0 };
        q.f0 = q.prim(-s);
        q.total = q.len_unit(1.0);
        q
    }

    /// `F(y) = ∫₀^y sqrt(c² + x²) dx`.
    fn prim(&self, y: f64) -> f64 {
        let c2 = self.c * self.c;
        let r = (c2 + y * y).sqrt();
        let asinh_term = if self.c > 1e-150 { c2 * (y / self.c).asinh() } else { 0.0 };
        0.5 * (y * r + asinh_term)
    }

    /// Speed `|B′(t)|/L` (the arc length's derivative in units of `L`).
    pub fn speed(&self, t: f64) -> f64 {
        let x = t - 0.5;
        2.0 * (self.c * self.c + 4.0 * self.s * self.s * x * x).sqrt()
    }

    /// Arc length from `P₀` to `B(t)` in units of `L`, `t ∈ [0, 1]`.
    pub fn len_unit(&self, t: f64) -> f64 {
        let t = t.clamp(0.0, 1.0);
        if self.s < SMALL_S {
            // speed/2 = c + 2s²(t−½)²/c + O(s⁴): integrate the series (error O(s⁴) < 1e-24).
            let x = t - 0.5;
            2.0 * (self.c * t + 2.0 * self.s * self.s / (3.0 * self.c) * (x * x * x + 0.125))
        } else {
            (self.prim(2.0 * self.s * (t - 0.5)) - self.f0) / self.s
        }
    }

    /// Total curve length of the B-spline part in units of `L`: `1 + (c²/s)·asinh(s/c)`.
    pub fn total(&self) -> f64 {
        self.total
    }

    /// The parameter `t` whose arc length is `u` (units of `L`, clamped to `[0, total]`):
    /// safeguarded Newton (the speed vanishes at the joint only when fully folded), to 1e-15.
    pub fn t_at_len(&self, u: f64) -> f64 {
        let u = u.clamp(0.0, self.total);
        if self.total <= 0.0 {
            return 0.0;
        }
        let (mut lo, mut hi) = (0.0f64, 1.0f64);
        let mut t = u / self.total;
        for _ in 0..60 {
            let f = self.len_unit(t) - u;
            if f.abs() <= 1e-15 {
                break;
            }
            if f > 0.0 {
                hi = t;
            } else {
                lo = t;
            }
            let d = self.speed(t);
            let mut tn = t - f / d;
            if !(tn > lo && tn < hi && tn.is_finite()) {
                tn = 0.5 * (lo + hi);
            }
            if (tn - t).abs() <= 1e-16 {
                t = tn;
                break;
            }
            t = tn;
        }
        t
    }

    /// Tangent angle ψ(t) ∈ [0, β] measured from `t₁` towards `u_c`.
    pub fn psi(&self, t: f64) -> f64 {
        (t * self.sinb).atan2(1.0 - t + t * self.cosb)
    }

    /// Point `B(t) − J` in the bend plane, units of `L`: `(−(1−t)² + t² cos β, t² sin β)`.
    pub fn point_plane(&self, t: f64) -> (f64, f64) {
        let a = 1.0 - t;
        (-a * a + t * t * self.cosb, t * t * self.sinb)
    }

    /// Largest curvature times `L` (at the joint): `s/c²` (∞ when folded back).
    pub fn max_curvature_l(&self) -> f64 {
        if self.c > 1e-12 {
            self.s / (self.c * self.c)
        } else {
            f64::INFINITY
        }
    }

    /// The fold-free factor `g(β)` of the centre-on-skeleton rule `L ≥ d·g(β)` (module docs).
    pub fn fold_factor_skeleton(&self) -> f64 {
        if self.c <= 1e-12 {
            return f64::INFINITY;
        }
        let tan = self.s / self.c;
        (tan / self.c + tan.asinh()) / (2.0 * self.c)
    }

    /// The fold-free factor of the centre-on-curve rule `L ≥ d·tan(β/2)/cos(β/2)`.
    pub fn fold_factor_curve(&self) -> f64 {
        self.max_curvature_l()
    }

    /// Closest point of the B-spline (in world space: joint `j`, unit `t1 = −u_a`, in-plane unit
    /// normal `n = b × t1`, binormal `b`, leg length `l`) to `x`: `(distance, t)`. Dense sampling
    /// then Newton on `(B − x)·B′ = 0`, clamped to `[0, 1]`.
    pub fn closest(&self, j: &Pt3, t1: &Vec3, n: &Vec3, b: &Vec3, l: f64, x: &Pt3) -> (f64, f64) {
        let d = x - j;
        let (px, py, pz) = (d.dot(t1) / l, d.dot(n) / l, d.dot(b) / l);
        let dist2 = |t: f64| {
            let (bx, by) = self.point_plane(t);
            (bx - px).powi(2) + (by - py).powi(2)
        };
        const N: usize = 32;
        let mut best_t = 0.0;
        let mut best = f64::INFINITY;
        for i in 0..=N {
            let t = i as f64 / N as f64;
            let v = dist2(t);
            if v < best {
                best = v;
                best_t = t;
            }
        }
        let mut t = best_t;
        for _ in 0..20 {
            let (bx, by) = self.point_plane(t);
            // B′/L = (2(1−t) + 2t cos β, 2t sin β), B″/L = (2 cos β − 2, 2 sin β).
            let (dx, dy) = (2.0 * (1.0 - t) + 2.0 * t * self.cosb, 2.0 * t * self.sinb);
            let (ddx, ddy) = (2.0 * self.cosb - 2.0, 2.0 * self.sinb);
            let g = (bx - px) * dx + (by - py) * dy;
            let h = dx * dx + dy * dy + (bx - px) * ddx + (by - py) * ddy;
            if h <= 0.0 {
                break;
            }
            let tn = (t - g / h).clamp(0.0, 1.0);
            if (tn - t).abs() < 1e-15 {
                t = tn;
                break;
            }
            t = tn;
        }
        let tt = if dist2(t) <= best { t } else { best_t };
        (l * (dist2(tt) + pz * pz).sqrt(), tt)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Arc length by composite Simpson on the speed (reference for the closed form).
    fn simpson_len(q: &QuadBSpline, t: f64) -> f64 {
        let n = 2000;
        let h = t / n as f64;
        let mut acc = q.speed(0.0) + q.speed(t);
        for i in 1..n {
            acc += q.speed(i as f64 * h) * if i % 2 == 1 { 4.0 } else { 2.0 };
        }
        acc * h / 3.0
    }

    #[test]
    fn arc_length_matches_quadrature_and_inverts() {
        // Closed form vs Simpson (error ~h⁴·max|speed⁗| ≪ 1e-10 except near β = π, where the
        // speed has a kink at t = ½: checked only to 1e-6 there).
        for &deg in &[0.0, 1e-5, 0.01, 10.0, 45.0, 90.0, 135.0, 170.0, 179.9] {
            let q = QuadBSpline::new(f64::to_radians(deg));
            let tol = if deg > 170.0 { 1e-6 } else { 1e-10 };
            for &t in &[0.0, 0.1, 0.37, 0.5, 0.8, 1.0] {
                let (a, b) = (q.len_unit(t), simpson_len(&q, t));
                assert!((a - b).abs() < tol, "β = {deg}°, t = {t}: {a} vs {b}");
                let back = q.t_at_len(a);
                assert!((back - t).abs() < 1e-9, "β = {deg}°, t = {t}: inverse {back}");
            }
        }
        assert!((QuadBSpline::new(0.0).total() - 2.0).abs() < 1e-15);
        assert!((QuadBSpline::new(std::f64::consts::PI).total() - 1.0).abs() < 1e-12);
    }

    #[test]
    fn tangent_angle_is_the_derivative_direction() {
        let q = QuadBSpline::new(1.2);
        for i in 1..20 {
            let t = i as f64 / 20.0;
            let h = 1e-6;
            let (a, b) = (q.point_plane(t + h), q.point_plane(t - h));
            let fd = (a.1 - b.1).atan2(a.0 - b.0);
            assert!((fd - q.psi(t)).abs() < 1e-8, "t = {t}");
            // Speed = |B′| (central difference, error O(h²)).
            let sp = ((a.0 - b.0).powi(2) + (a.1 - b.1).powi(2)).sqrt() / (2.0 * h);
            assert!((sp - q.speed(t)).abs() < 1e-7);
        }
        assert!((q.psi(0.5) - 0.6).abs() < 1e-14, "ψ(½) = β/2");
    }

    #[test]
    fn closest_point_beats_dense_sampling() {
        let q = QuadBSpline::new(2.0);
        let (j, t1, n, b) = (Pt3::new(0.1, 0.2, 0.3), Vec3::x(), Vec3::y(), Vec3::z());
        let l = 0.4;
        let mut rng = geom_core::rng::Rng::new(3);
        for _ in 0..200 {
            let x = j + Vec3::new(rng.normal(), rng.normal(), rng.normal()) * 0.3;
            let (d, t) = q.closest(&j, &t1, &n, &b, l, &x);
            let p = |t: f64| {
                let (u, v) = q.point_plane(t);
                j + t1 * (u * l) + n * (v * l)
            };
            assert!(((p(t) - x).norm() - d).abs() < 1e-12);
            for i in 0..=5000 {
                let dd = (p(i as f64 / 5000.0) - x).norm();
                assert!(d <= dd + 1e-12, "sample {i} closer: {dd} < {d}");
            }
        }
    }
}

//! One curve in one pose (spec §3.4.2–3.4.4): bend angle β, binormal b, Bone_CP distance L,
//! twist θ, and the closed-form frame field
//! `F(σ) = Rot(b, ψ(s)) · F_a · Rot(x, θ·D(σ))`, centre `c(σ)` and volume scale.
//!
//! `F_a` is the first bone's travel frame (x along the direction of travel, towards the joint);
//! `Rot(b, ψ)·F_a·Rot(x, τ)` equals the spec's `Rot(t(σ), τ)·S(σ)·F_a` because `F_a`'s x axis is
//! the first bone's tangent. At σ = 0 the frame is `F_a`; at σ = 1 it is the second bone's travel
//! frame `F_c` exactly, because θ is the twist of `F_c` relative to `Rot(b, β)·F_a` about the
//! second bone (swing–twist decomposition), so neighbouring curves agree at bone midpoints.
//!
//! Two curve shapes through the Bone_CPs (spec §3.4.2): the circular arc (rational quadratic with
//! middle weight cos(β/2), default) and the plain quadratic B-spline ([`super::bspline`]). With
//! the centre on the skeleton, the skeleton zone `[s_J − L, s_J + L]` is mapped onto the curve's
//! middle part by normalised arc length (the straight parts coincide), and ψ is the curve's
//! tangent angle there: linear in `s` for the arc, `ψ(t(u))` for the B-spline. The swing about the
//! constant binormal is the rotation-minimising frame of the planar curve.

use geom_core::anim::skin::SkinSkeleton;
use geom_core::math::{Iso3, Pt3, UnitQuat, Vec3};
use nalgebra::{Quaternion, Unit};
use std::f64::consts::PI;

use super::bspline::QuadBSpline;
use super::types::{BoneCp, BoneEnd, CentreMode, CurveShape, JointCurve, TwistDistribution, VolumeComp};

/// Largest volume-compensation scale applied whatever `max_scale` says (α → 90° at a fully
/// folded joint would otherwise give an infinite offset).
pub const MAX_VOLUME_SCALE: f64 = 10.0;

/// Rest-pose data of a curve, fixed at bind time.
#[derive(Clone, Debug, PartialEq)]
pub struct CurveRig {
    /// Travel-frame offsets of the two bones in their owners' local frames.
    pub e_in: UnitQuat,
    /// See `e_in`.
    pub e_out: UnitQuat,
    /// Rest lengths of the two bones (m).
    pub len_in: f64,
    /// See `len_in`.
    pub len_out: f64,
    /// Skin distance `d` used by the floating rule (m).
    pub skin_dist: f64,
}

fn travel_offset(sk: &SkinSkeleton, j: usize, b: &BoneEnd, towards_joint: bool) -> (UnitQuat, f64) {
    let d = sk.rest_world[b.far].translation.vector - sk.rest_world[j].translation.vector;
    let len = d.norm();
    if len <= 1e-12 {
        return (UnitQuat::identity(), 0.0);
    }
    let dir = if towards_joint { -d / len } else { d / len };
    let local = sk.rest_world[b.owner].rotation.inverse() * dir;
    let e = match UnitQuat::rotation_between(&Vec3::x(), &local) {
        Some(q) => q,
        // Antiparallel: a fixed 180° turn about the local z axis (spec §3.4.4).
        None => UnitQuat::from_axis_angle(&Vec3::z_axis(), PI),
    };
    (e, len)
}

impl CurveRig {
    /// Rest data of curve `c` on skeleton `sk`, with skin distance `skin_dist`.
    pub fn new(sk: &SkinSkeleton, c: &JointCurve, skin_dist: f64) -> CurveRig {
        let (e_in, len_in) = travel_offset(sk, c.joint, &c.bone_in, true);
        let (e_out, len_out) = travel_offset(sk, c.joint, &c.bone_out, false);
        CurveRig { e_in, e_out, len_in, len_out, skin_dist }
    }
}

/// Swing–twist decomposition about a unit axis: `q = q_swing · q_twist` with `q_twist` a rotation
/// about `axis`; returns `(swing, twist angle in (−π, π])`.
pub fn swing_twist(q: &UnitQuat, axis: &Vec3) -> (UnitQuat, f64) {
    let v = q.imag();
    let p = v.dot(axis);
    let w = q.w;
    let mut theta = 2.0 * p.atan2(w);
    if theta > PI {
        theta -= 2.0 * PI;
    } else if theta <= -PI {
        theta += 2.0 * PI;
    }
    let twist = UnitQuat::from_axis_angle(&Unit::new_unchecked(*axis), theta);
    (q * twist.inverse(), theta)
}

/// Returns the representative `θ + 2πk` closest to `prev`.
pub fn unwrap_near(theta: f64, prev: f64) -> f64 {
    let k = ((prev - theta) / (2.0 * PI)).round();
    theta + 2.0 * PI * k
}

/// A curve in one pose (all `f64`).
#[derive(Clone, Debug, PartialEq)]
pub struct CurveFrame {
    /// Posed joint position.
    pub j: Pt3,
    /// Unit direction from the joint along the first bone.
    pub u_in: Vec3,
    /// Unit direction from the joint along the second bone.
    pub u_out: Vec3,
    /// First bone's travel frame `F_a`.
    pub f_in: UnitQuat,
    /// `Rot(b, β)·F_a`: the swung frame after the zone (cached for [`CurveFrame::eval`]).
    pub f_swung: UnitQuat,
    /// Unit binormal of the bend plane.
    pub b: Vec3,
    /// Bend angle β ∈ [0, π] (rad).
    pub beta: f64,
    /// Bone_CP distance L (m).
    pub l_cp: f64,
    /// Twist θ (rad).
    pub theta: f64,
    /// Covered length of the first bone, `span_in·len_in` (m).
    pub l_in: f64,
    /// Covered length of the second bone (m).
    pub l_out: f64,
    /// Centre mode.
    pub centre: CentreMode,
    /// The B-spline shape for β (`None` = circular arc).
    pub quad: Option<QuadBSpline>,
    /// Largest volume-compensation scale (`None` = off).
    pub max_scale: Option<f64>,
    /// The fold-free minimum L (floating rule without its safety factor) — or a fixed / keyed L —
    /// exceeds the cap, so the skin may fold (spec §7.4 c diagnostic).
    pub cap_hit: bool,
}

/// Inputs for [`CurveFrame::new`] that carry state between frames.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FrameHistory {
    /// Binormal of the previous frame in the first bone's travel frame (used when the bend plane
    /// is undefined: β ≈ 0 or π).
    pub b_local: Vec3,
    /// Previous twist θ (rad), for unwrapping.
    pub theta: f64,
}

impl Default for FrameHistory {
    fn default() -> Self {
        FrameHistory { b_local: Vec3::z(), theta: 0.0 }
    }
}

/// How θ is chosen from the swing–twist angle.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum TwistChoice {
    /// The principal value in (−π, π].
    Principal,
    /// The representative closest to the previous frame's θ.
    Unwrap,
    /// An authored twist angle (rad).
    Hint(f64),
}

impl CurveFrame {
    /// Builds the posed curve from joint world frames. Returns the frame and the history for the
    /// next frame.
    pub fn new(
        c: &JointCurve,
        rig: &CurveRig,
        posed: &[Iso3],
        hist: &FrameHistory,
        twist: TwistChoice,
        volume: VolumeComp,
    ) -> (CurveFrame, FrameHistory) {
        let j = Pt3::from(posed[c.joint].translation.vector);
        let f_in = posed[c.bone_in.owner].rotation * rig.e_in;
        let f_out = posed[c.bone_out.owner].rotation * rig.e_out;
        let t1 = f_in * Vec3::x();
        let t2 = f_out * Vec3::x();
        let cross = t1.cross(&t2);
        let sinb = cross.norm();
        let cosb = t1.dot(&t2);
        let beta = sinb.atan2(cosb);
        let b = if sinb > 1e-12 {
            cross / sinb
        } else {
            // Bend plane undefined: previous binormal, made orthogonal to t1.
            let bp = f_in * hist.b_local;
            let bo = bp - t1 * t1.dot(&bp);
            if bo.norm() > 1e-9 {
                bo.normalize()
            } else {
                (f_in * Vec3::z()).normalize()
            }
        };
        let (l_in, l_out) = (c.span_in * rig.len_in, c.span_out * rig.len_out);
        let quad = match c.shape {
            CurveShape::CircularArc => None,
            CurveShape::QuadraticBSpline => Some(QuadBSpline::new(beta)),
        };
        let span_cap = l_in.min(l_out);
        let (l_cp, cap_hit) = match &c.bone_cp {
            BoneCp::Fixed { dist } => (dist.min(span_cap).max(0.0), *dist > span_cap),
            BoneCp::Keyed(curve) => {
                let v = curve.eval(beta);
                (v.min(span_cap).max(0.0), v > span_cap)
            }
            BoneCp::Floating { skin_dist, safety, min, max_frac } => {
                let d = skin_dist.unwrap_or(rig.skin_dist);
                let half = 0.5 * beta;
                let ch = half.cos();
                let raw = match (c.centre, &quad) {
                    (_, None) if ch <= 1e-12 => f64::INFINITY,
                    (CentreMode::OnSkeleton, None) => safety * d * beta / (2.0 * ch),
                    (CentreMode::OnCurve, None) => safety * d * half.tan(),
                    (CentreMode::OnSkeleton, Some(q)) => safety * d * q.fold_factor_skeleton(),
                    (CentreMode::OnCurve, Some(q)) => safety * d * q.fold_factor_curve(),
                };
                let cap = (max_frac * rig.len_in.min(rig.len_out)).min(span_cap);
                let l = raw.max(*min).min(cap).max(0.0);
                // Folding is possible only when the fold-free minimum itself (without the safety
                // factor) does not fit under the cap.
                (l, raw / safety.max(1e-12) > cap)
            }
        };
        let swing_end = UnitQuat::from_axis_angle(&Unit::new_unchecked(b), beta);
        let rel = f_out * (swing_end * f_in).inverse();
        let (_, raw_theta) = swing_twist(&rel, &t2);
        let theta = match twist {
            TwistChoice::Principal => raw_theta,
            TwistChoice::Unwrap => unwrap_near(raw_theta, hist.theta),
            TwistChoice::Hint(h) => h,
        };
        let max_scale = match volume {
            VolumeComp::Off => None,
            VolumeComp::Isotropic { max_scale } => Some(max_scale),
        };
        let fr = CurveFrame {
            j,
            u_in: -t1,
            u_out: t2,
            f_in,
            f_swung: swing_end * f_in,
            b,
            beta,
            l_cp,
            theta,
            l_in,
            l_out,
            centre: c.centre,
            quad,
            max_scale,
            cap_hit,
        };
        (fr, FrameHistory { b_local: f_in.inverse() * b, theta })
    }

    /// Total skeleton length of the domain (m).
    pub fn length(&self) -> f64 {
        self.l_in + self.l_out
    }

    /// σ of the joint.
    pub fn sigma_joint(&self) -> f64 {
        let s = self.length();
        if s > 0.0 {
            self.l_in / s
        } else {
            0.0
        }
    }

    /// Kink parameters: σ_J and the arc-zone ends `(s_J ± L)/S` (spec §3.4.6).
    pub fn kinks(&self) -> [f64; 3] {
        let s = self.length().max(1e-300);
        [(self.l_in - self.l_cp) / s, self.l_in / s, (self.l_in + self.l_cp) / s]
    }

    /// Swing angle ψ at skeleton arc length `s` (skeleton association: the zone `s_J ± L` maps
    /// onto the curve's middle part by normalised arc length).
    fn psi_skeleton(&self, s: f64) -> f64 {
        let sj = self.l_in;
        if self.l_cp > 1e-12 {
            let phi = ((s - (sj - self.l_cp)) / (2.0 * self.l_cp)).clamp(0.0, 1.0);
            match &self.quad {
                None => self.beta * phi,
                Some(q) if phi > 0.0 && phi < 1.0 => q.psi(q.t_at_len(phi * q.total())),
                Some(_) => self.beta * phi,
            }
        } else if s >= sj {
            self.beta
        } else {
            0.0
        }
    }

    /// Arc radius, middle-part length and total curve length of the line–arc–line (or
    /// line–B-spline–line) curve; the radius is ∞ for the B-spline.
    fn arc_dims(&self) -> (f64, f64, f64) {
        let l = self.l_cp;
        let (r, a) = if let Some(q) = &self.quad {
            (f64::INFINITY, l * q.total())
        } else if self.beta < 1e-9 {
            (f64::INFINITY, 2.0 * l)
        } else {
            let r = l / (0.5 * self.beta).tan();
            (r, r * self.beta)
        };
        (r, a, self.l_in + self.l_out - 2.0 * l + a)
    }

    /// Point and swing angle on the curve geometry at curve arc length `u` from the far end of
    /// the first bone.
    pub fn curve_point(&self, u: f64) -> (Pt3, f64) {
        let (r, a, total) = self.arc_dims();
        let u = u.clamp(0.0, total);
        let t1 = -self.u_in;
        let first = self.l_in - self.l_cp;
        let p0 = self.j + self.u_in * self.l_cp;
        if u <= first {
            return (self.j + self.u_in * self.l_in + t1 * u, 0.0);
        }
        if u <= first + a {
            let v = u - first;
            if let Some(q) = &self.quad {
                if self.l_cp <= 0.0 {
                    return (p0, 0.0);
                }
                let t = q.t_at_len(v / self.l_cp);
                let (x, y) = q.point_plane(t);
                let n = self.b.cross(&t1);
                return (self.j + (t1 * x + n * y) * self.l_cp, q.psi(t));
            }
            if !r.is_finite() {
                return (p0 + t1 * v, 0.0);
            }
            let phi = if a > 0.0 { self.beta * v / a } else { self.beta };
            let o = p0 + self.b.cross(&t1) * r;
            let q = UnitQuat::from_axis_angle(&Unit::new_unchecked(self.b), phi);
            return (o + q * (p0 - o), phi);
        }
        let p2 = self.j + self.u_out * self.l_cp;
        (p2 + self.u_out * (u - first - a), self.beta)
    }

    /// Closest point of the curve geometry (lines and arc) to `x`: distance and curve arc length.
    pub fn closest_on_curve(&self, x: &Pt3) -> (f64, f64) {
        let (r, a, _) = self.arc_dims();
        let t1 = -self.u_in;
        let first = self.l_in - self.l_cp;
        let far_in = self.j + self.u_in * self.l_in;
        let p0 = self.j + self.u_in * self.l_cp;
        let p2 = self.j + self.u_out * self.l_cp;
        let seg = |a: &Pt3, dir: &Vec3, len: f64| -> (f64, f64) {
            let t = (x - a).dot(dir).clamp(0.0, len.max(0.0));
            ((a + dir * t - x).norm(), t)
        };
        let (d1, t) = seg(&far_in, &t1, first);
        let mut best = (d1, t);
        let (d3, t) = seg(&p2, &self.u_out, self.l_out - self.l_cp);
        if d3 < best.0 {
            best = (d3, first + a + t);
        }
        if let Some(q) = &self.quad {
            if self.l_cp > 0.0 {
                let n = self.b.cross(&t1);
                let (d2, t) = q.closest(&self.j, &t1, &n, &self.b, self.l_cp, x);
                if d2 < best.0 {
                    best = (d2, first + self.l_cp * q.len_unit(t));
                }
            }
        } else if !r.is_finite() {
            let (d2, t) = seg(&p0, &t1, a);
            if d2 < best.0 {
                best = (d2, first + t);
            }
        } else if a > 0.0 {
            let o = p0 + self.b.cross(&t1) * r;
            let q = x - o;
            let qp = q - self.b * q.dot(&self.b);
            let e0 = (p0 - o) / r;
            let (d2, phi) = if qp.norm() > 1e-15 {
                let dir = qp.normalize();
                let phi = e0.cross(&dir).dot(&self.b).atan2(e0.dot(&dir));
                if (0.0..=self.beta).contains(&phi) {
                    ((o + dir * r - x).norm(), phi)
                } else {
                    (f64::INFINITY, 0.0)
                }
            } else {
                ((r * r + q.dot(&self.b).powi(2)).sqrt(), 0.0)
            };
            if d2 < best.0 {
                best = (d2, first + a * phi / self.beta);
            }
        }
        best
    }

    /// Total curve length (m).
    pub fn curve_length(&self) -> f64 {
        self.arc_dims().2
    }

    /// Centre, frame rotation and volume scale at σ ∈ [0, 1] (closed form, spec §3.4.4).
    pub fn eval(&self, sigma: f64, twist: &TwistDistribution) -> (Pt3, UnitQuat, f64) {
        let sigma = sigma.clamp(0.0, 1.0);
        let (centre, psi, alpha) = match self.centre {
            CentreMode::OnSkeleton => {
                let s = sigma * self.length();
                let psi = self.psi_skeleton(s);
                if s <= self.l_in {
                    (self.j + self.u_in * (self.l_in - s), psi, psi)
                } else {
                    (self.j + self.u_out * (s - self.l_in), psi, self.beta - psi)
                }
            }
            CentreMode::OnCurve => {
                let (p, psi) = self.curve_point(sigma * self.curve_length());
                (p, psi, 0.0)
            }
        };
        let (st, ct) = (0.5 * self.theta * twist.eval(sigma)).sin_cos();
        let tw = UnitQuat::new_unchecked(Quaternion::new(ct, st, 0.0, 0.0));
        // Outside the zone the swing is 0 or β: reuse F_a / Rot(b, β)·F_a (one sincos saved).
        let swung = if psi <= 0.0 {
            self.f_in
        } else if psi >= self.beta {
            self.f_swung
        } else {
            UnitQuat::from_axis_angle(&Unit::new_unchecked(self.b), psi) * self.f_in
        };
        let rot = swung * tw;
        let scale = match self.max_scale {
            None => 1.0,
            Some(m) => {
                // Hard limit keeps a folded joint (α → 90°) finite when max_scale is ∞.
                let m = m.min(MAX_VOLUME_SCALE);
                let ca = alpha.cos();
                if ca > 1.0 / (MAX_VOLUME_SCALE * MAX_VOLUME_SCALE) {
                    (1.0 / ca.sqrt()).min(m)
                } else {
                    m
                }
            }
        };
        (centre, rot, scale)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use geom_core::rng::Rng;

    #[test]
    fn swing_twist_recomposes() {
        // Spec 7.5 e: 10⁴ random rotations, recomposition equals the input (1e-12).
        let mut rng = Rng::new(7);
        for _ in 0..10_000 {
            let q = UnitQuat::from_quaternion(nalgebra::Quaternion::new(
                rng.normal(),
                rng.normal(),
                rng.normal(),
                rng.normal(),
            ));
            let axis = Vec3::new(rng.normal(), rng.normal(), rng.normal()).normalize();
            let (swing, th) = swing_twist(&q, &axis);
            let back = swing * UnitQuat::from_axis_angle(&Unit::new_unchecked(axis), th);
            assert!((back.coords - q.coords).norm().min((back.coords + q.coords).norm()) < 1e-12);
            // The swing has no component about the axis.
            assert!(swing.imag().dot(&axis).abs() < 1e-12);
        }
    }

    #[test]
    fn unwrap_follows_a_continuous_twist() {
        // A 0 → 540° hint-free sweep: the principal value jumps, the unwrapped one does not.
        let mut prev = 0.0;
        for i in 0..=540 {
            let t = (i as f64).to_radians();
            let principal = swing_twist(&UnitQuat::from_axis_angle(&Vec3::x_axis(), t), &Vec3::x()).1;
            let u = unwrap_near(principal, prev);
            assert!((u - t).abs() < 1e-9, "{i}: {u} vs {t}");
            prev = u;
        }
    }
}

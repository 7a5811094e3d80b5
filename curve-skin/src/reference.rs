//! Analytic solutions the skinning figures are compared with.
//!
//! ```
//! use curve_skin::reference::{lbs_joint_radius_ratio, lbs_twist_volume_ratio};
//! // Spec §7.2 c: smoothstep ramp, h = R = 0.15, ℓ = 2, θ = 180° ⇒ V/V₀ ≈ 0.9229.
//! let v = lbs_twist_volume_ratio(0.15, 1.0, std::f64::consts::PI);
//! assert!((v - 0.9229).abs() < 1e-4);
//! assert!((lbs_joint_radius_ratio(std::f64::consts::FRAC_PI_2) - 0.7071).abs() < 1e-4);
//! ```

/// Closed form of the LBS candy wrapper (spec §7.2 c, after the twist analysis of Kavan et al.
/// 2008): a cylinder of total length `2·bone_len` (m) whose forearm is twisted by `theta` (rad),
/// with smoothstep weights ramping over `[−half_width, half_width]` (m) about the joint, keeps
/// `V/V₀ = 1 − (2h/ℓ)(1 − cos θ)·2·I_w`, `I_w = 9/70`. Dimensionless.
pub fn lbs_twist_volume_ratio(half_width: f64, bone_len: f64, theta: f64) -> f64 {
    // The operation order of the scene runner this replaced (bitwise identical figures).
    1.0 - (2.0 * half_width / (2.0 * bone_len)) * (1.0 - theta.cos()) * 2.0 * 9.0 / 70.0
}

/// Radius ratio of the LBS joint ring (weight ½) under a bend `beta` (rad): `cos(β/2)` (spec
/// §3.2, §7.2 a — the collapsing elbow).
pub fn lbs_joint_radius_ratio(beta: f64) -> f64 {
    (0.5 * beta).cos()
}

/// Radius ratio of an LBS ring of weight `w` under a twist `theta` (rad):
/// `ρ(w) = √(1 − 2w(1 − w)(1 − cos θ))` (spec §3.2); 0 at w = ½, θ = π (the candy wrapper).
pub fn lbs_twist_ring_ratio(w: f64, theta: f64) -> f64 {
    (1.0 - 2.0 * w * (1.0 - w) * (1.0 - theta.cos())).max(0.0).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn closed_forms_match_the_spec_numbers() {
        let pi = std::f64::consts::PI;
        assert!((lbs_twist_volume_ratio(0.15, 1.0, pi) - 0.9229).abs() < 1e-4);
        assert!((lbs_twist_volume_ratio(0.30, 1.0, pi) - 0.8457).abs() < 1e-4);
        assert_eq!(lbs_twist_volume_ratio(0.3, 1.0, 0.0), 1.0);
        assert!(lbs_twist_ring_ratio(0.5, pi).abs() < 1e-12);
        assert!((lbs_twist_ring_ratio(0.5, 0.5 * pi) - (0.25 * pi).cos()).abs() < 1e-12);
    }
}

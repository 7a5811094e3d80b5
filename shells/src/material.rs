//! Material description (shells.md §2, §4): areal density, membrane law, bending stiffness,
//! damping and optional plasticity. All types are serde-(de)serialisable for scene files.

use crate::error::{Error, Result};
use crate::kernels::membrane::Membrane;
use geom_core::math::Vec3;
use serde::{Deserialize, Serialize};

/// A thin-shell material.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Material {
    /// Areal mass density ρ_s (kg/m²).
    pub density: f64,
    /// In-plane (membrane) law.
    pub membrane: MembraneLaw,
    /// Hinge bending stiffness k_B (J); see [`Material::k_b_from_modulus`].
    pub bending: f64,
    /// Damping model (§3.5).
    #[serde(default)]
    pub damping: Damping,
    /// Plasticity of the bending rest angles (seed §4.4); `None` = purely elastic.
    #[serde(default)]
    pub plasticity: Option<Plasticity>,
}

impl Material {
    /// k_B from a bending modulus B (½Bκ² per area, J): k_B = B/6, the cylinder calibration of
    /// §3.2 (interior energy density 3k_B/R² = ½B/R²). For a plate use B = D = Yt³/(12(1−ν²)).
    pub fn k_b_from_modulus(b: f64) -> f64 {
        b / 6.0
    }

    /// Checks every parameter (finite, in range); errors name the parameter and its value.
    pub fn validate(&self) -> Result<()> {
        let bad = |s: String| Err(Error::BadParameter(s));
        if !self.density.is_finite() || !self.bending.is_finite() {
            return Err(Error::NonFinite("material parameters"));
        }
        if self.density <= 0.0 {
            return bad(format!("density must be > 0 kg/m², got {}", self.density));
        }
        if self.bending < 0.0 {
            return bad(format!("bending stiffness must be ≥ 0 J, got {}", self.bending));
        }
        self.membrane.validate()?;
        self.damping.validate()?;
        if let Some(p) = &self.plasticity {
            p.validate()?;
        }
        Ok(())
    }
}

/// Membrane law (§3.3).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum MembraneLaw {
    /// Isotropic St. Venant–Kirchhoff CST.
    Isotropic {
        /// Yt, Young's modulus times thickness (N/m).
        young_thickness: f64,
        /// Poisson ratio ν ∈ [0, 0.5).
        poisson: f64,
        /// Optional compression-softening factor s ∈ (0, 1] (§3.3).
        #[serde(default)]
        compression_softening: Option<f64>,
    },
    /// Orthotropic Voigt law ψ = ½k_uG₁₁² + ½k_vG₂₂² + 2k_shear G₁₂² + k_couple G₁₁G₂₂ (N/m).
    Orthotropic {
        /// Warp stiffness (N/m).
        k_stretch_u: f64,
        /// Weft stiffness (N/m).
        k_stretch_v: f64,
        /// Shear stiffness (N/m).
        k_shear: f64,
        /// Coupling (N/m), k_u k_v ≥ k_couple².
        k_couple: f64,
        /// Where the warp direction comes from.
        warp: WarpSource,
    },
}

impl MembraneLaw {
    /// The kernel's resolved law.
    pub fn resolve(&self) -> Membrane {
        match *self {
            MembraneLaw::Isotropic { young_thickness, poisson, compression_softening } => match compression_softening {
                None => Membrane::isotropic(young_thickness, poisson),
                Some(s) => {
                    let (mu, lambda) = Membrane::lame(young_thickness, poisson);
                    Membrane::Softened { mu, lambda, s }
                }
            },
            MembraneLaw::Orthotropic { k_stretch_u, k_stretch_v, k_shear, k_couple, .. } => {
                Membrane::orthotropic(k_stretch_u, k_stretch_v, k_shear, k_couple)
            }
        }
    }

    /// A representative stiffness (N/m): Yt, or the largest orthotropic stretch stiffness.
    pub fn stiffness_scale(&self) -> f64 {
        match *self {
            MembraneLaw::Isotropic { young_thickness, .. } => young_thickness,
            MembraneLaw::Orthotropic { k_stretch_u, k_stretch_v, .. } => k_stretch_u.max(k_stretch_v),
        }
    }

    fn validate(&self) -> Result<()> {
        let bad = |s: String| Err(Error::BadParameter(s));
        match *self {
            MembraneLaw::Isotropic { young_thickness, poisson, compression_softening } => {
                if !young_thickness.is_finite()
                    || !poisson.is_finite()
                    || compression_softening.is_some_and(|s| !s.is_finite())
                {
                    return Err(Error::NonFinite("membrane parameters"));
                }
                if young_thickness < 0.0 {
                    return bad(format!("young_thickness must be ≥ 0 N/m, got {young_thickness}"));
                }
                if !(0.0..0.5).contains(&poisson) {
                    return bad(format!("poisson must be in [0, 0.5), got {poisson}"));
                }
                if let Some(s) = compression_softening {
                    if !(s > 0.0 && s <= 1.0) {
                        return bad(format!("compression_softening must be in (0, 1], got {s}"));
                    }
                }
            }
            MembraneLaw::Orthotropic { k_stretch_u, k_stretch_v, k_shear, k_couple, ref warp } => {
                let all = [k_stretch_u, k_stretch_v, k_shear, k_couple];
                if all.iter().any(|x| !x.is_finite()) {
                    return Err(Error::NonFinite("orthotropic membrane parameters"));
                }
                if k_stretch_u < 0.0
                    || k_stretch_v < 0.0
                    || k_shear < 0.0
                    || k_stretch_u * k_stretch_v < k_couple * k_couple
                {
                    return bad(format!(
                        "orthotropic stiffness must be PSD (k_u, k_v, k_shear ≥ 0, k_u k_v ≥ k_couple²), got {all:?}"
                    ));
                }
                if let WarpSource::Direction(d) = warp {
                    if !(d.norm() > 0.0) || d.iter().any(|x| !x.is_finite()) {
                        return bad(format!("warp direction must be a finite non-zero vector, got {d:?}"));
                    }
                }
            }
        }
        Ok(())
    }
}

/// Source of the warp (first material) direction of an orthotropic law.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum WarpSource {
    /// Direction of increasing rest-UV u (needs per-vertex or per-corner UVs).
    RestUv,
    /// A fixed direction, projected into each rest triangle.
    Direction(Vec3),
}

/// Damping model (§3.5): f_d = −(αM + K_d)v, K_d = Σ β_term H_term^GN.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub enum Damping {
    /// No damping.
    #[default]
    None,
    /// α (1/s) on the mass, β (s) on all Gauss–Newton stiffness terms.
    Rayleigh {
        /// Mass-proportional coefficient (1/s).
        alpha: f64,
        /// Stiffness-proportional coefficient (s).
        beta: f64,
    },
    /// Separate β per energy term.
    PerTerm {
        /// Mass-proportional coefficient (1/s).
        alpha: f64,
        /// β for membrane stretch (s).
        beta_stretch: f64,
        /// β for membrane shear (s).
        beta_shear: f64,
        /// β for bending (s).
        beta_bend: f64,
    },
}

impl Damping {
    /// (α, β_stretch, β_shear, β_bend).
    pub fn coefficients(&self) -> (f64, f64, f64, f64) {
        match *self {
            Damping::None => (0.0, 0.0, 0.0, 0.0),
            Damping::Rayleigh { alpha, beta } => (alpha, beta, beta, beta),
            Damping::PerTerm { alpha, beta_stretch, beta_shear, beta_bend } => {
                (alpha, beta_stretch, beta_shear, beta_bend)
            }
        }
    }

    fn validate(&self) -> Result<()> {
        let (a, b1, b2, b3) = self.coefficients();
        if [a, b1, b2, b3].iter().any(|x| !x.is_finite()) {
            return Err(Error::NonFinite("damping coefficients"));
        }
        if [a, b1, b2, b3].iter().any(|&x| x < 0.0) {
            return Err(Error::BadParameter(format!("damping coefficients must be ≥ 0, got {self:?}")));
        }
        Ok(())
    }
}

/// Bending plasticity (seed §4.4, shells.md §3.6).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Plasticity {
    /// Yield Δκ_max on the curvature deviation (1/m); `f64::INFINITY` disables updates.
    pub max_curvature_dev: f64,
    /// Hardening η (m): k ← k·exp(η x), x the excess over yield.
    pub hardening: f64,
    /// Update rule.
    #[serde(default)]
    pub rule: PlasticRule,
}

impl Plasticity {
    fn validate(&self) -> Result<()> {
        if self.max_curvature_dev.is_nan() || !self.hardening.is_finite() {
            return Err(Error::NonFinite("plasticity parameters"));
        }
        if self.max_curvature_dev < 0.0 {
            return Err(Error::BadParameter(format!("max_curvature_dev must be ≥ 0, got {}", self.max_curvature_dev)));
        }
        Ok(())
    }
}

/// Plastic update rule (§3.6, §12.3).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum PlasticRule {
    /// θ̄ ← θ̄ + sign(Δκ)(2Ā/|ē|)x: the classical return map, step-size independent (default).
    #[default]
    ReturnMapping,
    /// θ̄ ← θ − sign(Δκ)(2Ā/|ē|)x, exactly as printed in the seed.
    SeedLiteral,
}

//! Fabric parameters, their search ranges and the unit-cube mapping the optimiser works in
//! (spec §2, §4.1).
//!
//! The paper fits six Baraff–Witkin parameters (stiffness and damping of stretch, shear and
//! bend; Bhat et al. 2003 §3, eq. 1) and three coefficients of its nonlinear drag law (§3,
//! "f_drag"). Stiffnesses are per unit area so that they do not depend on the mesh.

use serde::{Deserialize, Serialize};

use crate::error::{FitError, Result};

/// One fabric parameter.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
pub enum ParamId {
    /// Tensile stiffness k_stretch (N/m).
    Stretch,
    /// In-plane shear stiffness k_shear (N/m).
    Shear,
    /// Bending modulus B (N·m): a cylinder of curvature κ stores ½Bκ² per unit area.
    Bend,
    /// Rayleigh β of the stretch term (s).
    StretchDamp,
    /// Rayleigh β of the shear term (s).
    ShearDamp,
    /// Rayleigh β of the bending term (s).
    BendDamp,
    /// Normal drag k_N (kg/m³).
    DragN,
    /// Tangential drag k_T (N·s/m³).
    DragT,
    /// Drag saturation k_f (s²/m²).
    DragF,
}

impl ParamId {
    /// All nine, in the order of the spec's table §4.1.
    pub const ALL: [ParamId; 9] = [
        ParamId::Stretch,
        ParamId::Shear,
        ParamId::Bend,
        ParamId::StretchDamp,
        ParamId::ShearDamp,
        ParamId::BendDamp,
        ParamId::DragN,
        ParamId::DragT,
        ParamId::DragF,
    ];
    /// The three stiffnesses.
    pub const STIFFNESS: [ParamId; 3] = [ParamId::Stretch, ParamId::Shear, ParamId::Bend];
    /// The six dynamic parameters (damping and drag) whose variability the waving test should
    /// lower (spec §5).
    pub const DYNAMIC: [ParamId; 6] =
        [ParamId::StretchDamp, ParamId::ShearDamp, ParamId::BendDamp, ParamId::DragN, ParamId::DragT, ParamId::DragF];
    /// The six cloth-model parameters of the static test (drag fixed).
    pub const CLOTH: [ParamId; 6] =
        [ParamId::Stretch, ParamId::Shear, ParamId::Bend, ParamId::StretchDamp, ParamId::ShearDamp, ParamId::BendDamp];

    /// Short lower-case name used in CSV headers and summary keys (`stretch`, `bend_damp`, …).
    pub fn name(self) -> &'static str {
        match self {
            ParamId::Stretch => "stretch",
            ParamId::Shear => "shear",
            ParamId::Bend => "bend",
            ParamId::StretchDamp => "stretch_damp",
            ParamId::ShearDamp => "shear_damp",
            ParamId::BendDamp => "bend_damp",
            ParamId::DragN => "drag_n",
            ParamId::DragT => "drag_t",
            ParamId::DragF => "drag_f",
        }
    }
}

/// Coefficients of the paper's nonlinear drag law (Bhat et al. 2003 §3):
/// f = −a [k_N |v_N|²/(1 + k_f |v_N|²) · v̂_N + k_T v_T].
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DragParams {
    /// Normal (quadratic) coefficient k_N (kg/m³).
    pub k_n: f64,
    /// Tangential (linear, Stokes) coefficient k_T (N·s/m³).
    pub k_t: f64,
    /// Saturation k_f (s²/m²): the normal force levels off at a·k_N/k_f.
    pub k_f: f64,
}

/// The nine fitted quantities of one fabric, in physical units (spec §4.1).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FabricParams {
    /// k_stretch (N/m).
    pub stretch: f64,
    /// k_shear (N/m).
    pub shear: f64,
    /// Bending modulus B (N·m).
    pub bend: f64,
    /// β_stretch (s).
    pub stretch_damp: f64,
    /// β_shear (s).
    pub shear_damp: f64,
    /// β_bend (s).
    pub bend_damp: f64,
    /// Air drag.
    pub drag: DragParams,
}

impl FabricParams {
    /// The value of one parameter.
    pub fn get(&self, id: ParamId) -> f64 {
        match id {
            ParamId::Stretch => self.stretch,
            ParamId::Shear => self.shear,
            ParamId::Bend => self.bend,
            ParamId::StretchDamp => self.stretch_damp,
            ParamId::ShearDamp => self.shear_damp,
            ParamId::BendDamp => self.bend_damp,
            ParamId::DragN => self.drag.k_n,
            ParamId::DragT => self.drag.k_t,
            ParamId::DragF => self.drag.k_f,
        }
    }

    /// Sets one parameter.
    pub fn set(&mut self, id: ParamId, v: f64) {
        match id {
            ParamId::Stretch => self.stretch = v,
            ParamId::Shear => self.shear = v,
            ParamId::Bend => self.bend = v,
            ParamId::StretchDamp => self.stretch_damp = v,
            ParamId::ShearDamp => self.shear_damp = v,
            ParamId::BendDamp => self.bend_damp = v,
            ParamId::DragN => self.drag.k_n = v,
            ParamId::DragT => self.drag.k_t = v,
            ParamId::DragF => self.drag.k_f = v,
        }
    }

    /// A copy with one parameter replaced.
    pub fn with(mut self, id: ParamId, v: f64) -> Self {
        self.set(id, v);
        self
    }

    /// Checks every value is finite and non-negative, stiffnesses positive.
    pub fn validate(&self) -> Result<()> {
        for id in ParamId::ALL {
            let v = self.get(id);
            let ok = v.is_finite() && if ParamId::STIFFNESS.contains(&id) { v > 0.0 } else { v >= 0.0 };
            if !ok {
                return Err(FitError::BadParameter(format!("{} = {v} (stiffness > 0, others ≥ 0, finite)", id.name())));
            }
        }
        Ok(())
    }
}

/// How a parameter is mapped to the unit interval.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum Scale {
    /// u = ln(p/lo)/ln(hi/lo).
    Log,
    /// u = (p − lo)/(hi − lo).
    Linear,
}

/// The search range of one parameter.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ParamRange {
    /// Which parameter.
    pub id: ParamId,
    /// Lower bound (physical units).
    pub lo: f64,
    /// Upper bound (physical units).
    pub hi: f64,
    /// Mapping to [0, 1].
    pub scale: Scale,
}

impl ParamRange {
    /// Physical value → unit coordinate (not clamped).
    pub fn to_unit(&self, p: f64) -> f64 {
        match self.scale {
            Scale::Log => (p / self.lo).ln() / (self.hi / self.lo).ln(),
            Scale::Linear => (p - self.lo) / (self.hi - self.lo),
        }
    }

    /// Unit coordinate → physical value.
    pub fn from_unit(&self, u: f64) -> f64 {
        match self.scale {
            Scale::Log => self.lo * (self.hi / self.lo).powf(u),
            Scale::Linear => self.lo + u * (self.hi - self.lo),
        }
    }

    /// The parameter error of spec §3.11: |ln(p̂/p*)| for log ranges, |p̂ − p*|/(hi − lo) for
    /// linear ones.
    pub fn error(&self, estimate: f64, truth: f64) -> f64 {
        match self.scale {
            Scale::Log => (estimate / truth).ln().abs(),
            Scale::Linear => (estimate - truth).abs() / (self.hi - self.lo),
        }
    }

    fn validate(&self) -> Result<()> {
        let ok = self.lo.is_finite()
            && self.hi.is_finite()
            && self.hi > self.lo
            && (self.scale == Scale::Linear || self.lo > 0.0)
            && (self.lo >= 0.0);
        if !ok {
            return Err(FitError::BadParameter(format!(
                "range of {}: [{}, {}] ({:?}) must be finite, non-negative, hi > lo, and lo > 0 for log scale",
                self.id.name(),
                self.lo,
                self.hi,
                self.scale
            )));
        }
        Ok(())
    }
}

/// The search space: ranges of all parameters, which are free, and the values of the fixed ones.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ParamSpace {
    /// One range per parameter (all nine).
    pub ranges: Vec<ParamRange>,
    /// The free parameters, in the order of the unit-cube coordinates.
    pub free: Vec<ParamId>,
    /// Values of every parameter not in `free`.
    pub fixed: FabricParams,
}

impl ParamSpace {
    /// A space over `ranges` with `free` parameters; the others take `fixed`'s values.
    /// Errors: a missing or invalid range, a repeated free parameter, invalid fixed values.
    pub fn new(ranges: Vec<ParamRange>, free: Vec<ParamId>, fixed: FabricParams) -> Result<Self> {
        let s = Self { ranges, free, fixed };
        s.validate()?;
        Ok(s)
    }

    /// Checks the space (see [`ParamSpace::new`]).
    pub fn validate(&self) -> Result<()> {
        for id in ParamId::ALL {
            let n = self.ranges.iter().filter(|r| r.id == id).count();
            if n != 1 {
                return Err(FitError::BadParameter(format!("parameter space: {n} ranges for {}", id.name())));
            }
        }
        for r in &self.ranges {
            r.validate()?;
        }
        for (i, id) in self.free.iter().enumerate() {
            if self.free[..i].contains(id) {
                return Err(FitError::BadParameter(format!("parameter space: {} is free twice", id.name())));
            }
        }
        if self.free.is_empty() {
            return Err(FitError::BadParameter("parameter space: no free parameter".into()));
        }
        self.fixed.validate()
    }

    /// The range of a parameter.
    pub fn range(&self, id: ParamId) -> &ParamRange {
        self.ranges.iter().find(|r| r.id == id).expect("validated: every parameter has exactly one range")
    }

    /// Number of free parameters (the unit cube's dimension).
    pub fn dim(&self) -> usize {
        self.free.len()
    }

    /// Free parameters of `p` as unit-cube coordinates (not clamped).
    pub fn to_unit(&self, p: &FabricParams) -> Vec<f64> {
        self.free.iter().map(|&id| self.range(id).to_unit(p.get(id))).collect()
    }

    /// The parameters at unit-cube point `x` (fixed ones from `fixed`).
    pub fn from_unit(&self, x: &[f64]) -> FabricParams {
        let mut p = self.fixed;
        for (&id, &u) in self.free.iter().zip(x) {
            p.set(id, self.range(id).from_unit(u));
        }
        p
    }

    /// The same space with other free parameters.
    pub fn with_free(&self, free: Vec<ParamId>) -> Result<Self> {
        Self::new(self.ranges.clone(), free, self.fixed)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::presets::{default_ranges, FabricPreset};

    /// Spec T15: to_unit ∘ from_unit = identity for log and linear ranges.
    #[test]
    fn unit_mapping_round_trips() {
        let truth = FabricPreset::Linen.params();
        let s = ParamSpace::new(default_ranges(), ParamId::ALL.to_vec(), truth).unwrap();
        for k in 0..=20 {
            let x: Vec<f64> = (0..9).map(|i| ((k * 7 + i * 3) % 21) as f64 / 20.0).collect();
            let back = s.to_unit(&s.from_unit(&x));
            for (a, b) in x.iter().zip(&back) {
                assert!((a - b).abs() <= 1e-14, "{a} vs {b}");
            }
        }
        let u = s.to_unit(&truth);
        let p = s.from_unit(&u);
        for id in ParamId::ALL {
            let r = s.range(id);
            assert!(r.error(p.get(id), truth.get(id)) <= 1e-14, "{id:?}");
        }
    }

    #[test]
    fn invalid_spaces_are_errors() {
        let truth = FabricPreset::Satin.params();
        let mut r = default_ranges();
        r.pop();
        assert!(ParamSpace::new(r, vec![ParamId::Bend], truth).is_err());
        assert!(ParamSpace::new(default_ranges(), vec![ParamId::Bend, ParamId::Bend], truth).is_err());
        assert!(ParamSpace::new(default_ranges(), vec![], truth).is_err());
        let mut bad = default_ranges();
        bad[0].lo = 0.0; // log range from 0
        assert!(ParamSpace::new(bad, vec![ParamId::Bend], truth).is_err());
        assert!(ParamSpace::new(default_ranges(), vec![ParamId::Bend], truth.with(ParamId::Bend, f64::NAN)).is_err());
    }
}

//! The curve-skeleton data model (spec §2.3): one [`JointCurve`] per linked bone pair at a joint,
//! with its Bone_CP rule, shape, twist distribution and frame-centre mode, plus the skinning
//! options [`CurveOptions`].

use geom_core::math::{smoothstep, Curve1D};
use serde::{Deserialize, Serialize};

use crate::error::{Result, SkinError};

/// One bone segment seen from a curve's joint `J`: `far` is the other end joint, `owner` the joint
/// whose frame moves the segment rigidly (`far` for the incoming bone from the parent, `J` for an
/// outgoing bone to a child).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct BoneEnd {
    /// The far end joint of the segment.
    pub far: usize,
    /// The joint whose frame the segment is rigid with.
    pub owner: usize,
}

/// Where the Bone_CPs sit (distance `L` from the joint along each bone), spec §3.4.3.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum BoneCp {
    /// Constant `L` (m).
    Fixed {
        /// Distance from the joint (m).
        dist: f64,
    },
    /// The fold-free rule `L = clamp(safety·d·β/(2cos(β/2)), min, max_frac·min(len_a, len_c))`
    /// (centre on the skeleton) or `clamp(safety·d·tan(β/2), …)` (centre on the curve).
    Floating {
        /// Skin-to-skeleton distance `d` (m); `None` = the 95th percentile of the bound
        /// vertices' distances to the curve's rest skeleton.
        skin_dist: Option<f64>,
        /// Multiplier on the minimal fold-free `L` (≥ 1).
        safety: f64,
        /// Smallest `L` (m).
        min: f64,
        /// Cap of `L` as a fraction of the shorter adjacent bone.
        max_frac: f64,
    },
    /// Animator curve: bend angle (rad) → `L` (m), monotone cubic through keys.
    Keyed(Curve1D),
}

impl Default for BoneCp {
    fn default() -> Self {
        BoneCp::Floating { skin_dist: None, safety: 1.1, min: 0.02, max_frac: 0.5 }
    }
}

/// Curve geometry through the Bone_CPs and the Joint_CP.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, Serialize, Deserialize)]
pub enum CurveShape {
    /// Rational quadratic with middle weight `cos(β/2)`: the circular arc tangent to both bones,
    /// radius `L / tan(β/2)` (spec §3.4.2, default). Its tangent angle grows linearly with arc
    /// length, so it is fold-free with the smallest `L`.
    #[default]
    CircularArc,
    /// The paper's plain quadratic B-spline (weight 1) on the same control points
    /// ([`super::bspline::QuadBSpline`]): curvature concentrates at the joint, so the floating
    /// rule needs a larger `L` (≈ 1.46× the arc's at 90°) to stay fold-free.
    QuadraticBSpline,
}

/// Twist distribution `D: [0,1] → [0,1]` along the curve (spec §3.4.4).
#[derive(Clone, Debug, PartialEq, Default, Serialize, Deserialize)]
pub enum TwistDistribution {
    /// `D(σ) = σ`.
    Linear,
    /// `D(σ) = 3σ² − 2σ³`.
    #[default]
    SmoothStep,
    /// Monotone cubic (Fritsch–Carlson) through keys, with `(0,0)` and `(1,1)` added.
    Keys(Curve1D),
}

impl TwistDistribution {
    /// `Keys` from key points `(σ, D)` in `[0,1]²`: adds `(0,0)` and `(1,1)` when absent. Errors
    /// when keys are outside the unit square, not increasing in σ, or not monotone in `D`.
    pub fn keys(keys: &[(f64, f64)]) -> Result<Self> {
        let mut k: Vec<(f64, f64)> = Vec::with_capacity(keys.len() + 2);
        if keys.first().is_none_or(|p| p.0 > 0.0) {
            k.push((0.0, 0.0));
        }
        k.extend_from_slice(keys);
        if keys.last().is_none_or(|p| p.0 < 1.0) {
            k.push((1.0, 1.0));
        }
        for (i, &(x, y)) in k.iter().enumerate() {
            if !(0.0..=1.0).contains(&x) || !(0.0..=1.0).contains(&y) {
                return Err(SkinError::Param(format!("twist key {i} ({x}, {y}) outside [0,1]²")));
            }
            if i > 0 && y < k[i - 1].1 {
                return Err(SkinError::Param(format!("twist keys not monotone at key {i}")));
            }
        }
        if k[0] != (0.0, 0.0) || k[k.len() - 1] != (1.0, 1.0) {
            return Err(SkinError::Param("twist keys must start at (0,0) and end at (1,1)".into()));
        }
        Ok(TwistDistribution::Keys(Curve1D::new(&k)?))
    }

    /// `D(σ)`, σ clamped to `[0, 1]`.
    pub fn eval(&self, sigma: f64) -> f64 {
        let s = sigma.clamp(0.0, 1.0);
        match self {
            TwistDistribution::Linear => s,
            TwistDistribution::SmoothStep => smoothstep(0.0, 1.0, s),
            TwistDistribution::Keys(c) => c.eval(s),
        }
    }
}

/// Where a curve frame's centre sits (spec §3.4.4).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, Serialize, Deserialize)]
pub enum CentreMode {
    /// On the posed skeleton polyline at the same skeleton arc length (paper: the bone never
    /// pokes through the skin).
    #[default]
    OnSkeleton,
    /// On the curve at the same normalised curve arc length.
    OnCurve,
}

/// Optional volume compensation (spec §3.4.4).
#[derive(Clone, Copy, Debug, PartialEq, Default, Serialize, Deserialize)]
pub enum VolumeComp {
    /// No compensation.
    #[default]
    Off,
    /// Scale the local offset by `min(max_scale, 1/sqrt(cos α))`.
    Isotropic {
        /// Largest scale (use `f64::INFINITY` for none).
        max_scale: f64,
    },
}

/// One curve of the curve skeleton (spec §3.4.1).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct JointCurve {
    /// The joint the curve passes through.
    pub joint: usize,
    /// First linked bone (the curve's parameter starts at its far end).
    pub bone_in: BoneEnd,
    /// Second linked bone (the parameter ends at its far end).
    pub bone_out: BoneEnd,
    /// Fraction of the first bone covered, measured from the joint.
    pub span_in: f64,
    /// Fraction of the second bone covered.
    pub span_out: f64,
    /// Bone_CP rule.
    pub bone_cp: BoneCp,
    /// Curve geometry.
    pub shape: CurveShape,
    /// Twist distribution.
    pub twist: TwistDistribution,
    /// Frame-centre mode.
    pub centre: CentreMode,
}

/// The curve skeleton: all joint curves.
#[derive(Clone, Debug, PartialEq, Default, Serialize, Deserialize)]
pub struct CurveSkeleton {
    /// The curves.
    pub curves: Vec<JointCurve>,
}

/// Which joints get curves.
#[derive(Clone, Debug, PartialEq, Default, Serialize, Deserialize)]
pub struct TopologyRules {
    /// Joints that own no curve.
    pub exclude_joints: Vec<usize>,
    /// Skip curves whose two bones move with the same joint frame (they never bend).
    pub skip_rigid: bool,
}

/// Per-curve settings applied by [`crate::curve::build_curve_skeleton`].
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct JointCurveDefaults {
    /// Bone fraction covered by a curve (1.0 is used where the far end is a leaf or a root).
    pub span: f64,
    /// Bone_CP rule.
    pub bone_cp: BoneCp,
    /// Shape.
    pub shape: CurveShape,
    /// Twist distribution.
    pub twist: TwistDistribution,
    /// Frame-centre mode.
    pub centre: CentreMode,
}

impl Default for JointCurveDefaults {
    fn default() -> Self {
        JointCurveDefaults {
            span: 0.5,
            bone_cp: BoneCp::default(),
            shape: CurveShape::default(),
            twist: TwistDistribution::default(),
            centre: CentreMode::default(),
        }
    }
}

/// Skinning options (spec §2.3, §4).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CurveOptions {
    /// Frame-table samples per curve (0 = exact `f64` evaluation per vertex).
    pub table_samples: usize,
    /// Also sample the kinks (σ_J and the arc-zone ends) — without them the table error is first
    /// order (spec §3.4.6).
    pub kink_samples: bool,
    /// Volume compensation.
    pub volume_comp: VolumeComp,
    /// Most curves bound to one vertex (paper: 3).
    pub max_curves_per_vertex: usize,
    /// Weight cut-off band β of §3.4.5.
    pub blend_band: f64,
    /// Choose the twist representative closest to the previous frame's.
    pub twist_unwrap: bool,
}

impl Default for CurveOptions {
    fn default() -> Self {
        CurveOptions {
            table_samples: 64,
            kink_samples: true,
            volume_comp: VolumeComp::Off,
            max_curves_per_vertex: 3,
            blend_band: 0.5,
            twist_unwrap: true,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn twist_keys_are_monotone_and_pass_through_keys() {
        // Spec 7.5 f.
        let d = TwistDistribution::keys(&[(0.3, 0.1), (0.5, 0.5), (0.8, 0.95)]).unwrap();
        assert_eq!(d.eval(0.0), 0.0);
        assert_eq!(d.eval(1.0), 1.0);
        for &(x, y) in &[(0.3, 0.1), (0.5, 0.5), (0.8, 0.95)] {
            assert!((d.eval(x) - y).abs() < 1e-12);
        }
        let mut prev = 0.0;
        for i in 0..=1000 {
            let v = d.eval(i as f64 / 1000.0);
            assert!(v >= prev - 1e-15, "not monotone at {i}");
            prev = v;
        }
        assert!(TwistDistribution::keys(&[(0.5, 0.7), (0.6, 0.2)]).is_err());
        assert!(TwistDistribution::keys(&[(0.5, 1.5)]).is_err());
    }

    #[test]
    fn presets_hit_the_ends() {
        for d in [TwistDistribution::Linear, TwistDistribution::SmoothStep] {
            assert_eq!(d.eval(0.0), 0.0);
            assert_eq!(d.eval(1.0), 1.0);
            assert_eq!(d.eval(-3.0), 0.0);
        }
    }
}

//! Linear blend skinning (spec §3.2; Magnenat-Thalmann et al. 1988, Lewis et al. 2000):
//! `x' = Σ_b w_b (R_b x + t_b)`, `n' = normalize(Σ_b w_b R_b n)`.
//!
//! The normal uses the blended linear part, not the inverse transpose of the blended matrix: the
//! common approximation (exact for rigid blends, slightly off where the blend shears).
//! Per frame each `T_b` becomes a row-major 3×4 `f32` matrix; per vertex the `K` matrices are
//! accumulated (12 FMAs each) and applied once ([`LbsBlend::Matrices`]), or the `K` transformed
//! points are accumulated ([`LbsBlend::Points`]); the benchmark compares both.

use std::ops::Range;

use geom_core::anim::skin::{skinning_transforms, SkinSkeleton};
use geom_core::math::{Iso3, Mat34, Pt3, Vec3};

use crate::error::{Result, SkinError};
use crate::skinner::{normalize3, DeformOutput, Skinner};
use crate::weights::PackedWeights;

/// How the per-vertex blend is evaluated (same result up to f32 rounding).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum LbsBlend {
    /// Accumulate the weighted 3×4 matrices, then one matrix–vector product.
    #[default]
    Matrices,
    /// Accumulate the weighted transformed points.
    Points,
}

/// Fast `f32` linear blend skinner with `K` influences per vertex.
#[derive(Clone, Debug)]
pub struct Lbs<const K: usize> {
    rest: Vec<[f32; 3]>,
    rest_n: Option<Vec<[f32; 3]>>,
    weights: PackedWeights<K>,
    max_bone: usize,
    mats: Vec<[f32; 12]>,
    /// Blend evaluation order.
    pub blend: LbsBlend,
}

/// Row-major 3×4 `f32` matrix of an affine map.
pub(crate) fn mat12(m: &Mat34) -> [f32; 12] {
    let mut o = [0f32; 12];
    for r in 0..3 {
        for c in 0..4 {
            o[4 * r + c] = m[(r, c)] as f32;
        }
    }
    o
}

/// The 3×4 matrix of a rigid transform.
pub(crate) fn iso_mat34(t: &Iso3) -> Mat34 {
    t.to_homogeneous().fixed_view::<3, 4>(0, 0).into_owned()
}

impl<const K: usize> Lbs<K> {
    /// Binds rest positions (and optionally rest normals) with packed weights. Errors: sizes
    /// differ.
    pub fn new(rest: Vec<[f32; 3]>, rest_normals: Option<Vec<[f32; 3]>>, weights: PackedWeights<K>) -> Result<Self> {
        let max_bone = weights.check_bind(
            rest.len(),
            rest_normals.as_ref().map(|n| n.len()),
            ["LBS weights rows", "LBS rest normals"],
        )?;
        Ok(Lbs { rest, rest_n: rest_normals, weights, max_bone, mats: Vec::new(), blend: LbsBlend::default() })
    }

    /// The packed weights.
    pub fn weights(&self) -> &PackedWeights<K> {
        &self.weights
    }

    /// Sets the per-bone skinning transforms `T_b` directly (rigid).
    pub fn set_transforms(&mut self, t: &[Iso3]) -> Result<()> {
        self.check_len(t.len())?;
        self.mats.clear();
        self.mats.extend(t.iter().map(|t| mat12(&iso_mat34(t))));
        Ok(())
    }

    /// Sets general affine per-bone transforms (scale and shear allowed; spec §8).
    pub fn set_affine(&mut self, a: &[Mat34]) -> Result<()> {
        self.check_len(a.len())?;
        self.mats.clear();
        self.mats.extend(a.iter().map(mat12));
        Ok(())
    }

    fn check_len(&self, n: usize) -> Result<()> {
        if n == 0 {
            return Err(SkinError::EmptySkeleton);
        }
        if !self.rest.is_empty() && n <= self.max_bone {
            return Err(SkinError::Size { what: "LBS bone transforms", expected: self.max_bone + 1, got: n });
        }
        Ok(())
    }
}

impl<const K: usize> Skinner for Lbs<K> {
    fn prepare(&mut self, sk: &SkinSkeleton, posed: &[Iso3]) -> Result<()> {
        if posed.len() != sk.len() {
            return Err(SkinError::Size { what: "posed frames", expected: sk.len(), got: posed.len() });
        }
        self.check_len(posed.len())?;
        self.mats.clear();
        for (w, b) in posed.iter().zip(&sk.rest_world) {
            self.mats.push(mat12(&iso_mat34(&(w * b.inverse()))));
        }
        Ok(())
    }

    fn len(&self) -> usize {
        self.rest.len()
    }

    fn deform_range(&self, range: Range<usize>, out: DeformOutput<'_>) {
        assert_eq!(out.positions.len(), range.len(), "LBS: output length");
        let rest = &self.rest[range.clone()];
        let bones = &self.weights.bone[range.clone()];
        let ws = &self.weights.w[range.clone()];
        let mats = &self.mats[..];
        match self.blend {
            LbsBlend::Matrices => {
                for i in 0..rest.len() {
                    let (b, w) = (&bones[i], &ws[i]);
                    let mut m = [0f32; 12];
                    for k in 0..K {
                        let mk = &mats[b[k] as usize];
                        let wk = w[k];
                        for e in 0..12 {
                            m[e] += wk * mk[e];
                        }
                    }
                    let x = rest[i];
                    out.positions[i] = [
                        m[0] * x[0] + m[1] * x[1] + m[2] * x[2] + m[3],
                        m[4] * x[0] + m[5] * x[1] + m[6] * x[2] + m[7],
                        m[8] * x[0] + m[9] * x[1] + m[10] * x[2] + m[11],
                    ];
                }
            }
            LbsBlend::Points => {
                for i in 0..rest.len() {
                    let (b, w) = (&bones[i], &ws[i]);
                    let x = rest[i];
                    let mut p = [0f32; 3];
                    for k in 0..K {
                        let m = &mats[b[k] as usize];
                        let wk = w[k];
                        p[0] += wk * (m[0] * x[0] + m[1] * x[1] + m[2] * x[2] + m[3]);
                        p[1] += wk * (m[4] * x[0] + m[5] * x[1] + m[6] * x[2] + m[7]);
                        p[2] += wk * (m[8] * x[0] + m[9] * x[1] + m[10] * x[2] + m[11]);
                    }
                    out.positions[i] = p;
                }
            }
        }
        if let (Some(nout), Some(rn)) = (out.normals, &self.rest_n) {
            assert_eq!(nout.len(), range.len(), "LBS: normal output length");
            let rn = &rn[range];
            for i in 0..rn.len() {
                let (b, w) = (&bones[i], &ws[i]);
                let n = rn[i];
                let mut a = [0f32; 3];
                for k in 0..K {
                    let m = &mats[b[k] as usize];
                    let wk = w[k];
                    a[0] += wk * (m[0] * n[0] + m[1] * n[1] + m[2] * n[2]);
                    a[1] += wk * (m[4] * n[0] + m[5] * n[1] + m[6] * n[2]);
                    a[2] += wk * (m[8] * n[0] + m[9] * n[1] + m[10] * n[2]);
                }
                nout[i] = normalize3(a);
            }
        }
    }
}

/// Reference LBS in `f64` with the same packed weights (the "f64 path" of the tests). The `f32`
/// weights are renormalised in `f64`, so the f64 path is exact to rounding (an `f32` row sums to
/// 1 only within ~1e-7).
pub fn lbs_f64<const K: usize>(rest: &[Pt3], w: &PackedWeights<K>, t: &[Iso3]) -> Vec<Pt3> {
    rest.iter()
        .zip(w.bone.iter().zip(&w.w))
        .map(|(x, (b, ws))| {
            let mut acc = Vec3::zeros();
            let mut sum = 0.0;
            for k in 0..K {
                if ws[k] > 0.0 {
                    acc += (t[b[k] as usize] * x).coords * ws[k] as f64;
                    sum += ws[k] as f64;
                }
            }
            Pt3::from(acc / sum)
        })
        .collect()
}

/// Convenience: skinning transforms of a posed skeleton (re-export of geom-core's).
pub fn transforms(sk: &SkinSkeleton, posed: &[Iso3]) -> Vec<Iso3> {
    skinning_transforms(sk, posed)
}

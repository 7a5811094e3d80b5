//! Dual-quaternion skinning (spec §3.3; Kavan, Collins, Žára, O'Sullivan 2007/2008):
//! `b̂ = Σ_b w_b s_b q̂_b`, `ĉ = b̂ / ‖b_real‖`, `x' = R(c₀) x + 2 (c_ε c₀*)_vec`, `n' = R(c₀) n`.
//!
//! Antipodality: [`Antipodal::PerVertexPivot`] (default) flips every blended quaternion into the
//! hemisphere of the vertex's largest-weight bone (slot 0 of [`PackedWeights`]), which also bounds
//! `‖b_real‖ ≥ w_pivot ≥ 1/K`; [`Antipodal::Hierarchy`] flips each bone once per frame into its
//! parent's hemisphere (cheaper per vertex, wrong for relative rotations beyond 180°).
//! Non-rigid bone transforms are refused ([`SkinError::NonRigidForDqs`]) unless `allow_scale`, in
//! which case each affine `A_b = R_b S_b` is split by the polar decomposition and the scale/shear
//! parts are blended linearly first (Kavan 2008's two-phase skinning; an approximation: the blend
//! of `S_b` is linear, and normals go through the blended `S_b⁻¹` before the rotation).

use std::ops::Range;

use geom_core::anim::skin::SkinSkeleton;
use geom_core::math::{Iso3, Mat3, Mat34, Pt3, UnitQuat, Vec3};
use nalgebra::{Quaternion, Translation3};
use serde::{Deserialize, Serialize};

use crate::dq::{hemisphere_sign, DualQuat};
use crate::error::{Result, SkinError};
use crate::skinner::{normalize3, DeformOutput, Skinner};
use crate::weights::PackedWeights;

/// The hemisphere rule for blended quaternions.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, Serialize, Deserialize)]
pub enum Antipodal {
    /// Per vertex: `s_b = sign(r_b · r_pivot)`, pivot = largest weight.
    #[default]
    PerVertexPivot,
    /// Per frame: each bone flipped into its (already flipped) parent's hemisphere.
    Hierarchy,
}

/// Fast `f32` dual-quaternion skinner with `K` influences per vertex.
#[derive(Clone, Debug)]
pub struct Dqs<const K: usize> {
    rest: Vec<[f32; 3]>,
    rest_n: Option<Vec<[f32; 3]>>,
    weights: PackedWeights<K>,
    max_bone: usize,
    /// Per bone `[r.w, r.x, r.y, r.z, d.w, d.x, d.y, d.z]`.
    dq: Vec<[f32; 8]>,
    /// Per bone scale/shear `S_b` and `S_b⁻¹` (row-major), only when a non-rigid frame was set.
    scale: Option<Vec<([f32; 9], [f32; 9])>>,
    /// Hemisphere rule.
    pub antipodal: Antipodal,
    /// Accept non-rigid bone transforms (two-phase approximation).
    pub allow_scale: bool,
}

fn dq8(q: &DualQuat) -> [f32; 8] {
    let (r, d) = (&q.real, &q.dual);
    [r.w as f32, r.i as f32, r.j as f32, r.k as f32, d.w as f32, d.i as f32, d.j as f32, d.k as f32]
}

fn flip_hierarchy(dq: &mut [DualQuat], parent: &[Option<usize>]) {
    for j in 0..dq.len() {
        if let Some(p) = parent.get(j).copied().flatten() {
            if hemisphere_sign(&dq[p].real, &dq[j].real) < 0.0 {
                dq[j] = dq[j].scale(-1.0);
            }
        }
    }
}

/// Deviation of a 3×3 matrix from a rotation, `max |AᵀA − I|`.
pub fn rigidity_deviation(a: &Mat3) -> f64 {
    (a.transpose() * a - Mat3::identity()).abs().max()
}

/// Polar decomposition `A = R S` (R proper rotation, S symmetric) by SVD.
fn polar(a: &Mat3) -> (Mat3, Mat3) {
    let svd = a.svd(true, true);
    // Both factors were requested above.
    let (u, vt) = (svd.u.expect("svd u requested"), svd.v_t.expect("svd v_t requested"));
    let mut d = Mat3::identity();
    if (u * vt).determinant() < 0.0 {
        d[(2, 2)] = -1.0;
    }
    let r = u * d * vt;
    let s = r.transpose() * a;
    (r, s)
}

fn m9(m: &Mat3) -> [f32; 9] {
    let mut o = [0f32; 9];
    for r in 0..3 {
        for c in 0..3 {
            o[3 * r + c] = m[(r, c)] as f32;
        }
    }
    o
}

impl<const K: usize> Dqs<K> {
    /// Binds rest positions (and optional normals) with packed weights sorted by decreasing
    /// weight (as [`PackedWeights::from_sparse`] makes them). Errors: sizes differ.
    pub fn new(rest: Vec<[f32; 3]>, rest_normals: Option<Vec<[f32; 3]>>, weights: PackedWeights<K>) -> Result<Self> {
        let max_bone = weights.check_bind(
            rest.len(),
            rest_normals.as_ref().map(|n| n.len()),
            ["DQS weights rows", "DQS rest normals"],
        )?;
        Ok(Dqs {
            rest,
            rest_n: rest_normals,
            weights,
            max_bone,
            dq: Vec::new(),
            scale: None,
            antipodal: Antipodal::default(),
            allow_scale: false,
        })
    }

    fn check_len(&self, n: usize) -> Result<()> {
        if n == 0 {
            return Err(SkinError::EmptySkeleton);
        }
        if !self.rest.is_empty() && n <= self.max_bone {
            return Err(SkinError::Size { what: "DQS bone transforms", expected: self.max_bone + 1, got: n });
        }
        Ok(())
    }

    /// Sets rigid skinning transforms `T_b` directly; `parent` is used by [`Antipodal::Hierarchy`].
    pub fn set_transforms(&mut self, t: &[Iso3], parent: &[Option<usize>]) -> Result<()> {
        self.check_len(t.len())?;
        let mut dq: Vec<DualQuat> = t.iter().map(DualQuat::from_iso).collect();
        if self.antipodal == Antipodal::Hierarchy {
            flip_hierarchy(&mut dq, parent);
        }
        self.dq.clear();
        self.dq.extend(dq.iter().map(dq8));
        self.scale = None;
        Ok(())
    }

    /// Sets affine skinning transforms. Errors with [`SkinError::NonRigidForDqs`] when a linear
    /// part deviates from a rotation by more than 1e-6 and `allow_scale` is off.
    pub fn set_affine(&mut self, a: &[Mat34], parent: &[Option<usize>]) -> Result<()> {
        self.check_len(a.len())?;
        let mut dq = Vec::with_capacity(a.len());
        let mut sc = Vec::with_capacity(a.len());
        let mut any_scale = false;
        for (b, m) in a.iter().enumerate() {
            let lin: Mat3 = m.fixed_view::<3, 3>(0, 0).into_owned();
            let dev = rigidity_deviation(&lin);
            let t = Vec3::new(m[(0, 3)], m[(1, 3)], m[(2, 3)]);
            if dev > 1e-6 {
                if !self.allow_scale {
                    return Err(SkinError::NonRigidForDqs { bone: b, deviation: dev });
                }
                any_scale = true;
            }
            let (r, s) = polar(&lin);
            let s_inv = s.try_inverse().ok_or_else(|| SkinError::Param(format!("bone {b}: singular transform")))?;
            let q = UnitQuat::from_matrix(&r);
            dq.push(DualQuat::from_iso(&Iso3::from_parts(Translation3::from(t), q)));
            sc.push((m9(&s), m9(&s_inv)));
        }
        if self.antipodal == Antipodal::Hierarchy {
            flip_hierarchy(&mut dq, parent);
        }
        self.dq.clear();
        self.dq.extend(dq.iter().map(dq8));
        self.scale = if any_scale { Some(sc) } else { None };
        Ok(())
    }

    #[inline(always)]
    fn blend(&self, b: &[u16; K], w: &[f32; K]) -> [f32; 8] {
        let p = &self.dq[b[0] as usize];
        let mut acc = [0f32; 8];
        for e in 0..8 {
            acc[e] = w[0] * p[e];
        }
        for k in 1..K {
            let q = &self.dq[b[k] as usize];
            let mut s = w[k];
            if self.antipodal == Antipodal::PerVertexPivot {
                let d = q[0] * p[0] + q[1] * p[1] + q[2] * p[2] + q[3] * p[3];
                if d < 0.0 {
                    s = -s;
                }
            }
            for e in 0..8 {
                acc[e] += s * q[e];
            }
        }
        let inv = 1.0 / (acc[0] * acc[0] + acc[1] * acc[1] + acc[2] * acc[2] + acc[3] * acc[3]).sqrt();
        for a in acc.iter_mut() {
            *a *= inv;
        }
        acc
    }
}

/// Rotates `v` by the unit quaternion `(w, x, y, z)`: `v + 2 u × (u × v + w v)`.
#[inline(always)]
pub(crate) fn qrot(q: &[f32], v: [f32; 3]) -> [f32; 3] {
    let (w, x, y, z) = (q[0], q[1], q[2], q[3]);
    // a = u × v + w v
    let a = [y * v[2] - z * v[1] + w * v[0], z * v[0] - x * v[2] + w * v[1], x * v[1] - y * v[0] + w * v[2]];
    // u × a
    let c = [y * a[2] - z * a[1], z * a[0] - x * a[2], x * a[1] - y * a[0]];
    [v[0] + 2.0 * c[0], v[1] + 2.0 * c[1], v[2] + 2.0 * c[2]]
}

#[inline(always)]
fn mat9v(m: &[f32; 9], v: [f32; 3]) -> [f32; 3] {
    [
        m[0] * v[0] + m[1] * v[1] + m[2] * v[2],
        m[3] * v[0] + m[4] * v[1] + m[5] * v[2],
        m[6] * v[0] + m[7] * v[1] + m[8] * v[2],
    ]
}

impl<const K: usize> Skinner for Dqs<K> {
    fn prepare(&mut self, sk: &SkinSkeleton, posed: &[Iso3]) -> Result<()> {
        if posed.len() != sk.len() {
            return Err(SkinError::Size { what: "posed frames", expected: sk.len(), got: posed.len() });
        }
        let t: Vec<Iso3> = posed.iter().zip(&sk.rest_world).map(|(w, b)| w * b.inverse()).collect();
        self.set_transforms(&t, &sk.parent)
    }

    fn len(&self) -> usize {
        self.rest.len()
    }

    fn deform_range(&self, range: Range<usize>, out: DeformOutput<'_>) {
        assert_eq!(out.positions.len(), range.len(), "DQS: output length");
        let rest = &self.rest[range.clone()];
        let bones = &self.weights.bone[range.clone()];
        let ws = &self.weights.w[range.clone()];
        let rn = self.rest_n.as_ref().map(|n| &n[range.clone()]);
        let mut nout = out.normals;
        for i in 0..rest.len() {
            let c = self.blend(&bones[i], &ws[i]);
            let (mut x, mut n) = (rest[i], rn.map(|n| n[i]));
            if let Some(sc) = &self.scale {
                // Phase 1 (allow_scale): linear blend of the per-bone scale/shear parts.
                let (mut xs, mut ns) = ([0f32; 3], [0f32; 3]);
                for k in 0..K {
                    let (s, si) = &sc[bones[i][k] as usize];
                    let (a, b) = (mat9v(s, x), mat9v(si, n.unwrap_or([0.0; 3])));
                    for e in 0..3 {
                        xs[e] += ws[i][k] * a[e];
                        ns[e] += ws[i][k] * b[e];
                    }
                }
                x = xs;
                if n.is_some() {
                    n = Some(normalize3(ns));
                }
            }
            let (w0, v) = (c[0], [c[1], c[2], c[3]]);
            let (we, ve) = (c[4], [c[5], c[6], c[7]]);
            // t = 2 (w0 ve − we v + v × ve)
            let t = [
                2.0 * (w0 * ve[0] - we * v[0] + v[1] * ve[2] - v[2] * ve[1]),
                2.0 * (w0 * ve[1] - we * v[1] + v[2] * ve[0] - v[0] * ve[2]),
                2.0 * (w0 * ve[2] - we * v[2] + v[0] * ve[1] - v[1] * ve[0]),
            ];
            let r = qrot(&c[..4], x);
            out.positions[i] = [r[0] + t[0], r[1] + t[1], r[2] + t[2]];
            if let (Some(no), Some(n)) = (nout.as_deref_mut(), n) {
                no[i] = qrot(&c[..4], n);
            }
        }
    }
}

/// Reference DQS in `f64` with the same packed weights (the "f64 path" of tests 7.3): rigid
/// skinning transforms `t`, parents for [`Antipodal::Hierarchy`].
pub fn dqs_f64<const K: usize>(
    rest: &[Pt3],
    w: &PackedWeights<K>,
    t: &[Iso3],
    parent: &[Option<usize>],
    antipodal: Antipodal,
) -> Vec<Pt3> {
    let mut dq: Vec<DualQuat> = t.iter().map(DualQuat::from_iso).collect();
    if antipodal == Antipodal::Hierarchy {
        flip_hierarchy(&mut dq, parent);
    }
    rest.iter()
        .zip(w.bone.iter().zip(&w.w))
        .map(|(x, (b, ws))| {
            let p = dq[b[0] as usize];
            let mut acc =
                DualQuat { real: Quaternion::new(0.0, 0.0, 0.0, 0.0), dual: Quaternion::new(0.0, 0.0, 0.0, 0.0) };
            for k in 0..K {
                let q = dq[b[k] as usize];
                let s = match antipodal {
                    Antipodal::PerVertexPivot => hemisphere_sign(&p.real, &q.real),
                    Antipodal::Hierarchy => 1.0,
                };
                acc = acc.add(&q.scale(s * ws[k] as f64));
            }
            acc.normalized().transform_point(x)
        })
        .collect()
}

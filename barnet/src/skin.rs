//! Control-mesh skinning (spec §3.4.1) and per-node frames (§3.5): linear blend skinning of
//! the control vertices and the rotation part of the dual-quaternion blend (normalised
//! quaternion average) of each node's bones.
//!
//! Bones are segments between consecutive joints of a chain; a bone's skinning transform is
//! `T_j = posed_j · rest_j⁻¹`, given directly by the caller (the identity at the rest pose).
//! Decision: the spec reuses curve-skin's `Lbs`/`Dqs`; this session must not depend on that
//! crate, so this small f64 implementation is used (weights as `(bone, w)` rows).

use crate::error::{check_len, BarNetError, Result};
use geom_core::graph::Ragged;
use geom_core::math::{smoothstep, Iso3, Pt3, UnitQuat, Vec3};
use nalgebra::Quaternion;

/// A joint chain: bone `j` goes from joint `j` to joint `j + 1`.
#[derive(Clone, Debug)]
pub struct Chain {
    /// Joint names.
    pub names: Vec<String>,
    /// Rest joint positions (m).
    pub joints: Vec<Pt3>,
}

impl Chain {
    /// Number of bones (`joints − 1`).
    pub fn n_bones(&self) -> usize {
        self.joints.len().saturating_sub(1)
    }

    /// Index of a joint by name. Errors: unknown name.
    pub fn joint(&self, name: &str) -> Result<usize> {
        self.names.iter().position(|n| n == name).ok_or_else(|| {
            BarNetError::InvalidParameter(format!("unknown joint '{name}'; known: {}", self.names.join(", ")))
        })
    }

    /// Skinning transforms for a chain posed by rotating each joint `j` (except the last) by the
    /// local rotation `local[j]` (about the joint, in the parent's frame); the root may also be
    /// moved by `root` (applied last). Bone `j` is rotated by the product of the rotations of
    /// joints `0..=j`.
    pub fn pose(&self, local: &[UnitQuat], root: &Iso3) -> Result<Vec<Iso3>> {
        check_len("joint rotations", self.n_bones(), local.len())?;
        let mut out = Vec::with_capacity(self.n_bones());
        let mut acc = Iso3::identity();
        for (j, r) in local.iter().enumerate() {
            // Rotate about joint j: p ↦ acc · (c + R (p − c)).
            let c = self.joints[j].coords;
            let about = Iso3::from_parts(nalgebra::Translation3::from(c), UnitQuat::identity())
                * Iso3::from_parts(nalgebra::Translation3::identity(), *r)
                * Iso3::from_parts(nalgebra::Translation3::from(-c), UnitQuat::identity());
            acc *= about;
            out.push(root * acc);
        }
        Ok(out)
    }

    /// Closest point on bone `j`'s rest segment and the bone's unit direction.
    pub fn closest_on_bone(&self, j: usize, p: &Pt3) -> (Pt3, Vec3) {
        let (a, b) = (self.joints[j], self.joints[j + 1]);
        let d = b - a;
        let t = ((p - a).dot(&d) / d.norm_squared()).clamp(0.0, 1.0);
        (a + d * t, d.normalize())
    }

    /// The bone whose rest segment is closest to `p`.
    pub fn closest_bone(&self, p: &Pt3) -> usize {
        (0..self.n_bones())
            .map(|j| (j, (self.closest_on_bone(j, p).0 - p).norm()))
            .fold((0, f64::INFINITY), |b, x| if x.1 < b.1 { x } else { b })
            .0
    }
}

/// Skin weights: per vertex, `(bone, weight)` rows summing to 1.
#[derive(Clone, Debug)]
pub struct SkinBinding {
    /// The rows.
    pub weights: Ragged<(u32, f64)>,
}

impl SkinBinding {
    /// Ramp weights along a chain: around each interior joint `j` (between bones `j−1` and `j`)
    /// the weight moves from bone `j−1` to bone `j` with a smoothstep over
    /// `[−half_width, +half_width]` of the signed distance along the bone direction (spec §2.3
    /// `Ramp(kind: SmoothStep, half_width)`). Rows hold at most two bones.
    pub fn ramp(chain: &Chain, points: &[Pt3], half_width: f64) -> Result<Self> {
        if half_width.is_nan() || half_width <= 0.0 {
            return Err(BarNetError::InvalidParameter(format!("ramp half_width = {half_width} must be > 0")));
        }
        let nb = chain.n_bones();
        if nb == 0 {
            return Err(BarNetError::InvalidParameter("skinning chain needs at least two joints".into()));
        }
        let mut rows = Vec::with_capacity(points.len());
        for p in points {
            // Which interior joint's ramp applies: the bone closest to p and its neighbours.
            let j = chain.closest_bone(p);
            let mut row: Vec<(u32, f64)> = vec![(j as u32, 1.0)];
            // Ramp towards the previous bone (joint j) or the next bone (joint j+1).
            let (_, d) = chain.closest_on_bone(j, p);
            if j > 0 {
                let s = (p - chain.joints[j]).dot(&d);
                let w = smoothstep(-half_width, half_width, s);
                if w < 1.0 {
                    row = vec![(j as u32 - 1, 1.0 - w), (j as u32, w)];
                }
            }
            if row.len() == 1 && j + 1 < nb {
                let s = (p - chain.joints[j + 1]).dot(&d);
                let w = smoothstep(-half_width, half_width, s);
                if w > 0.0 {
                    row = vec![(j as u32, 1.0 - w), (j as u32 + 1, w)];
                }
            }
            row.retain(|e| e.1 > 0.0);
            rows.push(row);
        }
        Ok(Self { weights: Ragged::from_rows(rows) })
    }

    /// Linear blend skinning `y_v = Σ_j w_vj T_j x_v` (f64).
    pub fn lbs(&self, rest: &[Pt3], t: &[Iso3], out: &mut [Pt3]) {
        for (v, o) in out.iter_mut().enumerate().take(rest.len()) {
            let mut acc = Vec3::zeros();
            for &(j, w) in self.weights.row(v) {
                acc += (t[j as usize] * rest[v]).coords * w;
            }
            *o = Pt3::from(acc);
        }
    }

    /// Dual-quaternion skinning (Kavan et al. 2008): blend the bones' unit dual quaternions with
    /// the weights (hemisphere-aligned to the first bone), normalise, apply. The reference the
    /// `elbow-volume` scene compares with (volume-preserving at the elbow, unlike LBS).
    pub fn dqs(&self, rest: &[Pt3], t: &[Iso3], out: &mut [Pt3]) {
        for (v, o) in out.iter_mut().enumerate().take(rest.len()) {
            let row = self.weights.row(v);
            let q0 = t[row[0].0 as usize].rotation;
            let mut br = Quaternion::new(0.0, 0.0, 0.0, 0.0);
            let mut bd = Quaternion::new(0.0, 0.0, 0.0, 0.0);
            for &(j, w) in row {
                let r = t[j as usize].rotation.into_inner();
                let tr = t[j as usize].translation.vector;
                let d = Quaternion::from_imag(tr) * r * 0.5;
                let s = if r.coords.dot(&q0.coords) < 0.0 { -w } else { w };
                br += r * s;
                bd += d * s;
            }
            let n = br.norm();
            let (r, d) = (br / n, bd / n);
            let rot = UnitQuat::new_unchecked(r);
            let tr = (d * r.conjugate()).imag() * 2.0;
            *o = rot * rest[v] + tr;
        }
    }

    /// Rotation of vertex `v`'s frame: the normalised, hemisphere-aligned quaternion blend of its
    /// bones' rotations (the rotation part of dual-quaternion skinning, spec §3.5).
    pub fn rotation(&self, v: usize, t: &[Iso3]) -> UnitQuat {
        let row = self.weights.row(v);
        let q0 = t[row[0].0 as usize].rotation;
        let mut acc = Quaternion::new(0.0, 0.0, 0.0, 0.0);
        for &(j, w) in row {
            let q = t[j as usize].rotation;
            let s = if q.coords.dot(&q0.coords) < 0.0 { -w } else { w };
            acc += q.into_inner() * s;
        }
        UnitQuat::new_normalize(acc)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ramp_rows_sum_to_one_and_lbs_is_rigid_under_rigid_motion() {
        let chain = Chain {
            names: vec!["a".into(), "b".into(), "c".into()],
            joints: vec![Pt3::origin(), Pt3::new(1.0, 0.0, 0.0), Pt3::new(2.0, 0.0, 0.0)],
        };
        let pts: Vec<Pt3> = (0..41).map(|i| Pt3::new(i as f64 * 0.05, 0.1, -0.05)).collect();
        let b = SkinBinding::ramp(&chain, &pts, 0.2).unwrap();
        for v in 0..pts.len() {
            let s: f64 = b.weights.row(v).iter().map(|e| e.1).sum();
            assert!((s - 1.0).abs() < 1e-15);
        }
        let g = Iso3::new(Vec3::new(0.3, -1.0, 2.0), Vec3::new(0.2, 0.5, -0.1));
        let t = vec![g; 2];
        let mut out = vec![Pt3::origin(); pts.len()];
        b.lbs(&pts, &t, &mut out);
        for (o, p) in out.iter().zip(&pts) {
            assert!((o - g * p).norm() < 1e-14);
        }
        assert!(b.rotation(20, &t).angle_to(&g.rotation) < 1e-14);
        // DQS of a rigid motion is the same rigid motion.
        b.dqs(&pts, &t, &mut out);
        for (o, p) in out.iter().zip(&pts) {
            assert!((o - g * p).norm() < 1e-14);
        }
    }

    #[test]
    fn pose_rotates_about_the_joint() {
        let chain = Chain {
            names: vec!["s".into(), "e".into(), "w".into()],
            joints: vec![Pt3::origin(), Pt3::new(1.0, 0.0, 0.0), Pt3::new(2.0, 0.0, 0.0)],
        };
        let r = UnitQuat::from_axis_angle(&Vec3::z_axis(), std::f64::consts::FRAC_PI_2);
        let t = chain.pose(&[UnitQuat::identity(), r], &Iso3::identity()).unwrap();
        let w = t[1] * chain.joints[2];
        assert!((w - Pt3::new(1.0, 1.0, 0.0)).norm() < 1e-15);
        assert!((t[1] * chain.joints[1] - chain.joints[1]).norm() < 1e-15);
    }
}

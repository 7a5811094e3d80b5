//! Fixed-width per-vertex weights for the fast skinners: [`PackedWeights<K>`] keeps the `K`
//! largest influences of each vertex, sorted by decreasing weight (slot 0 is the pivot bone of
//! dual-quaternion skinning, spec §3.3 step 2), padded with `(bone 0, w = 0)`.

use geom_core::anim::skin::SkinWeights;

use crate::error::{Result, SkinError};

/// `K` influences per vertex, structure-of-arrays; rows sum to 1 (± 1e-6), sorted by decreasing
/// weight, padding entries have `w = 0` and bone 0.
#[derive(Clone, Debug, PartialEq)]
pub struct PackedWeights<const K: usize> {
    /// Bone (joint) index per slot.
    pub bone: Vec<[u16; K]>,
    /// Weight per slot.
    pub w: Vec<[f32; K]>,
}

impl<const K: usize> PackedWeights<K> {
    /// Checks a skinner's bind data against these weights and returns the largest bone index
    /// with a positive weight (0 when none), so `prepare` can reject too-small skeletons.
    /// `what` names the rows and the normals in the size error (e.g. "LBS weights rows").
    /// Errors: [`SkinError::Size`] when the row or normal count differs from `rest_len`.
    pub(crate) fn check_bind(
        &self,
        rest_len: usize,
        normals_len: Option<usize>,
        what: [&'static str; 2],
    ) -> Result<usize> {
        if self.len() != rest_len {
            return Err(SkinError::Size { what: what[0], expected: rest_len, got: self.len() });
        }
        if let Some(n) = normals_len {
            if n != rest_len {
                return Err(SkinError::Size { what: what[1], expected: rest_len, got: n });
            }
        }
        Ok(self
            .bone
            .iter()
            .zip(&self.w)
            .flat_map(|(b, w)| (0..K).filter(move |&k| w[k] > 0.0).map(move |k| b[k] as usize))
            .max()
            .unwrap_or(0))
    }

    /// Number of vertices.
    pub fn len(&self) -> usize {
        self.w.len()
    }

    /// True when there is no vertex.
    pub fn is_empty(&self) -> bool {
        self.w.is_empty()
    }

    /// Packs sparse rows `(bone, weight)`: negative weights are clamped to 0, the `K` largest are
    /// kept (ties: lower bone first) and renormalised to sum 1. Returns the largest weight mass
    /// dropped from a row (relative to that row's clamped total) — spec §8 "more than K
    /// influences". Errors: [`SkinError::BadWeights`] for a NaN/∞ weight or a row whose clamped
    /// total is 0.
    pub fn from_sparse(rows: &[Vec<(u16, f32)>]) -> Result<(Self, f32)> {
        let mut out = PackedWeights { bone: Vec::with_capacity(rows.len()), w: Vec::with_capacity(rows.len()) };
        let mut worst = 0.0f32;
        let mut tmp: Vec<(u16, f32)> = Vec::new();
        for (v, row) in rows.iter().enumerate() {
            tmp.clear();
            for &(b, w) in row {
                if !w.is_finite() {
                    return Err(SkinError::BadWeights { vertex: v, msg: format!("weight of bone {b} is {w}") });
                }
                if w > 0.0 {
                    tmp.push((b, w));
                }
            }
            let (dropped, bones, ws) = Self::pack_row(&mut tmp)
                .ok_or_else(|| SkinError::BadWeights { vertex: v, msg: "all weights are zero or negative".into() })?;
            worst = worst.max(dropped);
            out.bone.push(bones);
            out.w.push(ws);
        }
        Ok((out, worst))
    }

    /// Sorts, keeps K, renormalises one row of positive weights; `None` if the row is empty.
    fn pack_row(tmp: &mut [(u16, f32)]) -> Option<(f32, [u16; K], [f32; K])> {
        if tmp.is_empty() {
            return None;
        }
        tmp.sort_by(|a, b| b.1.total_cmp(&a.1).then(a.0.cmp(&b.0)));
        let total: f64 = tmp.iter().map(|e| e.1 as f64).sum();
        let keep = tmp.len().min(K);
        let kept: f64 = tmp[..keep].iter().map(|e| e.1 as f64).sum();
        let mut bones = [0u16; K];
        let mut ws = [0f32; K];
        for (k, &(b, w)) in tmp[..keep].iter().enumerate() {
            bones[k] = b;
            ws[k] = (w as f64 / kept) as f32;
        }
        Some((((total - kept) / total) as f32, bones, ws))
    }

    /// Packs geom-core's exchange format (see [`Self::from_sparse`]).
    pub fn from_skin_weights(sw: &SkinWeights) -> Result<(Self, f32)> {
        let rows: Vec<Vec<(u16, f32)>> = (0..sw.len())
            .map(|v| {
                let (j, w) = sw.row(v);
                j.iter().copied().zip(w.iter().copied()).collect()
            })
            .collect();
        Self::from_sparse(&rows)
    }

    /// The weights as geom-core's sparse exchange format (padding dropped).
    pub fn to_skin_weights(&self) -> SkinWeights {
        let mut s = SkinWeights { offsets: vec![0], joint: Vec::new(), w: Vec::new() };
        for (b, w) in self.bone.iter().zip(&self.w) {
            for k in 0..K {
                if w[k] > 0.0 {
                    s.joint.push(b[k]);
                    s.w.push(w[k]);
                }
            }
            s.offsets.push(s.joint.len() as u32);
        }
        s
    }

    /// Checks every bone index is below `n_bones`.
    pub fn check_bones(&self, n_bones: usize) -> Result<()> {
        for (v, (b, w)) in self.bone.iter().zip(&self.w).enumerate() {
            for k in 0..K {
                if w[k] > 0.0 && b[k] as usize >= n_bones {
                    return Err(SkinError::BadWeights {
                        vertex: v,
                        msg: format!("bone {} out of range (skeleton has {n_bones})", b[k]),
                    });
                }
            }
        }
        Ok(())
    }

    /// Number of non-zero influences per vertex, as a histogram (`h[k]` = vertices with `k`).
    pub fn influence_histogram(&self) -> Vec<usize> {
        let mut h = vec![0usize; K + 1];
        for w in &self.w {
            h[w.iter().filter(|&&x| x > 0.0).count()] += 1;
        }
        h
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn keeps_k_largest_and_renormalises() {
        let rows =
            vec![vec![(0, 0.1), (1, 0.4), (2, 0.3), (3, 0.2)], vec![(5, 2.0)], vec![(1, -0.5), (2, 0.5), (3, 0.5)]];
        let (p, dropped) = PackedWeights::<2>::from_sparse(&rows).unwrap();
        assert_eq!(p.bone[0], [1, 2]);
        assert!((p.w[0][0] - 0.4 / 0.7).abs() < 1e-6 && (p.w[0][1] - 0.3 / 0.7).abs() < 1e-6);
        assert!((dropped - 0.3).abs() < 1e-6, "{dropped}");
        assert_eq!(p.bone[1], [5, 0]);
        assert_eq!(p.w[1], [1.0, 0.0]);
        assert_eq!(p.bone[2], [2, 3]);
        for w in &p.w {
            assert!((w.iter().sum::<f32>() - 1.0).abs() < 1e-6);
        }
    }

    #[test]
    fn rejects_nan_and_all_zero_rows() {
        assert!(matches!(
            PackedWeights::<4>::from_sparse(&[vec![(0, f32::NAN)]]),
            Err(SkinError::BadWeights { vertex: 0, .. })
        ));
        assert!(matches!(
            PackedWeights::<4>::from_sparse(&[vec![(0, 1.0)], vec![(0, 0.0), (1, -1.0)]]),
            Err(SkinError::BadWeights { vertex: 1, .. })
        ));
    }

    #[test]
    fn round_trips_through_skin_weights() {
        let rows = vec![vec![(0, 0.25), (1, 0.75)], vec![(3, 1.0)]];
        let (p, _) = PackedWeights::<4>::from_sparse(&rows).unwrap();
        let (q, d) = PackedWeights::<4>::from_skin_weights(&p.to_skin_weights()).unwrap();
        assert_eq!(p, q);
        assert_eq!(d, 0.0);
        assert_eq!(p.influence_histogram(), vec![0, 1, 1, 0, 0]);
    }

    proptest::proptest! {
        #[test]
        fn rows_sum_to_one_and_are_sorted(raw in proptest::collection::vec(proptest::collection::vec((0u16..20, -1.0f32..10.0), 1..10), 1..20)) {
            let rows: Vec<Vec<(u16, f32)>> = raw.into_iter().map(|mut r| { r.push((0, 0.5)); r }).collect();
            let (p, dropped) = PackedWeights::<4>::from_sparse(&rows).unwrap();
            proptest::prop_assert!((0.0..=1.0).contains(&dropped));
            for w in &p.w {
                proptest::prop_assert!((w.iter().sum::<f32>() - 1.0).abs() < 1e-6);
                for k in 1..4 { proptest::prop_assert!(w[k] <= w[k - 1]); }
            }
        }
    }
}

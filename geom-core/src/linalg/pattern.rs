//! [`FixedPattern`]: re-assembling a sparse matrix with a fixed pattern every time step.
//!
//! A simulator (shells, tracks, barnet) produces the same list of element contributions every
//! step, only with new values: element `e` adds its 3×3 blocks at the same `(row, col)` keys.
//! `FixedPattern` sorts the keys once into a [`Csc`] pattern and records, for every stored entry,
//! which contributions land on it. [`FixedPattern::assemble`] then only sums numbers: no
//! sorting, no allocation, and the symbolic Cholesky analysis of the pattern stays valid.
//!
//! Determinism: entry `e` is `Σ contrib[k]` over its contributions `k` in increasing `k`
//! (key order). Entries are computed in parallel but each sum is sequential and fixed, so the
//! result is bitwise identical for any thread count.

use super::csc::{csc_from_parts, Csc};
use rayon::prelude::*;

/// Minimum number of entries per Rayon task in [`FixedPattern::assemble`].
const PAR_ENTRIES: usize = 4096;

/// Marks a contribution that is not stored (above the diagonal of a lower-only pattern).
const DROPPED: u32 = u32::MAX;

/// A fixed [`Csc`] sparsity pattern with a gather list per entry; see the module docs.
#[derive(Clone, Debug)]
pub struct FixedPattern {
    /// The assembled matrix (pattern fixed at construction, values rewritten by `assemble`).
    mat: Csc,
    /// `gather_ptr[e]..gather_ptr[e + 1]` indexes `gather` for stored entry `e`.
    gather_ptr: Vec<usize>,
    /// Contribution indices, increasing within each entry.
    gather: Vec<u32>,
    /// Stored-entry index of each contribution, or `DROPPED`.
    slot: Vec<u32>,
}

impl FixedPattern {
    /// Builds the pattern of an `nrows × ncols` matrix from one `(row, col)` key per
    /// contribution (duplicates are expected: each becomes one term of the entry's sum).
    ///
    /// With `lower_only` (square symmetric matrices for the direct solvers), keys above the
    /// diagonal (`row < col`) are dropped: the result is the lower triangle of the matrix the
    /// keys describe, so pass contributions for both triangles (as a full element Hessian
    /// gives) or only the lower ones; upper contributions never count.
    ///
    /// # Panics
    /// If a key lies outside the matrix, there are `u32::MAX` or more keys, or `lower_only` is
    /// asked for a non-square matrix (all programming errors: keys come from mesh topology).
    pub fn new(nrows: usize, ncols: usize, keys: &[(u32, u32)], lower_only: bool) -> Self {
        assert!(keys.len() < DROPPED as usize, "FixedPattern::new: too many contributions");
        assert!(!lower_only || nrows == ncols, "FixedPattern::new: lower_only needs a square matrix");
        for (k, &(i, j)) in keys.iter().enumerate() {
            assert!(
                (i as usize) < nrows && (j as usize) < ncols,
                "FixedPattern::new: key {k} = ({i}, {j}) is outside the {nrows}×{ncols} matrix"
            );
        }
        // Contributions sorted by (col, row, k): a stable sort on (col, row) keeps k increasing.
        let mut order: Vec<u32> =
            (0..keys.len() as u32).filter(|&k| !lower_only || keys[k as usize].0 >= keys[k as usize].1).collect();
        order.sort_by_key(|&k| (keys[k as usize].1, keys[k as usize].0));
        let mut slot = vec![DROPPED; keys.len()];
        let mut col_ptr = vec![0usize; ncols + 1];
        let mut row_idx = Vec::new();
        let mut gather_ptr = vec![0usize];
        let mut gather = Vec::with_capacity(order.len());
        let mut last: Option<(u32, u32)> = None;
        for &k in &order {
            let (i, j) = keys[k as usize];
            if last != Some((i, j)) {
                if last.is_some() {
                    gather_ptr.push(gather.len());
                }
                row_idx.push(i as usize);
                col_ptr[j as usize + 1] += 1;
                last = Some((i, j));
            }
            slot[k as usize] = (row_idx.len() - 1) as u32;
            gather.push(k);
        }
        if last.is_some() {
            gather_ptr.push(gather.len());
        }
        for j in 0..ncols {
            col_ptr[j + 1] += col_ptr[j];
        }
        let nnz = row_idx.len();
        let mat = csc_from_parts(nrows, ncols, col_ptr, row_idx, vec![0.0; nnz]);
        Self { mat, gather_ptr, gather, slot }
    }

    /// Sums the contributions (one value per key given to [`FixedPattern::new`], same order)
    /// into the matrix and returns it. Parallel over entries, bitwise deterministic.
    ///
    /// # Panics
    /// If `contrib.len()` differs from the number of keys.
    pub fn assemble(&mut self, contrib: &[f64]) -> &Csc {
        assert_eq!(contrib.len(), self.slot.len(), "FixedPattern::assemble: one value per key expected");
        let (gather_ptr, gather) = (&self.gather_ptr, &self.gather);
        self.mat.val_mut().par_iter_mut().with_min_len(PAR_ENTRIES).enumerate().for_each(|(e, v)| {
            let mut s = 0.0;
            for &k in &gather[gather_ptr[e]..gather_ptr[e + 1]] {
                s += contrib[k as usize];
            }
            *v = s;
        });
        &self.mat
    }

    /// The matrix as last assembled (zeros before the first [`FixedPattern::assemble`]).
    pub fn csc(&self) -> &Csc {
        &self.mat
    }

    /// Number of stored entries.
    pub fn nnz(&self) -> usize {
        self.gather_ptr.len() - 1
    }

    /// Number of contributions (keys) the pattern was built from.
    pub fn n_contributions(&self) -> usize {
        self.slot.len()
    }

    /// Index into the matrix's value array of contribution `k`'s entry; `None` for a dropped
    /// (upper-triangle) contribution. Panics if `k` is out of range.
    pub fn slot(&self, k: usize) -> Option<usize> {
        let s = self.slot[k];
        (s != DROPPED).then_some(s as usize)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sums_duplicates_and_drops_upper() {
        let keys = [(0, 0), (1, 0), (0, 1), (1, 1), (0, 0), (1, 0)];
        let mut p = FixedPattern::new(2, 2, &keys, true);
        assert_eq!(p.nnz(), 3);
        assert_eq!(p.slot(2), None);
        let a = p.assemble(&[1.0, 2.0, 100.0, 3.0, 10.0, 20.0]).to_dense();
        assert_eq!(a[(0, 0)], 11.0);
        assert_eq!(a[(1, 0)], 22.0);
        assert_eq!(a[(0, 1)], 0.0);
        assert_eq!(a[(1, 1)], 3.0);
    }

    #[test]
    fn full_pattern_keeps_both_triangles() {
        let keys = [(0, 1), (1, 0), (0, 1)];
        let mut p = FixedPattern::new(2, 3, &keys, false);
        let a = p.assemble(&[1.0, 2.0, 4.0]).to_dense();
        assert_eq!((a[(0, 1)], a[(1, 0)], a[(0, 0)]), (5.0, 2.0, 0.0));
        assert_eq!((a.nrows(), a.ncols()), (2, 3));
    }
}

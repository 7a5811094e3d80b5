//! [`Triplets`]: the (row, column, value) list every sparse matrix is assembled from.

use crate::math::Mat3;

/// A list of `(row, col, value)` entries; duplicates are summed on conversion (in insertion
/// order, so the result is deterministic).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Triplets {
    /// Number of rows of the matrix being assembled.
    pub nrows: usize,
    /// Number of columns.
    pub ncols: usize,
    /// The entries, in insertion order.
    pub entries: Vec<(u32, u32, f64)>,
}

impl Triplets {
    /// An empty list for an `nrows × ncols` matrix.
    pub fn new(nrows: usize, ncols: usize) -> Self {
        Self { nrows, ncols, entries: Vec::new() }
    }

    /// An empty list with room for `cap` entries.
    pub fn with_capacity(nrows: usize, ncols: usize, cap: usize) -> Self {
        Self { nrows, ncols, entries: Vec::with_capacity(cap) }
    }

    /// Adds `v` at `(i, j)`. Panics in debug builds if the index is out of range.
    #[inline]
    pub fn push(&mut self, i: u32, j: u32, v: f64) {
        debug_assert!((i as usize) < self.nrows && (j as usize) < self.ncols, "triplet ({i}, {j}) out of range");
        self.entries.push((i, j, v));
    }

    /// Adds the 3×3 block `m` coupling vertex `vi` (rows `3vi..3vi+3`) and vertex `vj`
    /// (columns `3vj..3vj+3`) of an interleaved `[x0, y0, z0, x1, …]` layout.
    pub fn push_block3(&mut self, vi: u32, vj: u32, m: &Mat3) {
        for r in 0..3 {
            for c in 0..3 {
                self.push(3 * vi + r as u32, 3 * vj + c as u32, m[(r, c)]);
            }
        }
    }

    /// Number of entries pushed so far.
    pub fn len(&self) -> usize {
        self.entries.len()
    }

    /// True when no entry was pushed.
    pub fn is_empty(&self) -> bool {
        self.entries.is_empty()
    }
}

//! Sparse matrix algebra on [`Csr`]: transpose, product, linear combination, row scaling, the
//! `⊗ I₃` expansion for interleaved xyz unknowns, symmetry test and pattern components.
//!
//! Every result keeps the [`Csr`] invariant (columns strictly increasing within a row) and is
//! computed in a fixed order, so it is bitwise reproducible. Shape mismatches are programming
//! errors and panic with a message naming the operation.

use super::Csr;
use crate::graph::UnionFind;

impl Csr {
    /// `Aᵀ` (a counting sort by column: rows of the result come out sorted).
    pub fn transpose(&self) -> Csr {
        let mut count = vec![0usize; self.ncols + 1];
        for &j in &self.col {
            count[j as usize + 1] += 1;
        }
        for j in 0..self.ncols {
            count[j + 1] += count[j];
        }
        let mut cursor = count.clone();
        let mut col = vec![0u32; self.nnz()];
        let mut val = vec![0.0; self.nnz()];
        for i in 0..self.nrows {
            let (c, v) = self.row(i);
            for (&j, &a) in c.iter().zip(v) {
                let k = &mut cursor[j as usize];
                col[*k] = i as u32;
                val[*k] = a;
                *k += 1;
            }
        }
        Csr { nrows: self.ncols, ncols: self.nrows, row_ptr: count, col, val }
    }

    /// The product `A B` (Gustavson's row-by-row algorithm with a dense accumulator). Every
    /// structurally reachable entry is stored, even when it cancels to zero.
    ///
    /// # Panics
    /// If `self.ncols != b.nrows`.
    pub fn matmul(&self, b: &Csr) -> Csr {
        assert_eq!(self.ncols, b.nrows, "Csr::matmul: inner dimensions differ");
        let mut acc = vec![0.0f64; b.ncols];
        let mut mark = vec![usize::MAX; b.ncols];
        let mut touched: Vec<u32> = Vec::new();
        let mut row_ptr = Vec::with_capacity(self.nrows + 1);
        let mut col = Vec::new();
        let mut val = Vec::new();
        row_ptr.push(0);
        for i in 0..self.nrows {
            touched.clear();
            let (ca, va) = self.row(i);
            for (&k, &a) in ca.iter().zip(va) {
                let (cb, vb) = b.row(k as usize);
                for (&j, &bv) in cb.iter().zip(vb) {
                    let ju = j as usize;
                    if mark[ju] != i {
                        mark[ju] = i;
                        acc[ju] = 0.0;
                        touched.push(j);
                    }
                    acc[ju] += a * bv;
                }
            }
            touched.sort_unstable();
            for &j in &touched {
                col.push(j);
                val.push(acc[j as usize]);
            }
            row_ptr.push(col.len());
        }
        Csr { nrows: self.nrows, ncols: b.ncols, row_ptr, col, val }
    }

    /// `alpha A + beta B` on the union of both patterns.
    ///
    /// # Panics
    /// If the shapes differ.
    pub fn add(&self, b: &Csr, alpha: f64, beta: f64) -> Csr {
        assert!(self.nrows == b.nrows && self.ncols == b.ncols, "Csr::add: shapes differ");
        let mut row_ptr = Vec::with_capacity(self.nrows + 1);
        let mut col = Vec::with_capacity(self.nnz().max(b.nnz()));
        let mut val = Vec::with_capacity(self.nnz().max(b.nnz()));
        row_ptr.push(0);
        for i in 0..self.nrows {
            let (ca, va) = self.row(i);
            let (cb, vb) = b.row(i);
            let (mut p, mut q) = (0, 0);
            while p < ca.len() || q < cb.len() {
                let ja = ca.get(p).copied().unwrap_or(u32::MAX);
                let jb = cb.get(q).copied().unwrap_or(u32::MAX);
                if ja == jb {
                    col.push(ja);
                    val.push(alpha * va[p] + beta * vb[q]);
                    p += 1;
                    q += 1;
                } else if ja < jb {
                    col.push(ja);
                    val.push(alpha * va[p]);
                    p += 1;
                } else {
                    col.push(jb);
                    val.push(beta * vb[q]);
                    q += 1;
                }
            }
            row_ptr.push(col.len());
        }
        Csr { nrows: self.nrows, ncols: self.ncols, row_ptr, col, val }
    }

    /// Scales row `i` by `s[i]` in place (`A ← diag(s) A`).
    ///
    /// # Panics
    /// If `s.len() != nrows`.
    pub fn scale_rows(&mut self, s: &[f64]) {
        assert_eq!(s.len(), self.nrows, "Csr::scale_rows: wrong length");
        for (i, &si) in s.iter().enumerate() {
            for v in &mut self.val[self.row_ptr[i]..self.row_ptr[i + 1]] {
                *v *= si;
            }
        }
    }

    /// `A ⊗ I₃` for interleaved `[x0, y0, z0, x1, …]` unknowns: entry `a_ij` becomes `a_ij` at
    /// `(3i + r, 3j + r)` for `r = 0, 1, 2` (the zero off-diagonals of each block are not
    /// stored). Used to lift scalar operators (constraints, Laplacians) to 3-D displacements.
    ///
    /// # Panics
    /// If `3·ncols` does not fit a `u32` column index.
    pub fn kron_i3(&self) -> Csr {
        assert!(3 * self.ncols <= u32::MAX as usize, "Csr::kron_i3: too many columns for u32 indices");
        let mut row_ptr = Vec::with_capacity(3 * self.nrows + 1);
        let mut col = Vec::with_capacity(3 * self.nnz());
        let mut val = Vec::with_capacity(3 * self.nnz());
        row_ptr.push(0);
        for i in 0..self.nrows {
            let (c, v) = self.row(i);
            for r in 0..3u32 {
                for (&j, &a) in c.iter().zip(v) {
                    col.push(3 * j + r);
                    val.push(a);
                }
                row_ptr.push(col.len());
            }
        }
        Csr { nrows: 3 * self.nrows, ncols: 3 * self.ncols, row_ptr, col, val }
    }

    /// Largest absolute stored value (0 for an empty matrix).
    pub fn max_abs(&self) -> f64 {
        self.val.iter().fold(0.0f64, |m, v| m.max(v.abs()))
    }

    /// True when the matrix is square and `|a_ij − a_ji| ≤ tol · max|a|` for every stored
    /// entry (a missing partner counts as zero). `tol` is relative to the largest entry, so the
    /// test is scale-invariant; `tol = 0` asks for exact symmetry.
    pub fn is_symmetric(&self, tol: f64) -> bool {
        if self.nrows != self.ncols {
            return false;
        }
        let bound = tol * self.max_abs();
        (0..self.nrows).all(|i| {
            let (c, v) = self.row(i);
            c.iter().zip(v).all(|(&j, &a)| (a - self.get(j as usize, i)).abs() <= bound)
        })
    }

    /// Connected components of the (symmetrised) sparsity graph of a square matrix: rows `i`
    /// and `j` are connected when `a_ij` or `a_ji` is stored. Returns `(count, label per row)`,
    /// labels numbered by each component's lowest row (as [`crate::graph::components`]). A
    /// block-diagonal system splits into independent solves along these labels (e.g. separate
    /// fluid regions of a pressure Poisson problem).
    ///
    /// # Panics
    /// If the matrix is not square.
    pub fn pattern_components(&self) -> (usize, Vec<u32>) {
        assert_eq!(self.nrows, self.ncols, "Csr::pattern_components: matrix is not square");
        let mut uf = UnionFind::new(self.nrows);
        for i in 0..self.nrows {
            for &j in self.row(i).0 {
                uf.union(i as u32, j);
            }
        }
        uf.labels()
    }

    /// Dense copy (for tests and small problems).
    pub fn to_dense(&self) -> faer::Mat<f64> {
        let mut m = faer::Mat::zeros(self.nrows, self.ncols);
        for i in 0..self.nrows {
            let (c, v) = self.row(i);
            for (&j, &a) in c.iter().zip(v) {
                m[(i, j as usize)] += a;
            }
        }
        m
    }
}

//! [`Csr`]: compressed sparse row matrices with `u32` column indices, the toolkit's operator type
//! (prolongation P, constraint C, Laplacian L, mass M, pressure …).

use super::Triplets;
use rayon::prelude::*;

/// Minimum number of rows per Rayon task in the parallel row loops.
pub const PAR_ROWS: usize = 1024;

/// Compressed sparse row matrix. Within a row, columns are strictly increasing.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Csr {
    /// Number of rows.
    pub nrows: usize,
    /// Number of columns.
    pub ncols: usize,
    /// `nrows + 1` offsets into `col`/`val`.
    pub row_ptr: Vec<usize>,
    /// Column index of each stored entry.
    pub col: Vec<u32>,
    /// Value of each stored entry.
    pub val: Vec<f64>,
}

impl Csr {
    /// Converts triplets, summing duplicates in insertion order (deterministic). Explicit zeros
    /// are kept (the pattern is what was pushed).
    pub fn from_triplets(t: &Triplets) -> Csr {
        let n = t.nrows;
        let mut count = vec![0usize; n + 1];
        for &(i, _, _) in &t.entries {
            count[i as usize + 1] += 1;
        }
        for i in 0..n {
            count[i + 1] += count[i];
        }
        // Bucket entries by row, keeping insertion order within a row.
        let mut cursor = count.clone();
        let mut bucket: Vec<(u32, f64)> = vec![(0, 0.0); t.entries.len()];
        for &(i, j, v) in &t.entries {
            let c = &mut cursor[i as usize];
            bucket[*c] = (j, v);
            *c += 1;
        }
        let mut row_ptr = Vec::with_capacity(n + 1);
        let mut col = Vec::with_capacity(t.entries.len());
        let mut val = Vec::with_capacity(t.entries.len());
        row_ptr.push(0);
        for i in 0..n {
            let row = &mut bucket[count[i]..count[i + 1]];
            // Stable sort keeps insertion order among duplicates, so sums are deterministic.
            row.sort_by_key(|e| e.0);
            for &(j, v) in row.iter() {
                if col.len() > row_ptr[i] && *col.last().unwrap_or(&u32::MAX) == j {
                    // `val` is non-empty whenever `col` is: they grow together.
                    *val.last_mut().expect("val grows with col") += v;
                } else {
                    col.push(j);
                    val.push(v);
                }
            }
            row_ptr.push(col.len());
        }
        Csr { nrows: n, ncols: t.ncols, row_ptr, col, val }
    }

    /// The `n × n` identity.
    pub fn identity(n: usize) -> Csr {
        Csr::diag(&vec![1.0; n])
    }

    /// A diagonal matrix.
    pub fn diag(d: &[f64]) -> Csr {
        let n = d.len();
        Csr { nrows: n, ncols: n, row_ptr: (0..=n).collect(), col: (0..n as u32).collect(), val: d.to_vec() }
    }

    /// Number of stored entries.
    pub fn nnz(&self) -> usize {
        self.val.len()
    }

    /// Row `i` as (columns, values).
    pub fn row(&self, i: usize) -> (&[u32], &[f64]) {
        let r = self.row_ptr[i]..self.row_ptr[i + 1];
        (&self.col[r.clone()], &self.val[r])
    }

    /// Row `i` times `x`, summed in column order: the one kernel shared by [`Csr::mul_vec`] and
    /// [`Csr::mul_vec_par`], so both give bitwise identical results.
    #[inline]
    fn row_dot(&self, i: usize, x: &[f64]) -> f64 {
        let (c, v) = self.row(i);
        let mut s = 0.0;
        for (&j, &a) in c.iter().zip(v) {
            s += a * x[j as usize];
        }
        s
    }

    /// `y = A x`. Panics if the lengths do not match the shape.
    pub fn mul_vec(&self, x: &[f64], y: &mut [f64]) {
        assert_eq!(x.len(), self.ncols, "Csr::mul_vec: x has the wrong length");
        assert_eq!(y.len(), self.nrows, "Csr::mul_vec: y has the wrong length");
        for (i, yi) in y.iter_mut().enumerate() {
            *yi = self.row_dot(i, x);
        }
    }

    /// `y = A x` with rows in parallel (Rayon, chunks of at least [`PAR_ROWS`] rows). Each row is
    /// summed by the same kernel as [`Csr::mul_vec`], so the result is bitwise identical to the
    /// serial product for any thread count. Panics if the lengths do not match the shape.
    pub fn mul_vec_par(&self, x: &[f64], y: &mut [f64]) {
        assert_eq!(x.len(), self.ncols, "Csr::mul_vec_par: x has the wrong length");
        assert_eq!(y.len(), self.nrows, "Csr::mul_vec_par: y has the wrong length");
        y.par_iter_mut().with_min_len(PAR_ROWS).enumerate().for_each(|(i, yi)| *yi = self.row_dot(i, x));
    }

    /// `y = Aᵀ x` (serial scatter over rows, deterministic). Panics if the lengths do not match
    /// the shape.
    pub fn tr_mul_vec(&self, x: &[f64], y: &mut [f64]) {
        assert_eq!(x.len(), self.nrows, "Csr::tr_mul_vec: x has the wrong length");
        assert_eq!(y.len(), self.ncols, "Csr::tr_mul_vec: y has the wrong length");
        y.fill(0.0);
        for (i, &xi) in x.iter().enumerate() {
            let (c, v) = self.row(i);
            for (&j, &a) in c.iter().zip(v) {
                y[j as usize] += a * xi;
            }
        }
    }

    /// Entry `(i, j)`, zero when not stored.
    pub fn get(&self, i: usize, j: usize) -> f64 {
        let (c, v) = self.row(i);
        match c.binary_search(&(j as u32)) {
            Ok(k) => v[k],
            Err(_) => 0.0,
        }
    }
}

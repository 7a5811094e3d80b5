//! `Csr` algebra against dense references, conversions, and the bitwise determinism of the
//! parallel kernels (`mul_vec_par`, `dot`, `FixedPattern::assemble`) across thread counts.
//!
//! Dense comparisons use exact equality where the sparse and dense computations add the same
//! terms in the same order, and 1e-13 (relative to the largest magnitude involved) otherwise.

mod linalg_common;

use faer::Mat;
use geom_core::linalg::{dot, Csr, FixedPattern, Triplets};
use linalg_common::{laplacian_2d, poisson_3d, test_vector, with_threads};
use proptest::prelude::*;

fn dense_close(a: &Mat<f64>, b: &Mat<f64>, tol: f64) {
    assert_eq!((a.nrows(), a.ncols()), (b.nrows(), b.ncols()));
    for i in 0..a.nrows() {
        for j in 0..a.ncols() {
            assert!((a[(i, j)] - b[(i, j)]).abs() <= tol, "entry ({i}, {j}): {} vs {}", a[(i, j)], b[(i, j)]);
        }
    }
}

/// A random sparse matrix from proptest entries (duplicates allowed).
fn from_entries(m: usize, n: usize, e: &[(usize, usize, f64)]) -> Csr {
    let mut t = Triplets::new(m, n);
    for &(i, j, v) in e {
        t.push((i % m) as u32, (j % n) as u32, v);
    }
    Csr::from_triplets(&t)
}

#[test]
fn from_triplets_sums_duplicates_in_order() {
    let mut t = Triplets::new(3, 4);
    t.push(2, 1, 1.0);
    t.push(0, 3, 2.0);
    t.push(2, 1, 1e-17);
    t.push(2, 0, -1.0);
    t.push(2, 1, -1.0);
    let a = Csr::from_triplets(&t);
    assert_eq!(a.row_ptr, vec![0, 1, 1, 3]);
    assert_eq!(a.col, vec![3, 0, 1]);
    // (1 + 1e-17) − 1 in insertion order: 1 + 1e-17 rounds to 1, so the sum is exactly 0.
    assert_eq!(a.val, vec![2.0, -1.0, 0.0]);
    assert_eq!(a.get(2, 1), 0.0);
    assert_eq!(a.nnz(), 3, "the cancelled entry stays in the pattern");
}

#[test]
fn products_and_transposes_match_dense() {
    let a = from_entries(7, 5, &[(0, 0, 1.0), (1, 3, 2.0), (6, 4, -3.0), (3, 1, 0.5), (3, 2, 4.0), (5, 0, -1.5)]);
    let b = from_entries(5, 6, &[(0, 5, 2.0), (3, 0, 1.0), (4, 4, 2.5), (1, 1, -1.0), (2, 2, 3.0), (2, 3, 1.0)]);
    dense_close(&a.transpose().to_dense(), &a.to_dense().transpose().to_owned(), 0.0);
    dense_close(&a.matmul(&b).to_dense(), &(a.to_dense() * b.to_dense()), 1e-14);
    let x = test_vector(5, 1);
    let mut y = vec![0.0; 7];
    a.mul_vec(&x, &mut y);
    let mut yt = vec![0.0; 5];
    a.tr_mul_vec(&y, &mut yt);
    let ad = a.to_dense();
    for j in 0..5 {
        let r: f64 = (0..7).map(|i| ad[(i, j)] * y[i]).sum();
        assert!((yt[j] - r).abs() <= 1e-14);
    }
}

#[test]
fn kron_i3_matches_dense_kronecker() {
    let a = from_entries(3, 4, &[(0, 1, 2.0), (2, 3, -1.0), (1, 0, 0.5), (2, 0, 3.0)]);
    let k = a.kron_i3();
    let ad = a.to_dense();
    let kd = Mat::from_fn(9, 12, |r, c| if r % 3 == c % 3 { ad[(r / 3, c / 3)] } else { 0.0 });
    dense_close(&k.to_dense(), &kd, 0.0);
    assert_eq!(k.nnz(), 3 * a.nnz());
}

#[test]
fn add_scale_and_symmetry() {
    let l = laplacian_2d(6, 5, 0.0, false);
    let m = Csr::diag(&test_vector(30, 2));
    let s = l.add(&m, 2.0, -0.5);
    dense_close(&s.to_dense(), &(l.to_dense() * 2.0 - m.to_dense() * 0.5), 1e-15);
    assert!(s.is_symmetric(0.0));
    let mut r = s.clone();
    let w = test_vector(30, 3);
    r.scale_rows(&w);
    let rd = Mat::from_fn(30, 30, |i, j| w[i] * s.to_dense()[(i, j)]);
    dense_close(&r.to_dense(), &rd, 0.0);
    assert!(!r.is_symmetric(1e-3));
    let mut t = Triplets::new(2, 2);
    t.push(0, 1, 1.0);
    t.push(1, 0, 1.0 + 1e-10);
    assert!(Csr::from_triplets(&t).is_symmetric(1e-9));
    assert!(!Csr::from_triplets(&t).is_symmetric(1e-11));
    assert!(!from_entries(2, 3, &[(0, 0, 1.0)]).is_symmetric(1.0));
}

#[test]
fn csc_round_trips() {
    let a = from_entries(5, 4, &[(0, 0, 1.0), (4, 3, 2.0), (2, 1, -1.0), (2, 3, 5.0), (1, 1, 0.0)]);
    assert_eq!(Csr::from_csc(&a.to_csc()), a);
    dense_close(&a.to_csc().to_dense(), &a.to_dense(), 0.0);
    let l = laplacian_2d(4, 3, 1.0, true);
    let low = l.to_csc_lower();
    let ld = low.to_dense();
    for i in 0..12 {
        for j in 0..12 {
            assert_eq!(ld[(i, j)], if i >= j { l.get(i, j) } else { 0.0 });
        }
    }
}

#[test]
fn pattern_components_of_block_diagonal() {
    // Two 2-D grids side by side plus an isolated node: three components.
    let a = laplacian_2d(3, 3, 1.0, true);
    let b = laplacian_2d(2, 2, 1.0, true);
    let mut t = Triplets::new(14, 14);
    for (off, m) in [(0usize, &a), (9, &b)] {
        for i in 0..m.nrows {
            let (c, v) = m.row(i);
            for (&j, &x) in c.iter().zip(v) {
                t.push((i + off) as u32, j + off as u32, x);
            }
        }
    }
    t.push(13, 13, 1.0);
    let (count, labels) = Csr::from_triplets(&t).pattern_components();
    assert_eq!(count, 3);
    assert!(labels[..9].iter().all(|&l| l == 0));
    assert!(labels[9..13].iter().all(|&l| l == 1));
    assert_eq!(labels[13], 2);
}

#[test]
fn parallel_kernels_are_bitwise_deterministic() {
    // 3-D Poisson with 24³ = 13 824 rows: several Rayon row chunks and dot chunks.
    let a = poisson_3d(24);
    let n = a.nrows;
    let x = test_vector(n, 4);
    let mut serial = vec![0.0; n];
    a.mul_vec(&x, &mut serial);
    let par = |t: usize| {
        with_threads(t, || {
            let mut y = vec![0.0; n];
            a.mul_vec_par(&x, &mut y);
            (y.clone(), dot(&y, &x))
        })
    };
    let (y1, d1) = par(1);
    let (y2, d2) = par(2);
    assert_eq!(y1, serial);
    assert_eq!(y2, serial);
    assert_eq!(d1.to_bits(), d2.to_bits());

    // FixedPattern: contributions of a random symmetric element assembly.
    let mut keys = Vec::new();
    let mut vals = Vec::new();
    let w = test_vector(3 * n, 5);
    for (e, &we) in w.iter().enumerate() {
        let i = (e * 7919) % n;
        let j = (e * 104_729 + 3) % n;
        keys.extend([(i as u32, j as u32), (j as u32, i as u32), (i as u32, i as u32)]);
        vals.extend([we, we, we.abs()]);
    }
    let assemble = |t: usize, lower: bool| {
        with_threads(t, || {
            let mut p = FixedPattern::new(n, n, &keys, lower);
            p.assemble(&vals).val().to_vec()
        })
    };
    for lower in [false, true] {
        let v1 = assemble(1, lower);
        let v2 = assemble(2, lower);
        assert_eq!(
            v1.iter().map(|v| v.to_bits()).collect::<Vec<_>>(),
            v2.iter().map(|v| v.to_bits()).collect::<Vec<_>>()
        );
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    /// Random sparse matrices: algebra against dense, within 1e-12 of the operands' scale.
    #[test]
    fn random_algebra_matches_dense(
        ea in proptest::collection::vec((0usize..9, 0usize..7, -4.0f64..4.0), 0..40),
        eb in proptest::collection::vec((0usize..7, 0usize..8, -4.0f64..4.0), 0..40),
        ec in proptest::collection::vec((0usize..9, 0usize..7, -4.0f64..4.0), 0..40),
    ) {
        let a = from_entries(9, 7, &ea);
        let b = from_entries(7, 8, &eb);
        let c = from_entries(9, 7, &ec);
        // Row columns strictly increasing: the Csr invariant.
        for m in [&a, &b, &a.matmul(&b), &a.add(&c, 1.5, -2.0), &a.transpose(), &a.kron_i3()] {
            for i in 0..m.nrows {
                prop_assert!(m.row(i).0.windows(2).all(|w| w[0] < w[1]));
            }
        }
        dense_close(&a.matmul(&b).to_dense(), &(a.to_dense() * b.to_dense()), 1e-12);
        dense_close(&a.add(&c, 1.5, -2.0).to_dense(), &(a.to_dense() * 1.5 - c.to_dense() * 2.0), 1e-12);
        dense_close(&a.transpose().transpose().to_dense(), &a.to_dense(), 0.0);
        prop_assert_eq!(Csr::from_csc(&a.to_csc()), a.clone());
        let x = test_vector(7, 9);
        let (mut y1, mut y2) = (vec![0.0; 9], vec![0.0; 9]);
        a.mul_vec(&x, &mut y1);
        a.mul_vec_par(&x, &mut y2);
        prop_assert_eq!(y1, y2);
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    /// `FixedPattern` sums each entry's contributions in key order, exactly as
    /// `Csr::from_triplets` sums duplicates in insertion order: the two agree bitwise, and the
    /// lower-only pattern equals the triplets of the lower keys.
    #[test]
    fn fixed_pattern_equals_triplet_assembly(
        entries in proptest::collection::vec((0u32..6, 0u32..6, -1e3f64..1e3), 0..60),
    ) {
        let keys: Vec<(u32, u32)> = entries.iter().map(|e| (e.0, e.1)).collect();
        let vals: Vec<f64> = entries.iter().map(|e| e.2).collect();
        for lower in [false, true] {
            let mut t = Triplets::new(6, 6);
            for &(i, j, v) in &entries {
                if !lower || i >= j {
                    t.push(i, j, v);
                }
            }
            let mut p = FixedPattern::new(6, 6, &keys, lower);
            let got = Csr::from_csc(p.assemble(&vals));
            prop_assert_eq!(got, Csr::from_triplets(&t));
        }
    }
}
